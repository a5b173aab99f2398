#!/usr/bin/env python3
"""tests/typed/explain.py CASE.il CASE.expected OUTPUT -- names the cases
whose watched values differ: for each differing column, the comment of the
rung that writes it (what the instruction is and where its expected value
comes from), the expected and the printed value.  check_typed.sh calls it on
a mismatch; the raw rows are too wide to read."""
import re
import sys


def writers(il_path):
    """device -> the comment of the last rung whose last operand it is (or
    whose OUT it is)."""
    out, comment = {}, ""
    for line in open(il_path):
        s = line.strip()
        if s.startswith(";"):
            comment = s[1:].strip()
            continue
        toks = s.split()
        if not toks or toks[0].startswith("."):
            continue
        dev = toks[-1] if len(toks) > 1 else None
        if toks[0].startswith("STX"):
            dev = toks[2]
        if dev and re.fullmatch(r"[DM]\d+", dev):
            out[dev] = comment
            if re.fullmatch(r"D\d+", dev):  # a 64-bit result's second cell
                out.setdefault("D%d" % (int(dev[1:]) + 1), comment)
    return out


def rows(path):
    lines = [l.rstrip("\n").split(",") for l in open(path) if l.strip()]
    return lines[0], lines[1:]


def main(il, expected, output):
    who = writers(il)
    head, exp = rows(expected)
    head2, got = rows(output)
    if head != head2:
        print("the watched columns differ:\n  expected %s\n  printed  %s" % (",".join(head)[:200], ",".join(head2)[:200]))
        return 1
    shown = 0
    for s in range(max(len(exp), len(got))):
        e = exp[s] if s < len(exp) else []
        g = got[s] if s < len(got) else []
        for i, col in enumerate(head):
            ev = e[i] if i < len(e) else "(none)"
            gv = g[i] if i < len(g) else "(none)"
            if ev != gv:
                shown += 1
                if shown <= 40:
                    print("scan %d %s: expected %s, printed %s   [%s]" % (s + 1, col, ev, gv, who.get(col, "?")))
    if shown > 40:
        print("... %d differing values in all" % shown)
    return 1 if shown else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
