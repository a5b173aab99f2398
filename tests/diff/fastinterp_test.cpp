// tests/diff/fastinterp_test.cpp -- the fast interpreter (runtime/fastinterp.h)
// against the reference interpreter: whole memory images compared after every
// scan, on the shipped examples, on ldgen programs, on the benchmark's
// synthetic programs (bench/synth.h) and on hand-written IL that reaches every
// specialized handler and the generic one with edge values.
//
//   LDC_FAST_SEEDS  ldgen programs in all (default 160, split over 4 shards)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "backend-c/backend_c.h"
#include "bench/synth.h"
#include "runtime/fastinterp.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

std::unique_ptr<Engine> make_fast(const Program& p) {
  BinaryIl bin = encode_il(p);
  if (std::string why = validate_il(bin.code, p.layout()); !why.empty()) throw std::runtime_error("IL " + why);
  return make_fast_interp_engine(bin.code, p.layout());
}

std::string read(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::filesystem::path source_root() {
  return std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
}

// ------------------------------------------------------------------ examples and ldgen

TEST(FastInterp, MatchesOnEveryExample) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(source_root() / "examples")) {
    if (e.path().extension() != ".ld") continue;
    std::filesystem::path csv = e.path();
    csv.replace_extension(".csv");
    ASSERT_TRUE(std::filesystem::exists(csv)) << csv;
    Outcome out = compare_run(read(e.path()), read(csv), make_interp, make_fast);
    EXPECT_EQ(out.kind, Outcome::Kind::Same)
        << e.path().filename() << ": scan " << out.scan << ", " << out.place.name << ": reference " << out.ref_value
        << ", fast " << out.test_value << " " << out.message;
    EXPECT_GT(out.scans, 0);
    n++;
  }
  EXPECT_GE(n, 10);
}

class FastShard : public ::testing::TestWithParam<int> {};

TEST_P(FastShard, MatchesOnLdgenPrograms) {
  const long total = env_long("LDC_FAST_SEEDS", 160);
  for (long i = GetParam(); i < total; i += 4) {
    uint64_t seed = uint64_t(1000 + i);
    GenOptions o;
    o.rungs = 50;
    o.max_depth = 2 + int(seed % 5);
    if (seed % 4 == 1) { o.d = 3; o.f = 2; o.t = 2; o.c = 2; }  // small sets: rungs read each other's results
    GenProgram gp = generate_program(seed, o);
    std::string ld = render(gp), csv = generate_trace(seed, 30 + int(seed % 31), o);
    Outcome out = compare_isolated(ld, csv, make_interp, make_fast);
    ASSERT_NE(out.kind, Outcome::Kind::FrontEndError) << "seed " << seed << ": " << out.message;
    if (!out.failed()) continue;
    Reduced r = minimize(gp, csv, out, [](const std::string& l, const std::string& c) {
      return compare_isolated(l, c, make_interp, make_fast);
    });
    ADD_FAILURE() << reproducer("fast interpreter differs from the reference: ldgen seed " + std::to_string(seed),
                                ldgen_command(seed, o, 30 + int(seed % 31)), gp, r, output_dir(),
                                "fast_seed" + std::to_string(seed), "interp", "fast");
    return;
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, FastShard, ::testing::Range(0, 4));

// ------------------------------------------------------------------ IL programs

// splitmix64 for the inputs
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  int below(int n) { return int(next() % uint64_t(n)); }
};

