// bench/ldgen_iec.cpp -- typed IEC IL programs with the project's own POUs,
// arrays and structures for the differential test (ldgen's class `tpou`,
// docs/testing.md "Typed programs with POUs").
//
// The program is IEC 61131-3 IL text read by the typed reader
// (frontend/iecil/typed.cpp) into the typed program model: two structure
// types (one nested in the other, with an array member and members of the
// program's types), two FUNCTIONs, a FUNCTION_BLOCK with an array indexed by
// its input (so an index fault can stand inside a POU), one holding a nested
// instance and an array of instances, one with a VAR_IN_OUT and a
// VAR_EXTERNAL, and a PROGRAM that declares instances, arrays of instances,
// arrays of structures, a two-dimensional array and scalars of every type it
// draws.  Each body item is a few IL lines that stand alone (they start with
// LD or CAL), so a minimizer may drop any of them.  Indices come from the
// trace (WX0..WX5): inside their dimension's bounds 97 % of the time.
// Without `t64` no 64-bit type is drawn (TIME is 64-bit: a 32-bit machine).
#include <algorithm>
#include <iterator>
#include <string>
#include <vector>

#include "bench/ldgen.h"
#include "bench/rng.h"
#include "ir/ir.h"

namespace ldc {
namespace {

constexpr int kBitIn = 8;    // b0..b7 AT %IX0.0..%IX0.7 (X0..X7)
constexpr int kIdx = 3;      // k0..k2 AT %IW0 %IW2 %IW4: the indices of dimensions 0..2
constexpr int kWordIn = 6;   // w0..w5 AT %IW8 %IW10 ...: inputs of the program's types
constexpr int kWordAt = 8;   // the first WX of the word inputs

struct Dim {
  int lo, hi;
};

// A place a statement may read (and maybe write), of elementary type t.
struct Slot {
  std::string text;
  Ty t;
  bool writable;
};

bool is_int(Ty t) { return ty_info(t).kind == TyKind::Signed || ty_info(t).kind == TyKind::Unsigned; }
std::string tyname(Ty t) { return ty_info(t).name; }

class IecGen {
 public:
  IecGen(uint64_t seed, const GenOptions& o) : r_(seed * 0x2545F4914F6CDD1Dull + 0x6965632dull), o_(o) {
    wide_ = o.classes & kGenT64;
    for (int i = 1; i < kTyCount; i++)  // BOOL is always there; the palette is of the others
      if (Ty(i) != Ty::STRING && (wide_ || ty_info(Ty(i)).bits < 64)) all_.push_back(Ty(i));  // STRING: not on native code
    for (Ty t : all_)
      if (is_int(t)) ints_.push_back(t);
    // the palette: five types, shuffled from all; the FBs and FUNCTIONs work on its first ones
    std::vector<Ty> pool = all_;
    for (int i = 0; i < 5 && !pool.empty(); i++) {
      size_t k = size_t(r_.below(int(pool.size())));
      pal_.push_back(pool[k]);
      pool.erase(pool.begin() + long(k));
    }
    for (int j = 0; j < kIdx; j++) {
      int lo = r_.range(-2, 1);
      dims_.push_back({lo, lo + r_.range(1, 4)});
      kty_.push_back(ints_[size_t(r_.below(int(ints_.size())))]);
    }
    // an unsigned index type cannot hold a negative bound's index: such a dimension starts at 0
    for (int j = 0; j < kIdx; j++)
      if (ty_info(kty_[size_t(j)]).kind == TyKind::Unsigned && dims_[size_t(j)].lo < 0) {
        dims_[size_t(j)].hi -= dims_[size_t(j)].lo;
        dims_[size_t(j)].lo = 0;
      }
    // word inputs of the palette's types (a REAL is not located in WX: all_'s first type instead)
    for (int j = 0; j < kWordIn; j++) {
      Ty t = pal_[size_t(r_.below(int(pal_.size())))];
      win_.push_back(t == Ty::REAL ? all_[0] : t);
    }
  }

