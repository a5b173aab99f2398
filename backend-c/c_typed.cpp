// backend-c/c_typed.cpp -- typed instructions as C (c_typed.h).  Every value
// is a C variable of its type's C type (types.def: int16_t for INT ...); the
// arithmetic that C leaves undefined (signed overflow, a shift by the width or
// more, division by zero, INT_MIN / -1, an out-of-range float to integer
// conversion) is written so that it is defined and gives ir/typed.h's result:
// wrapping arithmetic in the unsigned type of the width, explicit tests, and
// the conversions through ldc_to_i64.  A narrowing conversion to a signed type
// is implementation-defined in C (not undefined); every C compiler ldc runs
// with (gcc, clang) wraps it modulo 2^width, which is typed.h's norm.
#include "backend-c/c_typed.h"

#include <cinttypes>
#include <cstdio>
#include <limits>

#include "ir/typed.h"

namespace ldc {
namespace {

const char kTypedPrelude[] = R"(/* typed instructions (ir/typed.h) */
static inline double d_of(uint64_t u) { double d; memcpy(&d, &u, 8); return d; }
/* a NaN result r of x op y (a function: y = x), as ldc_nanf (the common prelude) in double */
static inline double ldc_nand(double r, double x, double y) {
  uint64_t u;
  if (r == r) return r;
  if (x == x) x = y;
  if (x == x) u = 0xfff8000000000000ull; else { memcpy(&u, &x, 8); u |= 0x0008000000000000ull; }
  memcpy(&r, &u, 8);
  return r;
}
/* a constant the C compiler must not fold into a libm call (its folding may round otherwise) */
static inline double opq_d(double x) { volatile double v = x; return v; }
/* NaN and values outside INT64 give INT64_MIN, as x86-64's cvttsd2si */
static inline int64_t ldc_to_i64(double d) {
  if (!(d >= -9223372036854775808.0 && d < 9223372036854775808.0)) return INT64_MIN;
  return (int64_t)d;
}
/* MatIEC's __real_round: the nearest integer, an exact tie to even (IN + 0.5 rounded in double first) */
static inline int64_t ldc_round(double x) { return fmod(x, 1.0) == 0 ? (ldc_to_i64(x) / 2) * 2 : ldc_to_i64(x); }
/* REAL to an integer (__real_to_sint); to an unsigned type or a bit string (__real_to_uint) a negative value is 0 */
static inline int64_t ldc_r2s(double d) { return d >= 0 ? ldc_round(d + 0.5) : ldc_round(d - 0.5); }
static inline uint64_t ldc_r2u(double d) { return d >= 0 ? (uint64_t)ldc_round(d + 0.5) : 0; }
/* TIME and the dates against numbers count seconds (MatIEC's timespec tv_sec); nanoseconds here */
#define LDC_NS_S 1000000000LL
#define LDC_S_DAY 86400LL
static inline int64_t ldc_time_of(int64_t sec, int64_t nsec) { return (int64_t)((uint64_t)sec * (uint64_t)LDC_NS_S + (uint64_t)nsec); }
static inline int64_t ldc_r2time(double d) { int64_t s = ldc_to_i64(d); return ldc_time_of(s, ldc_to_i64((d - (double)s) * 1e9)); }
static inline double ldc_time2r(int64_t t) { return (double)(t / LDC_NS_S) + (double)(t % LDC_NS_S) / 1e9; }
static inline int64_t ldc_dt_date(int64_t t) { int64_t s = t / LDC_NS_S; return ldc_time_of(s - s % LDC_S_DAY - (s < 0 ? LDC_S_DAY : 0), 0); }
static inline int64_t ldc_dt_tod(int64_t t) { int64_t s = t / LDC_NS_S; return ldc_time_of(s % LDC_S_DAY + (s < 0 ? LDC_S_DAY : 0), t % LDC_NS_S); }
static inline void ldc_idx_fault(u8 *m, uint32_t at, uint64_t i) {
  uint32_t one = 1;
  memcpy(m + 8, &one, 4);
  memcpy(m + 12, &at, 4);
  memcpy(m + 16, &i, 8);
}
)";

const char kStringPrelude[] = R"(/* STRING (ir/typed.h "strings", docs/il.md "Strings"): 33 cells, the length
   read as a UINT32 clamped to 126; a result built whole, stored with zeros after it */
#include <stdio.h>
#include <stdlib.h>
typedef struct { uint32_t len; uint8_t b[126]; } ldc_str;
static inline ldc_str ldc_sld(const u8 *m, uint32_t a) {
  ldc_str s; uint32_t n; memcpy(&n, m + a, 4); s.len = n > 126 ? 126 : n; memcpy(s.b, m + a + 4, s.len); return s;
}
static inline void ldc_sst(u8 *m, uint32_t a, const ldc_str *s) {
  uint32_t n = s->len > 126 ? 126 : s->len; memcpy(m + a, &n, 4); memcpy(m + a + 4, s->b, n); memset(m + a + 4 + n, 0, 128 - n);
}
static inline void ldc_sapp(ldc_str *r, const uint8_t *b, int64_t n) {
  int64_t room = 126 - (int64_t)r->len;
  if (n <= 0) return;
  if (n > room) n = room;
  memcpy(r->b + r->len, b, (size_t)n); r->len += (uint32_t)n;
}
static inline int ldc_scmp(const u8 *m, uint32_t a, uint32_t b) {
  ldc_str x = ldc_sld(m, a), y = ldc_sld(m, b);
  int c = memcmp(x.b, y.b, x.len < y.len ? x.len : y.len);
  if (c) return c < 0 ? -1 : 1;
  return x.len > y.len ? 1 : x.len < y.len ? -1 : 0;
}
static inline void ldc_smove(u8 *m, uint32_t d, uint32_t a) { ldc_str s = ldc_sld(m, a); ldc_sst(m, d, &s); }
static inline void ldc_sleft(u8 *m, uint32_t d, uint32_t a, int64_t l, int right, u8 *s0) {
  ldc_str s = ldc_sld(m, a), r = {0};
  if (l < 0) { *s0 = 1; ldc_sst(m, d, &r); return; }
  if (l > (int64_t)s.len) l = s.len;
  ldc_sapp(&r, right ? s.b + (s.len - (uint32_t)l) : s.b, l);
  ldc_sst(m, d, &r);
}
static inline void ldc_smid(u8 *m, uint32_t d, uint32_t a, int64_t l, int64_t p, u8 *s0) {
  ldc_str s = ldc_sld(m, a), r = {0};
  int64_t i;
  if (l < 0 || p < 0) { *s0 = 1; ldc_sst(m, d, &r); return; }
  if (p <= (int64_t)s.len) {
    p -= 1;
    if (l > (int64_t)s.len - p) l = (int64_t)s.len - p;
    if (l > 126) l = 126;
    for (i = 0; i < l; i++) r.b[i] = p + i < 0 ? (uint8_t)s.len : s.b[p + i];
    r.len = (uint32_t)l;
  }
  ldc_sst(m, d, &r);
}
static inline void ldc_sconcat(u8 *m, uint32_t d, uint32_t a, uint32_t b) {
  ldc_str x = ldc_sld(m, a), y = ldc_sld(m, b);
  ldc_sapp(&x, y.b, y.len); ldc_sst(m, d, &x);
}
static inline uint32_t ldc_shead(uint32_t p8, uint32_t len) { return p8 > len ? len : p8 == 0 ? 0 : p8 - 1; }
static inline void ldc_sinsert(u8 *m, uint32_t d, uint32_t a, uint32_t b, int64_t p, u8 *s0) {
  ldc_str x = ldc_sld(m, a), y = ldc_sld(m, b), r = {0};
  uint32_t head;
  if (p < 0) { *s0 = 1; ldc_sst(m, d, &r); return; }
  head = (uint8_t)p > x.len ? x.len : (uint8_t)p;
  ldc_sapp(&r, x.b, head); ldc_sapp(&r, y.b, y.len); ldc_sapp(&r, x.b + head, x.len - head);
  ldc_sst(m, d, &r);
}
static inline void ldc_sdelete(u8 *m, uint32_t d, uint32_t a, int64_t l, int64_t p, u8 *s0) {
  ldc_str s = ldc_sld(m, a), r = {0};
  uint32_t l8, head;
  if (l < 0 || p < 0) { *s0 = 1; ldc_sst(m, d, &r); return; }
  l8 = (uint8_t)l; head = ldc_shead((uint8_t)p, s.len);
  ldc_sapp(&r, s.b, head);
  if (s.len > head + l8) ldc_sapp(&r, s.b + head + l8, s.len - head - l8);
  ldc_sst(m, d, &r);
}
static inline void ldc_sreplace(u8 *m, uint32_t d, uint32_t a, uint32_t b, int64_t l, int64_t p, u8 *s0) {
  ldc_str x = ldc_sld(m, a), y = ldc_sld(m, b), r = {0};
  uint32_t l8, head, from;
  if (l < 0 || p < 0) { *s0 = 1; ldc_sst(m, d, &r); return; }
  l8 = (uint8_t)l; head = ldc_shead((uint8_t)p, x.len);
  ldc_sapp(&r, x.b, head);
  ldc_sapp(&r, y.b, y.len < l8 ? y.len : l8);
  from = (uint8_t)(head + l8);
  if (r.len < 126 && from < x.len) ldc_sapp(&r, x.b + from, x.len - from);
  ldc_sst(m, d, &r);
}
static inline uint64_t ldc_sfind(const u8 *m, uint32_t a, uint32_t b) {
  ldc_str x = ldc_sld(m, a), y = ldc_sld(m, b);
  uint32_t c1 = 0, c2 = 0;
  if (!(y.len > 0 && x.len >= y.len)) return 0;
  while (c1 + c2 < x.len && c2 < y.len) {
    if (x.b[c1 + c2] != y.b[c2]) c1 += c2 + 1, c2 = 0;
    else c2++;
  }
  return c2 == y.len ? c1 + 1 : 0;
}
/* snprintf(body, STR_MAX_LEN, ...), len cut at 126, as MatIEC's __*_to_string */
static inline void ldc_sdone(u8 *m, uint32_t d, const char *buf, int n) {
  ldc_str r = {0};
  r.len = n < 0 ? 0 : n > 126 ? 126 : (uint32_t)n;
  memcpy(r.b, buf, r.len);
  ldc_sst(m, d, &r);
}
#define LDC_SPRINTF(m, d, ...) do { char buf_[127] = {0}; int n_ = snprintf(buf_, 126, __VA_ARGS__); ldc_sdone(m, d, buf_, n_); } while (0)
static inline void ldc_time_str(u8 *m, uint32_t d, int64_t ns) {
  int32_t sec = (int32_t)(uint32_t)(uint64_t)(ns / LDC_NS_S);
  int64_t nsec = ns % LDC_NS_S;
  int days = sec / 86400, drem = sec % 86400, hours = drem / 3600, hrem = drem % 3600, mins = hrem / 60, mrem = hrem % 60;
  if (!drem && nsec == 0) LDC_SPRINTF(m, d, "T#%dd", days);
  else if (!hrem && nsec == 0) LDC_SPRINTF(m, d, "T#%dd%dh", days, hours);
  else if (!mrem && nsec == 0) LDC_SPRINTF(m, d, "T#%dd%dh%dm", days, hours, mins);
  else if (nsec == 0) LDC_SPRINTF(m, d, "T#%dd%dh%dm%ds", days, hours, mins, mrem);
  else LDC_SPRINTF(m, d, "T#%dd%dh%dm%ds%gms", days, hours, mins, mrem, (double)nsec / 1000000);
}
/* MatIEC's convert_seconds_to_date_and_time and __date/_tod/_dt_to_string (ir/typed.h) */
static inline int ldc_leap(int y) { return y % 4 == 0 && (y % 100 != 0 || y % 400 == 0); }
static inline void ldc_date_str(u8 *m, uint32_t d, int64_t ns, int kind) { /* 0 DATE, 1 TOD, 2 DT */
  static const unsigned short yd[2][13] = {{0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334, 365},
                                           {0, 31, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335, 366}};
  int64_t sec = ns / LDC_NS_S, nsec = ns % LDC_NS_S, days = sec / 86400, rem = sec % 86400;
  int hour, min, s, year = 1970, mon = 1, day;
  double frac;
  if (rem < 0) { rem += 86400; days--; }
  hour = (int)(rem / 3600); rem %= 3600; min = (int)(rem / 60); s = (int)(rem % 60);
  while (days >= (rem = ldc_leap(year) ? 366 : 365)) { year++; days -= rem; }
  while (days < 0) { year--; days += ldc_leap(year) ? 366 : 365; }
  while (days >= yd[ldc_leap(year)][mon]) mon += 1;
  day = (int)(days - yd[ldc_leap(year)][mon - 1] + 1);
  frac = (double)s + (double)nsec / 1e9;
  if (kind == 0) LDC_SPRINTF(m, d, "D#%d-%2.2d-%2.2d", year, mon, day);
  else if (kind == 1 && sec >= 86400) LDC_SPRINTF(m, d, "TOD#ERROR");
  else if (kind == 1 && nsec == 0) LDC_SPRINTF(m, d, "TOD#%2.2d:%2.2d:%2.2d", hour, min, s);
  else if (kind == 1) LDC_SPRINTF(m, d, "TOD#%2.2d:%2.2d:%09.6f", hour, min, frac);
  else if (nsec == 0) LDC_SPRINTF(m, d, "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%2.2d", year, mon, day, hour, min, s);
  else LDC_SPRINTF(m, d, "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%09.6f", year, mon, day, hour, min, frac);
}
/* __pstring_to_sint with x86-64's C (ir/typed.h str_to_lint) */
static inline uint64_t ldc_s2lint(const ldc_str *s) {
  const uint8_t *b = s->b;
  uint32_t n = s->len, l;
  uint64_t res = 0, sign, fac;
  unsigned shift = 0;
  if (n < 1) return 0;
  if (n > 1 && (b[0] == '2' || b[0] == '8') && b[1] == '#') {
    unsigned bits = b[0] == '2' ? 1 : 3;
    uint8_t top = b[0] == '2' ? '1' : '7';
    for (l = n - 1; l >= 2 && shift < 64; l--)
      if (b[l] >= '0' && b[l] <= top) { res |= (uint64_t)(int64_t)(int32_t)((uint32_t)(b[l] - '0') << (shift & 31)); shift += bits; }
    return res;
  }
  if (n > 2 && b[0] == '1' && b[1] == '6' && b[2] == '#') {
    for (l = n - 1; l >= 3 && shift < 64; l--) {
      uint8_t c = b[l];
      int dg = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (dg >= 0) { res |= (uint64_t)dg << shift; shift += 4; }
    }
    return res;
  }
  sign = b[0] == '-' ? ~(uint64_t)0 : 1;
  fac = sign;
  for (l = n; l > 0 && shift < 20; l--) {
    uint8_t c = b[l - 1];
    if (c >= '0' && c <= '9') { res += (uint64_t)(c - '0') * fac; fac *= 10; shift++; }
    else if (c >= '.') { res = 0; fac = sign; shift = 0; }
  }
  return res;
}
static inline int ldc_sdot(const ldc_str *s) { uint32_t l = s->len; while (l > 0 && s->b[--l] != '.') {} return l != 0; }
static inline double ldc_s2real(const ldc_str *s) {
  char buf[127] = {0};
  if (!ldc_sdot(s)) return (double)(int64_t)ldc_s2lint(s);
  memcpy(buf, s->b, s->len);
  return strtod(buf, 0);
}
static inline uint8_t ldc_s2bool(const ldc_str *s) {
  int i;
  if (s->len == 1) return s->b[0] == '1';
  if (s->len != 4) return 0;
  for (i = 0; i < 4; i++) if ((s->b[i] >= 'a' && s->b[i] <= 'z' ? s->b[i] - 32 : s->b[i]) != "TRUE"[i]) return 0;
  return 1;
}
static inline int64_t ldc_s2time(const ldc_str *s) {
  if (!ldc_sdot(s)) return ldc_time_of((int64_t)ldc_s2lint(s), 0);
  return ldc_time_of(ldc_to_i64(ldc_s2real(s)), 0);
}
)";