// Runs `p` on both interpreters for `scans` scans with random inputs (X0..X63,
// WX0..WX15, D0..D15, F0..F7; `edgy` draws words from edge values) and
// compares the whole images after every scan.  "" if they always agree.
// The reference interpreter against `test` (the fast interpreter unless
// given); edgy: edge values in the inputs, and with wild_dt, in dt too.
std::string compare_il(const Program& p, uint64_t seed, int scans, bool edgy, const EngineFactory& test = make_fast,
                       bool wild_dt = false) {
  Layout L = p.layout();
  BinaryIl bin = encode_il(p);
  if (std::string why = validate_il(bin.code, L); !why.empty()) return "invalid IL: " + why;
  auto ref = make_interp_engine(bin.code, L);
  auto fast = test(p);
  Memory a(L), b(L);
  Rng r{seed};
  const int32_t ints[] = {0, 1, -1, 2, 7, -7, 31, 32, 100, -100, INT32_MIN, INT32_MAX, INT32_MIN + 1, 65536};
  const float reals[] = {0.0f, -0.0f, 1.5f, -2.25f, 0.1f, 7.9f, -8.0f, 1e30f, -1e30f, 3e9f, -3e9f,
                         std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                         std::numeric_limits<float>::quiet_NaN(), 2147483648.0f, -2147483648.0f, 1e-40f};
  for (int k = 1; k <= scans; k++) {
    auto both = [&](auto fn) { fn(a); fn(b); };
    for (int i = 0; i < 64; i++) {
      bool v = r.below(2);
      both([&](Memory& m) { m.set_bit(Area::X, i, v); });
    }
    for (int i = 0; i < 16; i++) {
      int32_t v = edgy ? ints[r.below(sizeof ints / sizeof ints[0])] : int32_t(r.below(2001)) - 1000;
      both([&](Memory& m) { m.set_int(Area::WX, i, v); });
      if (edgy && r.below(3) == 0) both([&](Memory& m) { m.set_int(Area::D, i, v); });
    }
    for (int i = 0; i < 8; i++) {
      float v = edgy ? reals[r.below(sizeof reals / sizeof reals[0])]
                     : (i < 4 ? 0.1f + r.below(79) / 10.0f : -8.0f + r.below(161) / 10.0f);
      both([&](Memory& m) { m.set_real(i, v); });
    }
    int32_t dt = wild_dt && r.below(2) ? ints[r.below(sizeof ints / sizeof ints[0])] : int32_t(r.below(61));
    both([&](Memory& m) {
      std::memcpy(m.data() + kSysDt, &dt, 4);
      m.set_bit(Area::S, kBitFirstScan, k == 1);
    });
    ref->scan(a.bytes);
    fast->scan(b.bytes);
    for (uint32_t off = 0; off < L.size; off++) {
      if (a.bytes[off] == b.bytes[off]) continue;
      Place pl = describe(L, off);
      return "scan " + std::to_string(k) + ": " + pl.name + ": reference " + value_at(L, a.bytes, off) + ", tested " +
             value_at(L, b.bytes, off);
    }
    uint32_t n = uint32_t(k);
    both([&](Memory& m) { std::memcpy(m.data() + kSysScan, &n, 4); });
  }
  return "";
}

TEST(FastInterp, MatchesOnSyntheticMixes) {
  for (double pb : {0.0, 0.5, 0.689, 0.95, 1.0}) {
    for (int n : {1, 7, 300, 1500}) {
      for (uint64_t seed = 1; seed <= 3; seed++) {
        synth::SynthOptions o;
        o.n_exe = n;
        o.p_basic = pb;
        o.seed = seed;
        Program p = parse_il_text(synth::synth_il(o), "synth.il");
        synth::ClassCounts c = synth::count_classes(p);
        EXPECT_LE(std::abs(c.total() - n), pb == 0.0 ? 1 : 0) << "n " << n << " p " << pb;
        EXPECT_EQ(compare_il(p, seed, 40, false), "") << "n " << n << " p_basic " << pb << " seed " << seed;
        EXPECT_EQ(compare_il(p, seed + 100, 20, true), "") << "edge values: n " << n << " p_basic " << pb;
      }
    }
  }
}

TEST(FastInterp, MatchesOnEveryClassProgram) {
  for (OpClass c : {OpClass::Basic, OpClass::Compare, OpClass::Move, OpClass::Arith, OpClass::Logic,
                    OpClass::Special, OpClass::Timer, OpClass::Counter}) {
    for (bool powered : {true, false}) {
      Program p = parse_il_text(synth::synth_class_il(c, 400, 5, powered), "class.il");
      EXPECT_EQ(compare_il(p, 9, 60, false), "") << op_class_name(c) << (powered ? "" : " (power off)");
      EXPECT_EQ(compare_il(p, 10, 30, true), "") << op_class_name(c) << " edge values";
    }
  }
}

