// tests/backend-c40sim/gen/c40diff_test.cpp -- ldgen random programs on the C40 engines,
// scan by scan (docs/c40.md, "How the C40 engines are tested"):
//   c40sim native code   == the C40 model, byte for byte
//   the C40-hosted interpreter == the C40 model, byte for byte
//   the C40 model (check mode) == the reference interpreter, byte for byte,
//   with every REAL step within the stated bound.
//
//   LDC_C40_SEEDS   programs in all (default 240, split over 8 shards)
//   LDC_C40_SEED0   first seed (default 4001)
//   LDC_C40_RUNGS   rungs per program (default 60)
//   LDC_DIFF_OUT    where reproducers are written (default: the current directory)
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "backend-c40sim/gen/c40gen.h"
#include "frontend/frontend.h"
#include "tests/backend-c40sim/gen/c40gen_util.h"

namespace {

using namespace ldc;
using namespace ldc::diff;
using namespace ldc::c40gen;

constexpr int kDefaultRungs = 60;
constexpr int kShards = 8;
#ifdef LDC_SANITIZED
// Under the sanitizers (a shard there took 50-90 s, against 3 s in the Debug
// build) a quarter: there the run is about memory safety; the plain build runs
// them all.
constexpr int kDefaultPrograms = 64;
#else
constexpr int kDefaultPrograms = 240;
static_assert(kDefaultPrograms * kDefaultRungs >= 10000, "the default run covers over ten thousand rungs");
#endif

long env_int(const char* name, long def) {
  const char* v = std::getenv(name);
  if (!v || !*v) return def;
  char* end = nullptr;
  long x = std::strtol(v, &end, 10);
  return *end ? def : x;
}

GenOptions options_for(uint64_t s) {
  GenOptions o;
  o.rungs = int(env_int("LDC_C40_RUNGS", kDefaultRungs));
  o.max_depth = 2 + int(s % 5);
  return o;
}
int scans_for(uint64_t s) { return 20 + int(s % 21); }

struct Totals {
  long programs = 0, rungs = 0, scans = 0, failures = 0;
  CheckReport report;
};

void add(CheckReport& to, const CheckReport& r) {
  for (int i = 0; i < kOpCount; i++) {
    to.checked[i] += r.checked[i];
    to.outside[i] += r.outside[i];
    to.rounding[i] += r.rounding[i];
    to.max_ulps[i] = std::max(to.max_ulps[i], r.max_ulps[i]);
  }
  to.violations += r.violations;
}

// One program: the three comparisons; on a failure, the minimal case and a reproducer.
void check_program(uint64_t seed, const GenOptions& o, int scans, Totals& t, const std::string& what) {
  GenProgram gp = generate_program(seed, o);
  std::string ld = render(gp), csv = generate_trace(seed, scans, o);
  test::Verdict v = test::check_c40(ld, csv);
  t.programs++;
  t.rungs += gp.rungs();
  t.scans += v.scans;
  add(t.report, v.report);
  if (v.native.kind == Outcome::Kind::FrontEndError) {
    ADD_FAILURE() << "seed " << seed << ": the generated case is refused: " << v.native.message;
    return;
  }
  if (v.ok()) return;
  Runner run = [](const std::string& l, const std::string& c) { return test::check_c40(l, c).first_failure(); };
  Reduced r = minimize(gp, csv, v.first_failure(), run);
  std::string rep = reproducer(what + ": ldgen seed " + std::to_string(seed), ldgen_command(seed, o, scans), gp, r,
                               output_dir(), "c40_seed" + std::to_string(seed), "C40 model", "C40 engine");
  ADD_FAILURE() << v.text() << rep;
  t.failures++;
}

void print(const char* name, const Totals& t, double secs) {
  std::printf("%s: %ld programs, %ld rungs, %ld scans in %.1f s; REAL steps checked %llu (outside the format %llu, "
              "rounded INT32 operands %llu), violations %llu\n",
              name, t.programs, t.rungs, t.scans, secs, (unsigned long long)t.report.total_checked(),
              (unsigned long long)t.report.total_outside(), (unsigned long long)t.report.total_rounding(),
              (unsigned long long)t.report.violations);
  for (int i = 0; i < kOpCount; i++)
    if (t.report.checked[i])
      std::printf("  %-6s checked %8llu  max %u ulp\n", op_info(Op(i)).name, (unsigned long long)t.report.checked[i],
                  t.report.max_ulps[i]);
}

class C40DiffShard : public ::testing::TestWithParam<int> {};

TEST_P(C40DiffShard, EnginesMatchTheModelAndTheModelTheReference) {
  const long total = env_int("LDC_C40_SEEDS", kDefaultPrograms), seed0 = env_int("LDC_C40_SEED0", 4001);
  Totals t;
  auto t0 = std::chrono::steady_clock::now();
  for (long i = GetParam(); i < total; i += kShards) {
    uint64_t seed = uint64_t(seed0 + i);
    check_program(seed, options_for(seed), scans_for(seed), t, "C40 engines");
    if (t.failures >= 3) {
      ADD_FAILURE() << "stopping this shard after 3 failing seeds";
      break;
    }
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  print(("shard " + std::to_string(GetParam())).c_str(), t, secs);
  EXPECT_EQ(t.report.violations, 0u);
}

INSTANTIATE_TEST_SUITE_P(Seeds, C40DiffShard, ::testing::Range(0, kShards));

// The test catches a wrong C40 engine and shrinks the case: a native engine
// whose MUL results are off by one (as if mul32 dropped a carry).
TEST(C40DiffHarness, CatchesAndShrinksAWrongEngine) {
  class OffByOne : public Engine {
   public:
    OffByOne(std::unique_ptr<Engine> e, std::vector<uint32_t> muls) : e_(std::move(e)), muls_(std::move(muls)) {}
    void scan(ImageBytes& mem) override {
      e_->scan(mem);
      for (uint32_t a : muls_) {
        int32_t v;
        std::memcpy(&v, mem.data() + a, 4);
        v++;
        std::memcpy(mem.data() + a, &v, 4);
      }
    }
   private:
    std::unique_ptr<Engine> e_;
    std::vector<uint32_t> muls_;
  };
  EngineFactory bad = [](const Program& p) -> std::unique_ptr<Engine> {
    std::vector<uint32_t> muls;  // INT32 destinations of INT32 MULs
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        if (in.op == Op::MUL && !in.a[0].is_real() && !in.a[1].is_real() && in.a[2].kind == OpdKind::Int)
          muls.push_back(p.layout().addr(in.a[2].area, in.a[2].index));
    return std::make_unique<OffByOne>(test::make_native(p), muls);
  };
  int caught = 0;
  for (uint64_t seed = 5001; seed <= 5040 && !caught; seed++) {
    GenOptions o;
    o.rungs = 30;
    o.classes = kGenContacts | kGenArith | kGenCoils;
    std::string ld = generate_ld(seed, o), csv = generate_trace(seed, 10, o);
    test::Verdict v = test::check_c40(ld, csv, bad);
    if (v.ok()) continue;
    caught++;
    EXPECT_EQ(v.native.kind, Outcome::Kind::Differ);
    GenProgram gp = generate_program(seed, o);
    Runner run = [&](const std::string& l, const std::string& c) { return test::check_c40(l, c, bad).first_failure(); };
    Reduced r = minimize(gp, csv, v.first_failure(), run);
    EXPECT_LE(r.prog.rungs(), 2) << render(r.prog);
    EXPECT_NE(render(r.prog).find("MUL"), std::string::npos) << render(r.prog);
  }
  EXPECT_EQ(caught, 1);
}

// Long programs: two thousand rungs each (the code is past 32K words, out of
// reach of Bcond's 16-bit displacement: jumps go through BR), few scans.
TEST(C40DiffLong, TwoThousandRungPrograms) {
  Totals t;
  auto t0 = std::chrono::steady_clock::now();
  for (uint64_t seed : {9001u, 9002u}) {
    GenOptions o;
    o.rungs = 2000;
    o.max_depth = 4;
    Program p = lower_to_il(parse_ld(generate_ld(seed, o), "long.ld"));
    as::Result r = as::assemble(as::c40::target(), generate_c40(p, p.layout()).program);
    ASSERT_TRUE(r.ok());
    EXPECT_GT(r.code.size() / 4, 32768u);
    check_program(seed, o, 8, t, "C40 engines, 2000 rungs");
  }
  print("long", t, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  EXPECT_EQ(t.report.violations, 0u);
}

// Element classes on their own, so that rare mnemonics get many steps: REAL
// functions and arithmetic; timers and counters; jumps and END.
TEST(C40DiffClasses, ClassesOnTheirOwn) {
  Totals t;
  auto t0 = std::chrono::steady_clock::now();
  const uint32_t sets[] = {kGenContacts | kGenCompares | kGenArith | kGenRealFn | kGenMove,
                           kGenContacts | kGenEdges | kGenTimers | kGenCounters | kGenSetReset,
                           kGenContacts | kGenCoils | kGenJumps | kGenEnd | kGenLogic};
  for (int k = 0; k < 3; k++)
    for (uint64_t seed = 1; seed <= 6; seed++) {
      GenOptions o;
      o.rungs = 50;
      o.classes = sets[k];
      check_program(7000 + uint64_t(k) * 100 + seed, o, 30, t, "C40 engines, classes " + gen_classes_text(sets[k]));
    }
  print("classes", t, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  EXPECT_EQ(t.report.violations, 0u);
}

}  // namespace
