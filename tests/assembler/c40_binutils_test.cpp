// Independent checks with GNU binutils for tic4x (-mcpu=40): GNU as gives
// the words of every golden row, of our printer's text and of the core's
// programs; objdump disassembles the rows' words to the same instructions
// as our disassembler. The tools come from tests/assembler/build_tic4x_tools.sh;
// without them these tests FAIL.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "c40_test_util.h"

using namespace ldc::as;
using namespace ldc::as::c40;
using namespace ldc::as::c40::test;

namespace {

std::vector<uint32_t> read_words(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return words_of(b);
}

// Assembles GNU as source; returns the .text words (empty + failure on error).
std::vector<uint32_t> gnu_assemble(const std::string& source) {
  std::string as = tic4x_tool("as"), objcopy = tic4x_tool("objcopy");
  if (as.empty() || objcopy.empty()) return {};
  std::string dir = temp_dir();
  std::ofstream(dir + "/a.s") << source;
  std::string out;
  if (run_command(as + " -mcpu=40 -o " + dir + "/a.o " + dir + "/a.s", &out) != 0) {
    ADD_FAILURE() << "GNU as failed:\n" << out;
    return {};
  }
  if (run_command(objcopy + " -O binary -j .text " + dir + "/a.o " + dir + "/a.bin", &out) != 0) {
    ADD_FAILURE() << "objcopy failed:\n" << out;
    return {};
  }
  auto w = read_words(dir + "/a.bin");
  run_command("rm -rf " + dir, nullptr);
  return w;
}

// The instruction as GNU as should see it at word `addr` of a file that
// starts with `.Lcode:`: Address operands relative to .Lcode.
std::string gas_line(const Instruction& in) { return "\t" + print_gnu_as(in, ".Lcode") + "\n"; }

// An instruction moved from address 0 to `addr` with the same displacement.
Instruction shifted(Instruction in, int64_t addr) {
  for (unsigned i = 0; i < in.num_operands; ++i)
    if (in.ops[i].kind == OperandKind::Address) in.ops[i].imm += addr;
  return in;
}

TEST(C40GnuAs, RowsAssembleToTheGoldenWords) {
  auto rows = load_rows();
  std::string by_text = "\t.text\n.Lcode:\n", by_printer = by_text;
  for (size_t i = 0; i < rows.size(); ++i) {
    Instruction in = shifted(parse(rows[i].text), int64_t(i));
    bool has_address = false;
    for (unsigned k = 0; k < in.num_operands; ++k) has_address |= in.ops[k].kind == OperandKind::Address;
    // The row text itself when it has no numeric branch target (GNU as
    // reads those as absolute addresses), else our text.
    by_text += has_address ? gas_line(in) : "\t" + rows[i].text + "\n";
    by_printer += gas_line(in);
  }
  for (const std::string* src : {&by_text, &by_printer}) {
    auto words = gnu_assemble(*src);
    ASSERT_EQ(words.size(), rows.size());
    for (size_t i = 0; i < rows.size(); ++i)
      EXPECT_EQ(hex_word(words[i]), rows[i].hex) << "c40_encode.rows:" << rows[i].line << ": " << rows[i].text;
  }
}

// Random words we decode, at random addresses, printed and fed to GNU as.
TEST(C40GnuAs, RandomDecodedInstructionsAssembleToTheSameWords) {
  std::mt19937 rng(4040);
  std::vector<uint32_t> want;
  std::string src = "\t.text\n.Lcode:\n";
  while (want.size() < 4000) {
    uint32_t w = rng();
    if (want.size() % 3 == 0) w &= 0x3fffffff;
    int64_t addr = int64_t(want.size());
    auto in = decode_word(w, addr);
    if (!in) continue;
    want.push_back(w);
    src += gas_line(*in);
  }
  auto got = gnu_assemble(src);
  ASSERT_EQ(got.size(), want.size());
  size_t bad = 0;
  for (size_t i = 0; i < want.size() && bad < 20; ++i)
    if (got[i] != want[i]) {
      ++bad;
      ADD_FAILURE() << print(*decode_word(want[i], int64_t(i))) << ": ours " << hex_word(want[i])
                    << ", GNU as " << hex_word(got[i]);
    }
}

// --------------------------------------------------------------- objdump

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string norm_operand(std::string o) {
  o = lower(o);
  std::string t;
  for (char c : o)
    if (c != ' ') t += c;
  bool direct = !t.empty() && t[0] == '@';
  std::string num = direct ? t.substr(1) : t;
  if (num.empty()) return t;
  bool neg = num[0] == '-';
  std::string body = neg ? num.substr(1) : num;
  if (body.empty() || !(std::isdigit(static_cast<unsigned char>(body[0])))) return t;
  if (body.find('.') != std::string::npos || body.find('e') != std::string::npos) {
    if (body.compare(0, 2, "0x") != 0) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%f", std::strtod(num.c_str(), nullptr));
      return buf;
    }
  }
  long long v = std::strtoll(body.c_str(), nullptr, 0);
  if (neg) v = -v;
  uint64_t u = uint64_t(v) & (direct ? 0xFFFF : 0xFFFFFFFF);  // objdump adds DP<<16 to @
  return (direct ? "@" : "") + std::to_string(u);
}

