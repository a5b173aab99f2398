"""tests/typed/nans.py -- the NaN cases of the conformance tests: which NaN an
operation stores (docs/il.md, "NaN results").  MatIEC leaves it to the C
compiler and the hardware, and IEEE 754 leaves it open, so every expected
pattern here is written down by hand from IEEE 754-2019 and docs/il.md's rule,
never computed by an engine (nor by Python's float arithmetic):

* IEEE 754 3.4, 6.2.1: a NaN is exponent all ones, trailing significand not 0;
  its first significand bit set is quiet, clear signalling; the rest is the
  payload.
* IEEE 754 7.2: an invalid operation (0/0, inf-inf, 0*inf, inf/inf, sqrt of a
  negative, a function outside its domain) returns a quiet NaN; 6.2.3: a NaN
  operand propagates (quiet, its payload kept), but which one of two is open.
* IEEE 754 5.5.1: MOVE (copy), NEG (negate) and ABS (IEC's `op < 0 ? -op : op`
  is a compare and a copy or negate) touch the sign bit only, a signalling NaN
  stays signalling; MIN/MAX are IEC's compare and select, a move.
* IEEE 754 5.4.2, 6.2.3: REAL <-> LREAL keeps the sign and quiets; widening
  keeps the payload (shifted to the top of the longer significand), narrowing
  keeps its top bits.
* docs/il.md's rule (x86-64 SSE's): a NaN result is the first NaN operand (a
  before b) quieted; with no NaN operand the default NaN, sign set, quiet bit,
  payload 0: 0xFFC00000 / 0xFFF8000000000000.  The C library functions and
  EXPT follow the same rule (glibc's own asin(2) is +NaN, its log(-1) -NaN).

`nan` (REAL) runs on every engine, the C40 included; `nan_64` (LREAL, and the
conversions between the two); `nan_fn`, `nan_fn_64`: the functions and EXPT,
which the C40 refuses by name.
"""

import matiec as m

# the patterns of each type: qp a positive quiet NaN with a payload, qn a
# negative one, sp a positive signalling NaN, sn a negative one
PAT = {
    "REAL": dict(qp=0x7FC12345, qn=0xFFE54321, sp=0x7F800001, sn=0xFF812345,
                 quiet=0x00400000, sign=0x80000000, default=0xFFC00000,
                 zero=0x00000000, neg0=0x80000000, one=0x3F800000, two=0x40000000, mone=0xBF800000,
                 inf=0x7F800000, ninf=0xFF800000, m8=0xC1000000, third=0x3EAAAAAB),
    "LREAL": dict(qp=0x7FF8123456789ABC, qn=0xFFFC000000004321, sp=0x7FF0000000000001, sn=0xFFF0123456789ABB,
                  quiet=0x0008000000000000, sign=0x8000000000000000, default=0xFFF8000000000000,
                  zero=0x0000000000000000, neg0=0x8000000000000000, one=0x3FF0000000000000,
                  two=0x4000000000000000, mone=0xBFF0000000000000, inf=0x7FF0000000000000,
                  ninf=0xFFF0000000000000, m8=0xC020000000000000, third=0x3FD5555555555555),
}
NAMES = {"qp": "+qNaN", "qn": "-qNaN", "sp": "+sNaN", "sn": "-sNaN", "default": "the default NaN",
         "zero": "0.0", "neg0": "-0.0", "one": "1.0", "two": "2.0", "mone": "-1.0", "inf": "+inf", "ninf": "-inf",
         "m8": "-8.0", "third": "1/3"}


