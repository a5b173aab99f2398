// The C40 simulator: per-instruction semantics and flags, the float format
// and conversions, branches and cycle counts, wait states, stops.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "backend-c40sim/machine/sim.h"
#include "tests/assembler/c40_test_util.h"

using namespace ldc::as;
using namespace ldc::as::c40;
using namespace ldc::c40sim;
using ldc::as::c40::test::build_program;

namespace {

constexpr uint32_t C = 0x01, V = 0x02, Z = 0x04, N = 0x08, UF = 0x10, LV = 0x20, LUF = 0x40;
constexpr uint32_t kData = 0x3000, kIo = 0x80000000u;

Config config(unsigned code_waits = 0) {
  Config c;
  c.regions = {{"code", 0x0000, 0x1000, code_waits},
               {"stack", 0x2000, 0x100, 0},
               {"data", kData, 0x100, 0},
               {"io", kIo, 0x1000, 1}};  // 50 ns SRAM: 1 wait state at 50 ns/cycle
  return c;
}

std::vector<uint32_t> assemble_text(const std::string& text) {
  Result r = assemble(target(), build_program({}, {{1, text}}));
  if (!r.ok()) throw std::runtime_error(r.errors[0].message);
  return words_of(r.code);
}

struct Fixture : ::testing::Test {
  C40Sim sim{config()};
  RunResult run(const std::string& text, uint64_t max_cycles = 100000) {
    sim.load(assemble_text(text), 0);
    sim.set_reg(Reg::SP, 0x1FFF);  // PUSH and CALL increment SP first
    return sim.call(0, max_cycles);
  }
  uint32_t flags() const { return sim.st() & 0x7F; }
};
using SimInt = Fixture;
using SimFloat = Fixture;
using SimFlow = Fixture;

TEST_F(SimInt, LoadsAndFlags) {
  RunResult r = run("LDI -5, R0\nLDI 0, R1\nLDI 7, AR0\nRETSU\n");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R0), uint32_t(-5));
  EXPECT_EQ(sim.reg(Reg::AR0), 7u);
  EXPECT_EQ(flags(), Z);  // from LDI 0, R1; LDI to AR0 sets no flags
  EXPECT_EQ(r.cycles, 3u + 4u);
  EXPECT_EQ(r.instructions, 4u);
}

TEST_F(SimInt, AddSubCompareFlags) {
  struct Case {
    const char* op;
    uint32_t dst, src, out, st;
  } cases[] = {
      {"ADDI", 0x7FFFFFFF, 1, 0x80000000, V | LV},           // N from the exact result
      {"ADDI", 0xFFFFFFFF, 1, 0, Z | C},
      {"ADDI", 0x80000000, 0x80000000, 0, Z | C | V | N | LV},
      {"SUBI", 5, 7, uint32_t(-2), N | C},                     // C = borrow
      {"SUBI", 0x80000000, 1, 0x7FFFFFFF, V | N | LV},         // exact -2^31-1 < 0
      {"SUBI", 7, 5, 2, 0},
      {"MPYI", 0x00400000, 4, 0x01000000, 0},                  // 24-bit operands
      {"MPYI", 0x01000003, 5, 15, 0},                          // bit 24 ignored
      {"MPYI", 0x007FFFFF, 0x007FFFFF, 0xFF000001, V | LV},    // 48-bit product
      {"MPYI", 0x00FFFFFF, 3, uint32_t(-3), N},                // -1 * 3
      {"AND", 0xF0F0, 0xFF00, 0xF000, 0},
      {"ANDN", 0xF0F0, 0xFF00, 0x00F0, 0},
      {"OR", 0x80000000, 1, 0x80000001, N},
      {"XOR", 0x1234, 0x1234, 0, Z},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.op) + " " + std::to_string(c.src) + ", " + std::to_string(c.dst));
    sim.set_reg(Reg::ST, 0);
    sim.set_reg(Reg::R0, c.dst);
    sim.set_reg(Reg::R1, c.src);
    RunResult r = run(std::string(c.op) + " R1, R0\nRETSU\n");
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(sim.reg(Reg::R0), c.out);
    EXPECT_EQ(flags(), c.st);
  }
  // CMPI: signed and unsigned conditions
  sim.set_reg(Reg::ST, 0);
  sim.set_reg(Reg::R0, uint32_t(-1));
  run("CMPI 1, R0\nRETSU\n");  // -1 - 1
  EXPECT_EQ(flags(), N);       // LT (signed) and HS (no borrow: 0xffffffff >= 1)
  sim.set_reg(Reg::R0, 0x80000000);
  run("CMPI 1, R0\nRETSU\n");
  EXPECT_EQ(flags() & (N | V | C), N | V);  // exact -2^31 - 1 is negative: LT holds
  // NEGI / ABSI of the most negative integer overflow
  sim.set_reg(Reg::ST, 0);
  sim.set_reg(Reg::R1, 0x80000000);
  run("NEGI R1, R0\nRETSU\n");
  EXPECT_EQ(sim.reg(Reg::R0), 0x80000000u);
  EXPECT_EQ(flags(), V | C | LV);  // exact 2^31 > 0, borrow
  sim.set_reg(Reg::ST, 0);
  run("ABSI R1, R0\nRETSU\n");
  EXPECT_EQ(sim.reg(Reg::R0), 0x80000000u);
  EXPECT_EQ(flags(), V | LV);
  run("LDI -9, R1\nABSI R1, R0\nNOT R0, R2\nTSTB 1, R0\nRETSU\n");
  EXPECT_EQ(sim.reg(Reg::R0), 9u);
  EXPECT_EQ(sim.reg(Reg::R2), ~9u);
  EXPECT_EQ(flags() & (N | Z), 0u);  // TSTB 1 & 9 = 1
}

