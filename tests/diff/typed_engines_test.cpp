// tests/diff/typed_engines_test.cpp -- the typed instructions (issue 25,
// docs/il.md "Typed instructions") on the fast interpreter and the C route,
// against the reference interpreter (which computes with ir/typed.h): whole
// memory images compared after every scan, including S0 and the IDX fault
// record at Sys+8/12/16.  The program holds every typed op at every type it
// takes (and every source type of CONV, TRUNC and the shifts), with device
// operands that the harness fills with edge values each scan (wrap limits,
// MIN / -1, zero divisors, shift counts at and past the width, REAL ties,
// NaN, infinities, values outside INT64) and with constant operands at the
// limits.  The C route is also built with -fsanitize=undefined
// -fno-sanitize-recover, so undefined behaviour in the generated C aborts.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "backend-c/backend_c.h"
#include "backend-c/c_shared.h"
#include "frontend/frontend.h"
#include "ir/typed.h"
#include "runtime/fastinterp.h"
#include "runtime/runtime.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;

struct Rng {  // splitmix64
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  size_t below(size_t n) { return size_t(next() % n); }
};

uint64_t dbits(double d) { uint64_t u; std::memcpy(&u, &d, 8); return u; }
uint32_t fbits(float f) { uint32_t u; std::memcpy(&u, &f, 4); return u; }

// Cell contents at the limits: integer widths, shift counts and divisors.
const uint32_t k32i[] = {0, 1, 0xffffffffu, 2, 7, 0xfffffff9u, 0x7f, 0x80, 0xff, 0x100, 0xff80, 0x7fff, 0x8000,
                         0xffff, 0x10000, 0x11171, 0x7fffffff, 0x80000000u, 0x80000001u, 8, 16, 31, 32, 33, 63, 64,
                         65, 0xffffffe0u};
// REAL cells: ties, the limits of the conversions, NaN (one: which of two
// NaN operands IEEE arithmetic passes on is the compiler's choice of operand
// order, so the inputs hold only the default NaN), infinities, a subnormal.
const uint32_t k32f[] = {0, fbits(1.5f), fbits(2.5f), fbits(-2.5f), fbits(3.5f), fbits(0.5f), fbits(-0.5f),
                         fbits(-0.0f), fbits(INFINITY), fbits(-INFINITY), fbits(NAN), fbits(2147483648.0f),
                         fbits(9.2233720e18f), fbits(-9.2233720e18f), fbits(1.8446744e19f), fbits(1e-40f),
                         fbits(0.1f), fbits(65535.5f), fbits(-129.5f), fbits(255.5f), fbits(100.0f), fbits(1.0f),
                         fbits(-1.0f), fbits(2.0f)};
const uint64_t kNsDay = 86400ull * 1000000000ull;
// Pairs of cells: 64-bit integers, times and dates at the limits ...
const uint64_t k64i[] = {0, 1, ~0ull, 0x8000000000000000ull, 0x7fffffffffffffffull, 2, 1000000, 1500000,
                         0 - 1500000ull, kNsDay, 5 * kNsDay + 12345, 0 - kNsDay + 1, 64, 0x100000000ull,
                         0xffffffff80000000ull, 0x7fffffff, 0xffffffffull};
// ... and LREALs (the default NaN only, as above).
const uint64_t k64d[] = {0, dbits(1.5), dbits(2.5), dbits(-2.5), dbits(3.5), dbits(0.5), dbits(-0.5), dbits(-0.0),
                         dbits(INFINITY), dbits(-INFINITY), dbits(NAN), dbits(9223372036854775808.0),
                         dbits(-9223372036854775808.0), dbits(18446744073709551616.0), dbits(1e300), dbits(1e-310),
                         dbits(0.1), dbits(2.0), dbits(-1e10), dbits(123456789.125), dbits(4503599627370497.5),
                         dbits(-0.75), dbits(1e-3), dbits(1.0), dbits(-1.0), dbits(0.5000000000000001),
                         dbits(-0.5000000000000001), dbits(4503599627370497.0), dbits(-4503599627370497.0)};
