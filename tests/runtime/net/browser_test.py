#!/usr/bin/python3
"""A real browser on `ldrun --monitor` (docs/runtime.md, "The monitor").

browser_test.py LDRUN_DIR SOURCE_ROOT OUT_DIR
Headless Debian chromium (--no-sandbox) is driven over the DevTools protocol
on a pipe (--remote-debugging-pipe; standard library only).  One page of the
monitor stays open while examples/traffic.csv runs: the lit elements in its
DOM must change.  Then on examples/eq1.ld (--monitor-write) the page's own
form forces X1 and writes X3, X4 (filling the inputs, clicking the buttons):
the coil Y1 must light in the DOM, and go dark when X1 is forced to 0.  Then
with --monitor-remote --monitor-write the page opened at the address ldrun
printed (/?token=...) keeps the write token and writes with it; without it
a write is refused 403 and the page says a token is needed.  Last an ST
program (tests/runtime/net/monitor/online.st): its source drawn as written,
markup in it as text, the values beside its targets those of one scan.
Screenshots of the traffic light and of the ST program go to
OUT_DIR/monitor.png and OUT_DIR/monitor-st.png.
Exit 77 (skipped) when chromium is not installed.
"""
import base64
import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
LDRUN_DIR, ROOT, OUT = sys.argv[1:4]
sys.argv = [sys.argv[0], LDRUN_DIR, "", ROOT, "none"]
import monitor_test as mt  # noqa: E402  (its Ldrun and HTTP helpers)

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if not CHROMIUM:
    print("chromium not installed: skipped")
    sys.exit(77)


class Browser:
    """chromium --remote-debugging-pipe: JSON messages ended by NUL on fds 3 (in) and 4 (out)."""

    def __init__(self):
        to_r, self.to_w = os.pipe()
        self.from_r, from_w = os.pipe()

        def fds():  # the pipe ends become fds 3 and 4 of chromium
            a, b = fcntl.fcntl(to_r, fcntl.F_DUPFD, 10), fcntl.fcntl(from_w, fcntl.F_DUPFD, 10)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.p = subprocess.Popen(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
             "--user-data-dir=" + os.path.join(OUT, "chromium-profile"), "--remote-debugging-pipe", "about:blank"],
            close_fds=False, preexec_fn=fds, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_r)
        os.close(from_w)
        self.buf = b""
        self.next_id = 0
        self.session = None
        tid = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.call("Target.attachToTarget", {"targetId": tid, "flatten": True})["sessionId"]
        self.call("Emulation.setDeviceMetricsOverride", {"width": 1500, "height": 1100, "deviceScaleFactor": 1,
                                                         "mobile": False})

    def call(self, method, params=None, timeout=30):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if self.session and not method.startswith("Target."):
            msg["sessionId"] = self.session
        os.write(self.to_w, json.dumps(msg).encode() + b"\0")
        end = time.time() + timeout
        while time.time() < end:
            while b"\0" in self.buf:
                raw, self.buf = self.buf.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self.next_id:
                    if "error" in reply:
                        mt.fail("%s: %s" % (method, reply["error"]))
                    return reply["result"]
            import select
            r, _, _ = select.select([self.from_r], [], [], 1.0)
            if r:
                chunk = os.read(self.from_r, 1 << 20)
                if not chunk:
                    mt.fail("chromium closed the pipe")
                self.buf += chunk
        mt.fail("chromium did not answer %s" % method)

    def js(self, expr):
        r = self.call("Runtime.evaluate", {"expression": expr, "returnByValue": True, "awaitPromise": True})
        if "exceptionDetails" in r:
            mt.fail("page script: %s" % r["exceptionDetails"])
        return r["result"].get("value")

    def open(self, url, drawn="svg.ladder"):
        self.call("Page.navigate", {"url": url})
        for _ in range(100):
            time.sleep(0.1)
            if self.js("document.querySelectorAll('%s').length" % drawn) or 0:
                return
        mt.fail("the page drew no " + drawn)

    def dom(self):
        return self.js("document.documentElement.outerHTML")

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except SystemExit:
            pass
        try:
            self.p.wait(10)
        except subprocess.TimeoutExpired:
            self.p.kill()


def lit(dom):
    """(rung svg id, element index) of every lit element in the DOM."""
    out = set()
    for svg in re.finditer(r'<svg class="ladder"[^>]*id="(rung-\d+-\d+)"(.*?)</svg>', dom, re.S):
        for g in re.finditer(r'<g class="elem (?:input|output) on" data-elem="(\d+)"', svg.group(2)):
            out.add((svg.group(1), int(g.group(1))))
    return out


