#!/usr/bin/python3
"""Named variables on Modbus (ldrun --modbus-map, docs/runtime.md "Modbus TCP").

modbus_names.py LDRUN SOURCE_ROOT
tests/runtime/names.st with tests/runtime/names.map, driven by mbpoll (a real
client). Expected values by hand:
  t := T#1h2m3s500ms = 3723.5 s = 3723500000000 ns = 0x0000_0362_F1E5_1300:
       registers 0, 866, 61925, 4864 (most significant first)
  tt = t + t = 7447000000000 ns = 0x0000_06C5_E3CA_2600: 0, 1733, 58314, 9728
  c[2] := 0 -> c[3] = c[2] - 1 in UDINT = 0xFFFFFFFF: 65535, 65535
  tank.level := 11 reads back 11; busy := 1 -> idle = NOT busy = 0
  r := 0.1 as REAL: 0x3DCCCCCD, registers 15820, 52429, read back unchanged
A register outside the device map and the named ones is exception 02; a map
naming a located variable, or an address inside the device map, is refused.
"""
import os
import shutil
import subprocess
import sys
import time

if not shutil.which("mbpoll"):
    print("skipped: mbpoll is not installed (.ci/run installs it)")
    sys.exit(77)

LDRUN, SRC = sys.argv[1], sys.argv[2]
NAMES = os.path.join(SRC, "tests/runtime/names.st")
MAP = os.path.join(SRC, "tests/runtime/names.map")
from checks import check, failures, finish, mbpoll, start_modbus  # noqa: E402 (beside this file)



assert 3723500000000 == (866 << 32) + (61925 << 16) + 4864
assert 2 * 3723500000000 == (1733 << 32) + (58314 << 16) + 9728
p, port = start_modbus([LDRUN, NAMES, "--io=none", "--period", "10ms", "--modbus", "127.0.0.1:0", "--modbus-map", MAP])
try:
    H = ["-t", "4"]
    check("write tank.level", mbpoll(port, *H, "-r", "20000", "127.0.0.1", "11"), "written")
    check("write t", mbpoll(port, *H, "-r", "20001", "127.0.0.1", "0", "866", "61925", "4864"), "written")
    check("write c[2]", mbpoll(port, *H, "-r", "20009", "127.0.0.1", "0", "0"), "written")
    check("write r", mbpoll(port, *H, "-r", "20013", "127.0.0.1", "15820", "52429"), "written")
    check("write busy", mbpoll(port, "-t", "0", "-r", "24576", "127.0.0.1", "1"), "written")
    time.sleep(0.3)
    check("tank.level", mbpoll(port, *H, "-r", "20000", "127.0.0.1"), [11])
    check("t", mbpoll(port, *H, "-r", "20001", "-c", "4", "127.0.0.1"), [0, 866, 61925, 4864])
    check("tt = t + t", mbpoll(port, *H, "-r", "20005", "-c", "4", "127.0.0.1"), [0, 1733, 58314, 9728])
    check("c[3] = c[2] - 1", mbpoll(port, *H, "-r", "20011", "-c", "2", "127.0.0.1"), [65535, 65535])
    check("r", mbpoll(port, *H, "-r", "20013", "-c", "2", "127.0.0.1"), [15820, 52429])
    check("busy, idle", mbpoll(port, "-t", "0", "-r", "24576", "-c", "2", "127.0.0.1"), [1, 0])
    check("unmapped 19999", "Illegal data address" in str(mbpoll(port, *H, "-r", "19999", "127.0.0.1")), True)
    check("past the map 20015", "Illegal data address" in str(mbpoll(port, *H, "-r", "20015", "127.0.0.1")), True)
finally:
    p.terminate()
    p.wait(10)

for text, want in (("motor coil 24576\n", "bad.map:1:1: error: 'motor' is located (Y0)"),
                   ("tank.level holding 100\n", "bad.map:1:20: error: holding registers of named variables are 19456..65535"),
                   ("tank.level holding 20000\nt holding 20000\n", "bad.map:2:11: error: 't' overlaps 'tank.level'"),
                   ("busy holding 20000\n", "bad.map:1:6: error: 'busy' is a BOOL: map it to a coil")):
    path = os.path.join(os.environ.get("TMPDIR", "/tmp"), "bad.map")
    with open(path, "w") as f:
        f.write(text)
    r = subprocess.run([LDRUN, NAMES, "--io=none", "--modbus", "127.0.0.1:0", "--modbus-map", path],
                       capture_output=True, text=True, timeout=30)
    check("refused: " + text.strip().replace("\n", "; "), (r.returncode, want in r.stderr), (1, True))
    if want not in r.stderr:
        print(r.stderr)
    os.unlink(path)

finish()
