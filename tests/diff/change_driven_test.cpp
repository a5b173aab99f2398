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
#include <cstring>
#include <sstream>

#include "bench/rng.h"
#include "ir/regions.h"
#include "runtime/change_driven.h"
#include "driver/targets.h"
#include "driver/x86_target.h"
#include "loader/loader.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

// The share of input cells that change from one scan to the next, per seed:
// 0%, 2%, 10%, 50% or every cell written again (100%).
int activity_permille(uint64_t seed) {
  static const int kLevels[] = {0, 20, 100, 500, 1000};
  return kLevels[seed % 5];
}

// The trace with each cell after the first row left empty (the device keeps
// its value) unless a draw of `permille` says it changes; dt is kept.  Two
// columns more, Y1 and M1, written on one row in ten: a client or the
// monitor forcing cells the rungs drive (the reference gets the same writes).
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
    if (row == 0) cells.push_back("Y1"), cells.push_back("M1");
    else
      for (int k = 0; k < 2; k++) cells.push_back(rng.below(10) == 0 ? std::to_string(rng.below(2)) : "");
    for (size_t i = 0; i < cells.size(); i++) out += (i ? "," : "") + cells[i];
    out += "\n";
    row++;
  }
  return out;
}

// The engine under test told, every 7th scan, that the whole image may have
// changed (as after an online download or a restart that keeps memory): it
// runs every region, and the result stays the full scan's.
class Redownloaded : public Engine {
 public:
  explicit Redownloaded(std::unique_ptr<Engine> e) : e_(std::move(e)) {}
  void scan(ImageBytes& mem) override {
    if (++n_ % 7 == 0) e_->written_all();
    e_->scan(mem);
  }
  void written(uint32_t off, uint32_t len) override { e_->written(off, len); }

 private:
  std::unique_ptr<Engine> e_;
  int n_ = 0;
};

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

// ------------------------------------------------------------------ by hand

// Rungs 0-5; the regions and what runs, derived from the rules of
// ir/regions.h and runtime/change_driven.h by hand.
const char* kPlanIl = R"(.rung line 1
    LOAD X0
    OUT Y0
.rung line 2
    LOAD X1
    JMP skip
.rung line 3
    LOAD X2
    OUT Y1
.label skip
.rung line 4
    LOAD Y0
    OUT Y2
.rung line 5
    LOAD X3
    TON T0 100
.rung line 6
    LOAD T0
    OUT Y3
.end
)";

TEST(ChangeDriven, RegionsAreTheRungsAJumpDoesNotJoin) {
  Program p = parse_il_text(kPlanIl, "plan.il");
  const Layout L = p.layout();
  RegionPlan plan = plan_regions(p, L);
  EXPECT_EQ(plan.whole, "");
  ASSERT_EQ(plan.regions.size(), 5u);  // the JMP (rung 1) joins the rung it skips (2)
  EXPECT_EQ(plan.regions[1].first, 1u);
  EXPECT_EQ(plan.regions[1].end, 3u);
  EXPECT_EQ(plan.regions[0].reads, (std::vector<Span>{{L.addr(Area::X, 0), 1}}));
  EXPECT_EQ(plan.regions[0].writes, (std::vector<Span>{{L.addr(Area::Y, 0), 1}}));
  EXPECT_TRUE(plan.regions[3].uses_time);   // TON T0
  EXPECT_FALSE(plan.regions[3].time_always);
  EXPECT_FALSE(plan.regions[4].uses_time);  // a contact on T0's done bit reads no dt
}

