"""tests/typed/strings.py -- MatIEC's STRING and its functions, transcribed
from its C library (github.com/beremiz/matiec, lib/C/iec_types.h: STR_MAX_LEN
126, IEC_STRING {uint8_t len; uint8_t body[126]}; lib/C/iec_std_functions.h:
LEN LEFT RIGHT MID CONCAT INSERT DELETE REPLACE FIND, __str_cmp;
lib/C/iec_std_lib.h: __*_to_string, __string_to_*), line by line with C's
types (__strlen_t is uint8_t), and the cases of the string family
(cases/strings.*).  Where MatIEC's C reads or writes outside its 126 bytes
the rule of docs/il.md ("Strings") is taken instead, and the case says so.
The C library's strtod (atof) is called through ctypes, as matiec.py calls libm.
"""
import ctypes
import ctypes.util
import math

import matiec as m

MAX = 126  # STR_MAX_LEN
CELLS = 33  # a STRING in the IL: the length cell and 32 cells of bytes
SENTINEL = 0x5A5A5A5A  # gen_cases.py's prefill of every result cell
_libc = ctypes.CDLL(ctypes.util.find_library("c"))
_libc.strtod.restype = ctypes.c_double
_libc.strtod.argtypes = [ctypes.c_char_p, ctypes.c_void_p]


def u8(v):  # a conversion to __strlen_t
    return v & 0xFF


def i32(v):
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >> 31 else v


# ------------------------------------------------------------ Table 29
def left(s, L):  # TEST_EN_COND(STRING, L < 0); L = L < IN.len ? L : IN.len
    if L < 0:
        return b"", True
    return s[:min(L, len(s))], False


def right(s, L):  # memcpy(&res.body, &IN.body[IN.len - L], L)
    if L < 0:
        return b"", True
    L = min(L, len(s))
    return s[len(s) - L:], False


def mid(s, L, P):
    if L < 0 or P < 0:
        return b"", True
    if P > len(s):
        return b"", False
    P -= 1  # "now can be used as [index]"
    L = L if L + P <= len(s) else len(s) - P
    struct = bytes([len(s)]) + s  # body[-1] is the struct's len byte
    return struct[P + 1:P + 1 + L][:MAX], False  # [:MAX]: docs/il.md (MatIEC overruns at P = 0 on 126 bytes)


def concat(a, b):  # charrem = STR_MAX_LEN - charcount
    return (a + b)[:MAX]


def insert(a, b, P):
    if P < 0:
        return b"", True
    P = u8(P)  # (__strlen_t)P
    to_copy = len(a) if P > len(a) else P
    res = a[:to_copy]
    P = to_copy
    to_copy = MAX - len(res) if len(b) + len(res) > MAX else len(b)
    res += b[:to_copy]
    to_copy = len(a) - P if len(a) - P < MAX - len(res) else MAX - len(res)
    res += a[P:P + to_copy]
    return res, False


def _head(P, n):  # to_copy = P > IN.len ? IN.len : P-1; P = 0: 0 (docs/il.md; MatIEC copies 255 bytes)
    return n if P > n else (P - 1 if P > 0 else 0)


def delete(s, L, P):
    if L < 0 or P < 0:
        return b"", True
    L, P = u8(L), u8(P)
    P = _head(P, len(s))
    res = s[:P]
    if len(s) > P + L:
        res += s[P + L:]
    return res, False


def replace(a, b, L, P):
    if L < 0 or P < 0:
        return b"", True
    L, P = u8(L), u8(P)
    P = _head(P, len(a))
    res = a[:P]
    to_copy = min(len(b), L)
    if to_copy + len(res) > MAX:
        to_copy = MAX - len(res)
    res += b[:to_copy]
    P = u8(P + L)  # P += L in __strlen_t
    if len(res) < MAX and P < len(a):
        res += a[P:]
    return res[:MAX], False  # [:MAX]: docs/il.md (MatIEC does not cut this copy)


def find(a, b):  # __pfind
    c1 = c2 = 0
    if not (len(b) > 0 and len(a) >= len(b)):
        return 0
    while c1 + c2 < len(a) and c2 < len(b):
        if a[c1 + c2] != b[c2]:
            c1 += c2 + 1
            c2 = 0
        else:
            c2 += 1
    return c1 + 1 if c2 == len(b) else 0


def cmp(a, b):  # __str_cmp: memcmp of the shorter length, then the longer is greater
    n = min(len(a), len(b))
    if a[:n] != b[:n]:
        return -1 if a[:n] < b[:n] else 1
    return (len(a) > len(b)) - (len(a) < len(b))