TEST_F(SimInt, Shifts) {
  struct Case {
    const char* op;
    uint32_t v;
    int count;
    uint32_t out;
    uint32_t st;
  } cases[] = {
      {"LSH", 0x80000001, 1, 0x00000002, C},
      {"LSH", 0x80000001, -1, 0x40000000, C},
      {"LSH", 0x80000000, -31, 1, 0},
      {"LSH", 0xFFFFFFFF, 32, 0, C | Z},
      {"LSH", 0xFFFFFFFF, -32, 0, C | Z},
      {"LSH", 0xFFFFFFFF, 40, 0, Z},
      {"LSH", 0x12345678, 0, 0x12345678, 0},
      {"ASH", 0x80000000, -1, 0xC0000000, N},
      {"ASH", 0x80000001, -1, 0xC0000000, N | C},
      {"ASH", 0x80000000, -40, 0xFFFFFFFF, N | C},
      {"ASH", 0x40000000, 1, 0x80000000, N},
      {"LSH", 0x00000001, 63, 0, Z},       // count is the low 7 bits, signed
      {"LSH", 0x00000001, 0x41, 0, Z},     // 0x41 = -63
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.op) + " " + std::to_string(c.count));
    sim.set_reg(Reg::ST, 0);
    sim.set_reg(Reg::R0, c.v);
    sim.set_reg(Reg::R1, uint32_t(c.count));
    RunResult r = run(std::string(c.op) + " R1, R0\nRETSU\n");
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(sim.reg(Reg::R0), c.out);
    EXPECT_EQ(flags(), c.st);
  }
  // the paper's bit stack: LSH -1 / LSH 1 on R10, and the 3-operand forms
  sim.set_reg(Reg::R10, 0x6);
  run("LSH -1, R10\nLSH3 3, R10, R11\nASH3 -1, R11, R1\nSUBI3 R1, R11, R2\nRETSU\n");
  EXPECT_EQ(sim.reg(Reg::R10), 3u);
  EXPECT_EQ(sim.reg(Reg::R11), 24u);
  EXPECT_EQ(sim.reg(Reg::R1), 12u);
  EXPECT_EQ(sim.reg(Reg::R2), 12u);
}

TEST_F(SimInt, MemoryAddressingAndStack) {
  sim.write(kData + 5, 42);
  RunResult r = run(R"(LDI 0x3000, AR0
NOP
NOP
LDI *+AR0(5), R0
STI R0, *++AR0(2)
LDI 1, IR0
LDI *AR0--(IR0), R1
PUSH R1
PUSH AR0
POP R2
POP R3
LDIEQ 9, R4
LDINE 8, R4
LDHI 0x8000, R5
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R0), 42u);
  EXPECT_EQ(sim.read(kData + 2), 42u);
  EXPECT_EQ(sim.reg(Reg::R1), 42u);
  EXPECT_EQ(sim.reg(Reg::AR0), kData + 1);
  EXPECT_EQ(sim.reg(Reg::R2), kData + 1);
  EXPECT_EQ(sim.reg(Reg::R3), 42u);
  EXPECT_EQ(sim.reg(Reg::R4), 8u);  // POP R3 = 42 cleared Z
  EXPECT_EQ(sim.reg(Reg::R5), 0x80000000u);
  EXPECT_EQ(sim.reg(Reg::SP), 0x1FFFu);  // balanced, and RETS popped the return address
}