const char* ct(Ty t) { return ty_info(t).c; }
const char* ut(Ty t) { return ty_info(t).bits <= 32 ? "uint32_t" : "uint64_t"; }
std::string tn(Ty t) { return ty_info(t).name; }
std::string u32(uint64_t v) { return std::to_string(v) + "u"; }
bool is_real(Ty t) { return typed::is_real(t); }
bool is_signed(Ty t) { return typed::is_signed(t); }

// Typed constant v (canonical bits) as a C expression of t's C type.
std::string literal(Ty t, uint64_t v) {
  char b[64];
  if (t == Ty::BOOL) return v ? "((uint8_t)1)" : "((uint8_t)0)";
  if (t == Ty::REAL) { std::snprintf(b, sizeof b, "f_of(0x%08" PRIx32 "u)", uint32_t(v)); return b; }
  if (t == Ty::LREAL) { std::snprintf(b, sizeof b, "d_of(0x%016" PRIx64 "ull)", v); return b; }
  if (is_signed(t)) {
    int64_t x = int64_t(v);
    if (x == std::numeric_limits<int64_t>::min()) return std::string("((") + ct(t) + ")INT64_MIN)";
    std::snprintf(b, sizeof b, "((%s)%" PRId64 "LL)", ct(t), x);
    return b;
  }
  std::snprintf(b, sizeof b, "((%s)%" PRIu64 "ull)", ct(t), v);
  return b;
}