  const std::vector<Dim>& dims() const { return dims_; }
  const std::vector<Ty>& index_types() const { return kty_; }
  const std::vector<Ty>& word_inputs() const { return win_; }

  GenProgram program(uint64_t seed) {
    GenProgram p;
    p.iec = true;
    p.header = "(* IEC IL: a typed program with POUs by ldgen " + ldgen_args(seed, o_) + " *)\n";
    p.header += types() + functions() + block_a() + block_b() + block_c() + program_head();
    program_slots();
    for (int k = 0; k < o_.rungs; k++) {
      GenItem it;
      it.number = k;
      code_ = "  (* item " + std::to_string(k) + " *)\n";
      statement(true);
      it.text = code_;
      p.items.push_back(std::move(it));
    }
    p.footer = "END_PROGRAM\n";
    return p;
  }

 private:
  Rng r_;
  GenOptions o_;
  bool wide_;
  std::vector<Ty> all_, ints_, pal_, kty_, win_;
  std::vector<Dim> dims_;
  std::vector<Slot> slots_;  // what the body being drawn reads and writes
  std::string code_;

  Ty pal(int i) const { return pal_[size_t(i) % pal_.size()]; }
  void line(const std::string& s) { code_ += "  " + s + "\n"; }
  std::string dim(int j) const {
    return std::to_string(dims_[size_t(j)].lo) + ".." + std::to_string(dims_[size_t(j)].hi);
  }
  std::string cidx(int j) { return std::to_string(r_.range(dims_[size_t(j)].lo, dims_[size_t(j)].hi)); }
  // An index of dimension j: a constant inside it, or the index input (from the trace).
  std::string idx(int j) { return r_.pct(35) ? cidx(j) : "k" + std::to_string(j); }

  // ---- literals (IEC spelling, MatIEC's meaning)
  std::string lit(Ty t) {
    const TyInfo& ti = ty_info(t);
    std::string n = tyname(t) + "#";
    switch (ti.kind) {
      case TyKind::Bool: return r_.pct(50) ? "TRUE" : "FALSE";
      case TyKind::Real: {
        static const char* const k[] = {"0.0", "1.5", "-2.25", "0.1", "100.0", "0.5", "-0.5", "7.0", "65536.0",
                                        "2147483648.0", "3.4E38", "-3.4E38", "1.0E-40", "1.0E19", "-1.0E10"};
        static const char* const kl[] = {"1.0E300", "-1.0E-300", "4503599627370497.0", "9.3E18", "1.0E-9"};
        return n + (ti.bits == 64 && r_.pct(30) ? r_.of(kl) : r_.of(k));
      }
      case TyKind::Time: {
        static const char* const k[] = {"0ms", "5ms", "-2ms", "3.5ms", "1h2m3.5s", "5d14h12m18s3.5ms", "250ms", "-7s", "10m"};
        return n + r_.of(k);
      }
      case TyKind::Date: {
        static const char* const d[] = {"1970-01-01", "2024-01-31", "2000-02-29", "1999-12-31"};
        static const char* const tod[] = {"00:00:00", "12:30:00.5", "23:59:59.999", "06:00:01"};
        static const char* const dt[] = {"1970-01-01-00:00:00", "2024-01-31-12:30:00", "2000-02-29-23:59:59.5"};
        return n + (t == Ty::DATE ? r_.of(d) : t == Ty::TOD ? r_.of(tod) : r_.of(dt));
      }
      default: break;
    }
    const uint64_t mask = ti.bits == 64 ? ~0ull : (1ull << ti.bits) - 1;
    uint64_t v;
    switch (r_.pick({3, 3, 4, 3})) {
      case 0: v = ti.kind == TyKind::Signed ? mask >> 1 : mask; break;  // the largest
      case 1: v = ti.kind == TyKind::Signed ? (mask >> 1) + 1 : 0; break;  // the smallest
      case 2: v = uint64_t(int64_t(r_.range(-7, 7))) & mask; break;
      default: v = r_.next() >> r_.below(64) & mask; break;
    }
    if (ti.kind == TyKind::Bits) {
      static const char kHex[] = "0123456789ABCDEF";
      std::string h;
      do h.insert(h.begin(), kHex[v & 15]), v >>= 4; while (v);
      return n + "16#" + h;
    }
    if (ti.kind == TyKind::Signed && (v >> (ti.bits - 1) & 1)) return n + std::to_string(int64_t(v | ~mask));
    return n + std::to_string(v);
  }