TEST(ChangeDriven, AnIdleScanRunsNothingAndAChangeRunsItsReaders) {
  Program p = parse_il_text(kPlanIl, "plan.il");
  const Layout L = p.layout();
  ChangeDrivenEngine e(plan_regions(p, L), L, [&] {
    std::vector<std::unique_ptr<Engine>> v;
    for (const Region& r : plan_regions(p, L).regions) v.push_back(make_interp(region_program(p, r)));
    return v;
  }());
  Memory m(L);
  auto scan = [&](int32_t dt) {
    std::memcpy(m.data() + kSysDt, &dt, 4);
    e.scan(m.bytes);
    return e.ran_last_scan();
  };
  EXPECT_EQ(scan(10), 5u);  // the first scan runs every region
  EXPECT_EQ(scan(10), 0u);  // nothing changed: nothing runs
  m.set_bit(Area::X, 0, true);
  // X0 -> region 0 writes Y0 (0 -> 1) -> region 2 (reads Y0) writes Y2
  EXPECT_EQ(scan(10), 2u);
  EXPECT_EQ(m.bytes[L.addr(Area::Y, 2)], 1);
  EXPECT_EQ(scan(10), 0u);
  m.set_bit(Area::X, 3, true);
  // T0 times 100 ms (ir/interp.cpp exec_TON): the scan IN comes on, elapsed
  // 0 and its input memory 0 -> 1; then 10, 20, ... 100 ms, each a change
  // that runs the TON's region again; at 100 the done bit comes on, which
  // runs region 4 too; one more run finds 100 kept (advance), then nothing
  for (int k = 1; k <= 10; k++) EXPECT_EQ(scan(10), 1u) << "scan " << k;
  EXPECT_EQ(scan(10), 2u);
  EXPECT_EQ(m.bytes[L.addr(Area::Y, 3)], 1);
  EXPECT_EQ(scan(10), 1u);
  EXPECT_EQ(scan(10), 0u);
  // a write by someone else to a device a region writes runs that region again
  m.set_bit(Area::Y, 0, false);
  e.written(L.addr(Area::Y, 0), 1);
  EXPECT_EQ(scan(10), 2u);  // region 0 puts Y0 back (1): region 2 runs, Y2 stays 1
  EXPECT_EQ(m.bytes[L.addr(Area::Y, 0)], 1);
}