class Typed {
 public:
  Typed(const Instr& in, const Layout& L, int64_t at) : in_(in), L_(L), at_(at), t_(in.ty), u_(in.src) {}

  CTyped run() {
    const Op op = in_.op;
    const OpInfo& oi = op_info(op);
    if (typed::is_string_instr(op, t_, u_)) return string();
    if (oi.push) return {true, "(" + val(0, t_) + " " + rel_info(oi.rel).c + " " + val(1, t_) + ")"};
    switch (op) {
      case Op::TMOVE: return body(st(1, val(0, t_)));
      case Op::TADD: case Op::TSUB: case Op::TMUL: return body(add_sub_mul());
      case Op::TDIV: case Op::TMOD: return body(div_mod());
      case Op::TMIN: case Op::TMAX:
        return body("{ " + decl2() + " " + st(2, std::string("b_ ") + (op == Op::TMIN ? "<" : ">") + " a_ ? b_ : a_") + " }");
      case Op::TEXPT: {  // pow in double, a NaN by the rule, then REAL's rounding
        const std::string call = "{ double x_ = " + dbl(0) + ", y_ = " + dbl(1) + "; ";
        return body(call + st(2, std::string(t_ == Ty::REAL ? "(float)" : "") + "ldc_nand(pow(x_, y_), x_, y_)") + " }");
      }
      case Op::TAND: case Op::TOR: case Op::TXOR: {
        const char* o = op == Op::TAND ? " & " : op == Op::TOR ? " | " : " ^ ";
        return body(st(2, cast(t_) + "(" + val(0, t_) + o + val(1, t_) + ")"));
      }
      case Op::TNOT:
        if (t_ == Ty::BOOL) return body(st(1, "(uint8_t)(" + val(0, t_) + " ^ 1)"));
        return body(st(1, cast(t_) + "~(" + ut(t_) + ")" + val(0, t_)));
      case Op::TSHL: case Op::TSHR: case Op::TROL: case Op::TROR: return body(shift());
      case Op::TNEG:
        if (is_real(t_)) return body(st(1, "-" + val(0, t_)));
        return body(st(1, wrap("0 - (" + std::string(ut(t_)) + ")" + val(0, t_))));
      case Op::TABS:
        if (is_real(t_))  // MatIEC's __abs_signed: ABS(-0.0) stays -0.0
          return body("{ " + std::string(ct(t_)) + " a_ = " + val(0, t_) + "; " + st(1, "a_ < 0 ? -a_ : a_") + " }");
        if (!is_signed(t_)) return body(st(1, val(0, t_)));
        return body("{ " + std::string(ct(t_)) + " a_ = " + val(0, t_) + "; " +
                    st(1, "a_ < 0 ? " + wrap("0 - (" + std::string(ut(t_)) + ")a_") + " : a_") + " }");
      case Op::TSQRT: case Op::TLN: case Op::TLOG: case Op::TEXP: case Op::TSIN: case Op::TCOS: case Op::TTAN:
      case Op::TASIN: case Op::TACOS: case Op::TATAN: {
        // MatIEC calls the C library's double function; REAL's result is rounded
        // (a NaN by the rule, in double: the same bits as in REAL once rounded)
        const std::string call = "ldc_nand(" + std::string(libm(op)) + "(x_), x_, x_)";
        return body("{ double x_ = " + dbl(0) + "; " + st(1, t_ == Ty::REAL ? "(float)" + call : call) + " }");
      }
      case Op::TCONV: return body(st(1, conv(t_, u_, val(0, u_))));
      case Op::TTRUNC: return body(st(1, cast(t_) + "ldc_to_i64(trunc((double)" + val(0, u_) + "))"));
      case Op::TIDX: return body(idx());
      case Op::TLDX: return body(st(2, "ld_" + tn(t_) + "(m, " + element(0, 1) + ")"));
      case Op::TSTX: return body("st_" + tn(t_) + "(m, " + element(1, 2) + ", " + val(0, t_) + ");");
      default: break;
    }
    throw CompileError(in_.loc.line, in_.loc.col, std::string("the C route has no translation for ") + op_spelling(in_));
  }