  // ---- the places of the body being drawn
  std::vector<const Slot*> of(Ty t, bool write) const {
    std::vector<const Slot*> v;
    for (const Slot& s : slots_)
      if (s.t == t && (s.writable || !write)) v.push_back(&s);
    return v;
  }
  bool has(Ty t, bool write) const { return !of(t, write).empty(); }
  std::string pick(Ty t, bool write) {
    auto v = of(t, write);
    return v[size_t(r_.below(int(v.size())))]->text;
  }
  std::string src(Ty t) { return r_.pct(22) || !has(t, false) ? lit(t) : pick(t, false); }
  // A place of a type: the variable indices drawn afresh at each use.
  void add(const std::string& text, Ty t, bool w) { slots_.push_back({text, t, w}); }

  // ---- declarations
  std::string types() {
    std::string s = "TYPE\n  S0 : STRUCT\n";
    for (int i = 0; i < 4; i++) s += "    m" + std::to_string(i) + " : " + tyname(pal(i)) + (r_.pct(30) ? " := " + lit(pal(i)) : "") + ";\n";
    s += "    flag : BOOL;\n  END_STRUCT;\n  S1 : STRUCT\n    inner : S0;\n";
    s += "    arr : ARRAY[" + dim(1) + "] OF " + tyname(pal(2)) + ";\n";
    s += "    n : " + tyname(pal(3)) + ";\n    fa : FA;\n  END_STRUCT;\nEND_TYPE\n";
    return s;
  }
  // FUNCTION Fk : T (x, y) -- two operations with a local that starts from its initial value at each call
  std::string functions() {
    std::string s;
    for (int k = 0; k < 2; k++) {
      Ty t = pal(k);
      s += "FUNCTION F" + std::to_string(k) + " : " + tyname(t) + "\nVAR_INPUT\n  x : " + tyname(t) + ";\n  y : " + tyname(t) +
           ";\nEND_VAR\nVAR\n  t : " + tyname(t) + " := " + lit(t) + ";\nEND_VAR\n";
      slots_ = {{"x", t, false}, {"y", t, false}, {"t", t, true}};
      code_.clear();
      arith(t, "t");
      arith(t, "F" + std::to_string(k));
      s += code_ + "END_FUNCTION\n";
    }
    return s;
  }
  // FA: an accumulator with an array indexed by its input i (a fault inside a POU)
  std::string block_a() {
    Ty t = pal(0);
    std::string T = tyname(t);
    std::string s = "FUNCTION_BLOCK FA\nVAR_INPUT\n  in : " + T + ";\n  i : " + tyname(kty_[0]) +
                    ";\n  go : BOOL;\nEND_VAR\nVAR_OUTPUT\n  out : " + T + ";\n  q : BOOL;\nEND_VAR\nVAR\n  acc : " + T +
                    (r_.pct(50) ? " := " + lit(t) : "") + ";\n  hist : ARRAY[" + dim(0) + "] OF " + T + ";\nEND_VAR\n";
    slots_ = {{"in", t, false}, {"acc", t, true}, {"out", t, true}, {"go", Ty::BOOL, false}, {"q", Ty::BOOL, true}};
    code_.clear();
    arith(t, "acc");
    line("LD acc");
    line("ST hist[i]");
    if (r_.pct(50)) {
      line("LD go");
      line("RETCN");  // leaves before the rest unless go
    }
    add("hist[" + cidx(0) + "]", t, true);
    add("hist[i]", t, true);
    for (int n = r_.range(1, 3); n-- > 0;) statement(false);
    arith(t, "out");
    logic("q");
    return s + code_ + "END_FUNCTION_BLOCK\n";
  }
  // FB: a nested instance and an array of instances
  std::string block_b() {
    Ty t = pal(0);
    std::string T = tyname(t), s = "FUNCTION_BLOCK FB\nVAR_INPUT\n  in : " + T + ";\n  i : " + tyname(kty_[0]) +
                                   ";\nEND_VAR\nVAR_OUTPUT\n  out : " + T + ";\nEND_VAR\nVAR\n  a : FA;\n  subs : ARRAY[0..1] OF FA;\nEND_VAR\n";
    code_.clear();
    line("CAL a(in := in, i := i, go := " + std::string(r_.pct(70) ? "TRUE" : "a.q") + ")");
    int sub = r_.below(2);
    line("CAL subs[" + std::to_string(sub) + "](in := a.out, i := i, go := " + (r_.pct(50) ? "a.q" : "TRUE") + ")");
    if (r_.pct(50)) line("CAL subs[" + std::to_string(1 - sub) + "](in := subs[" + std::to_string(sub) + "].out, i := i)");
    line("LD subs[" + std::to_string(sub) + "].out");
    line(std::string(op_takes(Op::TADD, t, Ty::None) ? "ADD" : op_takes(Op::TXOR, t, Ty::None) ? "XOR" : "MAX") + " a.out");
    line("ST out");
    return s + code_ + "END_FUNCTION_BLOCK\n";
  }
  // FC: a VAR_IN_OUT and a VAR_EXTERNAL (the program's VAR_GLOBAL g)
  std::string block_c() {
    Ty t = pal(1);
    std::string T = tyname(t);
    std::string s = "FUNCTION_BLOCK FC\nVAR_IN_OUT\n  p : " + T + ";\nEND_VAR\nVAR_EXTERNAL\n  g : " + T +
                    ";\nEND_VAR\nVAR_TEMP\n  tmp : " + T + " := " + lit(t) + ";\nEND_VAR\n";
    slots_ = {{"p", t, true}, {"g", t, true}, {"tmp", t, true}};
    code_.clear();
    arith(t, "tmp");
    arith(t, "p");
    arith(t, "g");
    return s + code_ + "END_FUNCTION_BLOCK\n";
  }
  std::string program_head() {
    std::string s = "PROGRAM main\nVAR_GLOBAL\n  g : " + tyname(pal(1)) + ";\nEND_VAR\nVAR\n";
    for (int i = 0; i < kBitIn; i++) s += "  b" + std::to_string(i) + " AT %IX0." + std::to_string(i) + " : BOOL;\n";
    for (int j = 0; j < kIdx; j++) s += "  k" + std::to_string(j) + " AT %IW" + std::to_string(2 * j) + " : " + tyname(kty_[size_t(j)]) + ";\n";
    for (int j = 0; j < kWordIn; j++)
      s += "  w" + std::to_string(j) + " AT %IW" + std::to_string(kWordAt + 2 * j) + " : " + tyname(win_[size_t(j)]) + ";\n";
    for (size_t i = 0; i < pal_.size(); i++)
      s += "  v" + std::to_string(i) + ", u" + std::to_string(i) + " : " + tyname(pal_[i]) + (r_.pct(40) ? " := " + lit(pal_[i]) : "") + ";\n";
    s += "  x0, x1, x2 : BOOL;\n  s, s2 : S1;\n  sa : ARRAY[" + dim(2) + "] OF S0;\n";
    s += "  grid : ARRAY[" + dim(0) + ", " + dim(2) + "] OF " + tyname(pal(4)) + ";\n";
    s += "  fa : FA;\n  fb : FB;\n  fbs : ARRAY[1..2] OF FB;\n  fc : FC;\nEND_VAR\n";
    return s;
  }
  void program_slots() {
    slots_.clear();
    for (int i = 0; i < kBitIn; i++) add("b" + std::to_string(i), Ty::BOOL, false);
    for (int j = 0; j < kIdx; j++) add("k" + std::to_string(j), kty_[size_t(j)], false);
    for (int j = 0; j < kWordIn; j++) add("w" + std::to_string(j), win_[size_t(j)], false);
    for (size_t i = 0; i < pal_.size(); i++) {
      add("v" + std::to_string(i), pal_[i], true);
      add("u" + std::to_string(i), pal_[i], true);
    }
    for (int i = 0; i < 3; i++) add("x" + std::to_string(i), Ty::BOOL, true);
    add("g", pal(1), true);
    for (const char* st : {"s", "s2"}) {
      std::string b = st;
      for (int i = 0; i < 4; i++) add(b + ".inner.m" + std::to_string(i), pal(i), true);
      add(b + ".inner.flag", Ty::BOOL, true);
      add(b + ".arr[@1]", pal(2), true);
      add(b + ".n", pal(3), true);
      add(b + ".fa.out", pal(0), false);
    }
    for (int i = 0; i < 4; i++) add("sa[@2].m" + std::to_string(i), pal(i), true);
    add("sa[@2].flag", Ty::BOOL, true);
    add("grid[@0, @2]", pal(4), true);
    add("fa.out", pal(0), false);
    add("fa.q", Ty::BOOL, false);
    add("fb.out", pal(0), false);
    add("fbs[1].out", pal(0), false);
    add("fbs[2].a.out", pal(0), false);
    add("fbs[2].subs[1].q", Ty::BOOL, false);
  }
  // "@j" in a slot's text: an index of dimension j, drawn at each use
  std::string fill(std::string s) {
    for (size_t at; (at = s.find('@')) != std::string::npos;) s.replace(at, 2, idx(s[at + 1] - '0'));
    return s;
  }

