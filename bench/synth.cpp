// bench/synth.cpp -- synthetic programs for the benchmarks (synth.h).
#include "bench/synth.h"

#include "bench/rng.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace ldc::synth {
namespace {

// The generators' splitmix64 (bench/rng.h), its seed spread first.
Rng synth_rng(uint64_t seed) { return Rng(seed * 0x2545F4914F6CDD1Dull + 1); }

using D = SynthDevices;
std::string num(long v) { return std::to_string(v); }

constexpr int kApp[] = {int(OpClass::Compare), int(OpClass::Move), int(OpClass::Arith), int(OpClass::Logic),
                        int(OpClass::Special), int(OpClass::Timer), int(OpClass::Counter)};

// Writes one program: rung headers, instructions, edge slots, timer numbers.
class Writer {
 public:
  explicit Writer(uint64_t seed) : r(synth_rng(seed)) {}
  Rng r;
  // One-class programs: every result goes to a device of its own (a compiler
  // cannot drop a store that a later one overwrites) and INT32 sources are the
  // WX inputs (data words nobody writes would only hold 0).
  bool fresh = false;

  void rung() { body_ += ".rung line " + num(++rungs_) + "\n"; }
  void ins(const std::string& s) { body_ += "    " + s + "\n"; count_++; }
  int rungs() const { return rungs_; }
  int count() const { return count_; }
  std::string text(const std::string& title) const {
    std::string h = "; " + title + "\n";
    if (edges_) h += ".edges " + num(edges_) + "\n";
    return h + body_ + ".end\n";
  }

  // ---- operands
  std::string bit_src() {
    switch (r.pick({50, 25, 15, 5, 5})) {
      case 0: return "X" + num(r.below(D::kInX));
      case 1: return "M" + num(r.below(D::kBitsM));
      case 2: return "Y" + num(r.below(D::kBitsY));
      case 3: return "T" + num(r.below(256));
      default: return "C" + num(r.below(256));
    }
  }
  std::string bit_dst() {
    if (fresh) return "M" + num(next_m_++ % 8192);
    return r.pct(60) ? "M" + num(r.below(D::kBitsM)) : "Y" + num(r.below(D::kBitsY));
  }
  std::string wx() { return "WX" + num(r.below(D::kInWX)); }
  std::string d_src() { return fresh ? wx() : "D" + num(r.below(D::kWordsD)); }
  std::string d_dst() { return fresh ? "D" + num(D::kWordsD + next_d_++ % (8192 - D::kWordsD)) : "D" + num(r.below(D::kWordsD)); }
  std::string wy_dst() { return fresh ? "WY" + num(next_wy_++ % 1024) : "WY" + num(r.below(D::kWordsWY)); }
  std::string int_word() { return r.pct(30) ? wx() : d_src(); }
  std::string int_const() { return num(r.pct(20) ? r.range(-1000, 1000) : r.range(1, 100)); }
  std::string int_src() { return r.pct(35) ? int_const() : int_word(); }
  std::string int_dst() { return r.pct(85) ? d_dst() : wy_dst(); }
  std::string real_in() { return "F" + num(D::kInFPos + r.below(D::kInF - D::kInFPos)); }     // [-8, 8]
  std::string real_pos() { return "F" + num(r.below(D::kInFPos)); }                          // [0.1, 8]
  std::string real_const() {
    char b[32];
    std::snprintf(b, sizeof b, "%d.%d", r.range(-9, 9), r.below(10));
    return b;
  }
  std::string real_src() { return r.pct(30) ? real_const() : real_in(); }
  std::string real_dst() {
    if (fresh) return "F" + num(D::kFirstFOut + next_f_++ % (1024 - D::kFirstFOut));
    return "F" + num(r.range(D::kFirstFOut, D::kLastFOut));
  }
  std::string edge() { return "E" + num(edges_++); }
  std::string timer() { return "T" + num(timers_++ % 256); }
  std::string counter() { return "C" + num(counters_++ % 256); }

