"""The harness's record of checks, shared by e2e_test.py and geom_check.py: check() prints one
line per check and keeps the failures; finish() ends the run, exit 1 when any check failed."""
import sys

FAILURES = []


def check(ok, what, indent=""):
    print(indent + ("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        FAILURES.append(what)


def finish():
    if FAILURES:
        print("%d check(s) failed" % len(FAILURES))
        sys.exit(1)
    print("all checks passed")