// Dates for DT_TO_DATE / DT_TO_TOD: typed.h's day arithmetic overflows INT64
// within a day of INT64_MIN (docs/runtime.md), so the day-taking conversions
// read these instead.
const int64_t kDates[] = {0, 1, -1, int64_t(kNsDay), -int64_t(kNsDay), int64_t(kNsDay) * 20000 + 7,
                          -int64_t(kNsDay) * 20000 - 7, std::numeric_limits<int64_t>::max(),
                          std::numeric_limits<int64_t>::min() + 2 * int64_t(kNsDay)};

// Where the generated program reads and writes: each source reads the inputs
// of its kind.
constexpr uint32_t kInt = 0, kIntCells = 100;    // D0..D99: integers (cells and pairs), new each scan
constexpr uint32_t kReal = 100, kRealCells = 40;  // D100..D139: REALs
constexpr uint32_t kLreal = 140, kLrealCells = 60;  // D140..D199: LREALs (pairs)
constexpr uint32_t kArr = 200;                // D200..D229: arrays LDX reads (integers)
constexpr uint32_t kDate = 230;               // D230..D239: dates (pairs)
constexpr uint32_t kIdx = 240;                // D240..D255: small indices (pairs, -3..8)
constexpr uint32_t kOut = 1000;               // results from D1000 on
constexpr uint32_t kStx = 4000;               // STX arrays from D4000 on (24 cells each)

// Constants of type t at its limits, as canonical bits.
uint64_t edge_const(Ty t, Rng& r) {
  if (t == Ty::BOOL) return r.below(2);
  if (t == Ty::REAL) {
    const float f[] = {0.0f, -0.0f, 1.5f, 2.5f, -2.5f, 0.5f, 1e10f, -3.75f, 0.1f, 65535.5f, 3.4e38f};
    return fbits(f[r.below(std::size(f))]);
  }
  if (t == Ty::LREAL) {
    const double d[] = {0.0, -0.0, 1.5, 2.5, -2.5, 0.5, 1e300, -3.75, 0.1, 9.3e18, -9.3e18, 2e19};
    return dbits(d[r.below(std::size(d))]);
  }
  uint64_t v = r.below(2) ? k64i[r.below(std::size(k64i))] : uint64_t(int64_t(int32_t(k32i[r.below(std::size(k32i))])));
  return typed::norm(t, v);
}

// Builds the IL text of a program with every (op, T, U) the op table allows.
class Gen {
 public:
  explicit Gen(uint64_t seed) : r_{seed} {}

  std::string program() {
    for (int o = 0; o < kOpCount; o++) {
      const Op op = Op(o);
      if (op_info(op).klass != OpClass::Typed || op == Op::TIDX || op == Op::TLDX || op == Op::TSTX) continue;
      for (int ti = 0; ti < kTyCount; ti++)
        for (int ui = 0; ui <= kTyCount; ui++) {
          const Ty t = Ty(ti), u = op_info(op).typed == 2 ? Ty(ui) : Ty::None;
          if ((op_info(op).typed == 2) == (ui == kTyCount) || !op_takes(op, t, u)) continue;
          if (typed::is_string_instr(op, t, u)) continue;  // the interpreters only: tests/typed strings*
          rung();
          for (int form = 0; form < (op_info(op).nopd == 2 && !op_info(op).push ? 2 : 3); form++) instr(op, t, u, form);
          if ((op == Op::TDIV || op == Op::TMOD) && !typed::is_real(t)) {  // the divisors at the limits
            instr(op, t, u, 2, "0");
            if (typed::is_signed(t)) instr(op, t, u, 2, "-1");
          }
        }
    }
    // arrays last: an index fault ends the scan there
    for (int ti = 0; ti < kTyCount; ti++)
      if (op_takes(Op::TIDX, Ty(ti), Ty::None))
        for (int k = 0; k < kTyCount; k++)
          if (Ty(k) != Ty::STRING) indexed(Ty(ti), Ty(k));
    return text_ + ".end\n";
  }

