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

// ---- memory
inline uint64_t load(Ty t, const uint8_t* p) {
  if (t == Ty::BOOL) return p[0] != 0;
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
        case Op::TADD: return bits_of(x + y);
        case Op::TSUB: return bits_of(x - y);
        case Op::TMUL: return bits_of(x * y);
        case Op::TDIV: return bits_of(x / y);
        case Op::TEXPT: return bits_of(float(std::pow(double(x), double(y))));  // C's pow, as MatIEC calls it
        default: break;
      }
    } else {
      double x = f64(a), y = f64(b);
      switch (op) {
        case Op::TADD: return bits_of(x + y);
        case Op::TSUB: return bits_of(x - y);
        case Op::TMUL: return bits_of(x * y);
        case Op::TDIV: return bits_of(x / y);
        case Op::TEXPT: return bits_of(std::pow(x, y));
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
    case Op::TSQRT: return bits_of(std::sqrt(x));
    case Op::TLN: return bits_of(std::log(x));
    case Op::TLOG: return bits_of(std::log10(x));
    case Op::TEXP: return bits_of(std::exp(x));
    case Op::TSIN: return bits_of(std::sin(x));
    case Op::TCOS: return bits_of(std::cos(x));
    case Op::TTAN: return bits_of(std::tan(x));
    case Op::TASIN: return bits_of(std::asin(x));
    case Op::TACOS: return bits_of(std::acos(x));
    case Op::TATAN: return bits_of(std::atan(x));
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

}  // namespace ldc::typed
