#!/usr/bin/python3
"""Headless LinuxCNC "DISPLAY" program: run one NGC file and exit.

LinuxCNC starts it as  lcsim_driver.py -ini <inifile>  once HAL, motion,
task and io are up; when it exits, the linuxcnc script shuts everything down
(its Cleanup), so the process exit IS the clean shutdown.

Environment (exported by ../run.sh):
  LCSIM_NGC      program to run (absolute path)
  LCSIM_PRE_NGC  optional program run first in the same session (rotacal:
                 the work-offset program of the compensation loop)
  LCSIM_OUT      output directory (driver.log, driver_status.json,
                 driver_probes.txt)
  LCSIM_TIMEOUT  seconds allowed for the program itself (default 170)

Sequence: wait for task -> estop reset -> machine on -> home all joints ->
auto mode -> open + run the program -> poll until the interpreter is idle
again (or an error / timeout) -> machine off, estop -> exit code
0 = program completed without error, 1 = error, 2 = timeout.
"""
import json
import os
import signal
import subprocess
import sys
import time

import linuxcnc

OUT = os.environ.get("LCSIM_OUT", ".")
LOG = open(os.path.join(OUT, "driver.log"), "a", buffering=1)
T0 = time.monotonic()
STOP = {"signal": None}


def log(msg):
    line = "[%7.3f] %s" % (time.monotonic() - T0, msg)
    LOG.write(line + "\n")
    print("lcsim_driver: " + line, flush=True)


def on_signal(sig, _frame):
    STOP["signal"] = sig


KIND = {}
for _n in ("NML_ERROR", "NML_TEXT", "NML_DISPLAY",
           "OPERATOR_ERROR", "OPERATOR_TEXT", "OPERATOR_DISPLAY"):
    if hasattr(linuxcnc, _n):
        KIND[getattr(linuxcnc, _n)] = _n
ERROR_KINDS = {getattr(linuxcnc, n) for n in ("NML_ERROR", "OPERATOR_ERROR") if hasattr(linuxcnc, n)}


