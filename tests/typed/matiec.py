"""tests/typed/matiec.py -- MatIEC's meaning of the IEC elementary types and
standard functions, computed independently of ldc's engines.

Every function here transcribes a definition of MatIEC's C library
(github.com/beremiz/matiec, lib/C/iec_types.h, iec_std_lib.h,
iec_std_functions.h; the quoted lines are from its HEAD) with C's semantics on
x86-64 (gcc, LP64): two's complement, integer conversions modulo 2^width, a
double converted to a 64-bit integer by cvttsd2si (INT64_MIN when NaN or out
of range), IEEE-754 binary32/binary64 in round-to-nearest-even.  The C
library's mathematical functions (sin, log10, pow ...) that MatIEC calls are
called here too, through ctypes, so they are the same functions.

Values travel as Python integers: an integer, bit string, TIME or date as its
value (TIME and dates in nanoseconds, ldc's representation: MatIEC holds a
timespec {tv_sec, tv_nsec}, and sec * 10^9 + nsec is the same quantity);
REAL and LREAL as their IEEE bit patterns (so -0.0 and NaN survive).
"""
import ctypes
import ctypes.util
import math
import struct

# ---- the types (ir/types.def; MatIEC's iec_types.h gives the same C types)
TYPES = {
    # name: (bits, kind)
    "BOOL": (1, "bool"),
    "SINT": (8, "signed"), "INT": (16, "signed"), "DINT": (32, "signed"), "LINT": (64, "signed"),
    "USINT": (8, "unsigned"), "UINT": (16, "unsigned"), "UDINT": (32, "unsigned"), "ULINT": (64, "unsigned"),
    "BYTE": (8, "bits"), "WORD": (16, "bits"), "DWORD": (32, "bits"), "LWORD": (64, "bits"),
    "REAL": (32, "real"), "LREAL": (64, "real"),
    "TIME": (64, "time"), "LTIME": (64, "time"),
    "DATE": (64, "date"), "TOD": (64, "date"), "DT": (64, "date"),
}
INTS = ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT"]
BITS = ["BYTE", "WORD", "DWORD", "LWORD"]
REALS = ["REAL", "LREAL"]
TIMES = ["TIME", "LTIME"]
DATES = ["DATE", "TOD", "DT"]
NS_PER_S = 10**9
NS_PER_DAY = 86400 * NS_PER_S  # MatIEC: SECONDS_PER_DAY


def bits(t):
    return TYPES[t][0]


def kind(t):
    return TYPES[t][1]


def is_signed(t):
    return kind(t) in ("signed", "time", "date")


def is_int(t):  # wraps at its width
    return kind(t) in ("signed", "unsigned", "bits", "time", "date")


def wide(t):  # takes two word cells; the C40 refuses it
    return bits(t) == 64


def lo(t):
    return -(1 << (bits(t) - 1)) if is_signed(t) else 0


def hi(t):
    return (1 << (bits(t) - 1)) - 1 if is_signed(t) else (1 << bits(t)) - 1


def wrap(t, v):
    """C's conversion of the integer v to t (gcc: modulo 2^width)."""
    if t == "BOOL":
        return 1 if v else 0
    w = bits(t)
    v &= (1 << w) - 1
    if is_signed(t) and v >> (w - 1):
        v -= 1 << w
    return v


def trunc_div(a, b):  # C's / on integers: toward zero
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def trunc_mod(a, b):  # C's %: the sign of the dividend
    return a - b * trunc_div(a, b)


# ---- IEEE values
def f32(b):
    return struct.unpack("<f", struct.pack("<I", b & 0xFFFFFFFF))[0]


def f64(b):
    return struct.unpack("<d", struct.pack("<Q", b & 0xFFFFFFFFFFFFFFFF))[0]


def bits32(x):
    """The binary32 nearest the double x (C's (float)x), as its bits."""
    return struct.unpack("<I", struct.pack("<f", ctypes.c_float(x).value))[0]


