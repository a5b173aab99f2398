// bench/ldgen.cpp -- the random ladder program and trace generator (docs/testing.md).
//
// Every rung is drawn as a tree and rendered as a grid of text blocks.  A block
// is a rectangle of rows; power enters on the left of its first row and leaves
// on the right of its first row:
//
//   series    A--B        blocks side by side, first rows joined by wire
//   parallel  +--A--+     children stacked, a column of '+' on each side at
//             |     |     each child's first row, '|' between them, every
//             +--B--+     child's first row padded with '-' to one width
//   fork      +--(Y0)     actions stacked with a left column of '+' only
//             +--[X1]--(Y1)
//
// Two stacked children are separated by a spacer row when a '+' or '|' at the
// bottom of the upper one would touch one at the top of the lower one (the
// grid joins those).
#include "bench/ldgen.h"
#include "bench/rng.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <initializer_list>
#include <map>

#include "ir/ir.h"
#include "driver/version.h"

namespace ldc {
namespace {

// ------------------------------------------------------------------ blocks

struct Block {
  std::vector<std::string> rows;
  size_t width() const {
    size_t w = 0;
    for (const auto& r : rows) w = std::max(w, r.size());
    return w;
  }
};

Block leaf(std::string s) { return Block{{std::move(s)}}; }

std::string pad(const std::string& s, size_t w, char fill) { return s.size() >= w ? s : s + std::string(w - s.size(), fill); }

bool vertical(char c) { return c == '+' || c == '|'; }

// Would row `lower`, drawn right under row `upper` (same left column), join it?
bool touches(const std::string& upper, const std::string& lower) {
  for (size_t i = 0; i < std::min(upper.size(), lower.size()); i++)
    if (vertical(upper[i]) && vertical(lower[i])) return true;
  return false;
}

// A--B--C: first rows joined by `wires` dashes, other rows by blanks.
Block series(const std::vector<Block>& kids, const std::vector<int>& wires) {
  Block b;
  size_t h = 0;
  for (const auto& k : kids) h = std::max(h, k.rows.size());
  b.rows.assign(h, "");
  for (size_t i = 0; i < kids.size(); i++) {
    size_t w = kids[i].width();
    for (size_t r = 0; r < h; r++) {
      if (i > 0) b.rows[r] += std::string(size_t(wires[i - 1]), r == 0 ? '-' : ' ');
      b.rows[r] += pad(r < kids[i].rows.size() ? kids[i].rows[r] : "", w, ' ');
    }
  }
  return b;
}

// Children stacked at column `lead`, a '+' in column 0 at each child's first row
// and '|' between the first and the last of them; with `right`, the same
// column on the right (a parallel block), else none (a fork of actions).
Block stack(const std::vector<Block>& kids, int lead, int trail, bool right) {
  size_t w = 0;
  for (const auto& k : kids) w = std::max(w, k.width());
  size_t inner = size_t(lead) + w + size_t(right ? trail : 0);
  Block b;
  std::vector<size_t> first;
  for (size_t i = 0; i < kids.size(); i++) {
    const Block& k = kids[i];
    if (i > 0 && touches(kids[i - 1].rows.back(), k.rows[0])) b.rows.push_back(" " + std::string(inner - 1, ' '));
    first.push_back(b.rows.size());
    for (size_t r = 0; r < k.rows.size(); r++) {
      std::string row;
      if (r == 0) {
        row = "+" + std::string(size_t(lead - 1), '-') + pad(k.rows[0], w, right ? '-' : ' ');
        if (right) row += std::string(size_t(trail - 1), '-') + "+";
      } else {
        row = " " + std::string(size_t(lead - 1), ' ') + pad(k.rows[r], w, ' ');
        if (right) row += std::string(size_t(trail), ' ');
      }
      b.rows.push_back(row);
    }
  }
  for (size_t r = first.front() + 1; r < first.back(); r++) {
    if (b.rows[r][0] != '+') b.rows[r][0] = '|';
    if (right && b.rows[r].back() != '+') b.rows[r].back() = '|';
  }
  return b;
}

std::string rstrip(std::string s) {
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

Block render_node(const GenNode& n) {
  std::vector<Block> kids;
  for (const auto& k : n.kids) kids.push_back(render_node(k));
  switch (n.kind) {
    case GenNode::Kind::Series: return series(kids, n.wires);
    case GenNode::Kind::Parallel: return stack(kids, 1 + n.wires[0], 1 + n.wires[1], true);
    case GenNode::Kind::Fork: return stack(kids, 1 + n.wires[0], 0, false);
    default: return leaf(n.text);
  }
}

bool is_action(const GenNode& n) {
  switch (n.kind) {
    case GenNode::Kind::Elem: return !n.text.empty() && n.text[0] == '(';
    case GenNode::Kind::Series: return !n.kids.empty() && is_action(n.kids.back());
    case GenNode::Kind::Parallel: return false;
    default: return true;
  }
}

void count(const GenNode& n, GenItem& it) {
  if (n.kind == GenNode::Kind::Elem) {
    if (n.text[0] == '[') it.inputs++;
    else {
      it.outputs++;
      if (n.text.rfind("(JMP ", 0) == 0) it.jumps.push_back(n.text.substr(5, n.text.size() - 6));
    }
  }
  for (const auto& k : n.kids) count(k, it);
}

// Every node of the tree, parents before their kids, by path.
void paths(const GenNode& n, std::vector<int>& at, std::vector<std::vector<int>>& out) {
  out.push_back(at);
  for (size_t i = 0; i < n.kids.size(); i++) {
    at.push_back(int(i));
    paths(n.kids[i], at, out);
    at.pop_back();
  }
}

// ------------------------------------------------------------------ the generator

class Gen {
 public:
  Gen(uint64_t seed, const GenOptions& o) : r_(seed * 0x2545F4914F6CDD1Dull + 0x1D), o_(o) {}
  GenProgram program(uint64_t seed);

 private:
  Rng r_;
  const GenOptions& o_;

  // state of the rung being drawn
  int depth_ = 0;        // nesting allowed for its conditions
  int leaves_left_ = 0;  // input elements it may still draw before staying small
  int outputs_ = 0;
  std::string special_;  // a (JMP L) or (END) still to place
  int special_at_ = 0;   // ... as this rung's output number

  bool on(uint32_t c) const { return (o_.classes & c) != 0; }

  std::string dev(const char* p, int n) { return std::string(p) + std::to_string(r_.below(n)); }
  std::string bit_read();
  std::string bit_write();
  std::string int_word();
  std::string dest_word();
  std::string int_const();
  std::string real_const();
  std::string int_value() { return r_.pct(55) ? int_word() : int_const(); }
  std::string value();
  std::string divisor(bool int_only);
  std::string shift_count();
  std::string timer_preset();
  std::string counter_preset();

  std::string input_text();
  std::string output_text();

  GenNode elem(std::string text) {
    GenNode n;
    n.text = std::move(text);
    return n;
  }
  GenNode cond(int depth, int parent);  // parent: 0 none, 1 series, 2 parallel
  GenNode output();
  GenNode special_block();
  GenNode then_of(std::vector<GenNode> kids);
  GenNode tail(int forks);
  GenNode then(int forks, int depth);
  GenNode fork(int forks);
  GenNode group();
  int wire() { return r_.pct(80) ? 2 : r_.range(1, 4); }
  GenItem rung(int index);
};

std::string Gen::bit_read() {
  switch (r_.pick({30, 14, 14, 8, o_.t ? 8 : 0, o_.c ? 8 : 0, 5})) {
    case 0: return dev("X", o_.x);
    case 1: return dev("Y", o_.y);
    case 2: return dev("M", o_.m);
    case 3: return dev("K", o_.k);
    case 4: return dev("T", o_.t);
    case 5: return dev("C", o_.c);
    default: {
      int p = r_.below(10);
      return p < 5 ? "S0" : p < 9 ? "S1" : "S" + std::to_string(r_.range(2, 15));
    }
  }
}

std::string Gen::bit_write() {
  switch (r_.pick({55, 28, 14, 3})) {
    case 0: return dev("Y", o_.y);
    case 1: return dev("M", o_.m);
    case 2: return dev("K", o_.k);
    default: return "S0";
  }
}

std::string Gen::int_word() {
  switch (r_.pick({50, o_.wx ? 18 : 0, o_.wy ? 10 : 0, o_.t ? 11 : 0, o_.c ? 11 : 0})) {
    case 0: return dev("D", o_.d);
    case 1: return dev("WX", o_.wx);
    case 2: return dev("WY", o_.wy);
    case 3: return dev("T", o_.t);
    default: return dev("C", o_.c);
  }
}

std::string Gen::dest_word() {
  switch (r_.pick({55, o_.f ? 22 : 0, o_.wy ? 10 : 0, o_.t ? 6 : 0, o_.c ? 7 : 0})) {
    case 0: return dev("D", o_.d);
    case 1: return dev("F", o_.f);
    case 2: return dev("WY", o_.wy);
    case 3: return dev("T", o_.t);
    default: return dev("C", o_.c);
  }
}

std::string Gen::int_const() {
  static const char* const special[] = {
      "0",           "1",           "-1",          "2",           "7",           "100",
      "1000",        "65535",       "65536",       "100000",      "2147483647",  "-2147483648",
      "16#80000000", "16#7FFFFFFF", "16#FFFFFFFF", "16#FF",       "0xFF00",      "2#1011",
      "8#777",       "1_000",       "-16#10",      "-2147483647", "46341",       "-65536"};
  switch (r_.pick({20, 15, 35, 10})) {
    case 0: return std::to_string(r_.range(-10, 10));
    case 1: return std::to_string(r_.range(-1000, 1000));
    case 2: return r_.of(special);
    default: return std::to_string(int32_t(uint32_t(r_.next())));
  }
}

std::string real_spelling(double v, bool exp) {
  char buf[64];
  std::snprintf(buf, sizeof buf, exp ? "%.3e" : "%.3f", v);
  return buf;  // always has '.' (and maybe an exponent): a REAL constant
}

std::string Gen::real_const() {
  static const char* const special[] = {"0.0",  "-0.0",   "1.0",   "-1.0", "0.5",    "2.5",    "-3.75",
                                        "3.14159", "1e30", "-1e30", "3.4e38", "1e-30", "1e-40", "1.5e3",
                                        "100.0", "2.0e9", "-3.0e9", "0.1",   "88.8",   "1.0e-3"};
  switch (r_.pick({40, 35, 25})) {
    case 0: return r_.of(special);
    case 1: return real_spelling(r_.range(-100000, 100000) / 1000.0, false);
    default: return real_spelling(double(r_.range(-9999, 9999)) * std::pow(10.0, r_.range(-12, 12)) / 1000.0, true);
  }
}

std::string Gen::value() {
  switch (r_.pick({35, o_.f ? 20 : 0, 25, 20})) {
    case 0: return int_word();
    case 1: return dev("F", o_.f);
    case 2: return int_const();
    default: return real_const();
  }
}

std::string Gen::divisor(bool int_only) {
  if (r_.pct(30)) {
    static const char* const ints[] = {"0", "-1", "0", "-1", "1", "-2147483648"};
    static const char* const reals[] = {"0.0", "-0.0", "-1.0", "1e-40"};
    return int_only || r_.pct(60) ? r_.of(ints) : r_.of(reals);
  }
  return int_only ? int_value() : value();
}

std::string Gen::shift_count() {
  static const char* const counts[] = {"-33", "-1", "0", "1", "4", "8", "15", "16", "31", "32", "33", "63", "100", "-2147483648"};
  return r_.pct(70) ? r_.of(counts) : int_word();
}

std::string Gen::timer_preset() {
  static const char* const presets[] = {"0", "1", "20", "35", "50", "80", "120", "200", "300ms", "T#40ms",
                                        "T#1s", "1s", "T#150ms", "TIME#60ms", "16#40", "2147483647"};
  return r_.pct(75) ? r_.of(presets) : int_word();
}

std::string Gen::counter_preset() {
  static const char* const presets[] = {"-1", "0", "1", "2", "3", "5", "8", "-2147483648", "2147483647"};
  return r_.pct(70) ? r_.of(presets) : int_word();
}

std::string Gen::input_text() {
  // NO/NC contacts also stand in when no input class is chosen at all
  int kind = r_.pick({on(kGenContacts) ? 40 : 0, on(kGenContacts) ? 25 : 0, on(kGenEdges) ? 12 : 0,
                      on(kGenCompares) ? 22 : 0});
  bool loose = r_.pct(5);  // blanks inside the brackets are free
  switch (kind) {
    case 0: return loose ? "[ " + bit_read() + " ]" : "[" + bit_read() + "]";
    case 1: return loose ? "[/ " + bit_read() + "]" : "[/" + bit_read() + "]";
    case 2: return std::string(r_.pct(50) ? "[P " : "[N ") + (loose ? " " : "") + bit_read() + "]";
    default: {
      static const char* const ops[] = {"==", "=", "!=", "<>", "<", "<=", ">", ">="};
      std::string a = r_.pct(85) ? (o_.f && r_.pct(30) ? dev("F", o_.f) : int_word()) : value();
      std::string b = value();
      if (r_.pct(25)) std::swap(a, b);
      const char* op = r_.of(ops);
      return loose ? "[" + a + op + b + "]" : "[" + a + " " + op + " " + b + "]";
    }
  }
}

std::string Gen::output_text() {
  int kind = r_.pick({on(kGenCoils) ? 22 : 0, on(kGenSetReset) ? 12 : 0, on(kGenTimers) ? 11 : 0,
                      on(kGenCounters) ? 8 : 0, on(kGenMove) ? 11 : 0, on(kGenArith) ? 14 : 0,
                      on(kGenLogic) ? 10 : 0, on(kGenRealFn) ? 8 : 0});
  switch (kind) {
    case 0:
    default: return std::string(r_.pct(25) ? "(/" : "(") + bit_write() + ")";  // also when no output class is on
    case 1: {
      static const char* const kw[] = {"S", "SET", "R", "RESET", "RST"};
      return "(" + std::string(r_.of(kw)) + " " + bit_write() + ")";
    }
    case 2: {
      if (r_.pct(15)) return "(RST " + dev("T", o_.t) + ")";
      static const char* const kw[] = {"TON", "TOF", "TP", "MTON", "MTOF", "MTP"};
      return "(" + std::string(r_.of(kw)) + " " + dev("T", o_.t) + " " + timer_preset() + ")";
    }
    case 3: {
      if (r_.pct(15)) return "(RST " + dev("C", o_.c) + ")";
      return std::string(r_.pct(55) ? "(CTU " : "(CTD ") + dev("C", o_.c) + " " + counter_preset() + ")";
    }
    case 4: return "(MOV " + value() + " " + dest_word() + ")";
    case 5: {
      static const char* const kw[] = {"ADD", "SUB", "MUL", "DIV", "MOD"};
      std::string op = r_.of(kw);
      bool int_only = op == "MOD";
      std::string a = int_only ? int_value() : value();
      std::string b = op == "DIV" || op == "MOD" ? divisor(int_only) : int_only ? int_value() : value();
      if (r_.pct(12)) {  // a pair at an edge of the arithmetic: wrap, overflow, INT32_MIN / -1, inf, NaN
        static const std::pair<const char*, const char*> pairs[] = {
            {"-2147483648", "-1"}, {"16#80000000", "-1"}, {"2147483647", "1"},  {"-2147483648", "1"},
            {"65536", "65536"},    {"46341", "46341"},    {"-7", "2"},          {"7", "-2"},
            {"3.4e38", "3.4e38"},  {"1e30", "-1e30"},     {"-7.5", "-0.0"},     {"1e-40", "1e-40"}};
        const auto& [x, y] = pairs[size_t(r_.below(int_only ? 8 : 12))];
        a = r_.pct(60) ? x : int_only ? int_word() : value();
        b = r_.pct(60) ? y : int_only ? int_word() : value();
        if (r_.pct(50) && op != "DIV" && op != "MOD") std::swap(a, b);
      }
      return "(" + op + " " + a + " " + b + " " + dest_word() + ")";
    }
    case 6: {
      static const char* const kw[] = {"AND", "OR", "XOR", "NOT", "SHL", "SHR"};
      std::string op = r_.of(kw);
      if (op == "NOT") return "(NOT " + int_value() + " " + dest_word() + ")";
      std::string b = op == "SHL" || op == "SHR" ? shift_count() : int_value();
      return "(" + op + " " + int_value() + " " + b + " " + dest_word() + ")";
    }
    case 7: {
      static const char* const kw[] = {"SIN", "COS", "TAN", "SQRT", "EXP", "LN", "ABS"};
      return "(" + std::string(r_.of(kw)) + " " + value() + " " + dest_word() + ")";
    }
  }
}

// A condition: a contact, or a series or parallel block of 2..3 conditions.
GenNode Gen::cond(int depth, int parent) {
  if (depth <= 0 || leaves_left_ <= 1 || r_.pct(35)) {
    leaves_left_--;
    return elem(input_text());
  }
  int kind = parent == 1 ? 2 : parent == 2 ? 1 : r_.range(1, 2);  // alternate: same kinds would merge
  int n = r_.pct(70) ? 2 : 3;
  GenNode b;
  b.kind = kind == 1 ? GenNode::Kind::Series : GenNode::Kind::Parallel;
  for (int i = 0; i < n; i++) b.kids.push_back(cond(depth - 1, kind));
  if (kind == 1)
    for (int i = 1; i < n; i++) b.wires.push_back(wire());
  else
    b.wires = {wire(), wire()};
  return b;
}

GenNode Gen::special_block() {
  std::string s = std::move(special_);
  special_.clear();
  if (s == "(END)")  // rare and conditional: two inputs in series
    return then_of({elem("[" + dev("X", o_.x) + "]"), elem("[" + dev("X", o_.x) + "]"), elem(s)});
  if (r_.pct(75)) return then_of({elem(r_.pct(70) ? "[" + dev("X", o_.x) + "]" : "[/" + dev("X", o_.x) + "]"), elem(s)});
  return elem(s);
}

GenNode Gen::then_of(std::vector<GenNode> kids) {
  GenNode b;
  b.kind = GenNode::Kind::Series;
  b.kids = std::move(kids);
  for (size_t i = 1; i < b.kids.size(); i++) b.wires.push_back(wire());
  return b;
}

GenNode Gen::output() {
  if (!special_.empty() && outputs_ >= special_at_) return special_block();
  outputs_++;
  return elem(output_text());
}

// What follows a condition: one output, or a fork of outputs.
GenNode Gen::tail(int forks) { return forks < 2 && r_.pct(30) ? fork(forks + 1) : output(); }

GenNode Gen::then(int forks, int depth) {
  GenNode c = cond(depth, 0);
  GenNode t = tail(forks);
  return then_of({std::move(c), std::move(t)});
}

// Actions sharing one power flow: bare outputs and conditions with their own tails.
GenNode Gen::fork(int forks) {
  int n = r_.pick({0, 0, 50, 30, 20});
  GenNode b;
  b.kind = GenNode::Kind::Fork;
  for (int i = 0; i < n; i++) b.kids.push_back(r_.pct(40) ? output() : then(forks, std::min(depth_, 2)));
  b.wires = {wire()};
  return b;
}

// One group of rows reached from the left rail.
GenNode Gen::group() {
  int p = r_.below(100);
  if (p < 8) return output();
  if (p < 20) return fork(1);
  return then(0, depth_);
}

GenItem Gen::rung(int index) {
  depth_ = r_.range(0, std::clamp(o_.max_depth, 0, 6));
  leaves_left_ = r_.range(3, 24);
  outputs_ = 0;
  special_at_ = r_.below(3);
  GenItem it;
  it.kind = GenItem::Kind::Rung;
  it.number = index;
  it.root.kind = GenNode::Kind::Rail;
  int n = r_.pct(85) ? 1 : r_.range(2, 3);
  for (int i = 0; i < n; i++) it.root.kids.push_back(group());
  if (!special_.empty()) it.root.kids.push_back(special_block());
  // A row joined to the rail starts "|-" or with an element right at the rail (0).
  for (size_t i = 0; i < it.root.kids.size(); i++) it.root.wires.push_back(r_.pct(10) ? 0 : wire());
  update_rung(it);
  return it;
}

GenProgram Gen::program(uint64_t seed) {
  GenProgram p;
  int n = std::max(1, o_.rungs);
  p.header = "# ldgen " + ldgen_args(seed, o_) + "\n";
  std::map<int, std::string> label_at;  // rung index -> label placed right before it (n: at the end)
  std::vector<GenItem> rungs;
  for (int i = 0; i < n; i++) {
    special_.clear();
    if (on(kGenJumps) && r_.pct(5)) {
      int lo = std::min(i + 2, n), hi = std::min(i + 9, n);
      int j = r_.range(lo, hi);
      auto it = label_at.find(j);
      if (it == label_at.end()) it = label_at.emplace(j, "L" + std::to_string(label_at.size())).first;
      special_ = "(JMP " + it->second + ")";
    } else if (on(kGenEnd) && r_.below(1000) < 4) {
      special_ = "(END)";
    }
    rungs.push_back(rung(i));
  }
  for (int i = 0; i <= n; i++) {
    if (auto it = label_at.find(i); it != label_at.end()) {
      GenItem l;
      l.kind = GenItem::Kind::Label;
      l.text = it->second;
      p.items.push_back(l);
    }
    if (i < n) p.items.push_back(std::move(rungs[size_t(i)]));
  }
  return p;
}

// ------------------------------------------------------------------ traces

std::string wx_cell(Rng& r) {
  static const char* const special[] = {"0", "-1", "2147483647", "-2147483648", "65536", "0x7fffffff", "0xFF", "-0x10", "46341"};
  switch (r.pick({35, 25, 20, 20})) {
    case 0: return std::to_string(r.range(-20, 20));
    case 1: return std::to_string(r.range(0, 1000));
    case 2: return r.of(special);
    default: return std::to_string(int32_t(uint32_t(r.next())));
  }
}

std::string real_cell(Rng& r) {
  static const char* const special[] = {"0",   "-0",   "1e30", "-1e30", "3.4e38", "1e-40", "nan", "-nan",
                                        "inf", "-inf", "0.5",  "-2.5",  "1e10",   "3.0e9", "-3.0e9", "2147483520"};
  switch (r.pick({30, 45, 25})) {
    case 0: return r.of(special);
    case 1: return real_spelling(r.range(-8000, 8000) / 8.0, false);
    default: return real_spelling(double(r.range(-9999, 9999)) * std::pow(10.0, r.range(-8, 8)) / 1000.0, true);
  }
}

}  // namespace

void update_rung(GenItem& it) {
  it.text = "rung \"" + std::to_string(it.number) + "\"\n";
  std::vector<std::string> prev;
  for (size_t g = 0; g < it.root.kids.size(); g++) {
    Block b = render_node(it.root.kids[g]);
    int dashes = g < it.root.wires.size() ? it.root.wires[g] : 2;
    if (dashes <= 0 && b.rows[0][0] == '+') dashes = 2;  // '+' right at the rail would not be joined to it
    std::string lead(size_t(std::max(dashes, 0)), '-');
    std::vector<std::string> lines;
    for (size_t r = 0; r < b.rows.size(); r++)
      lines.push_back(rstrip("|" + (r == 0 ? lead : std::string(lead.size(), ' ')) + b.rows[r]));
    // rows of two groups that would touch get a spacer row (just the rail)
    if (!prev.empty() && touches(prev.back().substr(1), lines[0].substr(1))) it.text += "|\n";
    for (const auto& l : lines) it.text += l + "\n";
    prev = std::move(lines);
  }
  it.outputs = it.inputs = 0;
  it.jumps.clear();
  count(it.root, it);
}

std::vector<GenNode> rung_reductions(const GenNode& root) {
  std::vector<GenNode> out;
  std::vector<int> at;
  std::vector<std::vector<int>> all;
  paths(root, at, all);
  for (const auto& path : all) {
    const GenNode* n = &root;
    for (int i : path) n = &n->kids[size_t(i)];
    for (size_t i = 0; i < n->kids.size(); i++) {
      if (n->kind == GenNode::Kind::Rail && n->kids.size() < 2) continue;
      if (n->kind == GenNode::Kind::Series && is_action(*n) && i + 1 == n->kids.size()) continue;
      GenNode copy = root;
      GenNode* m = &copy;
      for (int j : path) m = &m->kids[size_t(j)];
      m->kids.erase(m->kids.begin() + long(i));
      if (m->kind == GenNode::Kind::Series && !m->wires.empty()) m->wires.erase(m->wires.begin() + long(i == 0 ? 0 : i - 1));
      if (m->kind == GenNode::Kind::Rail && i < m->wires.size()) m->wires.erase(m->wires.begin() + long(i));
      if (m->kind != GenNode::Kind::Rail && m->kids.size() == 1) {
        GenNode only = std::move(m->kids[0]);
        *m = std::move(only);
      }
      out.push_back(std::move(copy));
    }
  }
  return out;
}

int GenProgram::rungs() const {
  int n = 0;
  for (const auto& i : items) n += i.kind == GenItem::Kind::Rung;
  return n;
}
int GenProgram::outputs() const {
  int n = 0;
  for (const auto& i : items) n += i.outputs;
  return n;
}
int GenProgram::inputs() const {
  int n = 0;
  for (const auto& i : items) n += i.inputs;
  return n;
}

std::string check_options(const GenOptions& o) {
  if (o.rungs < 1) return "at least one rung";
  if (o.max_depth < 0 || o.max_depth > 6) return "depth must be 0..6";
  struct R {
    const char* name;
    int n;
    Dev d;
  } ranges[] = {{"x", o.x, Dev::X}, {"y", o.y, Dev::Y}, {"m", o.m, Dev::M}, {"k", o.k, Dev::K},
                {"d", o.d, Dev::D}, {"f", o.f, Dev::F}, {"t", o.t, Dev::T}, {"c", o.c, Dev::C},
                {"wx", o.wx, Dev::WX}, {"wy", o.wy, Dev::WY}};
  for (const R& r : ranges) {
    bool needed = r.d == Dev::X || r.d == Dev::Y || r.d == Dev::M || r.d == Dev::K || r.d == Dev::D;
    if (r.n < (needed ? 1 : 0) || uint32_t(r.n) > device_count(r.d))
      return std::string("device range ") + r.name + " must be " + (needed ? "1" : "0") + ".." +
             std::to_string(device_count(r.d));
  }
  if ((o.classes & kGenTimers) && o.t == 0) return "timers need t >= 1";
  if ((o.classes & kGenCounters) && o.c == 0) return "counters need c >= 1";
  return "";
}

GenProgram generate_program(uint64_t seed, const GenOptions& opt) {
  if (std::string why = check_options(opt); !why.empty()) throw std::invalid_argument("ldgen: " + why);
  if (opt.classes & kGenTPou) return generate_iec_program(seed, opt);
  if (opt.classes & kGenTyped) return generate_typed_program(seed, opt);
  return Gen(seed, opt).program(seed);
}

std::string render(const GenProgram& p) {
  std::string s = p.header + "\n";
  for (const auto& it : p.items) {
    if (it.kind == GenItem::Kind::Label) s += (p.il ? ".label " : "label ") + it.text + "\n";
    else s += it.text + "\n";
  }
  if (p.il) s += ".end\n";
  return s + p.footer;
}

std::string generate_ld(uint64_t seed, const GenOptions& opt) { return render(generate_program(seed, opt)); }

std::string generate_trace(uint64_t seed, int scans, const GenOptions& o) {
  if (o.classes & kGenTPou) return generate_iec_trace(seed, scans, o);
  if (o.classes & kGenTyped) return generate_typed_trace(seed, scans, o);
  Rng r(seed * 0x9E3779B97F4A7C15ull + 0x7472616365ull);
  std::vector<std::string> head;
  for (int i = 0; i < o.x; i++) head.push_back("X" + std::to_string(i));
  for (int i = 0; i < o.wx; i++) head.push_back("WX" + std::to_string(i));
  for (int i = 0; i < o.d; i++) head.push_back("D" + std::to_string(i));
  for (int i = 0; i < o.f; i++) head.push_back("F" + std::to_string(i));
  head.push_back("dt");
  std::string s = "# ldgen trace --seed " + std::to_string(seed) + " --scans " + std::to_string(scans) + "\n";
  for (size_t i = 0; i < head.size(); i++) s += (i ? "," : "") + head[i];
  s += "\n";
  std::vector<int> x(size_t(o.x), 0);
  for (int k = 0; k < scans; k++) {
    std::vector<std::string> row;
    for (int i = 0; i < o.x; i++) {
      if (k > 0 && r.pct(12)) { row.push_back(""); continue; }  // keeps its value
      if (k == 0 ? r.pct(30) : r.pct(20)) x[size_t(i)] ^= 1;
      row.push_back(std::to_string(x[size_t(i)]));
    }
    for (int i = 0; i < o.wx; i++) row.push_back(r.pct(k == 0 ? 80 : 25) ? wx_cell(r) : "");
    for (int i = 0; i < o.d; i++) row.push_back(r.pct(k == 0 ? 70 : 3) ? wx_cell(r) : "");
    for (int i = 0; i < o.f; i++) row.push_back(r.pct(k == 0 ? 70 : 3) ? real_cell(r) : "");
    row.push_back(r.pct(85) ? std::to_string(r.pct(12) ? 0 : r.range(1, 60)) : "");
    for (size_t i = 0; i < row.size(); i++) s += (i ? "," : "") + row[i];
    s += "\n";
  }
  return s;
}

namespace {
const std::pair<const char*, uint32_t> kClassNames[] = {
    {"contacts", kGenContacts}, {"edges", kGenEdges},   {"compares", kGenCompares}, {"coils", kGenCoils},
    {"setreset", kGenSetReset}, {"timers", kGenTimers}, {"counters", kGenCounters}, {"move", kGenMove},
    {"arith", kGenArith},       {"logic", kGenLogic},   {"realfn", kGenRealFn},     {"jumps", kGenJumps},
    {"end", kGenEnd},           {"all", kGenAll},       {"tarith", kGenTArith},     {"tcompare", kGenTCompare},
    {"tconv", kGenTConv},       {"tbits", kGenTBits},   {"tarray", kGenTArray},     {"t64", kGenT64},  {"tstring", kGenTString},
    {"typed", kGenTyped},       {"tpou", kGenTPou}};
}  // namespace

std::string gen_classes_text(uint32_t mask) {
  std::string s = (mask & kGenAll) == kGenAll ? "all" : "";
  if ((mask & kGenTyped) == kGenTyped) s += (s.empty() ? "" : ",") + std::string("typed");
  for (const auto& [n, m] : kClassNames) {
    if (m == kGenAll || m == kGenTyped || (m & kGenAll && (mask & kGenAll) == kGenAll) ||
        (m & kGenTyped && (mask & kGenTyped) == kGenTyped))
      continue;
    if (mask & m) s += (s.empty() ? "" : ",") + std::string(n);
  }
  return s;
}

std::string ldgen_args(uint64_t seed, const GenOptions& o) {
  std::string s = "--seed " + std::to_string(seed) + " --rungs " + std::to_string(o.rungs) + " --depth " +
                  std::to_string(o.max_depth);
  if (o.classes != kGenAll) s += " --classes " + gen_classes_text(o.classes);
  GenOptions d;
  const std::pair<const char*, int> r[] = {{"x", o.x}, {"y", o.y}, {"m", o.m},   {"k", o.k},   {"d", o.d},
                                           {"f", o.f}, {"t", o.t}, {"c", o.c},   {"wx", o.wx}, {"wy", o.wy}};
  const int def[] = {d.x, d.y, d.m, d.k, d.d, d.f, d.t, d.c, d.wx, d.wy};
  std::string range;
  for (size_t i = 0; i < 10; i++)
    if (r[i].second != def[i]) range += (range.empty() ? "" : ",") + std::string(r[i].first) + "=" + std::to_string(r[i].second);
  if (!range.empty()) s += " --range " + range;
  return s;
}

bool parse_gen_classes(std::string_view list, uint32_t& mask, std::string& err) {
  const auto& names = kClassNames;
  mask = 0;
  size_t s = 0;
  while (s <= list.size()) {
    size_t e = list.find(',', s);
    std::string_view w = list.substr(s, e == std::string_view::npos ? std::string_view::npos : e - s);
    if (!w.empty()) {
      bool found = false;
      for (const auto& [n, m] : names)
        if (w == n) { mask |= m; found = true; }
      if (!found) {
        err = "unknown element class '" + std::string(w) +
              "' (contacts edges compares coils setreset timers counters move arith logic realfn jumps end all;"
              " typed: tarith tcompare tconv tbits tarray t64 tstring typed; tpou)";
        return false;
      }
    }
    if (e == std::string_view::npos) break;
    s = e + 1;
  }
  return true;
}

}  // namespace ldc

// ------------------------------------------------------------------ the ldgen command
#ifdef LDC_LDGEN_MAIN
#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace {

const char kUsage[] =
    "usage: ldgen [--seed N] [--rungs N] [--depth 0..6] [--classes LIST] [--without LIST]\n"
    "             [--range x=8,y=8,m=8,k=4,d=8,f=4,t=4,c=4,wx=4,wy=2]\n"
    "             [-o prog.ld] [--trace t.csv] [--scans N]\n"
    "  LIST: contacts edges compares coils setreset timers counters move arith logic realfn jumps end all\n"
    "        typed classes (an ldc IL program): tarith tcompare tconv tbits tarray t64 tstring typed\n"
    "        tpou (an IEC IL program with FBs, FUNCTIONs, arrays, structures; with t64 the 64-bit types)\n"
    "       ldgen --st [--seed N] [-o prog.st]   a Structured Text program: loops, arrays, calls (no inputs)\n"
    "  Without -o the program goes to stdout.  The same seed and options give the same files.\n";

bool write(const std::string& path, const std::string& data) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::fprintf(stderr, "ldgen: error: cannot write %s: %s\n", path.c_str(), std::strerror(errno));
    return false;
  }
  bool ok = std::fwrite(data.data(), 1, data.size(), f) == data.size();
  ok &= std::fclose(f) == 0;
  if (!ok) std::fprintf(stderr, "ldgen: error: cannot write %s\n", path.c_str());
  return ok;
}

