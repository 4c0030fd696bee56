#!/usr/bin/python3
"""End-to-end tests of rotacal through a real LinuxCNC 2.9 controller (docs/e2e-linuxcnc.md).

  e2e_test.py touch154  --rotacal BIN --work DIR
      plan touch154 on ac_trunnion_lcsim.json -> generate --dialect linuxcnc -> run unchanged on
      LinuxCNC whose virtual probe plays truth_table4.json -> the program's own LOG file ->
      analyze --dialect linuxcnc. Asserts, against the injected truth:
        * every recorded trigger lies 0 .. (slow feed x 1 ms servo period) past the exact contact
          of the true machine (computed by scripts/lateness.py from the truth, not from rotacal);
        * identified - injected within 0.5 um / 0.05 mdeg for all eight location errors;
      then the compensation loop of 000 Sec. 4.5: analyze --offsets offsets.ngc (G10 L2 P1),
      run that program and the same cycle again in one LinuxCNC session, analyze: dx_AY, dy_AY,
      dz_AY and a_AY re-identify within 0.5 um / 0.05 mdeg of zero, the other four within the
      same of the injected values (000 Table 4, last column); then the post-processor route
      (issue 18): compensate the program for run 1's report, run the compensated program
      unchanged, analyze --compensated-with the report: all eight within 0.5 um / 0.05 mdeg of
      zero (what the compensation left).
  e2e_test.py no_trigger --rotacal BIN --work DIR
      the same program with the piece moved 5 mm away from the first point's face: LinuxCNC
      must stop with rotacal's own message for point 1, with no point recorded.

  e2e_test.py comp_table --rotacal BIN --work DIR
      the spheres3 program (001: three spheres, 12 C angles, 180 touches) on LinuxCNC whose virtual
      probe carries the plan's three spheres on the table of truth_table4_ecc.json: 000 Table 4's
      location errors and setup error, and an angular positioning error of the C axis (E_CC = 3 cos C
      - 1.2 sin C + 2 sin 2C mdeg, played from the C motor's command). Session 1 -> analyze: every
      trigger 0 .. F x 1 ms past the exact contact; the C location errors Oxc = dx_AY, Oyc = dy_AY +
      dy_CA, Sxc = a_AY, Syc = b_AY + b_CA (the 000 chain at A = 0) within 0.5 um / 0.05 mdeg; E_CC
      within 0.05 mdeg of the injected; the other component errors (none injected) within the same
      bounds of zero at every angle. Then the third compensation route (docs/compensation.md): rotacal
      comp-table --dialect linuxcnc -> session 2 with the table loaded as joint 4's COMP_FILE
      (COMP_FILE_TYPE = 0) -> analyze: the re-measured E_CC within 0.05 mdeg of zero at every angle and
      below a tenth of what it was, the true residual from truth and table within 0.05 mdeg, the C
      location unchanged. Then the post-processor route: the program compensated for session 1's
      report, run unchanged (session 3, no table), analyze --compensated-with it: Oxc Oyc Sxc Syc and
      E_CC within the same bounds of zero. A program turning C through a full revolution runs first in
      every session (LinuxCNC follows a joint's table only once the joint has moved through a point
      where the correction is small: docs/e2e-linuxcnc.md). This case carries the assertions of the
      former spheres3 case, which ran the same program on truth_table4.json.

  e2e_test.py one_sphere_bc --rotacal BIN --work DIR
      the B/C table (bc_trunnion_lcsim.json, xyzbc-trt-kins): first the controller's conventions read
      back in its TCP kinematics (run.sh --kins-tcp): the joints it chooses for the sphere centre at
      every pose of the plan are rotacal's nominal machine positions at B = -B*, C = -C*, every other
      sign/order candidate is hundreds of mm off, the virtual probe's nominal table is its forward
      kinematics, also with a rot-point and B pivot offset away from zero. Then plan one_sphere (16
      poses) -> generate --dialect linuxcnc -> run unchanged on LinuxCNC whose virtual probe plays
      the sphere on its stem on the table of truth_bc.json (002 Eq. (2) location errors of the B and
      the C axis) -> the program's own LOG -> analyze --dialect linuxcnc. Asserts: every trigger
      0 .. F x 1 ms past the exact contact; all 8 location errors within 0.5 um / 0.05 mdeg. Beside
      it, the same program on the controller whose own joint compensation tables make the linear
      axes' positioning errors (000 Eq. (22), Table 5's sizes, drawn here): every trigger 0 .. F x 1 ms
      past the contact computed with the tables, the offsets written, U covering the truth. Then the
      write-back of the clean run: analyze --offsets writes xyzbc-trt-kins' pins (previous, change,
      new; what the module cannot hold named) and the G54 program (X Y Z B: dx_BY, dy_CB, dz_BY,
      b_BY); LinuxCNC restarted with both (the pins act not in identity kinematics) and the cycle run
      again: what the work offset holds within its U of zero, the rest unchanged; beside it the
      program compensated for the first report: all 8 within U of zero.

  e2e_test.py one_sphere_ab --rotacal BIN --work DIR
      the A/B dual rotary table (ab_table_lcsim.json, xyzab_tdr_kins): its conventions read back in
      its TCP kinematics (type 1, selected by the read-back program: M68 E3 Q1): the joints it chooses
      for the sphere centre at every pose are rotacal's nominal machine positions at A = +A*, B = +B*,
      every other sign/order candidate is far off, also with a rot-point and A offset away from zero.
      Then plan one_sphere (9 poses) -> generate -> run unchanged on LinuxCNC whose virtual probe plays
      truth_ab.json (rotacal's A/B chain) -> analyze: every trigger 0 .. F x 1 ms past the exact
      contact; all 8 location errors within 0.5 um / 0.05 mdeg. Then the write-back: analyze --offsets
      writes xyzab_tdr_kins' pins (previous, change, new; what the module cannot hold named with its
      route) and the G54 program; LinuxCNC restarted with both and the cycle run again: what the work
      offset holds within its U of zero, the rest unchanged; beside it the program compensated for the
      first report: all 8 within U of zero.

  e2e_test.py one_sphere_bhead --rotacal BIN --work DIR
      a B head over a C table (bc_head_lcsim.json) on maxkins' joints: maxkins' conventions read back in
      maxkins itself (two pivot lengths), then plan one_sphere (9 poses) -> generate -> run unchanged in
      trivkins on the same joints, the virtual probe on the head playing truth_bhead.json (rotacal's
      head_table parameters) -> analyze: every trigger 0 .. F x 1 ms past the exact contact; the six
      unseparable directions named; the 11 separable parameters within 0.5 um / 0.05 mdeg and U. Then
      the write-back: analyze --offsets writes maxkins' pivot-length (previous, change, new) and the G54
      program; LinuxCNC restarted with both and the cycle run again: the work offset's X0C, Y0C, B0B
      within U of zero, the rest unchanged (the pin is not loaded in trivkins); beside it the pin acting
      in maxkins (two short sessions with the stylus dL longer).

  e2e_test.py one_sphere_5axis --rotacal BIN --work DIR
      the bridge mill (cb_head_lcsim.json: 5axiskins, a C head carrying a B head over a fixed table): its
      conventions read back in its TCP type (two pivot lengths, the harness's nominal head), beside plan
      one_sphere (9 poses) -> generate -> run unchanged in its identity type, the virtual probe on the head
      playing truth_5axis.json (rotacal's head_cb parameters) -> analyze: every trigger 0 .. F x 1 ms past
      the exact contact; the five unseparable directions named; the 11 separable parameters within
      0.5 um / 0.05 mdeg and U. Then the write-back: analyze --offsets writes 5axiskins' pivot-length
      (previous, change, new) and the G54 program (B and C); LinuxCNC restarted with both and the cycle run
      again: C0C and B0B within U of zero, the rest unchanged (the pin is set but the identity type does
      not read it); beside it the pin acting in the TCP type (two short sessions, the stylus dL longer).

Exit 0 pass, 1 fail, 77 skip (LinuxCNC, halcompile or root missing: CTest SKIP_RETURN_CODE).
"""
import argparse
import concurrent.futures
import json
import math
import os
import shlex
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MACHINE = os.path.join(HERE, "ac_trunnion_lcsim.json")
TRUTH = os.path.join(HERE, "truth_table4.json")
AWAY = os.path.join(HERE, "truth_piece_away.json")
RUN = os.path.join(HERE, "run.sh")
LENGTH_TOL_UM = 0.5          # the issue's tolerance: identified - injected
ANGLE_TOL_MDEG = 0.05
SERVO_PERIOD_S = 0.001       # config/lcsim_xyzac.ini [EMCMOT] SERVO_PERIOD
SHIFTED = ("dx_AY", "dy_AY", "dz_AY", "a_AY")   # what the work offset corrects (000 Sec. 4.5)
TO_UM = {"um": 1.0, "mm": 1000.0}
TO_MDEG = {"mdeg": 1.0, "deg": 1000.0, "urad": 0.18 / 3.141592653589793}

os.environ["PYTHONDONTWRITEBYTECODE"] = "1"   # the scripts import lcsim_geom: no __pycache__ in the source tree
sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(HERE, "scripts"))
from checks import check, finish  # noqa: E402


# After a move whose end position a LOG reads (the conventions' read-backs): a short dwell and a
# second queue-buster. Under load the first M66 E0 L0 has let the LOG read joints still short of the
# commanded angle (A45.0002 B-29.9988 for A45 B-30, in 2 of 4 runs beside other sessions); the
# dwell is queued behind the move, so the second sync waits for the move's end as well.
SETTLE = "G4 P0.05\nM66 E0 L0\n"


def skip_reason():
    if os.geteuid() != 0:
        return "not root: the realtime virtual probe must be installed into /usr/lib/linuxcnc/modules"
    for tool, pkg in (("linuxcnc", "linuxcnc-uspace"), ("halcompile", "linuxcnc-uspace-dev")):
        if shutil.which(tool) is None:
            return "%s not installed (Debian package %s; scripts/install-deps.sh installs it)" % (tool, pkg)
    if subprocess.run(["/usr/bin/python3", "-c", "import linuxcnc, hal"], capture_output=True).returncode != 0:
        return "/usr/bin/python3 cannot import the linuxcnc and hal modules (linuxcnc-uspace)"
    return None


def side_by_side(*calls):
    """Run the calls (functions of no argument) at once and return their results in order: the
    LinuxCNC sessions of one case that need no other's output (run.sh gives each session its own
    namespaces). An exception of one, a failed command's SystemExit included, is raised here."""
    with concurrent.futures.ThreadPoolExecutor(max_workers=len(calls)) as ex:
        futures = [ex.submit(c) for c in calls]
        return [f.result() for f in futures]


def sh(cmd, expect=0):
    print("$ " + " ".join(cmd), flush=True)
    t0 = time.monotonic()
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    print(r.stdout.rstrip(), flush=True)
    if expect is not None and r.returncode != expect:
        raise SystemExit("FAIL: exit %d (expected %d): %s" % (r.returncode, expect, " ".join(cmd)))
    return r, time.monotonic() - t0


def session(cmd):
    """A LinuxCNC session (run.sh ... --out DIR ...), run once more when its only error is
    LinuxCNC's task read-ahead race (LinuxCNC/linuxcnc issues #3650, #662, #263; a fix is proposed
    in pull request #3971): it stops a correct probing program at random, rarely, more often on a
    loaded machine. Any other failure fails the case."""
    run = cmd[cmd.index("--out") + 1]
    r, t = sh(cmd, expect=None)
    if r.returncode == 1 and lcsim_errors(run) == [QUEUE_RACE]:
        print("note: LinuxCNC stopped with %r (a known race of its task, not of the program): running the "
              "session once more" % QUEUE_RACE, flush=True)
        r, t = sh(cmd, expect=None)
    if r.returncode != 0:
        raise SystemExit("FAIL: exit %d (expected 0): %s" % (r.returncode, " ".join(cmd)))
    return r, t


NAMES_AC = ("dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA")
NAMES_BC = ("dx_BY", "dy_CB", "dz_BY", "dx_CB", "a_BY", "b_BY", "c_BY", "a_CB")
NAMES_AB = ("dx_BY", "dy_AB", "dz_BY", "dz_AB", "a_BY", "b_BY", "c_BY", "c_AB")


def injected(truth=TRUTH):
    """The truth file's location errors in um / mdeg (missing = 0)."""
    with open(truth) as f:
        le = json.load(f)["location_errors"]
    out = {}
    names = NAMES_AB if any(n in le for n in ("dy_AB", "dz_AB", "c_AB")) else (
        NAMES_BC if any(n in le for n in NAMES_BC) else NAMES_AC)
    for name in names:
        e = le.get(name, {"value": 0.0, "unit": "um" if name[0] == "d" else "mdeg"})
        out[name] = e["value"] * (TO_UM if name[0] == "d" else TO_MDEG)[e["unit"]]
    return out


def identified(report):
    with open(report) as f:
        le = json.load(f)["location_errors"]
    out = {}
    for name, e in le.items():
        want = "um" if name[0] == "d" else "mdeg"
        if e["unit"] != want:
            raise SystemExit("FAIL: %s: %s in %s, expected %s" % (report, name, e["unit"], want))
        out[name] = e["value"]
    return out


def compare(got, want, label):
    print("%s (identified - expected):" % label)
    for name, w in want.items():
        tol, unit = (LENGTH_TOL_UM, "um") if name[0] == "d" else (ANGLE_TOL_MDEG, "mdeg")
        d = got[name] - w
        check(abs(d) <= tol, "%-6s identified %9.4f expected %9.4f diff %+8.4f %s (tol %g)"
              % (name, got[name], w, d, unit, tol))


# The program writes the probing line to 4 decimals: a plan line through non-round coordinates
# (the spheres sit at 220 mm x cos 30 deg ...) is moved off it by up to 0.05 um in each of the
# two directions across it. The recorded position is where the ball really was, so the analysis
# is not affected; only this check needs the bound.
ROUNDING_ACROSS_UM = 0.05 * 2 ** 0.5
# The A/B table's sides turned to face a diagonal stem (one_sphere's plan) are approached along a
# diagonal: each of the three coordinates' roundings has a part across it.
ROUNDING_ACROSS_3D_UM = 0.05 * 3 ** 0.5


def lateness(work, run_dir, plan, offsets=None, cycle="touch154", points=154, across_um=0.001, machine=MACHINE):
    out = os.path.join(run_dir, "lateness.json")
    cmd = ["/usr/bin/python3", os.path.join(HERE, "scripts", "lateness.py"), "--params",
           os.path.join(run_dir, "params.json"), "--plan", plan, "--results",
           os.path.join(run_dir, "rotacal_%s.txt" % cycle), "--json", out]
    if offsets:
        cmd += ["--offsets", offsets]
    sh(cmd)
    with open(out) as f:
        s = json.load(f)["summary"]
    with open(machine) as f:
        slow = json.load(f)["feeds"]["probing_slow_mm_min"]
    bound_um = slow / 60.0 * SERVO_PERIOD_S * 1000.0
    # 1 nm: the LOG prints 6 decimals (mm)
    check(s["points"] == points, "%d recorded touches" % points)
    check(s["over_um"]["min"] >= -0.001 and s["over_um"]["max"] <= bound_um + 0.001,
          "every trigger 0 .. %.3f um (F%g x 1 ms) past the exact contact: %.3f .. %.3f um"
          % (bound_um, slow, s["over_um"]["min"], s["over_um"]["max"]))
    check(s["across_um_max"] <= across_um, "no trigger off the approach line by more than %.4f um (max %.4f um)"
          % (across_um, s["across_um_max"]))
    return s


