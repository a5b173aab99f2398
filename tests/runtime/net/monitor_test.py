#!/usr/bin/python3
"""End-to-end tests of `ldrun --monitor` (docs/runtime.md, "The monitor").

monitor_test.py LDRUN_DIR LDC_DIR SOURCE_ROOT CASE
Runs ldrun with the monitor on a free loopback port (port 0; ldrun prints the
one it got) and talks to it over plain sockets: only the standard library.
"""
import json
import os
import signal
import socket
import subprocess
import sys
import time

LDRUN_DIR, LDC_DIR, ROOT, CASE = sys.argv[1:5]


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


class Ldrun:
    def __init__(self, args, stdout=subprocess.DEVNULL):
        self.p = subprocess.Popen([os.path.join(LDRUN_DIR, "ldrun")] + args, stdout=stdout,
                                  stderr=subprocess.PIPE, text=True, cwd=ROOT)
        line = self.p.stderr.readline()
        if "monitor on http://127.0.0.1:" not in line:
            self.p.kill()
            fail("no monitor line: " + line + self.p.stderr.read())
        self.port = int(line.split("127.0.0.1:")[1].split("/")[0])

    def stop(self):
        self.p.send_signal(signal.SIGINT)
        try:
            rc = self.p.wait(10)
        except subprocess.TimeoutExpired:
            self.p.kill()
            fail("ldrun did not stop on SIGINT")
        err = self.p.stderr.read()
        if rc != 0:
            fail("ldrun exited with %d: %s" % (rc, err))
        return err


def raw(port, data, timeout=3.0):
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    s.sendall(data)
    out = b""
    try:
        while True:
            b = s.recv(65536)
            if not b:
                break
            out += b
    except socket.timeout:
        pass
    s.close()
    return out.decode("utf-8", "replace")


def request(port, method, path, body=None, headers=None):
    h = {"Host": "127.0.0.1:%d" % port, "Connection": "close"}
    h.update(headers or {})
    if body is not None:
        h["Content-Type"] = "application/x-www-form-urlencoded"
        h["Content-Length"] = str(len(body))
    req = "%s %s HTTP/1.1\r\n" % (method, path) + "".join("%s: %s\r\n" % kv for kv in h.items()) + "\r\n"
    reply = raw(port, (req + (body or "")).encode())
    head, _, payload = reply.partition("\r\n\r\n")
    if not head.startswith("HTTP/1.1 "):
        fail("not an HTTP reply: %r" % reply[:200])
    return int(head.split()[1]), head, payload


def get_json(port, path):
    code, _, body = request(port, "GET", path)
    if code != 200:
        fail("GET %s: %d %s" % (path, code, body))
    return json.loads(body)


def post(port, path, body, csrf=True):
    return request(port, "POST", path, body, {"X-LDC-Monitor": "1"} if csrf else {})


def events(port, seconds):
    """The event stream for `seconds`: the list of decoded events."""
    s = socket.create_connection(("127.0.0.1", port), timeout=2)
    s.sendall(("GET /api/events HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n" % port).encode())
    buf = b""
    end = time.time() + seconds
    while time.time() < end:
        s.settimeout(max(0.01, end - time.time()))
        try:
            b = s.recv(65536)
        except socket.timeout:
            break
        if not b:
            break
        buf += b
    s.close()
    text = buf.decode()
    if "text/event-stream" not in text.split("\r\n\r\n")[0]:
        fail("not an event stream: " + text[:200])
    return [json.loads(l[6:]) for l in text.split("\n") if l.startswith("data: ")]