// ---------------------------------------------------------------- floats

double single(float f) { return double(f); }

TEST(SimFp, FormatAndConversions) {
  EXPECT_EQ(fp::to_single(fp::from_double(0.0).v), 0x80000000u);
  EXPECT_EQ(fp::to_single(fp::from_double(1.0).v), 0x00000000u);
  EXPECT_EQ(fp::to_single(fp::from_double(-1.0).v), 0xFF800000u);  // -2 * 2^-1
  EXPECT_EQ(fp::to_single(fp::from_double(-2.0).v), 0x00800000u);
  EXPECT_EQ(fp::to_single(fp::from_double(0.5).v), 0xFF000000u);
  EXPECT_EQ(fp::to_single(fp::from_double(3.0).v), 0x01400000u);
  EXPECT_EQ(fp::to_double(fp::from_single(0x01400000)), 3.0);
  EXPECT_EQ(fp::to_double(fp::from_short(0x0400)), 1.5);
  EXPECT_EQ(fp::to_double(fp::from_short(0x8000)), 0.0);
  EXPECT_EQ(fp::to_double(fp::from_int(INT32_MIN).v), -2147483648.0);
  EXPECT_EQ(fp::to_double(fp::from_int(INT32_MAX).v), 2147483647.0);  // exact in 40 bits
  EXPECT_EQ(fp::to_double(fp::from_double(-0.1).v) <= -0.1, true);     // truncation toward -inf
  bool ov = false;
  EXPECT_EQ(fp::fix(fp::from_double(-1.5).v, &ov), -2);  // floor
  EXPECT_EQ(fp::fix(fp::from_double(1.99).v, &ov), 1);
  EXPECT_EQ(fp::fix(fp::from_double(-0.25).v, &ov), -1);
  EXPECT_EQ(fp::fix(fp::from_double(-2147483648.0).v, &ov), INT32_MIN);
  EXPECT_FALSE(ov);
  EXPECT_EQ(fp::fix(fp::from_double(3e9).v, &ov), INT32_MAX);
  EXPECT_TRUE(ov);
  EXPECT_EQ(fp::fix(fp::from_double(-3e9).v, &ov), INT32_MIN);
  EXPECT_TRUE(ov);
  // overflow saturates, underflow flushes to zero
  fp::Res big = fp::mul(fp::from_double(std::ldexp(1.5, 100)).v, fp::from_double(std::ldexp(1.5, 100)).v);
  EXPECT_TRUE(big.overflow);
  EXPECT_EQ(fp::to_single(big.v), 0x7F7FFFFFu);
  fp::Res tiny = fp::mul(fp::from_double(std::ldexp(1.0, -100)).v, fp::from_double(std::ldexp(1.0, -100)).v);
  EXPECT_TRUE(tiny.underflow);
  EXPECT_TRUE(fp::is_zero(tiny.v));
  fp::Res neg_big = fp::neg(fp::from_single(0x7F800000));
  EXPECT_TRUE(neg_big.overflow);  // -(-2^128) does not fit
  EXPECT_EQ(fp::to_single(neg_big.v), 0x7F7FFFFFu);
  EXPECT_EQ(fp::compare(fp::from_double(-3).v, fp::from_double(2).v), -1);
  EXPECT_EQ(fp::compare(fp::kZero, fp::from_single(0x80123456)), 0);  // every e=-128 is zero
}

