"""tests/typed/arrays.py -- the array cases of the conformance tests: IDX, LDX
and STX (docs/il.md, "Index faults").  MatIEC does not check an index (C's
a[i] outside the array is undefined), so these expected values are derived by
hand from docs/il.md: element base + (i - lo) * stride; an index outside
lo..hi ends the scan at the IDX, so the rest of its rung and the rungs after
it do not run in that scan.
"""
import matiec as m

SENTINEL = 0x5A5A5A5A  # gen_cases.py's prefill of a result word


def fill(p, t, values):
    """Consecutive input cells holding `values` of t; the first one's device."""
    devs = [p.inp(t, v) for v in values]
    return devs[0]


def offset(dev, k):
    return "%s%d" % (dev[0], int(dev[1:]) + k)


def loads(Program):
    p = Program("array", "IDX with LDX / STX on arrays of INT, DINT, BOOL, REAL and of structures")
    # ARRAY[1..10] OF INT, element k holding 10k+1
    a = fill(p, "INT", [10 * k + 1 for k in range(10)])
    for i in (1, 5, 10):
        di, dr = p.inp("INT", i), p.out("INT")
        p.rung("INT array[1..10], index %d: element %d = %d" % (i, i - 1, 10 * (i - 1) + 1),
               ["TRUE", "IDX.INT %s 1 10" % di, "LDX.INT %s 1 %s" % (a, dr)])
        p.expect("INT", dr, 10 * (i - 1) + 1)
    # ARRAY[-5..5] OF DINT, element k holding -1000k
    b = fill(p, "DINT", [-1000 * k for k in range(11)])
    for i in (-5, 0, 5):
        di, dr = p.inp("DINT", i), p.out("DINT")
        p.rung("DINT array[-5..5], index %d: element %d" % (i, i + 5), ["TRUE", "IDX.DINT %s -5 5" % di, "LDX.DINT %s 1 %s" % (b, dr)])
        p.expect("DINT", dr, -1000 * (i + 5))
    # ARRAY[0..3] OF BOOL (bits), index a USINT
    c = fill(p, "BOOL", [0, 1, 1, 0])
    for i, v in ((1, 1), (3, 0)):
        di, dr = p.inp("USINT", i), p.out("BOOL")
        p.rung("BOOL array[0..3], index %d = %d" % (i, v), ["TRUE", "IDX.USINT %s 0 3" % di, "LDX.BOOL %s 1 %s" % (c, dr)])
        p.expect("BOOL", dr, v)
    # ARRAY[0..3] OF STRUCT a: DINT; b: REAL; c: INT END_STRUCT: stride 3, b at +1, c at +2
    recs = []
    for k in range(4):
        recs += [("DINT", 7 * k), ("REAL", m.bits32(k + 0.25)), ("INT", -k)]
    first = None
    for t, v in recs:
        d = p.inp(t, v)
        first = first or d
    for i in (0, 3):
        di, db, dc = p.inp("INT", i), p.out("REAL"), p.out("INT")
        p.rung("struct array[0..3], record %d: member b at +1 = %s, c at +2 = %d" % (i, i + 0.25, -i),
               ["TRUE", "IDX.INT %s 0 3" % di, "LDX.REAL %s 3 %s" % (offset(first, 1), db),
                "IDX.INT %s 0 3" % di, "LDX.INT %s 3 %s" % (offset(first, 2), dc)])
        p.expect("REAL", db, m.bits32(i + 0.25))
        p.expect("INT", dc, -i)
    # an element cell holding more than an INT: the typed load takes 16 bits
    raw = p.inp("INT", 0, raw=[70000])
    di, dr = p.inp("INT", 0), p.out("INT")
    p.rung("INT array[0..0] whose cell holds 70000: LDX.INT reads 4464", ["TRUE", "IDX.INT %s 0 0" % di, "LDX.INT %s 1 %s" % (raw, dr)])
    p.expect("INT", dr, 4464)
    # STX: ARRAY[0..3] OF DINT (result cells, 0 before the scan), element 2 := 77
    arr = [p.out("DINT") for _ in range(4)]
    di = p.inp("DINT", 2)
    p.rung("STX.DINT 77 into DINT array[0..3] at 2", ["TRUE", "IDX.DINT %s 0 3" % di, "STX.DINT 77 %s 1" % arr[0]])
    for k, d in enumerate(arr):
        p.expect("DINT", d, 77 if k == 2 else SENTINEL)
    bits = [p.flag() for _ in range(3)]
    di = p.inp("SINT", -1)
    p.rung("STX.BOOL TRUE into BOOL array[-2..0] at -1", ["TRUE", "IDX.SINT %s -2 0" % di, "STX.BOOL 1 %s 1" % bits[0]])
    for k, d in enumerate(bits):  # prefilled with 0: only element -1 becomes TRUE
        p.init.append((d, 0))
        p.watch.append((d, [1 if k == 1 else 0]))
    return p


