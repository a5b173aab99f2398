#!/usr/bin/env python3
"""Writes st_matiec_timers.expected: MatIEC's meaning of st_matiec_timers.st
over st_matiec_timers.csv, transcribed from MatIEC (github.com/beremiz/matiec)
lib/timer.txt (TON, TOF, TP), CURRENT_TIME + 10 ms each scan.  Never an ldc
engine.
  st_matiec_timers.py          prints the expected trace
  st_matiec_timers.py --check  fails if st_matiec_timers.expected differs
"""
import csv, os, sys

HERE = os.path.dirname(os.path.abspath(__file__))
MS = 1000000  # TIME in ns


class Timer:
    def __init__(self):
        self.state, self.prev_in, self.q, self.et, self.start = 0, False, False, 0, 0


def ton(s, IN, PT, now):
    if s.state == 0 and not s.prev_in and IN:
        s.state, s.q, s.start = 1, False, now
    elif not IN:
        s.et, s.q, s.state = 0, False, 0
    elif s.state == 1:
        if s.start + PT <= now:
            s.state, s.q, s.et = 2, True, PT
        else:
            s.et = now - s.start
    s.prev_in = IN


def tof(s, IN, PT, now):
    if s.state == 0 and s.prev_in and not IN:
        s.state, s.start = 1, now
    elif IN:
        s.et, s.state = 0, 0
    elif s.state == 1:
        if s.start + PT <= now:
            s.state, s.et = 2, PT
        else:
            s.et = now - s.start
    s.q = IN or s.state == 1
    s.prev_in = IN


def tp(s, IN, PT, now):
    if s.state == 0 and not s.prev_in and IN:
        s.state, s.q, s.start = 1, True, now
    elif s.state == 1:
        if s.start + PT <= now:
            s.state, s.q, s.et = 2, False, PT
        else:
            s.et = now - s.start
    if s.state == 2 and not IN:
        s.et, s.state = 0, 0
    s.prev_in = IN


def time_literal(ns):
    """ldrun's TIME format (docs/format.md, Traces): T#, units d h m s ms us ns, zeros left out."""
    if ns == 0:
        return "T#0s"
    out, neg = "", ns < 0
    ns = abs(ns)
    for unit, size in (("d", 86400 * 10**9), ("h", 3600 * 10**9), ("m", 60 * 10**9), ("s", 10**9), ("ms", 10**6),
                       ("us", 1000), ("ns", 1)):
        if ns >= size:
            out += str(ns // size) + unit
            ns %= size
    return "T#" + ("-" if neg else "") + out


def parse_time(t):
    assert t.startswith("T#") and t.endswith("ms"), t
    return int(float(t[2:-2]) * MS)


def rows():
    a = b = False
    p = 20 * MS
    timers = {n: Timer() for n in ("t0", "f0", "p0", "tp_on", "tf", "tp")}
    with open(os.path.join(HERE, "st_matiec_timers.csv")) as f:
        lines = [l for l in f if not l.startswith("#")]
    out = ["scan,q0,e0,qf0,ef0,qp0,ep0,qon,eon,qf,ef,qp,ep"]
    for k, r in enumerate(csv.DictReader(lines), 1):
        a, b = r["a"] == "1", r["b"] == "1"
        if r["p"]:
            p = parse_time(r["p"])
        now = (k - 1) * 10 * MS
        ton(timers["t0"], a, 0, now)
        tof(timers["f0"], a, 0, now)
        tp(timers["p0"], a, 0, now)
        ton(timers["tp_on"], b, p, now)
        tof(timers["tf"], b, 12500000, now)
        tp(timers["tp"], b, p, now)
        cells = [str(k)]
        for n in ("t0", "f0", "p0", "tp_on", "tf", "tp"):
            cells += [str(int(timers[n].q)), time_literal(timers[n].et)]
        out.append(",".join(cells))
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    text = rows()
    if sys.argv[1:] == ["--check"]:
        with open(os.path.join(HERE, "st_matiec_timers.expected")) as f:
            if f.read() != text:
                sys.exit("st_matiec_timers.expected is stale: run tests/frontend/st/st_matiec_timers.py > tests/frontend/st/st_matiec_timers.expected")
    else:
        sys.stdout.write(text)