class Driver:
    def __init__(self):
        self.s = linuxcnc.stat()
        self.c = linuxcnc.command()
        self.e = linuxcnc.error_channel()
        self.errors = []
        self.messages = []

    def drain_errors(self):
        while True:
            m = self.e.poll()
            if not m:
                return
            kind, text = m
            name = KIND.get(kind, str(kind))
            log("%s: %s" % (name, text))
            self.messages.append([round(time.monotonic() - T0, 3), name, text])
            if kind in ERROR_KINDS:
                self.errors.append(text)

    def wait(self, cond, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if STOP["signal"]:
                raise RuntimeError("signal %s while waiting for %s" % (STOP["signal"], what))
            self.s.poll()
            self.drain_errors()
            if cond():
                return
            time.sleep(0.01)
        raise RuntimeError("timeout (%.0f s) waiting for %s" % (timeout, what))


def run_program(d, ngc, deadline, probes, status, short=False):
    """Open and run one program in auto mode until the interpreter is idle again.

    short: a program of a few blocks (the G10 offsets program) can start and finish between
    two polls; then an interpreter that stays idle for 2 s without an error counts as done."""
    s, c = d.s, d.c
    c.program_open(ngc)
    c.wait_complete()
    t_run = time.monotonic()
    c.auto(linuxcnc.AUTO_RUN, 0)
    log("program started: %s" % ngc)
    # poll: follow probe trips independently of the NGC's own logging
    last_pp, started = None, False
    while True:
        s.poll()
        d.drain_errors()
        if s.interp_state != linuxcnc.INTERP_IDLE:
            started = True
        if s.probe_tripped and tuple(s.probed_position) != last_pp:
            last_pp = tuple(s.probed_position)
            probes.append([round(time.monotonic() - t_run, 3)] + list(last_pp))
        if STOP["signal"]:
            c.abort()
            raise RuntimeError("stopped by signal %s" % STOP["signal"])
        if time.monotonic() > deadline:
            c.abort()
            status["result"] = "timeout"
            raise RuntimeError("program did not finish in time (line %d)" % s.current_line)
        if started and s.interp_state == linuxcnc.INTERP_IDLE:
            # idle after running: finished (M2) or aborted by an error
            time.sleep(0.05)
            s.poll()
            d.drain_errors()
            if s.interp_state == linuxcnc.INTERP_IDLE:
                break
        if short and not started and time.monotonic() - t_run > 2 and not d.errors:
            break
        if not started and time.monotonic() - t_run > 10:
            raise RuntimeError("program never started (interp stayed idle)")
        time.sleep(0.005)
    t = round(time.monotonic() - t_run, 3)
    log("program finished after %.2f s: %s" % (t, ngc))
    return t


def main():
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    with open(os.path.join(OUT, "driver.pid"), "w") as f:   # run.sh's watchdog
        f.write("%d\n" % os.getpid())
    ngc = os.environ["LCSIM_NGC"]
    timeout = float(os.environ.get("LCSIM_TIMEOUT", "170"))
    status = {"ngc": ngc, "result": "error", "errors": [], "phases": {}}
    d = None
    rc = 1
    try:
        # task may need a moment before its NML channels answer
        end = time.monotonic() + 30
        while True:
            try:
                d = Driver()
                d.s.poll()
                break
            except linuxcnc.error as ex:
                if time.monotonic() > end:
                    raise RuntimeError("LinuxCNC status channel never came up: %s" % ex)
                time.sleep(0.2)
        s, c = d.s, d.c
        ini = sys.argv[sys.argv.index("-ini") + 1] if "-ini" in sys.argv else None
        njoints = int(linuxcnc.ini(ini).find("KINS", "JOINTS")) if ini else 5
        log("connected; ini=%s joints=%d" % (ini, njoints))
        try:
            comps = subprocess.run(["halcmd", "list", "comp"], capture_output=True,
                                   text=True, timeout=10).stdout.split()
            status["hal_components"] = comps
            log("HAL components: %s" % " ".join(comps))
        except Exception as ex:
            log("halcmd list comp failed: %s" % ex)

        c.state(linuxcnc.STATE_ESTOP_RESET)
        d.wait(lambda: s.task_state == linuxcnc.STATE_ESTOP_RESET, 10, "estop reset")
        c.state(linuxcnc.STATE_ON)
        d.wait(lambda: s.task_state == linuxcnc.STATE_ON, 10, "machine on")

        c.mode(linuxcnc.MODE_MANUAL)
        c.wait_complete()
        c.teleop_enable(0)
        c.wait_complete()
        c.home(-1)
        d.wait(lambda: all(s.homed[j] for j in range(njoints)), 30, "homing")
        status["phases"]["homed_s"] = round(time.monotonic() - T0, 3)
        log("all joints homed")

        c.mode(linuxcnc.MODE_AUTO)
        c.wait_complete()
        d.wait(lambda: s.task_mode == linuxcnc.MODE_AUTO, 10, "auto mode")
        deadline = time.monotonic() + timeout
        probes = []
        # rotacal: LCSIM_PRE_NGC (an offsets program, e.g. G10 L2 P1 ...) runs first in the
        # same session, so its work offsets are in effect for the cycle; a failure stops here.
        programs = [x for x in (os.environ.get("LCSIM_PRE_NGC", ""), ngc) if x]
        for k, prog in enumerate(programs):
            t_prog = run_program(d, prog, deadline, probes, status, short=prog != ngc)
            status["phases"]["program_s" if prog == ngc else "pre_program_%d_s" % k] = t_prog
            if d.errors:
                break
            # the active work offset (G54 here) after each program, as the controller holds it:
            # the evidence that an offsets program was loaded
            s.poll()
            status.setdefault("g5x_offset_after", []).append(list(s.g5x_offset))
            log("g5x offset (index %d) after %s: %s" % (s.g5x_index, prog, list(s.g5x_offset)))
        with open(os.path.join(OUT, "driver_probes.txt"), "w") as f:
            f.write("# t_s x y z a b c u v w  (stat.probed_position at each new trip)\n")
            for row in probes:
                f.write(" ".join("%.6f" % v for v in row) + "\n")
        log("%d probe trips seen via stat; errors: %d" % (len(probes), len(d.errors)))
        if d.errors:
            status["result"] = "error"
            rc = 1
        else:
            status["result"] = "ok"
            rc = 0
    except Exception as ex:  # report, then fall through to a clean shutdown
        log("FAILED: %s" % ex)
        status["errors"].append(str(ex))
        if status["result"] == "timeout":
            rc = 2
    finally:
        if d is not None:
            try:
                d.c.state(linuxcnc.STATE_OFF)
                d.c.state(linuxcnc.STATE_ESTOP)
                d.c.wait_complete(2)
                d.drain_errors()
            except Exception as ex:
                log("shutdown command failed: %s" % ex)
            status["errors"] += d.errors
            status["messages"] = d.messages
        status["wall_s"] = round(time.monotonic() - T0, 3)
        tmp = os.path.join(OUT, "driver_status.json.tmp")
        with open(tmp, "w") as f:
            json.dump(status, f, indent=1)
        os.replace(tmp, os.path.join(OUT, "driver_status.json"))
        log("exit %d" % rc)
    sys.exit(rc)


if __name__ == "__main__":
    main()
