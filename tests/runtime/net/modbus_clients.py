#!/usr/bin/python3
"""ldrun --modbus with real Modbus clients (docs/runtime.md, "Modbus TCP").

usage: modbus_clients.py LDRUN SRCDIR

Runs tests/runtime/net/modbus/echo.ld under ldrun --io=stdio --modbus 127.0.0.1:0 and
drives it with mbpoll and pymodbus: every area of the map read and written, a
write reaching the program's outputs on the next scan, exception replies, bad
frames.  Then the trace mode (--trace with --modbus).  Every step has a timeout;
exit status 0 on success, 1 with the failures listed.
"""
import os
import re
import select
import socket
import struct
import subprocess
import sys
import tempfile
import time

import shutil

try:
    from pymodbus.client import ModbusTcpClient
except ImportError:
    print("skipped: python3-pymodbus is not installed (.ci/run installs it)")
    sys.exit(77)
if not shutil.which("mbpoll"):
    print("skipped: mbpoll is not installed (.ci/run installs it)")
    sys.exit(77)

LDRUN, SRC = sys.argv[1], sys.argv[2]
ECHO = os.path.join(SRC, "tests/runtime/net/modbus/echo.ld")
from checks import check, failures, finish  # noqa: E402 (beside this file)


def start(args):
    """Starts ldrun, returns (process, port) once it listens."""
    p = subprocess.Popen([LDRUN] + args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, bufsize=1)
    deadline = time.time() + 20
    line = ""
    while time.time() < deadline:
        r, _, _ = select.select([p.stderr], [], [], 0.5)
        if r:
            line = p.stderr.readline()
            m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
            if m:
                return p, int(m.group(1))
            if not line:
                break
    p.kill()
    raise SystemExit("ldrun did not listen: " + line + p.stderr.read())


def command(p, line):
    """One line of the line protocol; its reply."""
    p.stdin.write(line + "\n")
    p.stdin.flush()
    r, _, _ = select.select([p.stdout], [], [], 30)
    if not r:
        raise SystemExit("no reply to " + line)
    return p.stdout.readline().strip()


def mbpoll(port, *args):
    """mbpoll once with 0-based addresses: the values it printed, or its error line."""
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(port), "-0", "-1", "-o", "5"] + list(args),
                         capture_output=True, text=True, timeout=30)
    values = re.findall(r"^\[\d+\]:\s+(-?[0-9.]+)", out.stdout, re.M)
    if values:
        return [float(v) if "." in v else int(v) for v in values]
    if "Written" in out.stdout:
        return "written"
    return (out.stdout + out.stderr).strip().splitlines()[-1] if (out.stdout + out.stderr).strip() else "?"


def raw(port, frame, unit_reply=True):
    """Sends raw bytes; the reply's PDU, or 'closed'."""
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    try:
        s.sendall(frame)
        head = b""
        while len(head) < 7:
            b = s.recv(7 - len(head))
            if not b:
                return "closed"
            head += b
        n = struct.unpack(">H", head[4:6])[0] - 1
        pdu = b""
        while len(pdu) < n:
            b = s.recv(n - len(pdu))
            if not b:
                return "closed"
            pdu += b
        return pdu.hex()
    except (ConnectionResetError, socket.timeout) as e:
        return "closed" if isinstance(e, ConnectionResetError) else "timeout"
    finally:
        s.close()


def adu(pdu, unit=1, tid=1, proto=0, length=None):
    return struct.pack(">HHHB", tid, proto, len(pdu) + 1 if length is None else length, unit) + pdu


def regs32(c, address, n=1, slave=1):
    r = c.read_holding_registers(address, 2 * n, slave=slave)
    if r.isError():
        return "error"
    return [struct.unpack(">i", struct.pack(">HH", r.registers[2 * i], r.registers[2 * i + 1]))[0] for i in range(n)]