bool number(const std::string& s, long long lo, long long hi, long long& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  v = std::strtoll(s.c_str(), &end, 10);
  return !*end && !errno && v >= lo && v <= hi;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ldc;
  GenOptions opt;
  uint64_t seed = 1;
  long long scans = 40;
  std::string out, trace;
  bool st = false;
  auto fail = [](const std::string& m) {
    std::fprintf(stderr, "ldgen: error: %s\n%s", m.c_str(), kUsage);
    return 1;
  };
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i], v;
    size_t eq = a.find('=');
    bool has_value = a.rfind("--", 0) == 0 && eq != std::string::npos;
    std::string name = has_value ? a.substr(0, eq) : a;
    auto value = [&]() -> bool {
      if (has_value) { v = a.substr(eq + 1); return true; }
      if (i + 1 >= argc) return false;
      v = argv[++i];
      return true;
    };
    long long n = 0;
    std::string err;
    if (name == "-h" || name == "--help") { std::fputs(kUsage, stdout); return 0; }
    if (name == "--version") return print_version("ldgen");
    if (name == "--st") {
      st = true;
      continue;
    }
    if (name != "--seed" && name != "--rungs" && name != "--depth" && name != "--classes" && name != "--without" &&
        name != "--range" && name != "-o" && name != "--trace" && name != "--scans")
      return fail("unknown option '" + a + "'");
    if (!value()) return fail(name + " needs a value");
    if (name == "--seed") {
      char* end = nullptr;
      errno = 0;
      unsigned long long s = std::strtoull(v.c_str(), &end, 0);
      if (v.empty() || *end || errno || v[0] == '-') return fail("bad --seed '" + v + "'");
      seed = s;
    } else if (name == "--rungs") {
      if (!number(v, 1, 1000000, n)) return fail("bad --rungs '" + v + "' (1..1000000)");
      opt.rungs = int(n);
    } else if (name == "--depth") {
      if (!number(v, 0, 6, n)) return fail("bad --depth '" + v + "' (0..6)");
      opt.max_depth = int(n);
    } else if (name == "--classes" || name == "--without") {
      uint32_t m = 0;
      if (!parse_gen_classes(v, m, err)) return fail(err);
      opt.classes = name == "--classes" ? m : opt.classes & ~m;
    } else if (name == "--range") {
      size_t s = 0;
      while (s <= v.size()) {
        size_t e = v.find(',', s);
        std::string item = v.substr(s, e == std::string::npos ? std::string::npos : e - s);
        size_t q = item.find('=');
        std::string key = item.substr(0, q);
        int* field = key == "x" ? &opt.x : key == "y" ? &opt.y : key == "m" ? &opt.m : key == "k" ? &opt.k
                   : key == "d" ? &opt.d : key == "f" ? &opt.f : key == "t" ? &opt.t : key == "c" ? &opt.c
                   : key == "wx" ? &opt.wx : key == "wy" ? &opt.wy : nullptr;
        if (!field || q == std::string::npos || !number(item.substr(q + 1), 0, 8192, n))
          return fail("bad --range item '" + item + "' (e.g. x=8,d=4)");
        *field = int(n);
        if (e == std::string::npos) break;
        s = e + 1;
      }
    } else if (name == "-o") {
      out = v;
    } else if (name == "--trace") {
      trace = v;
    } else if (name == "--scans") {
      if (!number(v, 0, 10000000, scans)) return fail("bad --scans '" + v + "'");
    }
  }
  if (std::string why = check_options(opt); !why.empty()) return fail(why);
  if (st && !trace.empty()) return fail("--st programs have no inputs: no --trace");
  std::string prog = st ? generate_st(seed) : generate_ld(seed, opt);
  if (out.empty() || out == "-") std::fwrite(prog.data(), 1, prog.size(), stdout);
  else if (!write(out, prog)) return 1;
  if (!trace.empty() && !write(trace, generate_trace(seed, int(scans), opt))) return 1;
  return 0;
}
#endif