// Every operand form the decoder tells apart: constants folded, mirrored
// compares, conversions, the generic handler, division rules, timers and
// counters with word presets, jumps to a label and to the end, END.
const char kEdgeIl[] = R"(.edges 4
.rung line 1
    LOAD    X0
    LDGT    5 D0
    ANDBLK
    LDLE    -3 WX1
    ORBLK
    LDEQ    3 3
    LDNE    3 3
    ORBLK
    LDLT    2 D1
    LDGE    D0 D1
    LDEQ    D2 7
    LDNE    F0 F1
    LDLT    F2 1.5
    LDGE    2 F3
    LDGT    D3 F4
    LDEQ    F5 2.0
    ORBLK
    LDGT    1.5 F6
    LDLE    F7 F6
    LDNE    2.5 F7
    ORBLK
    ANDBLK
    OUT     Y0
    OUTN    Y1
    MPS
    AND     X1
    SET     M0
    MRD
    ANDN    X2
    RST     M0
    MPP
    OR      X3
    ORN     X4
    OUT     Y2
.rung line 2
    LOADP   X5 E0
    LOADF   X6 E1
    ORBLK
    OUT     Y3
.rung line 3
    LOADN   X7
    MOV     1e+30 D20
    MOV     -1e+30 D21
    MOV     2.75 D22
    MOV     -7 F20
    MOV     3.5 F21
    MOV     F0 D23
    MOV     D0 F22
    MOV     D1 D24
    MOV     F1 F23
    MOV     WX2 WY0
.rung line 4
    TRUE
    ADD     D0 D1 D30
    SUB     D0 5 D31
    MUL     -3 D1 D32
    DIV     D0 D1 D33
    DIV     D0 0 D34
    DIV     7 D2 D35
    MOD     D0 D1 D36
    MOD     D0 -1 D37
    MOD     9 D3 D38
    WAND    D0 D1 D39
    WOR     D0 255 D40
    WXOR    -1 D1 D41
    SHL     D0 D2 D42
    SHR     D0 33 D43
    SHL     1 D3 D44
    WNOT    D0 D45
    WNOT    5 D46
    ADD     F0 F1 F30
    SUB     F0 F1 F31
    MUL     F0 F1 F32
    DIV     F0 F1 F33
    ADD     D0 F1 D47
    SUB     1.5 D1 F34
    MUL     D0 D1 F35
    DIV     F2 0.0 F36
    DIV     D0 D1 F37
    MOD     7 0 D48
    WAND    D0 D1 F38
    ADD     3 4 D49
    ABS     D0 D50
    ABS     F0 D51
    ABS     F1 F39
    ABS     -5 F40
    SIN     F0 F41
    COS     D0 F42
    TAN     F1 D52
    SQRT    F2 F43
    SQRT    -4.0 F44
    EXP     F3 F45
    LN      F4 F46
    LN      D1 D53
.rung line 5
    LOAD    X8
    TON     T0 D10
    TOF     T1 D11
    TP      T2 D12
    TON     T3 50
    TOF     T4 30
    TP      T5 40
    CTU     C0 D13 E2
    CTD     C1 -5 E3
.rung line 6
    LOAD    X9
    RSTT    T0
    RSTC    C0
    LDGE    T3 20
    OUT     Y4
    LDLT    C1 -3
    OUT     Y5
.rung line 7
    LOAD    X10
    JMP     skip
.rung line 8
    TRUE
    ADD     D60 1 D60
.label skip
.rung line 9
    LOAD    X11
    AND     X12
    JMP     fin
.rung line 10
    TRUE
    ADD     D61 1 D61
    LOAD    X13
    END
.rung line 11
    TRUE
    ADD     D62 1 D62
.label fin
.end
)";