  // ---- basic instructions
  void opener() {
    switch (r.pick({70, 15, 10, 5})) {
      case 0: return ins("LOAD " + bit_src());
      case 1: return ins("LOADN " + bit_src());
      case 2: return ins("LOADP " + bit_src() + " " + edge());
      default: return ins("LOADF " + bit_src() + " " + edge());
    }
  }
  // n basic instructions that keep the stack depth: AND/ANDN/OR/ORN, or a
  // parallel block LOAD x / OR y / ANDBLK (or its series twin).
  void extenders(int n) {
    while (n > 0) {
      if (n >= 3 && r.pct(20)) {
        bool par = r.pct(50);
        ins("LOAD " + bit_src());
        ins(std::string(par ? "OR " : "AND ") + bit_src());
        ins(par ? "ANDBLK" : "ORBLK");
        n -= 3;
        continue;
      }
      static const char* const ops[] = {"AND ", "ANDN ", "OR ", "ORN "};
      ins(ops[r.pick({35, 25, 25, 15})] + bit_src());
      n--;
    }
  }
  void output() {
    static const char* const ops[] = {"OUT ", "OUTN ", "SET ", "RST "};
    ins(ops[r.pick({70, 10, 10, 10})] + bit_dst());
  }
  // A rung of b basic instructions: a condition and one or two outputs, or a
  // fork (MPS/AND/OUT/MPP/OUT) when there is room.
  void basic_rung(int b) {
    rung();
    if (b <= 1) { opener(); return; }
    if (b >= 7 && r.pct(25)) {
      opener();
      extenders(b - 6);
      ins("MPS");
      ins("AND " + bit_src());
      output();
      ins("MPP");
      output();
      return;
    }
    int outs = b >= 4 && r.pct(30) ? 2 : 1;
    opener();
    extenders(b - outs - 1);
    for (int i = 0; i < outs; i++) output();
  }

  // ---- application instructions
  void compare() {
    static const char* const ops[] = {"LDEQ ", "LDNE ", "LDLT ", "LDLE ", "LDGT ", "LDGE "};
    std::string op = ops[r.pick({15, 15, 20, 15, 20, 15})];
    if (r.pct(20)) ins(op + real_in() + " " + (r.pct(50) ? real_const() : real_in()));
    else ins(op + int_word() + " " + (r.pct(55) ? int_const() : int_word()));
  }
  void move() {
    switch (r.pick({25, 20, 20, 15, 10, 5, 5})) {
      case 0: return ins("MOV " + wx() + " " + d_dst());
      case 1: return ins("MOV " + d_src() + " " + d_dst());
      case 2: return ins("MOV " + int_const() + " " + int_dst());
      case 3: return ins("MOV " + d_src() + " " + wy_dst());
      case 4: return ins("MOV " + real_in() + " " + real_dst());
      case 5: return ins("MOV " + d_src() + " " + real_dst());
      default: return ins("MOV " + real_in() + " " + d_dst());
    }
  }
  void arith() {
    static const char* const ops[] = {"ADD ", "SUB ", "MUL ", "DIV ", "MOD "};
    int k = r.pick({30, 25, 20, 15, 10});
    if (k < 4 && r.pct(20)) return ins(ops[k] + real_src() + " " + real_in() + " " + real_dst());
    ins(ops[k] + int_word() + " " + int_src() + " " + int_dst());
  }
  void logic() {
    switch (r.pick({20, 20, 20, 10, 15, 15})) {
      case 0: return ins("WAND " + int_word() + " " + int_src() + " " + int_dst());
      case 1: return ins("WOR " + int_word() + " " + int_src() + " " + int_dst());
      case 2: return ins("WXOR " + int_word() + " " + int_src() + " " + int_dst());
      case 3: return ins("WNOT " + int_word() + " " + int_dst());
      case 4: return ins("SHL " + int_word() + " " + num(r.below(32)) + " " + int_dst());
      default: return ins("SHR " + int_word() + " " + num(r.below(32)) + " " + int_dst());
    }
  }
  void special() {
    switch (r.pick({20, 15, 10, 20, 10, 10, 15})) {
      case 0: return ins("SIN " + real_in() + " " + real_dst());
      case 1: return ins("COS " + real_in() + " " + real_dst());
      case 2: return ins("TAN " + real_in() + " " + real_dst());
      case 3: return ins("SQRT " + real_pos() + " " + real_dst());
      case 4: return ins("EXP " + real_in() + " " + real_dst());
      case 5: return ins("LN " + real_pos() + " " + real_dst());
      default: return ins("ABS " + real_in() + " " + real_dst());
    }
  }
  void timer_ins() {
    static const char* const ops[] = {"TON ", "TOF ", "TP "};
    int k = r.pick({60, 20, 15, 5});
    if (k == 3) return ins("RSTT " + timer());
    ins(ops[k] + timer() + " " + num(r.range(1, 50) * 100));
  }
  void counter_ins() {
    int k = r.pick({60, 30, 10});
    if (k == 2) return ins("RSTC " + counter());
    ins(std::string(k == 0 ? "CTU " : "CTD ") + counter() + " " + num(r.range(2, 100)) + " " + edge());
  }
  void app(int klass) {
    switch (OpClass(klass)) {
      case OpClass::Compare: return compare();
      case OpClass::Move: return move();
      case OpClass::Arith: return arith();
      case OpClass::Logic: return logic();
      case OpClass::Special: return special();
      case OpClass::Timer: return timer_ins();
      case OpClass::Counter: return counter_ins();
      default: throw std::logic_error("synth: not an application class");
    }
  }