TEST(SimFp, IeeeConversionTables) {
  // TMS320C3x/C4x tables: C4x -> IEEE
  EXPECT_EQ(fp::to_ieee(fp::kZero), 0x00000000u);
  EXPECT_EQ(fp::to_ieee(fp::from_single(0x81000000)), 0x00000000u);  // e = -127: too small
  EXPECT_EQ(fp::to_ieee(fp::from_double(1.0).v), 0x3F800000u);
  EXPECT_EQ(fp::to_ieee(fp::from_double(-1.0).v), 0xBF800000u);      // negative, f = 0
  EXPECT_EQ(fp::to_ieee(fp::from_double(-1.5).v), 0xBFC00000u);      // negative, f != 0
  EXPECT_EQ(fp::to_ieee(fp::from_single(0x7F800000)), 0xFF800000u);  // most negative: -inf
  EXPECT_EQ(fp::to_ieee(fp::from_single(0x7F7FFFFF)), 0x7F7FFFFFu);  // most positive
  // IEEE -> C4x
  EXPECT_TRUE(fp::is_zero(fp::from_ieee(0x80000000).v));  // -0
  EXPECT_TRUE(fp::is_zero(fp::from_ieee(0x00000001).v));  // denormal
  EXPECT_TRUE(fp::from_ieee(0x7F800000).overflow);       // +inf
  EXPECT_EQ(fp::to_single(fp::from_ieee(0x7F800000).v), 0x7F7FFFFFu);
  EXPECT_EQ(fp::to_single(fp::from_ieee(0xFFC00000).v), 0x7F800000u);  // -NaN: most negative
  EXPECT_EQ(fp::to_double(fp::from_ieee(0x00800000).v), std::ldexp(1.0, -126));
  EXPECT_EQ(fp::to_double(fp::from_ieee(0x80800000).v), -std::ldexp(1.0, -126));
  // Round trips are exact on normal numbers.
  std::mt19937 rng(123);
  for (int i = 0; i < 100000; ++i) {
    uint32_t w = rng();
    uint32_t e8 = w >> 23 & 0xFF;
    if (e8 == 0 || e8 == 255) continue;
    fp::Res c = fp::from_ieee(w);
    ASSERT_FALSE(c.overflow);
    ASSERT_EQ(fp::to_double(c.v), single(std::bit_cast<float>(w))) << std::hex << w;
    ASSERT_EQ(fp::to_ieee(c.v), w) << std::hex << w;
    // and C4x single -> IEEE -> C4x for exponents -126..127
    uint32_t s = rng();
    int e = int(int8_t(s >> 24));
    if (e < -126) continue;
    Ext x = fp::from_single(s);
    ASSERT_EQ(fp::to_single(fp::from_ieee(fp::to_ieee(x)).v), s) << std::hex << s;
    ASSERT_EQ(double(std::bit_cast<float>(fp::to_ieee(x))), fp::to_double(x)) << std::hex << s;
  }
}

// ADDF/SUBF/MPYF then STF: relative error below 2^-23 (the bound for
// differential tests; docs/c40.md), exact products before the store.
TEST_F(SimFloat, ArithmeticWithinTheStatedBound) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> d(-1000.0f, 1000.0f);
  auto prog = assemble_text(R"(LDF *AR0, R0
LDF *+AR0(1), R1
ADDF3 R1, R0, R2
SUBF3 R1, R0, R3
MPYF3 R1, R0, R4
STF R2, *+AR0(2)
STF R3, *+AR0(3)
STF R4, *+AR0(4)
RETSU
)");
  sim.load(prog, 0);
  for (int i = 0; i < 3000; ++i) {
    float a = d(rng), b = d(rng);
    sim.write(kData, fp::to_single(fp::from_double(a).v));
    sim.write(kData + 1, fp::to_single(fp::from_double(b).v));
    sim.set_reg(Reg::AR0, kData);
    sim.set_reg(Reg::SP, 0x1FFF);
    ASSERT_TRUE(sim.call(0, 1000).ok());
    double exact[3] = {double(a) + b, double(a) - b, double(a) * b};
    Ext regs[3] = {sim.ext(Reg::R2), sim.ext(Reg::R3), sim.ext(Reg::R4)};
    for (int k = 0; k < 3; ++k) {
      double stored = fp::to_double(fp::from_single(sim.read(kData + 2 + k)));
      double in_reg = fp::to_double(regs[k]);
      if (exact[k] == 0) {
        EXPECT_EQ(stored, 0.0);
        continue;
      }
      EXPECT_LE(std::fabs(stored - exact[k]), std::ldexp(std::fabs(exact[k]), -23)) << a << " " << b << " " << k;
      EXPECT_LE(std::fabs(in_reg - exact[k]), std::ldexp(std::fabs(exact[k]), -31)) << a << " " << b << " " << k;
      EXPECT_LE(stored, exact[k]);  // truncation toward -infinity
    }
  }
}

