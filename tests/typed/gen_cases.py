#!/usr/bin/env python3
"""tests/typed/gen_cases.py -- writes the conformance cases of the typed IL
(tests/typed/README.md): for each family of typed instructions an ldc IL
program (cases/NAME.il), its input trace (NAME.csv) and the values ldrun must
print (NAME.expected), each expected value computed by matiec.py from
MatIEC's definitions, never by an engine.

A family's cases that touch a 64-bit type go to NAME_64 (the C40 refuses those
programs by name); the others to NAME.

    gen_cases.py [DIR]          write the cases into DIR (default: cases/ beside this file)
    gen_cases.py --check [DIR]  fail if DIR's files differ from what this script writes
"""
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import matiec as m  # noqa: E402

IN_D, OUT_D, IN_M, OUT_M = 0, 4000, 0, 4000  # first D / M of the inputs and of the results
# Before the scan the trace fills every result word with this, and every result
# bit with the opposite of its expected value, so an instruction that does not
# run (or does not store) never passes.
SENTINEL = 0x5A5A5A5A


class Program:
    """One IL program: rungs, input cells (one trace row per scan) and the
    watched results with their expected values."""

    def __init__(self, name, title, scans=1):
        self.name, self.title, self.scans = name, title, scans
        self.rungs = []                      # (comment, [instruction lines])
        self.inputs = []                     # (device, [value per scan])
        self.watch = []                      # (device, [expected per scan])
        self.d_in, self.d_out, self.m_in, self.m_out = IN_D, OUT_D, IN_M, OUT_M
        self.sentinel = scans == 1           # results prefilled by the trace (single-scan programs)
        self.init = []                       # (device, value) written before the scan
        self.source = "matiec.py"            # where the expected values come from (the header says)

    def _cells(self, t, out):
        n = max(1, m.bits(t) // 32) if t != "BOOL" else 1
        if t == "BOOL":
            if out:
                self.m_out += 1
                return "M%d" % (self.m_out - 1)
            self.m_in += 1
            return "M%d" % (self.m_in - 1)
        if out:
            self.d_out += n
            assert self.d_out < 8192, self.name
            if self.sentinel:
                self.init += [("D%d" % (self.d_out - n + i), SENTINEL) for i in range(n)]
            return "D%d" % (self.d_out - n)
        self.d_in += n
        assert self.d_in < OUT_D, self.name
        return "D%d" % (self.d_in - n)

    def inp(self, t, v, raw=None):
        """A device holding v of type t on every scan (or the raw INT32 words
        `raw`, to test what a typed load makes of a cell)."""
        dev = self._cells(t, False)
        if t == "BOOL":
            self.inputs.append((dev, [v] * self.scans))
            return dev
        ws = raw if raw is not None else m.cell_words(t, v)
        base = int(dev[1:])
        for i, w in enumerate(ws):
            self.inputs.append(("D%d" % (base + i), [w] * self.scans))
        return dev

    def out(self, t):
        return self._cells(t, True)

    def flag(self):
        return self._cells("BOOL", True)

    def watch_bit(self, dev, values):
        """Watch the result bit dev for values (one per scan), prefilled with
        the opposite."""
        if self.sentinel:
            self.init.append((dev, 1 - values[0]))
        self.watch.append((dev, values))

    def expect(self, t, dev, v):
        """Watch dev, of type t, for v; a NaN is checked as `NE.T r r` (its
        sign and payload are the hardware's, not MatIEC's)."""
        if t == "BOOL":
            self.watch_bit(dev, [v] * self.scans)
            return
        if m.kind(t) == "real" and m.is_nan(t, v):
            f = self.flag()
            self.rungs.append(("%s is NaN" % dev, ["NE.%s %s %s" % (t, dev, dev), "OUT %s" % f]))
            self.watch_bit(f, [1] * self.scans)
            return
        base = int(dev[1:])
        for i, w in enumerate(m.cell_words(t, v)):
            self.watch.append(("D%d" % (base + i), [w] * self.scans))

    def rung(self, comment, lines):
        self.rungs.append((comment, lines))

    def files(self):
        il = ["; %s" % self.title, "; written by tests/typed/gen_cases.py; expected values from " + self.source]
        for k, (comment, lines) in enumerate(self.rungs, 1):
            il.append(".rung line %d" % k)
            il.append("    ; " + comment)
            il.extend("    " + x for x in lines)
        il.append(".end")
        csv = ["# inputs of %s.il, one row per scan; then the results' prefill" % self.name]
        cols = self.inputs + [(d, [v] * self.scans) for d, v in self.init]
        if cols:
            csv.append(",".join(d for d, _ in cols))
            for s in range(self.scans):
                csv.append(",".join(str(v[s]) for _, v in cols))
        else:
            csv.append("dt")
            csv.extend(["10"] * self.scans)
        exp = ["scan," + ",".join(d for d, _ in self.watch)]
        for s in range(self.scans):
            exp.append(",".join([str(s + 1)] + [str(v[s]) for _, v in self.watch]))
        return {self.name + ".il": "\n".join(il) + "\n", self.name + ".csv": "\n".join(csv) + "\n",
                self.name + ".expected": "\n".join(exp) + "\n"}


class Family:
    """Cases of one family, split by width: NAME (types of up to 32 bits) and
    NAME_64 (a 64-bit type involved)."""

    def __init__(self, name, title):
        self.narrow = Program(name, title)
        self.wide = Program(name + "_64", title + " (64-bit types)")

    def prog(self, *types):
        return self.wide if any(m.wide(t) for t in types) else self.narrow

    def programs(self):
        return [p for p in (self.narrow, self.wide) if p.rungs]


def const_text(t, v):
    """v as an IL constant of t, or None (non-finite reals have no spelling)."""
    if m.kind(t) == "real":
        x = m.rval(t, v)
        return repr(x) if math.isfinite(x) else None
    return str(v)


def show(t, v):
    if t == "BOOL":
        return "TRUE" if v else "FALSE"
    if m.kind(t) == "real":
        return repr(m.rval(t, v))
    return str(v)


# ---------------------------------------------------------------- case makers
def binop(fam, op, t, a, b, r, why, s0=None, const=True):
    """OP.T a b r with a and b from the trace; again with b a constant.  s0:
    the expected S0 (reset before the instruction)."""
    p = fam.prog(t)
    for use_const in ((False, True) if const else (False,)):
        da = p.inp(t, a)
        bt = const_text(t, b) if use_const else None
        if use_const and bt is None:
            continue
        db = bt if use_const else p.inp(t, b)
        dr = p.out(t)
        lines = ["TRUE"] + (["RST S0"] if s0 is not None else []) + ["%s.%s %s %s %s" % (op, t, da, db, dr)]
        if s0 is not None:
            f = p.flag()
            lines += ["LOAD S0", "OUT %s" % f]
            p.watch_bit(f, [s0])
        p.rung("%s.%s %s %s = %s: %s%s" % (op, t, show(t, a), show(t, b), show(t, r), why,
                                           " (the second operand a constant)" if use_const else ""), lines)
        p.expect(t, dr, r)


def unop(fam, op, t, a, r, why):
    p = fam.prog(t)
    da, dr = p.inp(t, a), p.out(t)
    p.rung("%s.%s %s = %s: %s" % (op, t, show(t, a), show(t, r), why), ["TRUE", "%s.%s %s %s" % (op, t, da, dr)])
    p.expect(t, dr, r)


def conv(fam, op, to, frm, v, r, why, raw=None):
    p = fam.prog(to, frm)
    dv, dr = p.inp(frm, v, raw), p.out(to)
    p.rung("%s.%s.%s %s = %s: %s" % (op, to, frm, show(frm, v), show(to, r), why),
           ["TRUE", "%s.%s.%s %s %s" % (op, to, frm, dv, dr)])
    p.expect(to, dr, r)


def compare(fam, rel, t, a, b, why, raw_a=None, raw_b=None):
    p = fam.prog(t)
    da, db = p.inp(t, a, raw_a), p.inp(t, b, raw_b)
    f = p.flag()
    r = m.cmp(rel, t, a, b)
    p.rung("%s.%s %s %s = %d: %s" % (rel, t, show(t, a), show(t, b), r, why), ["%s.%s %s %s" % (rel, t, da, db), "OUT %s" % f])
    p.watch_bit(f, [r])


def shift(fam, op, t, u, a, n, why):
    p = fam.prog(t, u)
    da, dn, dr = p.inp(t, a), p.inp(u, n), p.out(t)
    r = m.shift(op, t, a, n)
    p.rung("%s.%s.%s %s %s = %s: %s" % (op, t, u, a, n, r, why), ["TRUE", "%s.%s.%s %s %s %s" % (op, t, u, da, dn, dr)])
    p.expect(t, dr, r)


# ---------------------------------------------------------------- families
def integer_arithmetic():
    fam = Family("int_arith", "ADD SUB MUL DIV MOD MIN MAX NEG ABS MOVE on SINT..ULINT at their limits")
    for t in m.INTS:
        lo, hi, w = m.lo(t), m.hi(t), m.bits(t)
        sg = m.is_signed(t)
        why_wrap = "C's arithmetic in %s, stored modulo 2^%d" % (t, w)
        for a, b in [(hi, 1), (lo, -1 if sg else 0), (hi, hi), (5, -7 if sg else 7), (lo, lo)]:
            binop(fam, "ADD", t, a, b, m.add(t, a, b), why_wrap)
        for a, b in [(lo, 1), (0, 1), (hi, lo), (lo, hi)]:
            binop(fam, "SUB", t, a, b, m.sub(t, a, b), why_wrap)
        half = 1 << (w // 2)
        for a, b in [(hi, 2), (hi, hi), (half, half), (lo, -1 if sg else 3), (-7 if sg else 7, 3)]:
            binop(fam, "MUL", t, a, b, m.mul(t, a, b), why_wrap)
        div_cases = [(7, 2), (hi, hi), (lo, 1), (hi, 0), (0, 0)]
        if sg:
            div_cases += [(-7, 2), (7, -2), (-7, -2), (lo, -1), (lo, 0)]
        for a, b in div_cases:
            r, s0 = m.div(t, a, b)
            why = "DIV_%s: op2 == 0 gives 0, ENO FALSE (S0)" % t if b == 0 else "C's / toward zero"
            if sg and a == lo and b == -1:
                why = "C's / (%s promoted: wraps when stored)" % t if w < 32 else "wraps (C: undefined; docs/il.md)"
            binop(fam, "DIV", t, a, b, r, why, s0=s0)
        mod_cases = [(7, 2), (hi, 10), (hi, 0), (0, 0)]
        if sg:
            mod_cases += [(-7, 2), (7, -2), (-7, -2), (lo, -1), (lo, 3)]
        for a, b in mod_cases:
            r, s0 = m.mod(t, a, b)
            why = "MOD_%s: if (op2 == 0) return 0" % t if b == 0 else "C's %"
            binop(fam, "MOD", t, a, b, r, why, s0=s0)
        for a, b in [(lo, hi), (hi, lo), (-1 if sg else 1, 1 if sg else 0)]:
            binop(fam, "MIN", t, a, b, m.min_(t, a, b), "MIN: op1 > tmp ? tmp : op1")
            binop(fam, "MAX", t, a, b, m.max_(t, a, b), "MAX: op1 < tmp ? tmp : op1")
        for a in ([lo, hi, 0, -1] if sg else [0, 1, hi]):
            unop(fam, "NEG", t, a, m.neg(t, a), "C's unary -, stored as %s" % t)
        for a in ([lo, -1, hi, 0] if sg else [hi, 0]):
            unop(fam, "ABS", t, a, m.abs_(t, a), "__abs_signed: op < 0 ? -op : op" if sg else "__abs_unsigned: op")
        for a in (lo, hi):
            unop(fam, "MOVE", t, a, a, "MOVE_%s: return op1" % t)
        if w < 32:  # a word cell holding more than the type: the load takes the type's width
            for raw in (70000, -70000, 0x1FF, 0x80):
                p = fam.prog(t)
                v = m.words_to_value(t, [raw])
                dv, dr = p.inp(t, 0, raw=[raw]), p.out(t)
                p.rung("MOVE.%s of a cell holding %d = %d: a typed load takes the low %d bits (docs/il.md)" % (t, raw, v, w),
                       ["TRUE", "MOVE.%s %s %s" % (t, dv, dr)])
                p.expect(t, dr, v)
                dv2, dr2 = p.inp(t, 0, raw=[raw]), p.out(t)
                r = m.add(t, v, 1)
                p.rung("ADD.%s (cell %d) 1 = %d" % (t, raw, r), ["TRUE", "ADD.%s %s 1 %s" % (t, dv2, dr2)])
                p.expect(t, dr2, r)
    return fam


def real_arithmetic():
    fam = Family("real_arith", "REAL and LREAL arithmetic and functions: IEEE at binary32 / binary64, the C library")
    for t in m.REALS:
        B = lambda x, t=t: m.rbits(t, x)  # noqa: E731
        nan, inf, big = m.rbits(t, math.nan), B(math.inf), (m.bits32(3.4028234663852886e38) if t == "REAL" else m.bits64(1.7976931348623157e308))
        sub = 1 if t == "REAL" else 1  # the smallest subnormal's pattern
        neg0 = 1 << (m.bits(t) - 1)
        zero, one, mone, third = B(0.0), B(1.0), B(-1.0), B(1 / 3)
        add_cases = [(big, big), (B(0.1), B(0.2)), (inf, B(-math.inf)), (neg0, neg0), (neg0, zero), (one, sub), (B(16777216.0), one)]
        for a, b in add_cases:
            binop(fam, "ADD", t, a, b, m.add(t, a, b), "IEEE addition in %s" % t)
        for a, b in [(inf, inf), (zero, zero), (neg0, zero), (B(-m.rval(t, big)), big)]:
            binop(fam, "SUB", t, a, b, m.sub(t, a, b), "IEEE subtraction")
        for a, b in [(big, B(2.0)), (sub, B(0.5)), (mone, zero), (inf, zero), (third, B(3.0))]:
            binop(fam, "MUL", t, a, b, m.mul(t, a, b), "IEEE multiplication")
        for a, b in [(one, zero), (mone, zero), (one, neg0), (zero, zero), (one, B(3.0)), (big, B(0.5)), (nan, one)]:
            r, s0 = m.div(t, a, b)
            binop(fam, "DIV", t, a, b, r, "ST's / on %s (IEEE; S0 untouched)" % t, s0=s0)
        for a, b in [(nan, one), (one, nan), (neg0, zero), (zero, neg0), (B(-math.inf), B(5.0))]:
            binop(fam, "MIN", t, a, b, m.min_(t, a, b), "MIN: op1 > tmp ? tmp : op1")
            binop(fam, "MAX", t, a, b, m.max_(t, a, b), "MAX: op1 < tmp ? tmp : op1")
        expts = [(2.0, 10.0), (2.0, 0.5), (-8.0, 1 / 3), (0.0, -1.0), (10.0, 400.0), (10.0, 39.0), (-2.0, 3.0), (1.0, math.nan), (math.nan, 0.0)]
        for a, b in expts:
            a, b = B(a), B(b)
            binop(fam, "EXPT", t, a, b, m.expt(t, a, b), "__expt: pow((double)IN1, (double)IN2), as %s" % t)
        for a in (zero, neg0, inf, nan, B(-2.5)):
            unop(fam, "NEG", t, a, m.neg(t, a), "ST's unary -: the sign flips")
        for a in (neg0, B(-1.5), B(-math.inf), zero, B(2.0)):
            unop(fam, "ABS", t, a, m.abs_(t, a), "__abs_signed: op < 0 ? -op : op")
        fn_cases = {
            "SQRT": [2.0, -1.0, -0.0, math.inf, 1e-300],
            "LN": [0.0, -1.0, 1.0, math.e, math.inf],
            "LOG": [1000.0, 0.0, 1e-5, -2.0],
            "EXP": [1.0, 710.0, 89.0, -1000.0, -0.0],
            "SIN": [math.pi, 1e22, -0.0, 0.5],
            "COS": [0.0, math.pi, 1e22],
            "TAN": [math.pi / 4, math.pi / 2, -0.0],
            "ASIN": [1.0, 2.0, -0.5],
            "ACOS": [-1.0, 1.5, 0.0],
            "ATAN": [math.inf, -0.0, 1.0],
        }
        for name, xs in fn_cases.items():
            for x in xs:
                a = B(x)
                unop(fam, name, t, a, m.fn(name, t, a), "the C library's %s on the double value, as %s" % (name.lower(), t))
    return fam


def bit_strings():
    fam = Family("bits", "AND OR XOR NOT MIN MAX and the shifts on BOOL and BYTE..LWORD")
    for t in m.BITS:
        w, hi = m.bits(t), m.hi(t)
        pat = int("A5" * (w // 8), 16)
        for op, a, b in [("AND", pat, int("3C" * (w // 8), 16)), ("OR", pat, 1), ("XOR", pat, hi), ("AND", hi, 0)]:
            binop(fam, op, t, a, b, m.logic(op, t, a, b), "C's bitwise %s" % op)
        for a in (0, pat, hi):
            unop(fam, "NOT", t, a, m.logic("NOT", t, a), "~op, stored as %s (zero-extended in its cell)" % t)
        for a, b in [(hi, 0), (0, hi), (pat, 1 << (w - 1))]:
            binop(fam, "MIN", t, a, b, m.min_(t, a, b), "MIN on ANY_NBIT: unsigned order")
            binop(fam, "MAX", t, a, b, m.max_(t, a, b), "MAX on ANY_BIT: unsigned order")
        one = 1 | (1 << (w - 1))
        counts = [0, 1, w - 1] + ([w, 31] if w < 32 else [])  # where C defines IN << N (IN promoted to int)
        us = ["INT", "USINT", "DINT", "ULINT", "BYTE", "UDINT"]
        for k, n in enumerate(counts):
            for op in ("SHL", "SHR"):
                u = us[k % len(us)]
                if m.lo(u) <= n <= m.hi(u):
                    shift(fam, op, t, u, pat if k % 2 else one, n, "__shift_: IN %s N" % ("<<" if op == "SHL" else ">>"))
        for k, n in enumerate([0, 1, w - 1, w, w + 3, -1, -w - 1, 1000]):
            for op in ("ROL", "ROR"):
                u = ["INT", "SINT", "DINT", "UINT", "USINT", "LINT", "DINT", "UINT"][k]
                if m.lo(u) <= n <= m.hi(u):
                    shift(fam, op, t, u, pat ^ 1, n, "N %%= %d (as size_t); (IN %s N) | (IN %s (%d-N))" % (w, "<<" if op == "ROL" else ">>", ">>" if op == "ROL" else "<<", w))
    for op, a, b in [("AND", 1, 0), ("AND", 1, 1), ("OR", 0, 0), ("OR", 0, 1), ("XOR", 1, 1), ("XOR", 1, 0)]:
        binop(fam, op, "BOOL", a, b, m.logic(op, "BOOL", a, b), "BOOL %s" % op, const=False)
    for a in (0, 1):
        unop(fam, "NOT", "BOOL", a, 1 - a, "!op")
    for a, b in [(0, 1), (1, 0)]:
        binop(fam, "MIN", "BOOL", a, b, m.min_("BOOL", a, b), "FALSE < TRUE", const=False)
        binop(fam, "MAX", "BOOL", a, b, m.max_("BOOL", a, b), "FALSE < TRUE", const=False)
    return fam


def shifts_beyond_c():
    """Shift counts where C (and so MatIEC) is undefined: docs/il.md's rule (a
    count below 0 or at least the width gives 0), the same on every engine."""
    fam = Family("shift_beyond_c", "SHL SHR with counts C leaves undefined: docs/il.md's rule, not MatIEC's")
    for t in m.BITS:
        w = m.bits(t)
        for n, u in [(-1, "INT"), (w, "UDINT"), (w + 1, "DINT"), (100, "USINT"), (-(1 << 31), "DINT")]:
            for op in ("SHL", "SHR"):
                if m.shift_defined(op, t, n):
                    continue
                p = fam.prog(t, u)
                da, dn, dr = p.inp(t, m.hi(t)), p.inp(u, n), p.out(t)
                p.rung("%s.%s.%s %d %d = 0: C undefined, docs/il.md gives 0" % (op, t, u, m.hi(t), n),
                       ["TRUE", "%s.%s.%s %s %s %s" % (op, t, u, da, dn, dr)])
                p.expect(t, dr, 0)
    return fam


def compares():
    fam = Family("compare", "EQ NE LT LE GT GE on every type: signed, unsigned or IEEE by the type")
    rels = ["EQ", "NE", "LT", "LE", "GT", "GE"]
    for t in m.INTS + m.BITS + m.TIMES + m.DATES:
        lo, hi = m.lo(t), m.hi(t)
        for a, b in [(lo, hi), (hi, lo), (hi, hi)]:
            for rel in rels:
                compare(fam, rel, t, a, b, "%s order" % ("signed" if m.is_signed(t) else "unsigned"))
    for t in ("SINT", "USINT", "INT", "UINT", "BYTE", "WORD"):  # the same cell, read by the type
        for rel in ("LT", "GT"):
            v = m.words_to_value(t, [-1])
            compare(fam, rel, t, v, 0, "a cell holding -1 read as %s is %d" % (t, v), raw_a=[-1])
    for t in m.REALS:
        B = lambda x, t=t: m.rbits(t, x)  # noqa: E731
        nan = m.rbits(t, math.nan)
        for a, b in [(nan, nan), (nan, B(1.0)), (B(-0.0), B(0.0)), (B(-math.inf), B(math.inf)), (B(1.0), B(1.0))]:
            for rel in rels:
                compare(fam, rel, t, a, b, "IEEE: a NaN is unordered, -0.0 == 0.0")
    for a, b in [(0, 1), (1, 1)]:
        for rel in rels:
            compare(fam, rel, "BOOL", a, b, "FALSE < TRUE")
    return fam


def integer_conversions():
    fam = Family("conv_int", "CONV between BOOL, the integers and the bit strings: C's conversions")
    types = ["BOOL"] + m.INTS + m.BITS
    for frm in types:
        vals = [0, 1] if frm == "BOOL" else [m.lo(frm), m.hi(frm), (m.hi(frm) // 3) ^ 0x55]
        if m.is_signed(frm):
            vals.append(-1)
        for to in types:
            if to == frm:
                continue
            for v in vals:
                r = m.conv(to, frm, v)
                why = ("%s_TO_BOOL: op == 0 ? 0 : 1" % frm if to == "BOOL"
                       else "__move_%s: C's conversion (modulo 2^%d)" % (to, m.bits(to)))
                conv(fam, "CONV", to, frm, v, r, why)
    return fam


def real_conversions():
    fam = Family("conv_real", "CONV to and from REAL and LREAL: __real_to_sint / __real_to_uint / __real_to_bit, C's (float)")
    ints = m.INTS + m.BITS
    for frm in m.REALS:
        B = lambda x, t=frm: m.rbits(t, x)  # noqa: E731
        common = [0.5, 1.5, 2.5, -0.5, -1.5, -2.5, 2.4999, 2.5001, 0.49999997, -0.7, -1.0, 40000.0, 300.0,
                  2147483647.0 if frm == "LREAL" else 2147483520.0, 1e30, math.nan, math.inf, -math.inf, 1e19, -1e19,
                  9.3e18]
        if frm == "LREAL":
            common += [4503599627370497.0, -4503599627370497.0, 4503599627370496.5 - 0.5, 9007199254740993.0,
                       0.49999999999999994, 4294967295.5, 1.8446744073709552e19,
                       0.5000000000000001, -0.5000000000000001, 2.5000000000000004, -4503599627370495.5,
                       9007199254740991.0, -9007199254740991.0, 1.4999999999999998]
        for x in common:
            v = B(x)
            for to in ints:
                r = m.conv(to, frm, v)
                why = ("__real_to_sint: __real_round(IN %s 0.5), as LINT, then (%s)" % ("+" if x >= 0 else "-", to)
                       if m.kind(to) == "signed" else "__real_to_uint: IN >= 0 ? __real_round(IN + 0.5) : 0, as LINT, then (%s)" % to)
                if math.isnan(x) or abs(x) >= 2**63:
                    why += "; (LINT) of it is cvttsd2si's INT64_MIN"
                conv(fam, "CONV", to, frm, v, r, why)
        for x in (0.0, -0.0, math.nan, 1e-45, -2.0):
            conv(fam, "CONV", "BOOL", frm, B(x), m.conv("BOOL", frm, B(x)), "__convert_num_to_bool: op == 0 ? 0 : 1")
        other = "LREAL" if frm == "REAL" else "REAL"
        xs = [0.1, -0.0, math.nan, math.inf, 1e-45, 3.4028235677973366e38, 1e39, 1e-50, 16777217.0] if frm == "LREAL" else [0.1, -0.0, math.inf, 1e-45, 3.4e38]
        for x in xs:
            v = B(x)
            conv(fam, "CONV", other, frm, v, m.conv(other, frm, v), "__move_%s: C's conversion" % other)
    for to in m.REALS:
        for frm in ["BOOL"] + ints:
            vals = [1] if frm == "BOOL" else sorted({m.lo(frm), m.hi(frm), m.wrap(frm, 16777217), m.wrap(frm, 16777219),
                                                     m.wrap(frm, (1 << 53) + 1), m.wrap(frm, -3)})
            for v in vals:
                conv(fam, "CONV", to, frm, v, m.conv(to, frm, v), "__move_%s: C's conversion, to nearest even" % to)
    return fam


def truncs():
    fam = Family("trunc", "TRUNC: C's conversion of the float toward zero, where it is defined")
    for frm in m.REALS:
        for to in m.INTS:
            for x in (2.7, -2.7, 0.9999, -0.9999, m.hi(to) + 0.5, m.lo(to) - 0.5, float(m.hi(to)), 1e-30):
                v = m.rbits(frm, x)
                r = m.trunc(to, frm, v)
                if r is None:
                    continue  # C leaves it undefined: not a MatIEC value
                conv(fam, "TRUNC", to, frm, v, r, "(%s)op: toward zero" % to)
    return fam


def times():
    fam = Family("time", "TIME and the dates: MatIEC's timespec conversions and arithmetic")
    S = m.NS_PER_S
    for frm, vals in [("DINT", [1500, -3, 0, 2147483647]), ("BOOL", [1]), ("UDINT", [4294967295]), ("SINT", [-128]),
                      ("LINT", [9223372036]), ("WORD", [65535])]:
        for to in ("TIME", "DATE", "DT", "TOD"):
            for v in vals:
                conv(fam, "CONV", to, frm, v, m.conv(to, frm, v), "__int_to_time(LINT IN): {IN, 0}: IN seconds")
    for frm in m.TIMES + m.DATES:
        for v in (1500000000, -1500000000, 59999999999, 300 * S, 1, -1):
            for to in ("DINT", "SINT", "UDINT", "LINT", "DWORD"):
                conv(fam, "CONV", to, frm, v, m.conv(to, frm, v), "__time_to_int: tv_sec (toward zero), then (%s)" % to)
    for frm in ("TIME", "DT"):
        for v in (1500000000, -250000000, 1, 86400 * S * 365 * 50 + 123456789):
            for to in m.REALS:
                conv(fam, "CONV", to, frm, v, m.conv(to, frm, v), "__time_to_real: (LREAL)tv_sec + (LREAL)tv_nsec/1e9")
            conv(fam, "CONV", "BOOL", frm, v, 1, "__convert_time_to_bool")
        conv(fam, "CONV", "BOOL", frm, 0, 0, "__convert_time_to_bool: tv_sec == 0 && tv_nsec == 0 ? 0 : 1")
    for frm in m.REALS:
        for x in (1.5, -2.25, 0.1, 1e-9, 59.9999999, -0.0, 1e9):
            v = m.rbits(frm, x)
            for to in ("TIME", "DT"):
                conv(fam, "CONV", to, frm, v, m.conv(to, frm, v), "__real_to_time: {IN, (IN - (LINT)IN) * 1e9}: seconds")
    day = 86400 * S
    for v in (19899 * day + 56215360000000, 0, -S // 2, -day, -day - S // 2, -1, day - 1):
        for to in ("DATE", "TOD"):
            conv(fam, "CONV", to, "DT", v, m.conv(to, "DT", v),
                 "__date_and_time_to_%s: C's %% on tv_sec" % ("date" if to == "DATE" else "time_of_day"))
    for t in m.TIMES:
        for a, b in [(1500000000, 2700000000), (0, 1), (-S, S // 2)]:
            binop(fam, "ADD", t, a, b, m.add(t, a, b), "__time_add")
            binop(fam, "SUB", t, a, b, m.sub(t, a, b), "__time_sub")
            binop(fam, "MIN", t, a, b, m.min_(t, a, b), "MIN: __time_cmp(op1, tmp) > 0")
            binop(fam, "MAX", t, a, b, m.max_(t, a, b), "MAX: __time_cmp(op1, tmp) < 0")
    for t in m.DATES:
        for a, b in [(5 * S, 3 * S), (-1, 0)]:
            binop(fam, "MIN", t, a, b, m.min_(t, a, b), "MIN: __time_cmp")
            binop(fam, "MAX", t, a, b, m.max_(t, a, b), "MAX: __time_cmp")
    return fam


FAMILIES = [integer_arithmetic, real_arithmetic, bit_strings, shifts_beyond_c, compares, integer_conversions,
            real_conversions, truncs, times]


def all_files():
    files = {}
    for make in FAMILIES:
        for p in make().programs():
            files.update(p.files())
    import arrays  # the array cases are hand-derived (docs/il.md "Index faults")
    for p in arrays.programs(Program):
        files.update(p.files())
    import nans  # which NaN an operation stores: by hand from IEEE 754 and docs/il.md's rule
    for p in nans.programs(Program):
        files.update(p.files())
    import strings  # STRING: MatIEC's Table 29 and conversions, transcribed in strings.py
    for p in strings.programs(Program):
        files.update(p.files())
    return files


def main(argv):
    check = "--check" in argv
    args = [a for a in argv if a != "--check"]
    here = os.path.dirname(os.path.abspath(__file__))
    out = args[0] if args else os.path.join(here, "cases")
    files = all_files()
    if check:
        bad = []
        names = set(os.listdir(out)) if os.path.isdir(out) else set()
        for name, text in sorted(files.items()):
            path = os.path.join(out, name)
            if not os.path.exists(path) or open(path).read() != text:
                bad.append(name)
        bad += sorted(names - set(files))
        if bad:
            print("tests/typed/cases is not what gen_cases.py writes (run it to refresh): " + " ".join(bad[:20]))
            return 1
        print("%d files current" % len(files))
        return 0
    os.makedirs(out, exist_ok=True)
    for name in os.listdir(out):
        if name not in files:
            os.remove(os.path.join(out, name))
    for name, text in files.items():
        with open(os.path.join(out, name), "w") as f:
            f.write(text)
    print("wrote %d files to %s" % (len(files), out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
