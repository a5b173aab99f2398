// bench/ldgen_typed.cpp -- typed programs for the differential test (ldgen's
// typed classes, docs/testing.md "Typed programs").
//
// The ladder grid has no typed elements, so a typed program is ldc IL text:
// each rung a random condition (bits, and typed compares when `tcompare` is
// on) followed by typed actions drawn from the classes asked for -- typed
// arithmetic and the REAL functions, conversions, bit strings and shifts, and
// IDX + LDX/STX over arrays and arrays of structures in D, with indices that
// are mostly inside their bounds and sometimes not (an index fault ends the
// scan, the same on every engine).  `t64` adds the 64-bit types.  Which
// instruction takes which types comes from ops.def (op_takes), so the
// generator follows the IL as it grows.
#include <algorithm>
#include <iterator>
#include <string>
#include <vector>

#include "bench/ldgen.h"
#include "bench/rng.h"
#include "ir/ir.h"
#include "ir/typed.h"

namespace ldc {
namespace {

// Where a typed program's values live.
constexpr int kScalarD = 48;            // D0..D47: scalars of every type (cells shared: a word is read as many types)
// D48..D55: array k's index in D48+2k (two words, for the 64-bit index types),
// written only by the trace: inside the array's bounds in 97 % of the rows
constexpr int kIndexD = 48, kIndexN = 8;
constexpr int kArrayD = 64, kArrayEnd = 192;  // D64..D191: arrays (the trace fills them on its first row)
constexpr int kBoolM = 16, kArrayM = 64;     // M0..M15 bits; M64.. BOOL arrays
constexpr int kStrD = 200, kStrN = 4;        // D200..D331: four STRINGs of 33 cells (tstring)

struct Array {
  Ty t;
  int lo, hi, stride, base;  // base: the element's first cell (or bit) of index lo, member offset included
};

class TypedGen {
 public:
  TypedGen(uint64_t seed, const GenOptions& o) : r_(seed * 0xD1B54A32D192ED03ull + 0x74797065ull), o_(o) {
    uint32_t c = o.classes & kGenTyped;
    wide_ = c & kGenT64;
    c &= ~kGenT64;
    if (!wide_) c &= ~kGenTString;  // (STRING with the 64-bit types: what the C40 lacks)
    cls_ = c ? c : (kGenTyped & ~(kGenT64 | kGenTString));
    for (int i = 0; i < kTyCount; i++)
      // STRING: by the string actions alone (strings()), in its own cells
      if ((wide_ || ty_info(Ty(i)).bits < 64) && Ty(i) != Ty::STRING) types_.push_back(Ty(i));
    make_arrays();
  }

  const std::vector<Array>& arrays() const { return arrays_; }

  GenProgram program(uint64_t seed) {
    GenProgram p;
    p.il = true;
    p.header = "; ldc IL: a typed program by ldgen " + ldgen_args(seed, o_) + "\n";
    for (int k = 0; k < o_.rungs; k++) {
      GenItem it;
      it.number = k;
      it.text = rung(k, it);
      p.items.push_back(std::move(it));
    }
    return p;
  }

 private:
  Rng r_;
  GenOptions o_;
  bool wide_;
  uint32_t cls_;
  std::vector<Ty> types_;
  std::vector<Array> arrays_;
  std::string code_;

  void emit(const std::string& line) { code_ += "    " + line + "\n"; }
  bool on(uint32_t c) const { return cls_ & c; }

  // A type that `op` takes (with source type u, or a U drawn too for typed == 2).
  bool pick_types(Op op, Ty& t, Ty& u) {
    // without t64 (the C40's programs) the REAL functions are left out too:
    // C's double functions rounded to REAL are what the C40 refuses by name
    if (!wide_ && (op == Op::TEXPT || (op >= Op::TSQRT && op <= Op::TATAN))) return false;
    for (int tries = 0; tries < 40; tries++) {
      t = types_[size_t(r_.below(int(types_.size())))];
      u = op_info(op).typed == 2 ? types_[size_t(r_.below(int(types_.size())))] : Ty::None;
      if (op_takes(op, t, u) && !typed::is_string_instr(op, t, u)) return true;
    }
    return false;
  }