 private:
  const Instr& in_;
  const Layout& L_;
  int64_t at_;
  Ty t_, u_;

  static CTyped body(std::string s) { return {false, std::move(s)}; }
  std::string a(int i) const { return u32(addr(in_.a[i])); }
  // an integer operand as int64_t (a length, a position)
  std::string i64(int i, Ty t) const { return "(int64_t)" + val(i, t); }
  // The string section (ir/typed.h "strings"): the prelude's ldc_s* routines.
  CTyped string() const {
    const std::string m = "m", e = "&" + s0();
    switch (in_.op) {
      case Op::TEQ: case Op::TNE: case Op::TLT: case Op::TLE: case Op::TGT: case Op::TGE:
        return {true, "(ldc_scmp(m, " + a(0) + ", " + a(1) + ") " + rel_info(op_info(in_.op).rel).c + " 0)"};
      case Op::TARGS: return body("sl_ = " + i64(0, t_) + "; sp_ = " + i64(1, t_) + ";");
      case Op::TMOVE: return body("ldc_smove(m, " + a(1) + ", " + a(0) + ");");
      case Op::TLEN: return body(st(1, cast(t_) + "ldc_sld(m, " + a(0) + ").len"));
      case Op::TFIND: return body(st(2, cast(t_) + "ldc_sfind(m, " + a(0) + ", " + a(1) + ")"));
      case Op::TLEFT: case Op::TRIGHT:
        return body("ldc_sleft(m, " + a(2) + ", " + a(0) + ", " + i64(1, u_) + ", " + (in_.op == Op::TRIGHT ? "1" : "0") + ", " + e + ");");
      case Op::TCONCAT: return body("ldc_sconcat(m, " + a(2) + ", " + a(0) + ", " + a(1) + ");");
      case Op::TMID: return body("ldc_smid(m, " + a(1) + ", " + a(0) + ", sl_, sp_, " + e + ");");
      case Op::TDELETE: return body("ldc_sdelete(m, " + a(1) + ", " + a(0) + ", sl_, sp_, " + e + ");");
      case Op::TINSERT: return body("ldc_sinsert(m, " + a(2) + ", " + a(0) + ", " + a(1) + ", sp_, " + e + ");");
      case Op::TREPLACE: return body("ldc_sreplace(m, " + a(2) + ", " + a(0) + ", " + a(1) + ", sl_, sp_, " + e + ");");
      case Op::TCONV: return body(t_ == Ty::STRING ? to_string() : from_string());
      default: break;
    }
    throw CompileError(in_.loc.line, in_.loc.col, std::string("the C route has no translation for ") + op_spelling(in_));
  }
  // CONV.STRING.U: MatIEC's U_TO_STRING formats
  std::string to_string() const {
    const std::string d = a(1), v = val(0, u_);
    switch (ty_info(u_).kind) {
      case TyKind::Bool: return "if (" + v + ") LDC_SPRINTF(m, " + d + ", \"TRUE\"); else LDC_SPRINTF(m, " + d + ", \"FALSE\");";
      case TyKind::Bits: return "LDC_SPRINTF(m, " + d + ", \"16#%llx\", (unsigned long long)" + v + ");";
      case TyKind::Signed: return "LDC_SPRINTF(m, " + d + ", \"%lld\", (long long)" + v + ");";
      case TyKind::Unsigned: return "LDC_SPRINTF(m, " + d + ", \"%llu\", (unsigned long long)" + v + ");";
      case TyKind::Real: return "LDC_SPRINTF(m, " + d + ", \"%.10g\", (double)" + v + ");";
      case TyKind::Time: return "ldc_time_str(m, " + d + ", " + v + ");";
      case TyKind::Date:
        return "ldc_date_str(m, " + d + ", " + v + ", " + (u_ == Ty::DATE ? "0" : u_ == Ty::TOD ? "1" : "2") + ");";
      default: break;
    }
    throw CompileError(in_.loc.line, in_.loc.col, std::string("the C route has no translation for ") + op_spelling(in_));
  }
  // CONV.T.STRING: MatIEC's STRING_TO_T
  std::string from_string() const {
    const std::string s = "{ ldc_str s_ = ldc_sld(m, " + a(0) + "); ";
    switch (ty_info(t_).kind) {
      case TyKind::Bool: return s + st(1, "ldc_s2bool(&s_)") + " }";
      case TyKind::Real: return s + st(1, cast(t_) + "ldc_s2real(&s_)") + " }";
      case TyKind::Time: case TyKind::Date: return s + st(1, "ldc_s2time(&s_)") + " }";
      default: return s + st(1, cast(t_) + "ldc_s2lint(&s_)") + " }";
    }
  }
  uint32_t addr(const Operand& o) const { return L_.addr(o.area, o.index); }
  static std::string cast(Ty t) { return std::string("(") + ct(t) + ")"; }
  std::string wrap(const std::string& e) const { return cast(t_) + "(" + e + ")"; }
  bool konst(int i) const { return in_.a[i].kind == OpdKind::ConstT; }
  // operand i, of type t, as a C expression of t's C type
  std::string val(int i, Ty t) const {
    const Operand& o = in_.a[i];
    if (o.kind == OpdKind::ConstT) return literal(t, o.bits());
    if (o.kind == OpdKind::ConstInt) return "((int32_t)" + std::to_string(o.ival) + ")";
    return "ld_" + tn(t) + "(m, " + u32(addr(o)) + ")";
  }
  // operand i as the double a libm function takes (a constant kept from folding)
  std::string dbl(int i) const {
    std::string d = "(double)" + val(i, t_);
    return konst(i) ? "opq_d(" + d + ")" : d;
  }
  std::string st(int i, const std::string& e) const {
    return "st_" + tn(t_) + "(m, " + u32(addr(in_.a[i])) + ", " + e + ");";
  }
  // the element an LDX / STX moves: base + xr * stride, in bytes
  std::string element(int base, int stride) const {
    const Operand& b = in_.a[base];
    return u32(addr(b)) + " + xr * " + u32(uint64_t(uint32_t(in_.a[stride].ival)) * L_.elem_size(b.area));
  }
  std::string decl2() const {
    return std::string(ct(t_)) + " a_ = " + val(0, t_) + ", b_ = " + val(1, t_) + ";";
  }
  std::string s0() const { return "m[" + u32(L_.addr(Area::S, kBitError)) + "]"; }