 private:
  Rng r_;
  std::string text_;
  int line_ = 0, in_rung_ = 0;
  uint32_t out_ = kOut, bit_ = 100, stx_ = kStx, stx_bit_ = 2000;

  void rung() {
    text_ += ".rung line " + std::to_string(++line_) + "\n";
    text_ += r_.below(4) == 0 ? "    TRUE\n" : "    LOAD X" + std::to_string(r_.below(64)) + "\n";
  }
  std::string src(Ty t) {
    if (t == Ty::REAL) return src(t, kReal, kRealCells);
    if (t == Ty::LREAL) return src(t, kLreal, kLrealCells);
    return src(t, kInt, kIntCells);
  }
  std::string src(Ty t, uint32_t from, uint32_t cells) {
    if (t == Ty::BOOL) return "X" + std::to_string(r_.below(64));
    uint32_t i = from + uint32_t(r_.below(cells));
    if (ty_info(t).cells == 2) i &= ~1u;
    return "D" + std::to_string(i);
  }
  std::string konst(Ty t) { return typed_const_text(t, edge_const(t, r_)); }
  std::string dst(Ty t) {
    if (t == Ty::BOOL) return "M" + std::to_string(bit_++);
    std::string d = "D" + std::to_string(out_);
    out_ += uint32_t(ty_info(t).cells);
    return d;
  }
  // form 0: devices; 1: the first source a constant; 2: the second
  void instr(Op op, Ty t, Ty u, int form, const std::string& fixed = "") {
    const OpInfo& oi = op_info(op);
    std::string s = "    " + op_spelling(Instr{op, t, u, {}, {}}) + " ";
    for (int i = 0; i < oi.nopd; i++) {
      const char sig = oi.operands[i];
      const Ty ty = sig == 'x' ? u : t;
      if (sig == 'r') s += dst(t);
      else if (op == Op::TCONV && (t == Ty::DATE || t == Ty::TOD) && u == Ty::DT)  // the dates kept from INT64_MIN
        s += i + 1 == form ? std::to_string(kDates[r_.below(std::size(kDates))]) : src(ty, kDate, 10);
      else if (i + 1 == form) s += fixed.empty() ? konst(ty) : fixed;
      else s += src(ty);
      s += i + 1 < oi.nopd ? " " : "\n";
    }
    text_ += s;
    if (oi.push) text_ += "    OUT M" + std::to_string(bit_++) + "\n    MPP\n";
  }
  // IDX.T of an index (a word of small values, or a constant) and the LDX.E /
  // STX.E right after it, E every type
  void indexed(Ty t, Ty e) {
    rung();
    const int32_t lo = typed::is_signed(t) ? -2 : 0, hi = 5;
    const std::string idx = r_.below(8) == 0 ? std::to_string(r_.below(7)) : src(t, kIdx, 16);
    text_ += "    IDX." + std::string(ty_info(t).name) + " " + idx + " " + std::to_string(lo) + " " + std::to_string(hi) + "\n";
    const uint32_t cells = uint32_t(std::max(ty_info(e).cells, 1)), stride = cells + uint32_t(r_.below(2));
    const std::string en = ty_info(e).name;
    if (r_.below(2)) {
      std::string base = e == Ty::BOOL ? "X" + std::to_string(r_.below(40)) : "D" + std::to_string(kArr + uint32_t(r_.below(4)) * 2);
      text_ += "    LDX." + en + " " + base + " " + std::to_string(stride) + " " + dst(e) + "\n";
    } else {
      std::string base;
      if (e == Ty::BOOL) base = "M" + std::to_string(stx_bit_), stx_bit_ += 20;
      else base = "D" + std::to_string(stx_), stx_ += 24;
      std::string v = r_.below(3) == 0 ? konst(e) : src(e);
      text_ += "    STX." + en + " " + v + " " + base + " " + std::to_string(stride) + "\n";
    }
  }
};

