"""What the Modbus client tests share: a named check that records its failure,
the end of the run (exit 1 with the failures listed, else 0), starting ldrun
with its Modbus server, and a read or write with mbpoll."""
import re
import select
import subprocess
import sys
import time

failures = []


def check(what, got, want):
    ok = got == want
    print(("ok   " if ok else "FAIL ") + what + ": " + repr(got) + ("" if ok else " (want " + repr(want) + ")"))
    if not ok:
        failures.append(what)


def finish():
    print("%d failures" % len(failures) + (": " + ", ".join(failures) if failures else ""))
    sys.exit(1 if failures else 0)


def start_modbus(argv):
    """Starts ldrun (argv) with --modbus 127.0.0.1:0 among its arguments;
    returns the process and the port it says it listens on (exits if none)."""
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    port, line, deadline = None, "", time.time() + 20
    while port is None and time.time() < deadline:
        if select.select([p.stderr], [], [], 0.5)[0]:
            line = p.stderr.readline()
            m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
            if m:
                port = int(m.group(1))
            elif not line:
                break
    if port is None:
        p.kill()
        sys.exit("ldrun did not listen: " + line + p.stderr.read())
    return p, port


def mbpoll(port, *args):
    """mbpoll's reply to a request on 127.0.0.1:port: the values read, "written",
    or its last line of text (an exception, an error)."""
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(port), "-0", "-1", "-o", "5"] + list(args),
                         capture_output=True, text=True, timeout=30)
    values = re.findall(r"^\[\d+\]:\s+(-?[0-9]+)", out.stdout, re.M)
    if values:
        return [int(v) for v in values]
    if "Written" in out.stdout:
        return "written"
    text = (out.stdout + out.stderr).strip()
    return text.splitlines()[-1] if text else "?"