TEST_F(SimFloat, InstructionsAndFlags) {
  sim.write(kData, 0x3FC00000);  // IEEE 1.5
  RunResult r = run(R"(LDI 0x3000, AR0
LDF 1.5, R0
FLOAT -3, R1
MPYF R0, R1
FIX R1, R2
NEGF R1, R3
ABSF R1, R4
FRIEEE *AR0, R5
TOIEEE R1, R6
STF R6, *+AR0(1)
CMPF R0, R5
LDFEQ 2.0, R7
RCPF R0, R8
LDF 0.0, R9
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.get_float(Reg::R1), -4.5);
  EXPECT_EQ(sim.reg(Reg::R2), uint32_t(-5));  // floor(-4.5)
  EXPECT_EQ(sim.get_float(Reg::R3), 4.5);
  EXPECT_EQ(sim.get_float(Reg::R4), 4.5);
  EXPECT_EQ(sim.get_float(Reg::R5), 1.5);
  EXPECT_EQ(sim.read(kData + 1), 0xC0900000u);  // IEEE -4.5
  EXPECT_EQ(sim.get_float(Reg::R7), 2.0);        // CMPF 1.5 - 1.5 set Z
  EXPECT_NEAR(sim.get_float(Reg::R8), 1 / 1.5, std::ldexp(1.0, -8));
  EXPECT_LE(sim.get_float(Reg::R8), 1 / 1.5);
  EXPECT_EQ(flags(), Z);  // LDF 0.0
  // float overflow sets V and latches LV; underflow sets UF and LUF
  sim.set_reg(Reg::ST, 0);
  sim.set_ext(Reg::R0, fp::from_double(std::ldexp(1.0, 120)).v);
  r = run("MPYF R0, R0\nRETSU\n");
  EXPECT_EQ(flags(), V | LV);
  sim.set_reg(Reg::ST, 0);
  sim.set_ext(Reg::R0, fp::from_double(std::ldexp(1.0, -120)).v);
  r = run("MPYF R0, R0\nRETSU\n");
  EXPECT_EQ(flags(), Z | UF | LUF);
}

// Newton division as docs/c40.md describes it: a/b = a * x2 with
// x0 = RCPF b and x(n+1) = x(n) * (2 - b * x(n)).
TEST_F(SimFloat, NewtonDivision) {
  auto prog = assemble_text(R"(RCPF R1, R2
MPYF3 R2, R1, R3
NEGF R3, R3
ADDF 2.0, R3
MPYF R3, R2
MPYF3 R2, R1, R3
NEGF R3, R3
ADDF 2.0, R3
MPYF R3, R2
MPYF R2, R0
RETSU
)");
  sim.load(prog, 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> d(-100.0f, 100.0f);
  for (int i = 0; i < 2000; ++i) {
    float a = d(rng), b = d(rng);
    if (std::fabs(b) < 1e-3f) continue;
    sim.set_ext(Reg::R0, fp::from_double(a).v);
    sim.set_ext(Reg::R1, fp::from_double(b).v);
    sim.set_reg(Reg::SP, 0x1FFF);
    ASSERT_TRUE(sim.call(0, 1000).ok());
    double q = double(a) / double(b);
    EXPECT_LE(std::fabs(sim.get_float(Reg::R0) - q), std::ldexp(std::fabs(q), -21)) << a << "/" << b;
  }
}

// ------------------------------------------------------- flow and cycles

TEST_F(SimFlow, StandardBranchesCostFourCycles) {
  // taken and not taken alike (the pipeline is flushed)
  RunResult r = run("LDI 0, R0\nBNE skip\nLDI 1, R1\nskip:\nCMPI 0, R0\nBEQ done\nLDI 2, R1\ndone:\nRETSU\n");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R1), 1u);
  EXPECT_EQ(r.cycles, 1u + 4 + 1 + 1 + 4 + 4);  // BNE not taken, BEQ taken: 4 each
  EXPECT_EQ(r.instructions, 6u);
  EXPECT_DOUBLE_EQ(r.ns, 15 * 50.0);
}

TEST_F(SimFlow, DelayedBranchRunsThreeMoreInstructions) {
  RunResult r = run(R"(LDI 0, R0
BUD there
ADDI 1, R0
ADDI 2, R0
ADDI 4, R0
ADDI 8, R0
there:
ADDI 16, R0
BNED never
ADDI 32, R0
ADDI 64, R0
ADDI 128, R0
ADDI 256, R0
never:
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  // BUD: its three slots run (1, 2, 4), 8 is skipped; BNED (R0 = 23, NE
  // holds) is taken: 32, 64, 128 run, 256 is skipped.
  EXPECT_EQ(sim.reg(Reg::R0), 1u + 2 + 4 + 16 + 32 + 64 + 128);
  EXPECT_EQ(r.cycles, 1u + 1 + 3 + 1 + 1 + 3 + 4);
  EXPECT_EQ(r.instructions, 11u);
}

TEST_F(SimFlow, CallsAndReturns) {
  RunResult r = run(R"(LDI 1, R0
CALL sub
ADDI 100, R0
RETSU
sub:
ADDI 10, R0
CALLNE sub2
RETSU
sub2:
LDI R0, R1
RETSEQ
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R0), 111u);
  EXPECT_EQ(sim.reg(Reg::R1), 11u);
  // LDI 1, CALL 4, ADDI 1, CALLNE 4, LDI 1, RETSEQ 4 (not taken), RETSU 4,
  // RETSU 4, ADDI 1, RETSU 4
  EXPECT_EQ(r.cycles, 1u + 4 + 1 + 4 + 1 + 4 + 4 + 4 + 1 + 4);
  EXPECT_EQ(sim.reg(Reg::SP), 0x1FFFu);
}

