// tests/backend-c40sim/gen/c40gen_test.cpp -- the C40 code generator, the C40-hosted
// interpreter and the C40 semantic model on the shipped examples; the REAL
// helpers; the word IL; GNU as for tic4x against our words (docs/c40.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "backend-c40sim/gen/c40gen.h"
#include "backend-c40sim/machine/c40interp.h"
#include "backend-c40sim/machine/c40machine.h"
#include "tests/backend-c40sim/gen/c40model.h"
#include "frontend/frontend.h"
#include "tests/assembler/c40_test_util.h"
#include "tests/backend-c40sim/gen/c40gen_util.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::c40gen;
namespace fp = ldc::c40sim::fp;

std::string read(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::vector<std::string> examples() {
  std::vector<std::string> v;
  for (const auto& e : std::filesystem::directory_iterator(LDC_EXAMPLES_DIR))
    if (e.path().extension() == ".ld") v.push_back(e.path().stem().string());
  std::sort(v.begin(), v.end());
  return v;
}

uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
float flt(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

// ------------------------------------------------------------------ examples

// Every example: the simulated native code (at -O0, -O1 and -O2) and the
// C40-hosted interpreter give the C40 model's image after every scan, byte for
// byte; the model in its
// checking mode gives the reference interpreter's image, and every REAL step
// is within the bound.
TEST(C40Examples, NativeAndInterpreterMatchTheModelAndTheReference) {
  auto names = examples();
  ASSERT_GE(names.size(), 12u);
  for (const std::string& n : names) {
    std::string ld = read(std::string(LDC_EXAMPLES_DIR) + "/" + n + ".ld");
    std::string csv = read(std::string(LDC_EXAMPLES_DIR) + "/" + n + ".csv");
    test::Verdict v = test::check_c40(ld, csv);
    EXPECT_TRUE(v.ok()) << n << ": " << v.text();
    EXPECT_GT(v.scans, 0) << n;
  }
}

// The REAL example exercises every REAL mnemonic and is checked, not skipped.
TEST(C40Examples, RealmathIsCheckedOperationByOperation) {
  std::string ld = read(std::string(LDC_EXAMPLES_DIR) + "/realmath.ld");
  std::string csv = read(std::string(LDC_EXAMPLES_DIR) + "/realmath.csv");
  test::Verdict v = test::check_c40(ld, csv);
  ASSERT_TRUE(v.ok()) << v.text();
  for (Op op : {Op::ADD, Op::SUB, Op::MUL, Op::DIV, Op::SIN, Op::COS, Op::TAN, Op::SQRT, Op::EXP, Op::LN, Op::MOV,
                Op::LDGT, Op::LDEQ})
    EXPECT_GT(v.report.checked[int(op)], 0u) << op_info(op).name;
  EXPECT_EQ(v.report.violations, 0u);
}

// The examples' expected outputs (ldrun --engine=interp) come out of the C40
// engines too: REAL values print with 6 significant digits.
TEST(C40Examples, EnginesPrintTheExpectedOutputs) {
  for (const std::string& n : examples()) {
    std::string base = std::string(LDC_EXAMPLES_DIR) + "/" + n;
    std::string expected = read(base + ".expected");
    std::string header = expected.substr(0, expected.find('\n'));
    Program p = lower_to_il(parse_ld(read(base + ".ld"), n + ".ld"));
    Trace t = read_trace(read(base + ".csv"), n + ".csv", p.aliases);
    RunOptions opt;
    std::stringstream hs(header);
    std::string col;
    std::getline(hs, col, ',');  // "scan"
    while (std::getline(hs, col, ',')) opt.watch.push_back(resolve_probe(col, p.aliases));
    for (int engine = 0; engine < 4; engine++) {  // native -O0, -O1, -O2, the interpreter
      std::unique_ptr<Engine> eng = engine < 3 ? test::make_native(p, engine) : test::make_interp(p);
      std::string out;
      run_trace(*eng, p.layout(), &t, n + ".csv", opt, out);
      EXPECT_EQ(out, expected) << n << (engine < 3 ? " c40sim -O" + std::to_string(engine) : " c40interp");
    }
  }
}

// ------------------------------------------------------------------ REAL helpers

TEST(C40Real, TruncationMatchesTheIlRuleInTheFormat) {
  std::mt19937 rng(40);
  std::vector<float> vals = {0.0f, -0.0f, 0.5f, -0.5f, 1.0f, -1.0f, 2.5f, -2.5f, 3.75f, -3.75f, -0.25f, 1e-30f,
                             -1e-30f, 2147483520.0f, 2147483648.0f, -2147483648.0f, -2147483904.0f, 3e9f, -3e9f,
                             3.4e38f, -3.4e38f, 16777217.0f, -8388607.5f};
  for (int i = 0; i < 200000; i++) vals.push_back(flt(rng()));
  for (float f : vals) {
    if (!(f == 0 || std::isnormal(f))) continue;
    EXPECT_EQ(real_to_int32(real_from_ieee(bits(f))), real_to_int(f)) << f;
  }
  // outside the format: infinities saturate, NaN is the saturated value (no NaN on the C40)
  EXPECT_EQ(real_to_int32(real_from_ieee(0x7F800000u)), INT32_MAX);
  EXPECT_EQ(real_to_int32(real_from_ieee(0xFF800000u)), INT32_MIN);
  EXPECT_EQ(real_to_int32(real_from_ieee(0x7FC00000u)), INT32_MAX);
  EXPECT_EQ(real_to_int32(real_from_ieee(0x00000001u)), 0);  // a denormal is 0
}

TEST(C40Real, IntegerConversionIsExactInRegistersAndTruncatesOnStore) {
  for (int32_t i : {0, 1, -1, 16777216, 16777217, 16777219, -16777219, INT32_MAX, INT32_MIN}) {
    Ext e = real_from_int(i);
    EXPECT_EQ(real_to_int32(e), i);
    float f = flt(real_to_ieee(e));
    EXPECT_LE(ulp_distance(f, float(i)), 1u) << i;
    EXPECT_LE(double(f), double(i)) << i;  // toward -infinity
  }
}

// __divf: within one unit in the last place of the IEEE quotient for normal
// operands and a normal quotient, tiny and huge ones included.
TEST(C40Real, DivisionIsWithinOneUlp) {
  std::mt19937 rng(4001);
  uint32_t worst = 0;
  int n = 0;
  while (n < 300000) {
    float x = flt(rng()), y = flt(rng());
    if (n % 3 == 0) x = float(int32_t(rng()) >> (rng() % 32));
    if (!std::isnormal(x) || !std::isnormal(y) || !std::isnormal(x / y)) continue;
    n++;
    float c = flt(real_to_ieee(real_div(real_from_ieee(bits(x)), real_from_ieee(bits(y)))));
    uint32_t u = ulp_distance(x / y, c);
    worst = std::max(worst, u);
    ASSERT_LE(u, CheckReport::kUlpsArith) << x << " / " << y << ": " << x / y << " vs " << c;
  }
  EXPECT_LE(worst, 1u);
  for (float y : {1.0f, -1.0f, 3.0f, 3.4e38f, -3.4e38f, 1.2e-38f}) {
    EXPECT_EQ(real_to_ieee(real_div(fp::kZero, real_from_ieee(bits(y)))), 0u);  // 0 / y = +0
  }
  EXPECT_LE(ulp_distance(flt(real_to_ieee(real_div(real_from_ieee(bits(3.4e38f)), real_from_ieee(bits(3.4e38f))))), 1.0f), 1u);
  EXPECT_LE(ulp_distance(flt(real_to_ieee(real_div(real_from_ieee(bits(1e-30f)), real_from_ieee(bits(97.0f))))), 1e-30f / 97.0f), 1u);
}

TEST(C40Real, UlpDistance) {
  EXPECT_EQ(ulp_distance(1.0f, 1.0f), 0u);
  EXPECT_EQ(ulp_distance(0.0f, -0.0f), 0u);
  EXPECT_EQ(ulp_distance(1.0f, std::nextafter(1.0f, 2.0f)), 1u);
  EXPECT_EQ(ulp_distance(std::nextafter(0.0f, 1.0f), std::nextafter(0.0f, -1.0f)), 2u);
}

// INT32 DIV and MOD through __divi (and the interpreter's divi): every edge
// pair and random ones of every bit length, on both engines, against the model.
TEST(C40Divide, IntegerDivisionIsExact) {
  std::string ld =
      "rung \"divide\"\n|--+--(DIV D0 D1 D2)\n|  +--(MOD D0 D1 D3)\n|  +--(DIV D1 D0 D4)\n|  +--(MOD D1 D0 D5)\n";
  std::string csv = "D0,D1\n";
  const int32_t edge[] = {0, 1, -1, 2, -2, 3, 7, -7, 100, 65535, 65536, INT32_MAX, INT32_MIN, INT32_MIN + 1,
                          1 << 30, -(1 << 30), 46341};
  for (int32_t a : edge)
    for (int32_t b : edge) csv += std::to_string(a) + "," + std::to_string(b) + "\n";
  std::mt19937 rng(77);
  for (int i = 0; i < 600; i++) {
    int32_t a = int32_t(rng()) >> (rng() % 32), b = int32_t(rng()) >> (rng() % 32);
    csv += std::to_string(a) + "," + std::to_string(b) + "\n";
  }
  test::Verdict v = test::check_c40(ld, csv);
  EXPECT_TRUE(v.ok()) << v.text();
  EXPECT_GT(v.scans, 800);
}

// ------------------------------------------------------------------ word IL

TEST(C40WordIl, EncodesOperandsAndJumpTargets) {
  Program p = parse_il_text(
      ".edges 1\n.rung line 1\n    LOAD X1\n    JMP skip\n.rung line 2\n    LOAD X2\n    ADD D1 70000 F3\n"
      "    MOV 1.5 F0\n.label skip\n.rung line 3\n    LOADP X3 E0\n    OUT Y1\n.end\n",
      "t.il");
  BinaryIl bin = encode_il(p);
  std::vector<uint32_t> w = word_il(bin.code, p.layout());
  std::vector<uint32_t> want = {
      0,                                                         // count, filled below
      uint32_t(Op::LOAD), 0x12u << 24 | 1,                       // LOAD X1
      uint32_t(Op::JMP), 0x04u << 24 | 15,                       // JMP skip (word 15)
      uint32_t(Op::LOAD), 0x12u << 24 | 2,                       // LOAD X2
      uint32_t(Op::ADD), 0x1Bu << 24 | 1, 0x01u << 24, 70000, 0x1Cu << 24 | 3,
      uint32_t(Op::MOV), 0x02u << 24, bits(1.5f), 0x1Cu << 24 | 0,
      uint32_t(Op::LOADP), 0x12u << 24 | 3, 0x03u << 24 | 0,    // word 15
      uint32_t(Op::OUT), 0x13u << 24 | 1,
  };
  want[0] = uint32_t(want.size() - 1);
  EXPECT_EQ(w, want);
}

TEST(C40Interp, DispatchTableFollowsOpsDef) {
  const InterpProgram& ip = interp_program();
  uint32_t table = ip.text.labels.at("dispatch");
  for (int op = 0; op < kOpCount; op++) {
    std::string name = std::string("op_") + op_info(Op(op)).name;
    if (op_info(Op(op)).klass == OpClass::Typed || Op(op) == Op::LOOP) {  // refused when the word IL is built (c40typed_tests)
      EXPECT_EQ(ip.text.labels.count(name), 0u) << name;
      continue;
    }
    EXPECT_EQ(ip.words.at(table + op), ip.text.labels.at(name));
  }
  EXPECT_EQ(ip.entry, ip.text.labels.at("interp"));
}

// ------------------------------------------------------------------ code shape

// Paper 003's Fig. 6 templates: LOAD is LSH/OR on R10 with a direct operand,
// every rung block starts with its LDPK, the prologue sets R10 and the mask R11.
TEST(C40Gen, TemplatesHaveThePaperShape) {
  Program p = parse_il_text(".rung line 1\n    LOAD X1\n    AND X2\n    ORN X3\n    OUT Y0\n.end\n", "t.il");
  C40Code c = generate_c40(p, p.layout());
  std::string text = as::c40::to_gnu_as(c.program);
  EXPECT_NE(text.find("LDI 0, R10"), std::string::npos) << text;
  EXPECT_NE(text.find("LDHI 0xffff, R11"), std::string::npos) << text;
  EXPECT_NE(text.find("LDPK 0x80"), std::string::npos) << text;
  EXPECT_NE(text.find("LSH 1, R10\n\tOR @0x21, R10"), std::string::npos) << text;  // X1: word 16 + 16 + 1
  EXPECT_NE(text.find("STI R0, @0x2020"), std::string::npos) << text;               // Y0: word 32 + 8192
  EXPECT_EQ(c.il_items.size(), 1u);
  EXPECT_EQ(c.il_items[0].size(), 4u);
}

// An edge slot beyond the first 64K words of the data page gets its own LDPK
// and the data page back right after.
TEST(C40Gen, AccessesOutsideTheDataPageSwitchAndRestoreDp) {
  std::string il = ".edges 30001\n.rung line 1\n    LOADP X1 E30000\n    OUT Y0\n.end\n";
  Program p = parse_il_text(il, "t.il");
  C40Layout w = C40Layout::of(p.layout());
  ASSERT_GT(w.addr(Area::E, 30000) >> 16, kDataPage);
  for (int opt = 0; opt <= 2; opt++) {
    C40Code c = generate_c40(p, p.layout(), opt);
    std::string text = as::c40::to_gnu_as(c.program);
    EXPECT_NE(text.find("LDPK 0x81"), std::string::npos) << text;
    // run the far edge on the simulator
    auto res = as::assemble(as::c40::target(), c.program);
    ASSERT_TRUE(res.ok());
    auto words = as::c40::words_of(res.code);
    C40Machine m(p.layout(), words, 0);
    Memory mem(p.layout());
    for (int k = 0; k < 4; k++) {
      mem.set_bit(Area::X, 1, k % 2 == 1);
      m.scan(mem.data());
      EXPECT_EQ(mem.get_bit(Area::Y, 0), k % 2 == 1) << k << " -O" << opt;
      EXPECT_EQ(mem.get_bit(Area::E, 30000), k % 2 == 1) << k << " -O" << opt;
    }
  }
}

// ------------------------------------------------------------------ optimization levels

// The instructions of a program's rung blocks at a level, as GNU as text
// (labels, notes and the prologue left out).
std::string rung_text(const std::string& il, int opt) {
  Program p = parse_il_text(il, "t.il");
  C40Code c = generate_c40(p, p.layout(), opt);
  std::string s;
  for (size_t b = 1; b + 1 < c.program.blocks.size(); b++)
    for (const auto& it : c.program.blocks[b].items)
      if (it.kind == as::ItemKind::Instruction) s += as::c40::print(it.inst) + "\n";
  return s;
}

// -O1 computes a run of contacts with an AND in R0 and pushes it once; the
// OUT after it stores R0 (no AND3 of the top); DP is set once per scan; two
// application instructions share one power test.  -O2 keeps the stack in R8...
TEST(C40Opt, TheLevelsHaveTheirShape) {
  std::string il = ".rung line 1\n    LOAD X1\n    AND X2\n    OUT Y0\n    MOV 5 D1\n    ADD D1 D2 D3\n.end\n";
  EXPECT_EQ(rung_text(il, 0),
            "LDPK 0x80\nLSH 1, R10\nOR @0x21, R10\nLDI @0x22, R0\nOR R11, R0\nAND R0, R10\nAND3 1, R10, R0\n"
            "STI R0, @0x2020\nTSTB 0x1, R10\nBEQ L0\nLDI 5, R0\nSTI R0, @0x8b21\nTSTB 0x1, R10\nBEQ L1\n"
            "LDI @0x8b21, R0\nADDI @0x8b22, R0\nSTI R0, @0x8b23\n");
  EXPECT_EQ(rung_text(il, 1),
            "LDI @0x21, R0\nAND @0x22, R0\nLSH 1, R10\nOR R0, R10\nSTI R0, @0x2020\nTSTB 0x1, R10\nBEQ L1\n"
            "LDI 5, R0\nSTI R0, @0x8b21\nLDI @0x8b21, R0\nADDI @0x8b22, R0\nSTI R0, @0x8b23\n");
  EXPECT_EQ(rung_text(il, 2),
            "LDI @0x21, R8\nAND @0x22, R8\nSTI R8, @0x2020\nBEQ L1\n"  // Z is still that of AND: no TSTB
            "LDI 5, R0\nSTI R0, @0x8b21\nADDI @0x8b22, R0\nSTI R0, @0x8b23\n");  // R0 holds D1: no reload
}

// -O2 drops a load of what the register holds: a rung's first load of the
// word the rung before stored from it (`STI R8, @Y0` ... `LDI @Y0, R8`), or a
// constant again; but not when the load's flags are the power test after it,
// nor after a label a jump may reach; and a rung from the rail (`TRUE`) has no
// power test.
TEST(C40Opt, ReloadsAndKnownPower) {
  std::string il = ".edges 0\n.rung line 1\n    LOAD X1\n    OUT Y0\n.rung line 2\n    LOAD Y0\n    OUT Y1\n"
                   ".rung line 3\n    LOAD Y1\n    OUT Y2\n.rung line 4\n    LOAD Y2\n    MOV 5 D1\n"
                   ".rung line 5\n    TRUE\n    MOV 6 D2\n.end\n";
  EXPECT_EQ(rung_text(il, 2),
            "LDI @0x21, R8\nSTI R8, @0x2020\nSTI R8, @0x2021\nSTI R8, @0x2022\n"
            "LDI @0x2022, R8\nBEQ L1\nLDI 5, R0\nSTI R0, @0x8b21\n"
            "LDI 1, R8\nLDI 6, R0\nSTI R0, @0x8b22\n");
  std::string jumped = ".rung line 1\n    LOAD X1\n    OUT Y0\n    JMP skip\n.label skip\n.rung line 2\n"
                       "    LOAD Y0\n    OUT Y1\n.end\n";
  std::string t = rung_text(jumped, 2);
  EXPECT_NE(t.find("LDI @0x2020, R8"), std::string::npos) << t;
  // a contact pushed only for a block's combine waits for it: paper 001's
  // equation (1), X1 AND (X2 OR (X3 AND X4)), in four instructions and one register
  EXPECT_EQ(rung_text(".rung line 1\n    LOAD X1\n    LOAD X2\n    LOAD X3\n    AND X4\n    ORBLK\n    ANDBLK\n"
                      "    OUT Y1\n.end\n", 2),
            "LDI @0x23, R8\nAND @0x24, R8\nOR @0x22, R8\nAND @0x21, R8\nSTI R8, @0x2021\n");
  EXPECT_EQ(rung_text(".rung line 1\n    LOADN X1\n    LOAD X2\n    ORBLK\n    OUT Y1\n.end\n", 2),
            "LDI @0x22, R8\nLDI @0x21, R0\nXOR 0x1, R0\nOR R0, R8\nSTI R8, @0x2021\n");  // ORN
  EXPECT_NE(rung_text(".rung line 1\n    LOAD X1\n    LOAD X2\n    OUT Y0\n    ANDBLK\n    OUT Y1\n.end\n", 2)
                .find("LDI @0x21, R8"), std::string::npos);  // an output inside the block: no wait
  // a constant loaded again: two RSTT share one `LDI 0, R0`
  EXPECT_EQ(rung_text(".rung line 1\n    LOAD X2\n    RSTT T0\n    RSTT T4\n.end\n", 2),
            "LDI @0x22, R8\nBEQ L1\nLDI 0, R0\nSTI R0, @0xaf20\nSTI R0, @0x8020\nSTI R0, @0x8220\n"
            "STI R0, @0xaf24\nSTI R0, @0x8024\nSTI R0, @0x8224\n");
}

// -O1 (and -O2) turn a branch into its delayed form where two or three
// useful instructions fill the slots: TOF's jump over its off branch takes
// the three instructions before it, the test of IN the preset load before
// it and the first load after it (and a NOP); -O0 has no delayed branch.
TEST(C40Opt, DelayedBranchesWhereTheSlotsFill) {
  std::string il = ".rung line 1\n    LOAD X1\n    TOF T1 300\n.end\n";
  EXPECT_EQ(rung_text(il, 0).find("D "), std::string::npos);
  for (int opt = 1; opt <= 2; opt++) {
    std::string t = rung_text(il, opt);
    std::string pt = opt == 2 ? "IR0" : "R1";  // -O2: a short constant preset in IR0 (its load leaves the flags)
    EXPECT_NE(t.find("BEQD L0\nLDI 300, " + pt + "\nLDI 1, R0\nNOP\nSTI R0, @0x8021\nBRD L1\nSTI R0, @0x8221\nLDI 0, R0\nSTI R0, @0xaf21\n"),
              std::string::npos) << t;
    EXPECT_EQ(t.find("BR "), std::string::npos) << t;
  }
}

// Rungs that read stack entries an earlier rung pushed (IL text can say so)
// keep R10 for the whole program at -O2: the native code still matches the
// C40 model scan by scan at every level.
TEST(C40Opt, RungsThatReadAnEarlierRungsStackStayExact) {
  std::string il =
      ".rung line 1\n    LOAD X1\n    LOAD X2\n    OUT Y0\n"
      ".rung line 2\n    ORBLK\n    AND X3\n    OUT Y1\n"
      ".rung line 3\n    LOAD X4\n    OUT Y2\n.end\n";
  Program p = parse_il_text(il, "t.il");
  for (int opt = 0; opt <= 2; opt++) {
    std::string text = as::c40::to_gnu_as(generate_c40(p, p.layout(), opt).program);
    EXPECT_EQ(text.find("stack in registers"), std::string::npos) << text;
    std::unique_ptr<Engine> nat = test::make_native(p, opt), model = test::make_model(p);
    Memory a(p.layout()), b(p.layout());
    for (int k = 0; k < 32; k++) {
      for (uint32_t x = 1; x <= 4; x++) {
        a.set_bit(Area::X, x, (k >> (x - 1)) & 1);
        b.set_bit(Area::X, x, (k >> (x - 1)) & 1);
      }
      nat->scan(a.bytes);
      model->scan(b.bytes);
      ASSERT_EQ(a.bytes, b.bytes) << "scan " << k << " -O" << opt;
    }
  }
  // without the second rung the same program keeps its stack in registers
  Program q = parse_il_text(".rung line 1\n    LOAD X1\n    LOAD X2\n    OUT Y0\n.end\n", "t.il");
  EXPECT_NE(as::c40::to_gnu_as(generate_c40(q, q.layout(), 2).program).find("stack in registers"), std::string::npos);
}

// Each level is faster than the one below on every example (the cycles of the
// whole trace on the simulated board), and no level is larger in words.
TEST(C40Opt, EveryLevelPaysOnEveryExample) {
  for (const std::string& n : examples()) {
    std::string base = std::string(LDC_EXAMPLES_DIR) + "/" + n;
    Program p = lower_to_il(parse_ld(read(base + ".ld"), n + ".ld"));
    Trace t = read_trace(read(base + ".csv"), n + ".csv", p.aliases);
    uint64_t cycles[3], words[3];
    for (int opt = 0; opt <= 2; opt++) {
      auto res = as::assemble(as::c40::target(), generate_c40(p, p.layout(), opt).program);
      ASSERT_TRUE(res.ok()) << n;
      words[opt] = res.code.size() / 4;
      class Counting : public Engine {
       public:
        explicit Counting(std::unique_ptr<Engine> e) : e_(std::move(e)) {}
        void scan(ImageBytes& mem) override { e_->scan(mem); cycles += e_->last_cost()->cycles; }
        uint64_t cycles = 0;
       private:
        std::unique_ptr<Engine> e_;
      } eng(make_c40sim_engine(res.code, 0, p.layout()));
      std::string out;
      run_trace(eng, p.layout(), &t, n + ".csv", RunOptions{}, out);
      cycles[opt] = eng.cycles;
    }
    EXPECT_LT(cycles[1], cycles[0]) << n;
    EXPECT_LT(cycles[2], cycles[1]) << n;
    EXPECT_LE(words[1], words[0]) << n;
    EXPECT_LE(words[2], words[1]) << n;
  }
}

// ------------------------------------------------------------------ GNU as

std::vector<uint32_t> gnu_words(const std::string& source) {
  std::string as = as::c40::test::tic4x_tool("as"), objcopy = as::c40::test::tic4x_tool("objcopy");
  if (as.empty() || objcopy.empty()) return {};
  std::string dir = as::c40::test::temp_dir();
  std::ofstream(dir + "/a.s") << source;
  std::string out;
  if (as::c40::test::run_command(as + " -mcpu=40 -o " + dir + "/a.o " + dir + "/a.s", &out) != 0) {
    ADD_FAILURE() << "GNU as failed:\n" << out;
    return {};
  }
  if (as::c40::test::run_command(objcopy + " -O binary -j .text " + dir + "/a.o " + dir + "/a.bin", &out) != 0) {
    ADD_FAILURE() << "objcopy failed:\n" << out;
    return {};
  }
  std::string b = read(dir + "/a.bin");
  as::c40::test::run_command("rm -rf " + dir, nullptr);
  std::vector<uint32_t> w(b.size() / 4);
  std::memcpy(w.data(), b.data(), w.size() * 4);
  return w;
}

// `ldc --emit=asm --target=c40` of every example (and of random programs), at
// -O0, -O1 and -O2, assembles with GNU as for tic4x to exactly our words.
TEST(C40GnuAs, EveryExampleAssemblesToOurWords) {
  std::vector<std::pair<std::string, std::string>> progs;
  for (const std::string& n : examples()) progs.emplace_back(n, read(std::string(LDC_EXAMPLES_DIR) + "/" + n + ".ld"));
  for (uint64_t seed : {11u, 12u, 13u}) {
    GenOptions o;
    o.rungs = 80;
    progs.emplace_back("ldgen seed " + std::to_string(seed), generate_ld(seed, o));
  }
  for (const auto& [name, ld] : progs) {
    Program p = lower_to_il(parse_ld(ld, name));
    for (int opt = 0; opt <= 2; opt++) {
      C40Code c = generate_c40(p, p.layout(), opt);
      auto res = as::assemble(as::c40::target(), c.program);
      ASSERT_TRUE(res.ok()) << name << " -O" << opt;
      auto ours = as::c40::words_of(res.code);
      auto theirs = gnu_words(as::c40::to_gnu_as(c.program));
      EXPECT_EQ(theirs.size(), ours.size()) << name << " -O" << opt;
      EXPECT_TRUE(theirs == ours) << name << " -O" << opt;
    }
  }
}

// The typed instructions' code (docs/c40.md, "Typed instructions"): the
// routines (__divu __f2i __i2f __fpack __fadd __fsub __fmul __fdiv) and the
// checked indexed access (LDI *AR0 / STI *AR0) through GNU as too.
TEST(C40GnuAs, TypedCodeAssemblesToOurWords) {
  Program p = parse_il_text(
      ".rung line 1\nLOAD X0\nADD.REAL WX0 WX1 D0\nSUB.REAL WX0 WX1 D1\nMUL.REAL WX0 WX1 D2\nDIV.REAL WX0 WX1 D3\n"
      "DIV.UDINT WX0 WX1 D4\nCONV.DINT.REAL WX0 D5\nCONV.REAL.INT WX1 D6\nTRUNC.UDINT.REAL WX2 D7\n"
      "ROL.BYTE.SINT WX0 WX1 D8\nLT.REAL WX0 WX1\nOUT Y0\n"
      ".rung line 2\nTRUE\nIDX.UDINT WX3 -2 7\nLDX.INT D100 2 D9\nIDX.DINT WX4 0 3\nSTX.REAL WX5 D200 1\n.end\n",
      "typed.il");
  for (int opt = 0; opt <= 2; opt++) {
    C40Code c = generate_c40(p, p.layout(), opt);
    auto res = as::assemble(as::c40::target(), c.program);
    ASSERT_TRUE(res.ok()) << "-O" << opt;
    auto ours = as::c40::words_of(res.code);
    auto theirs = gnu_words(as::c40::to_gnu_as(c.program));
    EXPECT_EQ(theirs.size(), ours.size()) << "-O" << opt;
    EXPECT_TRUE(theirs == ours) << "-O" << opt;
  }
}

}  // namespace