  // ---- operands
  std::string bit_src() {
    switch (r_.pick({3, 4, 2})) {
      case 0: return "X" + std::to_string(r_.below(o_.x));
      case 1: return "M" + std::to_string(r_.below(kBoolM));
      default: return "Y" + std::to_string(r_.below(o_.y));
    }
  }
  std::string bit_dst() { return r_.pct(70) ? "M" + std::to_string(r_.below(kBoolM)) : "Y" + std::to_string(r_.below(o_.y)); }
  std::string word(Ty t) {
    int cells = ty_info(t).cells;
    if (r_.pct(8)) return "F" + std::to_string(r_.below(4 - cells + 1));  // REAL's own area holds any type too
    return "D" + std::to_string(r_.below(kScalarD - cells + 1));
  }
  // A constant of t: the limits, small values, the awkward reals.
  std::string constant(Ty t) {
    const TyInfo& ti = ty_info(t);
    if (ti.kind == TyKind::Bool) return r_.pct(50) ? "1" : "0";
    if (ti.kind == TyKind::Real) {
      static const char* const kReals[] = {"0.0", "-0.0", "1.5", "-2.25", "0.1", "1e-45", "3.4e38", "-3.4e38", "100.0",
                                           "0.5", "2.5", "-0.5", "65536.0", "2147483648.0", "1e19", "-1e10", "7.0"};
      static const char* const kLreals[] = {"1e300", "-1e-300", "4503599627370497.0", "9.3e18", "1e-9", "5e-324"};
      if (ti.bits == 64 && r_.pct(30)) return r_.of(kLreals);
      return r_.of(kReals);
    }
    uint64_t v;
    const uint64_t mask = ti.bits == 64 ? ~0ull : (1ull << ti.bits) - 1;
    const bool sg = ti.kind == TyKind::Signed || ti.kind == TyKind::Time || ti.kind == TyKind::Date;
    switch (r_.pick({3, 3, 4, 2, 2})) {
      case 0: v = sg ? mask >> 1 : mask; break;                         // the largest
      case 1: v = sg ? ~(mask >> 1) : 0; break;                          // the smallest
      case 2: v = uint64_t(int64_t(r_.range(-7, 7))); break;             // small
      case 3: v = ti.kind == TyKind::Time || ti.kind == TyKind::Date ? uint64_t(int64_t(r_.range(-3000, 3000)) * 1000000) : r_.next(); break;
      default: v = r_.next() >> r_.below(64); break;
    }
    v &= mask;
    if (sg && ti.bits < 64 && (v >> (ti.bits - 1)) & 1) v |= ~mask;  // sign-extended: the canonical bits
    if (!sg && ti.bits < 64) v &= mask;
    return typed_const_text(t, v);
  }
  std::string src(Ty t) {
    if (r_.pct(25)) return constant(t);
    return t == Ty::BOOL ? bit_src() : word(t);
  }
  std::string dst(Ty t) { return t == Ty::BOOL ? bit_dst() : word(t); }
  static std::string name(Op op, Ty t, Ty u = Ty::None) {
    std::string s = std::string(op_info(op).name + 1) + "." + ty_info(t).name;
    return u == Ty::None ? s : s + "." + ty_info(u).name;
  }

  // ---- conditions: push exactly one value
  void leaf() {
    if (on(kGenTString) && r_.pct(10)) {
      static const Op kRels[] = {Op::TEQ, Op::TNE, Op::TLT, Op::TLE, Op::TGT, Op::TGE};
      return emit(name(kRels[r_.below(6)], Ty::STRING) + " " + str() + " " + str());
    }
    if (on(kGenTCompare) && r_.pct(55)) {
      static const Op kRels[] = {Op::TEQ, Op::TNE, Op::TLT, Op::TLE, Op::TGT, Op::TGE};
      Op op = kRels[r_.below(6)];
      Ty t = Ty::None, u = Ty::None;
      pick_types(op, t, u);
      std::string a = r_.pct(85) ? (t == Ty::BOOL ? bit_src() : word(t)) : constant(t);
      emit(name(op, t) + " " + a + " " + src(t));
      return;
    }
    if (r_.pct(5)) return emit("TRUE");
    emit(std::string(r_.pct(70) ? "LOAD" : "LOADN") + " " + bit_src());
  }
  void condition(int depth) {
    leaf();
    int more = depth > 0 ? r_.range(0, 2) : r_.range(0, 1);
    for (int i = 0; i < more; i++) {
      if (depth > 0 && r_.pct(40)) {
        condition(depth - 1);
        emit(r_.pct(50) ? "ANDBLK" : "ORBLK");
      } else {
        static const char* const kJoin[] = {"AND", "ANDN", "OR", "ORN"};
        emit(std::string(r_.of(kJoin)) + " " + bit_src());
      }
    }
  }

