/* ldc: sfc_shapes.sfc, a sequential function chart as C (paper 001). */
#include <stdint.h>
#include <string.h>
#include <math.h>

typedef unsigned char u8;
static inline int32_t rd_i(const u8 *m, uint32_t a) { int32_t v; memcpy(&v, m + a, 4); return v; }
static inline float rd_f(const u8 *m, uint32_t a) { float v; memcpy(&v, m + a, 4); return v; }
static inline void wr_i(u8 *m, uint32_t a, int32_t v) { memcpy(m + a, &v, 4); }
static inline void wr_f(u8 *m, uint32_t a, float v) { memcpy(m + a, &v, 4); }
static inline float f_of(uint32_t u) { float f; memcpy(&f, &u, 4); return f; }
/* a NaN result r of x op y (a function: y = x): the first NaN operand quieted, else the
   default NaN (docs/il.md "NaN results", typed::nan_rule); the C compiler may swap x and y */
static inline float ldc_nanf(float r, float x, float y) {
  uint32_t u;
  if (r == r) return r;
  if (x == x) x = y;
  if (x == x) u = 0xffc00000u; else { memcpy(&u, &x, 4); u |= 0x00400000u; }
  memcpy(&r, &u, 4);
  return r;
}
static inline int32_t r2i(float f) {
  if (f != f) return 0;
  if (f >= 2147483648.0f) return INT32_MAX;
  if (f < -2147483648.0f) return INT32_MIN;
  return (int32_t)f;
}
static inline int32_t i_add(int32_t a, int32_t b) { return (int32_t)((uint32_t)a + (uint32_t)b); }
static inline int32_t i_sub(int32_t a, int32_t b) { return (int32_t)((uint32_t)a - (uint32_t)b); }
static inline int32_t i_mul(int32_t a, int32_t b) { return (int32_t)((uint32_t)a * (uint32_t)b); }
static inline int32_t i_shl(int32_t a, int32_t n) { return n < 0 || n > 31 ? 0 : (int32_t)((uint32_t)a << n); }
static inline int32_t i_shr(int32_t a, int32_t n) { return n < 0 || n > 31 ? 0 : (int32_t)((uint32_t)a >> n); }
static inline int32_t i_abs(int32_t a) { return a == INT32_MIN ? INT32_MIN : (a < 0 ? -a : a); }
typedef float (*realfn)(float);
static inline float call_fn(const u8 *m, int32_t slot, float x) { realfn f; memcpy(&f, m + slot, sizeof f); return f(x); }
static inline int32_t adv(int32_t et, int32_t dt, int32_t pt) {
  if (et >= pt) return pt;
  int64_t s = (int64_t)et + dt;
  return s > pt ? pt : (int32_t)s;
}
static inline int32_t pre(int32_t pt) { return pt < 0 ? 0 : pt; }
static inline void ton(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in) {
    int32_t et = m[ti] ? adv(rd_i(m, tw), rd_i(m, 0), pt) : 0;
    wr_i(m, tw, et);
    m[tq] = et >= pt;
  } else {
    wr_i(m, tw, 0);
    m[tq] = 0;
  }
  m[ti] = (u8)in;
}
static inline void tof(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in) { m[tq] = 1; wr_i(m, tw, 0); }
  else if (m[ti]) { wr_i(m, tw, 0); m[tq] = pt > 0; }
  else if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et < pt; }
  m[ti] = (u8)in;
}
static inline void tp(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); if (et >= pt) m[tq] = 0; }
  else if (in && !m[ti]) { m[tq] = pt > 0; wr_i(m, tw, 0); }
  else if (!in) wr_i(m, tw, 0);
  m[ti] = (u8)in;
}
static inline void mton(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (!in || !m[ti]) { wr_i(m, tw, 0); m[tq] = 0; }
  else if (!m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et >= pt; }
  m[ti] = (u8)in;
}
static inline void mtof(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in || m[ti]) { m[tq] = 1; wr_i(m, tw, 0); }
  else if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et < pt; }
  m[ti] = (u8)in;
}
static inline void mtp(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); if (et >= pt) m[tq] = 0; }
  else if (in && !m[ti]) { m[tq] = 1; wr_i(m, tw, 0); }
  if (!m[tq] && !in) wr_i(m, tw, 0);
  m[ti] = (u8)in;
}
static inline void ctu(u8 *m, uint32_t cw, uint32_t cq, uint32_t e, int32_t pv, int in) {
  int32_t cv = rd_i(m, cw);
  if (in && !m[e] && cv != INT32_MAX) cv++;
  wr_i(m, cw, cv);
  m[cq] = cv >= pv;
  m[e] = (u8)in;
}
static inline void ctd(u8 *m, uint32_t cw, uint32_t cq, uint32_t e, int32_t pv, int in) {
  (void)pv;
  int32_t cv = rd_i(m, cw);
  if (in && !m[e] && cv != INT32_MIN) cv--;
  wr_i(m, cw, cv);
  m[cq] = cv <= 0;
  m[e] = (u8)in;
}