  std::string add_sub_mul() const {
    const char* o = in_.op == Op::TADD ? " + " : in_.op == Op::TSUB ? " - " : " * ";
    if (is_real(t_)) return real_arith(o);
    const std::string w = std::string("(") + ut(t_) + ")";
    return st(2, wrap(w + val(0, t_) + o + w + val(1, t_)));
  }
  // REAL / LREAL a o b, a NaN result by the rule (ldc_nanf, ldc_nand)
  std::string real_arith(const char* o) const {
    return "{ " + decl2() + " " + st(2, nan_fn() + "(a_" + o + "b_, a_, b_)") + " }";
  }
  std::string nan_fn() const { return t_ == Ty::REAL ? "ldc_nanf" : "ldc_nand"; }
  // integer division by 0: 0 and S0; MIN / -1 wraps, MIN % -1 is 0
  std::string div_mod() const {
    const bool div = in_.op == Op::TDIV;
    if (is_real(t_)) return real_arith(" / ");
    std::string q = div ? wrap("a_ / b_") : wrap("a_ % b_");
    if (is_signed(t_)) q = "b_ == -1 ? " + (div ? wrap(std::string("0 - (") + ut(t_) + ")a_") : cast(t_) + "0") + " : " + q;
    return "{ " + decl2() + " if (b_ == 0) { " + s0() + " = 1; " + st(2, cast(t_) + "0") + " } else " + st(2, q) + " }";
  }
  // shifts of T's bits by a count of type U: outside 0..width-1 everything
  // goes; rotations take the count modulo the width
  std::string shift() const {
    const std::string w = std::to_string(ty_info(t_).bits) + "u";
    const std::string neg = is_signed(u_) ? "n_ < 0" : "";
    std::string s = "{ " + std::string(ct(t_)) + " a_ = " + val(0, t_) + ", r_; " + ct(u_) + " n_ = " + val(1, u_) + "; ";
    if (in_.op == Op::TSHL || in_.op == Op::TSHR) {
      s += "if (" + (neg.empty() ? "" : neg + " || ") + "(uint64_t)n_ >= " + w + ") r_ = 0; else r_ = " +
           wrap(std::string("(") + ut(t_) + ")a_ " + (in_.op == Op::TSHL ? "<<" : ">>") + " n_") + "; ";
    } else {
      std::string k = "(uint64_t)n_ % " + w;
      if (!neg.empty()) k = neg + " ? (" + w + " - (0 - (uint64_t)n_) % " + w + ") % " + w + " : " + k;
      s += "uint64_t k_ = " + k + "; ";
      if (in_.op == Op::TROR) s += "if (k_ != 0) k_ = " + w + " - k_; ";
      s += "if (k_ == 0) r_ = a_; else r_ = " +
           wrap(std::string("((") + ut(t_) + ")a_ << k_) | ((" + ut(t_) + ")a_ >> (" + w + " - k_))") + "; ";
    }
    return s + st(2, "r_") + " }";
  }
  std::string idx() const {
    if (at_ < 0)
      throw CompileError(in_.loc.line, in_.loc.col,
                         "the C route cannot translate " + op_spelling(in_) +
                             " here: its fault record names the IL offset, which this form of C (a chart's) does not have");
    const std::string lo = std::to_string(in_.a[1].ival) + "LL", hi = std::to_string(in_.a[2].ival) + "LL";
    std::string ok;
    if (is_signed(t_)) ok = "i_ >= " + lo + " && i_ <= " + hi;
    else {
      ok = "(int64_t)i_ >= " + lo + " && (int64_t)i_ <= " + hi;
      if (ty_info(t_).bits == 64) ok = "i_ <= (uint64_t)INT64_MAX && " + ok;
    }
    return "{ " + std::string(ct(t_)) + " i_ = " + val(0, t_) + "; if (" + ok + ") xr = (uint32_t)((int64_t)i_ - " + lo +
           "); else { ldc_idx_fault(m, " + u32(uint64_t(at_)) + ", (uint64_t)i_); return; } }";
  }
  static const char* libm(Op op) {
    switch (op) {
      case Op::TSQRT: return "sqrt";
      case Op::TLN: return "log";
      case Op::TLOG: return "log10";
      case Op::TEXP: return "exp";
      case Op::TSIN: return "sin";
      case Op::TCOS: return "cos";
      case Op::TTAN: return "tan";
      case Op::TASIN: return "asin";
      case Op::TACOS: return "acos";
      default: return "atan";
    }
  }
  // MatIEC's U_TO_T (typed::conv) of a, an expression of U's C type
  static std::string conv(Ty to, Ty from, const std::string& a) {
    const TyKind fk = ty_info(from).kind, tk = ty_info(to).kind;
    const std::string c = cast(to);
    if (to == from) return a;
    if (tk == TyKind::Bool) return "(uint8_t)(" + a + " != 0)";
    if (fk == TyKind::Real) {
      if (tk == TyKind::Real) return c + a;
      if (tk == TyKind::Time || tk == TyKind::Date) return "ldc_r2time((double)" + a + ")";
      return c + (is_signed(to) ? "ldc_r2s" : "ldc_r2u") + "((double)" + a + ")";
    }
    if (fk == TyKind::Time || fk == TyKind::Date) {
      if (tk == TyKind::Real) return c + "ldc_time2r(" + a + ")";
      if (tk == TyKind::Time) return a;
      if (tk == TyKind::Date) {
        if (to == Ty::DATE && from == Ty::DT) return "ldc_dt_date(" + a + ")";
        if (to == Ty::TOD && from == Ty::DT) return "ldc_dt_tod(" + a + ")";
        return a;
      }
      return c + "(" + a + " / LDC_NS_S)";
    }
    if (tk == TyKind::Real) return c + a;
    if (tk == TyKind::Time || tk == TyKind::Date) return "(int64_t)((uint64_t)" + a + " * 1000000000u)";
    return c + a;
  }
};