def case_page_and_stream():
    m = Ldrun(["examples/traffic.ld", "--trace", "examples/traffic.csv", "--period", "50ms",
               "--monitor", "127.0.0.1:0"])
    code, head, html = request(m.port, "GET", "/")
    if code != 200 or '<script src="/monitor.js"' not in html or "text/html" not in head:
        fail("the page: %d %s" % (code, head))
    for f, t in (("/monitor.js", "javascript"), ("/monitor.css", "text/css")):
        code, head, body = request(m.port, "GET", f)
        if code != 200 or t not in head or len(body) < 500:
            fail("%s: %d" % (f, code))
    prog = get_json(m.port, "/api/program")
    if prog["write"]:
        fail("write allowed without --monitor-write")
    # the rungs are the grid `ldc --emit=ld` prints
    grid = subprocess.run([os.path.join(LDC_DIR, "ldc"), "examples/traffic.ld", "--emit=ld"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout
    want = [l for l in grid.split("\n") if l.startswith("|")]
    got = [row for r in prog["tasks"][0]["rungs"] for row in r["rows"]]
    if want != got:
        fail("rung rows differ from ldc --emit=ld:\n%s\n---\n%s" % ("\n".join(want), "\n".join(got)))
    titles = [r["title"] for r in prog["tasks"][0]["rungs"]]
    if "green time preset (first scan only)" not in titles or prog["tasks"][0]["rungs"][0]["line"] != 27:
        fail("titles or lines missing: %s" % titles)
    # at least 10 updates a second, scans advancing, the highlighting changing with the trace
    ev = events(m.port, 2.0)
    if len(ev) < 20:
        fail("%d events in 2 s" % len(ev))
    scans = [e["tasks"][0]["scan"] for e in ev]
    if scans[-1] <= scans[0]:
        fail("scans do not advance: %s" % scans)
    lit = set("".join(r.get("e", "") for r in e["tasks"][0]["rungs"]) for e in ev)
    if len(lit) < 3:
        fail("the highlighted elements did not change as the trace ran: %s" % lit)
    # a timer's elapsed ms is shown beside it
    if not any(v.endswith(" ms") for e in ev for r in e["tasks"][0]["rungs"] for v in r.get("v", {}).values()):
        fail("no timer value shown")
    st = ev[-1]["tasks"][0]
    if not (st["scan_us"]["median"] > 0 and st["scan_us"]["max"] >= st["scan_us"]["p99"] >= st["scan_us"]["median"]):
        fail("scan statistics: %s" % st["scan_us"])
    # the device table's values are the watched values of the trace
    dev = prog["tasks"][0]["devices"]
    names = [d[0] for d in dev]
    for n in ("X0", "Y0", "M0", "D10", "T0", "T0.Q"):
        if n not in names:
            fail("device %s not in the table: %s" % (n, names))
    if ev[-1]["tasks"][0]["dev"][names.index("D10")] != "500":
        fail("D10 (green_ms) should be 500")
    m.stop()


def case_refusals():
    m = Ldrun(["examples/eq1.ld", "--io=none", "--period", "20ms", "--monitor", "127.0.0.1:0"])
    p = m.port
    checks = [
        (b"GARBAGE\r\n\r\n", "400 Bad Request"),
        (b"GET / HTTP/2.0\r\nHost: x\r\n\r\n", "505 HTTP Version Not Supported"),
        (("GET / HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nX: %s\r\n\r\n" % (p, "a" * 9000)).encode(), "431"),
        (("POST /api/write HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Length: 100000\r\n\r\n" % p).encode(), "413"),
        (("GET /%s HTTP/1.1\r\nHost: x\r\n\r\n" % ("a" * 3000)).encode(), "414"),
        (("POST / HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nTransfer-Encoding: chunked\r\n\r\n" % p).encode(), "501"),
        (b"GET / HTTP/1.1\r\nHost: evil.example:80\r\n\r\n", "421"),
        (("DELETE /api/state HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n" % p).encode(), "405"),
        (("GET /nope HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n" % p).encode(), "404 Not Found"),
    ]
    for req, want in checks:
        got = raw(p, req)
        if want not in got.split("\r\n")[0]:
            fail("%r: expected %s, got %r" % (req[:60], want, got[:120]))
    for path in ("/api/write", "/api/run", "/api/stop"):
        code, _, body = post(p, path, "device=X1&value=1")
        if code != 403 or "--monitor-write" not in body:
            fail("%s without --monitor-write: %d %s" % (path, code, body))
    # the bound on connections: 32 held open, the next one is turned away
    held = [socket.create_connection(("127.0.0.1", p)) for _ in range(32)]
    time.sleep(0.3)
    got = raw(p, b"")
    if "503" not in got:
        fail("connection 33 was not refused: %r" % got[:100])
    for s in held:
        s.close()
    time.sleep(0.3)
    if get_json(p, "/api/state")["state"] != "RUN":
        fail("the monitor did not recover after the connections closed")
    m.stop()


def dev_value(state, prog, name):
    return state["tasks"][0]["dev"][[d[0] for d in prog["tasks"][0]["devices"]].index(name)]


def case_write_and_force():
    m = Ldrun(["examples/eq1.ld", "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0", "--monitor-write"])
    p = m.port
    prog = get_json(p, "/api/program")
    if not prog["write"]:
        fail("write not announced")
    code, _, body = post(p, "/api/write", "device=X1&value=1&force=1", csrf=False)
    if code != 403 or "X-LDC-Monitor" not in body:
        fail("a write without the page's header: %d %s" % (code, body))
    for body, want in (("device=Q7&value=1", 400), ("device=X1&value=abc", 400), ("device=D0&value=1&force=1", 400),
                       ("device=S1&value=1", 400), ("value=1", 400), ("device=X1&value=1&task=nope", 400)):
        code, _, text = post(p, "/api/write", body)
        if code != want:
            fail("%s: expected %d, got %d %s" % (body, want, code, text))
    st = get_json(p, "/api/state")
    if dev_value(st, prog, "Y1") != "0":
        fail("Y1 on before any input")
    # force X1, write X3 and X4 once: Y1 = X1 AND (X2 OR (X3 AND X4)) follows at the next scan
    for body in ("device=X1&value=1&force=1", "device=X3&value=1", "device=X4&value=1"):
        code, _, text = post(p, "/api/write", body)
        if code != 200:
            fail("%s: %d %s" % (body, code, text))
    time.sleep(0.2)
    st = get_json(p, "/api/state")
    if dev_value(st, prog, "Y1") != "1" or dev_value(st, prog, "X1") != "1":
        fail("Y1 did not follow the forced X1: %s" % st["tasks"][0]["dev"])
    if "X1" not in st["forced"]:
        fail("X1 not listed as forced")
    rung0 = st["tasks"][0]["rungs"][0]
    elems = prog["tasks"][0]["rungs"][0]["elems"]
    coil = [i for i, e in enumerate(elems) if e["o"]][0]
    if rung0["e"][coil] != "1" or rung0["n"][elems[coil]["i"]] != "1":
        fail("the coil of rung 1 is not shown energized: %s" % rung0)
    # X2 is open: its element is dark while the X3-X4 branch carries the power
    x2 = [i for i, e in enumerate(elems) if e["t"] == "[X2]"][0]
    if rung0["e"][x2] != "0":
        fail("X2 shown closed")
    code, _, _ = post(p, "/api/write", "device=X1&value=0&force=1")
    time.sleep(0.2)
    st = get_json(p, "/api/state")
    if dev_value(st, prog, "Y1") != "0":
        fail("Y1 did not follow X1 forced to 0")
    code, _, text = post(p, "/api/write", "device=X1&force=0")
    if code != 200 or "X1" in get_json(p, "/api/state")["forced"]:
        fail("release: %d %s" % (code, text))
    # STOP and RUN
    code, _, text = post(p, "/api/stop", "")
    if code != 200 or get_json(p, "/api/state")["state"] != "STOP":
        fail("STOP: %d %s" % (code, text))
    code, _, text = post(p, "/api/run", "")
    if code != 200 or get_json(p, "/api/state")["state"] != "RUN":
        fail("RUN: %d %s" % (code, text))
    m.stop()


def case_load():
    # 20 pages' event streams at once on a 1 ms task: every client is served
    # at >= 10 updates/s, nothing crashes, the task keeps scanning.
    m = Ldrun(["examples/traffic.ld", "--io=none", "--period", "1ms", "--monitor", "127.0.0.1:0", "--stats"])
    p = m.port
    import threading
    counts = [0] * 20
    scans = [[] for _ in range(20)]

    def client(i):
        ev = events(p, 3.0)
        counts[i] = len(ev)
        scans[i] = [e["tasks"][0]["scan"] for e in ev]

    ts = [threading.Thread(target=client, args=(i,)) for i in range(20)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    if min(counts) < 30:
        fail("an event-stream client got fewer than 30 updates in 3 s: %s" % counts)
    if any(s[-1] <= s[0] for s in scans):
        fail("scans did not advance for every client")
    err = m.stop()
    if "scan time" not in err:
        fail("no --stats: " + err)
    print(err)


def case_trace_output():
    # the decorator forwards everything: with a page watching and writes allowed (none
    # made), the trace driver prints exactly the example's expected CSV
    exp = os.path.join(ROOT, "examples/traffic.expected")
    watch = open(exp).readline().strip().split(",", 1)[1]
    out = open(os.path.join(os.environ.get("TMPDIR", "/tmp"), "ldc_monitor_trace_%d.csv" % os.getpid()), "w+")
    try:
        m = Ldrun(["examples/traffic.ld", "--trace", "examples/traffic.csv", "--watch", watch, "--period", "5ms",
                   "--monitor", "127.0.0.1:0", "--monitor-write"], stdout=out)
        ev = events(m.port, 1.5)
        if len(ev) < 10:
            fail("%d events" % len(ev))
        m.stop()
        out.seek(0)
        got = out.read()
    finally:
        out.close()
        os.unlink(out.name)
    if got != open(exp).read():
        fail("the trace output under the monitor differs from examples/traffic.expected:\n" + got[:2000])


def case_project():
    # a project of three tasks on two processors: one section per task, writes by task
    m = Ldrun(["--project", "tests/runtime/projects/shared.ldp", "--io=none", "--monitor", "127.0.0.1:0",
               "--monitor-write"])
    p = m.port
    prog = get_json(p, "/api/program")
    tasks = [(t["name"], t["period_us"], len(t["rungs"])) for t in prog["tasks"]]
    if [t[:2] for t in tasks] != [("fast", 1000), ("belt", 5000), ("slow", 20000)] or min(t[2] for t in tasks) < 1:
        fail("tasks: %s" % tasks)
    if any("rows" not in r for t in prog["tasks"] for r in t["rungs"]):
        fail("a rung of the project is not drawn")
    ev = events(p, 1.0)
    if len(ev) < 10 or any(ev[-1]["tasks"][i]["scan"] <= ev[0]["tasks"][i]["scan"] for i in range(3)):
        fail("not every task advances in the event stream")

    def value(task, name):
        st = get_json(p, "/api/state")
        names = [d[0] for d in prog["tasks"][task]["devices"]]
        return st["tasks"][task]["dev"][names.index(name)]

    # the shared input X0 (fill_btn) starts the mixer's valve Y0 in task fast
    code, _, text = post(p, "/api/write", "device=fill_btn&value=1")
    if code != 200:
        fail("write fill_btn: %d %s" % (code, text))
    time.sleep(0.2)
    if value(0, "Y0") != "1":
        fail("the valve of task fast did not open")
    # belt_on is an alias of the conveyor program (task belt)
    code, _, text = post(p, "/api/write", "device=belt_on&value=1&task=belt")
    if code != 200:
        fail("write belt_on in task belt: %d %s" % (code, text))
    code, _, text = post(p, "/api/write", "device=belt_on&value=1")
    if code != 400:
        fail("belt_on is not an alias of task fast's program, expected 400: %d %s" % (code, text))
    time.sleep(0.2)
    if value(1, "Y20") != "1":
        fail("the belt of task belt did not start")
    # STOP of task belt alone: its belt output goes to the safe state, task fast scans on
    code, _, text = post(p, "/api/stop", "task=belt")
    if code != 200 or text.strip() != "belt STOP":
        fail("STOP of task belt: %d %s" % (code, text))
    time.sleep(0.2)
    st = get_json(p, "/api/state")
    if not st["tasks"][1]["held"] or st["tasks"][0]["held"] or st["state"] != "RUN":
        fail("held flags: %s" % [(t["name"], t["held"]) for t in st["tasks"]])
    s0, s1 = st["tasks"][0]["scan"], st["tasks"][1]["scan"]
    time.sleep(0.3)
    st = get_json(p, "/api/state")
    if st["tasks"][0]["scan"] <= s0 or st["tasks"][1]["scan"] != s1:
        fail("task fast must scan on and task belt must not: %s -> %s" % ((s0, s1), (st["tasks"][0]["scan"], st["tasks"][1]["scan"])))
    if value(0, "Y0") != "1":
        fail("task fast's valve was touched by stopping task belt")
    if value(1, "Y20") != "0":
        fail("task belt's output Y20 is not in the safe state while it is stopped")
    code, _, text = post(p, "/api/run", "task=belt")
    if code != 200 or text.strip() != "belt RUN":
        fail("RUN of task belt: %d %s" % (code, text))
    time.sleep(0.3)
    st = get_json(p, "/api/state")
    if st["tasks"][1]["held"] or value(1, "Y20") != "1":
        fail("task belt did not run again: %s" % st["tasks"][1]["scan"])
    code, _, text = post(p, "/api/stop", "task=nope")
    if code != 400:
        fail("unknown task: %d %s" % (code, text))
    code, _, text = post(p, "/api/stop", "")
    if code != 200 or get_json(p, "/api/state")["state"] != "STOP":
        fail("STOP of the project: %d %s" % (code, text))
    m.stop()


if __name__ == "__main__":
    {"page_and_stream": case_page_and_stream, "refusals": case_refusals, "write_and_force": case_write_and_force,
     "load": case_load, "project": case_project,
     "trace_output": case_trace_output}[CASE]()
    print("ok")