TEST(FastInterp, MatchesOnEveryOperandForm) {
  Program p = parse_il_text(kEdgeIl, "edge.il");
  BinaryIl bin = encode_il(p);
  FastInterpreter fi(bin.code, p.layout());
  EXPECT_EQ(fi.il_instructions(), bin.instr_offset.size());
  EXPECT_LT(fi.specialized(), fi.il_instructions());  // some go to the generic handler
  for (uint64_t seed = 1; seed <= 20; seed++) {
    EXPECT_EQ(compare_il(p, seed, 80, seed % 2 == 0), "") << "seed " << seed;
  }
}

// Timers and counters at their limits: presets from inputs (negative, 0,
// INT32_MAX), elapsed times and counts written by MOV to any value, dt from
// the edge values (negative, INT32_MAX: the exact-sum rule of advance).
const char* kTimerEdgeIl = R"(; timers and counters at their limits
.edges 4
.rung line 1
    LOAD    X0
    MOV     WX0 T0
    MOV     WX1 T1
    MOV     WX2 T2
    MOV     WX3 C0
    MOV     WX4 C1
.rung line 2
    LOAD    X1
    TON     T0 WX5
    TOF     T1 WX6
    TP      T2 WX7
    CTU     C0 WX8 E0
    CTD     C1 WX9 E1
.rung line 3
    LOAD    X2
    AND     X3
    TON     T3 0
    TOF     T4 2147483647
    TP      T5 -5
    LOAD    X4
    ORBLK
    CTU     C2 2147483647 E2
    CTD     C3 0 E3
.rung line 4
    LOAD    X5
    RSTT    T1
    RSTC    C0
    LOADN   X6
    RSTT    T5
    RSTC    C3
.end
)";

// Power known while compiling (-O2's KnownStack): rungs from the rail, and
// what AND, OR, the blocks and MPS / MRD / MPP make of a known 1; the
// instructions after an unknown top must stay gated.
const char* kKnownPowerIl = R"(; power on for certain, and not
.edges 2
.rung line 1
    TRUE
    MOV     WX0 D0
    DIV     WX1 WX2 D1
    MOD     WX1 WX3 D2
    DIV     F0 F1 F2
    SIN     F0 F3
    ADD     F0 F1 F4
    SHL     WX3 WX4 D3
    WNOT    WX5 D4
    RSTT    T0
    RSTC    C0
    CTU     C2 5 E1
    TON     T3 WX14
    TOF     T4 300
    TP      T5 WX15
    OUT     Y0
.rung line 2
    TRUE
    AND     X0
    MOV     WX5 D5
    OR      X1
    SUB     D5 WX6 D6
.rung line 3
    LOAD    X2
    TRUE
    ORBLK
    MOV     WX6 D7
    TRUE
    ANDBLK
    ADD     D7 1 D8
    ANDN    X3
    MUL     D8 3 D9
.rung line 4
    TRUE
    MPS
    AND     X4
    MOV     WX7 D10
    MRD
    MOV     WX8 D11
    MPP
    WXOR    D11 WX9 D12
.rung line 5
    LOAD    X5
    MPS
    TRUE
    ORBLK
    MOV     WX10 D13
    MPP
    MOV     WX11 D14
.rung line 6
    TRUE
    ORN     X6
    SUB     D14 1 D15
    LOADN   X7
    TRUE
    ANDBLK
    ORBLK
    ADD     D15 2 D16
    TON     T1 WX12
    CTU     C1 WX13 E0
.end
)";

// What one scan cannot observe (ir/scanopt.h, -O2): stores overwritten unread
// (across rungs, with and without a read, JMP or END between, SET/RST, gated
// and certain application stores, DIV), unread stack entries (compares, an
// edge contact whose edge must still move), and constants folded or known.
const char* kScanFactsIl = R"(; dead stores, unread entries, folded constants
.edges 3
.rung line 1
    LOAD    X0
    OUT     Y0
    LDGT    WX0 5
    LOADP   X1 E0
    MPP
    SET     Y1
    TRUE
    MOV     WX1 D1
    ADD     D1 3 D2
    MOV     7 D3
    MOV     2.5 F4
.rung line 2
    LOAD    X2
    OUT     Y0
    LOAD    X3
    RST     Y1
    LOAD    X4
    MOV     WX2 D2
    ADD     D3 D3 D4
    MUL     F4 WX3 D5
    DIV     WX4 WX5 D6
    LDLT    D3 WX6
    OUT     Y2
