// The core's layout and relaxation checked against GNU as: the program is
// printed as GNU as source (to_gnu_as) and must assemble to the same bytes.
#include <gtest/gtest.h>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::test;

namespace {

std::string nops(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += "nop\n";
  return s;
}

void expect_same_as_gnu(const x86::X86Program& p) {
  std::string why;
  ASSERT_TRUE(binutils_available(&why)) << why;
  Result r = assemble(x86::target(), p);
  ASSERT_TRUE(r.ok()) << r.errors[0].message;
  std::string src = x86::to_gnu_as(p), err;
  std::vector<uint8_t> theirs = gnu_assemble(src, &err);
  ASSERT_TRUE(err.empty()) << err;
  if (r.code != theirs) {
    size_t i = 0;
    while (i < r.code.size() && i < theirs.size() && r.code[i] == theirs[i]) ++i;
    ADD_FAILURE() << "first difference at byte " << i << " (sizes " << r.code.size() << " vs "
                  << theirs.size() << ")\n"
                  << x86::listing(p, r);
  }
}

TEST(GnuAsCore, RelaxationBoundariesMatchGnuAs) {
  std::vector<BlockText> blocks;
  int line = 1;
  for (int n : {126, 127, 128, 129}) {
    for (const char* j : {"jmp", "je", "jg"}) {
      blocks.push_back({line++, std::string(j) + " L\n" + nops(n) + "L:\nret"});
      blocks.push_back({line++, "L:\n" + nops(n) + j + " L\nret"});
    }
  }
  expect_same_as_gnu(build_program({}, blocks));
}

TEST(GnuAsCore, CascadingGrowthMatchesGnuAs) {
  std::string t;
  // A chain where every jump sits just at the edge of its reach.
  for (int i = 0; i < 8; ++i) t += "jne L" + std::to_string(i) + "\n" + nops(60);
  for (int i = 0; i < 8; ++i) t += "L" + std::to_string(i) + ":\n" + nops(8);
  t += "B:\n" + nops(120) + "jmp B\njmp A\n" + nops(125) + "A:\nret\n";
  expect_same_as_gnu(build_program({}, {{1, t}}));
}

TEST(GnuAsCore, GlobalJumpsMatchGnuAsWithDisp32) {
  auto p = build_program({"r0", "r1", "r2"},
                        {{1, "r0::\ncmp eax, 0x1\nje r1\njmp r2\nskip:\njne skip\nret"},
                         {2, "r1::\nje r0\ncall r2\njmp r1\nskip:\njmp skip"},
                         {3, "r2::\njl r0\nret"}});
  expect_same_as_gnu(p);
}

TEST(GnuAsCore, LargeProgramMatchesGnuAs) {
  std::vector<std::string> globals;
  std::vector<BlockText> blocks;
  uint32_t seed = 12345;
  auto rnd = [&] {
    seed = seed * 1103515245u + 12345u;
    return (seed >> 16) & 0x7fff;
  };
  const char* fill[] = {"mov eax, dword ptr [rbx+0x10]", "add eax, 0x1", "xor ecx, ecx",
                        "movzx ecx, byte ptr [rbx+0x200]", "or byte ptr [rbx+0x7], 0x10",
                        "addss xmm0, dword ptr [rbx+0x40]", "nop", "sete al"};
  const int nb = 40;
  for (int b = 0; b < nb; ++b) globals.push_back("g" + std::to_string(b));
  for (int b = 0; b < nb; ++b) {
    std::string t = "g" + std::to_string(b) + "::\n";
    for (int l = 0; l < 3; ++l) {
      int n = int(rnd() % 50);
      for (int i = 0; i < n; ++i) t += std::string(fill[rnd() % 8]) + "\n";
      t += "jne x" + std::to_string(rnd() % 3) + "\n";
      if (rnd() % 2) t += "jge g" + std::to_string(rnd() % nb) + "\n";
      t += "x" + std::to_string(l) + ":\n";
    }
    blocks.push_back({b + 1, t});
  }
  expect_same_as_gnu(build_program(globals, blocks));
}

}  // namespace