def run_touch154(a):
    work = a.work
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "touch154.ngc")
    sh([a.rotacal, "plan", "--cycle", "touch154", "--machine", MACHINE, "-o", plan])
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    want = injected()
    figures = {}

    # 1. identification through the controller
    run1 = os.path.join(work, "run1")
    _, t1 = session([RUN, "--ngc", ngc, "--truth", TRUTH, "--machine", MACHINE, "--out", run1, "--timeout", "300"])
    figures["run1_s"] = t1
    figures["lateness1"] = lateness(work, run1, plan)
    rep1, offsets = os.path.join(work, "report1.json"), os.path.join(work, "offsets.ngc")
    if os.path.exists(offsets):
        os.remove(offsets)       # the loop starts from G54 = 0
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run1, "rotacal_touch154.txt"),
        "--dialect", "linuxcnc", "--json", rep1, "--offsets", offsets])
    got1 = identified(rep1)
    compare(got1, want, "run 1, injected errors through LinuxCNC")
    figures["identified1"] = got1

    # 2. the compensation loop (000 Sec. 4.5): the work-offset program, then the same cycle; and
    # 3. the post-processor route: the program rewritten for run 1's errors, run
    # unchanged, its records read back as the original program's. Both sessions need only run 1's
    # outputs: they run side by side, and are checked in this order after.
    with open(offsets) as f:
        print(f.read())
    comp = os.path.join(work, "touch154_compensated.ngc")
    sh([a.rotacal, "compensate", "--program", ngc, "--report", rep1, "--dialect", "linuxcnc", "-o", comp])
    run2, run3 = os.path.join(work, "run2"), os.path.join(work, "run3")
    (_, t2), (_, t3) = side_by_side(
        lambda: session([RUN, "--pre-ngc", offsets, "--ngc", ngc, "--truth", TRUTH, "--machine", MACHINE, "--out", run2,
                    "--timeout", "300"]),
        lambda: session([RUN, "--ngc", comp, "--truth", TRUTH, "--machine", MACHINE, "--out", run3, "--timeout", "300"]))
    figures["run2_s"] = t2
    # the controller's own G54 after the offsets program: X Y Z A of the G10 line
    with open(os.path.join(run2, "driver_status.json")) as f:
        g54 = json.load(f)["g5x_offset_after"][0]
    with open(offsets) as f:
        g10 = [l for l in f if l.startswith("G10 L2 P1")][0].split()[3:]
    want_g54 = {w[0]: float(w[1:]) for w in g10}
    check(all(abs(g54["XYZA".index(k)] - v) < 1e-9 for k, v in want_g54.items()),
          "LinuxCNC's G54 after the offsets program %s = the G10 line %s" % (g54[:4], want_g54))
    figures["lateness2"] = lateness(work, run2, plan, offsets)
    rep2 = os.path.join(work, "report2.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run2, "rotacal_touch154.txt"),
        "--dialect", "linuxcnc", "--json", rep2])
    got2 = identified(rep2)
    compare(got2, {k: (0.0 if k in SHIFTED else v) for k, v in want.items()},
            "run 2, after the work-offset correction")
    figures["identified2"] = got2

    figures["run3_s"] = t3
    rep3 = os.path.join(work, "report3.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run3, "rotacal_touch154.txt"),
        "--dialect", "linuxcnc", "--json", rep3, "--compensated-with", rep1])
    got3 = identified(rep3)
    compare(got3, {k: 0.0 for k in want}, "run 3, the compensated program (what the compensation left)")
    figures["identified3"] = got3
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)


TRUTH_ECC = os.path.join(HERE, "truth_table4_ecc.json")
QUEUE_RACE = "Queue is not empty after probing"


def lcsim_errors(run_dir):
    try:
        with open(os.path.join(run_dir, "driver_status.json")) as f:
            return [e.strip() for e in json.load(f)["errors"]]
    except (OSError, ValueError, KeyError):
        return None


def ecc_injected(c_deg):
    """E_CC of truth_ecc.json at the papers' angle C (mdeg), closed form."""
    with open(TRUTH_ECC) as f:
        e = json.load(f)["c_angular_positioning_error"]
    c = math.radians(c_deg)
    return (e.get("ECC_cos1C", 0.0) * math.cos(c) + e.get("ECC_sin1C", 0.0) * math.sin(c)
            + e.get("ECC_cos2C", 0.0) * math.cos(2 * c) + e.get("ECC_sin2C", 0.0) * math.sin(2 * c))


def table_residual_mdeg(table, c_list):
    """The C axis' true angular error left with the loaded table (mdeg), from the truth and the
    table's own rows, as LinuxCNC applies them (motor = joint + nominal - actual, interpolated
    linearly) and as the probe plays the truth (true joint angle = motor + dc(motor), dc(c) =
    E_CC(-c): truth_params.py). Independent of the second session's measurement, whose trigger
    pattern repeats the first one's exactly (the simulation is deterministic)."""
    rows = []
    with open(table) as f:
        for line in f:
            try:
                nom, fwd, _ = (float(x) for x in line.split())
            except ValueError:
                break
            rows.append((nom, nom - fwd))

    def trim(q):
        for (n0, t0), (n1, t1) in zip(rows, rows[1:]):
            if n0 <= q <= n1:
                return t0 + (t1 - t0) * (q - n0) / (n1 - n0)
        raise SystemExit("FAIL: joint angle %g outside the table" % q)

    def after(q):
        m = q + trim(q)
        return (m + ecc_injected(-m) * 1e-3 - q) * 1e3

    at_angles = max(abs(after(-c)) for c in c_list)
    over_turn = max(abs(after(-0.5 * k)) for k in range(721))
    return at_angles, over_turn


def c_location_expected(w):
    """The C axis's location (spheres3's Oxc Oyc Sxc Syc) from the 000 chain at A = 0, to first order
    (core/spheres3_identification.hpp)."""
    return {"Oxc": w["dx_AY"], "Oyc": w["dy_AY"] + w["dy_CA"], "Sxc": w["a_AY"], "Syc": w["b_AY"] + w["b_CA"]}


def check_c_location(r, want, label):
    print("%s: the C axis's location errors (identified - expected):" % label)
    for name, v in want.items():
        e = r["location_errors"][name]
        tol = LENGTH_TOL_UM if e["unit"] == "um" else ANGLE_TOL_MDEG
        check(abs(e["value"] - v) <= tol, "%s: %-4s identified %9.4f expected %9.4f diff %+8.4f %s (tol %g, u %.4f)"
              % (label, name, e["value"], v, e["value"] - v, e["unit"], tol, e["u"]))


def run_comp_table(a):
    work = a.work
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "spheres3.ngc")
    sh([a.rotacal, "plan", "--cycle", "spheres3", "--machine", MACHINE, "-o", plan])
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    # LinuxCNC 2.9's motion applies a joint's table only while the joint moves, and from rest it did
    # not take a step of 3 mdeg (observed: docs/e2e-linuxcnc.md); over one full turn the correction
    # passes zero, the filter locks on and follows from there. So: one turn of C first.
    turn = os.path.join(work, "turn_c.ngc")
    with open(turn, "w") as f:
        f.write("(rotacal e2e: one full turn of C, so that its compensation is followed from the start)\n"
                "G90 G0 C-360.0000\nG0 C0.0000\nM2\n")
    figures = {}

    def measure(tag, extra, program=ngc, compensated_with=None):
        run = os.path.join(work, tag)
        cmd = [RUN, "--pre-ngc", turn, "--ngc", program, "--truth", TRUTH_ECC, "--machine", MACHINE, "--plan", plan,
               "--out", run, "--timeout", "600"] + extra
        r, t = session(cmd)
        rep = os.path.join(work, tag + "_report.json")
        sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run, "rotacal_spheres3.txt"),
            "--dialect", "linuxcnc", "--json", rep] + (["--compensated-with", compensated_with] if compensated_with else []))
        with open(rep) as f:
            r = json.load(f)
        figures[tag + "_s"] = t
        return run, rep, r

    # 1. the error, measured through the controller
    run1, rep1, r1 = measure("before", ["--c-from-motor"])
    figures["lateness_before"] = lateness(work, run1, plan, cycle="spheres3", points=n_points,
                                          across_um=ROUNDING_ACROSS_UM)
    ecc1 = r1["component_errors"]["ECC"]
    check(ecc1["unit"] == "mdeg", "ECC in mdeg")
    want = [ecc_injected(c) for c in ecc1["c_deg"]]
    mean = sum(want) / len(want)          # the identification has no mean (a sphere position)
    d1 = max(abs(v - (w - mean)) for v, w in zip(ecc1["values"], want))
    check(d1 <= ANGLE_TOL_MDEG, "before: ECC identified - injected at most %.4f mdeg over %d angles (tol %g)"
          % (d1, len(want), ANGLE_TOL_MDEG))
    before = max(abs(v) for v in ecc1["values"])
    # the C axis's location through the controller (the former spheres3 case's assertions): the truth's
    # 000 Table 4 location errors, and every other component error (none injected) within the same
    # bounds of zero at every angle
    want_loc = c_location_expected(injected(TRUTH_ECC))
    check_c_location(r1, want_loc, "before")
    worst = {}
    for name, c in r1["component_errors"].items():
        if name == "ECC":
            continue
        tol = LENGTH_TOL_UM if c["unit"] == "um" else ANGLE_TOL_MDEG
        worst[name] = max(abs(v) for v in c["values"])
        check(worst[name] <= tol, "before: %s: none injected, identified at most %.4f %s over the turn (tol %g)"
              % (name, worst[name], c["unit"], tol))
    figures["component_max_before"] = worst
    figures["c_location_before"] = {k: r1["location_errors"][k] for k in want_loc}
    # 2. the table, in LinuxCNC's form
    table = os.path.join(work, "c_axis.comp")
    if os.path.exists(table):
        os.remove(table)
    sh([a.rotacal, "comp-table", "--report", rep1, "--dialect", "linuxcnc", "--machine", MACHINE, "-o", table])
    # 4.'s program (below): the program compensated for session 1's report
    comp = os.path.join(work, "spheres3_compensated.ngc")
    if os.path.exists(comp):
        os.remove(comp)
    sh([a.rotacal, "compensate", "--program", ngc, "--report", rep1, "--dialect", "linuxcnc", "-o", comp])
    # 3. and 4. need only session 1's outputs: their sessions run side by side, and are checked in
    # this order after
    (run2, rep2, r2), (_, _, r3) = side_by_side(
        lambda: measure("after", ["--comp-file", table]),
        lambda: measure("compensated", ["--c-from-motor"], program=comp, compensated_with=rep1))
    # 3. the same program with the table loaded
    ini = open(os.path.join(run2, "config", "lcsim_xyzac.ini")).read()
    check("COMP_FILE_TYPE = 0" in ini, "the second session's INI loads the table into [JOINT_4]")
    ecc2 = r2["component_errors"]["ECC"]
    after = max(abs(v) for v in ecc2["values"])
    check(after <= ANGLE_TOL_MDEG, "after: re-measured ECC at most %.4f mdeg over the turn (tol %g)"
          % (after, ANGLE_TOL_MDEG))
    check(after <= 0.1 * before, "ECC dropped from %.4f to %.4f mdeg (%.1f %%)"
          % (before, after, 100.0 * (1.0 - after / before)))
    # the truth's verdict on the table, independent of the second measurement
    res_angles, res_turn = table_residual_mdeg(table, ecc1["c_deg"])
    check(res_angles <= ANGLE_TOL_MDEG, "true C error left by the table at the %d angles: at most %.4f mdeg (tol %g)"
          % (len(ecc1["c_deg"]), res_angles, ANGLE_TOL_MDEG))
    check(res_turn <= ANGLE_TOL_MDEG, "true C error left by the table over the turn (every 0.5 deg): at most %.4f mdeg "
          "(tol %g)" % (res_turn, ANGLE_TOL_MDEG))
    figures["true_residual_at_angles_mdeg"] = res_angles
    figures["true_residual_over_turn_mdeg"] = res_turn
    # the table turns C only: the C axis's location is what it was
    check_c_location(r2, want_loc, "after")
    # 4. the post-processor route (the former spheres3 case): the program compensated for session 1's
    # report (the C axis's location and its component errors, E_CC included), run unchanged without
    # the table, read back as the original program's: what the compensation left
    print("after the compensated program (what the compensation left):")
    left = {}
    for name in want_loc:
        e = r3["location_errors"][name]
        tol = LENGTH_TOL_UM if e["unit"] == "um" else ANGLE_TOL_MDEG
        left[name] = e["value"]
        check(abs(e["value"]) <= tol, "compensated: %-4s %9.4f %s (tol %g)" % (name, e["value"], e["unit"], tol))
    ecc3 = max(abs(v) for v in r3["component_errors"]["ECC"]["values"])
    check(ecc3 <= ANGLE_TOL_MDEG, "compensated: E_CC left at most %.4f mdeg over the turn (tol %g)"
          % (ecc3, ANGLE_TOL_MDEG))
    figures["left_after_compensation"] = left
    figures["ecc_left_after_compensation_mdeg"] = ecc3
    vol = {"before": r1["volumetric_error_um"], "after": r2["volumetric_error_um"],
           "compensated": r3["volumetric_error_um"]}
    figures.update({"ecc_before_mdeg": ecc1["values"], "ecc_after_mdeg": ecc2["values"], "c_deg": ecc1["c_deg"],
                    "ecc_max_before_mdeg": before, "ecc_max_after_mdeg": after, "identified_minus_injected_mdeg": d1,
                    "volumetric_error_um": vol})
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("comp_table on LinuxCNC: max |ECC| %.4f -> %.4f mdeg" % (before, after))


MACHINE_BC = os.path.join(HERE, "bc_trunnion_lcsim.json")
TRUTH_BC = os.path.join(HERE, "truth_bc.json")
# one_sphere's poses on the B/C machine: four B angles (the tilt axis both ways, 90 deg puts the stem
# horizontal) x four C angles = 16 poses, 4 or 5 touches each. The plan's default (7 x 4 = 28 poses,
# 116 touches) would take twice as long; this set keeps every separable parameter (the plan refuses a
# set that loses one) and the identification within the tolerance (docs/e2e-linuxcnc.md).
ONE_SPHERE_BC_SET = ["tilt_list=-90,-30,30,90", "c_list=0,90,180,270"]


def papers_chain_bc(b_star, c_star, pw):
    """Nominal 002 Eq. (2) of rotacal (docs/conventions.md): p_m = Db(-B*) Dc(-C*) p_w."""
    b, c = math.radians(-b_star), math.radians(-c_star)
    x = math.cos(c) * pw[0] - math.sin(c) * pw[1]
    y = math.sin(c) * pw[0] + math.cos(c) * pw[1]
    return [math.cos(b) * x + math.sin(b) * pw[2], y, -math.sin(b) * x + math.cos(b) * pw[2]]