.rung line 3
    LOAD    X5
    JMP     skip
.rung line 4
    LOAD    X6
    OUT     Y0
    TRUE
    MOV     WX7 D6
    MOV     D3 D7
    SQRT    16.0 F5
    LOADF   X7 E1
    LOAD    X8
    ORBLK
    LOAD    X9
    AND     X10
.label skip
.rung line 5
    LOAD    X11
    OUTN    Y0
    ADD     D3 1 D8
    LOAD    X12
    SET     Y1
    TRUE
    MOV     WX8 D2
    LOAD    X13
    END
.rung line 6
    LOAD    X14
    OUT     Y1
    TRUE
    MOV     WX9 D6
    LOADP   X15 E2
    OUT     Y0
.end
)";

// Rungs that read what the rung before them left on the stack (IL text may):
// every native level keeps the stack in ebp from rung to rung then (no slot
// registers, no push dropped at a rung's end, no unread entries); the C route
// refuses such a program by name.
const char* kSharedStackIl = R"(; stack entries read across rungs
.edges 1
.rung line 1
    LOAD    X1
    LOAD    X2
    OUT     Y0
.rung line 2
    ORBLK
    AND     X3
    OUT     Y1
.rung line 3
    LOADP   X4 E0
    LOAD    X5
    LDGT    WX0 3
.rung line 4
    ANDBLK
    MOV     WX1 D0
    ORBLK
    OUT     Y2
.rung line 5
    LOAD    X6
    OUT     Y3
.end
)";

// INT32 DIV and MOD by constants (-O2 multiplies by a magic number: no idiv,
// no S0), with and without power, into words and REALs, on the edge values of
// compare_il's inputs; the divisors around the powers of two, both signs.
std::string constant_division_il() {
  std::string s = ".rung line 1\n    TRUE\n";
  std::string gated = ".rung line 2\n    LOAD X0\n";
  int k = 0;
  for (int32_t d : {2, 3, 5, 6, 7, 9, 10, 12, 25, 60, 100, 125, 641, 1000, 3600, 65535, 65536, 65537, 1000000007,
                    INT32_MAX, INT32_MIN + 1, -2, -3, -7, -10, -60, -641, -65536, -1000000007}) {
    std::string ds = std::to_string(d), wx = "WX" + std::to_string(k % 16);
    s += "    DIV " + wx + " " + ds + " D" + std::to_string(2 * k) + "\n    MOD " + wx + " " + ds + " D" + std::to_string(2 * k + 1) + "\n";
    gated += "    DIV D" + std::to_string(k % 16) + " " + ds + " D" + std::to_string(100 + 2 * k) + "\n    MOD " + wx + " " + ds +
             " D" + std::to_string(101 + 2 * k) + "\n    DIV " + wx + " " + ds + " F" + std::to_string(8 + k) + "\n";
    k++;
  }
  return s + gated + ".end\n";
}

// INT32 divisions of one pair of words after another with power on for
// certain (-O2 takes the earlier result: ScanFacts::reused): the same
// operation again, a MOD after a DIV (a - q*b), a DIV after a MOD (divides),
// and the cases that must divide again: an operand or the earlier
// destination written since, a destination that is an operand, S0 cleared,
// a jump that may skip the earlier division, a gated division in between;
// a DIV after a MOD whose quotient the MOD stores (no code), and the cases
// where it may not: the DIV's destination read or written since, the MOD a
// copy itself, a JMP or END between.
// compare_il's edgy inputs give divisors of 0, -1 and INT32_MIN.
const char* const kRepeatedDivisionIl = R"(
.rung line 1
    TRUE
    DIV     WX0 WX1 D20
    MOD     WX0 WX1 D21
    DIV     WX0 WX1 D22
    MOD     WX0 WX1 D23
    MOD     WX2 WX3 D24
    DIV     WX2 WX3 D25
    MOD     WX2 WX3 D26
    DIV     WX1 WX2 D27
    MOD     WX1 WX2 D28
    MOV     D8 D27
    MOD     WX1 WX2 D29
    DIV     D10 D11 D30
    ADD     D10 1 D10
    DIV     D10 D11 D31
    DIV     D11 D10 D11
    DIV     D11 D10 D32
    MOD     D11 D10 D33