 private:
  std::string body_;
  int rungs_ = 0, count_ = 0, edges_ = 0, timers_ = 0, counters_ = 0;
  int next_m_ = 0, next_d_ = 0, next_wy_ = 0, next_f_ = 0;
};

}  // namespace

AppMix typical_app_mix() {
  AppMix m{};
  m[int(OpClass::Compare)] = 0.28;
  m[int(OpClass::Move)] = 0.25;
  m[int(OpClass::Arith)] = 0.17;
  m[int(OpClass::Logic)] = 0.05;
  m[int(OpClass::Special)] = 0.05;
  m[int(OpClass::Timer)] = 0.12;
  m[int(OpClass::Counter)] = 0.08;
  return m;
}

std::string synth_il(const SynthOptions& o) {
  if (o.n_exe < 1) throw std::invalid_argument("synth: n_exe must be at least 1");
  if (!(o.p_basic >= 0 && o.p_basic <= 1)) throw std::invalid_argument("synth: p_basic must be in [0, 1]");
  // Exact counts: basic, then the application classes by largest remainder.
  std::array<int, kOpClassCount> rem{};
  rem[int(OpClass::Basic)] = int(std::lround(o.p_basic * o.n_exe));
  int napp = o.n_exe - rem[int(OpClass::Basic)];
  double wsum = 0;
  for (int c : kApp) wsum += std::max(0.0, o.mix[c]);
  if (napp > 0 && wsum <= 0) throw std::invalid_argument("synth: the application mix is empty");
  std::vector<std::pair<double, int>> frac;
  int given = 0;
  for (int c : kApp) {
    double want = napp * std::max(0.0, o.mix[c]) / (wsum > 0 ? wsum : 1);
    rem[c] = int(std::floor(want));
    given += rem[c];
    frac.push_back({want - rem[c], c});
  }
  std::stable_sort(frac.begin(), frac.end(), [](auto& a, auto& b) { return a.first > b.first; });
  for (size_t i = 0; given < napp; i++, given++) rem[frac[i % frac.size()].second]++;

  Writer w(o.seed);
  auto app_left = [&] {
    int n = 0;
    for (int c : kApp) n += rem[c];
    return n;
  };
  auto draw_app = [&] {  // a class, in proportion to what is left of each
    int n = app_left(), x = w.r.below(n);
    for (int c : kApp) {
      if (x < rem[c]) { rem[c]--; return c; }
      x -= rem[c];
    }
    throw std::logic_error("synth: no application instruction left");
  };
  int& basic = rem[int(OpClass::Basic)];
  while (basic + app_left() > 0) {
    int apps = app_left();
    if (apps == 0) {  // basic rungs only; never leave a single instruction behind
      int b = std::min(basic, w.r.range(2, 7));
      if (basic - b == 1) b++;
      w.basic_rung(b);
      basic -= b;
      continue;
    }
    // Basics per application instruction still to place, and this rung's share.
    // Many basics per application instruction: mostly plain bit rungs between.
    double ratio = double(basic) / apps;
    if (ratio > 5 && w.r.below(1000) < int(1000 * (1 - 5 / ratio))) {
      int b = std::min(basic, w.r.range(2, 7));
      if (basic - b == 1) b++;
      w.basic_rung(b);
      basic -= b;
      continue;
    }
    int k = ratio >= 1 ? (w.r.pct(30) ? 2 : 1) : std::clamp(int(std::lround((0.5 + w.r.below(100) / 100.0) / ratio)), 1, 6);
    k = std::min(k, apps);
    std::vector<int> cls;
    for (int i = 0; i < k; i++) cls.push_back(draw_app());
    int b = int(std::lround(ratio * k)) + w.r.range(-1, 1);
    b = std::clamp(b, 0, std::min(basic, 8));
    std::vector<int> cmps, others;
    for (int c : cls) (c == int(OpClass::Compare) ? cmps : others).push_back(c);
    bool open_with_compare = !cmps.empty() && (b == 0 || others.empty() || w.r.pct(50));
    if (!open_with_compare && b == 0) {
      if (w.rungs() > 0) {  // no basic left for a condition: these run on the last rung's
        for (int c : cls) w.app(c);
        continue;
      }
      b = 1;  // the very first rung needs a push
      if (basic == 0) basic++;  // p_basic 0: one basic over the quota
    }
    w.rung();
    int used = 0;
    if (open_with_compare) {
      w.compare();
      cmps.pop_back();
    } else {
      w.opener();
      used++;
    }
    for (size_t i = 0; i < cmps.size(); i++) {  // more compares: in series or parallel if a basic is left
      w.compare();
      if (used < b) { w.ins(w.r.pct(70) ? "ANDBLK" : "ORBLK"); used++; }
    }
    int left = b - used;
    int outs = others.empty() ? std::min(left, 1 + (left >= 3 && w.r.pct(30))) : (left >= 2 && w.r.pct(40) ? 1 : 0);
    w.extenders(left - outs);
    for (int c : others) w.app(c);
    for (int i = 0; i < outs; i++) w.output();
    basic -= b;
  }
  char title[128];
  std::snprintf(title, sizeof title, "synth: n_exe %d, p_basic %.3f, seed %llu", o.n_exe, o.p_basic,
                (unsigned long long)o.seed);
  return w.text(title);
}