def kins_readback_bc(a, work, plan_path):
    """The controller's B/C conventions, read back from the running xyzbc-trt-kins (TCP mode,
    run.sh --kins-tcp), not assumed. For every pose of the plan the program moves the ball, in
    table coordinates, to the sphere's nominal centre at the joint angles rotacal's program
    commands there (B = -B*, C = -C*: bc_trunnion_lcsim.json's linuxcnc sign), and LOGs the joints
    LinuxCNC chose and the ball as the virtual probe sees it in its table frame. Checks:
      * the joints are the plan's nominal sphere centre in machine coordinates (rotacal's 002
        Eq. (2) at B*, C*): rotacal's nominal kinematics are the controller's;
      * every other sign/order candidate (Ry(+-B) Rz(+-C), Rz(+-C) Ry(+-B)) is far off;
      * the probe (no errors) puts the ball at the commanded table point: its nominal map is the
        controller's forward kinematics;
    then the same at a rot-point and B pivot offset (x-offset, z-offset) away from zero, set on the
    kinematics and on the probe's axis lines alike: the pins' meaning (trtfuncs.c:
    p_m = Ry(B) (Rz(C) (p_t - R) - D) + R + D, D = (x-offset, 0, z-offset))."""
    with open(plan_path) as f:
        plan = json.load(f)
    centre = plan["points"][0]["sphere"]["center_w_mm"]
    radius = plan["points"][0]["sphere"]["radius_mm"]
    rows = []    # (B*, C*, table point)
    for pose in plan["poses"]:
        rows.append((pose["pose"]["B"], pose["pose"]["C"], centre))
    # a few more, off the sphere: a general point, a full C turn and beyond, B both ways
    rows += [(-30.0, 45.0, [10.0, 20.0, 30.0]), (60.0, -120.0, [40.0, -70.0, 25.0]),
             (-75.0, 400.0, [-50.0, 30.0, 60.0]), (0.0, 0.0, [0.0, 0.0, 0.0])]
    truth0 = os.path.join(work, "truth_none.json")
    with open(truth0, "w") as f:
        json.dump({"format": "rotacal-truth/1", "_comment": "no error: the controller's nominal table"}, f)
    # R and D for the second pass; the probe's lines follow them: pA = R + D, pC = R
    R, D = (5.0, -3.0, 7.0), (20.0, 0.0, -15.0)
    out = {}
    n_poses = len(plan["poses"])
    for tag, rd in (("zero", None), ("offsets", (R, D))):
        # the pins' meaning needs no more than the four extra rows and four of the plan's poses
        rows_ = rows if rd is None else rows[:n_poses:max(1, n_poses // 4)] + rows[n_poses:]
        ngc = os.path.join(work, "kins_readback_%s.ngc" % tag)
        with open(ngc, "w") as f:
            f.write("(rotacal e2e: xyzbc-trt-kins read-back, TCP kinematics; row: i B C x y z, the joints 0..4,"
                    " the probe's ball in its table frame)\nG21 G17 G40 G49 G54 G61 G90 G94\n"
                    "(LOGOPEN,kins_readback.txt)\n")
            # nothing to touch (no artefact): straight from row to row
            for i, (b_star, c_star, p) in enumerate(rows_):
                b, c = -b_star, -c_star
                f.write(("G0 X%.6f Y%.6f Z%.6f B%.6f C%.6f\nM66 E0 L0\n" + SETTLE) % (p[0], p[1], p[2], b, c))
                # three LOG lines a row: LinuxCNC refuses a block longer than 256 characters
                f.write("(LOG,R %d %.6f %.6f %.6f %.6f %.6f)\n" % (i, b, c, p[0], p[1], p[2]))
                f.write("(LOG,J %d" % i + "".join(" #<_hal[joint.%d.pos-cmd]>" % j for j in range(5)) + ")\n")
                f.write("(LOG,T %d #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % i)
            f.write("(LOGCLOSE)\nM2\n")
        cmd = [RUN, "--kins-tcp", "--ngc", ngc, "--truth", truth0, "--machine", MACHINE_BC, "--out",
               os.path.join(work, "readback_" + tag), "--timeout", "300"]
        if rd:
            setp = os.path.join(work, "readback_offsets.hal")
            with open(setp, "w") as f:
                (rx_, ry_, rz_), (dx, _, dz) = rd
                for k, v in (("x-rot-point", rx_), ("y-rot-point", ry_), ("z-rot-point", rz_), ("x-offset", dx),
                             ("z-offset", dz)):
                    f.write("setp xyzbc-trt-kins.%s %.12g\n" % (k, v))
                for k, v in zip(("a-px", "a-py", "a-pz", "c-px", "c-py", "c-pz"), (rx_ + dx, ry_, rz_ + dz, rx_, ry_, rz_)):
                    f.write("setp vtouchprobe.0.%s %.12g\n" % (k, v))
            cmd += ["--setp", setp]
        _, t = session(cmd)
        parts = {}
        with open(os.path.join(work, "readback_" + tag, "kins_readback.txt")) as f:
            for line in f:
                t_ = line.split()
                if len(t_) >= 2 and t_[0] in ("R", "J", "T"):
                    parts.setdefault(int(t_[1]), {})[t_[0]] = [float(x) for x in t_[2:]]
        # a row: i, B, C, x, y, z (commanded), joints 0..4, the probe's ball x y z
        got = [[float(i)] + v["R"] + v["J"] + v["T"] for i, v in sorted(parts.items())
               if len(v.get("R", [])) == 5 and len(v.get("J", [])) == 5 and len(v.get("T", [])) == 3]
        check(len(got) == len(rows_), "read-back (%s): %d rows of %d" % (tag, len(got), len(rows_)))
        R_, D_ = rd if rd else ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

        def cand(order, sb, sc, b, c, p):
            q = [p[k] - R_[k] for k in range(3)]
            rb, rc = math.radians(sb * b), math.radians(sc * c)

            def Ry(v):
                return [math.cos(rb) * v[0] + math.sin(rb) * v[2], v[1], -math.sin(rb) * v[0] + math.cos(rb) * v[2]]

            def Rz(v):
                return [math.cos(rc) * v[0] - math.sin(rc) * v[1], math.sin(rc) * v[0] + math.cos(rc) * v[1], v[2]]
            if order == "BC":     # the table point turned by C first, then carried by B (trtfuncs.c)
                v = Ry([x - d for x, d in zip(Rz(q), D_)])
            else:
                v = Rz([x - d for x, d in zip(Ry(q), D_)])
            return [v[k] + R_[k] + D_[k] for k in range(3)]
        worst = {}
        for order in ("BC", "CB"):
            for sb in (1, -1):
                for sc in (1, -1):
                    worst[(order, sb, sc)] = max(
                        max(abs(g[6 + k] - cand(order, sb, sc, g[1], g[2], g[3:6])[k]) for k in range(3)) for g in got)
        best = worst[("BC", 1, 1)]
        others = min(v for k, v in worst.items() if k != ("BC", 1, 1))
        check(best < 1e-6, "read-back (%s): joints = Ry(+B) (Rz(+C) (p - R) - D) + R + D within %.1e mm (%d rows)"
              % (tag, best, len(got)))
        check(others > 1.0, "read-back (%s): every other sign/order candidate is off by at least %.1f mm"
              % (tag, others))
        check(all(abs(g[9] - g[1]) < 1e-9 and abs(g[10] - g[2]) < 1e-9 for g in got),
              "read-back (%s): joints 3, 4 are the commanded B, C" % tag)
        ball = max(max(abs(g[11 + k] - g[3 + k]) for k in range(3)) for g in got)
        check(ball < 1e-6, "read-back (%s): the probe's ball in its table frame = the commanded table point within "
              "%.1e mm" % (tag, ball))
        if not rd:
            # rotacal's own nominal machine positions of the sphere centre (the plan's triggers less
            # (R + r) along the contact normal) at B*, C* against what the controller chose at B = -B*, C = -C*
            r_ball = plan["machine"]["probe"]["ball_diameter_mm"] / 2.0
            dev, dev_chain = 0.0, 0.0
            for pose_i, pose in enumerate(plan["poses"]):
                pt = [q for q in plan["points"] if q["pose_name"] == pose["name"]][0]
                cm = [pt["trigger_m_mm"][k] + (radius + r_ball) * pt["approach_m"][k] for k in range(3)]
                dev = max(dev, max(abs(got[pose_i][6 + k] - cm[k]) for k in range(3)))
                pc = papers_chain_bc(pose["pose"]["B"], pose["pose"]["C"], centre)
                dev_chain = max(dev_chain, max(abs(pc[k] - cm[k]) for k in range(3)))
            check(dev < 1e-5, "read-back: at all %d poses LinuxCNC puts the sphere centre where rotacal's plan does "
                  "(B = -B*, C = -C*), within %.1e mm" % (len(plan["poses"]), dev))
            check(dev_chain < 1e-5, "the plan's centres are Db(-B*) Dc(-C*) c_w (002 Eq. (2), nominal) within %.1e mm"
                  % dev_chain)
        out[tag] = {"rows": len(got), "session_s": t, "max_dev_mm": best, "other_candidates_min_mm": others,
                    "candidates_mm": {"%s B%+d C%+d" % k: v for k, v in worst.items()}, "probe_ball_dev_mm": ball}
    return out


CONTRIB_LINEAR = os.path.join(HERE, "contributors_linear.json")
LINEAR_SEED = 1   # fixed before the first run; the controller and the probe are deterministic
LINEAR_JOINT_RANGE_MM = (-600.0, 600.0)   # config/lcsim_xyzbc.ini's joint limits: the tables cover them


def draw_linear_comp(dirpath, seed):
    """000 Eq. (22)'s positioning errors of X, Y and Z at 000 Table 5's sizes, drawn here (not by
    rotacal, which is under test): per axis a node spacing p uniform in [20, 50] mm, nodes Q_i = p i
    over the joint's limits and beyond, values N(0, 2 um) plus the scale N(0, 1 um/100 mm) x Q_i,
    linearly interpolated between nodes, as the controller interpolates its table (the scale, being
    linear, is exact there). Written as LinuxCNC's COMP_FILE_TYPE = 0 rows 'nominal forward reverse'
    with forward = reverse = nominal - e: the controller then drives the motor to joint + e(joint)
    (motor = joint + nominal - actual), and the probe reads the motor (run.sh --linear-comp), so the
    axis stands e past where the controller believes. Returns the largest |e| (um)."""
    import random
    rng = random.Random(seed)
    os.makedirs(dirpath, exist_ok=True)
    largest = 0.0
    for j in range(3):
        p = rng.uniform(20.0, 50.0)
        scale = rng.gauss(0.0, 1.0e-3 / 100.0)
        i0 = int(math.floor(LINEAR_JOINT_RANGE_MM[0] / p)) - 1
        i1 = int(math.ceil(LINEAR_JOINT_RANGE_MM[1] / p)) + 1
        with open(os.path.join(dirpath, "joint%d.comp" % j), "w") as f:
            for i in range(i0, i1 + 1):
                q = p * i
                e = rng.gauss(0.0, 2.0e-3) + scale * q
                largest = max(largest, abs(e) * 1000.0)
                f.write("%.6f %.6f %.6f\n" % (q, q - e, q - e))
    return largest


def linear_axes_session(a, work):
    """The controller makes the linear axes' errors (its own joint compensation tables) under the
    same injected location errors: the analysis, given what the controller makes as its declared
    contributors, still writes the offsets, and its U covers the truth: at least 6 of the 8 within
    U (a 95 % U each: 3 or more outside has probability 0.6 %) and every one within 2 U (a normal
    beyond 3.9 sigma: 1e-4). Returns its figures."""
    comp = os.path.join(work, "linear_comp")
    largest = draw_linear_comp(comp, LINEAR_SEED)
    # the machine as the controller makes it: the probe's repeatability is the servo period's
    # lateness (contributors_linear.json), one quantity in the machine file and the declaration
    with open(MACHINE_BC) as f:
        m = json.load(f)
    m["probe"]["repeatability_um"] = 0.05
    machine = os.path.join(work, "machine_linear.json")
    with open(machine, "w") as f:
        json.dump(m, f, indent=1)
    plan, ngc = plan_one_sphere_bc(a, machine, work, "_linear")
    run = os.path.join(work, "run_linear")
    _, t = session([RUN, "--ngc", ngc, "--truth", TRUTH_BC, "--machine", machine, "--plan", plan, "--out", run,
               "--linear-comp", comp, "--timeout", "300"])
    return {"comp": comp, "plan": plan, "run": run, "machine": machine, "largest_um": largest, "run_s": t}


def check_linear_axes_session(a, work, s):
    with open(s["plan"]) as f:
        n_points = len(json.load(f)["points"])
    # the controller applied its tables: every trigger is 0 .. F x 1 ms past the contact computed
    # with them (and would be several um off without them)
    lat = lateness_cmd(work, s["run"], s["plan"], "one_sphere", ["--linear-comp", s["comp"]])
    check(lat["points"] == n_points and lat["over_um"]["min"] >= -0.001 and lat["over_um"]["max"] <= 0.168,
          "linear axes in the controller's tables (largest %.2f um): every trigger 0 .. 0.167 um past the contact "
          "computed with the tables: %.3f .. %.3f um" % (s["largest_um"], lat["over_um"]["min"], lat["over_um"]["max"]))
    plain = lateness_cmd(work, s["run"], s["plan"], "one_sphere", [], name="lateness_without_tables.json")
    check(max(abs(plain["over_um"]["min"]), abs(plain["over_um"]["max"])) > 0.5,
          "without the tables the same triggers are off by up to %.2f um: the tables acted"
          % max(abs(plain["over_um"]["min"]), abs(plain["over_um"]["max"])))
    rep, off = os.path.join(work, "report_linear.json"), os.path.join(work, "offsets_linear.hal")
    sh([a.rotacal, "analyze", "--plan", s["plan"], "--results", os.path.join(s["run"], "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--contributors", CONTRIB_LINEAR, "--json", rep, "--offsets", off])
    check(os.path.exists(off), "the offsets are written on the machine the controller makes")
    with open(rep) as f:
        le = json.load(f)["location_errors"]
    want = injected(TRUTH_BC)
    within, within2, rows = 0, 0, {}
    for name, w in want.items():
        d, U = le[name]["value"] - w, le[name]["U"]
        within += abs(d) <= U
        within2 += abs(d) <= 2 * U
        rows[name] = {"identified_minus_injected": d, "U": U}
        print("  %-6s identified - injected %+8.4f, U %.4f %s" % (name, d, U, le[name]["unit"]))
    check(within >= 6 and within2 == 8, "U covers the truth: %d of 8 within U (>= 6), %d within 2 U (all)"
          % (within, within2))
    return {"lateness": lat, "lateness_without_tables": plain, "errors": rows, "largest_um": s["largest_um"],
            "run_s": s["run_s"]}


def lateness_cmd(work, run_dir, plan, cycle, extra, name="lateness_tables.json"):
    out = os.path.join(run_dir, name)
    sh(["/usr/bin/python3", os.path.join(HERE, "scripts", "lateness.py"), "--params", os.path.join(run_dir, "params.json"),
        "--plan", plan, "--results", os.path.join(run_dir, "rotacal_%s.txt" % cycle), "--json", out] + extra)
    with open(out) as f:
        return json.load(f)["summary"]


def plan_one_sphere_bc(a, machine, work, tag=""):
    """The case's short one_sphere plan (ONE_SPHERE_BC_SET) and its LinuxCNC program."""
    plan, ngc = os.path.join(work, "plan%s.json" % tag), os.path.join(work, "one_sphere%s.ngc" % tag)
    cmd = [a.rotacal, "plan", "--cycle", "one_sphere", "--machine", machine, "-o", plan]
    for kv in ONE_SPHERE_BC_SET:
        cmd += ["--set", kv]
    sh(cmd)
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    return plan, ngc


def analyze_one_sphere(a, work, plan, run, truth, chain):
    """analyze of a one_sphere session: the report, its location errors checked to be the truth's
    eight (of `chain`), the truth's values and what the plan holds at nominal (unseparable)."""
    rep = os.path.join(work, "report.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep])
    with open(rep) as f:
        r = json.load(f)
    want = injected(truth)
    check(sorted(want) == sorted(r["location_errors"]), "the report carries the 8 location errors of %s: %s"
          % (chain, sorted(r["location_errors"])))
    return rep, r, want, sorted(u["held"] for u in r.get("unseparable", []))


def run_one_sphere_bc(a):
    work = a.work
    plan, ngc = plan_one_sphere_bc(a, MACHINE_BC, work)
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    run = os.path.join(work, "run")
    # the read-back (two short sessions) and the cycle's session need nothing of each other: side by side
    # and the session whose controller carries the linear axes' errors in its own tables
    readback, (_, t), linear = side_by_side(
        lambda: kins_readback_bc(a, work, plan),
        lambda: session([RUN, "--ngc", ngc, "--truth", TRUTH_BC, "--machine", MACHINE_BC, "--plan", plan, "--out", run,
                    "--timeout", "300"]),
        lambda: linear_axes_session(a, work))
    figures = {"readback": readback}
    figures["run_s"] = t
    figures["lateness"] = lateness(work, run, plan, cycle="one_sphere", points=n_points,
                                   across_um=ROUNDING_ACROSS_UM, machine=MACHINE_BC)
    rep, r, want, held = analyze_one_sphere(a, work, plan, run, TRUTH_BC, "002 Eq. (2)")
    # what one sphere cannot separate: C's zero (with the sphere's set-up) and C's tilt about B (with
    # B's zero); 002 Eq. (2) carries neither, so the truth injects neither
    check(held == ["B0C", "C0C"], "the report holds exactly B0C and C0C at nominal (unseparable): %s" % held)
    got = identified(rep)
    compare(got, want, "one_sphere on LinuxCNC (xyzbc-trt-kins), injected B and C location errors")
    figures.update({"identified": got, "injected": want, "unseparable": r.get("unseparable"),
                    "points": n_points, "location_errors_note": r.get("location_errors_note")})
    figures["U"] = {n: e["U"] for n, e in r["location_errors"].items()}
    figures["linear_axes"] = check_linear_axes_session(a, work, linear)
    figures.update(write_back_bc(a, work, plan, ngc, rep, got, want))
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("one_sphere B/C on LinuxCNC: %d touches, LinuxCNC session %.0f s" % (n_points, t))


# What each route holds on the B/C table: xyzbc-trt-kins' pins (in TCP only) B's place and C's from it
# (the C axis through rot-point, the B pivot at rot-point + offset); the work offset, in every
# kinematics, B's place (X, Z), C's place along B's line (Y) and B's zero; the rest (dx_CB, a_BY,
# c_BY, a_CB) only a rewritten program (rotacal compensate) or the mechanics.
BC_PINS = {"x-rot-point": ("dx_BY", "dx_CB"), "y-rot-point": ("dy_CB",), "z-rot-point": ("dz_BY",),
           "x-offset": ("-dx_CB",), "z-offset": ()}
BC_WORK_OFFSET = ("dx_BY", "dy_CB", "dz_BY", "b_BY")


def write_back_bc(a, work, plan, ngc, rep1, got1, want):
    """The B/C table's write-back and the loop closed on the controller (write_back_table): analyze
    --offsets writes xyzbc-trt-kins' pins (offsets.hal: previous, change, new; what the module cannot
    hold named) and the work offset (offsets.ngc). The cycle runs in identity kinematics: the pins,
    loaded, act not there (their meaning is the read-back's, in TCP); the work offset does."""
    def pin_value(terms):
        return sum(-got1[t[1:]] if t[0] == "-" else got1[t] for t in terms) * 1e-3

    def files(hal_text, g10_text):
        pins = {}
        for line in hal_text.splitlines():
            t_ = line.split()
            if len(t_) == 3 and t_[0] == "setp" and t_[1].startswith("xyzbc-trt-kins."):
                pins[t_[1].split(".", 1)[1]] = float(t_[2])
        check(sorted(pins) == sorted(BC_PINS), "offsets.hal sets xyzbc-trt-kins' %s" % ", ".join(sorted(pins)))
        check(all(abs(pins[k] - pin_value(v)) <= 1e-6 for k, v in BC_PINS.items() if k in pins),
              "each pin's new value = its previous (0) + the identified %s in mm"
              % ", ".join("%s -> %s" % (" + ".join(v) or "0", k) for k, v in BC_PINS.items()))
        table = [l for l in hal_text.splitlines() if l.startswith("# ") and len(l.split()) == 5]
        check(any(l.split()[1:] == ["pin", "previous", "change", "new"] for l in table),
              "offsets.hal gives each pin's previous value, change and new value")
        rest = [l for l in hal_text.splitlines() if "Reported only" in l]
        check(any("a_BY, c_BY" in l and "a_CB" in l for l in rest),
              "offsets.hal names what the module cannot hold (a_BY, c_BY, a_CB)")
        check("G10 L2 P1 B" in hal_text, "offsets.hal gives B's zero as a work offset (G10 L2 P1 B)")
        check("dx_CB, a_BY, c_BY, a_CB: rotacal compensate" in g10_text,
              "offsets.ngc names what no shift expresses (dx_CB, a_BY, c_BY, a_CB) and the route (rotacal compensate)")
        return pins
    return write_back_table(a, work, plan, ngc, rep1, want, files, MACHINE_BC, TRUTH_BC, "B",
                            BC_WORK_OFFSET, ROUNDING_ACROSS_UM)


MACHINE_AB = os.path.join(HERE, "ab_table_lcsim.json")
TRUTH_AB = os.path.join(HERE, "truth_ab.json")
# one_sphere's poses on the A/B machine: three B tilts x three A turns = 9 poses. The plan's default
# (B x A, -60 .. 60 in 30 deg steps, 25 poses) would take three times as long; this set keeps
# every separable parameter (the plan refuses a set that loses one) and the identification within
# the tolerance (docs/e2e-linuxcnc.md).
ONE_SPHERE_AB_SET = ["tilt_list=-60,0,60", "a_list=-60,0,60"]


def rx_deg(t, v):
    t = math.radians(t)
    return [v[0], math.cos(t) * v[1] - math.sin(t) * v[2], math.sin(t) * v[1] + math.cos(t) * v[2]]


def ry_deg(t, v):
    t = math.radians(t)
    return [math.cos(t) * v[0] + math.sin(t) * v[2], v[1], -math.sin(t) * v[0] + math.cos(t) * v[2]]


def kins_readback_ab(a, work, plan_path):
    """The controller's A/B conventions, read back from the running xyzab_tdr_kins in its TCP
    kinematics (type 1, selected by the program itself as the sample config's M428 does: M68 E3 Q1,
    M66 E0 L0), not assumed. For every pose of the plan the program moves the ball, in table
    coordinates, to the sphere's nominal centre at the joint angles rotacal's program commands there
    (A = +A*, B = +B*: ab_table_lcsim.json's linuxcnc sign), and LOGs the joints LinuxCNC chose and
    the ball as the virtual probe sees it in its table frame. Checks:
      * the joints are the plan's nominal sphere centre in machine coordinates: rotacal's nominal
        kinematics (p_m = Db(-B*) Da(-A*) p_w) are the controller's;
      * every other sign/order candidate (Ry(+-B) Rx(+-A), Rx(+-A) Ry(+-B)) is far off;
      * the probe (no errors) puts the ball at the commanded table point;
    then the same with a rot-point and A offset away from zero, on the kinematics' pins and the
    probe's lines alike: the pins' meaning, which the write-back relies on (the module's
    kinematicsInverse: p_m = Ry(-B) (Rx(-A) (p_t - R - D) + D) + R, D = (x-offset, 0, z-offset))."""
    with open(plan_path) as f:
        plan = json.load(f)
    centre = plan["points"][0]["sphere"]["center_w_mm"]
    radius = plan["points"][0]["sphere"]["radius_mm"]
    rows = [(pose["pose"]["A"], pose["pose"]["B"], centre) for pose in plan["poses"]]   # (A*, B*, table point)
    rows += [(45.0, -30.0, [10.0, 20.0, 30.0]), (-100.0, 60.0, [40.0, -70.0, 25.0]),
             (30.0, 100.0, [-50.0, 30.0, 60.0]), (0.0, 0.0, [0.0, 0.0, 0.0])]
    truth0 = os.path.join(work, "truth_none.json")
    with open(truth0, "w") as f:
        json.dump({"format": "rotacal-truth/1", "_comment": "no error: the controller's nominal table"}, f)
    R, D = (5.0, -3.0, 7.0), (20.0, 0.0, -15.0)
    out = {}
    n_poses = len(plan["poses"])
    for tag, rd in (("zero", None), ("offsets", (R, D))):
        rows_ = rows if rd is None else rows[:n_poses:max(1, n_poses // 4)] + rows[n_poses:]
        ngc = os.path.join(work, "kins_readback_%s.ngc" % tag)
        with open(ngc, "w") as f:
            f.write("(rotacal e2e: xyzab_tdr_kins read-back, TCP kinematics; row: i A B x y z, the joints 0..4,"
                    " the probe's ball in its table frame)\nG21 G17 G40 G49 G54 G61 G90 G94\n"
                    "M68 E3 Q1\nM66 E0 L0\n(LOGOPEN,kins_readback.txt)\n(LOG,K #<_hal[motion.switchkins-type]>)\n")
            for i, (a_star, b_star, p) in enumerate(rows_):
                f.write(("G0 X%.6f Y%.6f Z%.6f A%.6f B%.6f\nM66 E0 L0\n" + SETTLE) % (p[0], p[1], p[2], a_star, b_star))
                f.write("(LOG,R %d %.6f %.6f %.6f %.6f %.6f)\n" % (i, a_star, b_star, p[0], p[1], p[2]))
                f.write("(LOG,J %d" % i + "".join(" #<_hal[joint.%d.pos-cmd]>" % j for j in range(5)) + ")\n")
                f.write("(LOG,T %d #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % i)
            # back to identity at zero angles, where the two agree
            f.write("G0 A0 B0\nM68 E3 Q0\nM66 E0 L0\n(LOGCLOSE)\nM2\n")
        cmd = [RUN, "--ngc", ngc, "--truth", truth0, "--machine", MACHINE_AB, "--out",
               os.path.join(work, "readback_" + tag), "--timeout", "300"]
        if rd:
            setp = os.path.join(work, "readback_offsets.hal")
            with open(setp, "w") as f:
                (rx_, ry_, rz_), (dx, _, dz) = rd
                for k, v in (("x-rot-point", rx_), ("y-rot-point", ry_), ("z-rot-point", rz_), ("x-offset", dx),
                             ("z-offset", dz)):
                    f.write("setp xyzab_tdr_kins.%s %.12g\n" % (k, v))
                # the probe's B line through R, its A line through R + D (x-offset moves along A: nothing)
                for k, v in zip(("a-px", "a-py", "a-pz", "c-px", "c-py", "c-pz"), (rx_, ry_, rz_, rx_ + dx, ry_, rz_ + dz)):
                    f.write("setp vtouchprobe.0.%s %.12g\n" % (k, v))
            cmd += ["--setp", setp]
        _, t = session(cmd)
        parts, kinstype = {}, None
        with open(os.path.join(work, "readback_" + tag, "kins_readback.txt")) as f:
            for line in f:
                t_ = line.split()
                if len(t_) == 2 and t_[0] == "K":
                    kinstype = float(t_[1])
                if len(t_) >= 2 and t_[0] in ("R", "J", "T"):
                    parts.setdefault(int(t_[1]), {})[t_[0]] = [float(x) for x in t_[2:]]
        check(kinstype == 1.0, "read-back (%s): motion.switchkins-type = %s after M68 E3 Q1 (1: TCP)" % (tag, kinstype))
        # a row: i, A, B, x, y, z (commanded), joints 0..4, the probe's ball x y z
        got = [[float(i)] + v["R"] + v["J"] + v["T"] for i, v in sorted(parts.items())
               if len(v.get("R", [])) == 5 and len(v.get("J", [])) == 5 and len(v.get("T", [])) == 3]
        check(len(got) == len(rows_), "read-back (%s): %d rows of %d" % (tag, len(got), len(rows_)))
        R_, D_ = rd if rd else ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

        def cand(order, sa, sb, a_, b_, p):
            q = [p[k] - R_[k] - D_[k] for k in range(3)]
            if order == "BA":     # A turns the table point first and is carried by B
                v = ry_deg(sb * b_, [x + d for x, d in zip(rx_deg(sa * a_, q), D_)])
            else:
                v = rx_deg(sa * a_, [x + d for x, d in zip(ry_deg(sb * b_, q), D_)])
            return [v[k] + R_[k] for k in range(3)]
        worst = {}
        for order in ("BA", "AB"):
            for sa in (1, -1):
                for sb in (1, -1):
                    worst[(order, sa, sb)] = max(
                        max(abs(g[6 + k] - cand(order, sa, sb, g[1], g[2], g[3:6])[k]) for k in range(3)) for g in got)
        best = worst[("BA", -1, -1)]
        others = min(v for k, v in worst.items() if k != ("BA", -1, -1))
        check(best < 1e-6, "read-back (%s): joints = Ry(-B) (Rx(-A) (p - R - D) + D) + R within %.1e mm (%d rows)"
              % (tag, best, len(got)))
        check(others > 1.0, "read-back (%s): every other sign/order candidate is off by at least %.1f mm"
              % (tag, others))
        check(all(abs(g[9] - g[1]) < 1e-9 and abs(g[10] - g[2]) < 1e-9 for g in got),
              "read-back (%s): joints 3, 4 are the commanded A, B" % tag)
        ball = max(max(abs(g[11 + k] - g[3 + k]) for k in range(3)) for g in got)
        check(ball < 1e-6, "read-back (%s): the probe's ball in its table frame = the commanded table point within "
              "%.1e mm" % (tag, ball))
        if not rd:
            r_ball = plan["machine"]["probe"]["ball_diameter_mm"] / 2.0
            dev, dev_chain = 0.0, 0.0
            for pose_i, pose in enumerate(plan["poses"]):
                pt = [q for q in plan["points"] if q["pose_name"] == pose["name"]][0]
                cm = [pt["trigger_m_mm"][k] + (radius + r_ball) * pt["approach_m"][k] for k in range(3)]
                dev = max(dev, max(abs(got[pose_i][6 + k] - cm[k]) for k in range(3)))
                pc = ry_deg(-pose["pose"]["B"], rx_deg(-pose["pose"]["A"], centre))
                dev_chain = max(dev_chain, max(abs(pc[k] - cm[k]) for k in range(3)))
            check(dev < 1e-5, "read-back: at all %d poses LinuxCNC puts the sphere centre where rotacal's plan does "
                  "(A = +A*, B = +B*), within %.1e mm" % (len(plan["poses"]), dev))
            check(dev_chain < 1e-5, "the plan's centres are Db(-B*) Da(-A*) c_w (rotacal's A/B chain, nominal) within "
                  "%.1e mm" % dev_chain)
        out[tag] = {"rows": len(got), "session_s": t, "max_dev_mm": best, "other_candidates_min_mm": others,
                    "candidates_mm": {"%s A%+d B%+d" % k: v for k, v in worst.items()}, "probe_ball_dev_mm": ball}
    return out


def plan_one_sphere_ab(a, work):
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "one_sphere.ngc")
    cmd = [a.rotacal, "plan", "--cycle", "one_sphere", "--machine", MACHINE_AB, "-o", plan]
    for kv in ONE_SPHERE_AB_SET:
        cmd += ["--set", kv]
    sh(cmd)
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    return plan, ngc


def run_one_sphere_ab(a):
    work = a.work
    plan, ngc = plan_one_sphere_ab(a, work)
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    run = os.path.join(work, "run")
    readback, (_, t) = side_by_side(
        lambda: kins_readback_ab(a, work, plan),
        lambda: session([RUN, "--ngc", ngc, "--truth", TRUTH_AB, "--machine", MACHINE_AB, "--plan", plan, "--out", run,
                         "--timeout", "300"]))
    figures = {"readback": readback, "run_s": t}
    figures["lateness"] = lateness(work, run, plan, cycle="one_sphere", points=n_points,
                                   across_um=ROUNDING_ACROSS_3D_UM, machine=MACHINE_AB)
    rep, r, want, held = analyze_one_sphere(a, work, plan, run, TRUTH_AB, "the A/B chain")
    # what one sphere cannot separate: A's zero (with the sphere's set-up) and A's tilt about Y (with
    # B's zero); the A/B chain carries neither, so the truth injects neither
    check(held == ["A0A", "B0A"], "the report holds exactly A0A and B0A at nominal (unseparable): %s" % held)
    got = identified(rep)
    compare(got, want, "one_sphere on LinuxCNC (xyzab_tdr_kins), injected B and A location errors")
    U = {n: e["U"] for n, e in r["location_errors"].items()}
    figures.update({"identified": got, "injected": want, "unseparable": r.get("unseparable"), "points": n_points,
                    "U": U, "location_errors_note": r.get("location_errors_note")})
    figures.update(write_back_ab(a, work, plan, ngc, rep, got, want))
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("one_sphere A/B on LinuxCNC: %d touches, LinuxCNC session %.0f s" % (n_points, t))


# What each route holds on the A/B table: xyzab_tdr_kins' pins the B axis's place (rot-point) and A's
# offset from it (z-offset); the work offset, in every kinematics, B's place and zero; the rest only
# a rewritten program (rotacal compensate) or the mechanics.
AB_PINS = {"x-rot-point": "dx_BY", "y-rot-point": "dy_AB", "z-rot-point": "dz_BY", "z-offset": "dz_AB"}
AB_WORK_OFFSET = ("dx_BY", "dy_AB", "dz_BY", "b_BY")


def write_back_ab(a, work, plan, ngc, rep1, got1, want):
    """The A/B table's write-back and the loop closed on the controller (write_back_table): analyze
    --offsets writes the kinematics' own pins (offsets.hal: previous, change, new; what the module
    cannot hold named with its route) and the work offset (offsets.ngc)."""
    def files(hal_text, g10_text):
        pins = {}
        for line in hal_text.splitlines():
            t_ = line.split()
            if len(t_) == 3 and t_[0] == "setp" and t_[1].startswith("xyzab_tdr_kins."):
                pins[t_[1].split(".", 1)[1]] = float(t_[2])
        check(sorted(pins) == sorted(AB_PINS), "offsets.hal sets xyzab_tdr_kins' %s" % ", ".join(sorted(pins)))
        check(all(abs(pins[k] - got1[n] * 1e-3) <= 1e-6 for k, n in AB_PINS.items() if k in pins),
              "each pin's new value = its previous (0) + the identified %s in mm"
              % ", ".join("%s -> %s" % (n, k) for k, n in AB_PINS.items()))
        table = [l for l in hal_text.splitlines() if l.startswith("# ") and len(l.split()) == 5]
        check(any(l.split()[1:] == ["pin", "previous", "change", "new"] for l in table),
              "offsets.hal gives each pin's previous value, change and new value")
        rest = [l for l in hal_text.splitlines() if "Reported only" in l or "rotacal compensate" in l]
        check(any("a_BY, c_BY" in l and "c_AB" in l for l in rest) and any("rotacal compensate" in l for l in rest),
              "offsets.hal names what the module cannot hold (a_BY, c_BY, c_AB) and the route (rotacal compensate)")
        check("G10 L2 P1 B" in hal_text, "offsets.hal gives B's zero as a work offset (G10 L2 P1 B)")
        check("dz_AB, a_BY, c_BY, c_AB" in g10_text, "offsets.ngc names what no shift expresses (dz_AB, a_BY, c_BY, c_AB)")
        return pins
    return write_back_table(a, work, plan, ngc, rep1, want, files, MACHINE_AB, TRUTH_AB, "B",
                            AB_WORK_OFFSET, ROUNDING_ACROSS_3D_UM)


def write_back_table(a, work, plan, ngc, rep1, want, files, machine, truth, tilt, work_offset, across_um):
    """The write-back of a table machine and the loop closed on the controller. analyze --offsets writes
    the kinematics' pins (offsets.hal, checked by `files` with offsets.ngc's text) and the work offset
    (offsets.ngc: G54 X Y Z and the tilt axis' zero). LinuxCNC is then started again with the pins
    loaded (--setp, as the HAL file would be) and the work offset run first (--pre-ngc), and the
    unchanged cycle measures again: what the work offset holds (`work_offset`) within its U of zero,
    the rest as before. The cycle runs in identity kinematics, where the trt pins act not (their
    meaning is the read-back's, in TCP); beside it, the program rewritten for all eight (rotacal
    compensate): every one within U of zero."""
    hal, g10 = os.path.join(work, "offsets.hal"), os.path.join(work, "offsets.ngc")
    res1 = os.path.join(work, "run", "rotacal_one_sphere.txt")
    for out in (hal, g10):
        if os.path.exists(out):
            os.remove(out)       # the loop starts from the nominal pins and G54 = 0 (a file present is added to)
        sh([a.rotacal, "analyze", "--plan", plan, "--results", res1, "--dialect", "linuxcnc", "--json",
            os.path.join(work, "report_offsets.json"), "--offsets", out])
    with open(hal) as f:
        hal_text = f.read()
    print(hal_text)
    with open(g10) as f:
        g10_text = f.read()
    print(g10_text)
    pins = files(hal_text, g10_text)
    g10_line = [l for l in g10_text.splitlines() if l.startswith("G10 L2 P1")][0].split()[3:]
    want_g54 = {w[0]: float(w[1:]) for w in g10_line}
    check(sorted(want_g54) == sorted(["X", "Y", "Z", tilt]), "offsets.ngc shifts G54 %s" % " ".join(sorted(want_g54)))
    print("note: the cycle runs in identity kinematics: offsets.hal's trt pins, loaded, act not there (they act in "
          "TCP, the read-back's mode); the work offset does", flush=True)
    comp = os.path.join(work, "one_sphere_compensated.ngc")
    sh([a.rotacal, "compensate", "--program", ngc, "--report", rep1, "--dialect", "linuxcnc", "-o", comp])
    run2, run3 = os.path.join(work, "run2"), os.path.join(work, "run3")
    (_, t2), (_, t3) = side_by_side(
        lambda: session([RUN, "--setp", hal, "--pre-ngc", g10, "--ngc", ngc, "--truth", truth, "--machine",
                         machine, "--plan", plan, "--out", run2, "--timeout", "300"]),
        lambda: session([RUN, "--ngc", comp, "--truth", truth, "--machine", machine, "--plan", plan, "--out",
                         run3, "--timeout", "300"]))
    with open(os.path.join(run2, "driver_status.json")) as f:
        g54 = json.load(f)["g5x_offset_after"][0]
    # LinuxCNC's status carries G54 as X Y Z A B C U V W
    check(all(abs(g54["XYZABCUVW".index(k)] - v) < 1e-9 for k, v in want_g54.items()),
          "LinuxCNC's G54 after the offsets program %s = the G10 line %s" % (g54[:6], want_g54))
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    lat2 = lateness(work, run2, plan, offsets=g10, cycle="one_sphere", points=n_points, across_um=across_um,
                    machine=machine)
    rep2, rep3 = os.path.join(work, "report2.json"), os.path.join(work, "report3.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run2, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep2])
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run3, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep3, "--compensated-with", rep1])
    out = {"run2_s": t2, "run3_s": t3, "lateness2": lat2, "pins": pins, "g54": want_g54}
    for tag, path, held in (("after_offsets", rep2, work_offset), ("compensated", rep3, tuple(want))):
        with open(path) as f:
            le = json.load(f)["location_errors"]
        rows = {}
        for name, w in want.items():
            expect = 0.0 if name in held else w
            d, U = le[name]["value"] - expect, le[name]["U"]
            # the compensated program prints its angles to 4 decimals (0.05 mdeg of rounding on each
            # axis): there U alone is the bound
            tol = (LENGTH_TOL_UM if name[0] == "d" else ANGLE_TOL_MDEG) if tag == "after_offsets" else U
            what = "within its U of zero" if name in held else "unchanged (not held: reported, named above)"
            check(abs(d) <= U and abs(d) <= tol, "%s: %-6s %9.4f %s, expected %9.4f: diff %+8.4f, U %.4f (tol %g)"
                  % (tag, name, le[name]["value"], le[name]["unit"], expect, d, U, tol) + " " + what)
            rows[name] = {"value": le[name]["value"], "U": U, "expected": expect}
        out[tag] = rows
    return out


GUIDE = os.path.join(HERE, "..", "..", "..", "docs", "guide", "linuxcnc.md")
GUIDE_MACHINE = "examples/machines/ac_trunnion.json"   # the guide's MACHINE.json, here the e2e controller's


def guide_commands(path=GUIDE):
    """The rotacal command lines of the guide's code blocks, in order (a trailing backslash joins
    the next line; comments and prose inside a block are not commands)."""
    cmds, block, pending = [], False, ""
    for line in open(path).read().split("\n"):
        t = line.strip()
        if t.startswith("```"):
            block, pending = not block, ""
            continue
        if not block:
            continue
        t = pending + t
        if t.endswith("\\"):
            pending = t[:-1].rstrip() + " "
            continue
        pending = ""
        if t.startswith("rotacal "):
            cmds.append(t)
    return cmds


def guide_step(cmds, prefix, contains=""):
    """The guide's first command starting with `prefix` (and holding `contains`): a guide that no
    longer shows it fails the case, so the test follows the page."""
    for c in cmds:
        if c.startswith(prefix) and contains in c:
            return c
    raise SystemExit("FAIL: docs/guide/linuxcnc.md no longer shows a command %r%s" %
                     (prefix, " with " + contains if contains else ""))


def run_guide_command(a, work, cmd, env=None, **replace):
    """One of the guide's commands, as written, run in `work`: `rotacal` is the binary under test,
    the guide's MACHINE.json the e2e controller's machine, and `replace` swaps one word for another
    (an output's name: the guide says the offsets' form follows the extension)."""
    words = shlex.split(cmd)
    words = [a.rotacal] + [MACHINE if w == GUIDE_MACHINE else replace.get(w, w) for w in words[1:]]
    print("$ (guide) " + cmd + ("   [%s]" % ", ".join("%s -> %s" % kv for kv in replace.items()) if replace else ""),
          flush=True)
    r = subprocess.run(words, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       env=dict(os.environ, **(env or {})))
    print(r.stdout.rstrip(), flush=True)
    if r.returncode != 0:
        raise SystemExit("FAIL: the guide's command exits %d: %s" % (r.returncode, cmd))
    return r.stdout


def run_one_sphere_ac(a):
    """docs/guide/linuxcnc.md followed as written on the A/C table (xyzac-trt-kins): its commands are
    read from the page and run in order, MACHINE.json being the e2e controller's (step 1 is the
    user's), the controller's virtual probe playing truth_table4.json (000 Table 4's location
    errors; its set-up moves only the column): plan one_sphere (68 touches), generate and check the
    program, run it unchanged, bring the LOG back, analyze with offsets. Asserts: every trigger
    0 .. F x 1 ms past the exact contact (A = -A*, C = -C*, the mapping the touch154 case checks),
    the verdict first, all 8 location errors within 0.5 um / 0.05 mdeg, the HAL offsets naming the
    xyzac-trt-kins pins. Then step 10's re-measurements side by side: the same program after the
    offsets' G54 shift (the four shifted errors within the tolerance of zero, the others unchanged)
    and the program compensated by step 9's commands (all 8 within it of zero, read with
    --compensated-with); and the history kept by step 10's commands."""
    work = a.work
    cmds = guide_commands()
    for name in os.listdir(work):
        p = os.path.join(work, name)
        if os.path.isfile(p):
            os.remove(p)   # the guide's outputs start afresh (an earlier run's would become .bak)
    # steps 2 and 4: plan, generate, check
    run_guide_command(a, work, guide_step(cmds, "rotacal plan --cycle one_sphere"))
    run_guide_command(a, work, guide_step(cmds, "rotacal generate"))
    out = run_guide_command(a, work, guide_step(cmds, "rotacal check", "one_sphere.ngc"))
    check("ok" in out, "the guide's `rotacal check` passes the program it generated")
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "one_sphere.ngc")
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    # step 5: send the program; step 7: bring the LOG back
    run = os.path.join(work, "run")
    _, t = session([RUN, "--ngc", ngc, "--truth", TRUTH, "--machine", MACHINE, "--plan", plan, "--out", run,
                    "--timeout", "300"])
    shutil.copy(os.path.join(run, "rotacal_one_sphere.txt"), work)
    figures = {"run_s": t, "points": n_points}
    figures["lateness"] = lateness(work, run, plan, cycle="one_sphere", points=n_points,
                                   across_um=ROUNDING_ACROSS_UM, machine=MACHINE)
    # step 8: analyze with offsets, the verdict first
    analyze = guide_step(cmds, "rotacal analyze", "rotacal_one_sphere.txt")
    run_guide_command(a, work, analyze)
    rep = os.path.join(work, "REPORT.json")
    with open(rep) as f:
        r = json.load(f)
    with open(os.path.join(work, "REPORT.txt")) as f:
        check(f.read().startswith("verdict"), "REPORT.txt opens with the verdict (the guide: read the verdict first)")
    check("verdict" in r, "REPORT.json carries the verdict block")
    want = injected(TRUTH)
    check(sorted(want) == sorted(r["location_errors"]), "the report carries the 8 location errors of 000 Eq. (1): %s"
          % sorted(r["location_errors"]))
    held = sorted(u["held"] for u in r.get("unseparable", []))
    print("what one sphere cannot separate on this plan (held at nominal): %s" % held)
    got = identified(rep)
    compare(got, want, "one_sphere on LinuxCNC (xyzac-trt-kins) by the guide, 000 Table 4's location errors")
    with open(os.path.join(work, "offsets.hal")) as f:
        hal = f.read()
    check(all("setp xyzac-trt-kins.%s " % pin in hal for pin in ("x-rot-point", "y-rot-point", "z-rot-point")),
          "offsets.hal sets the xyzac-trt-kins pins the guide names")
    # step 8's other form (the guide: the form follows the extension), then step 9's commands
    run_guide_command(a, work, analyze, **{"offsets.hal": "offsets.ngc", "REPORT.json": "REPORT_ngc.json",
                                           "REPORT.txt": "REPORT_ngc.txt", "REPORT.html": "REPORT_ngc.html"})
    run_guide_command(a, work, guide_step(cmds, "rotacal compensate"))
    run_guide_command(a, work, guide_step(cmds, "rotacal check", "one_sphere_comp.ngc"))
    # step 10: the same program after the offsets, and the compensated program, side by side
    run2, run3 = os.path.join(work, "run2"), os.path.join(work, "run3")
    side_by_side(
        lambda: session([RUN, "--pre-ngc", os.path.join(work, "offsets.ngc"), "--ngc", ngc, "--truth", TRUTH,
                         "--machine", MACHINE, "--plan", plan, "--out", run2, "--timeout", "300"]),
        lambda: session([RUN, "--ngc", os.path.join(work, "one_sphere_comp.ngc"), "--truth", TRUTH, "--machine",
                         MACHINE, "--plan", plan, "--out", run3, "--timeout", "300"]))
    rep2, rep3 = os.path.join(work, "report_after_offsets.json"), os.path.join(work, "report_compensated.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run2, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep2])
    got2 = identified(rep2)
    compare(got2, {k: (0.0 if k in SHIFTED else v) for k, v in want.items()},
            "the same program after the guide's offsets.ngc (G54 shift)")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run3, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep3, "--compensated-with", rep])
    got3 = identified(rep3)
    compare(got3, {k: 0.0 for k in want}, "the guide's compensated program (what the compensation left)")
    # step 10: the history, where the guide says it lands
    env = {"XDG_DATA_HOME": os.path.join(work, "xdg")}
    run_guide_command(a, work, guide_step(cmds, "rotacal history add"), env=env)
    run_guide_command(a, work, guide_step(cmds, "rotacal history show"), env=env)
    check(os.path.exists(os.path.join(work, "xdg", "rotacal", "history.sqlite")),
          "the history database is where the guide says ($XDG_DATA_HOME/rotacal/history.sqlite)")
    check(os.path.exists(os.path.join(work, "TREND.html")), "history show wrote TREND.html")
    figures.update({"identified": got, "injected": want, "unseparable": r.get("unseparable"),
                    "after_offsets": got2, "compensated": got3})
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("docs/guide/linuxcnc.md on LinuxCNC (A/C): %d touches, first session %.0f s" % (n_points, t))


MACHINE_BHEAD = os.path.join(HERE, "bc_head_lcsim.json")
TRUTH_BHEAD = os.path.join(HERE, "truth_bhead.json")
# one_sphere's poses on the B head over the C table: three B tilts x three C turns = 9 poses, 39
# touches. The plan's default (B -60 .. 60 in 30 deg steps x C every 90 deg, 20 poses, 84 touches)
# would take twice as long; two tilts leave 8 directions unseen and the plan refuses them.
ONE_SPHERE_BHEAD_SET = ["tilt_list=-60,0,60", "c_list=0,120,240"]
# What one sphere cannot separate on a B head over a C table, as rotacal computes it from the plan's
# Jacobian (REPORT.json unseparable): C's zero (with the sphere's set-up), the pivot's X and Z (with
# the table's X and the sphere's Z), the ball's offsets from the spindle axis (with Y0C and B0B) and
# the linear axes' Y/Z squareness (with Y0C and A0B). The truth injects none of them.
BHEAD_HELD = ["C0C", "S_yz", "X0B", "Z0B", "dX_T", "dY_T"]
BHEAD_NAMES = ("X0C", "Y0C", "A0C", "B0C", "A0B", "C0B", "B0B", "dL", "dX_S", "dY_S", "dZ_S")
BHEAD_LENGTHS = ("X0C", "Y0C", "dL", "dX_S", "dY_S", "dZ_S")


def injected_bhead(truth=TRUTH_BHEAD):
    """The head truth's parameters in um / mdeg (missing = 0)."""
    with open(truth) as f:
        le = json.load(f)["location_errors"]
    out = {}
    for name in BHEAD_NAMES:
        length = name in BHEAD_LENGTHS
        e = le.get(name, {"value": 0.0, "unit": "um" if length else "mdeg"})
        out[name] = e["value"] * (TO_UM if length else TO_MDEG)[e["unit"]]
    return out


def rz_deg(t, v):
    t = math.radians(t)
    return [math.cos(t) * v[0] - math.sin(t) * v[1], math.sin(t) * v[0] + math.cos(t) * v[1], v[2]]


def kins_readback_max(a, work, plan_path):
    """maxkins' conventions, read back from the running module (it has no identity type: run.sh
    --kins-tcp loads it in place of the cycle's trivkins), not assumed. For every pose of the plan
    the program moves the tip, in table coordinates, to the sphere's nominal centre at the joint
    angles rotacal's program commands there (B = -B*, C = +C*: bc_head_lcsim.json's linuxcnc signs),
    and to four rows off the sphere, and LOGs the joints LinuxCNC chose and the ball as the virtual
    probe sees it in its table frame. Checks, with maxkins.pivot-length L = 250 (the machine's pivot
    to ball) and then 173.5 mm:
      * the joints are maxkins' inverse as its source writes it: the tip turned by -C, joint 0 -= L
        sin B, joint 2 += L cos B - L (B against ISO 841's head, C as rotacal's table, joint 2 reading
        the tip at B = 0, so the pivot is L above it);
      * every other candidate (B's sign, C's sign, joint 2 reading the pivot) is far off;
      * the probe, its pivot L above the joints' point, puts the ball at the commanded tip;
      * at the plan's poses the joints are rotacal's machine positions for the ball on the sphere's
        centre minus (0, 0, L): the same motion, Z counted from the tip at B = 0 instead of the pivot."""
    with open(plan_path) as f:
        plan = json.load(f)
    centre = plan["points"][0]["sphere"]["center_w_mm"]
    radius = plan["points"][0]["sphere"]["radius_mm"]
    L0 = plan["machine"]["head"]["pivot_to_ball_mm"]
    rows = [(-pose["pose"]["B"], pose["pose"]["C"], centre) for pose in plan["poses"]]   # (joint B, joint C, tip)
    rows += [(-45.0, 30.0, [10.0, 20.0, 30.0]), (80.0, -100.0, [40.0, -70.0, 25.0]),
             (-100.0, 200.0, [-50.0, 30.0, 60.0]), (0.0, 0.0, [0.0, 0.0, 0.0])]
    truth0 = os.path.join(work, "truth_none.json")
    with open(truth0, "w") as f:
        json.dump({"format": "rotacal-truth/1", "_comment": "no error: the controller's nominal machine"}, f)
    n_poses = len(plan["poses"])
    out = {}
    for tag, L in (("pivot_%g" % L0, L0), ("pivot_173.5", 173.5)):
        rows_ = rows if L == L0 else rows[:n_poses:max(1, n_poses // 4)] + rows[n_poses:]
        ngc = os.path.join(work, "kins_readback_%s.ngc" % tag)
        with open(ngc, "w") as f:
            f.write("(rotacal e2e: maxkins read-back, its TCP kinematics; row: i B C x y z, the joints 0..5,"
                    " the probe's ball in its table frame)\nG21 G17 G40 G49 G54 G61 G90 G94\n"
                    "(LOGOPEN,kins_readback.txt)\n(LOG,K #<_hal[maxkins.pivot-length]>)\n")
            for i, (b, c, p) in enumerate(rows_):
                f.write(("G0 X%.6f Y%.6f Z%.6f B%.6f C%.6f\nM66 E0 L0\n" + SETTLE) % (p[0], p[1], p[2], b, c))
                f.write("(LOG,R %d %.6f %.6f %.6f %.6f %.6f)\n" % (i, b, c, p[0], p[1], p[2]))
                f.write("(LOG,J %d" % i + "".join(" #<_hal[joint.%d.pos-cmd]>" % j for j in range(6)) + ")\n")
                f.write("(LOG,T %d #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % i)
            f.write("(LOGCLOSE)\nM2\n")
        setp = os.path.join(work, "readback_%s.hal" % tag)
        with open(setp, "w") as f:
            # maxkins' pin; the probe's pivot L above the joints' point, the ball on it at B = 0
            f.write("setp maxkins.pivot-length %.12g\nsetp vtouchprobe.0.h1-pz %.12g\nsetp vtouchprobe.0.hb-z 0\n"
                    % (L, L))
        _, t = session([RUN, "--ngc", ngc, "--truth", truth0, "--machine", MACHINE_BHEAD, "--kins-tcp", "--setp", setp,
                        "--out", os.path.join(work, "readback_" + tag), "--timeout", "300"])
        parts, pin = {}, None
        with open(os.path.join(work, "readback_" + tag, "kins_readback.txt")) as f:
            for line in f:
                t_ = line.split()
                if len(t_) == 2 and t_[0] == "K":
                    pin = float(t_[1])
                if len(t_) >= 2 and t_[0] in ("R", "J", "T"):
                    parts.setdefault(int(t_[1]), {})[t_[0]] = [float(x) for x in t_[2:]]
        check(pin is not None and abs(pin - L) < 1e-9, "read-back (%s): maxkins.pivot-length = %s" % (tag, pin))
        # a row: i, B, C, x, y, z (commanded), joints 0..5, the probe's ball x y z
        got = [[float(i)] + v["R"] + v["J"] + v["T"] for i, v in sorted(parts.items())
               if len(v.get("R", [])) == 5 and len(v.get("J", [])) == 6 and len(v.get("T", [])) == 3]
        check(len(got) == len(rows_), "read-back (%s): %d rows of %d" % (tag, len(got), len(rows_)))

        def cand(con, sc, tip_at_b0, b, c, p):
            q = rz_deg(-sc * c, p)
            zb = L * math.cos(math.radians(b)) - (L if tip_at_b0 else 0.0)
            return [q[0] + con * L * math.sin(math.radians(b)), q[1], q[2] + zb]
        worst = {}
        for con in (-1, 1):
            for sc in (1, -1):
                for tip in (True, False):
                    worst[(con, sc, tip)] = max(max(abs(g[6 + k] - cand(con, sc, tip, g[1], g[2], g[3:6])[k])
                                                    for k in range(3)) for g in got)
        best = worst[(-1, 1, True)]
        others = min(v for k, v in worst.items() if k != (-1, 1, True))
        check(best < 1e-6, "read-back (%s): joints = Rz(-C) p + (-L sin B, 0, L cos B - L) within %.1e mm (%d rows)"
              % (tag, best, len(got)))
        check(others > 1.0, "read-back (%s): every other candidate (B's sign, C's sign, joint 2 at the pivot) is off by "
              "at least %.1f mm" % (tag, others))
        check(all(abs(g[10] - g[1]) < 1e-9 and abs(g[11] - g[2]) < 1e-9 and abs(g[9]) < 1e-9 for g in got),
              "read-back (%s): joints 4, 5 are the commanded B, C, joint 3 (A) stays 0" % tag)
        ball = max(max(abs(g[12 + k] - g[3 + k]) for k in range(3)) for g in got)
        check(ball < 1e-6, "read-back (%s): the probe's ball in its table frame = the commanded tip within %.1e mm"
              % (tag, ball))
        if L == L0:
            r_ball = plan["machine"]["probe"]["ball_diameter_mm"] / 2.0
            dev = 0.0
            for pose_i, pose in enumerate(plan["poses"]):
                pt = [q for q in plan["points"] if q["pose_name"] == pose["name"]][0]
                cm = [pt["trigger_m_mm"][k] + (radius + r_ball) * pt["approach_m"][k] for k in range(3)]
                dev = max(dev, max(abs(got[pose_i][6 + k] - (cm[k] - (L0 if k == 2 else 0.0))) for k in range(3)))
            check(dev < 1e-5, "read-back: at all %d poses LinuxCNC's joints are rotacal's plan's carriage for the ball on "
                  "the sphere's centre (B = -B*, C = +C*), Z less L = %g mm (maxkins' Z reads the tip at B = 0), within "
                  "%.1e mm" % (len(plan["poses"]), L0, dev))
        out[tag] = {"rows": len(got), "session_s": t, "pivot_length_mm": L, "max_dev_mm": best,
                    "other_candidates_min_mm": others, "probe_ball_dev_mm": ball,
                    "candidates_mm": {"con%+d C%+d %s" % (k[0], k[1], "tip@B0" if k[2] else "pivot"): v
                                      for k, v in worst.items()}}
    return out


def plan_one_sphere_bhead(a, work):
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "one_sphere.ngc")
    cmd = [a.rotacal, "plan", "--cycle", "one_sphere", "--machine", MACHINE_BHEAD, "-o", plan]
    for kv in ONE_SPHERE_BHEAD_SET:
        cmd += ["--set", kv]
    sh(cmd)
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    return plan, ngc


def kinematic_parameters(report):
    """A head machine's report: its kinematic parameters (value, U, unit) by ISO name."""
    with open(report) as f:
        r = json.load(f)
    out = {}
    for name, e in r["kinematic_parameters"].items():
        want = "um" if name in BHEAD_LENGTHS or name in ("X0B", "Z0B", "dX_T", "dY_T", "dR") else "mdeg"
        if e["unit"] != want:
            raise SystemExit("FAIL: %s: %s in %s, expected %s" % (report, name, e["unit"], want))
        out[name] = e
    return r, out


def run_one_sphere_bhead(a):
    work = a.work
    plan, ngc = plan_one_sphere_bhead(a, work)
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    run = os.path.join(work, "run")
    readback, (_, t) = side_by_side(
        lambda: kins_readback_max(a, work, plan),
        lambda: session([RUN, "--ngc", ngc, "--truth", TRUTH_BHEAD, "--machine", MACHINE_BHEAD, "--plan", plan, "--out",
                         run, "--timeout", "300"]))
    figures = {"readback": readback, "run_s": t}
    figures["lateness"] = lateness(work, run, plan, cycle="one_sphere", points=n_points,
                                   across_um=ROUNDING_ACROSS_3D_UM, machine=MACHINE_BHEAD)
    rep = os.path.join(work, "report.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep])
    r, kp = kinematic_parameters(rep)
    held = sorted(u["held"] for u in r.get("unseparable", []))
    check(held == BHEAD_HELD, "the report holds exactly %s at nominal (unseparable, from the plan's Jacobian): %s"
          % (", ".join(BHEAD_HELD), held))
    want = injected_bhead()
    print("one_sphere on LinuxCNC (B head over C table, maxkins' joints), injected head_table errors "
          "(identified - expected):")
    for name, w in want.items():
        tol = LENGTH_TOL_UM if name in BHEAD_LENGTHS else ANGLE_TOL_MDEG
        d, U = kp[name]["value"] - w, kp[name]["U"]
        check(abs(d) <= tol and abs(d) <= U, "%-5s identified %9.4f expected %9.4f diff %+8.4f %s, U %.4f (tol %g)"
              % (name, kp[name]["value"], w, d, kp[name]["unit"], U, tol))
    figures.update({"identified": {n: kp[n]["value"] for n in want}, "U": {n: kp[n]["U"] for n in want},
                    "injected": want, "unseparable": r.get("unseparable"), "points": n_points})
    figures.update(write_back_bhead(a, work, plan, ngc, rep, kp, want))
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("one_sphere B head / C table on LinuxCNC: %d touches, LinuxCNC session %.0f s" % (n_points, t))


# What each route holds on maxkins' machine: its pin, pivot-length, the stylus (dL: the ball's distance
# from the pivot); the work offset, in every kinematics, the C table's place and the head's zero; the
# tilts no pin or shift (a mechanical adjustment); the sphere's set-up is the artefact's.
BHEAD_WORK_OFFSET = ("X0C", "Y0C", "B0B")


def write_back_bhead(a, work, plan, ngc, rep1, kp1, want):
    """The write-back and the loop closed on the controller. analyze --offsets writes maxkins' pin
    (offsets.hal: pivot-length's previous value, change and new value; the rest named with its route)
    and the work offset (offsets.ngc). LinuxCNC is started again with both: the G54 program first
    (--pre-ngc), the pin's line given to the session (--setp), and the unchanged cycle measures again:
    what the work offset holds within its U of zero, the rest as before. The cycle's session runs
    trivkins (maxkins has no identity type), where the pin is not even loaded: run.sh keeps the line
    as a comment, and dL comes back unchanged. Beside it, a short session in maxkins itself with the
    stylus dL longer than nominal shows the pin acting: the tip commanded at the plan's poses, the
    ball's offset from it varies with B by dL sin B at the nominal pin and is the same at every pose
    at the written one (the constant left, -dL in Z, is the Z reference's: the file says so)."""
    hal, g10 = os.path.join(work, "offsets.hal"), os.path.join(work, "offsets.ngc")
    res1 = os.path.join(work, "run", "rotacal_one_sphere.txt")
    for out in (hal, g10):
        if os.path.exists(out):
            os.remove(out)       # the loop starts from the nominal pin and G54 = 0 (a file present is added to)
        sh([a.rotacal, "analyze", "--plan", plan, "--results", res1, "--dialect", "linuxcnc", "--json",
            os.path.join(work, "report_offsets.json"), "--offsets", out])
    with open(plan) as f:
        pl = json.load(f)
    L = pl["machine"]["head"]["pivot_to_ball_mm"]
    with open(hal) as f:
        hal_text = f.read()
    print(hal_text)
    pins = {}
    for line in hal_text.splitlines():
        t_ = line.split()
        if len(t_) == 3 and t_[0] == "setp" and t_[1].startswith("maxkins."):
            pins[t_[1].split(".", 1)[1]] = float(t_[2])
    check(sorted(pins) == ["pivot-length"], "offsets.hal sets maxkins' pivot-length only: %s" % sorted(pins))
    new_pl = pins.get("pivot-length", float("nan"))
    check(abs(new_pl - (L + kp1["dL"]["value"] * 1e-3)) <= 1e-6,
          "pivot-length = previous (MACHINE.json's L = %g mm) + the identified dL (%.4f um): %.6f mm"
          % (L, kp1["dL"]["value"], new_pl))
    check(any(l.split()[1:] == ["pin", "previous", "change", "new"] for l in hal_text.splitlines() if l.startswith("# ")),
          "offsets.hal gives the pin's previous value, change and new value")
    check("A0C, B0C (orientation of the C axis) and A0B, C0B" in hal_text and "mechanical adjustment" in hal_text,
          "offsets.hal names what maxkins cannot hold (A0C, B0C, A0B, C0B) and the route")
    check("C0C, X0B, Z0B, dX_T, dY_T" in hal_text, "offsets.hal names the held (unseparable) parameters")
    check("G10 L2 P1 X" in hal_text, "offsets.hal gives the C table's place and the B zero as a work offset (G10 L2 P1)")
    with open(g10) as f:
        g10_text = f.read()
    print(g10_text)
    g10_line = [l for l in g10_text.splitlines() if l.startswith("G10 L2 P1")][0].split()[3:]
    want_g54 = {w[0]: float(w[1:]) for w in g10_line}
    sign_b = -1   # bc_head_lcsim.json's linuxcnc sign of B, read back above
    expect_g54 = {"X": kp1["X0C"]["value"] * 1e-3, "Y": kp1["Y0C"]["value"] * 1e-3,
                  "B": -sign_b * kp1["B0B"]["value"] * 1e-3}
    check(sorted(want_g54) == ["B", "X", "Y"] and all(abs(want_g54[k] - v) <= 0.5e-6 for k, v in expect_g54.items()),
          "offsets.ngc shifts G54 X, Y by the identified X0C, Y0C and B by %+d x B0B: %s" % (-sign_b, want_g54))
    check("dL [maxkins' pivot-length, a .hal file], A0C, B0C, A0B, C0B" in g10_text,
          "offsets.ngc names what no shift expresses (dL, A0C, B0C, A0B, C0B)")
    # rotacal compensate rewrites table machines' programs: it refuses the head, naming why
    r, _ = sh([a.rotacal, "compensate", "--program", ngc, "--report", rep1, "--dialect", "linuxcnc", "-o",
               os.path.join(work, "one_sphere_compensated.ngc")], expect=None)
    check(r.returncode == 1 and "head_table" in r.stdout, "rotacal compensate refuses the head_table report with its "
          "reason (exit %d)" % r.returncode)
    run2 = os.path.join(work, "run2")
    # the pin acting, in maxkins: the true stylus dL longer (truth: dL alone), the carriage reading the tip
    # at B = 0 for the nominal L; the tip commanded to the sphere's centre at the plan's poses
    dl_true = injected_bhead()["dL"] * 1e-3
    truth_dl = os.path.join(work, "truth_dl.json")
    with open(truth_dl, "w") as f:
        json.dump({"format": "rotacal-truth/1", "_comment": "the stylus alone, dL longer than nominal",
                   "location_errors": {"dL": {"value": dl_true * 1e3, "unit": "um"}}}, f)
    centre = pl["points"][0]["sphere"]["center_w_mm"]

    def pin_session(tag, pivot_length):
        prog = os.path.join(work, "pin_%s.ngc" % tag)
        with open(prog, "w") as f:
            f.write("(rotacal e2e: maxkins' pivot-length acting; row: i B C, the probe's ball in its table frame)\n"
                    "G21 G17 G40 G49 G54 G61 G90 G94\n(LOGOPEN,pin.txt)\n")
            for i, pose in enumerate(pl["poses"]):
                b, c = sign_b * pose["pose"]["B"], pose["pose"]["C"]
                f.write(("G0 X%.6f Y%.6f Z%.6f B%.6f C%.6f\nM66 E0 L0\n" + SETTLE) % (centre[0], centre[1], centre[2], b, c))
                f.write("(LOG,T %d %.6f %.6f #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % (i, b, c))
            f.write("(LOGCLOSE)\nM2\n")
        setp = os.path.join(work, "pin_%s.hal" % tag)
        with open(setp, "w") as f:
            f.write("setp maxkins.pivot-length %.12g\nsetp vtouchprobe.0.h1-pz %.12g\nsetp vtouchprobe.0.hb-z %.12g\n"
                    % (pivot_length, L, -dl_true))
        out_dir = os.path.join(work, "pin_" + tag)
        _, t_ = session([RUN, "--ngc", prog, "--truth", truth_dl, "--machine", MACHINE_BHEAD, "--kins-tcp", "--setp",
                         setp, "--out", out_dir, "--timeout", "300"])
        rows = []
        with open(os.path.join(out_dir, "pin.txt")) as f:
            for line in f:
                t = line.split()
                if len(t) == 7 and t[0] == "T":
                    rows.append([float(v) for v in t[2:]])
        check(len(rows) == len(pl["poses"]), "pin session (%s): %d rows" % (tag, len(rows)))
        # the ball's offset from the commanded tip, its spread over the poses (um)
        dev = [[(r_[2 + k] - centre[k]) * 1e3 for k in range(3)] for r_ in rows]
        spread = max(max(d[k] for d in dev) - min(d[k] for d in dev) for k in range(3))
        return t_, dev, spread

    (_, t2), (t_nom, dev_nom, spread_nom), (t_new, dev_new, spread_new) = side_by_side(
        lambda: session([RUN, "--setp", hal, "--pre-ngc", g10, "--ngc", ngc, "--truth", TRUTH_BHEAD, "--machine",
                         MACHINE_BHEAD, "--plan", plan, "--out", run2, "--timeout", "300"]),
        lambda: pin_session("nominal", L),
        lambda: pin_session("written", new_pl))
    bound = 2 * kp1["dL"]["U"]
    check(spread_nom > 0.8 * dl_true * 1e3 * 2 * math.sin(math.radians(60)),
          "maxkins at the nominal pivot-length: the ball's offset from the tip varies by %.3f um over the poses "
          "(dL sin B, B -60 .. 60)" % spread_nom)
    check(spread_new <= bound, "maxkins at the written pivot-length: the offset is the same at every pose within %.3f um "
          "(bound 2 U of dL, %.3f um); left: %s um (the Z reference's -dL)"
          % (spread_new, bound, ["%.3f" % v for v in dev_new[0]]))
    with open(os.path.join(run2, "params.hal")) as f:
        p2 = f.read()
    check("not loaded in this session (maxkins: identity kinematics run instead), not applied: setp maxkins.pivot-length"
          in p2, "the cycle's session (trivkins) does not load maxkins: the pin's line is kept, not applied")
    with open(os.path.join(run2, "driver_status.json")) as f:
        g54 = json.load(f)["g5x_offset_after"][0]
    check(all(abs(g54["XYZABC".index(k)] - v) < 1e-9 for k, v in want_g54.items()),
          "LinuxCNC's G54 after the offsets program %s = the G10 line %s" % (g54[:6], want_g54))
    lat2 = lateness(work, run2, plan, offsets=g10, cycle="one_sphere", points=len(pl["points"]),
                    across_um=ROUNDING_ACROSS_3D_UM, machine=MACHINE_BHEAD)
    rep2 = os.path.join(work, "report2.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run2, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep2])
    _, kp2 = kinematic_parameters(rep2)
    rows = {}
    for name, w in want.items():
        expect = 0.0 if name in BHEAD_WORK_OFFSET else w
        d, U = kp2[name]["value"] - expect, kp2[name]["U"]
        tol = LENGTH_TOL_UM if name in BHEAD_LENGTHS else ANGLE_TOL_MDEG
        what = ("within its U of zero (the work offset holds it)" if name in BHEAD_WORK_OFFSET else
                "unchanged (the pin not loaded in identity kinematics)" if name == "dL" else
                "unchanged (not held: reported, named above)")
        check(abs(d) <= U and abs(d) <= tol, "after_offsets: %-5s %9.4f %s, expected %9.4f: diff %+8.4f, U %.4f (tol %g) %s"
              % (name, kp2[name]["value"], kp2[name]["unit"], expect, d, U, tol, what))
        rows[name] = {"value": kp2[name]["value"], "U": U, "expected": expect}
    return {"run2_s": t2, "lateness2": lat2, "pins": pins, "g54": want_g54, "after_offsets": rows,
            "pin_acting": {"nominal": {"session_s": t_nom, "dev_um": dev_nom, "spread_um": spread_nom},
                           "written": {"session_s": t_new, "dev_um": dev_new, "spread_um": spread_new}}}


def kins_readback_5axis(a, work):
    """5axiskins' conventions (the bridge mill: a C head carrying a B head over a fixed table), read
    back from the running module in its TCP kinematics (run.sh --kins-tcp: its type 0 without
    sparm=identityfirst), a session of its own for each of two pivot lengths (run.sh --params: the
    harness's nominal head, no truth), beside the one_sphere_5axis cycle's session. The
    program moves the tip to table points at B and C and LOGs the joints and the probe's ball.
    Checks: the joints are tip - (0, 0, L) - Rz(+C) Ry(-B) (0, 0, -L) (5axiskins' source:
    s2r(L, C, 180 - B) = L (sin B cos C, sin B sin C, -cos B); the C head carries the B head, B
    against ISO 841's head, joint 2 reading the tip at B = 0); every other sign, order or Z
    candidate is far off; the probe's nominal head (two lines through one pivot) puts the ball on
    the commanded tip."""
    rows = [(0.0, 0.0, [0.0, 0.0, 0.0]), (30.0, 45.0, [10.0, 20.0, 30.0]), (-45.0, 120.0, [40.0, -70.0, 25.0]),
            (60.0, -30.0, [-50.0, 30.0, 60.0]), (90.0, 200.0, [5.0, 5.0, 5.0]), (-100.0, 10.0, [100.0, -50.0, 0.0]),
            (15.0, -170.0, [0.0, 0.0, 100.0])]
    out = {}
    for tag, L in (("pivot_250", 250.0), ("pivot_173.5", 173.5)):
        params = os.path.join(work, "params_%s.json" % tag)
        with open(params, "w") as f:
            json.dump({"_comment": "the bridge mill's nominal head (5axiskins' read-back): C head about +Z, B head "
                       "about -Y, through one pivot L above the joints' point",
                       "machine": {"kins": "5axis"}, "block": {"enable": False},
                       "head": {"enable": True, "axis": "CB", "pivot_to_ball": L, "sign": -1.0, "c_sign": 1.0,
                                "carriage_reads_ball": True}}, f)
        ngc = os.path.join(work, "kins_readback_%s.ngc" % tag)
        with open(ngc, "w") as f:
            f.write("(rotacal e2e: 5axiskins read-back, its TCP kinematics; row: i B C x y z, the joints 0..5,"
                    " the probe's ball)\nG21 G17 G40 G49 G54 G61 G90 G94\n"
                    "(LOGOPEN,kins_readback.txt)\n(LOG,K #<_hal[5axiskins.pivot-length]> "
                    "#<_hal[motion.switchkins-type]>)\n")
            for i, (b, c, p) in enumerate(rows):
                f.write(("G0 X%.6f Y%.6f Z%.6f B%.6f C%.6f W0\nM66 E0 L0\n" + SETTLE) % (p[0], p[1], p[2], b, c))
                f.write("(LOG,R %d %.6f %.6f %.6f %.6f %.6f)\n" % (i, b, c, p[0], p[1], p[2]))
                f.write("(LOG,J %d" % i + "".join(" #<_hal[joint.%d.pos-cmd]>" % j for j in range(6)) + ")\n")
                f.write("(LOG,T %d #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % i)
            f.write("G0 B0 C0\n(LOGCLOSE)\nM2\n")
        setp = os.path.join(work, "readback_%s.hal" % tag)
        with open(setp, "w") as f:
            f.write("setp 5axiskins.pivot-length %.12g\n" % L)
        _, t = session([RUN, "--ngc", ngc, "--params", params, "--kins-tcp", "--setp", setp,
                        "--out", os.path.join(work, "readback_" + tag), "--timeout", "300"])
        parts, pin, kt = {}, None, None
        with open(os.path.join(work, "readback_" + tag, "kins_readback.txt")) as f:
            for line in f:
                t_ = line.split()
                if len(t_) == 3 and t_[0] == "K":
                    pin, kt = float(t_[1]), float(t_[2])
                if len(t_) >= 2 and t_[0] in ("R", "J", "T"):
                    parts.setdefault(int(t_[1]), {})[t_[0]] = [float(x) for x in t_[2:]]
        check(pin is not None and abs(pin - L) < 1e-9 and kt == 0.0,
              "read-back (%s): 5axiskins.pivot-length = %s, motion.switchkins-type %s (0: TCP without the sparm)"
              % (tag, pin, kt))
        got = [[float(i)] + v["R"] + v["J"] + v["T"] for i, v in sorted(parts.items())
               if len(v.get("R", [])) == 5 and len(v.get("J", [])) == 6 and len(v.get("T", [])) == 3]
        check(len(got) == len(rows), "read-back (%s): %d rows of %d" % (tag, len(got), len(rows)))

        def cand(order, sb, sc, tip_at_b0, b, c, p):
            v = [0.0, 0.0, -L]
            v = rz_deg(sc * c, ry_deg(sb * b, v)) if order == "CB" else ry_deg(sb * b, rz_deg(sc * c, v))
            return [p[0] - v[0], p[1] - v[1], p[2] - v[2] - (L if tip_at_b0 else 0.0)]
        worst = {}
        for order in ("CB", "BC"):
            for sb in (1, -1):
                for sc in (1, -1):
                    for tip in (True, False):
                        worst[(order, sb, sc, tip)] = max(
                            max(abs(g[6 + k] - cand(order, sb, sc, tip, g[1], g[2], g[3:6])[k]) for k in range(3))
                            for g in got)
        key = ("CB", -1, 1, True)
        best = worst[key]
        others = min(v for k, v in worst.items() if k != key)
        check(best < 1e-6, "read-back (%s): joints = p - (0, 0, L) - Rz(+C) Ry(-B) (0, 0, -L) within %.1e mm (%d rows)"
              % (tag, best, len(got)))
        check(others > 1.0, "read-back (%s): every other order, sign or Z candidate is off by at least %.1f mm"
              % (tag, others))
        check(all(abs(g[9] - g[1]) < 1e-9 and abs(g[10] - g[2]) < 1e-9 and abs(g[11]) < 1e-9 for g in got),
              "read-back (%s): joints 3, 4 are the commanded B, C, joint 5 (W) stays 0" % tag)
        ball = max(max(abs(g[12 + k] - g[3 + k]) for k in range(3)) for g in got)
        check(ball < 1e-6, "read-back (%s): the probe's nominal head puts the ball on the commanded tip within %.1e mm"
              % (tag, ball))
        out[tag] = {"rows": len(got), "session_s": t, "pivot_length_mm": L, "max_dev_mm": best,
                    "other_candidates_min_mm": others, "probe_ball_dev_mm": ball}
    return out


MACHINE_5AXIS = os.path.join(HERE, "cb_head_lcsim.json")
TRUTH_5AXIS = os.path.join(HERE, "truth_5axis.json")
# one_sphere's poses on the bridge mill: three B tilts x three C turns = 9 poses, 39 touches, as on the
# B head over the C table (the plan refuses a set that loses a separable direction).
ONE_SPHERE_5AXIS_SET = ["tilt_list=-60,0,60", "c_list=0,120,240"]
# What one sphere cannot separate on the C head carrying the B head, as rotacal computes it from the
# plan's Jacobian (REPORT.json unseparable): the head's place X0C Y0C Z0B (with the sphere's set-up),
# C's tilt about B's direction C0B (with C's zero) and the ball's offset along X (with B's zero). The
# truth injects none of them.
FIVEAXIS_HELD = ["C0B", "X0C", "Y0C", "Z0B", "dX_T"]
FIVEAXIS_NAMES = ("A0C", "B0C", "C0C", "X0B", "A0B", "B0B", "dY_T", "dL", "dX_S", "dY_S", "dZ_S")
FIVEAXIS_LENGTHS = ("X0B", "dY_T", "dL", "dX_S", "dY_S", "dZ_S")
# What the work offset holds on 5axiskins' machine: the C and B zeros (G54 C, B); its pin, pivot-length,
# the stylus (dL), acting in its TCP type only; the places and tilts no pin or shift.
FIVEAXIS_WORK_OFFSET = ("C0C", "B0B")
SIGN_5AXIS = {"B": -1, "C": 1}   # cb_head_lcsim.json's linuxcnc signs, read back by the case


def injected_5axis(truth=TRUTH_5AXIS):
    """The bridge mill's truth in um / mdeg (missing = 0)."""
    with open(truth) as f:
        le = json.load(f)["location_errors"]
    out = {}
    for name in FIVEAXIS_NAMES:
        length = name in FIVEAXIS_LENGTHS
        e = le.get(name, {"value": 0.0, "unit": "um" if length else "mdeg"})
        out[name] = e["value"] * (TO_UM if length else TO_MDEG)[e["unit"]]
    return out


def run_one_sphere_5axis(a):
    """The bridge mill (cb_head_lcsim.json) on 5axiskins: its conventions read back in its TCP type (two
    short sessions) beside the one_sphere cycle in its identity type, the probe on the head playing
    truth_5axis.json (rotacal's head_cb parameters); analyze; then the write-back closed on the
    controller (write_back_5axis)."""
    work = a.work
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "one_sphere.ngc")
    cmd = [a.rotacal, "plan", "--cycle", "one_sphere", "--machine", MACHINE_5AXIS, "-o", plan]
    for kv in ONE_SPHERE_5AXIS_SET:
        cmd += ["--set", kv]
    sh(cmd)
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    with open(plan) as f:
        n_points = len(json.load(f)["points"])
    run = os.path.join(work, "run")
    readback_dir = os.path.join(work, "readback")
    os.makedirs(readback_dir, exist_ok=True)
    readback, (_, t) = side_by_side(
        lambda: kins_readback_5axis(a, readback_dir),
        lambda: session([RUN, "--ngc", ngc, "--truth", TRUTH_5AXIS, "--machine", MACHINE_5AXIS, "--plan", plan,
                         "--out", run, "--timeout", "300"]))
    figures = {"readback": readback, "run_s": t}
    figures["lateness"] = lateness(work, run, plan, cycle="one_sphere", points=n_points,
                                   across_um=ROUNDING_ACROSS_3D_UM, machine=MACHINE_5AXIS)
    rep = os.path.join(work, "report.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep])
    r, kp = kinematic_parameters(rep)
    held = sorted(u["held"] for u in r.get("unseparable", []))
    check(held == FIVEAXIS_HELD, "the report holds exactly %s at nominal (unseparable, from the plan's Jacobian): %s"
          % (", ".join(FIVEAXIS_HELD), held))
    want = injected_5axis()
    print("one_sphere on LinuxCNC (C head carrying a B head, 5axiskins' identity type), injected head_cb errors "
          "(identified - expected):")
    for name, w in want.items():
        tol = LENGTH_TOL_UM if name in FIVEAXIS_LENGTHS else ANGLE_TOL_MDEG
        d, U = kp[name]["value"] - w, kp[name]["U"]
        check(abs(d) <= tol and abs(d) <= U, "%-5s identified %9.4f expected %9.4f diff %+8.4f %s, U %.4f (tol %g)"
              % (name, kp[name]["value"], w, d, kp[name]["unit"], U, tol))
    figures.update({"identified": {n: kp[n]["value"] for n in want}, "U": {n: kp[n]["U"] for n in want},
                    "injected": want, "unseparable": r.get("unseparable"), "points": n_points})
    figures.update(write_back_5axis(a, work, plan, ngc, rep, kp, want))
    with open(os.path.join(work, "figures.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print("one_sphere C head / B head on LinuxCNC (5axiskins): %d touches, LinuxCNC session %.0f s" % (n_points, t))


def write_back_5axis(a, work, plan, ngc, rep1, kp1, want):
    """The write-back closed on the controller. analyze --offsets writes 5axiskins' pin (offsets.hal:
    pivot-length's previous value, change and new value; the rest named with its route) and the work
    offset (offsets.ngc: G54 B and C). LinuxCNC is started again with both: the G54 program first
    (--pre-ngc), the pin's line in the session's HAL (--setp), and the unchanged cycle measures again:
    the C and B zeros within their U of zero, the rest as before. The cycle runs in 5axiskins' identity
    type: the module is loaded and its pin set, but the identity type does not read it, so dL comes
    back unchanged. Beside it, two short sessions in 5axiskins' TCP type with the stylus dL longer than
    nominal show the pin acting: the tip commanded at the plan's poses, the ball's offset from it
    varies with B and C at the nominal pin and is the same at every pose at the written one."""
    hal, g10 = os.path.join(work, "offsets.hal"), os.path.join(work, "offsets.ngc")
    res1 = os.path.join(work, "run", "rotacal_one_sphere.txt")
    for out in (hal, g10):
        if os.path.exists(out):
            os.remove(out)       # the loop starts from the nominal pin and G54 = 0 (a file present is added to)
        sh([a.rotacal, "analyze", "--plan", plan, "--results", res1, "--dialect", "linuxcnc", "--json",
            os.path.join(work, "report_offsets.json"), "--offsets", out])
    with open(plan) as f:
        pl = json.load(f)
    L = pl["machine"]["head"]["pivot_to_ball_mm"]
    with open(hal) as f:
        hal_text = f.read()
    print(hal_text)
    pins = {}
    for line in hal_text.splitlines():
        t_ = line.split()
        if len(t_) == 3 and t_[0] == "setp" and t_[1].startswith("5axiskins."):
            pins[t_[1].split(".", 1)[1]] = float(t_[2])
    check(sorted(pins) == ["pivot-length"], "offsets.hal sets 5axiskins' pivot-length only: %s" % sorted(pins))
    new_pl = pins.get("pivot-length", float("nan"))
    check(abs(new_pl - (L + kp1["dL"]["value"] * 1e-3)) <= 1e-6,
          "pivot-length = previous (MACHINE.json's L = %g mm) + the identified dL (%.4f um): %.6f mm"
          % (L, kp1["dL"]["value"], new_pl))
    check(any(l.split()[1:] == ["pin", "previous", "change", "new"] for l in hal_text.splitlines() if l.startswith("# ")),
          "offsets.hal gives the pin's previous value, change and new value")
    check("Reported only: A0C, B0C, X0B, A0B, dY_T:" in hal_text and "mechanical adjustment" in hal_text,
          "offsets.hal names what 5axiskins cannot hold (A0C, B0C, X0B, A0B, dY_T) and the route")
    check("B and C zeros (B0B, C0C)" in hal_text and "work offset holds them" in hal_text,
          "offsets.hal sends the B and C zeros to the work offset")
    with open(g10) as f:
        g10_text = f.read()
    print(g10_text)
    g10_line = [l for l in g10_text.splitlines() if l.startswith("G10 L2 P1")][0].split()[3:]
    want_g54 = {w[0]: float(w[1:]) for w in g10_line}
    # commanding the axis at program + offset, the head at the nominal angle: offset = -zero in the papers'
    # count, times the controller's sign (B -1, C +1: read back above)
    expect_g54 = {"B": -SIGN_5AXIS["B"] * kp1["B0B"]["value"] * 1e-3,
                  "C": -SIGN_5AXIS["C"] * kp1["C0C"]["value"] * 1e-3}
    check(sorted(want_g54) == ["B", "C"] and all(abs(want_g54[k] - v) <= 0.5e-6 for k, v in expect_g54.items()),
          "offsets.ngc shifts G54 B by +B0B and C by -C0C (5axiskins' counts): %s" % want_g54)
    check("dL: 5axiskins.pivot-length [a .hal file]" in g10_text, "offsets.ngc sends dL to the pin's .hal file")
    # rotacal compensate rewrites table machines' programs: it refuses the head, naming why
    r, _ = sh([a.rotacal, "compensate", "--program", ngc, "--report", rep1, "--dialect", "linuxcnc", "-o",
               os.path.join(work, "one_sphere_compensated.ngc")], expect=None)
    check(r.returncode == 1 and "head_cb" in r.stdout, "rotacal compensate refuses the head_cb report with its "
          "reason (exit %d)" % r.returncode)
    run2 = os.path.join(work, "run2")
    dl_true = want["dL"] * 1e-3
    centre = pl["points"][0]["sphere"]["center_w_mm"]

    def pin_session(tag, pivot_length):
        # 5axiskins' TCP type, the carriage reading the tip at B = 0 for the nominal L (the pivot L above the
        # joints' point), the true stylus dL longer (head_cb: dL alone), the tip at the sphere's centre
        params = os.path.join(work, "pin_params_%s.json" % tag)
        with open(params, "w") as f:
            json.dump({"_comment": "5axiskins' pin acting: the nominal bridge mill, the stylus dL longer",
                       "machine": {"kins": "5axis"}, "block": {"enable": False},
                       "head": {"enable": True, "axis": "CB", "pivot_to_ball": L, "sign": float(SIGN_5AXIS["B"]),
                                "c_sign": float(SIGN_5AXIS["C"]), "carriage_reads_ball": True},
                       "head_cb": {"dL_um": dl_true * 1e3}}, f)
        prog = os.path.join(work, "pin_%s.ngc" % tag)
        with open(prog, "w") as f:
            f.write("(rotacal e2e: 5axiskins' pivot-length acting; row: i B C, the probe's ball)\n"
                    "G21 G17 G40 G49 G54 G61 G90 G94\n(LOGOPEN,pin.txt)\n")
            for i, pose in enumerate(pl["poses"]):
                b, c = SIGN_5AXIS["B"] * pose["pose"]["B"], SIGN_5AXIS["C"] * pose["pose"]["C"]
                f.write(("G0 X%.6f Y%.6f Z%.6f B%.6f C%.6f W0\nM66 E0 L0\n" + SETTLE) % (centre[0], centre[1], centre[2], b, c))
                f.write("(LOG,T %d %.6f %.6f #<_hal[vtouchprobe.0.ball-tx]> #<_hal[vtouchprobe.0.ball-ty]> "
                        "#<_hal[vtouchprobe.0.ball-tz]>)\n" % (i, b, c))
            f.write("G0 B0 C0\n(LOGCLOSE)\nM2\n")
        setp = os.path.join(work, "pin_%s.hal" % tag)
        with open(setp, "w") as f:
            f.write("setp 5axiskins.pivot-length %.12g\n" % pivot_length)
        out_dir = os.path.join(work, "pin_" + tag)
        _, t_ = session([RUN, "--ngc", prog, "--params", params, "--kins-tcp", "--setp", setp, "--out", out_dir,
                         "--timeout", "300"])
        rows = []
        with open(os.path.join(out_dir, "pin.txt")) as f:
            for line in f:
                t = line.split()
                if len(t) == 7 and t[0] == "T":
                    rows.append([float(v) for v in t[2:]])
        check(len(rows) == len(pl["poses"]), "pin session (%s): %d rows" % (tag, len(rows)))
        dev = [[(r_[2 + k] - centre[k]) * 1e3 for k in range(3)] for r_ in rows]
        spread = max(max(d[k] for d in dev) - min(d[k] for d in dev) for k in range(3))
        return t_, dev, spread

    (_, t2), (t_nom, dev_nom, spread_nom), (t_new, dev_new, spread_new) = side_by_side(
        lambda: session([RUN, "--setp", hal, "--pre-ngc", g10, "--ngc", ngc, "--truth", TRUTH_5AXIS, "--machine",
                         MACHINE_5AXIS, "--plan", plan, "--out", run2, "--timeout", "300"]),
        lambda: pin_session("nominal", L),
        lambda: pin_session("written", new_pl))
    bound = 2 * kp1["dL"]["U"]
    # at the nominal pin the ball sits dL further along the spindle: dL Rz(C) Ry(B) (0, 0, -1), whose X
    # spreads by dL (sin 60 - sin -60) over the plan's B -60 .. 60 at C = 0
    check(spread_nom > 0.8 * dl_true * 1e3 * 2 * math.sin(math.radians(60)),
          "5axiskins at the nominal pivot-length: the ball's offset from the tip varies by %.3f um over the poses "
          "(dL along the spindle, B -60 .. 60)" % spread_nom)
    check(spread_new <= bound, "5axiskins at the written pivot-length: the offset is the same at every pose within "
          "%.3f um (bound 2 U of dL, %.3f um); left: %s um (the Z reference's -dL)"
          % (spread_new, bound, ["%.3f" % v for v in dev_new[0]]))
    with open(os.path.join(run2, "params.hal")) as f:
        p2 = f.read()
    check(("setp 5axiskins.pivot-length %.6f" % new_pl) in p2,
          "the cycle's session loads 5axiskins (identity type) and sets the written pivot-length %.6f mm" % new_pl)
    with open(os.path.join(run2, "driver_status.json")) as f:
        g54 = json.load(f)["g5x_offset_after"][0]
    axes = "XYZBCW"   # 5axiskins' coordinates (lcsim_5axis.ini): the status' 9 slots are X Y Z A B C U V W
    check(all(abs(g54["XYZABCUVW".index(k)] - v) < 1e-9 for k, v in want_g54.items())
          and all(abs(g54["XYZABCUVW".index(k)]) < 1e-12 for k in axes if k not in want_g54),
          "LinuxCNC's G54 after the offsets program %s = the G10 line %s" % (g54[:9], want_g54))
    lat2 = lateness(work, run2, plan, offsets=g10, cycle="one_sphere", points=len(pl["points"]),
                    across_um=ROUNDING_ACROSS_3D_UM, machine=MACHINE_5AXIS)
    rep2 = os.path.join(work, "report2.json")
    sh([a.rotacal, "analyze", "--plan", plan, "--results", os.path.join(run2, "rotacal_one_sphere.txt"),
        "--dialect", "linuxcnc", "--json", rep2])
    _, kp2 = kinematic_parameters(rep2)
    rows = {}
    for name, w in want.items():
        expect = 0.0 if name in FIVEAXIS_WORK_OFFSET else w
        d, U = kp2[name]["value"] - expect, kp2[name]["U"]
        tol = LENGTH_TOL_UM if name in FIVEAXIS_LENGTHS else ANGLE_TOL_MDEG
        what = ("within its U of zero (the work offset holds it)" if name in FIVEAXIS_WORK_OFFSET else
                "unchanged (the pin set, but not read by the identity type)" if name == "dL" else
                "unchanged (not held: reported, named above)")
        check(abs(d) <= U and abs(d) <= tol, "after_offsets: %-5s %9.4f %s, expected %9.4f: diff %+8.4f, U %.4f (tol %g) %s"
              % (name, kp2[name]["value"], kp2[name]["unit"], expect, d, U, tol, what))
        rows[name] = {"value": kp2[name]["value"], "U": U, "expected": expect}
    return {"run2_s": t2, "lateness2": lat2, "pins": pins, "g54": want_g54, "after_offsets": rows,
            "pin_acting": {"nominal": {"session_s": t_nom, "dev_um": dev_nom, "spread_um": spread_nom},
                           "written": {"session_s": t_new, "dev_um": dev_new, "spread_um": spread_new}}}


def run_no_trigger(a):
    work = a.work
    plan, ngc = os.path.join(work, "plan.json"), os.path.join(work, "touch154.ngc")
    sh([a.rotacal, "plan", "--cycle", "touch154", "--machine", MACHINE, "-o", plan])
    sh([a.rotacal, "generate", "--plan", plan, "--dialect", "linuxcnc", "-o", ngc])
    run = os.path.join(work, "run")
    r, _ = sh([RUN, "--ngc", ngc, "--truth", AWAY, "--machine", MACHINE, "--out", run, "--timeout", "300"],
              expect=None)
    check(r.returncode == 1, "run.sh reports a program error (exit %d, expected 1)" % r.returncode)
    with open(os.path.join(run, "driver_status.json")) as f:
        status = json.load(f)
    msg = "rotacal: point 1 did not trigger"
    check(any(e.strip() == msg for e in status["errors"]),
          "the controller stopped with rotacal's own message %r (errors: %s)" % (msg, status["errors"]))
    res = os.path.join(run, "rotacal_touch154.txt")
    lines = [l for l in open(res).read().split("\n") if l.strip()] if os.path.exists(res) else []
    # the program opened its LOG (so it did run) and stopped before recording anything
    check(len(lines) == 1 and lines[0].startswith("rotacal-results/1 "),
          "the results file holds the header and no point (%s: %s)" % (res, lines))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("case", choices=("touch154", "no_trigger", "comp_table", "one_sphere_bc", "one_sphere_ac",
                                     "one_sphere_ab", "one_sphere_bhead", "one_sphere_5axis"))
    ap.add_argument("--rotacal", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    why = skip_reason()
    if why:
        print("SKIP: " + why)
        sys.exit(77)
    os.makedirs(a.work, exist_ok=True)
    {"touch154": run_touch154, "no_trigger": run_no_trigger, "comp_table": run_comp_table,
     "one_sphere_bc": run_one_sphere_bc, "one_sphere_ac": run_one_sphere_ac, "one_sphere_ab": run_one_sphere_ab,
     "one_sphere_bhead": run_one_sphere_bhead,
     "one_sphere_5axis": run_one_sphere_5axis}[a.case](a)
    finish()


if __name__ == "__main__":
    main()