// The inputs of one scan, the same on every engine's image.
// finite: no NaN or infinity among the REAL and LREAL inputs (for programs
// that compute on their own results, where a NaN made inside could meet one
// of the inputs).
void fill_inputs(Memory& m, Rng& r, int scan, bool finite) {
  const Layout& L = m.layout;
  auto cell = [&](uint32_t i, uint32_t v) { std::memcpy(m.data() + L.addr(Area::D, i), &v, 4); };
  auto pair = [&](uint32_t i, uint64_t v) { cell(i, uint32_t(v)), cell(i + 1, uint32_t(v >> 32)); };
  // a third of the integer inputs from the values of the MIN / -1 rules
  const uint32_t hot32[] = {0, 1, 0xffffffffu, 0x80000000u, 0x7fffffffu, 0xffff8000u, 0xffffff80u};
  const uint64_t hot64[] = {0, 1, ~0ull, 0x8000000000000000ull, 0x7fffffffffffffffull};
  auto ints = [&](uint32_t from, uint32_t n) {
    for (uint32_t i = from; i < from + n; i += 2) {
      if (r.below(3) == 0) {
        if (r.below(2)) pair(i, hot64[r.below(std::size(hot64))]);
        else cell(i, hot32[r.below(std::size(hot32))]), cell(i + 1, hot32[r.below(std::size(hot32))]);
      } else if (r.below(2)) pair(i, k64i[r.below(std::size(k64i))]);
      else cell(i, k32i[r.below(std::size(k32i))]), cell(i + 1, k32i[r.below(std::size(k32i))]);
    }
  };
  ints(kInt, kIntCells);
  ints(kArr, 30);
  for (uint32_t i = kReal; i < kReal + kRealCells; i++) {
    uint32_t v = k32f[r.below(std::size(k32f))];
    cell(i, finite && !std::isfinite(typed::f32(v)) ? fbits(1.0f) : v);
  }
  for (uint32_t i = kLreal; i < kLreal + kLrealCells; i += 2) {
    uint64_t v = k64d[r.below(std::size(k64d))];
    pair(i, finite && !std::isfinite(typed::f64(v)) ? dbits(1.0) : v);
  }
  for (uint32_t i = kDate; i < kDate + 10; i += 2) pair(i, uint64_t(kDates[r.below(std::size(kDates))]));
  for (uint32_t i = kIdx; i < kIdx + 16; i += 2) pair(i, uint64_t(int64_t(r.below(12)) - 3));
  for (uint32_t i = 0; i < 64; i++) m.set_bit(Area::X, i, r.below(2));
  int32_t dt = int32_t(r.below(50));
  std::memcpy(m.data() + kSysDt, &dt, 4);
  m.set_bit(Area::S, kBitFirstScan, scan == 1);
  m.set_bit(Area::S, kBitError, false);  // so that each scan's S0 is seen
}

