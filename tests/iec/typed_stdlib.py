#!/usr/bin/env python3
"""Writes typed_stdlib.expected: MatIEC's meaning of typed_stdlib.il over
typed_stdlib.csv, transcribed from MatIEC (github.com/beremiz/matiec):

  lib/counter.txt      CTU CTD CTUD and their _DINT _LINT _UDINT _ULINT forms
  lib/sema.txt         SEMA
  lib/bistable.txt     RS
  ASIN ACOS ATAN LOG   the C library (MatIEC calls asin acos atan log10; Python's math is the same libm)
  lib/rtc.txt          RTC (CURRENT_TIME: ldrun's scan clock, docs/stdlib.md)
  lib/C/iec_std_lib.h  __uint_to_bcd, __bcd_to_uint, __test_bcd
  lib/C/iec_std_functions.h  X_TO_BCD_Y := (Y)__uint_to_bcd(IN);
                       X_BCD_TO_Y: TEST_EN_COND(__test_bcd(IN)) gives 0, else (Y)__bcd_to_uint(IN)

Python integers with C's conversions (modulo 2^width); never an ldc engine.
  typed_stdlib.py          prints the expected trace
  typed_stdlib.py --check  fails if typed_stdlib.expected differs
"""
import csv, math, os, sys

HERE = os.path.dirname(os.path.abspath(__file__))
WIDTH = {"INT": 16, "DINT": 32, "LINT": 64, "UDINT": 32, "ULINT": 64, "USINT": 8, "UINT": 16,
         "BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}
SIGNED = {"INT", "DINT", "LINT"}


def c_cast(v, t):
    """C's conversion of an integer to type t (modulo 2^width)."""
    w = WIDTH[t]
    v &= (1 << w) - 1
    if t in SIGNED and v >= 1 << (w - 1):
        v -= 1 << w
    return v


def as_dint(v):
    """What --watch prints for a cell: its 32 bits as an INT32."""
    return c_cast(v, "DINT")


class RTrig:  # lib/edge_detection.txt: Q := CLK AND NOT M; M := CLK
    def __init__(self):
        self.m = False

    def __call__(self, clk):
        q = clk and not self.m
        self.m = clk
        return q


class CTU:  # lib/counter.txt
    def __init__(self, t):
        self.t, self.cv, self.q, self.cu_t = t, 0, False, RTrig()

    def __call__(self, cu, r, pv):
        e = self.cu_t(cu)
        if r:
            self.cv = 0
        elif e and self.cv < pv:
            self.cv = c_cast(self.cv + 1, self.t)
        self.q = self.cv >= pv


class CTD:
    def __init__(self, t):
        self.t, self.cv, self.q, self.cd_t = t, 0, False, RTrig()

    def __call__(self, cd, ld, pv):
        e = self.cd_t(cd)
        if ld:
            self.cv = pv
        elif e and self.cv > 0:
            self.cv = c_cast(self.cv - 1, self.t)
        self.q = self.cv <= 0


class CTUD:
    def __init__(self, t):
        self.t, self.cv, self.qu, self.qd = t, 0, False, False
        self.cd_t, self.cu_t = RTrig(), RTrig()

    def __call__(self, cu, cd, r, ld, pv):
        ed = self.cd_t(cd)
        eu = self.cu_t(cu)
        if r:
            self.cv = 0
        elif ld:
            self.cv = pv
        elif not (eu and ed):
            if eu and self.cv < pv:
                self.cv = c_cast(self.cv + 1, self.t)
            elif ed and self.cv > 0:
                self.cv = c_cast(self.cv - 1, self.t)
        self.qu = self.cv >= pv
        self.qd = self.cv <= 0


class SEMA:  # lib/sema.txt
    def __init__(self):
        self.q_internal = False

    def __call__(self, claim, release):
        self.q_internal = claim or (self.q_internal and not release)
        return self.q_internal


class RS:  # lib/bistable.txt: Q1 := NOT R1 AND (S OR Q1)
    def __init__(self):
        self.q1 = False

    def __call__(self, s, r1):
        self.q1 = not r1 and (s or self.q1)
        return self.q1


def c_round(v):
    """MatIEC's LREAL_TO_DINT: __real_round, the nearest integer, ties to even."""
    return round(v)


class RTC:  # lib/rtc.txt, times in ns
    def __init__(self):
        self.prev_in, self.offset, self.cdt, self.q = False, 0, 0, False

    def __call__(self, inp, pdt, current_time):
        if inp:
            if not self.prev_in:
                self.offset = pdt - current_time
            self.cdt = current_time + self.offset
        else:
            self.cdt = current_time
        self.q = inp
        self.prev_in = inp


def uint_to_bcd(v):
    """__uint_to_bcd: res |= (IN % 10) << shift, shift += 4.  A shift of 64 or
    more (the 17th..20th digit of a ULINT) is undefined in C; ldc's SHL gives 0
    there (docs/il.md), so those digits are dropped."""
    res, shift = v % 10, 4
    v //= 10
    while v:
        if shift < 64:
            res |= (v % 10) << shift
        v //= 10
        shift += 4
    return res


def test_bcd(v):
    while v:
        if v & 0xF > 9:
            return True
        v >>= 4
    return False


def bcd_to_uint(v):
    res, factor = v & 0xF, 10
    v >>= 4
    while v:
        res += (v & 0xF) * factor
        factor *= 10
        v >>= 4
    return res


def bcd_to(v, t):  # X_BCD_TO_Y: 0 (ENO FALSE) for an invalid digit
    return 0 if test_bcd(v) else c_cast(bcd_to_uint(v), t)


ULINT_MAX, LINT_MAX, LINT_MIN, DINT_MAX = 2**64 - 1, 2**63 - 1, -2**63, 2**31 - 1
PDT_S = 1706702400  # DT#2024-01-31-12:00:00 in seconds since 1970-01-01 (UTC)


MS, S, DAY = 10**6, 10**9, 86400 * 10**9


def time_and_date():
    """ADD_TIME ... CONCAT_DATE_TOD: __time_add / __time_sub (ns here); seen as
    ms through __time_to_real (seconds) * 1000 rounded, or as seconds through
    __time_to_int (tv_sec, toward zero)."""
    ms = lambda ns: round(ns / MS)
    sec = lambda ns: int(ns / S)  # toward zero, as a normalized timespec's tv_sec
    t_a, t_b, t_c, one_d = 1500000, 2500000, S, DAY
    tod_a, tod_b, tod_c = 86399 * S + 500 * MS, 2 * S, 43199 * S + 500 * MS
    d_a, d_b, d_c = 1709251200 * S, 1706745600 * S, 1706659200 * S  # 2024-03-01, 2024-02-01, 2024-01-31
    pdt = PDT_S * S
    return [ms(t_a + t_b), ms(t_a - t_b), ms(tod_a + t_c), ms(tod_b - t_c), ms(tod_b - tod_a), ms(pdt - (d_c + tod_c)),
            sec(d_a + tod_b), sec(d_a - d_b), sec(pdt + one_d), sec(pdt - one_d)]


def lo_hi(v):
    v &= 2**64 - 1
    return [as_dint(v), as_dint(v >> 32)]


def run():
    rows = [r for r in csv.reader(l for l in open(os.path.join(HERE, "typed_stdlib.csv")) if not l.startswith("#"))]
    head, rows = rows[0], rows[1:]
    counters = {
        "u_ulint": (CTU("ULINT"), ULINT_MAX), "u_int": (CTU("INT"), 2), "u_neg": (CTU("DINT"), -5),
        "u_udint": (CTU("UDINT"), 0), "u_lint": (CTU("LINT"), LINT_MAX),
        "d_ulint": (CTD("ULINT"), ULINT_MAX), "d_udint": (CTD("UDINT"), 1), "d_lint": (CTD("LINT"), LINT_MIN),
        "d_int": (CTD("INT"), 2), "d_dint": (CTD("DINT"), DINT_MAX),
        "ud_ulint": (CTUD("ULINT"), ULINT_MAX), "ud_int": (CTUD("INT"), 2), "ud_udint": (CTUD("UDINT"), 1),
        "ud_lint": (CTUD("LINT"), -3), "ud_dint": (CTUD("DINT"), 3)}
    sem, rtc, rs = SEMA(), RTC(), RS()
    clock_ns = 0  # ldrun's scan clock: 0 on the first scan, then + dt (10 ms) each scan
    out = []
    for k, row in enumerate(rows):
        v = dict(zip(head, row))
        b = lambda n: v[n] == "1"
        x, bb = int(v["x"]) & 0xFFFFFFFF, int(v["b"]) & 0xFFFFFFFF
        if k > 0:
            clock_ns += 10_000_000
        for name, (c, pv) in counters.items():
            if isinstance(c, CTU):
                c(b("cu"), b("r"), pv)
            elif isinstance(c, CTD):
                c(b("cd"), b("ld"), pv)
            else:
                c(b("cu"), b("cd"), b("r"), b("ld"), pv)
        g = lambda n: counters[n][0]
        busy = sem(b("claim"), b("release"))
        rtc(b("rin"), PDT_S * 10**9, clock_ns)
        cdt_s, cdt_ms = rtc.cdt // 10**9, (rtc.cdt % 10**9) // 10**6
        bxl = c_cast(uint_to_bcd(x), "LWORD")
        r = []
        r += lo_hi(g("u_ulint").cv) + [g("u_ulint").q, g("u_int").cv, g("u_int").q, g("u_neg").cv, g("u_neg").q,
                                       as_dint(g("u_udint").cv), g("u_udint").q, lo_hi(g("u_lint").cv)[0], g("u_lint").q]
        r += lo_hi(g("d_ulint").cv) + [g("d_ulint").q, as_dint(g("d_udint").cv), g("d_udint").q]
        r += lo_hi(g("d_lint").cv) + [g("d_lint").q, g("d_int").cv, g("d_int").q, g("d_dint").cv, g("d_dint").q]
        r += lo_hi(g("ud_ulint").cv) + [g("ud_ulint").qu, g("ud_ulint").qd]
        for n in ("ud_int", "ud_udint"):
            r += [as_dint(g(n).cv), g(n).qu, g(n).qd]
        r += [lo_hi(g("ud_lint").cv)[0], g("ud_lint").qu, g("ud_lint").qd]
        r += [g("ud_dint").cv, g("ud_dint").qu, g("ud_dint").qd]
        r += [busy, rtc.q, cdt_s, cdt_ms]
        r += [c_cast(uint_to_bcd(x), "DWORD")] + lo_hi(bxl)  # a DWORD: watched unsigned
        r += [c_cast(uint_to_bcd(c_cast(x, "USINT")), "BYTE"), c_cast(uint_to_bcd(c_cast(x, "UINT")), "WORD")]
        r += [as_dint(bcd_to(bb, "UDINT")), bcd_to(bb, "USINT"), bcd_to(bb & 0xFFFF, "UINT")]
        r += lo_hi(bcd_to(0x9999999999999999, "ULINT")) + lo_hi(uint_to_bcd(ULINT_MAX))
        r += time_and_date()
        rsq = rs(b("claim"), b("release"))
        r += [rsq, 0x100F, c_round(math.asin(0.5) * 1e6), c_round(math.acos(0.5) * 1e6), c_round(math.atan(0.5) * 1e6),
              c_round(math.log10(float(x) + 1000.0) * 1e6), c_cast(32768, "INT"), c_cast(32768, "INT"),
              PDT_S - PDT_S % 86400, PDT_S % 86400]
        out.append(",".join(str(int(e)) for e in [k + 1] + r))
    return out


WATCH = ("u_ulint_lo,u_ulint_hi,u_ulint_q,u_int_cv,u_int_q,u_neg_cv,u_neg_q,u_udint_cv,u_udint_q,u_lint_lo,u_lint_q,"
         "d_ulint_lo,d_ulint_hi,d_ulint_q,d_udint_cv,d_udint_q,d_lint_lo,d_lint_hi,d_lint_q,d_int_cv,d_int_q,d_dint_cv,"
         "d_dint_q,ud_ulint_lo,ud_ulint_hi,ud_ulint_qu,ud_ulint_qd,ud_int_cv,ud_int_qu,ud_int_qd,ud_udint_cv,ud_udint_qu,"
         "ud_udint_qd,ud_lint_lo,ud_lint_qu,ud_lint_qd,ud_dint_cv,ud_dint_qu,ud_dint_qd,busy,rq,cdt_s,cdt_ms,bx,bxl_lo,"
         "bxl_hi,b8,bw,db,db8,dw,lw_lo,lw_hi,ul_lo,ul_hi,r_addtime,r_subtime,r_addtod,r_subtod,r_subtodtod,r_subdtdt,"
         "r_concat,r_subdate,r_adddt,r_subdt,rsq,rr,as_u,ac_u,at_u,lg_u,ng,ab,dd,dtod")

if __name__ == "__main__":
    text = "scan," + WATCH + "\n" + "\n".join(run()) + "\n"
    path = os.path.join(HERE, "typed_stdlib.expected")
    if "--check" in sys.argv:
        if open(path).read() != text:
            sys.exit("typed_stdlib.expected is stale: run tests/iec/typed_stdlib.py > tests/iec/typed_stdlib.expected")
    else:
        sys.stdout.write(text)
