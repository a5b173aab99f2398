// backend-c40sim/machine/c40float.cpp -- the C40 float format (c40float.h).
// Semantics: TMS320C4x User's Guide, "Data formats"; docs/c40.md.
#include "backend-c40sim/machine/c40float.h"

#include <cmath>
#include <limits>

namespace ldc::c40sim {

using i128 = __int128;

namespace fp {
namespace {

// A value m * 2^e (m == 0: zero).
struct Val {
  i128 m = 0;
  int e = 0;
};

int msb(unsigned __int128 v) {
  int p = -1;
  while (v) {
    v >>= 1;
    ++p;
  }
  return p;
}

i128 shr(i128 v, int s) {  // arithmetic (floor) shift, any s >= 0
  if (s <= 0) return v;
  if (s >= 127) return v < 0 ? -1 : 0;
  return v >> s;
}

int exp_of(Ext x) { return int(int8_t(x.exp)); }

// The 33-bit signed mantissa: value = sm * 2^(exp - 31).
int64_t sm(Ext x) {
  int64_t f = x.man & 0x7FFFFFFF;
  return (x.man >> 31) ? f - (int64_t(1) << 32) : f + (int64_t(1) << 31);
}

Val val(Ext x) {
  if (is_zero(x)) return {};
  return {sm(x), exp_of(x) - 31};
}

// Normalizes with truncation toward -infinity (dropping low bits of the
// two's complement mantissa), saturating on overflow and flushing to zero
// on underflow.
Res normalize(Val v) {
  Res r;
  if (v.m == 0) {
    r.v = kZero;
    return r;
  }
  int k;
  if (v.m > 0) {
    k = msb((unsigned __int128)v.m) - 31;
  } else {
    unsigned __int128 mag = (unsigned __int128)(-v.m);
    bool pow2 = (mag & (mag - 1)) == 0;
    k = msb(mag) - (pow2 ? 32 : 31);
  }
  i128 s = k >= 0 ? shr(v.m, k) : v.m << -k;
  int e = v.e + k + 31;
  if (e > 127) {
    r.overflow = true;
    r.v = v.m > 0 ? Ext{0x7F, 0x7FFFFFFF} : Ext{0x7F, 0x80000000};
    return r;
  }
  if (e < -127) {
    r.underflow = true;
    r.v = kZero;
    return r;
  }
  r.v = Ext{uint8_t(int8_t(e)), uint32_t(uint64_t(int64_t(s))) ^ 0x80000000u};
  return r;
}

}  // namespace

bool is_zero(Ext x) { return x.exp == 0x80; }
bool is_negative(Ext x) { return !is_zero(x) && (x.man >> 31); }

double to_double(Ext x) {
  if (is_zero(x)) return 0.0;
  return std::ldexp(double(sm(x)), exp_of(x) - 31);
}

Res from_double(double v) {
  if (v == 0 || std::isnan(v)) return {};
  if (std::isinf(v)) return normalize(Val{v > 0 ? 1 : -1, 1000});
  int e = 0;
  double f = std::frexp(v, &e);  // v = f * 2^e, |f| in [0.5, 1)
  int64_t m = int64_t(std::ldexp(f, 53));
  return normalize(Val{m, e - 53});
}

Ext from_single(uint32_t w) { return Ext{uint8_t(w >> 24), (w & 0xFFFFFF) << 8}; }
uint32_t to_single(Ext x) { return uint32_t(x.exp) << 24 | x.man >> 8; }

Ext from_short(uint16_t bits) {
  int e = int(bits >> 12 & 0xF);
  if (e >= 8) e -= 16;
  if (e == -8) return kZero;
  int32_t f = bits & 0x7FF;
  int32_t m = (bits & 0x800) ? f - 4096 : f + 2048;  // 12-bit mantissa
  return Ext{uint8_t(int8_t(e)), uint32_t(m << 20) ^ 0x80000000u};
}

Res from_int(int32_t i) { return normalize(Val{i, 0}); }

int32_t fix(Ext x, bool* overflow) {
  *overflow = false;
  if (is_zero(x)) return 0;
  int e = exp_of(x);
  if (e > 30) {
    *overflow = true;
    return is_negative(x) ? std::numeric_limits<int32_t>::min() : std::numeric_limits<int32_t>::max();
  }
  return int32_t(shr(sm(x), 31 - e));
}

Res add(Ext a, Ext b) {
  Val x = val(a), y = val(b);
  if (x.m == 0) return normalize(y);
  if (y.m == 0) return normalize(x);
  if (x.e < y.e) std::swap(x, y);
  constexpr int G = 40;  // guard bits: the result is still exactly truncated
  int d = x.e - y.e;
  i128 big = x.m << G;
  i128 small = d <= G ? y.m << (G - d) : shr(y.m, d - G);
  return normalize(Val{big + small, x.e - G});
}

Res neg(Ext a) {
  Val x = val(a);
  x.m = -x.m;
  return normalize(x);
}

Res sub(Ext a, Ext b) {
  Val y = val(b);
  if (y.m == 0) return normalize(val(a));
  Val x = val(a);
  y.m = -y.m;
  if (x.m == 0) return normalize(y);
  if (x.e < y.e) std::swap(x, y);
  constexpr int G = 40;
  int d = x.e - y.e;
  i128 big = x.m << G;
  i128 small = d <= G ? y.m << (G - d) : shr(y.m, d - G);
  return normalize(Val{big + small, x.e - G});
}

Res abs(Ext a) { return is_negative(a) ? neg(a) : normalize(val(a)); }

Res mul(Ext a, Ext b) {
  if (is_zero(a) || is_zero(b)) return {};
  // Operands truncated to single precision: 25-bit mantissas.
  int64_t ma = sm(a) >> 8, mb = sm(b) >> 8;
  return normalize(Val{i128(ma) * mb, (exp_of(a) - 23) + (exp_of(b) - 23)});
}

Res rcp(Ext a) {
  if (is_zero(a)) {
    Res r;
    r.overflow = true;
    r.v = Ext{0x7F, 0x7FFFFFFF};
    return r;
  }
  // 1/a = 2^95 / sm * 2^(31 - e - 95) (floor division toward -infinity).
  i128 num = i128(1) << 95;
  i128 d = sm(a);
  i128 q = num / d;
  if ((num % d != 0) && ((num < 0) != (d < 0))) --q;
  Res r = normalize(Val{q, 31 - exp_of(a) - 95});
  if (!r.overflow && !r.underflow && !is_zero(r.v)) {
    int64_t s = sm(r.v);
    s = (s >> 23) << 23;  // keep 8 fraction bits
    r.v.man = uint32_t(uint64_t(s)) ^ 0x80000000u;
  }
  return r;
}

int compare(Ext a, Ext b) {
  double x = to_double(a), y = to_double(b);
  return x < y ? -1 : x > y ? 1 : 0;
}

uint32_t to_ieee(Ext x) {
  uint32_t w = to_single(x);
  int e = int(int8_t(w >> 24));
  uint32_t s = w >> 23 & 1, f = w & 0x7FFFFF;
  if (e <= -127) return 0;  // zero and the values too small for IEEE normals
  if (!s) return uint32_t(e + 127) << 23 | f;
  if (f) return 0x80000000u | uint32_t(e + 127) << 23 | ((0x800000 - f) & 0x7FFFFF);
  if (e == 127) return 0xFF800000u;  // the most negative value: -infinity
  return 0x80000000u | uint32_t(e + 128) << 23;
}

Res from_ieee(uint32_t w) {
  Res r;
  uint32_t e8 = w >> 23 & 0xFF, s = w >> 31, f = w & 0x7FFFFF;
  if (e8 == 255) {  // NaN and infinity: saturate, signal overflow
    r.overflow = true;
    r.v = s ? Ext{0x7F, 0x80000000} : Ext{0x7F, 0x7FFFFF00};
    return r;
  }
  if (e8 == 0) return r;  // zeros and denormals
  if (!s) {
    r.v = Ext{uint8_t(int8_t(int(e8) - 127)), f << 8};
  } else if (f) {
    r.v = Ext{uint8_t(int8_t(int(e8) - 127)), 0x80000000u | (((0x800000 - f) & 0x7FFFFF) << 8)};
  } else {
    r.v = Ext{uint8_t(int8_t(int(e8) - 128)), 0x80000000u};
  }
  return r;
}

}  // namespace fp

}  // namespace ldc::c40sim
