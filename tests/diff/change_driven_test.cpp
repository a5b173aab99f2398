// tests/diff/change_driven_test.cpp -- the change-driven scan (issue 28,
// runtime/change_driven.h) against the reference interpreter running every
// rung: whole memory images compared after every scan, on ldgen programs
// (double coils, feedback between rungs, jumps, END, edges, timers,
// counters, arithmetic, typed programs) at input activities from 0% to 100%.
// The regions run on the reference interpreter itself (what the record of
// changes gets right or wrong, alone) and on native code.
//
//   LDC_CD_SEEDS  programs per test (default 120; docs/testing.md has the 10^5 run)
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

#include "bench/rng.h"
#include "ir/regions.h"
#include "runtime/change_driven.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

long env_long(const char* name, long def) {
  const char* v = std::getenv(name);
  if (!v || !*v) return def;
  char* end = nullptr;
  long x = std::strtol(v, &end, 10);
  return *end ? def : x;
}

// The share of input cells that change from one scan to the next, per seed:
// 0%, 2%, 10%, 50% or every cell written again (100%).
int activity_permille(uint64_t seed) {
  static const int kLevels[] = {0, 20, 100, 500, 1000};
  return kLevels[seed % 5];
}

// The trace with each cell after the first row left empty (the device keeps
// its value) unless a draw of `permille` says it changes; dt is kept.
std::string thin_trace(uint64_t seed, const std::string& csv, int permille) {
  std::istringstream in(csv);
  std::string line, out;
  int row = 0, dt_col = -1;  // row 0: the header
  Rng rng(seed * 31 + 7);
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      out += line + "\n";
      continue;
    }
    std::vector<std::string> cells(1);
    for (char ch : line)
      if (ch == ',') cells.emplace_back();
      else cells.back() += ch;
    if (row == 0)
      for (size_t i = 0; i < cells.size(); i++)
        if (cells[i] == "dt") dt_col = int(i);
    if (row >= 2)
      for (size_t i = 0; i < cells.size(); i++)
        if (int(i) != dt_col && rng.below(1000) >= permille) cells[i].clear();
    for (size_t i = 0; i < cells.size(); i++) out += (i ? "," : "") + cells[i];
    out += "\n";
    row++;
  }
  return out;
}

GenOptions options_for(uint64_t s) {
  GenOptions o;
  o.rungs = 10 + int(s % 41);
  o.max_depth = 1 + int(s % 4);
  // small device sets: rungs read what other rungs write, double coils
  o.x = 6, o.y = 4 + int(s % 5), o.m = 4 + int(s % 3), o.d = 4, o.t = 3, o.c = 3;
  if (s % 7 == 3) o.classes = kGenTyped & ~kGenTString;  // typed rungs (no STRING: the regions bound them as 132 bytes)
  return o;
}

void run(const char* what, EngineFactory test, long count_default) {
  SeedRun r;
  r.seed0 = env_long("LDC_CD_SEED0", 1);
  r.count = env_long("LDC_CD_SEEDS", count_default);
  r.options = options_for;
  r.scans = [](uint64_t s) { return 40 + int(s % 41); };
  r.trace_filter = [](uint64_t s, const std::string& csv) { return thin_trace(s, csv, activity_permille(s)); };
  r.test = std::move(test);
  r.what = what;
  r.engine = "interp";
  r.stem = "cd_seed";
  SeedTotals t = run_seeds(r, [](const std::string& m) { ADD_FAILURE() << m; });
  std::printf("%s: %ld programs, %ld rungs, %ld scans compared in %.1f s\n", what, t.programs, t.rungs, t.scans, t.secs);
}

TEST(ChangeDriven, RegionsOnTheInterpreterMatchTheFullScan) {
  run("change-driven (interp regions)", [](const Program& p) { return make_change_driven(p, make_interp); }, 120);
}

TEST(ChangeDriven, RegionsOfSeveralRungsMatchTheFullScan) {
  run("change-driven (interp regions of 4 rungs)", [](const Program& p) { return make_change_driven(p, make_interp, 4); }, 60);
}

TEST(ChangeDriven, NativeRegionsMatchTheFullScan) {
  run("change-driven (native -O1 regions)", [](const Program& p) { return make_change_driven(p, make_native_o1); }, 60);
}

}  // namespace
