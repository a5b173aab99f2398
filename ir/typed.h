// ir/typed.h -- the meaning of the typed instructions (ops.def, class Typed):
// every IEC elementary type of types.def at its own width, with MatIEC's
// arithmetic.  The reference interpreter computes with these functions, the
// fast interpreter too, and the code generators (native x86-64, the C route,
// the C40) are tested against them scan by scan; docs/il.md, "Typed
// instructions", says the same in words and gives where each rule comes from.
//
// A value travels as 64 canonical bits:
//   Signed, Time, Date   sign-extended from the type's width
//   Unsigned, Bits       zero-extended
//   BOOL                 0 or 1
//   REAL                 the binary32 bits in the low 32 (the high 32 zero)
//   LREAL                the binary64 bits
// In memory a type of up to 32 bits takes one word cell (4 bytes), held
// extended to 32 bits; a 64-bit type takes two cells, low word first; BOOL
// takes one bit device (one byte, 0 or 1).  A load reads a cell whatever
// wrote it and makes it canonical (a DINT word read as an INT is its low 16
// bits, sign-extended); a store writes the whole cell.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "ir/ir.h"

namespace ldc::typed {

constexpr int64_t kNsPerMs = 1000000;
constexpr int64_t kNsPerS = 1000000000;  // MatIEC's conversions count seconds (tv_sec)
constexpr int64_t kNsPerDay = 86400LL * 1000000000LL;

inline bool is_int_kind(Ty t) {  // wraps at its width: the integers, bit strings, times and dates
  TyKind k = ty_info(t).kind;
  return k == TyKind::Signed || k == TyKind::Unsigned || k == TyKind::Bits || k == TyKind::Time || k == TyKind::Date;
}
inline bool is_signed(Ty t) {
  TyKind k = ty_info(t).kind;
  return k == TyKind::Signed || k == TyKind::Time || k == TyKind::Date;
}
inline bool is_real(Ty t) { return ty_info(t).kind == TyKind::Real; }

// v wrapped to t's width and extended: the canonical bits of t.
inline uint64_t norm(Ty t, uint64_t v) {
  const TyInfo& ti = ty_info(t);
  if (ti.kind == TyKind::Bool) return v != 0;
  if (ti.kind == TyKind::Real) return ti.bits == 32 ? (v & 0xffffffffu) : v;
  if (ti.bits == 64) return v;
  uint64_t mask = (uint64_t(1) << ti.bits) - 1;
  v &= mask;
  if (is_signed(t) && (v >> (ti.bits - 1)) & 1) v |= ~mask;
  return v;
}

inline float f32(uint64_t v) { float f; uint32_t u = uint32_t(v); std::memcpy(&f, &u, 4); return f; }
inline double f64(uint64_t v) { double d; std::memcpy(&d, &v, 8); return d; }
inline uint64_t bits_of(float f) { uint32_t u; std::memcpy(&u, &f, 4); return u; }
inline uint64_t bits_of(double d) { uint64_t u; std::memcpy(&u, &d, 8); return u; }
// A REAL or LREAL value as a double (exact).
inline double real_value(Ty t, uint64_t v) { return ty_info(t).bits == 32 ? double(f32(v)) : f64(v); }
// A double as t's bits (REAL rounds to binary32).
inline uint64_t real_bits(Ty t, double d) { return ty_info(t).bits == 32 ? bits_of(float(d)) : bits_of(d); }

// ---- NaN results (docs/il.md, "NaN results").  IEEE 754 says an operation
// with a NaN result returns a quiet NaN, ideally one of its NaN operands, but
// not which one nor which bits an invalid operation makes; hardware and C
// compilers differ (a C compiler may swap a commutative operation's operands,
// and the C library's asin(2) is +NaN where 0/0 is -NaN).  ldc's rule is
// x86-64 SSE's, written out: a NaN result is the first NaN operand (a before
// b) with its quiet bit set, sign and payload kept; with no NaN operand it is
// the default NaN, sign set, quiet bit, payload 0.  Each engine computes the
// result as it likes and, only when it is a NaN, stores nan_result's.
constexpr uint32_t kQuietBit32 = 0x00400000u;
constexpr uint64_t kQuietBit64 = 0x0008000000000000ull;
constexpr uint32_t kDefaultNaN32 = 0xffc00000u;
constexpr uint64_t kDefaultNaN64 = 0xfff8000000000000ull;
inline float nan_result(float x, float y) {
  if (x != x) return f32(bits_of(x) | kQuietBit32);
  if (y != y) return f32(bits_of(y) | kQuietBit32);
  return f32(kDefaultNaN32);
}
inline double nan_result(double x, double y) {
  if (x != x) return f64(bits_of(x) | kQuietBit64);
  if (y != y) return f64(bits_of(y) | kQuietBit64);
  return f64(kDefaultNaN64);
}
// r, computed from x and y (a one-operand function: y = x), by the rule
template <class F>
inline F nan_rule(F r, F x, F y) { return r == r ? r : nan_result(x, y); }
template <class F> inline F real_add(F x, F y) { return nan_rule(x + y, x, y); }
template <class F> inline F real_sub(F x, F y) { return nan_rule(x - y, x, y); }
template <class F> inline F real_mul(F x, F y) { return nan_rule(x * y, x, y); }
template <class F> inline F real_div(F x, F y) { return nan_rule(x / y, x, y); }

// ---- memory
inline uint64_t load(Ty t, const uint8_t* p) {
  if (t == Ty::BOOL) return p[0] != 0;
  if (t == Ty::STRING) return 0;  // a string is not a 64-bit value: the string routines below read it
  if (ty_info(t).cells == 1) {
    uint32_t u;
    std::memcpy(&u, p, 4);
    return norm(t, u);
  }
  uint64_t u;
  std::memcpy(&u, p, 8);
  return u;
}
inline void store(Ty t, uint8_t* p, uint64_t v) {
  if (t == Ty::BOOL) { p[0] = v ? 1 : 0; return; }
  if (t == Ty::STRING) return;
  if (ty_info(t).cells == 1) {
    uint32_t u = uint32_t(v);
    std::memcpy(p, &u, 4);
    return;
  }
  std::memcpy(p, &v, 8);
}

// ---- compares (TEQ..TGE, MIN, MAX): signed, unsigned or IEEE by the kind
inline bool compare(Rel r, Ty t, uint64_t a, uint64_t b) {
  if (is_real(t)) {
    if (ty_info(t).bits == 32) return rel_holds(r, f32(a), f32(b));
    return rel_holds(r, f64(a), f64(b));
  }
  if (is_signed(t)) return rel_holds(r, int64_t(a), int64_t(b));
  return rel_holds(r, a, b);
}

// ---- arithmetic (TADD TSUB TMUL TDIV TMOD TMIN TMAX TEXPT); `error` is set
// (S0) by an integer division by zero, whose result is 0 (MatIEC's DIV and MOD
// functions give 0 there; C leaves `/` undefined)
inline uint64_t arith(Op op, Ty t, uint64_t a, uint64_t b, bool& error) {
  if (op == Op::TMIN) return compare(Rel::Lt, t, b, a) ? b : a;   // MatIEC: res = IN1; if (IN2 < res) res = IN2
  if (op == Op::TMAX) return compare(Rel::Gt, t, b, a) ? b : a;
  if (is_real(t)) {
    if (ty_info(t).bits == 32) {
      float x = f32(a), y = f32(b);
      switch (op) {
        case Op::TADD: return bits_of(real_add(x, y));
        case Op::TSUB: return bits_of(real_sub(x, y));
        case Op::TMUL: return bits_of(real_mul(x, y));
        case Op::TDIV: return bits_of(real_div(x, y));
        case Op::TEXPT: return bits_of(float(f64(arith(op, Ty::LREAL, bits_of(double(x)), bits_of(double(y)), error))));
        default: break;
      }
    } else {
      double x = f64(a), y = f64(b);
      switch (op) {
        case Op::TADD: return bits_of(real_add(x, y));
        case Op::TSUB: return bits_of(real_sub(x, y));
        case Op::TMUL: return bits_of(real_mul(x, y));
        case Op::TDIV: return bits_of(real_div(x, y));
        case Op::TEXPT: return bits_of(nan_rule(std::pow(x, y), x, y));  // C's pow, as MatIEC calls it
        default: break;
      }
    }
    return a;
  }
  switch (op) {
    case Op::TADD: return norm(t, a + b);
    case Op::TSUB: return norm(t, a - b);
    case Op::TMUL: return norm(t, a * b);
    case Op::TDIV:
      if (b == 0) { error = true; return 0; }
      if (is_signed(t)) return int64_t(b) == -1 ? norm(t, 0 - a) : norm(t, uint64_t(int64_t(a) / int64_t(b)));
      return norm(t, a / b);
    case Op::TMOD:
      if (b == 0) { error = true; return 0; }
      if (is_signed(t)) return int64_t(b) == -1 ? 0 : norm(t, uint64_t(int64_t(a) % int64_t(b)));
      return norm(t, a % b);
    default: break;
  }
  return a;
}

// ---- bit strings (TAND TOR TXOR TNOT) and shifts (TSHL TSHR TROL TROR, the
// count of type u): a count outside 0..width-1 shifts everything out (C leaves
// it undefined); rotations take the count modulo the width
inline uint64_t logic(Op op, Ty t, uint64_t a, uint64_t b) {
  switch (op) {
    case Op::TAND: return a & b;
    case Op::TOR: return a | b;
    case Op::TXOR: return a ^ b;
    case Op::TNOT: return t == Ty::BOOL ? a ^ 1 : norm(t, ~a);
    default: break;
  }
  return a;
}
inline uint64_t shift(Op op, Ty t, uint64_t a, Ty u, uint64_t n) {
  const uint64_t w = uint64_t(ty_info(t).bits);
  bool negative = is_signed(u) && int64_t(n) < 0;
  if (op == Op::TSHL || op == Op::TSHR) {
    if (negative || n >= w) return 0;
    return norm(t, op == Op::TSHL ? a << n : a >> n);
  }
  uint64_t k = negative ? (w - (0 - n) % w) % w : n % w;
  if (k == 0) return a;
  if (op == Op::TROR) k = w - k;
  return norm(t, (a << k) | (a >> (w - k)));
}

// ---- one-operand functions (TNEG TABS TSQRT .. TATAN); ABS is MatIEC's
// __abs_signed, `op < 0 ? -op : op`, for REAL too: ABS(-0.0) is -0.0 and a NaN
// keeps its sign (fabs would clear it)
inline uint64_t unary(Op op, Ty t, uint64_t a) {
  if (!is_real(t)) {
    if (op == Op::TNEG) return norm(t, 0 - a);
    if (op == Op::TABS) return is_signed(t) && int64_t(a) < 0 ? norm(t, 0 - a) : a;
    return a;
  }
  // REAL: MatIEC calls the C library's double functions (sqrt, sin ...) and
  // the result is rounded to binary32, which may differ from sinf in the last bit
  if (ty_info(t).bits == 32) {
    float x = f32(a);
    if (op == Op::TNEG) return bits_of(-x);
    if (op == Op::TABS) return bits_of(x < 0 ? -x : x);
    return bits_of(float(f64(unary(op, Ty::LREAL, bits_of(double(x))))));
  }
  double x = f64(a);
  switch (op) {
    case Op::TNEG: return bits_of(-x);
    case Op::TABS: return bits_of(x < 0 ? -x : x);
    case Op::TSQRT: return bits_of(nan_rule(std::sqrt(x), x, x));
    case Op::TLN: return bits_of(nan_rule(std::log(x), x, x));
    case Op::TLOG: return bits_of(nan_rule(std::log10(x), x, x));
    case Op::TEXP: return bits_of(nan_rule(std::exp(x), x, x));
    case Op::TSIN: return bits_of(nan_rule(std::sin(x), x, x));
    case Op::TCOS: return bits_of(nan_rule(std::cos(x), x, x));
    case Op::TTAN: return bits_of(nan_rule(std::tan(x), x, x));
    case Op::TASIN: return bits_of(nan_rule(std::asin(x), x, x));
    case Op::TACOS: return bits_of(nan_rule(std::acos(x), x, x));
    case Op::TATAN: return bits_of(nan_rule(std::atan(x), x, x));
    default: break;
  }
  return a;
}

// ---- conversions (TCONV: MatIEC's *_TO_*; TTRUNC)
// A double to INT64 as x86's cvttsd2si does: NaN and values outside the range
// give INT64_MIN (C leaves them undefined; MatIEC's result is what the C
// compiler makes of it there, which on x86-64 is this).
inline int64_t to_i64(double d) {
  if (!(d >= -9223372036854775808.0 && d < 9223372036854775808.0)) return std::numeric_limits<int64_t>::min();
  return int64_t(d);
}
// MatIEC's __real_round (iec_std_lib.h): `fmod(IN, 1) == 0 ? ((LINT)IN / 2) *
// 2 : (LINT)IN`, called with IN + 0.5 (or IN - 0.5): the nearest integer, an
// exact tie to even -- but IN + 0.5 is itself rounded in double, so an odd
// integer between 2^52 and 2^53 goes to its even neighbour.
inline int64_t real_round(double x) { return std::fmod(x, 1.0) == 0 ? (to_i64(x) / 2) * 2 : to_i64(x); }
// REAL to an integer: __real_to_sint `IN >= 0 ? __real_round(IN + 0.5) :
// __real_round(IN - 0.5)`; to an unsigned type or a bit string __real_to_uint /
// __real_to_bit `IN >= 0 ? __real_round(IN + 0.5) : 0` -- a LINT in both, so a
// value from 2^63 up gives INT64_MIN there too; then C's conversion to t.
inline uint64_t real_to_int(Ty t, double d) {
  if (is_signed(t)) return norm(t, uint64_t(d >= 0 ? real_round(d + 0.5) : real_round(d - 0.5)));
  return norm(t, uint64_t(d >= 0 ? real_round(d + 0.5) : 0));
}
// MatIEC's timespec of a TIME or date: {tv_sec, tv_nsec} of one sign
// (__normalize_timespec), both toward zero.
inline int64_t time_sec(int64_t ns) { return ns / kNsPerS; }
inline int64_t time_nsec(int64_t ns) { return ns % kNsPerS; }
inline uint64_t time_of(int64_t sec, int64_t nsec) { return uint64_t(sec) * uint64_t(kNsPerS) + uint64_t(nsec); }  // wraps
inline uint64_t conv(Ty to, Ty from, uint64_t v) {
  const TyKind fk = ty_info(from).kind, tk = ty_info(to).kind;
  if (to == from) return v;
  if (tk == TyKind::Bool) return fk == TyKind::Real ? real_value(from, v) != 0 : v != 0;
  if (fk == TyKind::Real) {
    double d = real_value(from, v);
    if (tk == TyKind::Real) return real_bits(to, d);
    if (tk == TyKind::Time || tk == TyKind::Date) {  // __real_to_time: {IN, (IN - (LINT)IN) * 1000000000}: seconds
      int64_t sec = to_i64(d);
      return time_of(sec, to_i64((d - double(sec)) * 1e9));
    }
    return real_to_int(to, d);
  }
  if (fk == TyKind::Time || fk == TyKind::Date) {
    const int64_t sec = time_sec(int64_t(v)), nsec = time_nsec(int64_t(v));
    if (tk == TyKind::Real) return real_bits(to, double(sec) + double(nsec) / 1e9);  // __time_to_real: seconds
    if (tk == TyKind::Time) return v;
    if (tk == TyKind::Date) {  // __date_and_time_to_date / _time_of_day: C's % on tv_sec (before 1970 too)
      constexpr int64_t kDay = kNsPerDay / kNsPerS;
      if (to == Ty::DATE && from == Ty::DT) return time_of(sec - sec % kDay - (sec < 0 ? kDay : 0), 0);
      if (to == Ty::TOD && from == Ty::DT) return time_of(sec % kDay + (sec < 0 ? kDay : 0), nsec);
      return v;
    }
    return norm(to, uint64_t(sec));  // __time_to_int: tv_sec, whole seconds toward zero
  }
  // from BOOL, an integer or a bit string
  if (tk == TyKind::Real) {
    double d = is_signed(from) ? double(int64_t(v)) : double(v);
    if (ty_info(to).bits == 32) return bits_of(is_signed(from) ? float(int64_t(v)) : float(v));  // one rounding, as C
    return bits_of(d);
  }
  if (tk == TyKind::Time || tk == TyKind::Date) return v * uint64_t(kNsPerS);  // __int_to_time: {IN, 0}: seconds, wrapping
  return norm(to, v);
}
inline uint64_t trunc(Ty to, Ty from, uint64_t v) {
  return norm(to, uint64_t(to_i64(std::trunc(real_value(from, v)))));
}

// ---- arrays (TIDX): is v, of type t, inside lo..hi?  The index register is
// then v - lo.
inline bool index_ok(Ty t, uint64_t v, int32_t lo, int32_t hi) {
  if (!is_signed(t) && v > uint64_t(std::numeric_limits<int64_t>::max())) return false;
  return int64_t(v) >= lo && int64_t(v) <= hi;
}

// ---- strings (STRING, types.def): MatIEC's IEC_STRING, {uint8_t len; uint8_t
// body[STR_MAX_LEN]} with STR_MAX_LEN 126 (lib/C/iec_types.h), and its
// functions of Table 29 (lib/C/iec_std_functions.h) and conversions
// (lib/C/iec_std_lib.h, __*_to_string, __string_to_*).  In memory a STRING
// takes 33 cells: cell 0 the length, cells 1..32 the bytes (126 used, 2 spare).
// A length cell is read as a UINT32 clamped to 126, whatever wrote it (an
// untrusted image may hold 0x7fffffff or -1 there), so no routine here reads
// or writes outside the string's 132 bytes.  A result is built whole and then
// stored with its unused bytes zero (MatIEC's __INIT_STRING), so a destination
// may also be an operand.  Where MatIEC's C writes outside its 126 bytes or
// reads outside its struct, these routines clamp (docs/il.md, "Strings").
constexpr uint32_t kStrMax = 126;   // MatIEC's STR_MAX_LEN
constexpr uint32_t kStrBytes = 132; // 33 cells
struct Str {
  uint32_t len = 0;
  uint8_t body[kStrMax];  // the first len bytes hold it; nothing reads past them (not cleared: a scan makes many)
};
inline Str str_load(const uint8_t* p) {
  Str s;
  uint32_t n;
  std::memcpy(&n, p, 4);
  s.len = n > kStrMax ? kStrMax : n;
  std::memcpy(s.body, p + 4, s.len);
  return s;
}
inline void str_store(uint8_t* p, const Str& s) {
  const uint32_t n = s.len > kStrMax ? kStrMax : s.len;
  std::memcpy(p, &n, 4);
  std::memcpy(p + 4, s.body, n);
  std::memset(p + 4 + n, 0, kStrBytes - 4 - n);
}
// Appends up to n bytes (as many as fit).
inline void str_append(Str& r, const uint8_t* b, int64_t n) {
  if (n <= 0) return;
  const int64_t room = int64_t(kStrMax) - int64_t(r.len);
  if (n > room) n = room;
  std::memcpy(r.body + r.len, b, size_t(n));
  r.len += uint32_t(n);
}
// MatIEC's __str_cmp: memcmp of the common length, then the longer is greater.
inline int str_cmp(const Str& a, const Str& b) {
  int c = std::memcmp(a.body, b.body, a.len < b.len ? a.len : b.len);
  if (c) return c < 0 ? -1 : 1;
  return a.len > b.len ? 1 : a.len < b.len ? -1 : 0;
}
inline bool str_compare(Rel r, const Str& a, const Str& b) { return rel_holds(r, str_cmp(a, b), 0); }

// LEFT / RIGHT (L < 0: ENO FALSE, the empty string): min(L, len) bytes.
inline Str str_left(const Str& s, int64_t l, bool& error) {
  Str r;
  if (l < 0) { error = true; return r; }
  str_append(r, s.body, l < int64_t(s.len) ? l : int64_t(s.len));
  return r;
}
inline Str str_right(const Str& s, int64_t l, bool& error) {
  Str r;
  if (l < 0) { error = true; return r; }
  if (l > int64_t(s.len)) l = s.len;
  str_append(r, s.body + (s.len - uint32_t(l)), l);
  return r;
}
// MID: `if (P <= len) { P -= 1; L = L + P <= len ? L : len - P; memcpy(res.body,
// &IN.body[P], L); }`.  P = 0 makes MatIEC start at body[-1], the length byte of
// its struct: so here too (MID('abc', 2, 0) is '\x03a'); a result of 127 bytes
// (P = 0 on a full string) is cut to 126 where MatIEC overruns.
inline Str str_mid(const Str& s, int64_t l, int64_t p, bool& error) {
  Str r;
  if (l < 0 || p < 0) { error = true; return r; }
  if (p > int64_t(s.len)) return r;
  p -= 1;
  if (l > int64_t(s.len) - p) l = int64_t(s.len) - p;
  if (l > int64_t(kStrMax)) l = kStrMax;
  if (l <= 0) return r;
  if (p < 0) r.body[0] = uint8_t(s.len), p = 0, r.len = 1, l--;  // body[-1]: the length byte
  std::memcpy(r.body + r.len, s.body + p, size_t(l));
  r.len += uint32_t(l);
  return r;
}
// CONCAT: as many bytes of each as fit in 126.
inline Str str_concat(const Str& a, const Str& b) {
  Str r = a;
  str_append(r, b.body, b.len);
  return r;
}
// INSERT (__insert, P cast to __strlen_t, uint8_t): IN1's first min(P, len1)
// bytes, IN2, the rest of IN1, cut at 126.
inline Str str_insert(const Str& a, const Str& b, int64_t p, bool& error) {
  Str r;
  if (p < 0) { error = true; return r; }
  const uint32_t p8 = uint8_t(p);
  const uint32_t head = p8 > a.len ? a.len : p8;
  str_append(r, a.body, head);
  str_append(r, b.body, b.len);
  str_append(r, a.body + head, a.len - head);
  return r;
}
// The first bytes DELETE and REPLACE keep: `P > len ? len : P - 1` in
// __strlen_t.  P = 0 gives 255 there and MatIEC copies 255 bytes into its
// 126 (a buffer overrun); here it keeps none, as P = 1.
inline uint32_t str_head(uint32_t p8, uint32_t len) { return p8 > len ? len : p8 == 0 ? 0 : p8 - 1; }
inline Str str_delete(const Str& s, int64_t l, int64_t p, bool& error) {
  Str r;
  if (l < 0 || p < 0) { error = true; return r; }
  const uint32_t l8 = uint8_t(l), head = str_head(uint8_t(p), s.len);
  str_append(r, s.body, head);
  if (s.len > head + l8) str_append(r, s.body + head + l8, s.len - head - l8);
  return r;
}
// REPLACE (__replace): IN1's head, min(len2, L) bytes of IN2, then IN1 from
// P + L (that sum in __strlen_t: modulo 256); MatIEC does not cut the last
// copy at 126 (an overrun), here it is cut.
inline Str str_replace(const Str& a, const Str& b, int64_t l, int64_t p, bool& error) {
  Str r;
  if (l < 0 || p < 0) { error = true; return r; }
  const uint32_t l8 = uint8_t(l), head = str_head(uint8_t(p), a.len);
  str_append(r, a.body, head);
  str_append(r, b.body, b.len < l8 ? b.len : l8);
  const uint32_t from = uint8_t(head + l8);
  if (r.len < kStrMax && from < a.len) str_append(r, a.body + from, a.len - from);
  return r;
}
// FIND (__pfind): the 1-based position of IN2's first occurrence in IN1, 0 if
// none or IN2 is empty.  After a partial match of c2 bytes at c1 MatIEC goes on
// at c1 + c2 + 1, past bytes where a match could start: FIND('aaab', 'aab') is 0.
inline uint64_t str_find(const Str& a, const Str& b) {
  if (!(b.len > 0 && a.len >= b.len)) return 0;
  uint32_t c1 = 0, c2 = 0;
  while (c1 + c2 < a.len && c2 < b.len) {
    if (a.body[c1 + c2] != b.body[c2]) c1 += c2 + 1, c2 = 0;
    else c2++;
  }
  return c2 == b.len ? c1 + 1 : 0;
}

// ---- conversions to and from STRING (CONV.STRING.U, CONV.T.STRING)
// snprintf(body, STR_MAX_LEN, ...) with len = its result cut at 126, as
// MatIEC's __*_to_string.
template <typename... A>
inline Str str_printf(const char* fmt, A... a) {
  Str r;
  char buf[kStrMax + 1] = {};
  int n = std::snprintf(buf, kStrMax, fmt, a...);
  r.len = n < 0 ? 0 : uint32_t(n) > kStrMax ? kStrMax : uint32_t(n);
  std::memcpy(r.body, buf, r.len);
  return r;
}
// __time_to_string: T#<d>d, then h, m, s and `%g`ms as far as needed; the days
// and the rest come from div(tv_sec, 86400) with tv_sec passed as an int.
inline Str time_to_string(int64_t ns) {
  const int32_t sec = int32_t(uint32_t(uint64_t(time_sec(ns))));
  const int64_t nsec = time_nsec(ns);
  const int days = sec / 86400, drem = sec % 86400;
  if (!drem && nsec == 0) return str_printf("T#%dd", days);
  const int hours = drem / 3600, hrem = drem % 3600;
  if (!hrem && nsec == 0) return str_printf("T#%dd%dh", days, hours);
  const int mins = hrem / 60, mrem = hrem % 60;
  if (!mrem && nsec == 0) return str_printf("T#%dd%dh%dm", days, hours, mins);
  if (nsec == 0) return str_printf("T#%dd%dh%dm%ds", days, hours, mins, mrem);
  return str_printf("T#%dd%dh%dm%ds%gms", days, hours, mins, mrem, double(nsec) / 1000000);
}
// MatIEC's convert_seconds_to_date_and_time (iec_std_lib.h): the day and the
// time of day by C's / and % (a negative rest moved into the day before),
// then whole years from 1970 and the month by __mon_yday.
struct Tm {
  int sec, min, hour, day, mon, year;
};
inline Tm seconds_to_date(int64_t seconds) {
  static const unsigned short mon_yday[2][13] = {{0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334, 365},
                                                 {0, 31, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335, 366}};
  auto leap = [](int y) { return y % 4 == 0 && (y % 100 != 0 || y % 400 == 0); };
  Tm t{};
  int64_t days = seconds / 86400, rem = seconds % 86400;
  if (rem < 0) rem += 86400, days--;
  t.hour = int(rem / 3600);
  rem %= 3600;
  t.min = int(rem / 60);
  t.sec = int(rem % 60);
  t.year = 1970;
  while (days >= (rem = leap(t.year) ? 366 : 365)) t.year++, days -= rem;
  while (days < 0) t.year--, days += leap(t.year) ? 366 : 365;
  t.mon = 1;
  while (days >= mon_yday[leap(t.year)][t.mon]) t.mon += 1;
  t.day = int(days - mon_yday[leap(t.year)][t.mon - 1] + 1);
  return t;
}
// __date_to_string "D#%d-%2.2d-%2.2d"; __tod_to_string "TOD#%2.2d:%2.2d:%2.2d" (with
// a fraction "%09.6f" seconds; from 86400 s on 'TOD#ERROR'); __dt_to_string
// "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%2.2d" (or "%09.6f" seconds).
inline Str date_to_string(Ty u, int64_t ns) {
  const int64_t sec = time_sec(ns), nsec = time_nsec(ns);
  const Tm t = seconds_to_date(sec);
  const double frac = double(t.sec) + double(nsec) / 1e9;
  if (u == Ty::DATE) return str_printf("D#%d-%2.2d-%2.2d", t.year, t.mon, t.day);
  if (u == Ty::TOD) {
    if (sec >= 86400) return str_printf("%s", "TOD#ERROR");
    if (nsec == 0) return str_printf("TOD#%2.2d:%2.2d:%2.2d", t.hour, t.min, t.sec);
    return str_printf("TOD#%2.2d:%2.2d:%09.6f", t.hour, t.min, frac);
  }
  if (nsec == 0) return str_printf("DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%2.2d", t.year, t.mon, t.day, t.hour, t.min, t.sec);
  return str_printf("DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%09.6f", t.year, t.mon, t.day, t.hour, t.min, frac);
}
// U_TO_STRING: __bool_to_string 'TRUE' / 'FALSE'; __bit_to_string "16#%llx";
// __sint_to_string "%lld"; __uint_to_string "%llu"; __real_to_string "%.10g"
// of the LREAL value; __time_to_string; the dates above.
inline Str to_string(Ty u, uint64_t v) {
  switch (ty_info(u).kind) {
    case TyKind::Bool: return str_printf("%s", v ? "TRUE" : "FALSE");
    case TyKind::Bits: return str_printf("16#%llx", (unsigned long long)v);
    case TyKind::Signed: return str_printf("%lld", (long long)int64_t(v));
    case TyKind::Unsigned: return str_printf("%llu", (unsigned long long)v);
    case TyKind::Real: return str_printf("%.10g", real_value(u, v));
    case TyKind::Time: return time_to_string(int64_t(v));
    case TyKind::Date: return date_to_string(u, int64_t(v));
    default: return Str{};
  }
}
// __pstring_to_sint, with C's arithmetic on x86-64 where MatIEC's is
// undefined: `(c - '0') << shift` in 2# and 8# is an int shift, whose count
// x86 takes modulo 32, sign-extended into the LINT; the decimal digits
// accumulate in wrapping 64-bit arithmetic.  A decimal string is read from its
// end: digits count, a byte below '.' ('-', '+', ' ') is skipped, any other
// resets the value (so '1.5' gives 1, 'a7' gives 7); at most 20 digits count.
inline uint64_t str_to_lint(const Str& s) {
  const uint8_t* b = s.body;
  const uint32_t n = s.len;
  uint64_t res = 0;
  unsigned shift = 0;
  if (n < 1) return 0;
  if (n > 1 && (b[0] == '2' || b[0] == '8') && b[1] == '#') {
    const unsigned bits = b[0] == '2' ? 1 : 3;
    const uint8_t top = b[0] == '2' ? '1' : '7';
    for (uint32_t l = n - 1; l >= 2 && shift < 64; l--) {
      uint8_t c = b[l];
      if (c >= '0' && c <= top) {
        res |= uint64_t(int64_t(int32_t(uint32_t(c - '0') << (shift & 31))));
        shift += bits;
      }
    }
    return res;
  }
  if (n > 2 && b[0] == '1' && b[1] == '6' && b[2] == '#') {
    for (uint32_t l = n - 1; l >= 3 && shift < 64; l--) {
      uint8_t c = b[l];
      int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (d >= 0) res |= uint64_t(d) << shift, shift += 4;
    }
    return res;
  }
  const uint64_t sign = b[0] == '-' ? ~uint64_t(0) : 1;
  uint64_t fac = sign;
  for (uint32_t l = n; l > 0 && shift < 20; l--) {
    uint8_t c = b[l - 1];
    if (c >= '0' && c <= '9') {
      res += uint64_t(c - '0') * fac;
      fac *= 10;
      shift++;
    } else if (c >= '.') {
      res = 0, fac = sign, shift = 0;
    }
  }
  return res;
}
// __string_to_real: atof of the bytes if a '.' is at an index above 0, else
// __pstring_to_sint (so '.5' is 0: its '.' resets the 5; '1e3' is 1).
inline double str_to_real(const Str& s) {
  uint32_t l = s.len;
  while (l > 0 && s.body[--l] != '.') {}
  if (l == 0) return double(int64_t(str_to_lint(s)));
  char buf[kStrMax + 1] = {};
  std::memcpy(buf, s.body, s.len);
  return std::strtod(buf, nullptr);  // atof: the C locale
}
// STRING_TO_T: __string_to_bool (len 1: '1'; len 4: 'TRUE' in any case),
// __string_to_sint / _uint / _bit then C's conversion to T, __string_to_real,
// __string_to_time: `{(long)IN_val, (long)(IN_val - (LINT)IN_val)*1000000000}`
// -- the cast binds before the product, so the fraction is always 0: whole
// seconds; without a '.', the integer's seconds.
inline uint64_t from_string(Ty t, const Str& s) {
  switch (ty_info(t).kind) {
    case TyKind::Bool: {
      if (s.len == 1) return s.body[0] == '1';
      if (s.len != 4) return 0;
      const char* w = "TRUE";
      for (int i = 0; i < 4; i++)
        if ((s.body[i] >= 'a' && s.body[i] <= 'z' ? s.body[i] - 32 : s.body[i]) != w[i]) return 0;
      return 1;
    }
    case TyKind::Real: return real_bits(t, str_to_real(s));
    case TyKind::Time: case TyKind::Date: {  // STRING_TO_[ANY_DATE] is __string_to_time too
      uint32_t l = s.len;
      while (l > 0 && s.body[--l] != '.') {}
      if (l == 0) return time_of(int64_t(str_to_lint(s)), 0);
      return time_of(to_i64(str_to_real(s)), 0);
    }
    default: return norm(t, str_to_lint(s));
  }
}
// Does CONV take T and U when one is a STRING?  Every elementary type, to and
// from; not STRING to STRING (that is MOVE).
inline bool conv_string_ok(Ty t, Ty u) { return !(t == Ty::STRING && u == Ty::STRING); }

// ---- running a string instruction (every engine that runs them calls this)
// Is this an instruction of the string section: a STRING operand, or ARGS?
inline bool is_string_instr(Op op, Ty t, Ty u) { return t == Ty::STRING || u == Ty::STRING || op == Op::TARGS; }
// The string-argument registers (L, P) that ARGS sets.
struct StrArgs {
  int64_t l = 0, p = 0;
};
// Runs string instruction `op` (not a compare) with power on.  o[i] is the
// address of device operand i (a STRING's first cell, an integer's cell), or
// nullptr for a constant, whose canonical bits are k[i].  Returns true for
// MatIEC's ENO FALSE (a negative length or position), which sets S0.
inline bool str_exec(Op op, Ty t, Ty u, uint8_t* const o[], const uint64_t k[], StrArgs& args) {
  auto num = [&](int i, Ty ty) { return int64_t(o[i] ? load(ty, o[i]) : k[i]); };
  auto sv = [&](int i) { return str_load(o[i]); };
  bool error = false;
  switch (op) {
    case Op::TARGS: args.l = num(0, t), args.p = num(1, t); return false;
    case Op::TMOVE: str_store(o[1], sv(0)); return false;
    case Op::TLEN: {  // the length cell alone, clamped as str_load reads it
      uint32_t n;
      std::memcpy(&n, o[0], 4);
      store(t, o[1], norm(t, n > kStrMax ? kStrMax : n));
      return false;
    }
    case Op::TFIND: store(t, o[2], norm(t, str_find(sv(0), sv(1)))); return false;
    case Op::TCONV:
      if (t == Ty::STRING) str_store(o[1], to_string(u, o[0] ? load(u, o[0]) : k[0]));
      else store(t, o[1], from_string(t, sv(0)));
      return false;
    case Op::TLEFT: str_store(o[2], str_left(sv(0), num(1, u), error)); break;
    case Op::TRIGHT: str_store(o[2], str_right(sv(0), num(1, u), error)); break;
    case Op::TCONCAT: str_store(o[2], str_concat(sv(0), sv(1))); break;
    case Op::TMID: str_store(o[1], str_mid(sv(0), args.l, args.p, error)); break;
    case Op::TDELETE: str_store(o[1], str_delete(sv(0), args.l, args.p, error)); break;
    case Op::TINSERT: str_store(o[2], str_insert(sv(0), sv(1), args.p, error)); break;
    case Op::TREPLACE: str_store(o[2], str_replace(sv(0), sv(1), args.l, args.p, error)); break;
    default: break;
  }
  return error;
}

}  // namespace ldc::typed