// Runs `test` beside the reference interpreter for `scans` scans; "" or the first difference.
std::string compare(const Program& p, Engine& test, uint64_t seed, int scans, int* faults = nullptr,
                    bool finite = false) {
  const Layout L = p.layout();
  BinaryIl bin = encode_il(p);
  if (std::string why = validate_il(bin.code, L); !why.empty()) return "invalid IL: " + why;
  auto ref = make_interp_engine(bin.code, L);
  Memory a(L), b(L);
  Rng ra{seed}, rb{seed};
  for (int k = 1; k <= scans; k++) {
    fill_inputs(a, ra, k, finite);
    fill_inputs(b, rb, k, finite);
    ref->scan(a.bytes);
    test.scan(b.bytes);
    uint32_t fault;
    std::memcpy(&fault, a.data() + kSysFault, 4);
    if (faults) *faults += fault != 0;
    for (uint32_t off = 0; off < L.size; off++)
      if (a.bytes[off] != b.bytes[off])
        return "scan " + std::to_string(k) + ": " + diff::describe(L, off).name + ": reference " +
               diff::value_at(L, a.bytes, off) + ", tested " + diff::value_at(L, b.bytes, off);
    std::memset(a.data() + kSysFault, 0, 16);  // the runtime would stop; the test runs on
    std::memset(b.data() + kSysFault, 0, 16);
    uint32_t n = uint32_t(k);
    std::memcpy(a.data() + kSysScan, &n, 4);
    std::memcpy(b.data() + kSysScan, &n, 4);
  }
  return "";
}

std::unique_ptr<FastInterpreter> make_fast(const Program& p) {
  BinaryIl bin = encode_il(p);
  return std::make_unique<FastInterpreter>(bin.code, p.layout());
}