def bits64(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def rval(t, b):  # a REAL/LREAL pattern as a Python float (exact)
    return f32(b) if t == "REAL" else f64(b)


def rbits(t, x):  # a double as t (REAL rounds once, as C's (float))
    return bits32(x) if t == "REAL" else bits64(x)


def is_nan(t, b):
    return math.isnan(rval(t, b))


def int_to_real(t, n):
    """C's conversion of an integer to float / double: one rounding, to
    nearest, ties to even (Python's float(int) is correctly rounded for
    double; binary32 is rounded here from the exact integer)."""
    if t == "LREAL":
        return bits64(float(n))
    m = abs(n)
    if m >= 1 << 24:
        shift = m.bit_length() - 24
        q, r = divmod(m, 1 << shift)
        half = 1 << (shift - 1)
        if r > half or (r == half and q & 1):
            q += 1
        m = q << shift
    return bits32(float(-m if n < 0 else m))


def cvtt64(x):
    """(LINT)x, x a double: cvttsd2si on x86-64 (C leaves NaN and values
    outside INT64 undefined; gcc's code gives INT64_MIN there)."""
    if math.isnan(x) or not (-9223372036854775808.0 <= x < 9223372036854775808.0):
        return -(1 << 63)
    return int(x)  # toward zero


# ---- the C library, as MatIEC calls it
_libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
LIBM = {}
for _name in ("sin", "cos", "tan", "asin", "acos", "atan", "log", "log10", "exp", "sqrt", "fmod", "pow"):
    _f = getattr(_libm, _name)
    _f.restype = ctypes.c_double
    _f.argtypes = [ctypes.c_double] * (2 if _name in ("fmod", "pow") else 1)
    LIBM[_name] = _f


# ---- arithmetic (iec_std_functions.h, Table 24; ST's operators in
# stage4/generate_c/generate_c_st.cc print C's + - * / %)
def add(t, a, b):
    if kind(t) == "real":
        return rbits(t, rval(t, a) + rval(t, b))  # float + float: one rounding (exact in double first)
    return wrap(t, a + b)  # time: __time_add, the same quantity


def sub(t, a, b):
    if kind(t) == "real":
        return rbits(t, rval(t, a) - rval(t, b))
    return wrap(t, a - b)


def mul(t, a, b):
    if kind(t) == "real":
        return rbits(t, rval(t, a) * rval(t, b))
    return wrap(t, a * b)


def div(t, a, b):
    """(result, S0).  Integers: MatIEC's DIV_T `TEST_EN_COND(TYPENAME, op2 == 0)
    return op1 / op2;` returns __INIT_T (0) and ENO FALSE for a zero divisor
    (ldc: S0), else C's truncating `/`.  REAL/LREAL: ST's `/` (IEEE; the
    DIV function would give 0.0 and ENO FALSE instead -- see README.md)."""
    if kind(t) == "real":
        x, y = rval(t, a), rval(t, b)
        if y == 0:
            if math.isnan(x) or x == 0:
                return rbits(t, math.nan), 0
            neg = (math.copysign(1, x) < 0) != (math.copysign(1, y) < 0)
            return rbits(t, -math.inf if neg else math.inf), 0
        return rbits(t, x / y), 0
    if b == 0:
        return 0, 1
    return wrap(t, trunc_div(a, b)), 0


def mod(t, a, b):
    """MOD_T: `if (op2 == 0) return 0; return op1 % op2;` (no ENO FALSE in
    MatIEC; ldc sets S0 as for DIV, docs/il.md)."""
    if b == 0:
        return 0, 1
    return wrap(t, trunc_mod(a, b)), 0


def cmp(rel, t, a, b):
    if kind(t) == "real":
        x, y = rval(t, a), rval(t, b)
    else:
        x, y = a, b
    return int({"EQ": x == y, "NE": x != y, "LT": x < y, "LE": x <= y, "GT": x > y, "GE": x >= y}[rel])


def max_(t, a, b):  # __extrem_(MAX_T, T, op1 < tmp): op1 = op1 < tmp ? tmp : op1
    return b if cmp("LT", t, a, b) else a


def min_(t, a, b):  # __extrem_(MIN_T, T, op1 > tmp)
    return b if cmp("GT", t, a, b) else a


def neg(t, a):  # ST's unary " -"
    if kind(t) == "real":
        return a ^ (1 << (bits(t) - 1))
    return wrap(t, -a)


def abs_(t, a):
    """__abs_signed: `if (op < 0) return -op; return op;` (so ABS(-0.0) is
    -0.0 and a NaN keeps its sign); __abs_unsigned: op."""
    if kind(t) == "real":
        return neg(t, a) if rval(t, a) < 0 else a
    if kind(t) == "signed" and a < 0:
        return wrap(t, -a)
    return a


def expt(t, a, b):  # __expt(IN1, IN2): pow(double, double), rounded to IN1's type
    return rbits(t, LIBM["pow"](rval(t, a), rval(t, b)))


def fn(name, t, a):
    """__numeric(SQRT_, T, sqrt) ...: the C library's double function on the
    value, returned as T."""
    c = {"SQRT": "sqrt", "LN": "log", "LOG": "log10", "EXP": "exp", "SIN": "sin", "COS": "cos",
         "TAN": "tan", "ASIN": "asin", "ACOS": "acos", "ATAN": "atan"}[name]
    return rbits(t, LIBM[c](rval(t, a)))


# ---- bit strings (Table 25 and 26)
def logic(op, t, a, b=0):
    if op == "AND":
        return a & b
    if op == "OR":
        return a | b
    if op == "XOR":
        return a ^ b
    return (1 - a) if t == "BOOL" else wrap(t, ~a)  # NOT: ! on BOOL, ~ (then stored as T)


def shift_defined(op, t, n):
    """Is MatIEC's `IN << N` / `IN >> N` defined in C for this count?  IN is
    promoted to int when narrower than 32 bits."""
    width = max(bits(t), 32)
    return op in ("ROL", "ROR") or 0 <= n < width


def shift(op, t, a, n):
    w = bits(t)
    if op in ("SHL", "SHR"):  # __shift_: return IN OP N;
        if n < 0 or n >= w:
            return 0  # defined by C (promotion) only for n < 32; docs/il.md's rule beyond
        return wrap(t, a << n) if op == "SHL" else a >> n
    # ROR: N %= 8*sizeof(T) (N converted to size_t: n mod 2^64, and w divides
    # 2^64); return (IN >> N) | (IN << (8*sizeof(T) - N));  ROL mirrored.
    k = n % w
    if op == "ROL":
        return wrap(t, (a << k) | (a >> (w - k)))
    return wrap(t, (a >> k) | (a << (w - k)))


# ---- conversions (iec_std_functions.h "Type Conversion Functions",
# iec_std_lib.h "Convertions")
def real_round(x):
    """__real_round(LREAL IN): `fmod(IN, 1) == 0 ? ((LINT)IN / 2) * 2 : (LINT)IN`."""
    if LIBM["fmod"](x, 1.0) == 0:
        return trunc_div(cvtt64(x), 2) * 2
    return cvtt64(x)


def preal_to_sint(x):  # `IN >= 0 ? __real_round(IN + 0.5) : __real_round(IN - 0.5)` (double arithmetic)
    return real_round(x + 0.5) if x >= 0 else real_round(x - 0.5)


def preal_to_uint(x):  # `IN >= 0 ? __real_round(IN + 0.5) : 0`, a LINT
    return real_round(x + 0.5) if x >= 0 else 0


def time_split(ns):
    """A TIME's timespec as MatIEC normalizes it (__normalize_timespec keeps
    tv_sec and tv_nsec of one sign): (tv_sec, tv_nsec), toward zero."""
    s = trunc_div(ns, NS_PER_S)
    return s, ns - s * NS_PER_S


def conv(to, frm, v):
    """FROM_TO_TO(v) as MatIEC defines it; None where MatIEC has no such
    function (e.g. TOD_TO_TIME: "Not supported")."""
    fk, tk = kind(frm), kind(to)
    if to == frm:
        return v  # __move_T
    if tk == "bool":
        if fk == "real":
            return 0 if rval(frm, v) == 0 else 1  # __convert_num_to_bool: op == 0 ? 0 : 1 (NaN: 1)
        return 0 if v == 0 else 1  # also __convert_time_to_bool: tv_sec == 0 && tv_nsec == 0 ? 0 : 1
    if fk in ("bool", "signed", "unsigned", "bits"):
        if tk in ("signed", "unsigned", "bits"):
            return wrap(to, v)  # __move_TO: C's conversion
        if tk == "real":
            return int_to_real(to, v)  # __move_REAL: C's conversion
        # __int_to_time(LINT IN) {return (TIME){IN, 0};}: IN counts seconds
        return wrap(to, wrap("LINT", v) * NS_PER_S)
    if fk == "real":
        x = rval(frm, v)
        if tk == "real":
            return rbits(to, x)  # __move_T
        if tk == "signed":
            return wrap(to, preal_to_sint(x))  # __real_to_sint, then (T)
        if tk in ("unsigned", "bits"):
            return wrap(to, preal_to_uint(x))  # __real_to_uint / __real_to_bit: (ULINT)/(LWORD) of the LINT
        # __real_to_time(LREAL IN) {return (TIME){IN, (IN - (LINT)IN) * 1000000000};}
        sec = cvtt64(x)
        nsec = cvtt64((x - float(sec)) * 1e9)
        return wrap(to, sec * NS_PER_S + nsec)
    # from TIME or a date
    sec, nsec = time_split(v)
    if tk in ("signed", "unsigned", "bits"):
        return wrap(to, sec)  # __time_to_int: return IN.tv_sec;
    if tk == "real":
        return rbits(to, float(sec) + float(nsec) / 1e9)  # __time_to_real: (LREAL)tv_sec + (LREAL)tv_nsec/1e9
    if frm == "DT" and to == "TOD":
        # __date_and_time_to_time_of_day: {IN.tv_sec % SECONDS_PER_DAY + (IN.tv_sec < 0 ? SECONDS_PER_DAY : 0), IN.tv_nsec}
        return (trunc_mod(sec, 86400) + (86400 if sec < 0 else 0)) * NS_PER_S + nsec
    if frm == "DT" and to == "DATE":
        # __date_and_time_to_date: {IN.tv_sec - IN.tv_sec % SECONDS_PER_DAY - (IN.tv_sec < 0 ? SECONDS_PER_DAY : 0), 0}
        return (sec - trunc_mod(sec, 86400) - (86400 if sec < 0 else 0)) * NS_PER_S
    return None


def trunc(to, frm, v):
    """TRUNC__TO__FROM: `return (TO)__move_TO(op);`: C's conversion of the
    float to the integer, toward zero; defined only when the result fits."""
    x = rval(frm, v)
    if math.isnan(x) or math.isinf(x):
        return None
    r = int(x)
    return r if lo(to) <= r <= hi(to) else None


# ---- memory: what ldrun --watch prints for a value of t in its cells
def canon64(t, v):
    """The 64 canonical bits (ir/typed.h): signed kinds sign-extended."""
    return v & 0xFFFFFFFFFFFFFFFF


def s32(u):
    u &= 0xFFFFFFFF
    return u - (1 << 32) if u >> 31 else u


def cell_words(t, v):
    """The INT32 values of t's word cells: one cell holds the value extended to
    32 bits; two cells hold the 64 bits, low word first."""
    u = canon64(t, v)
    if bits(t) <= 32:
        return [s32(u)]
    return [s32(u), s32(u >> 32)]


def words_to_value(t, ws):
    """A typed load of cells holding the INT32 words ws (a narrow type takes
    its width of the cell: a D word of 70000 read as an INT is 4464)."""
    if bits(t) <= 32:
        u = ws[0] & 0xFFFFFFFF
    else:
        u = (ws[0] & 0xFFFFFFFF) | ((ws[1] & 0xFFFFFFFF) << 32)
    if kind(t) == "real":
        return u if t == "LREAL" else u & 0xFFFFFFFF
    return wrap(t, u)