TEST_F(SimFlow, RegisterConflictStalls) {
  // An AR written in execute is used for addressing two cycles later.
  sim.write(kData, 7);
  RunResult r = run("LDI 0x3000, AR0\nLDI *AR0, R0\nRETSU\n");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R0), 7u);
  EXPECT_EQ(r.cycles, 1u + (1 + 2) + 4);
  r = run("LDI 0x3000, AR0\nNOP\nLDI *AR0, R0\nRETSU\n");
  EXPECT_EQ(r.cycles, 1u + 1 + (1 + 1) + 4);
  r = run("LDI 0x3000, AR0\nNOP\nNOP\nLDI *AR0, R0\nRETSU\n");
  EXPECT_EQ(r.cycles, 1u + 1 + 1 + 1 + 4);
  // any register of the group: IR0 written, AR1 used
  r = run("LDI 0x3000, AR1\nNOP\nNOP\nLDI 1, IR0\nLDI *AR1, R0\nRETSU\n");
  EXPECT_EQ(r.cycles, 3u + 1 + (1 + 2) + 4);
  // DP (LDPK) then a direct read of the 1-wait-state I/O table
  sim.write(kIo + 1, 0x55);
  r = run("LDPK 0x8000\nLDI @0x1, R0\nRETSU\n");
  EXPECT_EQ(sim.reg(Reg::R0), 0x55u);
  EXPECT_EQ(r.cycles, 1u + (1 + 2 + 1) + 4);
  // SP: LDI to SP then PUSH
  r = run("LDI 0x2010, SP\nPUSH R0\nPOP R1\nLDI 0x2000, SP\nNOP\nNOP\nRETSU\n");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.cycles, 1u + (1 + 2) + 1 + 1 + 1 + 1 + 4);
  // A writer of R0 does not stall addressing
  r = run("LDI 0x3000, R0\nLDI *AR0, R1\nRETSU\n");
  EXPECT_EQ(r.cycles, 1u + 1 + 4);
}

TEST(SimWait, WaitStatesOnFetchAndData) {
  C40Sim sim(config(2));  // code in 2-wait-state memory
  sim.load(assemble_text("NOP\nNOP\nRETSU\n"), 0);
  sim.set_reg(Reg::SP, 0x1FFF);
  RunResult r = sim.call(0, 1000);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.cycles, 3u * 2 + 1 + 1 + 4);
  C40Sim io(config());
  io.load(assemble_text("LDPK 0x8000\nNOP\nNOP\nLDI @0x2, R0\nSTI R0, @0x3\nADDI @0x2, R0\nRETSU\n"), 0);
  io.set_reg(Reg::SP, 0x1FFF);
  io.write(kIo + 2, 20);
  r = io.call(0, 1000);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(io.read(kIo + 3), 20u);
  EXPECT_EQ(io.reg(Reg::R0), 40u);
  EXPECT_EQ(r.cycles, 3u + 2 + 2 + 2 + 4);
}