os.makedirs(OUT, exist_ok=True)
b = Browser()
try:
    # 1. the traffic light: one open page, its lit elements change while the trace runs
    m = mt.Ldrun(["examples/traffic.ld", "--trace", "examples/traffic.csv", "--period", "100ms",
                  "--monitor", "127.0.0.1:0"])
    b.open("http://127.0.0.1:%d/" % m.port)
    seen = []
    for k in range(8):
        time.sleep(0.4)
        dom = b.dom()
        if dom.count('class="ladder"') != 11:
            mt.fail("expected 11 rungs drawn, found %d" % dom.count('class="ladder"'))
        if 'class="state RUN"' not in dom:
            mt.fail("the state is not shown as RUN")
        seen.append(frozenset(lit(dom)))
    if len(set(seen)) < 3:
        mt.fail("the lit elements did not change as the trace ran: %s" % seen)
    # tick two devices for the trend, wait, and take the picture
    b.js("for (const tr of document.querySelectorAll('#devices tbody tr'))"
         "  if (['st_red','st_green','st_yellow'].includes(tr.dataset.alias)) tr.querySelector('input').click();")
    time.sleep(2.5)
    if b.js("document.querySelectorAll('#trend polyline').length") != 3:
        mt.fail("the trend does not plot the ticked devices")
    if b.js("document.querySelectorAll('#scantrend polyline').length") != 3:
        mt.fail("the scan-time trend is missing")
    png = base64.b64decode(b.call("Page.captureScreenshot", {"format": "png"})["data"])
    with open(os.path.join(OUT, "monitor.png"), "wb") as f:
        f.write(png)
    if len(png) < 20000:
        mt.fail("the screenshot is suspiciously small")
    m.stop()

    # 2. eq1: the page's own form forces X1 and writes X3, X4; the coil of rung 1 follows
    m = mt.Ldrun(["examples/eq1.ld", "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0", "--monitor-write"])
    b.open("http://127.0.0.1:%d/" % m.port)
    prog = mt.get_json(m.port, "/api/program")
    coil = [i for i, e in enumerate(prog["tasks"][0]["rungs"][0]["elems"]) if e["t"] == "(Y1)"][0]
    time.sleep(0.3)
    if ("rung-0-0", coil) in lit(b.dom()):
        mt.fail("Y1 lit before any input")

    def submit(dev, val, button):
        b.js("document.getElementById('wdev').value = %s; document.getElementById('wval').value = %s;"
             "document.getElementById('%s').click();" % (json.dumps(dev), json.dumps(val), button))
        for _ in range(50):
            time.sleep(0.05)
            reply = b.js("document.getElementById('reply').textContent")
            if reply.startswith("200"):
                b.js("document.getElementById('reply').textContent = ''")
                return
        mt.fail("the page's %s of %s=%s was not accepted: %r" % (button, dev, val, reply))

    submit("X1", "1", "wforce")
    submit("X3", "1", "wwrite")
    submit("X4", "1", "wwrite")
    time.sleep(0.4)
    dom = b.dom()
    if ("rung-0-0", coil) not in lit(dom):
        mt.fail("the coil Y1 did not light after forcing X1: %s" % sorted(lit(dom)))
    if 'class="forced"' not in dom:
        mt.fail("the forced input is not marked in the device table")
    submit("X1", "0", "wforce")
    time.sleep(0.4)
    if ("rung-0-0", coil) in lit(b.dom()):
        mt.fail("the coil Y1 stayed lit after X1 was forced to 0")
    m.stop()

    # 3. the write token (--monitor-remote --monitor-write): the page opened once
    # as ldrun printed it (/?token=...) keeps the token, takes it out of the
    # address bar, and writes with it -- also when opened again without it
    m = mt.Ldrun(["examples/eq1.ld", "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0", "--monitor-remote",
                  "--monitor-write"])
    url = m.banner.split("open ")[1].split()[0]
    if "?token=" not in url:
        mt.fail("no address with the token printed: " + m.banner)
    b.open(url)
    if b.js("location.search") != "":
        mt.fail("the token stays in the address bar: " + b.js("location.href"))
    submit("X1", "1", "wforce")
    b.open("http://127.0.0.1:%d/" % m.port)
    if mt.get_json(m.port, "/api/state")["forced"] != ["X1"]:
        mt.fail("the page's force with the token did not arrive")
    submit("X1", "", "wrelease")
    if mt.get_json(m.port, "/api/state")["forced"]:
        mt.fail("the page's release (opened again without ?token=) did not arrive")
    # a browser without the token is refused, and the page says why
    b.js("localStorage.clear()")
    b.open("http://127.0.0.1:%d/" % m.port)
    time.sleep(0.3)
    if "token" not in b.js("document.getElementById('reply').textContent"):
        mt.fail("the page does not say that writes need the token")
    b.js("document.getElementById('wdev').value = 'X1'; document.getElementById('wval').value = '1';"
         "document.getElementById('wforce').click();")
    for _ in range(50):
        time.sleep(0.05)
        reply = b.js("document.getElementById('reply').textContent")
        if reply.startswith("403"):
            break
    if not reply.startswith("403") or "token" not in reply:
        mt.fail("a write without the token: %r" % reply)
    if mt.get_json(m.port, "/api/state")["forced"]:
        mt.fail("a write without the token forced an input")
    m.stop()

    # 4. an ST program: its source as written, line by line, markup in it shown
    # as text, and the values beside the targets those of one scan count N
    # (tests/runtime/net/monitor/online.st says how each follows from N)
    m = mt.Ldrun([mt.ONLINE, "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0"])
    b.open("http://127.0.0.1:%d/" % m.port, "div.source")
    lines = open(os.path.join(ROOT, mt.ONLINE)).read().split("\n")
    shown = b.js("[...document.querySelectorAll('div.source .sl')].map(l => [...l.childNodes].slice(1)"
                 ".filter(n => !n.classList.contains('stv')).map(n => n.textContent).join(''))")
    if shown != lines:
        mt.fail("the page shows the source as %r" % shown[:40])
    if b.js("document.querySelectorAll('script').length") != 1 or b.js("document.querySelectorAll('svg.ladder').length"):
        mt.fail("markup in the source became elements, or rungs were drawn beside the source")
    for _ in range(3):
        time.sleep(0.3)
        vals = b.js("Object.fromEntries([...document.querySelectorAll('div.source .stv')].map(v => [v.title, v.textContent]))")
        want = {k: str(v) for k, v in mt.online_expected(int(vals.get("n", "0"))).items()}
        if vals != want or int(vals["n"]) < 1:
            mt.fail("the page shows %s, expected %s" % (vals, want))
    png = base64.b64decode(b.call("Page.captureScreenshot", {"format": "png"})["data"])
    with open(os.path.join(OUT, "monitor-st.png"), "wb") as f:
        f.write(png)
    m.stop()
finally:
    b.close()
print("ok")