// ld_T / st_T: a value of T from and to its cell (or bit): one cell holds a
// narrow value extended to 32 bits, a 64-bit one takes two (docs/il.md).
std::string load_store(Ty t) {
  const TyInfo& ti = ty_info(t);
  const std::string n = ti.name, c = ti.c;
  if (t == Ty::BOOL)
    return "static inline uint8_t ld_BOOL(const u8 *m, uint32_t a) { return m[a] != 0; }\n"
           "static inline void st_BOOL(u8 *m, uint32_t a, uint8_t v) { m[a] = v ? 1 : 0; }\n";
  std::string s = "static inline " + c + " ld_" + n + "(const u8 *m, uint32_t a) { " + c +
                  " v; memcpy(&v, m + a, sizeof v); return v; }\n";
  s += "static inline void st_" + n + "(u8 *m, uint32_t a, " + c + " v) { ";
  if (ti.cells == 2 || ti.bits == 32) return s + "memcpy(m + a, &v, sizeof v); }\n";
  return s + (is_signed(t) ? "int32_t" : "uint32_t") + " w = v; memcpy(m + a, &w, 4); }\n";
}

}  // namespace

std::string c_typed_prelude() {
  std::string s = kTypedPrelude;
  for (int i = 0; i < kTyCount; i++)
    if (Ty(i) != Ty::STRING) s += load_store(Ty(i));  // STRING: ldc_sld / ldc_sst
  return s + kStringPrelude;
}

CTyped c_typed(const Instr& in, const Layout& layout, int64_t il_offset) { return Typed(in, layout, il_offset).run(); }

}  // namespace ldc