TEST_F(SimFlow, Stops) {
  // an illegal word, with its address
  sim.load(assemble_text("NOP\nNOP\n"), 0);
  sim.write(2, 0xFFFFFFFF);
  sim.set_reg(Reg::SP, 0x1FFF);
  RunResult r = sim.call(0, 1000);
  EXPECT_EQ(r.stop, Stop::IllegalInstruction);
  EXPECT_EQ(r.pc, 2u);
  EXPECT_NE(r.error.find("0x00000002"), std::string::npos) << r.error;
  // memory outside every region names the address and the PC
  r = run("LDI 0x1500, AR0\nNOP\nNOP\nLDI *+AR0(0x10), R0\nRETSU\n");
  EXPECT_EQ(r.stop, Stop::MemoryFault);
  EXPECT_NE(r.error.find("0x00001510"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("PC 0x00000003"), std::string::npos) << r.error;
  // runaway code: cycle limit and instruction limit, never a hang
  r = run("loop:\nBU loop\n", 10000);
  EXPECT_EQ(r.stop, Stop::CycleLimit);
  EXPECT_GE(r.cycles, 10000u);
  Config c = config();
  c.max_instructions = 500;
  C40Sim s2(c);
  s2.load(assemble_text("loop:\nBUD loop\nNOP\nNOP\nNOP\n"), 0);
  s2.set_reg(Reg::SP, 0x1FFF);
  r = s2.call(0, 1u << 30);
  EXPECT_EQ(r.stop, Stop::InstructionLimit);
  EXPECT_EQ(r.instructions, 500u);
  // a branch in a delay slot
  r = run("BUD x\nBU x\nNOP\nNOP\nx:\nRETSU\n");
  EXPECT_EQ(r.stop, Stop::Unsupported);
  // circular addressing is not modelled
  r = run("LDI 0x3000, AR0\nNOP\nNOP\nLDI *AR0++(1)%, R0\nRETSU\n");
  EXPECT_EQ(r.stop, Stop::Unsupported);
  // stack outside memory
  sim.set_reg(Reg::SP, 0x10000);
  r = sim.call(0, 100);
  EXPECT_EQ(r.stop, Stop::MemoryFault);
}

// The board's protection (issue 24): a fetch from a region that is not
// executable and a store into one that is not writable stop the run with a
// MemoryFault naming the address and the PC, and leave memory as it was.
Config protected_config() {
  Config c = config();
  c.regions[0].writable = false;    // code: read and execute
  c.regions[1].executable = false;  // stack
  c.regions[2].executable = false;  // data
  c.regions[3].executable = false;  // io
  return c;
}

TEST(SimProtection, AFetchOutsideTheCodeFaults) {
  for (const char* how : {"BU R1", "BR 0x3000", "RETSU"}) {  // a computed branch, a direct one, a return to data
    C40Sim sim(protected_config());
    sim.load(assemble_text(std::string("LDI 0x3000, R1\nPUSH R1\n") + how + "\n"), 0);
    sim.write(kData, assemble_text("RETSU\n")[0]);  // a word that would decode and return
    sim.set_reg(Reg::SP, 0x1FFF);
    RunResult r = sim.call(0, 1000);
    EXPECT_EQ(r.stop, Stop::MemoryFault) << how;
    EXPECT_EQ(r.pc, kData) << how;
    EXPECT_NE(r.error.find("fetch of 0x00003000 outside the code (region 'data' is not executable), at PC 0x00003000 "
                           "(after the instruction at 0x00000002)"),
              std::string::npos) << how << ": " << r.error;
    EXPECT_EQ(r.instructions, 3u) << how;
  }
  // falling off the end of the code into the stack region is the same fault
  Config c = protected_config();
  c.regions = {{"code", 0, 2, 0, true, false}, {"stack", 2, 0x100, 0, false, true}};
  C40Sim sim(c);
  sim.load(assemble_text("NOP\nNOP\n"), 0);
  sim.set_reg(Reg::SP, 0x10);
  RunResult r = sim.call(0, 1000);
  EXPECT_EQ(r.stop, Stop::MemoryFault);
  EXPECT_NE(r.error.find("fetch of 0x00000002 outside the code (region 'stack' is not executable)"), std::string::npos) << r.error;
  // the same code where every region is executable (the default) runs the data word
  C40Sim open(config());
  open.load(assemble_text("LDI 0x3000, R1\nBU R1\n"), 0);
  open.write(kData, assemble_text("RETSU\n")[0]);
  open.set_reg(Reg::SP, 0x1FFF);
  EXPECT_TRUE(open.call(0, 1000).ok());
}

TEST(SimProtection, AStoreIntoTheCodeFaults) {
  C40Sim sim(protected_config());
  const std::vector<uint32_t> code = assemble_text("LDI 4, AR0\nLDI 0x3000, R0\nLDI 1, R1\nSTI R1, *AR0\nRETSU\n");
  sim.load(code, 0);
  sim.set_reg(Reg::SP, 0x1FFF);
  RunResult r = sim.call(0, 1000);
  EXPECT_EQ(r.stop, Stop::MemoryFault);
  EXPECT_EQ(r.pc, 3u);
  EXPECT_NE(r.error.find("write of 0x00000004 into the read-only region 'code', at PC 0x00000003"), std::string::npos) << r.error;
  EXPECT_EQ(sim.read(4), code[4]);  // the RETSU is still there
  // STF, a direct store and PUSH (SP pointed into the code) are stores too
  for (const char* how : {"STF R1, *AR0", "LDPK 0\nSTI R1, @4", "LDI 3, SP\nPUSH R1"}) {
    C40Sim s(protected_config());
    s.load(assemble_text(std::string("LDI 4, AR0\nNOP\nNOP\n") + how + "\nRETSU\nRETSU\n"), 0);
    s.set_reg(Reg::SP, 0x1FFF);
    RunResult q = s.call(0, 1000);
    EXPECT_EQ(q.stop, Stop::MemoryFault) << how;
    EXPECT_NE(q.error.find("write of 0x00000004 into the read-only region 'code'"), std::string::npos) << how << ": " << q.error;
  }
  // the host may still load code, and data stays writable
  sim.write(4, 0);
  EXPECT_EQ(sim.read(4), 0u);
  C40Sim ok(protected_config());
  ok.load(assemble_text("LDI 0x3000, AR0\nLDI 7, R1\nNOP\nSTI R1, *AR0\nRETSU\n"), 0);
  ok.set_reg(Reg::SP, 0x1FFF);
  ASSERT_TRUE(ok.call(0, 1000).ok());
  EXPECT_EQ(ok.read(kData), 7u);
}

// The decode cache holds at most 2^16 entries per region, direct-mapped: code
// longer than that runs right, words 2^16 apart (one cache entry) included,
// and a word the host rewrites is decoded again.
TEST(SimProtection, CodeLongerThanTheDecodeCacheRunsRight) {
  const uint32_t n = (1u << 16) + 1000;
  Config c;
  c.regions = {{"code", 0, n + 1, 0, true, false}, {"stack", 0x100000, 0x10, 0, false, true}};
  C40Sim sim(c);
  std::vector<uint32_t> code(n + 1);
  const uint32_t add1 = encode_at(parse("ADDI 1, R0")), add2 = encode_at(parse("ADDI 2, R0"));
  for (uint32_t i = 0; i < n; i++) code[i] = i < (1u << 16) ? add1 : add2;  // the last 1,000 share entries with the first
  code[n] = encode_at(parse("RETSU"));
  sim.load(code, 0);
  for (int run = 1; run <= 2; run++) {
    sim.set_reg(Reg::SP, 0x100000);
    sim.set_reg(Reg::R0, 0);
    RunResult r = sim.call(0, 10 * n);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(sim.reg(Reg::R0), (1u << 16) + 2 * 1000) << "run " << run;
  }
  sim.write(5, add2);
  sim.set_reg(Reg::SP, 0x100000);
  sim.set_reg(Reg::R0, 0);
  ASSERT_TRUE(sim.call(0, 10 * n).ok());
  EXPECT_EQ(sim.reg(Reg::R0), (1u << 16) + 2 * 1000 + 1);
}

// ------------------------------------------------------- tiny programs

TEST_F(SimFlow, SumAWordArrayWithExactCycles) {
  for (int i = 0; i < 10; ++i) sim.write(kData + i, uint32_t(i * i));
  RunResult r = run(R"(LDI 0x3000, AR0
LDI 0, R0
LDI 9, AR1
loop:
ADDI *AR0++(1), R0
DBU AR1, loop
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.reg(Reg::R0), 285u);
  // 3 loads; the first ADDI waits 2 cycles for AR1's group (written by the
  // LDI just before); 10 x (ADDI 1 + DBU 4); RETSU 4.
  EXPECT_EQ(r.cycles, 3u + 2 + 10 * 5 + 4);
  EXPECT_EQ(r.instructions, 3u + 20 + 1);
}

TEST_F(SimFlow, FloatLoopWithDelayedBranchAndExactCycles) {
  const float xs[4] = {1.25f, -2.5f, 3.0f, 0.125f};
  for (int i = 0; i < 4; ++i) sim.write(kData + i, fp::to_single(fp::from_double(xs[i]).v));
  RunResult r = run(R"(LDI 0x3000, AR0
LDF 0.0, R0
LDI 3, AR1
LDF 1.5, R2
loop:
MPYF3 *AR0++(1), R2, R1
DBUD AR1, loop
ADDF R1, R0
NOP
NOP
RETSU
)");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(sim.get_float(Reg::R0), 1.5 * (1.25 - 2.5 + 3.0 + 0.125));
  // 4 loads; first MPYF3 stalls 1 (AR1 written 1 instruction earlier... two:
  // LDI AR1 then LDF, so 1 cycle); 4 x 5 single-cycle instructions; RETSU 4.
  EXPECT_EQ(r.cycles, 4u + 1 + 4 * 5 + 4);
  EXPECT_EQ(r.instructions, 4u + 20 + 1);
}

}  // namespace