// The C route in a directory of its own, removed with it.
struct CRoute {
  std::filesystem::path dir;
  std::unique_ptr<Engine> engine;
  CRoute(const Program& p, const std::vector<std::string>& flags) {
    std::string tmpl = (std::filesystem::temp_directory_path() / "ldc-typed-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    dir = tmpl;
    engine = make_shared_object_engine(build_c_text(generate_c(p, p.layout()), dir.string(), flags), kCScanSymbol);
  }
  ~CRoute() {
    engine.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

Program typed_program(uint64_t seed) {
  std::string text = Gen(seed).program();
  if (const char* dump = std::getenv("LDC_TYPED_DUMP")) {  // the program, for a reproducer
    FILE* f = std::fopen((std::string(dump) + std::to_string(seed) + ".il").c_str(), "w");
    if (f) std::fputs(text.c_str(), f), std::fclose(f);
  }
  return parse_il_text(text, "typed.il");
}

TEST(TypedEngines, ProgramHoldsEveryTypedOpAtEveryType) {
  Program p = typed_program(1);
  std::map<std::string, int> seen;
  size_t n = 0;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      if (op_info(in.op).klass == OpClass::Typed) seen[op_spelling(in)]++, n++;
  size_t want = 0;
  for (int o = 0; o < kOpCount; o++)
    for (int t = 0; t < kTyCount; t++)
      for (int u = 0; u <= kTyCount; u++) {
        const Op op = Op(o);
        if (op_info(op).klass != OpClass::Typed || (op_info(op).typed == 2) == (u == kTyCount)) continue;
        if (!op_takes(op, Ty(t), op_info(op).typed == 2 ? Ty(u) : Ty::None)) continue;
        if (typed::is_string_instr(op, Ty(t), op_info(op).typed == 2 ? Ty(u) : Ty::None)) continue;
        want++;
        Instr in{op, Ty(t), op_info(op).typed == 2 ? Ty(u) : Ty::None, {}, {}};
        EXPECT_TRUE(seen.count(op_spelling(in)) || op == Op::TLDX || op == Op::TSTX) << op_spelling(in);
      }
  EXPECT_GT(want, 300u);
  EXPECT_GT(n, 1000u);
}

TEST(TypedEngines, FastInterpreterMatchesScanByScan) {
  int faults = 0;
  for (uint64_t seed = 1; seed <= 6; seed++) {
    Program p = typed_program(seed);
    auto fast = make_fast(p);
    EXPECT_EQ(compare(p, *fast, seed * 77, 40, &faults), "") << "seed " << seed;
  }
  EXPECT_GT(faults, 20);  // index faults happened (and ended scans) on both
}

// One build (cc -O2 takes seconds on this program), inputs of two seeds.
TEST(TypedEngines, CRouteMatchesScanByScan) {
  Program p = typed_program(2);
  CRoute c(p, {});
  for (uint64_t seed : {77, 78}) EXPECT_EQ(compare(p, *c.engine, seed, 40), "") << "inputs " << seed;
}

// -fno-sanitize-recover: any undefined behaviour of the generated C aborts
// the test with UBSan's message (at -O0, after the -O2 of the build: the
// checks are the same and the compile is three times faster).
TEST(TypedEngines, CRouteHasNoUndefinedBehaviour) {
  Program p = typed_program(3);
  CRoute c(p, {"-O0", "-fsanitize=undefined", "-fno-sanitize-recover=all"});
  EXPECT_EQ(compare(p, *c.engine, 1234, 40), "");
}

// Values at the limits, by the rules of docs/il.md (the expected value after
// each instruction says which rule gives it), on all three engines.
const char kLimitsIl[] = R"(.rung line 1
    TRUE
    MOVE.INT 32767 D0
    ADD.INT D0 1 D1
    MOVE.DINT -2147483648 D2
    DIV.DINT D2 -1 D3
    MOD.DINT D2 -1 D4
    DIV.INT D0 0 D5
    CONV.INT.REAL 2.5 D6
    CONV.INT.REAL 3.5 D7
    CONV.INT.REAL -2.5 D8
    CONV.UINT.REAL -1.5 D9
    CONV.DINT.LREAL 1e300 D10
    SHL.WORD.INT 1 16 D11
    SHL.WORD.INT 1 -1 D12
    ROL.BYTE.SINT 129 -1 D13
    ABS.SINT -128 D14
    CONV.TIME.DINT 1500 D16
    CONV.DINT.TIME D16 D18
    TRUNC.DINT.REAL -2.75 D19
    NOT.BYTE 15 D20
    MUL.UINT 65535 65535 D21
    MOVE.DINT 70000 D22
    MOVE.INT D22 D23
.rung line 2
    TRUE
    IDX.INT 11 1 10
    LDX.INT D0 1 D30
.rung line 3
    TRUE
    MOVE.INT 1 D31
.end
)";

TEST(TypedEngines, LimitsFollowTheRulesOnEveryEngine) {
  Program p = parse_il_text(kLimitsIl, "limits.il");
  BinaryIl bin = encode_il(p);
  ASSERT_EQ(validate_il(bin.code, p.layout()), "");
  CRoute c(p, {});
  std::vector<std::pair<const char*, std::unique_ptr<Engine>>> engines;
  engines.emplace_back("interp", make_interp_engine(bin.code, p.layout()));
  engines.emplace_back("fast", make_fast(p));
  engines.emplace_back("c", std::move(c.engine));
  for (auto& [name, e] : engines) {
    Memory m(p.layout());
    e->scan(m.bytes);
    auto d = [&](uint32_t i) { return m.get_int(Area::D, i); };
    SCOPED_TRACE(name);
    EXPECT_EQ(d(1), -32768);           // INT wraps at 16 bits
    EXPECT_EQ(d(3), INT32_MIN);        // MIN / -1 wraps to itself
    EXPECT_EQ(d(4), 0);                // MIN MOD -1 is 0
    EXPECT_EQ(d(5), 0);                // a zero divisor gives 0 ...
    EXPECT_EQ(m.get_bit(Area::S, kBitError), 1);  // ... and sets S0
    EXPECT_EQ(d(6), 2);                // REAL to INT: nearest, ties to even
    EXPECT_EQ(d(7), 4);
    EXPECT_EQ(d(8), -2);
    EXPECT_EQ(d(9), 0);                // to an unsigned type a negative value is 0
    EXPECT_EQ(d(10), 0);               // outside INT64: INT64_MIN, wrapped to 32 bits
    EXPECT_EQ(d(11), 0);               // a shift by the width or more gives 0
    EXPECT_EQ(d(12), 0);               // so does a negative count
    EXPECT_EQ(d(13), 0xC0);            // ROL by -1 is ROR by 1: 1000_0001 -> 1100_0000
    EXPECT_EQ(d(14), -128);            // ABS of SINT -128 wraps
    EXPECT_EQ(int64_t(uint32_t(d(16))) | (int64_t(d(17)) << 32), 1500000000000);  // 1500 s as ns (MatIEC __int_to_time: {IN, 0})
    EXPECT_EQ(d(18), 1500);            // and back: whole seconds (__time_to_int: tv_sec)
    EXPECT_EQ(d(19), -2);              // TRUNC: toward zero
    EXPECT_EQ(d(20), 0xF0);            // NOT of a BYTE: its 8 bits
    EXPECT_EQ(d(21), 1);               // 65535 * 65535 mod 2^16
    EXPECT_EQ(d(23), 4464);            // a DINT cell of 70000 read as an INT: its low 16 bits
    // IDX 11 outside 1..10: the fault record, and the scan ends there
    uint32_t kind, at;
    int64_t index;
    std::memcpy(&kind, m.data() + kSysFault, 4);
    std::memcpy(&at, m.data() + kSysFaultAt, 4);
    std::memcpy(&index, m.data() + kSysFaultValue, 8);
    EXPECT_EQ(kind, kFaultIndex);
    EXPECT_EQ(at, bin.instr_offset[bin.instr_offset.size() - 4]);  // IDX LDX TRUE MOVE: the IDX
    EXPECT_EQ(index, 11);
    EXPECT_EQ(d(30), 0);  // the LDX after it did not run
    EXPECT_EQ(d(31), 0);  // nor the rung after
  }
}

// Found by the 10^5 typed long run (seed 61266, docs/testing.md): -O2 keeps a
// stored word in eax and drops its reload, but a store of eax may leave the
// upper half of rax set (TRUNC's 64-bit result, cut to a UDINT), where the
// 64-bit conversion after it reads rax whole.  By typed.h's rules: TRUNC of
// -1e300 is INT64_MIN (outside INT64), as a UDINT 0; its REAL 0.0.
TEST(TypedEngines, AWordKeptInEaxHasItsUpperHalfZero) {
  const char il[] = R"(.rung line 1
    TRUE
    MOVE.LREAL -1e300 D37
    TRUNC.UDINT.LREAL D37 D32
    CONV.REAL.UDINT D32 D26
    CONV.LREAL.UDINT D32 D40
.end
)";
  Program p = parse_il_text(il, "upper.il");
  using diff::EngineFactory;
  for (auto& [name, make] : std::vector<std::pair<const char*, EngineFactory>>{
           {"interp", [](const Program& q) { return make_interp_engine(encode_il(q).code, q.layout()); }},
           {"native -O0", diff::make_native}, {"native -O1", diff::make_native_o1}, {"native -O2", diff::make_native_o2}}) {
    SCOPED_TRACE(name);
    Memory m(p.layout());
    m.set_int(Area::D, 26, -1), m.set_int(Area::D, 40, -1), m.set_int(Area::D, 41, -1);
    make(p)->scan(m.bytes);
    EXPECT_EQ(m.get_int(Area::D, 32), 0);
    EXPECT_EQ(m.get_int(Area::D, 26), 0);  // 0.0f
    EXPECT_EQ(m.get_int(Area::D, 40), 0);  // 0.0, both words
    EXPECT_EQ(m.get_int(Area::D, 41), 0);
  }
}

// The common cases run in specialized handlers, not the generic routine.
TEST(TypedEngines, FastInterpreterSpecializesTheCommonCases) {
  const char il[] = R"(.rung line 1
    TRUE
    ADD.INT D0 D1 D2
    SUB.DINT D3 5 D4
    MUL.LREAL 1.5 D140 D1008
    DIV.LREAL D140 D142 D1012
    ADD.REAL D100 D101 D16
    MOVE.INT D0 D17
    MOVE.LREAL 2.5 D1018
    MOVE.DINT D3 D20
    LT.INT D0 100
    GE.DINT 5 D3
    OR X0
    EQ.LREAL D144 D1008
    ANDBLK
    ANDBLK
    OUT Y0
    IDX.DINT D3 0 9
    LDX.LREAL D160 2 D1022
    IDX.INT D0 0 9
    STX.DINT D4 D4000 1
.end
)";
  Program p = parse_il_text(il, "common.il");
  auto fast = make_fast(p);
  EXPECT_EQ(fast->specialized(), fast->il_instructions());
  EXPECT_EQ(compare(p, *fast, 5, 30), "");
}

