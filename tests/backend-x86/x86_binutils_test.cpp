#include <gtest/gtest.h>

#include <dirent.h>

#include <algorithm>

#include "tests/assembler/test_util.h"
#include "bench/ldgen.h"
#include "driver/driver.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"

using namespace ldc;

namespace {

std::vector<std::string> programs() {
  std::vector<std::string> files;
  for (const char* dir : {"/examples", "/tests/golden"}) {
    std::string d = std::string(LDC_SOURCE_DIR) + dir;
    if (DIR* h = opendir(d.c_str())) {
      while (dirent* e = readdir(h)) {
        std::string n = e->d_name;
        if (n.size() > 3 && n.substr(n.size() - 3) == ".ld") files.push_back(d + "/" + n);
      }
      closedir(h);
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

// as on our --emit=asm gives our bytes; objdump -d of our bytes gives our
// disassembler's instructions.
void check_against_binutils(const Program& p, const std::string& name, int opt_level) {
  std::string why;
  ASSERT_TRUE(as::test::binutils_available(&why)) << why;
  SCOPED_TRACE("-O" + std::to_string(opt_level));
  NativeBuild nb = build_x86(p, name, as::Mode::Blockwise, opt_level);
  const auto& ours = nb.asm_result.code;
  std::string err;
  auto theirs = as::test::gnu_assemble(as::x86::to_gnu_as(nb.gen.program), &err);
  ASSERT_TRUE(err.empty()) << err;
  ASSERT_EQ(theirs.size(), ours.size());
  for (size_t i = 0; i < ours.size(); i++) ASSERT_EQ(theirs[i], ours[i]) << "first difference at code offset " << i;

  auto dis = as::x86::disassemble(ours);
  ASSERT_FALSE(dis.error) << dis.error->message << " at " << dis.error->offset;
  auto od = as::test::objdump_intel(ours, &err);
  ASSERT_TRUE(err.empty()) << err;
  ASSERT_EQ(od.size(), dis.insts.size());
  for (size_t i = 0; i < od.size(); i++) {
    ASSERT_EQ(od[i].address, dis.insts[i].offset) << "instruction boundaries differ";
    as::x86::Instruction theirs_inst = as::x86::parse(as::test::normalize_objdump(od[i].text));
    as::x86::Instruction mine = dis.insts[i].inst;
    mine.long_branch = false;  // objdump does not spell the rel32 choice; the bytes above agree
    EXPECT_EQ(as::x86::print(theirs_inst), as::x86::print(mine)) << "at " << od[i].address << ": objdump says " << od[i].text;
  }
}

class Binutils : public ::testing::TestWithParam<std::string> {};

TEST_P(Binutils, GnuAsGivesOurBytesAndObjdumpOurInstructions) {
  Program p = compile_source(GetParam()).il;
  for (int level : {0, 1, 2}) check_against_binutils(p, GetParam(), level);
}

// Random programs over every element class (bench/ldgen.h), 24 seeds x 60 rungs,
// a third each at -O0, -O1 and -O2 (6 seeds under the sanitizers, where the
// run is about memory safety and all 24 took 330 s of the suite's time).
#ifdef LDC_SANITIZED
constexpr uint64_t kBinutilsSeeds = 6;
#else
constexpr uint64_t kBinutilsSeeds = 24;
#endif
TEST(BinutilsGenerated, GnuAsAndObjdumpAgreeOnRandomPrograms) {
  for (uint64_t seed = 1; seed <= kBinutilsSeeds; seed++) {
    SCOPED_TRACE("ldgen --seed " + std::to_string(seed) + " --rungs 60");
    GenOptions o;
    o.rungs = 60;
    check_against_binutils(lower_to_il(parse_ld(generate_ld(seed, o), "gen.ld")), "gen.ld", int(seed % 3));
    if (HasFatalFailure()) return;
  }
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string p = info.param;
  std::string dir = p.find("/examples/") != std::string::npos ? "example_" : "golden_";
  std::string n = p.substr(p.rfind('/') + 1);
  n = n.substr(0, n.size() - 3);
  for (char& ch : n)
    if (!isalnum((unsigned char)ch)) ch = '_';
  return dir + n;
}

INSTANTIATE_TEST_SUITE_P(Programs, Binutils, ::testing::ValuesIn(programs()), test_name);

}  // namespace