def loads64(Program):
    p = Program("array_64", "IDX with LDX / STX on arrays of LINT and LREAL (two cells an element)")
    vals = [-(1 << 63), (1 << 40) + 3, -1]
    a = fill(p, "LINT", vals)
    for i in (0, 2):
        di, dr = p.inp("ULINT", i), p.out("LINT")
        p.rung("LINT array[0..2], ULINT index %d" % i, ["TRUE", "IDX.ULINT %s 0 2" % di, "LDX.LINT %s 2 %s" % (a, dr)])
        p.expect("LINT", dr, vals[i])
    arr = [p.out("LREAL") for _ in range(3)]
    di = p.inp("LINT", 11)
    v = m.bits64(-2.5e-300)
    p.rung("STX.LREAL into LREAL array[10..12] at 11", ["TRUE", "IDX.LINT %s 10 12" % di, "STX.LREAL -2.5e-300 %s 2" % arr[0]])
    for k, d in enumerate(arr):
        p.expect("LREAL", d, v if k == 1 else SENTINEL | SENTINEL << 32)
    return p


def fault(Program, name, t, indices, lo, hi):
    """Scans with the indices given; those outside lo..hi end the scan at the IDX."""
    p = Program(name, "an index outside %d..%d ends the scan at its IDX (docs/il.md, Index faults)" % (lo, hi),
                scans=len(indices))
    cells = m.cell_words(t, 0)
    first = "D0"
    for k in range(len(cells)):
        p.inputs.append(("D%d" % k, [m.cell_words(t, i)[k] for i in indices]))
    p.d_in = len(cells)
    before, same, after = p.out("DINT"), p.out("DINT"), p.out("DINT")
    arr = [p.out("DINT") for _ in range(hi - lo + 1)]
    p.rung("counts every scan", ["TRUE", "ADD.DINT %s 1 %s" % (before, before)])
    p.rung("counts, then IDX: the STX stores the scan's count in element i",
           ["TRUE", "ADD.DINT %s 1 %s" % (same, same), "IDX.%s %s %d %d" % (t, first, lo, hi),
            "STX.DINT %s %s 1" % (before, arr[0])])
    p.rung("counts the scans that get past the IDX", ["TRUE", "ADD.DINT %s 1 %s" % (after, after)])
    counts, past, elems = [], [], [0] * len(arr)
    per_scan = []
    for s, i in enumerate(indices, 1):
        ok = lo <= i <= hi
        if ok:
            elems[i - lo] = s
        counts.append(s)
        past.append((past[-1] if past else 0) + (1 if ok else 0))
        per_scan.append(list(elems))
    p.watch.append((before, counts))
    p.watch.append((same, counts))
    p.watch.append((after, past))
    for k, d in enumerate(arr):
        p.watch.append((d, [e[k] for e in per_scan]))
    return p


def programs(Program):
    return [loads(Program), loads64(Program),
            fault(Program, "array_fault", "INT", [2, 4, -1, 0, 32767, 1], 0, 3),
            fault(Program, "array_fault_neg", "SINT", [-3, -128, -1, 127, -2], -3, -1),
            fault(Program, "array_fault_udint", "UDINT", [1, 4294967295, 2147483648, 0], 0, 2),
            fault(Program, "array_fault_64", "ULINT", [1, (1 << 63) + 1, (1 << 64) - 1, 2, 1 << 32], 0, 2),
            fault(Program, "array_fault_lint_64", "LINT", [-(1 << 63), 5, (1 << 32) + 1, 4], 3, 5)]