std::string synth_class_il(OpClass c, int n, uint64_t seed, bool powered) {
  if (n < 1) throw std::invalid_argument("synth: n must be at least 1");
  Writer w(seed);
  w.fresh = true;
  std::string title = std::string("synth: class ") + op_class_name(c) + ", " + num(n) + " instructions" +
                      (powered ? "" : ", power off");
  if (c == OpClass::Basic) {
    int left = n;
    while (left > 0) {
      int b = std::min(left, w.r.range(2, 9));
      if (left - b == 1) b++;
      w.basic_rung(b);
      left -= b;
    }
    return w.text(title);
  }
  if (c == OpClass::Flow) throw std::invalid_argument("synth: no class program for Flow");
  w.rung();
  if (c == OpClass::Compare) {
    for (int i = 0; i < n; i++) w.compare();
    return w.text(title);
  }
  w.ins(powered ? "TRUE" : "LOAD M8191");
  for (int i = 0; i < n; i++) w.app(int(c));
  return w.text(title + " (and one " + (powered ? "TRUE" : "LOAD") + ")");
}

int ClassCounts::total() const {
  int t = 0;
  for (int v : n) t += v;
  return t;
}
double ClassCounts::p_basic() const { return total() ? double(n[int(OpClass::Basic)]) / total() : 0; }