  // ---- actions (run when the top is 1; they leave the stack alone)
  void arith() {
    static const Op kOps[] = {Op::TMOVE, Op::TADD, Op::TSUB, Op::TMUL, Op::TDIV, Op::TMOD, Op::TMIN, Op::TMAX,
                              Op::TNEG,  Op::TABS, Op::TEXPT, Op::TSQRT, Op::TLN, Op::TLOG, Op::TEXP, Op::TSIN,
                              Op::TCOS, Op::TTAN, Op::TASIN, Op::TACOS, Op::TATAN, Op::TADD, Op::TDIV, Op::TMUL};
    Op op = kOps[r_.below(int(std::size(kOps)))];
    Ty t = Ty::None, u = Ty::None;
    if (!pick_types(op, t, u)) return;
    std::string s = name(op, t) + " " + src(t);
    if (op_info(op).nopd == 3) {
      // divisors: zero, -1 and the type's edge values often
      s += " " + ((op == Op::TDIV || op == Op::TMOD) && r_.pct(30) ? (r_.pct(50) ? std::string("0") : ty_info(t).kind == TyKind::Signed ? "-1" : "1") : src(t));
    }
    emit(s + " " + dst(t));
  }
  void conv() {
    Op op = r_.pct(80) ? Op::TCONV : Op::TTRUNC;
    Ty t = Ty::None, u = Ty::None;
    if (!pick_types(op, t, u)) return;
    emit(name(op, t, u) + " " + src(u) + " " + dst(t));
  }
  void bits() {
    static const Op kOps[] = {Op::TAND, Op::TOR, Op::TXOR, Op::TNOT, Op::TSHL, Op::TSHR, Op::TROL, Op::TROR};
    Op op = kOps[r_.below(8)];
    Ty t = Ty::None, u = Ty::None;
    if (!pick_types(op, t, u)) return;
    if (op == Op::TNOT) return emit(name(op, t) + " " + src(t) + " " + dst(t));
    if (u == Ty::None) return emit(name(op, t) + " " + src(t) + " " + src(t) + " " + dst(t));
    std::string n;
    if (r_.pct(60)) {  // counts at and beyond the limits, negative ones where U has them
      const int w = ty_info(t).bits;
      const int counts[] = {0, 1, w - 1, w, w + 1, 31, 32, 33, 63, 64, 65, 100, -1, -w, 255};
      for (int tries = 0; tries < 10 && n.empty(); tries++) {
        int c = counts[r_.below(int(std::size(counts)))];
        std::string why;
        if (parse_typed_const(u, std::to_string(c), why)) n = std::to_string(c);
      }
    }
    if (n.empty()) n = src(u);
    emit(name(op, t, u) + " " + src(t) + " " + n + " " + dst(t));
  }
  void make_arrays() {
    int d = kArrayD, m = kArrayM;
    for (int k = 0; k < 4; k++) {
      Array a;
      a.t = types_[size_t(r_.below(int(types_.size())))];
      a.lo = r_.range(-2, 1);
      a.hi = a.lo + r_.range(1, 7);
      const int cells = std::max(ty_info(a.t).cells, 1);
      a.stride = cells + (r_.pct(40) ? r_.range(1, 2) : 0);  // an array of structures: the element is one member
      const int member = r_.below(a.stride - cells + 1);
      const int span = (a.hi - a.lo + 1) * a.stride;
      if (a.t == Ty::BOOL) {
        a.base = m + member;
        m += span;
      } else {
        if (d + span > kArrayEnd) continue;
        a.base = d + member;
        d += span;
      }
      arrays_.push_back(a);
    }
  }
  void array() {
    if (arrays_.empty()) return;
    const size_t k = size_t(r_.below(int(arrays_.size())));
    const Array& a = arrays_[k];
    Ty it;
    for (;;) {  // an index type that holds the bounds (an unsigned one reads -1 as its largest value: a fault)
      it = types_[size_t(r_.below(int(types_.size())))];
      TyKind kind = ty_info(it).kind;
      if (op_takes(Op::TIDX, it, Ty::None) && (a.lo >= 0 || kind == TyKind::Signed || r_.pct(5))) break;
    }
    // the index: the array's own index word, rarely any word (then mostly a fault)
    std::string idx = r_.pct(97) ? "D" + std::to_string(kIndexD + 2 * int(k)) : word(it);
    emit(name(Op::TIDX, it) + " " + idx + " " + std::to_string(a.lo) + " " + std::to_string(a.hi));
    std::string base = (a.t == Ty::BOOL ? "M" : "D") + std::to_string(a.base), stride = std::to_string(a.stride);
    if (r_.pct(50)) emit(name(Op::TLDX, a.t) + " " + base + " " + stride + " " + dst(a.t));
    else emit(name(Op::TSTX, a.t) + " " + src(a.t) + " " + base + " " + stride);
  }
  // ---- strings: four in their own cells, sometimes one over the scalars
  // (whose words make untrusted length cells); filled by literals moved into
  // their cells and by conversions of the scalars
  std::string str() {
    if (r_.pct(10)) return "D" + std::to_string(r_.below(16));
    return "D" + std::to_string(kStrD + 33 * r_.below(kStrN));
  }
  // A type other than STRING for U (an integer type where `op` needs one).
  Ty other(Op op, bool t_is_string) {
    for (int tries = 0; tries < 40; tries++) {
      Ty u = types_[size_t(r_.below(int(types_.size())))];
      if (t_is_string ? op_takes(op, Ty::STRING, u) : op_takes(op, u, Ty::STRING)) return u;
    }
    return Ty::DINT;
  }
  std::string num(Ty u) {  // a length or position: around the edges of 0..126 often
    static const int kNums[] = {-1, 0, 1, 2, 3, 5, 126, 127, 200, 255, 256};
    std::string why;
    if (r_.pct(60))
      if (std::string v = std::to_string(kNums[r_.below(int(std::size(kNums)))]); parse_typed_const(u, v, why)) return v;
    return src(u);
  }
  void literal() {  // a short text of digits, signs, '.', '#', letters and blanks into a string's cells
    static const char kChars[] = "0123456789-+.# TtRrUuEeSsHhMmDdxa16";
    std::string s;
    for (int n = r_.range(0, 9); n > 0; n--) s += kChars[r_.below(int(sizeof kChars - 1))];
    std::string d = str();
    const int base = std::stoi(d.substr(1));
    emit("MOVE.DINT " + std::to_string(s.size()) + " " + d);
    for (size_t i = 0; i < s.size(); i += 4) {
      uint32_t w = 0;
      for (size_t j = 0; j < 4 && i + j < s.size(); j++) w |= uint32_t(uint8_t(s[i + j])) << (8 * j);
      emit("MOVE.DWORD " + std::to_string(w) + " D" + std::to_string(base + 1 + int(i / 4)));
    }
  }
  void strings() {
    switch (r_.below(10)) {
      case 0: return literal();
      case 1: return emit(name(Op::TMOVE, Ty::STRING) + " " + str() + " " + str());
      case 2: {
        Ty u = other(Op::TCONV, true);
        return emit(name(Op::TCONV, Ty::STRING, u) + " " + src(u) + " " + str());
      }
      case 3: {
        Ty t = other(Op::TCONV, false);
        return emit(name(Op::TCONV, t, Ty::STRING) + " " + str() + " " + dst(t));
      }
      case 4: {
        Ty u = other(Op::TLEN, false);
        return emit(name(Op::TLEN, u, Ty::STRING) + " " + str() + " " + dst(u));
      }
      case 5: {
        Op op = r_.pct(50) ? Op::TLEFT : Op::TRIGHT;
        Ty u = other(op, true);
        return emit(name(op, Ty::STRING, u) + " " + str() + " " + num(u) + " " + str());
      }
      case 6: return emit(name(Op::TCONCAT, Ty::STRING) + " " + str() + " " + str() + " " + str());
      case 7: {
        Ty u = other(Op::TFIND, false);
        return emit(name(Op::TFIND, u, Ty::STRING) + " " + str() + " " + str() + " " + dst(u));
      }
      default: {  // ARGS, then the function that reads it
        Ty u = Ty::DINT;
        for (int tries = 0; tries < 40 && !op_takes(Op::TARGS, u, Ty::None); tries++) u = types_[size_t(r_.below(int(types_.size())))];
        emit(name(Op::TARGS, u) + " " + num(u) + " " + num(u));
        static const Op kFns[] = {Op::TMID, Op::TDELETE, Op::TINSERT, Op::TREPLACE};
        Op op = kFns[r_.below(4)];
        if (op_info(op).nopd == 2) return emit(name(op, Ty::STRING) + " " + str() + " " + str());
        return emit(name(op, Ty::STRING) + " " + str() + " " + str() + " " + str());
      }
    }
  }
  void action() {
    std::vector<void (TypedGen::*)()> kinds;
    if (on(kGenTArith)) kinds.insert(kinds.end(), 3, &TypedGen::arith);
    if (on(kGenTConv)) kinds.insert(kinds.end(), 2, &TypedGen::conv);
    if (on(kGenTBits)) kinds.insert(kinds.end(), 2, &TypedGen::bits);
    if (on(kGenTArray)) kinds.insert(kinds.end(), 2, &TypedGen::array);
    if (on(kGenTString)) kinds.insert(kinds.end(), 2, &TypedGen::strings);
    if (kinds.empty() || r_.pct(12)) {  // a bit for later rungs' conditions
      static const char* const kCoils[] = {"OUT", "OUT", "SET", "RST", "OUTN"};
      return emit(std::string(r_.of(kCoils)) + " " + bit_dst());
    }
    (this->*kinds[size_t(r_.below(int(kinds.size())))])();
  }