std::string normalize(const std::string& text, bool ours) {
  std::string t = lower(text);
  size_t sp = t.find(' ');
  std::string mn = t.substr(0, sp);
  std::string rest = sp == std::string::npos ? "" : t.substr(sp + 1);
  if (ours && mn.size() > 1 && mn.back() == '3' && !rest.empty() &&
      std::count(rest.begin(), rest.end(), ',') >= 1 && mn != "tstb3" ? true : false)
    mn.pop_back();
  if (ours && mn == "tstb3") mn = "tstb";
  std::vector<std::string> ops;
  std::string cur;
  int depth = 0;
  for (char c : rest) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == ',' && depth == 0) {
      ops.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!rest.empty()) ops.push_back(cur);
  if (!ours && mn == "nop" && ops.size() == 1 && ops[0] == "r0") ops.clear();
  std::string out = mn;
  for (size_t i = 0; i < ops.size(); ++i) out += (i ? "," : " ") + norm_operand(ops[i]);
  return out;
}

TEST(C40Objdump, DisassemblyOfTheRowsAgreesWithOurs) {
  std::string objdump = tic4x_tool("objdump");
  ASSERT_FALSE(objdump.empty());
  auto rows = load_rows();
  std::string dir = temp_dir();
  std::vector<uint32_t> words;
  {
    std::ofstream f(dir + "/rows.bin", std::ios::binary);
    for (const Row& r : rows) {
      uint32_t w = uint32_t(std::stoul(r.hex, nullptr, 16));
      words.push_back(w);
      for (int k = 0; k < 4; ++k) f.put(char(w >> (8 * k)));
    }
  }
  std::string out;
  ASSERT_EQ(run_command(objdump + " -D -b binary -m tic4x -EL " + dir + "/rows.bin", &out), 0) << out;
  run_command("rm -rf " + dir, nullptr);
  std::map<uint64_t, std::string> theirs;
  std::istringstream ss(out);
  std::string line;
  while (std::getline(ss, line)) {
    // "   1c:\t1b810000 \ttoieee r0,r1"
    size_t colon = line.find(':');
    size_t tab2 = line.find('\t', colon == std::string::npos ? 0 : colon + 2);
    if (colon == std::string::npos || tab2 == std::string::npos) continue;
    std::string a = line.substr(0, colon);
    size_t p = a.find_first_not_of(' ');
    if (p == std::string::npos || a.find_first_not_of("0123456789abcdef", p) != std::string::npos) continue;
    std::string text = line.substr(tab2 + 1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.pop_back();
    theirs[std::stoull(a.substr(p), nullptr, 16)] = text;
  }
  ASSERT_EQ(theirs.size(), rows.size()) << out.substr(0, 2000);
  for (size_t i = 0; i < rows.size(); ++i) {
    DecodeError e;
    auto in = decode_word(words[i], int64_t(i), &e);
    ASSERT_TRUE(in) << e.message;
    EXPECT_EQ(normalize(print(*in), true), normalize(theirs[i], false))
        << "c40_encode.rows:" << rows[i].line << ": " << rows[i].text << " (objdump: " << theirs[i] << ")";
  }
}

// ------------------------------------------------------ core programs

TEST(C40GnuAs, CoreProgramsMatchGnuAs) {
  C40Program p = build_program({"main", "rung1", "done"},
                              {{10, R"(main::
LDPK 0x8000
LDI @0x1, R0
AND R11, R0
LSH -1, R10
OR R0, R10
BNE skip
CALL rung1
skip:
BR rung1
)"},
                               {20, R"(rung1::
LDI R10, R0
loop:
SUBI 1, R0
BNED loop
ADDI3 *+AR0(3), R1, R2
MPYF3 R1, *AR2, R3
STF R3, *AR1++(1)
DBGE AR3, loop
BU done
skip:
BR done
)"},
                               {30, "done::\nRETSU\n.word main\n.word done\n"}});
  // and a long random one with local branches at every distance
  std::mt19937 rng(7);
  std::vector<BlockText> blocks;
  std::vector<std::string> globals;
  for (int b = 0; b < 60; ++b) {
    globals.push_back("g" + std::to_string(b));
    std::string t = "g" + std::to_string(b) + "::\n";
    int n = int(rng() % 40) + 1;
    for (int i = 0; i < n; ++i) {
      switch (rng() % 7) {
        case 0: t += "M" + std::to_string(i) + ":\n"; break;
        case 1: t += "BNE Z0\n"; break;
        case 2: t += "BR g" + std::to_string(rng() % 60) + "\n"; break;
        case 3: t += "CALLEQ g" + std::to_string(rng() % 60) + "\n"; break;
        case 4: t += "LDI @" + std::to_string(rng() % 65536) + ", R" + std::to_string(rng() % 8) + "\n"; break;
        case 5: t += "BUD end\n"; break;
        default: t += "NOP\n"; break;
      }
    }
    t += "Z0:\nend:\nRETSU\n";
    blocks.push_back({b + 100, t});
  }
  C40Program big = build_program(globals, blocks);
  for (const C40Program* prog : {&p, &big}) {
    Result r = assemble(target(), *prog);
    ASSERT_TRUE(r.ok()) << r.errors[0].message;
    auto words = gnu_assemble(to_gnu_as(*prog));
    EXPECT_EQ(words, words_of(r.code)) << to_gnu_as(*prog);
  }
}

}  // namespace
