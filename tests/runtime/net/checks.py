"""What the Modbus client tests share: a named check that records its failure,
and the end of the run (exit 1 with the failures listed, else 0)."""
import sys

failures = []


def check(what, got, want):
    ok = got == want
    print(("ok   " if ok else "FAIL ") + what + ": " + repr(got) + ("" if ok else " (want " + repr(want) + ")"))
    if not ok:
        failures.append(what)


def finish():
    print("%d failures" % len(failures) + (": " + ", ".join(failures) if failures else ""))
    sys.exit(1 if failures else 0)