# ---------------------------------------------------------------- the line-protocol run
p, port = start([ECHO, "--io=stdio", "--period", "2ms", "--modbus", "127.0.0.1:0"])
try:
    check("wait for scans", command(p, "wait 3"), "ok")
    # coils: Y0..Y2 off; M0 (8192) through mbpoll turns Y0 on in the scan the reply waits for
    check("mbpoll read coils Y0..Y2", mbpoll(port, "-t", "0", "-r", "0", "-c", "3", "127.0.0.1"), [0, 0, 0])
    check("mbpoll write coil M0", mbpoll(port, "-t", "0", "-r", "8192", "127.0.0.1", "1"), "written")
    check("Y0 = M0 on the next scan (mbpoll)", mbpoll(port, "-t", "0", "-r", "0", "127.0.0.1"), [1])
    check("Y0 through the line protocol", command(p, "get Y0"), "Y0 = 1")
    c = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
    check("pymodbus connect", c.connect(), True)
    check("pymodbus write coil K0", c.write_coil(16384, True, slave=1).isError(), False)
    check("Y1 = K0 on the next scan (pymodbus)", c.read_coils(0, 3, slave=1).bits[:3], [True, True, False])
    check("K0 through the line protocol", command(p, "get K0"), "K0 = 1")
    # a coil no program writes keeps its value: Y100, M4000 (FC 15)
    check("pymodbus write coils Y100..Y102", c.write_coils(100, [True, False, True], slave=1).isError(), False)
    check("read back Y100..Y102", c.read_coils(100, 3, slave=1).bits[:3], [True, False, True])
    check("pymodbus write coils M4000..M4009", c.write_coils(8192 + 4000, [True] * 10, slave=1).isError(), False)
    check("mbpoll read M4000..M4009", mbpoll(port, "-t", "0", "-r", str(8192 + 4000), "-c", "10", "127.0.0.1"), [1] * 10)
    check("M4009 through the line protocol", command(p, "get M4009"), "M4009 = 1")
    # discrete inputs: X0 set through the line protocol; the program copies it to Y2 and M1
    check("set X0", command(p, "set X0 1"), "ok")
    check("wait", command(p, "wait 2"), "ok")
    check("mbpoll read discrete input X0", mbpoll(port, "-t", "1", "-r", "0", "-c", "2", "127.0.0.1"), [1, 0])
    check("pymodbus read discrete inputs X0..X7", c.read_discrete_inputs(0, 8, slave=1).bits[:8], [True] + [False] * 7)
    check("coils Y2, M1 follow X0", [c.read_coils(2, 1, slave=1).bits[0], c.read_coils(8193, 1, slave=1).bits[0]], [True, True])
    # input registers: WX0 = -5, one register (low half); the program copies it to D2
    check("set WX0", command(p, "set WX0 -5"), "ok")
    check("wait", command(p, "wait 2"), "ok")
    check("mbpoll read input register WX0 (unsigned 16 bits)", mbpoll(port, "-t", "3", "-r", "0", "127.0.0.1"), [65531])
    check("pymodbus read input registers WX0..WX1", c.read_input_registers(0, 2, slave=1).registers, [0xFFFB, 0])
    check("D2 = WX0 (two registers)", regs32(c, 1028), [-5])
    # holding registers: D0 as INT32 through mbpoll (big-endian word order); the program writes D1 = WY1 = D0 + 1
    check("mbpoll write D0 = 100000", mbpoll(port, "-t", "4:int", "-B", "-r", "1024", "127.0.0.1", "100000"), "written")
    check("mbpoll read D0, D1", mbpoll(port, "-t", "4:int", "-B", "-r", "1024", "-c", "2", "127.0.0.1"), [100000, 100001])
    check("D1 through the line protocol", command(p, "get D1"), "D1 = 100001")
    check("WY1 = 100001: its low half", c.read_holding_registers(1, 1, slave=1).registers, [100001 & 0xFFFF])
    # WY0 written as a 16-bit register, sign-extended; the program copies it to D3
    check("pymodbus write WY0 = 0xFFFE", c.write_register(0, 0xFFFE, slave=1).isError(), False)
    check("WY0 through the line protocol", command(p, "get WY0"), "WY0 = -2")
    check("D3 = WY0 = -2 (two registers)", regs32(c, 1030), [-2])
    check("mbpoll write WY5 = 64302 (-1234 in 16 bits)", mbpoll(port, "-t", "4", "-r", "5", "127.0.0.1", "64302"), "written")
    check("mbpoll read WY5", mbpoll(port, "-t", "4", "-r", "5", "127.0.0.1"), [64302])
    check("WY5 sign-extended", command(p, "get WY5"), "WY5 = -1234")
    # one half of a D word (FC 6): the other half stays
    check("pymodbus write D0's low half", c.write_register(1025, 7, slave=1).isError(), False)
    check("D0 = 0x00010007", command(p, "get D0"), "D0 = 65543")
    # F (REAL): F0 = 1.5 through mbpoll's float; the program writes F1 = 2 * F0
    check("mbpoll write F0 = 1.5", mbpoll(port, "-t", "4:float", "-B", "-r", "17408", "127.0.0.1", "1.5"), "written")
    check("mbpoll read F0, F1", mbpoll(port, "-t", "4:float", "-B", "-r", "17408", "-c", "2", "127.0.0.1"), [1.5, 3.0])
    check("F1 through pymodbus", c.read_holding_registers(17410, 2, slave=1).registers, [0x4040, 0x0000])
    # the scan counter D4 moves between two reads
    a, b = regs32(c, 1032)[0], None
    time.sleep(0.05)
    b = regs32(c, 1032)[0]
    check("D4 counts scans", b > a, True)
    # 123 registers in one FC 16 request (the limit): D10..D70 and half of D71
    values = list(range(1, 124))
    check("pymodbus write 123 registers", c.write_registers(1044, values, slave=1).isError(), False)
    check("read them back", c.read_holding_registers(1044, 123, slave=1).registers, values)
    check("2000 coils in one read", len(c.read_coils(0, 2000, slave=1).bits), 2000)
    # exceptions through the clients
    r = c.read_coils(24576, 1, slave=1)
    check("pymodbus read coil 24576: exception 02", getattr(r, "exception_code", None), 2)
    r = c.read_holding_registers(19455, 2, slave=1)
    check("pymodbus read holding 19455..19456: exception 02", getattr(r, "exception_code", None), 2)
    r = c.read_input_registers(2048, 1, slave=1)  # past the counters' values (1536..2047)
    check("pymodbus read input register 2048: exception 02", getattr(r, "exception_code", None), 2)
    r = c.read_holding_registers(1024, 2, slave=7)
    check("pymodbus unit 7 (no such task): exception 0x0B", getattr(r, "exception_code", None), 0x0B)
    check("mbpoll read discrete input 8704", mbpoll(port, "-t", "1", "-r", "8704", "127.0.0.1"),
          "Read discrete input failed: Illegal data address")
    c.close()
    # raw frames: exceptions and what closes the connection
    check("FC 0x41: illegal function", raw(port, adu(bytes([0x41, 0, 0, 0, 1]))), "c101")
    check("FC 8 (diagnostics): illegal function", raw(port, adu(bytes([8, 0, 0, 0, 0]))), "8801")
    check("read 0 coils: illegal data value", raw(port, adu(bytes([1, 0, 0, 0, 0]))), "8103")
    check("read 126 registers: illegal data value", raw(port, adu(bytes([3, 0, 0, 0, 126]))), "8303")
    check("write coil value 0x1234: illegal data value", raw(port, adu(bytes([5, 0, 0, 0x12, 0x34]))), "8503")
    check("FC 15 byte count wrong: illegal data value", raw(port, adu(bytes([15, 0, 0, 0, 9, 1, 0xFF]))), "8f03")
    check("FC 16 byte count wrong: illegal data value", raw(port, adu(bytes([16, 0, 0, 0, 2, 2, 0, 1]))), "9003")
    check("write register 19456: illegal data address", raw(port, adu(bytes([6, 0x4C, 0, 0, 1]))), "8602")
    check("PDU too short: illegal data value", raw(port, adu(bytes([3, 0, 0]))), "8303")
    check("protocol identifier 1: closed", raw(port, adu(bytes([3, 0, 0, 0, 1]), proto=1)), "closed")
    check("length field 1: closed", raw(port, adu(b"", length=1)), "closed")
    check("length field 300: closed", raw(port, adu(bytes([3, 0, 0, 0, 1]), length=300)), "closed")
    check("still serving", raw(port, adu(bytes([2, 0, 0, 0, 1]))), "020101")
    # two pipelined requests in one send, answered in order
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    s.sendall(adu(bytes([5, 0x20, 0x05, 0xFF, 0]), tid=1) + adu(bytes([1, 0x20, 0x05, 0, 1]), tid=2))
    got = b""
    deadline = time.time() + 5
    while len(got) < 12 + 10 and time.time() < deadline:
        got += s.recv(64)
    s.close()
    check("pipelined write then read", got.hex(), adu(bytes([5, 0x20, 0x05, 0xFF, 0]), tid=1).hex() + "0002000000040101" + "0101")
    # STOP: writes get exception 06 and are not applied; RUN again serves them
    check("stop", command(p, "stop"), "ok STOP")
    check("write in STOP: exception 06", raw(port, adu(bytes([5, 0x20, 0x10, 0xFF, 0]))), "8506")
    check("M16 not written", command(p, "get M16"), "M16 = 0")
    check("read in STOP: the safe outputs", raw(port, adu(bytes([1, 0, 0, 0, 2]))), "010100")
    check("run", command(p, "run"), "ok RUN")
    check("write after RUN", raw(port, adu(bytes([5, 0x20, 0x10, 0xFF, 0]))), "052010ff00")
    check("M16 written", command(p, "get M16"), "M16 = 1")
    check("quit", command(p, "quit"), "ok bye")
    check("exit status", p.wait(timeout=20), 0)