ClassCounts count_classes(const Program& p) {
  ClassCounts c;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) c.n[int(op_info(in.op).klass)]++;
  return c;
}

// ------------------------------------------------------------------ the plant

namespace {

// "|--+--A--+--rest" / "|  +--B--+" with A and B padded to one width.
std::string parallel_rung(const std::string& title, const std::string& a, const std::string& b,
                          const std::string& rest) {
  size_t w = std::max(a.size(), b.size());
  std::string pa = "--" + a + std::string(w - a.size(), '-') + "--";
  std::string pb = "--" + b + std::string(w - b.size(), '-') + "--";
  return "rung \"" + title + "\"\n|--+" + pa + "+--" + rest + "\n|  +" + pb + "+\n\n";
}
// "|--cond--+--(A)" / "|        +--(B)"
std::string fork_rung(const std::string& title, const std::string& cond, const std::string& a, const std::string& b) {
  std::string first = "|--" + cond + "--";
  return "rung \"" + title + "\"\n" + first + "+--" + a + "\n|" + std::string(first.size() - 1, ' ') + "+--" + b + "\n\n";
}
std::string line_rung(const std::string& title, const std::string& row) {
  return "rung \"" + title + "\"\n|--" + row + "\n\n";
}

}  // namespace

std::string synth_plant_ld(int rungs, uint64_t seed) {
  if (rungs < 1) throw std::invalid_argument("synth: a plant needs at least one rung");
  Rng r = synth_rng(seed);
  std::string out = "# synthetic plant: " + num(rungs) + " rungs (bench/synth.cpp)\n\n";
  int made = 0;
  for (int g = 0; made < rungs; g++) {
    // Inputs stay in X0..X63 so a bench trace drives them; the rest is spread out.
    auto X = [&](int k) { return "X" + num((g * 5 + k) % D::kInX); };
    std::string motor = "Y" + num((g * 3) % 8192), lamp = "Y" + num((g * 3 + 1) % 8192),
                done = "Y" + num((g * 3 + 2) % 8192);
    std::string fault = "M" + num((g * 2) % 8192), alarm = "M" + num((g * 2 + 1) % 8192);
    std::string t1 = "T" + num((g * 2) % 256), t2 = "T" + num((g * 2 + 1) % 256), c = "C" + num(g % 256);
    std::string level = "D" + num((g * 4) % 8192), total = "D" + num((g * 4 + 1) % 8192),
                speed = "D" + num((g * 4 + 2) % 8192);
    std::string gs = num(g);
    std::string items[] = {
        parallel_rung("motor " + gs + " start/stop", "[" + X(0) + "]", "[" + motor + "]",
                      "[/" + X(1) + "]--[/" + fault + "]--(" + motor + ")"),
        line_rung("motor " + gs + " overload", "[" + X(2) + "]--(S " + fault + ")"),
        line_rung("motor " + gs + " acknowledge", "[" + X(3) + "]--[/" + X(2) + "]--(R " + fault + ")"),
        line_rung("conveyor " + gs + " start delay", "[" + motor + "]--[" + X(4) + "]--(TON " + t1 + " " +
                                                       num(r.range(1, 30) * 100) + ")"),
        parallel_rung("conveyor " + gs + " running", "[" + t1 + "]", "[" + lamp + "]",
                      "[" + motor + "]--(" + lamp + ")"),
        line_rung("parts " + gs, "[P " + X(4) + "]--[" + lamp + "]--(CTU " + c + " " + num(r.range(5, 200)) + ")"),
        fork_rung("batch " + gs + " done", "[" + c + "]", "(" + done + ")", "(RST " + c + ")"),
        line_rung("level " + gs, "[" + motor + "]--(MOV WX" + num(g % D::kInWX) + " " + level + ")"),
        fork_rung("level " + gs + " alarm", "[" + level + " > " + num(r.range(100, 5000)) + "]", "(" + alarm + ")",
                  "(TOF " + t2 + " 5s)"),
        line_rung("total " + gs, "[P " + done + "]--(ADD " + total + " 1 " + total + ")"),
        line_rung("speed " + gs, "[" + lamp + "]--[/" + alarm + "]--(MUL WX" + num((g + 1) % D::kInWX) + " 3 " +
                                     speed + ")"),
    };
    for (const std::string& s : items) {
      if (made == rungs) break;
      out += s;
      made++;
    }
  }
  return out;
}

}  // namespace ldc::synth

