// tests/diff/st_loops_diff_test.cpp -- random Structured Text programs with
// loops, arrays and calls (bench/ldgen_st.cpp, `ldgen --st`; docs/st.md
// "Loops"; the IL's LOOP, docs/il.md) on every engine against the reference
// interpreter, memory images compared after every scan.
//
//   LDC_DIFF_ST_SEEDS   programs per engine (default 24; the C route 6)
//   LDC_DIFF_ST_SEED0   first seed (default 1)
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "bench/ldgen.h"
#include "frontend/frontend.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;



// Runs `p` for `scans` scans on the reference and on `test`: the memory images
// after each scan must be equal.  The fault record is cleared before a scan,
// as the runtime does.  Returns "" or what differs.
std::string compare(const Program& p, const EngineFactory& test, int scans) {
  std::unique_ptr<Engine> ref = make_interp(p), other = test(p);
  const Layout L = p.layout();
  ImageBytes a(L.size), b(L.size);
  for (int s = 1; s <= scans; s++) {
    std::memset(a.data() + kSysFault, 0, 4);
    std::memset(b.data() + kSysFault, 0, 4);
    ref->scan(a);
    other->scan(b);
    for (uint32_t k = 0; k < L.size; k++)
      if (a.data()[k] != b.data()[k])
        return "scan " + std::to_string(s) + ": image byte " + std::to_string(k) + " is " + std::to_string(b.data()[k]) +
               ", the reference's " + std::to_string(a.data()[k]);
  }
  return "";
}

void run(const EngineFactory& test, const char* what, long def, long first = 0) {
  long seed0 = first ? first : env_long("LDC_DIFF_ST_SEED0", 1), seeds = first ? def : env_long("LDC_DIFF_ST_SEEDS", def);
  int loops = 0, faults = 0;
  for (long seed = seed0; seed < seed0 + seeds; seed++) {
    std::string text = generate_st(uint64_t(seed));
    Program p;
    try {
      p = parse_st(text, "random.st");
    } catch (const CompileError& e) {
      ADD_FAILURE() << "seed " << seed << ": " << e.line << ":" << e.col << ": " << e.what() << "\n" << text;
      continue;
    }
    loops += has_loop(p);
    std::string why = compare(p, test, 5);
    EXPECT_EQ(why, "") << what << ", seed " << seed << " (LDC_DIFF_ST_SEED0=" << seed << " LDC_DIFF_ST_SEEDS=1):\n" << text;
    ImageBytes m(p.layout().size);
    make_interp(p)->scan(m);
    uint32_t kind;
    std::memcpy(&kind, m.data() + kSysFault, 4);
    faults += kind != kFaultNone;
  }
  std::printf("st loops, %s: %ld programs (%d with a LOOP, %d faulting in scan 1)\n", what, seeds, loops, faults);
  if (seeds >= 12) { EXPECT_GT(loops, int(seeds) / 2) << "too few programs with a LOOP"; }
}

// The generator's programs compile, most have a LOOP, and its faults occur.
TEST(StLoops, ProgramsHaveLoopsAndSomeFault) {
  int loops = 0, loop_faults = 0, index_faults = 0;
  for (uint64_t seed = 1; seed <= 60; seed++) {
    Program p = parse_st(generate_st(seed), "random.st");
    loops += has_loop(p);
    ImageBytes m(p.layout().size);
    std::unique_ptr<Engine> e = make_interp(p);
    for (int s = 0; s < 3; s++) {
      std::memset(m.data() + kSysFault, 0, 4);
      e->scan(m);
      uint32_t kind;
      std::memcpy(&kind, m.data() + kSysFault, 4);
      loop_faults += kind == kFaultLoop, index_faults += kind == kFaultIndex;
    }
  }
  std::printf("60 programs: %d with a LOOP, %d loop faults, %d index faults in 180 scans\n", loops, loop_faults, index_faults);
  EXPECT_GT(loops, 40);
  EXPECT_GT(loop_faults, 0);
  EXPECT_GT(index_faults, 0);
}

TEST(StLoops, FastMatchesInterpreter) { run(make_fast_interp, "fast", 24); }
TEST(StLoops, NativeMatchesInterpreter) { run(make_native, "native -O0", 24); }
TEST(StLoops, NativeO1MatchesInterpreter) { run(make_native_o1, "native -O1", 24); }
TEST(StLoops, NativeO2MatchesInterpreter) { run(make_native_o2, "native -O2", 24); }
TEST(StLoops, CRouteMatchesInterpreter) { run(make_c_route, "the C route", 6); }

// Seeds the long runs found (docs/testing.md, 2a), kept: 91283 stores into an
// array element under an IF whose end label carries the current result; the
// carried store split the IDX from its STX (the IL check refused the image).
TEST(StLoops, SeedsFoundByLongRuns) {
  for (long seed : {91283L}) {
    run(make_fast_interp, "fast", 1, seed);
    run(make_native_o2, "native -O2", 1, seed);
  }
}

}  // namespace