finally:
    if p.poll() is None:
        p.kill()
        p.wait()

# ---------------------------------------------------------------- the trace mode
with tempfile.TemporaryDirectory() as tmp:
    trace = os.path.join(tmp, "in.csv")
    out = os.path.join(tmp, "out.csv")
    with open(trace, "w") as f:
        f.write("X0\n" + "0\n" * 100 + "1\n" * 200)
    p, port = start([ECHO, "--trace", trace, "--watch", "Y0,Y2,M0", "--period", "5ms", "--out", out, "--modbus", "0"])
    try:
        time.sleep(0.1)
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
        check("trace mode: pymodbus connect", c.connect(), True)
        check("trace mode: write coil M0", c.write_coil(8192, True, slave=1).isError(), False)
        check("trace mode: Y0 follows", c.read_coils(0, 1, slave=1).bits[0], True)
        deadline = time.time() + 20
        x0 = False
        while time.time() < deadline and not x0:  # the trace's X0 rises at row 101
            r = c.read_discrete_inputs(0, 1, slave=1)
            x0 = not r.isError() and r.bits[0]
            time.sleep(0.02)
        check("trace mode: discrete input X0 from the trace", x0, True)
        c.close()
        check("trace mode: exit status", p.wait(timeout=30), 0)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    rows = [l.split(",") for l in open(out).read().split("\n")[1:] if l]
    check("trace mode: 300 rows", len(rows), 300)
    y0 = [r[1] for r in rows]
    first = y0.index("1") if "1" in y0 else -1
    check("trace mode: Y0 = 1 from the write on, to the end", first > 0 and all(v == "1" for v in y0[first:]), True)
    check("trace mode: M0 column agrees", [r[3] for r in rows] == y0, True)
    check("trace mode: Y2 = X0 of the trace", [r[2] for r in rows], ["0"] * 100 + ["1"] * 200)

