#!/usr/bin/python3
"""A real browser on `ldrun --monitor` (docs/runtime.md, "The monitor").

browser_test.py LDRUN_DIR SOURCE_ROOT OUT_DIR [page|iec]
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
Part `iec` (monitor/browser_iec): tests/runtime/net/monitor/iec.ld drawn with
the IEC symbols, clicking a contact with and without --monitor-write, the
forced marker, the trends' lanes and time axis, an online download redrawn by
the open page and drawn by a page opened after it (OUT_DIR/monitor-iec.png, the
picture of docs/runtime.md), and a project's shared devices listed once.
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
PART = sys.argv[4] if len(sys.argv) > 4 else "page"
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


def sections_page(b):
    """The traffic light, eq1's form, the write token, an ST program."""
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
    if b.js("document.querySelectorAll('#trend path.step').length") != 3:
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


def elems_by(b, kind):
    """[(rung svg id, element index, device)] of the drawn elements of one IEC kind."""
    return b.js("[...document.querySelectorAll('g.elem[data-kind=\"%s\"]')].map(g => "
                "[g.closest('svg').id, Number(g.dataset.elem), g.dataset.device || ''])" % kind)


def click(b, svg_id, k):
    b.js("document.getElementById('reply').textContent = '';"
         "document.querySelector('#%s g.elem[data-elem=\"%d\"]').dispatchEvent(new MouseEvent('click', {bubbles: true}))"
         % (svg_id, k))
    for _ in range(60):
        time.sleep(0.05)
        reply = b.js("document.getElementById('reply').textContent")
        if reply:
            return reply
    mt.fail("no reply on the page after clicking %s element %d" % (svg_id, k))


def wait_for(b, expr, what, tries=60):
    for _ in range(tries):
        if b.js(expr):
            return
        time.sleep(0.05)
    mt.fail(what)