void ldc_scan(u8 *m) {
  int s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11, s12, s13, s14, s15, s16, s17, s18, s19, s20, s21, s22, s23, s24, s25, s26, s27, s28, s29, s30, s31;
  if (m[65u]) {  /* first scan */
    m[16664u] = 1; m[16678u] = 1; /* enter Wait */
  }
  m[16671u] = m[16664u];
  m[16672u] = m[16665u];
  m[16673u] = m[16666u];
  m[16677u] = m[16670u];
  int step_status = m[16664u] ? 0 : m[16665u] ? 1 : m[16666u] ? 2 : m[16670u] ? 6 : -1;
  switch (step_status) {
  case 0: { /* step Wait, line 9 */
    if (m[16678u]) {  /* P: on the step's first scan */
      /* rung, line 12 */
      /* LOADP X0 E0 */
      s0 = (m[80u] && !m[80720u]);
      m[80720u] = m[80u];
      /* ADD D0 1 D0 */
      if (s0) { wr_i(m, 41808u, i_add(rd_i(m, 41808u), (1))); }
    }
    m[16678u] = 0;
    /* transition, line 14: go OR D0 >= 3 */
    /* LOAD X0 */
    s0 = m[80u];
    /* LDGE D0 3 */
    s1 = (rd_i(m, 41808u) >= (3));
    /* ORBLK */
    s0 |= s1;
    if (s0) {
      m[16664u] = 0;
      m[16665u] = 1; m[16679u] = 1; /* enter Choose */
      break;
    }
    break;
  }
  case 1: { /* step Choose, line 15 */
    if (m[16679u]) { wr_i(m, 78692u, 0); m[32853u] = 0; m[33365u] = 0; }  /* T5: time in the step */
    ton(m, 78692u, 32853u, 33365u, 2147483647, 1);
    m[16465u] = 1;  /* SET M1 */
    m[16679u] = 0;
    /* transition, line 20: X1 AND T5 >= 1s */
    /* LOAD X1 */
    s0 = m[81u];
    /* LDGE T5 1000 */
    s1 = (rd_i(m, 78692u) >= (1000));
    /* ANDBLK */
    s0 &= s1;
    if (s0) {
      m[16665u] = 0;
      m[16664u] = 1; m[16678u] = 1; /* enter Wait */
      break;
    }
    /* transition, line 23: NOT (X2 OR X3) */
    /* LOADN X2 */
    s0 = !m[82u];
    /* ANDN X3 */
    s0 &= !m[83u];
    if (s0) {
      m[16665u] = 0;
      m[16666u] = 1; /* enter parallel_line_24 */
      m[16667u] = 1; m[16681u] = 1; /* enter Left */
      m[16669u] = 1; m[16683u] = 1; /* enter Right */
      break;
    }
    /* transition, line 45: X2 */
    /* LOAD X2 */
    s0 = m[82u];
    if (s0) {
      m[16665u] = 0;
      m[16670u] = 1; m[16684u] = 1; /* enter Last */
      break;
    }
    break;
  }
  case 2: { /* simultaneous sequence parallel_line_24, line 24 */
    /* branch */
    m[16674u] = m[16667u];
    m[16675u] = m[16668u];
    int branch1 = m[16667u] ? 3 : m[16668u] ? 4 : -1;
    switch (branch1) {
    case 3: { /* step Left, line 26 */
      m[16681u] = 0;
      /* N: every scan while active */
      /* rung, line 28 */
      /* LOADP X4 E1 */
      s0 = (m[84u] && !m[80721u]);
      m[80721u] = m[84u];
      /* OUT Y1 */
      m[8273u] = (u8)s0;
      /* transition, line 32: X5 */
      /* LOAD X5 */
      s0 = m[85u];
      if (s0) {
        m[16667u] = 0;
        m[16668u] = 1; m[16682u] = 1; /* enter LeftDone */
        break;
      }
      break;
    }
    case 4: { /* step LeftDone, line 33 */
      m[16682u] = 0;
      break;
    }
    default:
      break;
    }
    /* branch */
    m[16676u] = m[16669u];
    int branch2 = m[16669u] ? 5 : -1;
    switch (branch2) {
    case 5: { /* step Right, line 35 */
      m[16683u] = 0;
      /* N: every scan while active */
      /* rung, line 37 */
      /* LOAD X6 */
      s0 = m[86u];
      /* JMP sfcb2_SKIP */
      if (s0) goto lbl_sfcb2_SKIP;
lbl_sfcb2_SKIP:;
      /* rung, line 40 */
      /* LOADF X7 E2 */
      s0 = (!m[87u] && m[80722u]);
      m[80722u] = m[87u];
      /* OUT Y2 */
      m[8274u] = (u8)s0;
      break;
    }
    default:
      break;
    }
    /* transition, line 43: TRUE */
    /* TRUE */
    s0 = 1;
    if (s0 && branch1 == 4 && branch2 == 5) {
      m[16666u] = 0;
      m[16668u] = 0;
      m[16669u] = 0;
      m[16670u] = 1; m[16684u] = 1; /* enter Last */
      break;
    }
    break;
  }
  case 6: { /* step Last, line 47 */
    m[16465u] = 0;  /* RST M1 */
    m[16684u] = 0;
    break;
  }
  default:
    break;
  }
  m[8272u] = m[16664u] | m[16665u];  /* N Y0 */
  (void)s0;
}