// The typed benchmark of docs/runtime.md: the fast interpreter agrees, and
// only its MIN / MAX clamps and conversions take the generic routine.
TEST(TypedEngines, FastInterpreterMatchesOnTheTypedBenchmark) {
  std::ifstream f(LDC_TYPED_BENCH);
  std::stringstream ss;
  ss << f.rdbuf();
  Program p = parse_il_text(ss.str(), "typed_bench.il");
  auto fast = make_fast(p);
  size_t generic = 0;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) generic += in.op == Op::TMIN || in.op == Op::TMAX || in.op == Op::TCONV;
  EXPECT_GT(generic, 0u);
  EXPECT_EQ(fast->il_instructions() - fast->specialized(), generic);
  for (uint64_t seed : {1, 2}) EXPECT_EQ(compare(p, *fast, seed, 20, nullptr, true), "") << "inputs " << seed;
}

// A chart's C (c_rungs, c_code: paper 001's switch form) has no binary IL
// offsets: it translates typed instructions but refuses an IDX by name.
TEST(TypedEngines, ChartCTranslatesTypedInstructionsButRefusesIdx) {
  Program p = parse_il_text(".rung line 1\n    TRUE\n    ADD.INT D0 1 D1\n.end\n", "t.il");
  EXPECT_NE(c_rungs(p.rungs, {}, p.layout(), "  ").find("st_INT(m, "), std::string::npos);
  Program q = parse_il_text(".rung line 1\n    TRUE\n    IDX.INT D0 1 5\n    LDX.INT D10 1 D1\n.end\n", "t.il");
  try {
    c_rungs(q.rungs, {}, q.layout(), "  ");
    ADD_FAILURE() << "the chart form translated an IDX";
  } catch (const CompileError& e) {
    EXPECT_NE(std::string(e.what()).find("IDX.INT"), std::string::npos) << e.what();
  }
}