# ------------------------------------------------------------ conversions
def _snprintf(text):  # res.len = snprintf(body, STR_MAX_LEN, ...); if (res.len > STR_MAX_LEN) res.len = STR_MAX_LEN
    return text.encode()[:MAX - 1] + (b"\0" if len(text) >= MAX else b"")


def _cdiv(a, b):  # div(): toward zero
    q = abs(a) // abs(b) * (1 if (a >= 0) == (b >= 0) else -1)
    return q, a - q * b


def time_to_string(ns):  # __time_to_string; div(IN.tv_sec, ...) with tv_sec passed as an int
    sec = int(ns / 10**9) if ns >= 0 else -((-ns) // 10**9)
    nsec = ns - sec * 10**9
    days, drem = _cdiv(i32(sec), 86400)
    if not drem and nsec == 0:
        return _snprintf("T#%dd" % days)
    hours, hrem = _cdiv(drem, 3600)
    if not hrem and nsec == 0:
        return _snprintf("T#%dd%dh" % (days, hours))
    mins, mrem = _cdiv(hrem, 60)
    if not mrem and nsec == 0:
        return _snprintf("T#%dd%dh%dm" % (days, hours, mins))
    if nsec == 0:
        return _snprintf("T#%dd%dh%dm%ds" % (days, hours, mins, mrem))
    return _snprintf("T#%dd%dh%dm%ds%gms" % (days, hours, mins, mrem, nsec / 1000000))


_MON_YDAY = [[0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334, 365],
             [0, 31, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335, 366]]


def _leap(y):
    return int(y % 4 == 0 and (y % 100 != 0 or y % 400 == 0))


def seconds_to_date(seconds):  # convert_seconds_to_date_and_time (long arithmetic: C's / and %)
    days, rem = _cdiv(seconds, 86400)
    if rem < 0:
        rem += 86400
        days -= 1
    hour, rem = _cdiv(rem, 3600)
    mn, sec = _cdiv(rem, 60)
    year = 1970
    while days >= (366 if _leap(year) else 365):
        days -= 366 if _leap(year) else 365
        year += 1
    while days < 0:
        year -= 1
        days += 366 if _leap(year) else 365
    mon = 1
    while days >= _MON_YDAY[_leap(year)][mon]:
        mon += 1
    return year, mon, days - _MON_YDAY[_leap(year)][mon - 1] + 1, hour, mn, sec


def date_to_string(t, ns):  # __date_to_string, __tod_to_string, __dt_to_string
    sec, nsec = _cdiv(ns, 10**9)  # tv_sec and tv_nsec: ldc's time_sec / time_nsec (C's / and %)
    y, mo, d, h, mi, s = seconds_to_date(sec)
    frac = s + nsec / 1e9
    if t == "DATE":
        return _snprintf("D#%d-%02d-%02d" % (y, mo, d))
    if t == "TOD":
        if sec >= 86400:
            return _snprintf("TOD#ERROR")
        return _snprintf("TOD#%02d:%02d:%02d" % (h, mi, s) if nsec == 0 else "TOD#%02d:%02d:%09.6f" % (h, mi, frac))
    if nsec == 0:
        return _snprintf("DT#%d-%02d-%02d-%02d:%02d:%02d" % (y, mo, d, h, mi, s))
    return _snprintf("DT#%d-%02d-%02d-%02d:%02d:%09.6f" % (y, mo, d, h, mi, frac))


# TIME, LTIME to STRING, derived by hand from __time_to_string (thiagoralves/matiec cb9937a8,
# lib/C/iec_std_lib.h): days = div(IN.tv_sec, 86400) (tv_sec, a long, passed as div's int);
# "T#%dd" if days.rem and tv_nsec are 0, else hours = div(days.rem, 3600): "T#%dd%dh" if
# hours.rem and tv_nsec are 0, else minuts = div(hours.rem, 60): "T#%dd%dh%dm", "T#%dd%dh%dm%ds",
# or with tv_nsec "T#%dd%dh%dm%ds%gms" of tv_nsec / 1000000.
TIMES_BY_HAND = [
    ("TIME", 0, b"T#0d", "div(0, 86400) = {0, 0}, tv_nsec 0"),
    ("TIME", 2 * 3600 * 10**9, b"T#0d2h", "div(7200, 86400) = {0, 7200}; div(7200, 3600) = {2, 0}"),
    ("TIME", 90 * 10**9, b"T#0d0h1m30s", "{0, 90}; {0, 90}; div(90, 60) = {1, 30}"),
    ("TIME", (86400 + 3723) * 10**9 + 5500000, b"T#1d1h2m3s5.5ms", "{1, 3723}; {1, 123}; {2, 3}; %g of 5.5"),
    ("TIME", 3500000, b"T#0d0h0m0s3.5ms", "tv_sec 0 but tv_nsec 3500000: every field, %g of 3.5"),
    ("TIME", -1500 * 10**6, b"T#0d0h0m-1s-500ms", "tv_sec -1, tv_nsec -5e8: div(-1, ...) = {0, -1} each time; %g of -500"),
    ("TIME", 2**31 * 10**9, b"T#-24855d-3h-14m-8s",
     "tv_sec 2^31 as an int is -2147483648: div by 86400 = {-24855, -11648}; by 3600 {-3, -848}; by 60 {-14, -8}"),
    ("LTIME", 3 * 86400 * 10**9, b"T#3d", "div(259200, 86400) = {3, 0}"),
]

# DATE, TOD, DT to STRING.  Each string is derived by hand from OpenPLC's MatIEC
# (github.com/thiagoralves/matiec cb9937a8, lib/C/iec_std_lib.h): __date_to_string
# "D#%d-%2.2d-%2.2d", __tod_to_string (tv_sec >= SECONDS_PER_DAY: 'TOD#ERROR'; else
# "TOD#%2.2d:%2.2d:%2.2d", or with tv_nsec "TOD#%2.2d:%2.2d:%09.6f" of tm_sec + tv_nsec / 1e9),
# __dt_to_string "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%2.2d" (or "%09.6f"), the fields from
# convert_seconds_to_date_and_time(tv_sec): days = s / 86400, rem = s % 86400 (C's), a
# negative rem + 86400 with days - 1; whole years from 1970 (366 if __isleap); then
# tm_mon from 1 while days >= __mon_yday[leap][tm_mon], tm_day = days - __mon_yday[leap][tm_mon - 1] + 1.
# ldc's value is ns; tv_sec = ns / 10^9 and tv_nsec = ns % 10^9 (C's, both of ns's sign, as
# __normalize_timespec leaves a negative time).  beremiz/matiec 0dff6e04 has the same code but
# for __tod_to_string's `uint64_t seconds`, which makes a negative TOD 'TOD#ERROR'; OpenPLC's
# `time_t` is taken (docs/il.md).
NS_PER_S = 10**9
DATES_BY_HAND = [
    ("DATE", 0, b"D#1970-01-01", "days 0 < __mon_yday[0][1] = 31: month 1, day 0 - 0 + 1"),
    ("DATE", 31 * 86400 * NS_PER_S, b"D#1970-02-01", "days 31 >= __mon_yday[0][1] = 31: month 2, day 31 - 31 + 1"),
    ("DATE", (86400 + 3600) * NS_PER_S, b"D#1970-01-02", "the time of day is dropped: days 1, day 2"),
    ("DATE", 19753 * 86400 * NS_PER_S, b"D#2024-01-31",
     "1970..2023 are 54 * 365 + 13 leap days = 19723 days; 19753 - 19723 = 30 < 31: month 1, day 31"),
    ("DATE", -86400 * NS_PER_S, b"D#1969-12-31",
     "days -1 < 0: year 1969 (365), days 364 >= __mon_yday[0][11] = 334, < 365: month 12, day 364 - 334 + 1"),
    ("DATE", 11016 * 86400 * NS_PER_S, b"D#2000-02-29",
     "1970..1999: 30 * 365 + 7 = 10957; days 59 in leap 2000 (2000 % 400 == 0): 59 >= 31, < 60: month 2, day 29"),
    ("DATE", 47541 * 86400 * NS_PER_S, b"D#2100-03-01",
     "1970..2099: 130 * 365 + 32 = 47482; days 59 in 2100, not leap (2100 % 100 == 0): 59 >= __mon_yday[0][2] = 59: month 3, day 1"),
    ("TOD", (12 * 3600 + 30 * 60 + 15) * NS_PER_S + 500000000, b"TOD#12:30:15.500000",
     "tv_sec 45015: 12 h 30 min 15 s; tv_nsec 5e8: %09.6f of 15.5"),
    ("TOD", 5 * NS_PER_S + 250000000, b"TOD#00:00:05.250000", "%09.6f pads 5.25 to nine characters"),
    ("TOD", 59 * NS_PER_S + 999999900, b"TOD#00:00:60.000000", "%09.6f rounds 59.9999999 up to 60.000000"),
    ("TOD", 1, b"TOD#00:00:00.000000", "tv_nsec 1 is not 0, so the %09.6f form, of 1e-9"),
    ("TOD", 86399 * NS_PER_S, b"TOD#23:59:59", "tv_sec 86399: 23 h 59 min 59 s, tv_nsec 0"),
    ("TOD", 86400 * NS_PER_S, b"TOD#ERROR", "tv_sec 86400 >= SECONDS_PER_DAY"),
    ("TOD", -1 * NS_PER_S, b"TOD#23:59:59", "tv_sec -1 (time_t) < 86400; rem -1 + 86400 = 86399"),
    ("DT", (951782400 + 45296) * NS_PER_S, b"DT#2000-02-29-12:34:56",
     "951782400 s = 11016 days (2000-02-29 above); 45296 s = 12 h 34 min 56 s"),
    ("DT", -1 * NS_PER_S, b"DT#1969-12-31-23:59:59", "days 0, rem -1: rem 86399, days -1: 1969-12-31 (above)"),
    ("DT", -1500000000, b"DT#1969-12-31-23:59:58.500000",
     "tv_sec -1, tv_nsec -5e8: 1969-12-31-23:59:59 and %09.6f of 59 - 0.5"),
    ("DT", -500000000, b"DT#1970-01-01-00:00:-0.500000", "tv_sec 0, tv_nsec -5e8: %09.6f of 0 - 0.5"),
    ("DT", 1700000000 * NS_PER_S + 250000000, b"DT#2023-11-14-22:13:20.250000",
     "1700000000 s = 19675 days + 80000 s (22 h 13 min 20 s); 2023 starts at day 19358, 317 >= 304, < 334: month 11, day 14"),
]
# STRING to DATE, TOD, DT: __string_to_time, derived by hand (as TIME: whole seconds).
DATES_FROM_STRING_BY_HAND = [
    ("DATE", b"86400", 86400 * NS_PER_S, "no dot: __pstring_to_sint 86400, {86400, 0}"),
    ("DT", b"1.9", 1 * NS_PER_S, "a dot at 1: atof 1.9, {(long)1.9, (long)(0.9) * 1000000000} = {1, 0}"),
    ("DT", b"-3", -3 * NS_PER_S, "no dot: __pstring_to_sint -3"),
    ("DATE", b"1.5e9", 1500000000 * NS_PER_S, "a dot: atof 1.5e9, whole"),
    ("TOD", b"12:30", 12 * NS_PER_S, "read from the end: 30, ':' >= '.' resets, then 12"),
    ("TOD", b"D#2024-01-31", 0, "read from the end: '-' and '#' are skipped, the 'D' resets the 20240131 read so far"),
]


def to_string(t, v):
    if t == "BOOL":
        return b"TRUE" if v else b"FALSE"  # __bool_to_string
    if t in m.BITS:
        return _snprintf("16#%x" % v)  # __bit_to_string "16#%llx"
    if t in m.INTS:
        return _snprintf("%d" % v)  # __sint_to_string "%lld", __uint_to_string "%llu"
    if t in m.REALS:
        return _snprintf("%.10g" % m.rval(t, v))  # __real_to_string "%.10g" of the LREAL
    if t in m.TIMES:
        return time_to_string(v)
    if t in m.DATES:
        return date_to_string(t, v)
    raise ValueError(t)


def pstring_to_sint(s):  # __pstring_to_sint, C's arithmetic on x86-64 (see ir/typed.h)
    n = len(s)
    res, shift = 0, 0
    if n < 1:
        return 0
    if n > 1 and s[0:1] in (b"2", b"8") and s[1:2] == b"#":
        step, top = (1, ord("1")) if s[0:1] == b"2" else (3, ord("7"))
        l = n - 1
        while l >= 2 and shift < 64:
            c = s[l]
            if ord("0") <= c <= top:
                res |= i32((c - ord("0")) << (shift & 31)) & (2**64 - 1)  # an int shift, sign-extended
                shift += step
            l -= 1
        return res
    if n > 2 and s[:3] == b"16#":
        l = n - 1
        while l >= 3 and shift < 64:
            c = chr(s[l])
            if c in "0123456789abcdefABCDEF":
                res |= int(c, 16) << shift
                shift += 4
            l -= 1
        return res
    sign = -1 if s[0:1] == b"-" else 1
    fac = sign
    l = n
    while l > 0 and shift < 20:
        c = s[l - 1]
        if ord("0") <= c <= ord("9"):
            res = (res + (c - ord("0")) * fac) % 2**64
            fac = fac * 10 % 2**64
            shift += 1
        elif c >= ord("."):
            res, fac, shift = 0, sign, 0
        l -= 1
    return res % 2**64


def _dot(s):  # while (l > 0 && IN.body[--l] != '.'); return l != 0
    l = len(s)
    while l > 0:
        l -= 1
        if s[l:l + 1] == b".":
            break
    return l != 0


def string_to_real(s):
    if _dot(s):
        return _libc.strtod(s, None)  # atof
    v = pstring_to_sint(s)
    return float(v - 2**64 if v >> 63 else v)


def from_string(t, s):
    if t == "BOOL":  # __string_to_bool
        if len(s) == 1:
            return int(s == b"1")
        return int(len(s) == 4 and s.upper() == b"TRUE")
    if t in m.REALS:
        return m.rbits(t, string_to_real(s))
    if t in m.TIMES or t in m.DATES:  # __string_to_time: {(long)IN_val, (long)(IN_val - (LINT)IN_val)*1000000000}: whole seconds
        if _dot(s):
            return m.wrap(t, m.cvtt64(string_to_real(s)) * 10**9)
        v = pstring_to_sint(s)
        return m.wrap(t, (v - 2**64 if v >> 63 else v) * 10**9)
    return m.wrap(t, pstring_to_sint(s))  # __string_to_sint / _uint / _bit, then C's conversion


# ------------------------------------------------------------ cells
def cells(s, length=None):
    """The 33 INT32 cells of a STRING holding s (the length cell `length` if given, raw)."""
    body = s + bytes(4 * (CELLS - 1) - len(s))
    return [i32(len(s) if length is None else length)] + [i32(int.from_bytes(body[4 * k:4 * k + 4], "little"))
                                                          for k in range(CELLS - 1)]


def show(s):
    if len(s) > 24:  # a long string: its start and its length
        return show(s[:10]) + "...(%d bytes)" % len(s)
    return "'" + "".join(chr(c) if 32 <= c < 127 and c not in (39, 36) else "$%02X" % c for c in s) + "'"


# ------------------------------------------------------------ the cases
class Cases:
    """The string family on one gen_cases.Program: string inputs and results
    take 33 D cells each; results are prefilled and watched whole (so the
    zero fill after the length counts too)."""

    def __init__(self, p):
        self.p = p

    def sin(self, s, length=None):
        p = self.p
        base = p.d_in
        p.d_in += CELLS
        assert p.d_in < 4000, "inputs run into the results"
        for i, w in enumerate(cells(s, length)):
            p.inputs.append(("D%d" % (base + i), [w]))
        return "D%d" % base

    def sout(self):
        p = self.p
        base = p.d_out
        p.d_out += CELLS
        assert p.d_out < 8192
        p.init += [("D%d" % (base + i), SENTINEL) for i in range(CELLS)]
        return "D%d" % base

    def expect_str(self, dev, s):
        base = int(dev[1:])
        for i, w in enumerate(cells(s)):
            self.p.watch.append(("D%d" % (base + i), [w]))

    def rung(self, comment, lines, s0=None):
        p = self.p
        body = ["TRUE"] + (["RST S0"] if s0 is not None else []) + lines
        if s0 is not None:
            f = p.flag()
            body += ["LOAD S0", "OUT %s" % f]
            p.watch_bit(f, [int(s0)])
        p.rung(comment, body)


def _int_arg(p, t, v, const):
    return str(v) if const else p.inp(t, v)


def programs(Program):
    progs = [Program("strings", "STRING: MOVE LEN LEFT RIGHT MID CONCAT (MatIEC's Table 29)"),
             Program("strings_edit", "STRING: INSERT DELETE REPLACE FIND (MatIEC's Table 29)"),
             Program("strings_conv", "STRING: compares, *_TO_STRING and STRING_TO_* (MatIEC's iec_std_lib.h)")]
    p = progs[0]
    c = Cases(p)
    full = bytes(range(0x21, 0x21 + 94)) + b"abcdefghijklmnopqrstuvwxyzABCDEF"  # 126 bytes
    assert len(full) == MAX
    hello = b"Hello, World"

    def str_res(op, args_text, ins, expected, why, s0=None):
        r = c.sout()
        c.rung("%s %s = %s: %s" % (op, args_text, show(expected), why), ins(r), s0)
        c.expect_str(r, expected)

    # MOVE, and what a length cell outside 0..126 reads as
    for s, raw, why in [(b"abc", None, "MOVE_STRING: return op1"), (b"", None, "the empty string"),
                        (full, None, "126 bytes, STR_MAX_LEN"),
                        (full, 0x7FFFFFFF, "a length cell of 0x7fffffff is read as 126 (docs/il.md: clamped)"),
                        (b"xy", -1, "a length cell of -1 is read as UINT32, so 126 (the body bytes after 'xy' are zero)"),
                        (full, 127, "a length cell of 127 is read as 126")]:
        a = c.sin(s, raw)
        exp = s if raw is None else (s + bytes(MAX))[:MAX]
        str_res("MOVE.STRING", show(s) + ("" if raw is None else " (length cell %d)" % raw),
                lambda r, a=a: ["MOVE.STRING %s %s" % (a, r)], exp, why)
    # LEN
    for s, raw, t in [(b"", None, "INT"), (hello, None, "DINT"), (full, None, "USINT"), (b"ab", 0x7FFFFFFF, "INT"),
                      (full, 200, "SINT")]:
        a = c.sin(s, raw)
        r = p.out(t)
        n = min(len(s) if raw is None else raw & 0xFFFFFFFF, MAX)
        c.rung("LEN.%s.STRING %s = %d: __len: IN.len%s" % (t, show(s), n, "" if raw is None else " (cell %d, clamped)" % raw),
               ["LEN.%s.STRING %s %s" % (t, a, r)])
        p.expect(t, r, m.wrap(t, n))
    # LEFT / RIGHT with lengths before, at and past the end, and negative
    for fn, name in [(left, "LEFT"), (right, "RIGHT")]:
        for s, L, t, const in [(hello, 5, "INT", False), (hello, 0, "INT", True), (hello, 12, "DINT", False),
                               (hello, 200, "INT", False), (b"", 3, "INT", True), (hello, -1, "INT", False),
                               (full, 126, "UINT", False), (hello, 2**40, "LINT", False)]:
            a = c.sin(s)
            n = _int_arg(p, t, L, const)
            exp, eno = fn(s, L)
            str_res("%s.STRING.%s" % (name, t), "%s %d" % (show(s), L),
                    lambda r, a=a, n=n, t=t: ["%s.STRING.%s %s %s %s" % (name, t, a, n, r)], exp,
                    "%s: L < 0 is ENO FALSE (S0), the empty string; L is cut at IN.len" % name, s0=eno)
    # MID through ARGS
    for s, L, P in [(hello, 5, 8), (hello, 3, 1), (hello, 20, 10), (hello, 2, 12), (hello, 2, 13), (hello, 2, 200),
                    (hello, 0, 3), (b"abc", 2, 0), (full, 126, 0), (hello, -1, 2), (hello, 2, -1), (b"", 1, 1)]:
        a = c.sin(s)
        exp, eno = mid(s, L, P)
        why = "MID: P <= IN.len: P -= 1; L = L + P <= IN.len ? L : IN.len - P"
        if P == 0 and L >= 0:
            why = "MID: P = 0 starts at body[-1], the struct's length byte" + (" (127 bytes cut to 126, docs/il.md)" if len(s) == MAX else "")
        if L < 0 or P < 0:
            why = "MID: L < 0 || P < 0 is ENO FALSE (S0), the empty string"
        str_res("MID.STRING", "%s L=%d P=%d" % (show(s), L, P),
                lambda r, a=a, L=L, P=P: ["ARGS.DINT %d %d" % (L, P), "MID.STRING %s %s" % (a, r)], exp, why, s0=eno)
    # CONCAT: truncation at 126
    for x, y in [(b"ab", b"cd"), (b"", b""), (full[:100], full[:50]), (full, b"x"), (b"", hello)]:
        a, b_ = c.sin(x), c.sin(y)
        str_res("CONCAT.STRING", "%s %s" % (show(x), show(y)), lambda r, a=a, b_=b_: ["CONCAT.STRING %s %s %s" % (a, b_, r)],
                concat(x, y), "CONCAT: charrem = STR_MAX_LEN - charcount: cut at 126")
    p = progs[1]
    c = Cases(p)
    # INSERT at 0, inside, at the end, past it, P beyond 255, truncation, P < 0
    for x, y, P in [(b"abcdef", b"XY", 0), (b"abcdef", b"XY", 3), (b"abcdef", b"XY", 6), (b"abcdef", b"XY", 100),
                    (b"abcdef", b"XY", 258), (full[:120], b"0123456789", 60), (b"abc", b"", 1), (b"abc", b"XY", -1)]:
        a, b_ = c.sin(x), c.sin(y)
        exp, eno = insert(x, y, P)
        why = "__insert: P cast to __strlen_t (uint8_t), min(P, len1) bytes of IN1, IN2, the rest, cut at 126"
        str_res("INSERT.STRING", "%s %s P=%d" % (show(x), show(y), P),
                lambda r, a=a, b_=b_, P=P: ["ARGS.DINT 0 %d" % P, "INSERT.STRING %s %s %s" % (a, b_, r)], exp,
                "INSERT: P < 0 is ENO FALSE (S0)" if eno else why, s0=eno)
    # DELETE
    for s, L, P in [(b"abcdef", 2, 3), (b"abcdef", 2, 1), (b"abcdef", 10, 4), (b"abcdef", 2, 6), (b"abcdef", 2, 7),
                    (b"abcdef", 2, 0), (b"abcdef", 0, 3), (b"abcdef", 258, 2), (b"abcdef", -1, 2)]:
        a = c.sin(s)
        exp, eno = delete(s, L, P)
        why = "__delete: P > len ? len : P-1 bytes kept, then IN from P + L"
        if P == 0:
            why = "DELETE with P = 0: MatIEC copies 255 bytes (an overrun); docs/il.md keeps none, as P = 1"
        str_res("DELETE.STRING", "%s L=%d P=%d" % (show(s), L, P),
                lambda r, a=a, L=L, P=P: ["ARGS.DINT %d %d" % (L, P), "DELETE.STRING %s %s" % (a, r)], exp,
                "DELETE: L < 0 || P < 0 is ENO FALSE (S0)" if eno else why, s0=eno)
    # REPLACE
    for x, y, L, P in [(b"abcdef", b"XY", 2, 3), (b"abcdef", b"XYZ", 1, 1), (b"abcdef", b"XY", 5, 3),
                       (b"abcdef", b"XY", 2, 10), (b"abcdef", b"XY", 250, 3), (full, b"0123456789", 2, 100),
                       (b"abcdef", b"XY", 2, 0), (b"abcdef", b"XY", 2, -3)]:
        a, b_ = c.sin(x), c.sin(y)
        exp, eno = replace(x, y, L, P)
        why = "__replace: head, min(len2, L) bytes of IN2, then IN1 from P + L (in uint8_t)"
        if len(x) == MAX:
            why = "REPLACE: the last copy cut at 126 (docs/il.md; MatIEC writes past its body)"
        if P == 0:
            why = "REPLACE with P = 0: as P = 1 (docs/il.md; MatIEC overruns)"
        str_res("REPLACE.STRING", "%s %s L=%d P=%d" % (show(x), show(y), L, P),
                lambda r, a=a, b_=b_, L=L, P=P: ["ARGS.DINT %d %d" % (L, P), "REPLACE.STRING %s %s %s" % (a, b_, r)], exp,
                "REPLACE: P < 0 is ENO FALSE (S0)" if eno else why, s0=eno)
    # FIND
    for x, y, t in [(hello, b"World", "INT"), (hello, b"o", "DINT"), (hello, b"xyz", "INT"), (hello, b"", "INT"),
                    (b"ab", b"abc", "INT"), (b"aaab", b"aab", "INT"), (b"abab", b"ab", "UINT"), (full, full[-3:], "SINT")]:
        a, b_ = c.sin(x), c.sin(y)
        r = p.out(t)
        v = find(x, y)
        c.rung("FIND.%s.STRING %s %s = %d: __pfind%s" % (t, show(x), show(y), v,
                                                          " (after a partial match it goes on past it)" if x == b"aaab" else ""),
               ["FIND.%s.STRING %s %s %s" % (t, a, b_, r)])
        p.expect(t, r, m.wrap(t, v))
    p = progs[2]
    c = Cases(p)
    # compares: __str_cmp
    for x, y in [(b"abc", b"abd"), (b"ab", b"abc"), (b"", b""), (hello, hello), (b"b", b"abc"), (b"\xff", b"a")]:
        a, b_ = c.sin(x), c.sin(y)
        for rel, holds in [("EQ", lambda k: k == 0), ("NE", lambda k: k != 0), ("LT", lambda k: k < 0),
                           ("LE", lambda k: k <= 0), ("GT", lambda k: k > 0), ("GE", lambda k: k >= 0)]:
            f = p.flag()
            v = int(holds(cmp(x, y)))
            p.rung("%s.STRING %s %s = %d: __str_cmp (memcmp, then the longer)" % (rel, show(x), show(y), v),
                   ["%s.STRING %s %s" % (rel, a, b_), "OUT %s" % f])
            p.watch_bit(f, [v])
    # conversions to STRING
    for t, v in [("INT", -5), ("INT", 32767), ("DINT", -2147483648), ("LINT", -(2**63)), ("UDINT", 4294967295),
                 ("ULINT", 2**64 - 1), ("BOOL", 1), ("BOOL", 0), ("BYTE", 255), ("WORD", 0xABC), ("LWORD", 2**64 - 1),
                 ("REAL", m.bits32(1.5)), ("REAL", m.bits32(0.1)), ("LREAL", m.bits64(0.1)), ("LREAL", m.bits64(1e300)),
                 ("LREAL", m.bits64(-2.5e-7)), ("REAL", m.bits32(float("inf")))]:
        a = p.inp(t, v)
        exp = to_string(t, v)
        str_res("CONV.STRING.%s" % t, m_show(t, v), lambda r, a=a, t=t: ["CONV.STRING.%s %s %s" % (t, a, r)], exp,
                "%s_TO_STRING: %s" % (t, {"BOOL": "__bool_to_string", "REAL": '__real_to_string "%.10g"',
                                          "LREAL": '__real_to_string "%.10g"', "TIME": "__time_to_string",
                                          "LTIME": "__time_to_string", "DATE": "__date_to_string",
                                          "TOD": "__tod_to_string (from 86400 s: TOD#ERROR)",
                                          "DT": "__dt_to_string"}.get(t, "__bit_to_string \"16#%llx\"" if t in m.BITS
                                                                          else "__sint/__uint_to_string")))
    # TIME and the dates to STRING: the model above must give the strings derived by hand
    for t, v, exp, why in TIMES_BY_HAND + DATES_BY_HAND:
        assert to_string(t, v) == exp, (t, v, to_string(t, v), exp)
        a = p.inp(t, v)
        str_res("CONV.STRING.%s" % t, m_show(t, v), lambda r, a=a, t=t: ["CONV.STRING.%s %s %s" % (t, a, r)], exp,
                "%s_TO_STRING: %s" % (t, why))
    # conversions from STRING
    for t, s in [("INT", b"123"), ("INT", b"-5"), ("INT", b"70000"), ("DINT", b"2#1010"), ("DINT", b"8#17"),
                 ("DWORD", b"16#fF"), ("INT", b"1.5"), ("INT", b"abc"), ("INT", b""), ("INT", b"a7"), ("DINT", b" - 42"),
                 ("LINT", b"2#" + b"1" * 33), ("LINT", b"-9223372036854775808"), ("ULINT", b"18446744073709551615"),
                 ("BOOL", b"true"), ("BOOL", b"1"), ("BOOL", b"0"), ("BOOL", b"TRUE "), ("REAL", b"1.5"),
                 ("REAL", b"12"), ("LREAL", b"3.25e2"), ("LREAL", b".5"), ("TIME", b"5"), ("TIME", b"2.7"),
                 ("TIME", b"-3")]:
        a = c.sin(s)
        r = p.out(t) if t != "BOOL" else p.flag()
        v = from_string(t, s)
        p.rung("CONV.%s.STRING %s = %s: STRING_TO_%s (%s)" % (t, show(s), m_show(t, v), t,
                                                           "__string_to_bool" if t == "BOOL" else "__string_to_real" if t in m.REALS
                                                           else "__string_to_time: whole seconds" if t in m.TIMES or t in m.DATES
                                                           else "__pstring_to_sint, then C's conversion"),
               ["TRUE", "CONV.%s.STRING %s %s" % (t, a, r)])
        p.expect(t, r, v)
    # STRING to the dates (__string_to_time, as for TIME): the model above must give the values derived by hand
    for t, s, exp, why in DATES_FROM_STRING_BY_HAND:
        v = from_string(t, s)
        assert v == exp, (t, s, v, exp)
        a = c.sin(s)
        r = p.out(t)
        p.rung("CONV.%s.STRING %s = %s: STRING_TO_%s (__string_to_time: %s)" % (t, show(s), m_show(t, v), t, why),
               ["TRUE", "CONV.%s.STRING %s %s" % (t, a, r)])
        p.expect(t, r, v)
    return progs


def m_show(t, v):
    if t in m.REALS:
        return repr(m.rval(t, v))
    return str(v)