.rung line 2
    LOAD    X2
    DIV     WX0 WX1 D34
    DIV     WX4 WX5 D35
.rung line 3
    TRUE
    DIV     WX4 WX5 D36
    RST     S0
.rung line 4
    TRUE
    DIV     WX0 WX1 D37
    MOD     WX4 WX5 D38
.rung line 5
    LOAD    X1
    JMP     past
.rung line 6
    TRUE
    DIV     WX6 WX7 D39
.label past
.rung line 7
    TRUE
    DIV     WX6 WX7 D40
    MOD     WX6 WX7 D41
    DIV     WX0 WX1 D42
.rung line 8
    TRUE
    MOD     WX8 WX9 D43
    DIV     WX8 WX9 D44
    MOD     WX10 WX11 D45
    MOV     D46 D48
    DIV     WX10 WX11 D46
    MOD     WX12 WX13 D49
    MOV     WX0 D50
    DIV     WX12 WX13 D50
    MOD     WX14 WX15 D51
    MOD     WX14 WX15 D52
    DIV     WX14 WX15 D53
    MOD     WX3 WX9 D54
.rung line 9
    LOAD    X4
    JMP     after
.rung line 10
    TRUE
    DIV     WX3 WX9 D55
    MOD     WX5 WX9 D56
.rung line 11
    LOAD    X5
    END
.rung line 12
    TRUE
    DIV     WX5 WX9 D57
.label after
.rung line 13
    TRUE
    DIV     WX3 WX9 D58
.end
)";

// The native code at every level on the operand forms, the timer limits and
// the class programs (the -O2 code is branch-free there: cmov, setcc, masks).
TEST(NativeEdges, EveryLevelMatchesOnOperandFormsAndTimerLimits) {
  struct Level { const char* name; EngineFactory make; };
  const Level levels[] = {{"-O0", make_native}, {"-O1", make_native_o1}, {"-O2", make_native_o2}};
  Program edge = parse_il_text(kEdgeIl, "edge.il"), timers = parse_il_text(kTimerEdgeIl, "timers.il"),
          known = parse_il_text(kKnownPowerIl, "known.il"), facts = parse_il_text(kScanFactsIl, "facts.il"),
          shared = parse_il_text(kSharedStackIl, "shared.il"), divisions = parse_il_text(constant_division_il(), "div.il"),
          repeated = parse_il_text(kRepeatedDivisionIl, "repeated.il");
  try {
    generate_c(shared, shared.layout());
    ADD_FAILURE() << "the C route compiled a shared stack";
  } catch (CompileError& e) {
    EXPECT_EQ(e.line, 8);  // ORBLK in rung 2
  }
  for (const Level& lv : levels) {
    for (uint64_t seed = 1; seed <= 12; seed++) {
      EXPECT_EQ(compare_il(edge, seed, 60, seed % 2 == 0, lv.make, true), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(timers, seed, 200, true, lv.make, seed % 3 != 0), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(known, seed, 60, true, lv.make, seed % 2 == 0), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(facts, seed, 60, seed % 2 == 0, lv.make), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(shared, seed, 40, false, lv.make), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(divisions, seed, 40, seed % 2 == 1, lv.make), "") << lv.name << " seed " << seed;
      EXPECT_EQ(compare_il(repeated, seed, 60, seed % 4 != 0, lv.make), "") << lv.name << " seed " << seed;
    }
    for (OpClass c : {OpClass::Move, OpClass::Arith, OpClass::Logic, OpClass::Special, OpClass::Timer, OpClass::Counter})
      for (bool powered : {true, false}) {
        Program p = parse_il_text(synth::synth_class_il(c, 300, 5, powered), "class.il");
        EXPECT_EQ(compare_il(p, 10, 30, true, lv.make), "") << lv.name << " " << op_class_name(c);
      }
  }
}

}  // namespace