# ---------------------------------------------------------------- a project: unit identifiers pick the task
p, port = start(["--project", os.path.join(SRC, "tests/runtime/net/modbus/two.ldp"), "--io=stdio", "--modbus", ":0"])
try:
    check("project: wait", command(p, "wait 3"), "ok")
    c = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
    check("project: pymodbus connect", c.connect(), True)
    check("project: unit 1 writes fast.D0 = 10", c.write_registers(1024, [0, 10], slave=1).isError(), False)
    check("project: unit 2 writes slow.D0 = 10", c.write_registers(1024, [0, 10], slave=2).isError(), False)
    check("project: unit 1 reads fast.D1 = D0 + 1", regs32(c, 1026, slave=1), [11])
    check("project: unit 0 is task fast too", regs32(c, 1026, slave=0), [11])
    check("project: unit 2 reads slow.D1 = 2 x D0", regs32(c, 1026, slave=2), [20])
    check("project: slow.D1 through the line protocol", command(p, "get slow.D1"), "slow.D1 = 20")
    r = c.read_holding_registers(1024, 2, slave=3)
    check("project: unit 3: exception 0x0B", getattr(r, "exception_code", None), 0x0B)
    check("project: coil M0 through unit 2", c.write_coil(8192, True, slave=2).isError(), False)
    check("wait", command(p, "wait 2"), "ok")
    check("project: both tasks see M0 (Y0 of fast, Y16 of slow)",
          [c.read_coils(0, 1, slave=1).bits[0], c.read_coils(16, 1, slave=1).bits[0]], [True, True])
    c.close()
    check("project: quit", command(p, "quit"), "ok bye")
    check("project: exit status", p.wait(timeout=20), 0)
finally:
    if p.poll() is None:
        p.kill()
        p.wait()

# ---------------------------------------------------------------- refused before the start
def refused(args):
    r = subprocess.run([LDRUN, ECHO] + args, capture_output=True, text=True, timeout=30)
    return r.returncode, r.stderr.strip()


check("bad address", refused(["--modbus", "abc"]),
      (1, "ldrun: error: bad Modbus address 'abc' (PORT, :PORT or HOST:PORT; port 0..65535)"))
check("--modbus-connections 0", refused(["--modbus", "0", "--modbus-connections", "0"]),
      (1, "ldrun: error: bad --modbus-connections '0' (1..1000)"))
busy = socket.socket()
busy.bind(("127.0.0.1", 0))
busy.listen()
taken = busy.getsockname()[1]
check("port in use", refused(["--modbus", str(taken)]),
      (1, "ldrun: error: modbus: cannot listen on 127.0.0.1:%d: Address already in use" % taken))
busy.close()

finish()
