// Online change that takes real edits (runtime/online_carry.h, docs/runtime.md
// "What a download carries"): rungs inserted above, appended, deleted and
// reordered, counters, timers, edges and variables added, a type changed --
// state carried by identity, checked through the running runtime and, for
// random edit sequences, against an oracle that knows each item's identity.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include "driver/driver.h"
#include "runtime/online_carry.h"
#include "runtime/plc.h"
#include "runtime/runtime.h"
#include "tests/runtime/process_util.h"

namespace ldc {
namespace {

using test::TmpDir;

// A source text compiled with ldc's own front end into an image without
// machine code (the interpreter runs it; what is carried is decided from the
// IL, the line map, the titles and the aliases).
Image image_of(const TmpDir& d, const std::string& name, const std::string& text) {
  {
    std::ofstream f(d / name, std::ios::binary);
    f << text;
  }
  Compiled c = compile_source(d / name);
  size_t n = 0;
  for (const Rung& r : c.il.rungs) n += r.code.size();
  std::vector<uint32_t> offsets(n, 0);
  return make_image(ImageTarget::X86_64, c.il, {}, offsets);
}

// One task on the interpreter with no outside world: inputs change by set().
struct OnePlc {
  std::unique_ptr<plc::Runtime> rt;
  explicit OnePlc(Image img, std::unique_ptr<plc::IoDriver> io = plc::make_null_driver()) {
    std::vector<plc::TaskSpec> specs(1);
    specs[0].name = "main", specs[0].program = "p", specs[0].file = "v1", specs[0].period_us = 1000;
    specs[0].image = std::move(img);
    start(std::move(specs), std::move(io));
  }
  explicit OnePlc(std::vector<plc::TaskSpec> specs, std::unique_ptr<plc::IoDriver> io) { start(std::move(specs), std::move(io)); }
  void start(std::vector<plc::TaskSpec> specs, std::unique_ptr<plc::IoDriver> io) {
    plc::Options opt;
    auto engines = [](const Image& img) -> std::unique_ptr<Engine> { return make_interp_engine(img.il, img.layout); };
    rt = std::make_unique<plc::Runtime>(std::move(specs), opt, engines, std::move(io));
    rt->start();
  }
  ~OnePlc() { rt->shutdown(); }
  void scans(int n) { ASSERT_TRUE(rt->wait_scans(n, 10000)); }
  // A rising and a falling edge of each input, a few scans each.
  void pulse(std::initializer_list<const char*> inputs) {
    for (const char* x : inputs) rt->set(x, "1");
    scans(3);
    for (const char* x : inputs) rt->set(x, "0");
    scans(3);
  }
};

const char* kCounters =
    "rung \"count parts\"\n|--[P X0]--(CTU C0 1000)\n\n"
    "rung \"count boxes\"\n|--[X1]--(CTU C1 1000)\n\n";

// The two edits of the issue's evidence.  Before the switch C0 and C1 have
// counted 3 pulses and one more rising edge each, and X0 and X1 stay 1
// across the switch: an edge slot not carried (0 in the new program) would
// count that edge once more on the first new scan (5, not 4).
void count_four(OnePlc& p) {
  for (int i = 0; i < 3; i++) p.pulse({"X0", "X1"});
  p.rt->set("X0", "1"), p.rt->set("X1", "1");
  p.scans(3);
  ASSERT_EQ(p.rt->get("C0"), "4");
  ASSERT_EQ(p.rt->get("C1"), "4");
}

TEST(OnlineChange, ARungWithAnEdgeAndACounterInsertedAboveKeepsEveryCount) {
  TmpDir d;
  OnePlc p(image_of(d, "v1.ld", kCounters));
  count_four(p);
  std::string v2 = std::string("rung \"count pallets (new, above)\"\n|--[P X2]--(CTU C2 1000)\n\n") + kCounters;
  plc::SwapReport r = p.rt->replace("main", image_of(d, "v2.ld", v2), "v2.ld");
  // v1's slots: [P X0] E0, CTU C0 E1, CTU C1 E2 -- all three carried, now E2 E3 E4.
  EXPECT_EQ(r.carry.text(), "carried 3 edge slots and 0 variables, devices by address; new: edge [P X2] (line 2), counter edge CTU C2 (line 2)");
  p.scans(3);
  EXPECT_EQ(p.rt->get("C0"), "4");
  EXPECT_EQ(p.rt->get("C1"), "4");
  p.rt->set("X0", "0"), p.rt->set("X1", "0");
  p.scans(3);
  p.pulse({"X0", "X1", "X2"});
  EXPECT_EQ(p.rt->get("C0"), "5");
  EXPECT_EQ(p.rt->get("C1"), "5");
  EXPECT_EQ(p.rt->get("C2"), "1");
}

TEST(OnlineChange, ARungWithANewCounterAppendedKeepsEveryCount) {
  TmpDir d;
  OnePlc p(image_of(d, "v1.ld", kCounters));
  count_four(p);
  std::string v2 = std::string(kCounters) + "rung \"count rejects (new)\"\n|--[X3]--(CTU C5 1000)\n";
  plc::SwapReport r = p.rt->replace("main", image_of(d, "v2.ld", v2), "v2.ld");
  EXPECT_EQ(r.carry.text(), "carried 3 edge slots and 0 variables, devices by address; new: counter edge CTU C5 (line 8)");
  p.scans(3);
  EXPECT_EQ(p.rt->get("C0"), "4");
  EXPECT_EQ(p.rt->get("C1"), "4");
  p.rt->set("X0", "0"), p.rt->set("X1", "0");
  p.scans(3);
  p.pulse({"X0", "X1", "X3"});
  EXPECT_EQ(p.rt->get("C0"), "5");
  EXPECT_EQ(p.rt->get("C1"), "5");
  EXPECT_EQ(p.rt->get("C5"), "1");
}

// Rungs deleted and reordered: the counters' edges follow their rungs.
TEST(OnlineChange, RungsDeletedAndReorderedKeepTheirEdges) {
  TmpDir d;
  std::string v1 = std::string("rung \"gone\"\n|--[P X5]--(CTU C9 1000)\n\n") + kCounters;
  OnePlc p(image_of(d, "v1.ld", v1));
  count_four(p);
  std::string v2 = "rung \"count boxes\"\n|--[X1]--(CTU C1 1000)\n\nrung \"count parts\"\n|--[P X0]--(CTU C0 1000)\n\n";
  plc::SwapReport r = p.rt->replace("main", image_of(d, "v2.ld", v2), "v2.ld");
  EXPECT_EQ(r.carry.text(), "carried 3 edge slots and 0 variables, devices by address; dropped: edge [P X5] (line 2), counter edge CTU C9 (line 2)");
  p.scans(3);
  EXPECT_EQ(p.rt->get("C0"), "4");
  EXPECT_EQ(p.rt->get("C1"), "4");
}

// Typed variables are placed one after another: a variable inserted above
// moves the others, which are carried by name; a type change resets its
// variable to its initial value, or is refused with --strict.
TEST(OnlineChange, VariablesAreCarriedByNameAndATypeChangeResets) {
  TmpDir d;
  const std::string v1 =
      "PROGRAM p\nVAR\n  a : INT;\n  b : INT;\n  flag : BOOL;\nEND_VAR\n  a := a;\nEND_PROGRAM\n";
  const std::string v2 =
      "PROGRAM p\nVAR\n  n : INT := 5;\n  a : INT;\n  b : DINT;\n  bit : BOOL;\n  flag : BOOL;\nEND_VAR\n  a := a;\n"
      "END_PROGRAM\n";
  OnePlc p(image_of(d, "v1.st", v1));
  p.scans(2);
  p.rt->set("a", "40");
  p.rt->set("b", "7");
  p.rt->set("flag", "1");
  p.scans(2);
  // --strict: b would be reset, so nothing happens.
  EXPECT_THROW(p.rt->replace("main", image_of(d, "v2.st", v2), "v2.st", 5000, true), std::runtime_error);
  EXPECT_EQ(p.rt->get("a"), "40");
  plc::SwapReport r = p.rt->replace("main", image_of(d, "v2.st", v2), "v2.st");
  // v1 places a D0, b D1, flag M0; v2 n D0, a D1, b D2 (two cells), bit M0, flag M1 (ldc --emit=il);
  // the types are the image's `vars` section's.
  EXPECT_EQ(r.carry.text(), "carried 0 edge slots and 2 variables, devices by address (moved: a D0 -> D1, flag M0 -> M1); "
                            "new: n, bit; reset: b (INT -> DINT: initial value)");
  p.scans(2);
  EXPECT_EQ(p.rt->get("a"), "40");
  EXPECT_EQ(p.rt->get("flag"), "1");
  EXPECT_EQ(p.rt->get("n"), "5");    // its initial value, not a's old cell
  EXPECT_EQ(p.rt->get("bit"), "0");  // flag's old cell, not flag's value
  EXPECT_EQ(p.rt->get("b"), "0");
}

// The image's `vars` section carries variables as wholes: an array past
// its 64 named elements moves whole, and a structure whose type gained a
// member is reset with the members of the same name and type carried.
TEST(OnlineChange, WholeVariablesMoveAndAChangedStructureKeepsItsMembers) {
  TmpDir d;
  const std::string v1 =
      "TYPE Tank : STRUCT level : INT; temp : REAL; END_STRUCT; END_TYPE\nPROGRAM p\nVAR\n  big : ARRAY[1..100] OF INT;\n"
      "  tank : Tank;\nEND_VAR\n  big[1] := big[1];\nEND_PROGRAM\n";
  const std::string v2 =
      "TYPE Tank : STRUCT level : INT; temp : REAL; alarm : BOOL; END_STRUCT; END_TYPE\nPROGRAM p\nVAR\n"
      "  extra : ARRAY[1..3] OF INT;\n  big : ARRAY[1..100] OF INT;\n  tank : Tank;\nEND_VAR\n  big[1] := big[1];\nEND_PROGRAM\n";
  Image i1 = image_of(d, "v1.st", v1), i2 = image_of(d, "v2.st", v2);
  ASSERT_EQ(i1.vars.size(), 2u);
  ASSERT_EQ(i1.vars[0].cells, Area::D);
  ASSERT_EQ(i1.vars[0].cell_first, 0u);  // big D0..D99: big[100] is D99, which has no alias (64 at most)
  ASSERT_EQ(i1.vars[0].cell_count, 100u);
  ASSERT_EQ(i2.vars[1].cell_first, 3u);   // after extra: big[100] is D102
  OnePlc p(std::move(i1));
  p.scans(2);
  p.rt->set("D99", "9");
  p.rt->set("tank.level", "11");
  p.rt->set("tank.temp", "2.5");
  p.scans(2);
  plc::SwapReport r = p.rt->replace("main", std::move(i2), "v2.st");
  std::string t = r.carry.text();
  EXPECT_NE(t.find("moved: big D0 -> D3"), std::string::npos) << t;
  EXPECT_NE(t.find("new: extra; reset: tank (Tank#"), std::string::npos) << t;
  EXPECT_NE(t.find(": initial value, 2 parts of the same name and type carried)"), std::string::npos) << t;
  p.scans(2);
  EXPECT_EQ(p.rt->get("D102"), "9");
  EXPECT_EQ(p.rt->get("tank.level"), "11");
  EXPECT_EQ(p.rt->get("tank.temp"), "2.5");
  EXPECT_EQ(p.rt->get("tank.alarm"), "0");
  EXPECT_EQ(p.rt->get("extra[1]"), "0");
}

// restart TASK: one task from its first scan, its outputs through the safe
// state, while the other runs on.
struct OutputLog : plc::IoDriver {
  std::mutex mu;
  std::vector<int> y0;  // global Y0 at each publish of task a (0) that includes it
  void write_outputs(const uint8_t* global, const plc::ScanContext& c) override {
    Layout L = Layout::standard(0);
    if (c.task != 0) return;
    for (const plc::Run& r : c.runs)
      if (r.offset <= L.addr(Area::Y, 0) && L.addr(Area::Y, 0) < r.offset + r.size) {
        std::lock_guard<std::mutex> l(mu);
        y0.push_back(global[L.addr(Area::Y, 0)]);
      }
  }
};

TEST(OnlineChange, RestartTaskRestartsOneTaskFromItsFirstScan) {
  TmpDir d;
  std::vector<plc::TaskSpec> specs(2);
  specs[0].name = "a", specs[0].program = "a", specs[0].period_us = 1000;
  specs[0].image = image_of(d, "a.ld", "|--[S1]--(MOV 100 D1)\n\n|--(ADD D0 1 D0)\n\n|--(Y0)\n");
  specs[1].name = "b", specs[1].program = "b", specs[1].period_us = 1000;
  specs[1].image = image_of(d, "b.ld", "|--(ADD D0 1 D0)\n\n|--(Y1)\n");
  auto log = std::make_unique<OutputLog>();
  OutputLog* lg = log.get();
  OnePlc p(std::move(specs), std::move(log));
  p.scans(20);
  p.rt->set("a.D1", "5");
  p.scans(2);
  ASSERT_EQ(p.rt->get("a.D1"), "5");
  {
    std::lock_guard<std::mutex> l(lg->mu);
    ASSERT_FALSE(lg->y0.empty());
    for (int v : lg->y0) ASSERT_EQ(v, 1);
    lg->y0.clear();
  }
  long b_before = std::stol(p.rt->get("b.D0"));
  p.rt->restart_task(0);
  p.scans(3);
  EXPECT_EQ(p.rt->get("a.D1"), "100");  // the first scan's rung ran again
  long a_after = std::stol(p.rt->get("a.D0")), b_after = std::stol(p.rt->get("b.D0"));
  // a counted again from 0 (as many scans as b did since the restart, give
  // or take one), b goes on from the 20 and more it had.
  EXPECT_LT(a_after, b_after - 10);
  EXPECT_GE(b_after, b_before + 3);       // b was not touched
  EXPECT_EQ(p.rt->get("Y0"), "1");
  std::lock_guard<std::mutex> l(lg->mu);
  ASSERT_FALSE(lg->y0.empty());
  // The restart published Y0 in the safe state (a scan of a under way as
  // the log was cleared may publish a 1 before it), then a's scans set it again.
  EXPECT_NE(std::find(lg->y0.begin(), lg->y0.end(), 0), lg->y0.end());
  EXPECT_EQ(lg->y0.back(), 1);
}

// ---------------------------------------------------------------- random edit sequences

// A program is a list of items, each with an identity k that fixes its
// devices; an edit inserts, deletes or moves items, adds new ones or changes
// a variable's type.  Variables are placed one after another from D100 in
// the order they appear, as an IEC front end places them, so an insertion
// moves the variables after it.
struct Item {
  enum Kind { EdgeCount, LevelCount, Timer, FallAdd, Var } kind;
  int k;         // identity: counter C<k>, timer T<k>, word D<k>, variable v<k>
  int x;         // the input it reads
  bool titled;   // `rung "r<k>"` (else untitled: matched by its content)
  bool dint;     // Var: DINT, else INT
};

struct Version {
  std::vector<Item> items;
  std::string text() const {
    std::string s;
    int loc = 100;
    for (const Item& it : items)
      if (it.kind == Item::Var)
        s += "alias v" + std::to_string(it.k) + " = D" + std::to_string(loc++) + (it.dint ? " : DINT\n" : " : INT\n");
    for (const Item& it : items) {
      std::string k = std::to_string(it.k), x = "X" + std::to_string(it.x);
      if (it.titled) s += "rung \"r" + k + "\"\n";
      switch (it.kind) {
        case Item::EdgeCount: s += "|--[P " + x + "]--(CTU C" + k + " 7)\n"; break;
        case Item::LevelCount: s += "|--[" + x + "]--(CTU C" + k + " 5)\n"; break;
        case Item::Timer: s += "|--[" + x + "]--(TON T" + k + " 4ms)\n"; break;
        case Item::FallAdd: s += "|--[N " + x + "]--(ADD D" + k + " 1 D" + k + ")\n"; break;
        case Item::Var: s += "|--[P " + x + "]--(ADD v" + k + " 3 v" + k + ")\n"; break;
      }
      s += "\n";
    }
    return s;
  }
  int var_loc(int k) const {
    int loc = 100;
    for (const Item& it : items)
      if (it.kind == Item::Var) {
        if (it.k == k) return loc;
        loc++;
      }
    return -1;
  }
  const Item* find(int k) const {
    for (const Item& it : items)
      if (it.k == k) return &it;
    return nullptr;
  }
};

// The oracle's memory after a switch, from the items alone: devices by
// address; each surviving item's edge slots from its old slots; the edges of
// new items pair with the dropped edges of the same kind and input in
// program order (the documented last rule), others start at 0; variables by
// name, a type change to 0; a new variable 0 where an old one lived, else
// its device as it was.
std::vector<uint8_t> oracle(const Version& ov, const Version& nv, const uint8_t* old_mem, const Layout& ol, const Layout& nl) {
  std::vector<uint8_t> m(nl.size, 0);
  std::memcpy(m.data(), old_mem, std::min(ol.offset[int(Area::E)], nl.offset[int(Area::E)]));
  struct Slot {
    int k;
    std::string key;
    uint32_t slot;
  };
  auto slots = [](const Version& v) {
    std::vector<Slot> s;
    uint32_t e = 0;
    for (const Item& it : v.items) {
      std::string x = "X" + std::to_string(it.x), c = "C" + std::to_string(it.k);
      switch (it.kind) {
        case Item::EdgeCount: s.push_back({it.k, "P" + x, e++}), s.push_back({it.k, "CTU" + c, e++}); break;
        case Item::LevelCount: s.push_back({it.k, "CTU" + c, e++}); break;
        case Item::FallAdd: s.push_back({it.k, "N" + x, e++}); break;
        case Item::Var: s.push_back({it.k, "P" + x, e++}); break;
        case Item::Timer: break;
      }
    }
    return s;
  };
  std::vector<Slot> os = slots(ov), ns = slots(nv);
  std::vector<bool> used(os.size()), done(ns.size());
  for (size_t i = 0; i < ns.size(); i++)
    for (size_t j = 0; j < os.size(); j++)
      if (!used[j] && os[j].k == ns[i].k && os[j].key == ns[i].key) {
        m[nl.offset[int(Area::E)] + ns[i].slot] = old_mem[ol.offset[int(Area::E)] + os[j].slot];
        used[j] = done[i] = true;
        break;
      }
  for (size_t i = 0; i < ns.size(); i++)
    for (size_t j = 0; j < os.size() && !done[i]; j++)
      if (!used[j] && os[j].key == ns[i].key) {
        m[nl.offset[int(Area::E)] + ns[i].slot] = old_mem[ol.offset[int(Area::E)] + os[j].slot];
        used[j] = done[i] = true;
      }
  std::set<int> old_locs;
  for (const Item& it : ov.items)
    if (it.kind == Item::Var) old_locs.insert(ov.var_loc(it.k));
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> writes;  // old values read first
  for (const Item& it : nv.items) {
    if (it.kind != Item::Var) continue;
    uint32_t to = nl.addr(Area::D, uint32_t(nv.var_loc(it.k)));
    const Item* was = ov.find(it.k);
    if (was && was->dint == it.dint) {
      const uint8_t* from = old_mem + ol.addr(Area::D, uint32_t(ov.var_loc(it.k)));
      writes.push_back({to, std::vector<uint8_t>(from, from + 4)});
    } else if (was || old_locs.count(nv.var_loc(it.k))) {
      writes.push_back({to, std::vector<uint8_t>(4, 0)});
    }
  }
  for (auto& [to, v] : writes) std::memcpy(m.data() + to, v.data(), 4);
  return m;
}

Item random_item(std::mt19937& g, int k) {
  Item it;
  it.kind = Item::Kind(g() % 5);
  it.k = k;
  it.x = int(g() % 4);  // few inputs: several edges read the same one
  it.titled = g() % 2;
  it.dint = g() % 2;
  return it;
}

Version edit(const Version& v, std::mt19937& g, int& next_k) {
  Version n = v;
  int edits = 1 + int(g() % 3);
  for (int e = 0; e < edits; e++) {
    switch (g() % 5) {
      case 0:  // insert a new item anywhere (a counter, timer, edge or variable)
        n.items.insert(n.items.begin() + long(g() % (n.items.size() + 1)), random_item(g, next_k++));
        break;
      case 1:  // delete one (a program keeps one rung at least)
        if (n.items.size() > 1) n.items.erase(n.items.begin() + long(g() % n.items.size()));
        break;
      case 2:  // move one
        if (n.items.size() > 1) {
          size_t from = g() % n.items.size();
          Item it = n.items[from];
          n.items.erase(n.items.begin() + long(from));
          n.items.insert(n.items.begin() + long(g() % (n.items.size() + 1)), it);
        }
        break;
      case 3:  // append
        n.items.push_back(random_item(g, next_k++));
        break;
      case 4:  // a variable's type changes
        for (Item& it : n.items)
          if (it.kind == Item::Var && g() % 2) {
            it.dint = !it.dint;
            break;
          }
        break;
    }
  }
  return n;
}

// Runs `scans` scans of `engine` on `mem` with inputs from `g`; S1 is 0
// (after a switch the program continues, it does not restart).
void run_scans(Engine& engine, ImageBytes& mem, const Layout& L, std::mt19937& g, int scans, std::vector<std::vector<uint8_t>>* trace) {
  for (int s = 0; s < scans; s++) {
    for (uint32_t x = 0; x < 4; x++) mem[L.addr(Area::X, x)] = g() % 2;
    int32_t dt = 1 + int32_t(g() % 3);
    std::memcpy(mem.data() + kSysDt, &dt, 4);
    mem[L.addr(Area::S, kBitFirstScan)] = 0;
    engine.scan(mem);
    if (trace) trace->emplace_back(mem.data(), mem.data() + L.size);
  }
}

// One edit sequence: versions v0 -> v1 -> ... each run a few scans, each
// switch carried by plan_carry/apply_carry and by the oracle; the two
// memories must be equal, and the new program then runs the same scans from
// both (the switched one and one started afresh on the oracle's memory).
void one_sequence(const TmpDir& d, uint32_t seed) {
  std::mt19937 g(seed);
  int next_k = 0;
  Version v;
  for (int i = 0, n = 1 + int(g() % 5); i < n; i++) v.items.push_back(random_item(g, next_k++));
  Image img = image_of(d, "s.ld", v.text());
  ImageBytes mem(img.layout.size);
  std::fill(mem.begin(), mem.end(), 0);
  mem[img.layout.addr(Area::S, kBitFirstScan)] = 1;
  auto eng = make_interp_engine(img.il, img.layout);
  run_scans(*eng, mem, img.layout, g, 4 + int(g() % 8), nullptr);
  for (int step = 0, steps = 2 + int(g() % 4); step < steps; step++) {
    Version nv = edit(v, g, next_k);
    Image nimg = image_of(d, "s.ld", nv.text());
    plc::CarryPlan plan = plc::plan_carry(img, nimg);
    ImageBytes switched(nimg.layout.size);
    plc::apply_carry(plan, img.layout, mem.data(), nimg.layout, switched.data(), nullptr);
    std::vector<uint8_t> want = oracle(v, nv, mem.data(), img.layout, nimg.layout);
    ImageBytes fresh(nimg.layout.size);
    std::memcpy(fresh.data(), want.data(), want.size());
    for (size_t i = 0; i < want.size(); i++)
      ASSERT_EQ(switched[i], want[i]) << "seed " << seed << " step " << step << ": byte " << i << " after the switch\nold:\n"
                                      << v.text() << "new:\n" << nv.text() << plan.report.text();
    auto e1 = make_interp_engine(nimg.il, nimg.layout), e2 = make_interp_engine(nimg.il, nimg.layout);
    std::mt19937 g1 = g, g2 = g;
    std::vector<std::vector<uint8_t>> t1, t2;
    int n = 4 + int(g() % 8);
    run_scans(*e1, switched, nimg.layout, g1, n, &t1);
    run_scans(*e2, fresh, nimg.layout, g2, n, &t2);
    for (int s = 0; s < n; s++) ASSERT_TRUE(t1[s] == t2[s]) << "seed " << seed << " step " << step << ": scan " << s << " differs";
    g = g1;
    mem = std::move(switched);
    img = std::move(nimg);
    v = std::move(nv);
  }
}

// 200 sequences in ctest (about 2.5 s), 40 under the sanitizers (which make
// each 20 times slower); ONLINE_CHANGE_SEQUENCES=10000 for the long run
// (docs/testing.md).
TEST(OnlineChange, RandomEditSequencesCarryAsTheOracleSays) {
  TmpDir d;
#ifdef LDC_SANITIZED
  int n = 40;
#else
  int n = 200;
#endif
  if (const char* e = std::getenv("ONLINE_CHANGE_SEQUENCES")) n = std::atoi(e);
  for (int i = 0; i < n; i++) {
    one_sequence(d, uint32_t(i) * 2654435761u + 1);
    if (HasFatalFailure()) return;
  }
}

}  // namespace
}  // namespace ldc