// A chart whose IL actions hold typed instructions: its C (paper 001's
// switch form) against the reference interpreter on the lowered chart.
const char kTypedChart[] = R"(# typed instructions in a chart's IL actions (the C route's chart form)
flags M100
initial step A
  N il {
  TRUE
  ADD.INT D0 1000 D0
  MUL.LREAL D2 1.5 D4
  CONV.DINT.LREAL D4 D6
  SHL.WORD.INT D0 3 D8
  }
transition X0
step B
  P il {
  TRUE
  MOVE.LREAL 2.5 D2
  LT.INT D0 0
  OUT Y0
  }
transition TRUE
jump A
)";

TEST(TypedEngines, ChartCMatchesScanByScan) {
  Chart chart = parse_sfc(kTypedChart, "typed.sfc");
  Program p = lower_chart(chart);
  std::string tmpl = (std::filesystem::temp_directory_path() / "ldc-typed-XXXXXX").string();
  ASSERT_TRUE(mkdtemp(tmpl.data()));
  {
    auto c = make_shared_object_engine(build_c_text(generate_sfc_c(chart, p.layout()), tmpl), kCScanSymbol);
    EXPECT_EQ(compare(p, *c, 9, 30), "");
  }
  std::filesystem::remove_all(tmpl);
}

}  // namespace