  // ---- statements
  // dst := src OP src ... (one to three operations of t, maybe none)
  void arith(Ty t, const std::string& dst) {
    static const Op kOps[] = {Op::TADD, Op::TSUB, Op::TMUL, Op::TDIV, Op::TMOD, Op::TAND, Op::TOR, Op::TXOR, Op::TADD, Op::TMUL};
    line("LD " + fill(src(t)));
    for (int n = r_.range(0, 3); n-- > 0;) {
      Op op = kOps[r_.below(int(std::size(kOps)))];
      if (!op_takes(op, t, Ty::None)) continue;
      line(std::string(op_info(op).name + 1) + " " + fill(src(t)));
    }
    if (r_.pct(15) && op_takes(Op::TMAX, t, Ty::None)) line(std::string(r_.pct(50) ? "MAX " : "MIN ") + fill(src(t)));
    if (r_.pct(15) && op_takes(Op::TNEG, t, Ty::None)) line(r_.pct(50) ? "NEG" : "ABS");
    if (wide_ && r_.pct(15) && ty_info(t).kind == TyKind::Real) {
      static const char* const kFns[] = {"SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN"};
      line(r_.of(kFns));
    }
    line("ST " + fill(dst));
  }
  void logic(const std::string& dst) {
    static const char* const kOps[] = {"AND", "ANDN", "OR", "ORN", "XOR", "XORN"};
    line(std::string(r_.pct(70) ? "LD " : "LDN ") + fill(pick(Ty::BOOL, false)));
    for (int n = r_.range(0, 3); n-- > 0;) line(std::string(r_.of(kOps)) + " " + fill(pick(Ty::BOOL, false)));
    if (r_.pct(25)) {
      line(std::string(r_.pct(50) ? "AND( " : "OR( ") + fill(pick(Ty::BOOL, false)));
      line(std::string(r_.of(kOps)) + " " + fill(pick(Ty::BOOL, false)));
      line(")");
    }
    static const char* const kSt[] = {"ST ", "STN ", "S ", "R "};
    line(std::string(r_.of(kSt)) + fill(dst));
  }
  Ty any() { return r_.pct(85) ? pal_[size_t(r_.below(int(pal_.size())))] : all_[size_t(r_.below(int(all_.size())))]; }
  void statement(bool program) {
    switch (r_.pick({6, 3, 3, 2, 2, program ? 5 : 0, program ? 2 : 0, program ? 2 : 0})) {
      case 0: {  // arithmetic
        Ty t = any();
        if (!has(t, true)) t = pal(0);
        return arith(t, pick(t, true));
      }
      case 1: {  // a compare into a BOOL, or a jump over a statement
        Ty t = any();
        static const Op kRel[] = {Op::TEQ, Op::TNE, Op::TLT, Op::TLE, Op::TGT, Op::TGE};
        Op op = kRel[r_.below(6)];
        if (!op_takes(op, t, Ty::None)) t = pal(0);
        line("LD " + fill(has(t, false) ? pick(t, false) : lit(t)));
        line(std::string(op_info(op).name + 1) + " " + fill(src(t)));
        if (!program || r_.pct(50)) return line("ST " + fill(pick(Ty::BOOL, true)));
        std::string l = "L" + std::to_string(label_++);
        line(std::string(r_.pct(50) ? "JMPC " : "JMPCN ") + l);
        Ty u = pal(r_.below(5));
        arith(u, pick(u, true));
        code_ += l + ":\n";
        return;
      }
      case 2: return logic(pick(Ty::BOOL, true));
      case 3: {  // a conversion
        Ty a = any(), b = any();
        if (!op_takes(Op::TCONV, b, a) || !has(b, true)) return arith(pal(0), pick(pal(0), true));
        line("LD " + fill(src(a)));
        line(tyname(a) + "_TO_" + tyname(b));
        return line("ST " + fill(pick(b, true)));
      }
      case 4: {  // a shift or rotation of a bit string
        std::vector<Ty> bs;
        for (Ty t : all_)
          if (ty_info(t).kind == TyKind::Bits && has(t, true)) bs.push_back(t);
        if (bs.empty()) return logic(pick(Ty::BOOL, true));
        Ty t = bs[size_t(r_.below(int(bs.size())))];
        static const char* const kSh[] = {"SHL", "SHR", "ROL", "ROR"};
        line("LD " + fill(src(t)));
        Ty n = ints_[size_t(r_.below(int(ints_.size())))];
        static const char* const kCounts[] = {"0", "1", "7", "8", "15", "16", "31", "32", "33", "63", "64", "65"};
        std::string cnt = r_.pct(50) ? r_.of(kCounts) : has(n, false) ? fill(pick(n, false)) : lit(n);
        line(std::string(r_.of(kSh)) + " " + cnt);
        return line("ST " + fill(pick(t, true)));
      }
      case 5: return call();
      case 6: {  // a FUNCTION, with the CR as its first input or formally
        int k = r_.below(2);
        Ty t = pal(k);
        std::string f = "F" + std::to_string(k);
        if (r_.pct(50)) {
          line("LD " + fill(src(t)));
          line(f + " " + fill(src(t)));
        } else {
          line(f + "(x := " + fill(src(t)) + ", y := " + fill(src(t)) + ")");
        }
        return line("ST " + fill(pick(t, true)));
      }
      default: {  // a whole structure
        static const char* const kPairs[][2] = {{"s", "s2"}, {"s2", "s"}, {"sa[@2]", "s.inner"}, {"s2.inner", "sa[@2]"}, {"s.inner", "s2.inner"}};
        const auto& pr = kPairs[r_.below(5)];
        std::string a = fill(pr[0]), b = fill(pr[1]);
        // a structure selected by a variable index is not copied whole (the reader refuses it): constant ones only
        if (a.find("[k") != std::string::npos || b.find("[k") != std::string::npos) return;
        line("LD " + a);
        return line("ST " + b);
      }
    }
  }
  // CAL of an instance: alone, in an array, in a structure; with EN/ENO sometimes
  void call() {
    Ty t = pal(0);
    static const char* const kInst[] = {"fa", "fb", "fbs[1]", "fbs[2]", "s.fa", "s2.fa", "fc"};
    std::string inst = kInst[r_.below(7)];
    std::string args;
    if (inst == "fc") {
      std::string p = pick(pal(1), true);
      args = "p := " + (p.find('@') != std::string::npos ? "v1" : p);  // an in-out names a variable itself
    } else {
      args = "in := " + fill(src(t)) + ", i := " + (r_.pct(80) ? "k0" : r_.pct(80) ? cidx(0) : lit(kty_[0]));  // a literal: mostly outside
      if (inst == "fa" || inst.find(".fa") != std::string::npos) args += ", go := " + fill(pick(Ty::BOOL, false));
    }
    if (r_.pct(25)) args = "EN := " + fill(pick(Ty::BOOL, false)) + ", " + args + ", ENO => x" + std::to_string(r_.below(3));
    if (r_.pct(15)) {
      line("LD " + fill(pick(Ty::BOOL, false)));
      line(std::string(r_.pct(50) ? "CALC " : "CALCN ") + inst + "(" + args + ")");
    } else {
      line("CAL " + inst + "(" + args + ")");
    }
    if (inst != "fc" && r_.pct(60)) {
      line("LD " + inst + ".out");
      line("ST " + fill(pick(t, true)));
    }
  }
  int label_ = 0;
};

// A 32-bit trace cell: small numbers, the limits of the widths, REAL patterns, random words.
std::string trace_word(Rng& r) {
  static const char* const kWords[] = {"0", "1", "-1", "2147483647", "-2147483648", "32767", "32768", "-32768", "65535",
                                       "127", "128", "255", "-128", "0x7fc00000", "0x7f800000", "0x3fc00000", "0x00000001",
                                       "-8388608", "86400000", "1000000"};
  switch (r.pick({4, 5, 3})) {
    case 0: return std::to_string(r.range(-9, 9));
    case 1: return r.of(kWords);
    default: return std::to_string(int32_t(uint32_t(r.next())));
  }
}

}  // namespace

GenProgram generate_iec_program(uint64_t seed, const GenOptions& opt) { return IecGen(seed, opt).program(seed); }

// The trace of generate_iec_program(seed, o): the bit inputs, each index input
// inside its dimension 97 % of the time (else just outside it), the word inputs.
std::string generate_iec_trace(uint64_t seed, int scans, const GenOptions& o) {
  Rng r(seed * 0x9E3779B97F4A7C15ull + 0x69656374ull);
  IecGen g(seed, o);
  std::string s = "# ldgen iec trace --seed " + std::to_string(seed) + " --scans " + std::to_string(scans) + "\n";
  for (int i = 0; i < kBitIn; i++) s += "X" + std::to_string(i) + ",";
  for (int i = 0; i < kWordAt + 2 * kWordIn; i++) s += "WX" + std::to_string(i) + ",";
  s += "dt\n";
  for (int k = 0; k < scans; k++) {
    std::vector<std::string> row;
    for (int i = 0; i < kBitIn; i++) row.push_back(r.pct(30) ? std::to_string(r.below(2)) : "");
    for (int j = 0; j < kIdx; j++) {
      const Dim d = g.dims()[size_t(j)];
      if (k > 0 && !r.pct(40)) {
        row.insert(row.end(), {"", ""});
        continue;
      }
      int v = r.pct(97) ? r.range(d.lo, d.hi) : r.pct(50) ? r.range(d.hi + 1, d.hi + 3) : r.range(d.lo - 3, d.lo - 1);
      row.push_back(std::to_string(v));
      row.push_back(v < 0 ? "-1" : "0");  // the high word of a 64-bit index
    }
    for (int j = kIdx * 2; j < kWordAt; j++) row.push_back("");
    for (int j = 0; j < 2 * kWordIn; j++) row.push_back(k == 0 || r.pct(20) ? trace_word(r) : "");
    row.push_back(std::to_string(r.range(0, 60)));
    for (size_t i = 0; i < row.size(); i++) s += (i ? "," : "") + row[i];
    s += "\n";
  }
  return s;
}

}  // namespace ldc