// The checked mapping of region code refuses a table that lets a region's
// bytes overlap another's, leave the code, or cut an instruction, and code
// that is fine as a whole but not region by region.
TEST(ChangeDriven, TheRegionTableIsChecked) {
  Program p = parse_il_text(kPlanIl, "plan.il");
  const Layout L = p.layout();
  RegionCode rc = build_x86_regions(p, plan_regions(p, L), 1);
  ASSERT_EQ(rc.start.size(), 5u);
  EXPECT_NO_THROW(map_checked_regions(rc.code, rc.start, rc.size, L));
  auto refused = [&](std::vector<uint32_t> start, std::vector<uint32_t> size, const std::string& want) {
    try {
      map_checked_regions(rc.code, start, size, L);
      ADD_FAILURE() << "accepted; wanted: " << want;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  };
  auto start = rc.start, size = rc.size;
  start[2] = rc.start[1] + 1;
  refused(start, rc.size, "region 2 starts at");  // inside region 1
  size = rc.size;
  size[4] += 1;
  refused(rc.start, size, "region 4 [");  // past the code's end
  size = rc.size;
  size[0] -= 1;
  refused(rc.start, size, "region 0 (its bytes");  // its last instruction cut: no epilogue
  size = rc.size;
  size[0] = 0;
  refused(rc.start, size, "is empty");
  refused({}, {}, "no regions");
  // two regions as one: the slice holds two functions, the second's prologue
  // inside the first's body
  start = {rc.start[0]}, size = {rc.start[1] + rc.size[1] - rc.start[0]};
  refused(start, size, "region 0 (its bytes");
}

// The image's 'regions' section (docs/image-format.md): written and read back,
// and each broken promise refused by the loader or, for a table that is not
// the program's plan, by the runtime making the engine.
TEST(ChangeDriven, TheImageRegionTableIsCheckedWhereItIsRead) {
  Program p = parse_il_text(kPlanIl, "plan.il");
  const Target& x86 = *find_target("x86-64");
  Image img = target_image(x86, p, "plan.il", 1);
  img.regions = x86_region_table(p, 1, 1);
  ASSERT_EQ(img.regions->first, (std::vector<uint32_t>{0, 1, 3, 4, 5}));
  EXPECT_EQ(read_image(write_image(img), "plan.bin"), img);
  EXPECT_NO_THROW(find_engine("native").engine->make(img));
  auto refused = [&](Image bad, const std::string& want) {
    try {
      Image back = read_image(write_image(bad), "plan.bin");
      find_engine("native").engine->make(back);
      ADD_FAILURE() << "accepted; wanted: " << want;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  };
  Image bad = img;
  bad.regions->first[0] = 1;
  refused(bad, "section 'regions' at offset");
  bad = img;
  std::swap(bad.regions->first[1], bad.regions->first[2]);
  refused(bad, "is not after the region before");
  bad = img;
  bad.regions->first[4] = 9;
  refused(bad, "past the program's 6 rungs");
  bad = img;
  bad.regions->start[2] = bad.regions->start[1];
  refused(bad, "overlaps the region before");
  bad = img;
  bad.regions->size[4] += 1;
  refused(bad, "outside the region code");
  bad = img;
  bad.regions->size[1] -= 1;  // the last byte (a ret) cut off
  refused(bad, "region 1: its code");
  bad = img;
  bad.regions->max_rungs = 0;
  refused(bad, "region size 0");
  bad = img;
  bad.lines.clear();
  refused(bad, "needs the 'lines' section with an entry for each");
  bad = img;
  bad.regions->max_rungs = 2;  // the runtime's plan: other regions
  refused(bad, "is not the program's");
  bad = img;  // a region that joins rungs the plan keeps apart
  bad.regions->first = {0, 3, 4, 5};
  bad.regions->start.erase(bad.regions->start.begin() + 1), bad.regions->size.erase(bad.regions->size.begin() + 1);
  refused(bad, "is not the program's");
}

TEST(ChangeDriven, RegionsOnTheInterpreterMatchTheFullScan) {
  run("change-driven (interp regions)", [](const Program& p) { return make_change_driven(p, make_interp); }, 120);
}

TEST(ChangeDriven, RegionsOfSeveralRungsMatchTheFullScan) {
  run("change-driven (interp regions of 4 rungs)", [](const Program& p) { return make_change_driven(p, make_interp, 4); }, 60);
}

TEST(ChangeDriven, NativeRegionsMatchTheFullScan) {
  run("change-driven (native -O1 regions)", [](const Program& p) { return make_change_driven_native(p, 1, 1, false); }, 60);
}

TEST(ChangeDriven, EveryRegionMarkedNowAndThenMatchesTheFullScan) {
  run("change-driven (interp regions, all marked every 7th scan)", [](const Program& p) {
    return std::make_unique<Redownloaded>(make_change_driven(p, make_interp));
  }, 60);
}

TEST(ChangeDriven, NativeO2RegionsOfSeveralRungsMatchTheFullScan) {
  run("change-driven (native -O2 regions of 8 rungs)", [](const Program& p) { return make_change_driven_native(p, 2, 8, false); }, 40);
}

// The adaptive engine switching between its full scan and its regions on a
// fixed schedule (seed-drawn), so every kind of switch is compared.
TEST(ChangeDriven, SwitchesBetweenTheFullScanAndTheRegionsMatchTheFullScan) {
  run("change-driven (adaptive, native -O2, switching)", [](const Program& p) {
    std::unique_ptr<Engine> e = make_change_driven_native(p, 2, 1, true);
    const uint64_t h = std::hash<std::string>()(print_il_text(p));
    static_cast<ChangeDrivenEngine&>(*e).alternate(1 + h % 5, 1 + (h >> 8) % 7);
    return e;
  }, 60);
}

}  // namespace