// ------------------------------------------------------------------ typed programs

namespace ldc::synth {

std::string synth_typed_il(int instances) {
  if (instances < 1 || instances > kTypedMaxInstances) throw std::invalid_argument("synth_typed_il: instance count");
  std::string s = "; typed program: " + std::to_string(instances) + " instances of a scaling block\n";
  auto d = [](int cell) { return "D" + std::to_string(cell); };
  s += ".rung line 1 \"table\"\nLOAD S1\n";  // the shared lookup table, set on the first scan
  for (int i = 0; i < 16; i++) s += "MOVE.INT " + std::to_string(i * 37 - 200) + " " + d(kTypedTable + i) + "\n";
  for (int k = 0; k < instances; k++) {
    const int b = kTypedBase + kTypedCells * k;
    // cells: +0 INT count, +1 DINT raw, +2..3 LREAL value, +4..5 LREAL filtered, +6 DINT total,
    // +7 DINT slot, +8 INT looked up, +9 INT scaled, +10..21 DINT ring of 12, +22..23 LREAL gain
    const std::string en = "X" + std::to_string(k % SynthDevices::kInX), in = "WX" + std::to_string(k % SynthDevices::kInWX);
    s += ".rung line " + std::to_string(2 + 3 * k) + " \"fb" + std::to_string(k) + ": scale\"\n";
    s += "LOAD " + en + "\n";
    s += "ADD.INT " + d(b) + " 1 " + d(b) + "\n";
    s += "MOVE.DINT " + in + " " + d(b + 1) + "\n";
    s += "CONV.LREAL.DINT " + d(b + 1) + " " + d(b + 2) + "\n";
    s += "MUL.LREAL " + d(b + 2) + " 0.0125 " + d(b + 2) + "\n";
    s += "SUB.LREAL " + d(b + 2) + " " + d(b + 4) + " " + d(b + 22) + "\n";
    s += "MUL.LREAL " + d(b + 22) + " 0.25 " + d(b + 22) + "\n";
    s += "ADD.LREAL " + d(b + 4) + " " + d(b + 22) + " " + d(b + 4) + "\n";
    s += "ADD.DINT " + d(b + 6) + " " + d(b + 1) + " " + d(b + 6) + "\n";
    s += "CONV.INT.LREAL " + d(b + 4) + " " + d(b + 9) + "\n";
    s += ".rung line " + std::to_string(3 + 3 * k) + " \"fb" + std::to_string(k) + ": tables\"\n";
    s += "LOAD " + en + "\n";
    s += "MOD.DINT " + d(b + 1) + " 12 " + d(b + 7) + "\n";
    s += "ABS.DINT " + d(b + 7) + " " + d(b + 7) + "\n";
    s += "IDX.DINT " + d(b + 7) + " 0 11\n";
    s += "STX.DINT " + d(b + 6) + " " + d(b + 10) + " 1\n";
    s += "AND.WORD " + d(b) + " 15 " + d(b + 8) + "\n";
    s += "IDX.INT " + d(b + 8) + " 0 15\n";
    s += "LDX.INT " + d(kTypedTable) + " 1 " + d(b + 8) + "\n";
    s += "ADD.INT " + d(b + 8) + " " + d(b + 9) + " " + d(b + 9) + "\n";
    s += ".rung line " + std::to_string(4 + 3 * k) + " \"fb" + std::to_string(k) + ": alarm\"\n";
    s += "GT.LREAL " + d(b + 4) + " 10.0\n";
    s += "LT.INT " + d(b + 9) + " -100\n";
    s += "ORBLK\n";
    s += "AND " + en + "\n";
    s += "OUT Y" + std::to_string(k % SynthDevices::kBitsY) + "\n";
  }
  return s + ".end\n";
}

}  // namespace ldc::synth
