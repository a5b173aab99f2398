#!/usr/bin/python3
"""Timers and counters on Modbus (docs/runtime.md, "The map"), with mbpoll.

modbus_timers.py LDRUN SOURCE_ROOT
modbus/timers.ld on --clock=virtual (dt = the 1 ms period each scan). Expected
values by hand: three rising edges of M0 (coil 8192, each write taken by its
own scan) count C2 to 3 = its preset, so [C2] (discrete input 8448 + 2) is on
and C2 reads 0, 3 at input registers 1536 + 2*2 = 1540, 1541; M1 (coil 8193)
on for more than 500 scans runs T1 to its preset: ET = 500 at input registers
1024 + 2*1 = 1026, 1027 (it stops there) and [T1] (discrete input 8193) on.
Modbus writes no input register or discrete input (no function code does), so
they are read-only; holding register 1026 stays D1 (0), and 2048 is exception 02.
"""
import os
import shutil
import sys
import time

if not shutil.which("mbpoll"):
    print("skipped: mbpoll is not installed (.ci/run installs it)")
    sys.exit(77)

LDRUN, SRC = sys.argv[1], sys.argv[2]
PROG = os.path.join(SRC, "tests/runtime/net/modbus/timers.ld")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish, mbpoll, start_modbus  # noqa: E402 (beside this file)



p, port = start_modbus([LDRUN, PROG, "--io=none", "--period", "1ms", "--clock=virtual", "--modbus", "127.0.0.1:0"])
try:
    check("C2 before", mbpoll(port, "-t", "3", "-r", "1540", "-c", "2", "127.0.0.1"), [0, 0])
    for k in range(3):
        check("M0 on %d" % k, mbpoll(port, "-t", "0", "-r", "8192", "127.0.0.1", "1"), "written")
        check("M0 off %d" % k, mbpoll(port, "-t", "0", "-r", "8192", "127.0.0.1", "0"), "written")
    check("C2 = 3", mbpoll(port, "-t", "3", "-r", "1540", "-c", "2", "127.0.0.1"), [0, 3])
    check("[C2] on, [C3] off", mbpoll(port, "-t", "1", "-r", "8450", "-c", "2", "127.0.0.1"), [1, 0])
    check("M1 on", mbpoll(port, "-t", "0", "-r", "8193", "127.0.0.1", "1"), "written")
    time.sleep(1.5)  # 1,500 scans of 1 ms at least: T1 is done long before
    check("T1 = 500", mbpoll(port, "-t", "3", "-r", "1026", "-c", "2", "127.0.0.1"), [0, 500])
    check("[T1] on", mbpoll(port, "-t", "1", "-r", "8193", "127.0.0.1"), [1])
    check("holding 1026 is still D1", mbpoll(port, "-t", "4", "-r", "1026", "-c", "2", "127.0.0.1"), [0, 0])
    check("past the counters (2048)", "Illegal data address" in str(mbpoll(port, "-t", "3", "-r", "2048", "127.0.0.1")), True)
finally:
    p.terminate()
    p.wait(10)
finish()
