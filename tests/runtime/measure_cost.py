#!/usr/bin/python3
"""What the monitor costs the scan: not a test (timing is measured, never asserted).

measure_cost.py LDRUN_DIR SOURCE_ROOT [SCANS]
Runs examples/traffic.ld at a 1 ms period for SCANS scans (default 10000) with
--stats: without the monitor, with it and no page, with 1 and with 20
event-stream clients, and prints each run's statistics (docs/runtime.md).
"""
import os
import signal
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
LDRUN_DIR, ROOT = sys.argv[1:3]
SCANS = sys.argv[3] if len(sys.argv) > 3 else "10000"
sys.argv = [sys.argv[0], LDRUN_DIR, "", ROOT, "none"]
import monitor_test as mt  # noqa: E402

base = ["examples/traffic.ld", "--io=none", "--period", "1ms", "--scans", SCANS, "--stats"]
r = subprocess.run([os.path.join(LDRUN_DIR, "ldrun")] + base, cwd=ROOT, capture_output=True, text=True)
print("== no monitor\n" + r.stderr)
for clients in (0, 1, 20):
    m = mt.Ldrun(base + ["--monitor", "127.0.0.1:0"])
    stop = time.time() + int(SCANS) / 1000.0 + 0.5
    ts = [threading.Thread(target=mt.events, args=(m.port, stop - time.time())) for _ in range(clients)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    time.sleep(max(0, stop - time.time()))
    print("== monitor, %d event-stream clients\n%s" % (clients, m.stop()))