def sections_iec(b):
    """tests/runtime/net/monitor/iec.ld drawn with the IEC symbols; clicking a
    contact with and without --monitor-write; the forced marker; an online
    download redrawn by the open page and drawn by a page opened after it."""
    iec = "tests/runtime/net/monitor/iec.ld"
    # 1. read-only: every symbol of iec.ld drawn; a click forces nothing and says why
    m = mt.Ldrun([iec, "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0"])
    b.open("http://127.0.0.1:%d/" % m.port)
    # iec.ld has: 5 normally open contacts ([start] [run] [run] [run] [stop] [pump] [S1] -> 7),
    # 1 normally closed, 1 rising, 1 falling; coils pump run; /idle; S alarm; RST alarm;
    # boxes TON CTU ADD MOV; the compare level < 1000
    want = {"no": 7, "nc": 1, "p": 1, "n": 1, "coil": 2, "ncoil": 1, "set": 1, "reset": 1, "fb": 4, "cmp": 1}
    got = {k: len(elems_by(b, k)) for k in want}
    if got != want:
        mt.fail("IEC symbols drawn: %s, expected %s" % (got, want))
    # a contact is two plates (a normally closed one a slash too), a coil two arcs
    if b.js("document.querySelector('g[data-kind=\"no\"] ').querySelectorAll('line.plate').length") != 2 or \
       b.js("document.querySelector('g[data-kind=\"nc\"]').querySelectorAll('line.plate').length") != 3 or \
       b.js("document.querySelector('g[data-kind=\"coil\"]').querySelectorAll('path.arc').length") != 2:
        mt.fail("a contact or coil is not drawn as -| |-, -|/|-, -( )-")
    marks = b.js("[...document.querySelectorAll('g[data-kind] text.mark')].map(t => t.textContent).join('')")
    if sorted(marks) != sorted("PNSR/"):
        mt.fail("the marks inside edge contacts and coils: %r" % marks)
    ton = b.js("[...document.querySelectorAll('g[data-kind=\"fb\"]')].map(g => [...g.querySelectorAll(':scope > text:not(.val)')]"
               ".map(t => t.textContent).filter(t => t).join(' '))")
    if sorted(ton) != ["ADD EN IN1 level IN2 7 OUT", "CTU C0 CU PV 10 Q CV", "MOV EN IN 100 OUT", "TON T0 IN PT T#5s Q ET"]:
        mt.fail("the timer and counter boxes and their pins: %s" % ton)
    start = [e for e in elems_by(b, "no") if e[2] == "X0"][0]
    reply = click(b, start[0], start[1])
    if "--monitor-write" not in reply or mt.get_json(m.port, "/api/state")["forced"]:
        mt.fail("a click on a read-only monitor: %r" % reply)
    m.stop()

    # 2. --monitor-write: a click on [start] forces X0 to 1: the latch closes,
    # its energised path lit, the contact marked; a second click releases it
    m = mt.Ldrun([iec, "--io=none", "--period", "10ms", "--monitor", "127.0.0.1:0", "--monitor-write",
                  "--control=stdin"], stdout=subprocess.PIPE, stdin=subprocess.PIPE)
    url = "http://127.0.0.1:%d/" % m.port
    b.open(url)
    reply = click(b, start[0], start[1])
    if not reply.startswith("200") or mt.get_json(m.port, "/api/state")["forced"] != ["X0"]:
        mt.fail("clicking [start] did not force X0: %r" % reply)
    coil_run = [e for e in elems_by(b, "coil") if e[2] == "M0"][0]
    wait_for(b, "document.querySelector('#%s g.elem[data-elem=\"%d\"]').classList.contains('on')" % tuple(coil_run[:2]),
             "the coil run did not light with start forced")
    wait_for(b, "document.querySelectorAll('#rung-0-0 line.on').length >= 3", "no energised path lit in the latch")
    forced_marks = b.js("[...document.querySelectorAll('g.elem[data-forced]')].map(g => g.dataset.device + '=' + "
                        "g.dataset.forced + ':' + !g.querySelector('.forcemark').classList.contains('hidden'))")
    if forced_marks != ["X0=1:true"]:
        mt.fail("the forced contact is not marked on the rung: %s" % forced_marks)
    if 'class="forced"' not in b.dom():
        mt.fail("the forced input is not marked in the device table")
    reply = click(b, start[0], start[1])
    if not reply.startswith("200") or mt.get_json(m.port, "/api/state")["forced"]:
        mt.fail("a second click did not release X0: %r" % reply)
    wait_for(b, "!document.querySelectorAll('g.elem[data-forced]').length", "the marker stayed after the release")
    # a relay is forced too: with start written 0 (released, it kept its 1), run
    # (M0) is latched at 1; a click forces it to 0, which breaks the latch
    # ([start] or [run], and not [stop]), so pump (Y0) goes off; released, run
    # stays 0 (nothing closes the latch again)
    mt.post(m.port, "/api/write", "device=X0&value=0")
    time.sleep(0.2)
    if mt.dev_value(mt.get_json(m.port, "/api/state"), mt.get_json(m.port, "/api/program"), "M0") != "1":
        mt.fail("run did not stay latched after start went to 0")
    reply = click(b, coil_run[0], coil_run[1])
    st = mt.get_json(m.port, "/api/state")
    if not reply.startswith("200") or st["forced"] != ["M0"] or st["fv"] != [0]:
        mt.fail("a click on the relay run did not force M0 to 0: %r %s" % (reply, st["forced"]))
    wait_for(b, "!document.querySelector('#%s g.elem[data-elem=\"%d\"]').classList.contains('on')" % tuple(coil_run[:2]),
             "the coil run stayed lit while forced to 0")
    time.sleep(0.2)
    if mt.dev_value(mt.get_json(m.port, "/api/state"), mt.get_json(m.port, "/api/program"), "Y0") != "0":
        mt.fail("pump stayed on with run forced to 0")
    reply = click(b, coil_run[0], coil_run[1])
    if not reply.startswith("200") or mt.get_json(m.port, "/api/state")["forced"]:
        mt.fail("a second click did not release M0: %r" % reply)
    time.sleep(0.2)
    if mt.dev_value(mt.get_json(m.port, "/api/state"), mt.get_json(m.port, "/api/program"), "M0") != "0":
        mt.fail("the latch closed again after M0 was released")
    # start forced (from 0: a click forces the other value), the latch and the
    # timer running, two trends: the picture of docs/runtime.md once the download below ran
    mt.post(m.port, "/api/write", "device=X0&value=0")
    time.sleep(0.2)
    if not click(b, start[0], start[1]).startswith("200") or mt.get_json(m.port, "/api/state")["fv"] != [1]:
        mt.fail("start was not forced to 1 from 0")
    b.js("for (const tr of document.querySelectorAll('#devices tbody tr'))"
         "  if (['pump','level'].includes(tr.dataset.alias)) tr.querySelector('input').click();")
    time.sleep(2.5)
    if b.js("document.querySelectorAll('#trend path.step').length") != 1 or \
       b.js("document.querySelectorAll('#trend path.word').length") != 1 or \
       not b.js("[...document.querySelectorAll('#trend text.tick')].some(t => t.textContent === '-5 s')"):
        mt.fail("the trend: a bit as steps, a word on its own scale, a time axis")

    # 3. an online download while the page is open: it redraws the new
    # program (a rung appended) and says when; a page opened afterwards draws it too
    tmp = os.path.join(OUT, "iec_v2.ld")
    open(tmp, "w").write(open(os.path.join(ROOT, iec)).read() + mt.IEC_APPENDED)
    if b.js("document.querySelectorAll('svg.ladder').length") != 7:
        mt.fail("iec.ld has 7 rungs")
    m.p.stdin.write("load %s\n" % tmp)
    m.p.stdin.flush()
    if not m.p.stdout.readline().startswith("ok task main switched"):
        mt.fail("the download was refused")
    wait_for(b, "document.querySelectorAll('svg.ladder').length === 8", "the open page did not redraw the new program")
    banner = b.js("document.getElementById('banner').textContent")
    if "new program downloaded at" not in banner or b.js("document.getElementById('banner').classList.contains('hidden')"):
        mt.fail("no banner after the download: %r" % banner)
    wait_for(b, "document.querySelectorAll('#rung-0-7 g.elem[data-kind=\"coil\"][data-device=\"Y3\"]').length === 1",
             "the appended rung is not drawn")
    # values of the old program never paint over the new one: a state of
    # generation 0 with every element lit is dropped; the same state of the
    # current generation (the control) lights every element; one of a newer
    # generation makes the page fetch the program again
    lit_after = b.js("""(async () => {
        const s = await (await fetch('/api/state')).json();
        for (const t of s.tasks) for (const r of t.rungs) if (r.e) r.e = r.e.replace(/0/g, '1');
        const all = document.querySelectorAll('g.elem').length, lit = () => document.querySelectorAll('g.elem.on').length;
        s.tasks[0].gen = 0; update(s); const old = lit();
        s.tasks[0].gen = 1; update(s); const cur = lit();
        s.tasks[0].gen = 2; update(s); const refetch = refetching;
        return [all, old, cur, refetch]; })()""")
    if lit_after[1] >= lit_after[0] or lit_after[2] != lit_after[0] or not lit_after[3]:
        mt.fail("[elements, lit by an old state, lit by a current one, refetching on a newer one]: %s" % lit_after)
    # the trends ticked before go on across the redraw; the picture: the banner, the
    # new program with its forced contact marked, the trends
    time.sleep(1.0)
    if b.js("document.querySelectorAll('#trend path').length") != 2:
        mt.fail("the trends did not go on across the redraw")
    png = base64.b64decode(b.call("Page.captureScreenshot", {"format": "png"})["data"])
    with open(os.path.join(OUT, "monitor-iec.png"), "wb") as f:
        f.write(png)
    b.open(url)
    if b.js("document.querySelectorAll('svg.ladder').length") != 8 or \
       "new program downloaded at" not in b.js("document.getElementById('banner').textContent"):
        mt.fail("a page opened after the download does not draw the new rungs")
    m.p.stdin.write("quit\n")
    m.p.stdin.flush()
    m.stop()

    # 4. a project: a shared device (X Y M K WX WY) listed once in the table, with every
    # task's alias of it; each task's own devices as TASK.NAME
    m = mt.Ldrun(["--project", "tests/runtime/projects/shared.ldp", "--io=none", "--monitor", "127.0.0.1:0"])
    b.open("http://127.0.0.1:%d/" % m.port)
    tasks = mt.get_json(m.port, "/api/program")["tasks"]
    shared_re = re.compile(r"^(X|Y|M|K|WX|WY)\d+$")
    shared, own = {}, []
    for t in tasks:
        for name, alias in t["devices"]:
            if shared_re.match(name):
                shared.setdefault(name, [])
                if alias and alias not in shared[name]:
                    shared[name].append(alias)
            else:
                own.append(t["name"] + "." + name)
    if sum(len(t["devices"]) for t in tasks) == len(shared) + len(own):
        mt.fail("shared.ldp's tasks share no device: the check would check nothing")
    rows = b.js("[...document.querySelectorAll('#devices tbody tr')].map(tr => [tr.children[1].textContent, "
                "tr.children[2].textContent])")
    want = sorted([[n, ", ".join(a)] for n, a in shared.items()] + [[n, a] for t in tasks for n, a in
                  [(t["name"] + "." + d, al) for d, al in t["devices"] if not shared_re.match(d)]])
    if sorted(rows) != want:
        mt.fail("the project's device table:\n%s\nexpected\n%s" % (sorted(rows), want))
    m.stop()


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    b = Browser()
    try:
        {"page": sections_page, "iec": sections_iec}[PART](b)
    finally:
        b.close()
    print("ok")