def show(t, v):
    return "16#%0*X" % (m.bits(t) // 4, v)


class Cases:
    def __init__(self, Program, name, title):
        self.p = Program(name, title)
        self.p.source = "nans.py, by hand from IEEE 754 and docs/il.md's rule (NaN results)"

    def exact(self, t, dev, v):
        """Watch dev's cells for the pattern v bit for bit."""
        base = int(dev[1:])
        for i, w in enumerate(m.cell_words(t, v)):
            self.p.watch.append(("D%d" % (base + i), [w] * self.p.scans))

    def binop(self, op, t, a, b, r, why, const_b=None):
        """OP.T a b r, a and b from the trace; again with b the IL constant const_b."""
        P = PAT[t]
        for c in ((None, const_b) if const_b else (None,)):
            da = self.p.inp(t, P[a])
            db = c if c else self.p.inp(t, P[b])
            dr = self.p.out(t)
            self.p.rung("%s.%s %s %s = %s: %s%s" % (op, t, NAMES[a], NAMES[b], show(t, r), why,
                                                    " (b the constant %s)" % c if c else ""),
                        ["TRUE", "%s.%s %s %s %s" % (op, t, da, db, dr)])
            self.exact(t, dr, r)

    def unop(self, op, t, a, r, why, frm=None):
        frm = frm or t
        da, dr = self.p.inp(frm, PAT[frm][a]), self.p.out(t)
        ins = "%s.%s %s %s" % (op, t, da, dr) if frm == t else "%s.%s.%s %s %s" % (op, t, frm, da, dr)
        self.p.rung("%s = %s: %s" % (ins.split()[0] + " " + NAMES[a], show(t, r), why), ["TRUE", ins])
        self.exact(t, dr, r)


def first_nan(t, *ops):
    """docs/il.md's rule, by hand: the first operand that is a NaN, quiet bit set."""
    P = PAT[t]
    for o in ops:
        if o in ("qp", "qn", "sp", "sn"):
            return P[o] | P["quiet"]
    return P["default"]


def arithmetic(Program, t, name):
    c = Cases(Program, name, "which NaN ADD SUB MUL DIV, MIN MAX NEG ABS MOVE and a store store, in %s" % t)
    P = PAT[t]
    inv = "invalid (IEEE 754 7.2), no NaN operand: the default NaN"
    for op, a, b in [("DIV", "zero", "zero"), ("DIV", "neg0", "zero"), ("DIV", "inf", "ninf"), ("SUB", "inf", "inf"),
                     ("ADD", "inf", "ninf"), ("MUL", "zero", "inf"), ("MUL", "ninf", "neg0")]:
        c.binop(op, t, a, b, P["default"], inv)
    prop = "a NaN operand: the first one (a before b), quiet bit set, sign and payload kept"
    for op, a, b in [("ADD", "qp", "qn"), ("ADD", "qn", "qp"),  # ldgen seeds 224 and 235: the C compiler swapped these
                     ("ADD", "sp", "one"), ("ADD", "one", "sp"), ("ADD", "sp", "qp"), ("ADD", "qp", "sn"),
                     ("SUB", "one", "qn"), ("SUB", "qn", "qp"), ("SUB", "inf", "sn"), ("SUB", "sn", "inf"),
                     ("MUL", "qp", "zero"), ("MUL", "zero", "sn"), ("MUL", "inf", "qn"), ("MUL", "sn", "sp"),
                     ("DIV", "qp", "qn"), ("DIV", "zero", "sn"), ("DIV", "sn", "zero"), ("DIV", "qn", "sp")]:
        const = "1.0" if b == "one" else "0.0" if b == "zero" else None
        c.binop(op, t, a, b, first_nan(t, a, b), prop, const_b=const)
    move = "a move (IEEE 754 5.5.1): the bits as they are, a signalling NaN stays signalling"
    for op, a, b, r in [("MIN", "sp", "one", "sp"), ("MIN", "one", "qn", "one"), ("MAX", "sn", "two", "sn"),
                        ("MAX", "two", "qp", "two"), ("MIN", "qn", "sp", "qn"), ("MAX", "sp", "sn", "sp")]:
        c.binop(op, t, a, b, P[r], "IEC's compare and select (a NaN b never taken); " + move)
    for a in ("sp", "qn"):
        c.unop("NEG", t, a, P[a] ^ P["sign"], "negate flips the sign bit only (IEEE 754 5.5.1)")
        c.unop("ABS", t, a, P[a], "op < 0 is false for a NaN: op, as it is (" + move + ")")
        c.unop("MOVE", t, a, P[a], move)
    # a NaN made by an operation, stored, moved, compared and used again
    p = c.p
    z, r, mv, r2 = p.inp(t, P["zero"]), p.out(t), p.out(t), p.out(t)
    eq, ne, lt, ge = p.flag(), p.flag(), p.flag(), p.flag()
    p.rung("DIV.%s 0.0 0.0 stored, MOVEd, compared with its copy (only NE holds), then ADD 1.0: the default NaN "
           "all along" % t,
           ["TRUE", "DIV.%s %s %s %s" % (t, z, z, r), "MOVE.%s %s %s" % (t, r, mv), "ADD.%s %s 1.0 %s" % (t, mv, r2),
            "EQ.%s %s %s" % (t, r, mv), "OUT %s" % eq, "NE.%s %s %s" % (t, r, mv), "OUT %s" % ne,
            "LT.%s %s %s" % (t, mv, r), "OUT %s" % lt, "GE.%s %s %s" % (t, mv, mv), "OUT %s" % ge])
    for dev in (r, mv, r2):
        c.exact(t, dev, P["default"])
    for f, v in ((eq, 0), (ne, 1), (lt, 0), (ge, 0)):
        p.watch_bit(f, [v])
    # through an array element: STX then LDX move the bits
    i, arr = p.inp("DINT", 1), p.out(t)
    p.out(t)  # the array's second element
    out = p.out(t)
    s = p.inp(t, P["sn"])
    p.rung("STX.%s -sNaN into array[0..1] element 1, LDX.%s it back: %s, the bits as they are" % (t, t, show(t, P["sn"])),
           ["TRUE", "IDX.DINT %s 0 1" % i, "STX.%s %s %s %d" % (t, s, arr, m.bits(t) // 32 or 1),
            "IDX.DINT %s 0 1" % i, "LDX.%s %s %d %s" % (t, arr, m.bits(t) // 32 or 1, out)])
    c.exact(t, out, P["sn"])
    return c.p


def conversions(Program):
    c = Cases(Program, "nan_conv_64", "REAL <-> LREAL of a NaN: sign kept, quieted, payload shifted or cut")
    R, L = PAT["REAL"], PAT["LREAL"]

    def widen(x):  # sign, all-ones exponent, the 23 significand bits on top of the 52, quiet bit set
        return ((x >> 31) << 63) | (0x7FF << 52) | ((x & 0x7FFFFF) << 29) | L["quiet"]

    def narrow(x):  # the top 23 of the 52 significand bits, quiet bit set
        return ((x >> 63) << 31) | (0xFF << 23) | ((x >> 29) & 0x7FFFFF) | R["quiet"]

    why_w = "IEEE 754 6.2.3: the payload kept, at the top of the wider significand; quiet"
    for a in ("qp", "qn", "sp", "sn"):
        c.unop("CONV", "LREAL", a, widen(R[a]), why_w, frm="REAL")
    why_n = "IEEE 754 6.2.3: the payload's top bits kept; quiet (a payload in the low 29 bits only is lost)"
    for a in ("qp", "qn", "sp", "sn"):
        c.unop("CONV", "REAL", a, narrow(L[a]), why_n, frm="LREAL")
    return c.p


def functions(Program, t, name):
    c = Cases(Program, name, "which NaN the functions and EXPT store, in %s" % t)
    P = PAT[t]
    inv = "outside the domain (IEEE 754 9.2): the default NaN, whatever the C library's NaN"
    for op, a in [("SQRT", "mone"), ("LN", "mone"), ("LOG", "mone"), ("ASIN", "two"), ("ACOS", "m8"),
                  ("SIN", "inf"), ("COS", "ninf"), ("TAN", "inf")]:
        c.unop(op, t, a, P["default"], inv)
    prop = "a NaN operand: itself, quiet bit set, sign and payload kept"
    for op, a in [("SQRT", "sn"), ("LN", "qn"), ("LOG", "sp"), ("EXP", "qn"), ("SIN", "sp"), ("COS", "qp"),
                  ("TAN", "sn"), ("ASIN", "qn"), ("ACOS", "sp"), ("ATAN", "sn")]:
        c.unop(op, t, a, P[a] | P["quiet"], prop)
    c.binop("EXPT", t, "m8", "third", P["default"], "pow of a negative to a non-integer: invalid, the default NaN")
    for a, b in [("qn", "two"), ("two", "sp"), ("qp", "qn"), ("sn", "qp")]:
        c.binop("EXPT", t, a, b, first_nan(t, a, b), "the first NaN operand, quiet bit set",
                const_b="2.0" if b == "two" else None)
    c.binop("EXPT", t, "qn", "zero", P["one"], "C's pow(x, 0) is 1 for a NaN x too (C11 F.10.4.4): no NaN result",
            const_b="0.0")
    c.binop("EXPT", t, "one", "qp", P["one"], "C's pow(1, y) is 1 for a quiet NaN y too (C11 F.10.4.4)")
    return c.p


def untyped(Program):
    """The untyped REAL instructions of F words (paper 003's ADD SUB MUL DIV)
    follow the same rule; typed MOVEs carry the bits between D and F words."""
    c = Cases(Program, "nan_untyped", "which NaN the untyped ADD SUB MUL DIV store in F words (REAL)")
    p, R = c.p, PAT["REAL"]
    qp, sn = p.inp("REAL", R["qp"]), p.inp("REAL", R["sn"])
    p.rung("F2 = inf - inf: the default NaN 16#FFC00000; F3 = ABS F2 (fabsf): 16#7FC00000; F4, F5 = +qNaN, -sNaN "
           "moved from D words (MOVE.REAL: the bits as they are)",
           ["TRUE", "MOV 3.0e38 F0", "MUL F0 F0 F1", "SUB F1 F1 F2", "ABS F2 F3",
            "MOVE.REAL %s F4" % qp, "MOVE.REAL %s F5" % sn])
    cases = [("ADD", "F3", "F2", 0x7FC00000), ("ADD", "F2", "F3", R["default"]), ("SUB", "F3", "F2", 0x7FC00000),
             ("MUL", "F2", "F3", R["default"]), ("DIV", "F3", "F2", 0x7FC00000), ("DIV", "F2", "F3", R["default"]),
             ("ADD", "F4", "F5", R["qp"]), ("ADD", "F5", "F4", R["sn"] | R["quiet"]), ("SUB", "F0", "F5", R["sn"] | R["quiet"]),
             ("MUL", "F5", "F1", R["sn"] | R["quiet"])]
    for k, (op, a, b, r) in enumerate(cases):
        f, d = "F%d" % (10 + k), p.out("REAL")
        p.rung("%s %s %s = %s: the first NaN operand quieted, else the default NaN (docs/il.md)" % (op, a, b, show("REAL", r)),
               ["TRUE", "%s %s %s %s" % (op, a, b, f), "MOVE.REAL %s %s" % (f, d)])
        c.exact("REAL", d, r)
    return p


def programs(Program):
    return [arithmetic(Program, "REAL", "nan"), arithmetic(Program, "LREAL", "nan_64"), conversions(Program),
            untyped(Program),
            functions(Program, "REAL", "nan_fn"), functions(Program, "LREAL", "nan_fn_64")]