  std::string rung(int k, GenItem& it) {
    code_.clear();
    if (r_.pct(20)) {
      emit("TRUE");
      it.inputs = 0;
    } else {
      condition(r_.range(0, std::min(o_.max_depth, 2)));  // --depth bounds the nesting of blocks
      it.inputs = 1;
    }
    int n = r_.range(1, 3);
    for (int i = 0; i < n; i++) action();
    it.outputs = n;
    return ".rung line " + std::to_string(k + 1) + " \"" + std::to_string(k) + "\"\n" + code_;
  }
};

// A word of a typed trace: small numbers, the limits of the widths, REAL and
// LREAL patterns (NaN, infinities, -0.0, subnormals), random bits.
std::string typed_word(Rng& r) {
  // (a trace cell is an INT32: the patterns with the top bit set are written in decimal)
  static const char* const kWords[] = {"0", "1", "-1", "2147483647", "-2147483648", "32767", "32768", "-32769", "65535",
                                       "127", "128", "255", "256", "-129", "0x7fc00000", "-8388608" /* -inf */,
                                       "0x7f800000", "-2147483648" /* -0.0 */, "0x00000001", "0x3fc00000",
                                       "0x4f000000", "0x5f000000", "0x7ff00000", "0x43300000", "1000000000",
                                       "-1000000000", "86400", "-4194304" /* -NaN */};
  switch (r.pick({4, 5, 3})) {
    case 0: return std::to_string(r.range(-9, 9));
    case 1: return r.of(kWords);
    default: return std::to_string(int32_t(uint32_t(r.next())));
  }
}

}  // namespace

GenProgram generate_typed_program(uint64_t seed, const GenOptions& opt) { return TypedGen(seed, opt).program(seed); }

// The trace of generate_typed_program(seed, o): it knows the program's arrays
// (drawn first from the same seed) to write their indices.

std::string generate_typed_trace(uint64_t seed, int scans, const GenOptions& o) {
  Rng r(seed * 0x9E3779B97F4A7C15ull + 0x7479706574ull);
  std::vector<std::string> head;
  for (int i = 0; i < o.x; i++) head.push_back("X" + std::to_string(i));
  for (int i = 0; i < kIndexD + kIndexN; i++) head.push_back("D" + std::to_string(i));
  for (int i = kArrayD; i < kArrayEnd; i++) head.push_back("D" + std::to_string(i));
  head.push_back("dt");
  std::string s = "# ldgen typed trace --seed " + std::to_string(seed) + " --scans " + std::to_string(scans) + "\n";
  for (size_t i = 0; i < head.size(); i++) s += (i ? "," : "") + head[i];
  s += "\n";
  const std::vector<Array> arrays = TypedGen(seed, o).arrays();
  for (int k = 0; k < scans; k++) {
    std::vector<std::string> row;
    for (int i = 0; i < o.x; i++) row.push_back(r.pct(25) ? std::to_string(r.below(2)) : "");
    for (int i = 0; i < kIndexD; i++) row.push_back(k == 0 || r.pct(6) ? typed_word(r) : "");
    for (int i = 0; i < kIndexN / 2; i++) {  // array i's index: low word, high word
      if (k > 0 && !r.pct(30)) {
        row.insert(row.end(), {"", ""});
        continue;
      }
      int lo = i < int(arrays.size()) ? arrays[size_t(i)].lo : 0, hi = i < int(arrays.size()) ? arrays[size_t(i)].hi : 3;
      int v = r.pct(97) ? r.range(lo, hi) : r.pct(50) ? r.range(hi + 1, hi + 3) : r.range(lo - 3, lo - 1);
      row.push_back(std::to_string(v));
      row.push_back(r.pct(97) ? (v < 0 ? "-1" : "0") : typed_word(r));
    }
    for (int i = kArrayD; i < kArrayEnd; i++) row.push_back(k == 0 ? typed_word(r) : "");
    row.push_back(std::to_string(r.range(0, 60)));
    for (size_t i = 0; i < row.size(); i++) s += (i ? "," : "") + row[i];
    s += "\n";
  }
  return s;
}

}  // namespace ldc
