#!/usr/bin/python3
"""Self-check of the harness geometry (lcsim_geom.py), no LinuxCNC needed (CTest
e2e_harness_geometry, not label e2e):

* the probe's line form of the true table (what vtouchprobe.comp evaluates: lines pA/uA, pC/uC and
  the artefact placed by true_artefact) equals the papers' chain term by term, for the A/C table
  (000 Eq. (1), "eq1", with the angle harmonics switched off), the B/C table (002 Eq. (2), "eq2") and
  the A/B table (rotacal's chain, "eq3"),
  over random poses and points with 1000 x realistic errors;
* the nominal forward kinematics invert the nominal inverse (xyzac and xyzbc, with a rot-point and
  pivot offsets), and with R = D = 0 the B/C table is p_m = Ry(+B) Rz(+C) p_w (what the read-back of
  e2e_linuxcnc_one_sphere_bc measures on the controller);
* the head mode (maxkins' B head over a C table, "max"): the probe's head and table lines against
  rotacal's head_table chains written as 4x4 matrices (300 random poses, 1000 x realistic errors),
  maxkins' nominal inverse against the probe's nominal head, and with --rotacal BIN every trigger of
  `rotacal simulate` on truth_bhead.json against the harness's true contact;
* the head mode on the bridge mill (5axiskins' C head carrying a B head, "5axis"): the probe's two
  head lines against rotacal's head_cb chain written as 4x4 matrices (300 random poses, 1000 x
  realistic errors), and with --rotacal BIN every trigger of `rotacal simulate` on truth_5axis.json
  against the harness's true contact;
* the stem's signed distance at a few points of known answer.
Exit 0 pass, 1 fail.
"""
import argparse
import json
import math
import os
import random
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcsim_geom as G  # noqa: E402
from checks import check, finish  # noqa: E402


def params(d):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(d, f)
    try:
        return G.load_params(f.name)
    finally:
        os.remove(f.name)


HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEAD_ERRORS = {"X0C_um": 12400, "Y0C_um": -8600, "A0C_mdeg": 24000, "B0C_mdeg": -31000, "C0C_mdeg": 15000,
               "X0B_um": 9100, "Z0B_um": -7700, "A0B_mdeg": 18000, "C0B_mdeg": -27000, "B0B_mdeg": 21000,
               "dX_T_um": 5300, "dY_T_um": -4100, "dL_um": 15300, "dX_S_um": 9700, "dY_S_um": -6200,
               "dZ_S_um": 11500}


def htm(rot=None, axis=None, t=(0.0, 0.0, 0.0)):
    """A 4x4 homogeneous transform: a rotation by rot (rad) about axis 'x', 'y' or 'z', or a translation t."""
    m = [[1.0, 0.0, 0.0, t[0]], [0.0, 1.0, 0.0, t[1]], [0.0, 0.0, 1.0, t[2]], [0.0, 0.0, 0.0, 1.0]]
    if rot is not None:
        c, s_ = math.cos(rot), math.sin(rot)
        i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
        m[i][i], m[i][j], m[j][i], m[j][j] = c, -s_, s_, c
    return m


def mul(*ms):
    out = ms[0]
    for m in ms[1:]:
        out = [[sum(out[i][k] * m[k][j] for k in range(4)) for j in range(4)] for i in range(4)]
    return out


def apply(m, v):
    return [m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] + m[i][3] for i in range(3)]


def head_by_htm(e, L, B_star, C_star, pw):
    """rotacal's head_table chains as 4x4 matrices written out here (core/kinematic_model.hpp's
    factors, not lcsim_geom's rotations): the ball's offset from the carriage and the sphere point,
    machine frame, at the papers' angles."""
    mm = lambda n: e[n + "_um"] * 1e-6 * 1e3   # noqa: E731 (um -> mm)
    rad = lambda n: e[n + "_mdeg"] * 1e-3 * math.pi / 180.0   # noqa: E731
    head = mul(htm(t=(mm("X0B"), 0, 0)), htm(t=(0, 0, mm("Z0B"))), htm(rad("A0B"), "x"), htm(rad("C0B"), "z"),
               htm(rad("B0B"), "y"), htm(math.radians(B_star), "y"), htm(t=(mm("dX_T"), 0, 0)),
               htm(t=(0, mm("dY_T"), 0)), htm(t=(0, 0, -mm("dL"))))
    table = mul(htm(t=(mm("X0C"), 0, 0)), htm(t=(0, mm("Y0C"), 0)), htm(rad("A0C"), "x"), htm(rad("B0C"), "y"),
                htm(rad("C0C"), "z"), htm(-math.radians(C_star), "z"), htm(t=(mm("dX_S"), 0, 0)),
                htm(t=(0, mm("dY_S"), 0)), htm(t=(0, 0, mm("dZ_S"))))
    return apply(head, [0.0, 0.0, -L]), apply(table, pw)


def head_cb_by_htm(e, L, B_star, C_star, pw):
    """rotacal's head_cb chain as 4x4 matrices written out here (docs/conventions.md's factors, not
    lcsim_geom's rotations): the ball's offset from the carriage and the sphere point (the table
    stays), machine frame, at the papers' angles."""
    mm = lambda n: e[n + "_um"] * 1e-3   # noqa: E731 (um -> mm)
    rad = lambda n: e[n + "_mdeg"] * 1e-3 * math.pi / 180.0   # noqa: E731
    head = mul(htm(t=(mm("X0C"), 0, 0)), htm(t=(0, mm("Y0C"), 0)), htm(rad("A0C"), "x"), htm(rad("B0C"), "y"),
               htm(rad("C0C"), "z"), htm(math.radians(C_star), "z"), htm(t=(mm("X0B"), 0, 0)),
               htm(t=(0, 0, mm("Z0B"))), htm(rad("A0B"), "x"), htm(rad("C0B"), "z"), htm(rad("B0B"), "y"),
               htm(math.radians(B_star), "y"), htm(t=(mm("dX_T"), 0, 0)), htm(t=(0, mm("dY_T"), 0)),
               htm(t=(0, 0, -mm("dL"))))
    table = mul(htm(t=(mm("dX_S"), 0, 0)), htm(t=(0, mm("dY_S"), 0)), htm(t=(0, 0, mm("dZ_S"))))
    return apply(head, [0.0, 0.0, -L]), apply(table, pw)


def check_head_cb(rnd, rotacal):
    """The head mode on the bridge mill (5axiskins' C head carrying a B head, "5axis"): the probe's two
    head lines against rotacal's head_cb chain as hand-written matrices, then against `rotacal
    simulate`'s triggers."""
    L = 250.0
    hp = params({"machine": {"kins": "5axis"}, "block": {"enable": False},
                 "head": {"enable": True, "axis": "CB", "pivot_to_ball": L, "sign": -1.0, "c_sign": 1.0},
                 "head_cb": HEAD_ERRORS, "sphere": {"enable": True, "center": [0.0, 0.0, 0.0], "radius": 12.7}})
    worst, worst_chain = 0.0, 0.0
    for _ in range(300):
        b, c = rnd.uniform(-110, 110), rnd.uniform(-400, 400)
        pw = [rnd.uniform(-200, 200) for _ in range(3)]
        ball_off, sphere_m = head_cb_by_htm(HEAD_ERRORS, L, b, c, pw)
        carriage = G.sub(sphere_m, ball_off)          # where X Y Z put the ball on the point
        hp["sphere"]["center"] = pw
        art = G.true_artefact(hp)
        pt = G.true_table_point(carriage + [0.0, 0.0, c, -b], hp)   # joints: C = +C*, B = -B* (5axiskins)
        worst = max(worst, G.norm(G.sub(pt, art["sphere"]["center"])))
        ball_g, sphere_g = G.head_cb_chain(b, c, hp, pw, [0.0, 0.0, 0.0])
        worst_chain = max(worst_chain, G.norm(G.sub(ball_g, ball_off)), G.norm(G.sub(sphere_g, sphere_m)))
    check(worst < 1e-9, "head_cb (5axis): the probe's two head lines put the ball on the sphere point where rotacal's "
          "chain (4x4 matrices) does, within %.2g mm (300 poses, 1000 x the errors)" % worst)
    check(worst_chain < 1e-9, "head_cb (5axis): lcsim_geom's chain term by term = the matrices within %.2g mm"
          % worst_chain)
    if not rotacal:
        return
    # rotacal's own simulator on the case's machine and truth: every trigger puts the harness's true ball
    # on the true sphere
    import subprocess
    import lateness as LT
    with tempfile.TemporaryDirectory() as d:
        machine, truth = os.path.join(HERE, "cb_head_lcsim.json"), os.path.join(HERE, "truth_5axis.json")
        plan, res = os.path.join(d, "plan.json"), os.path.join(d, "sim.txt")
        for cmd in ([rotacal, "plan", "--cycle", "one_sphere", "--machine", machine, "--set", "tilt_list=-90,-45,0,45,90",
                     "--set", "c_list=0,72,144,216,288", "-o", plan],
                    [rotacal, "simulate", "--plan", plan, "--truth", truth, "--dialect", "linuxcnc", "-o", res]):
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        pj = os.path.join(d, "params.json")
        subprocess.run(["/usr/bin/python3", os.path.join(HERE, "scripts", "truth_params.py"), "--truth", truth,
                        "--machine", machine, "--plan", plan, "-o", pj], check=True)
        p = G.load_params(pj)
        with open(plan) as f:
            pl = json.load(f)
        got = LT.read_log(res)
        art = G.true_artefact(p)
        worst = 0.0
        for pt in pl["points"]:
            j = got[pt["id"]] + [0.0, 0.0, pt["pose"]["C"], -pt["pose"]["B"]]
            worst = max(worst, abs(G.clearance_table(G.true_table_point(j, p), art)))
        check(worst < 2e-6, "head_cb (5axis): at all %d triggers of rotacal simulate (truth_5axis.json) the harness's "
              "true ball touches the true sphere within %.2g mm (the LOG's 6 decimals)" % (len(pl["points"]), worst))


def check_head(rnd, rotacal):
    """The head mode (maxkins' B head over a C table): the probe's line form against rotacal's
    chains as hand-written matrices, then against `rotacal simulate`'s triggers."""
    L = 250.0
    hp = params({"machine": {"kins": "max"}, "head": {"enable": True, "pivot_to_ball": L, "sign": -1.0, "c_sign": 1.0},
                 "head_table": HEAD_ERRORS, "sphere": {"enable": True, "center": [0.0, 0.0, 0.0], "radius": 12.7}})
    worst, worst_chain = 0.0, 0.0
    for _ in range(300):
        b, c = rnd.uniform(-110, 110), rnd.uniform(-400, 400)
        pw = [rnd.uniform(-200, 200) for _ in range(3)]
        ball_off, sphere_m = head_by_htm(HEAD_ERRORS, L, b, c, pw)
        carriage = G.sub(sphere_m, ball_off)          # where X Y Z put the ball on the point
        hp["sphere"]["center"] = pw
        art = G.true_artefact(hp)
        pt = G.true_table_point(carriage + [0.0, c, -b], hp)   # joints: C = +C*, B = -B* (maxkins)
        worst = max(worst, G.norm(G.sub(pt, art["sphere"]["center"])))
        ball_g, sphere_g = G.head_table_chain(b, c, hp, pw, [0.0, 0.0, 0.0])
        worst_chain = max(worst_chain, G.norm(G.sub(ball_g, ball_off)), G.norm(G.sub(sphere_g, sphere_m)))
    check(worst < 1e-9, "head_table (max): the probe's head and table lines put the ball on the sphere point where "
          "rotacal's chains (4x4 matrices) do, within %.2g mm (300 poses, 1000 x the errors)" % worst)
    check(worst_chain < 1e-9, "head_table (max): lcsim_geom's chain term by term = the matrices within %.2g mm"
          % worst_chain)
    # maxkins' nominal inverse and the probe read back as in its own session: the carriage reads the tip at
    # B = 0 (the pivot L above the joints' point), no error: the ball lands on the commanded tip
    np_ = params({"machine": {"kins": "max"}, "head": {"enable": True, "pivot_to_ball": 173.5, "sign": -1.0,
                                                        "c_sign": 1.0, "carriage_reads_ball": True}})
    worst = 0.0
    for _ in range(100):
        b, c = rnd.uniform(-110, 110), rnd.uniform(-400, 400)
        w = [rnd.uniform(-200, 200) for _ in range(3)]
        j = G.maxkins_inverse(w, b, c, 173.5)
        worst = max(worst, G.norm(G.sub(G.true_table_point(j + [0.0, c, b], np_), w)))
    check(worst < 1e-9, "maxkins' inverse (con = -1) and the probe with the carriage reading the tip at B = 0: the ball "
          "at the commanded tip within %.2g mm" % worst)
    # the bridge mill's nominal head (two lines through one pivot, "5axis") against 5axiskins' source:
    # joints = tip - (0, 0, L) - s2r(L, C, 180 - B) = tip - (0, 0, L) - L (sin B cos C, sin B sin C, -cos B)
    p5 = params({"machine": {"kins": "5axis"}, "block": {"enable": False},
                 "head": {"enable": True, "axis": "CB", "pivot_to_ball": 173.5, "sign": -1.0, "c_sign": 1.0,
                          "carriage_reads_ball": True}})
    worst = 0.0
    for _ in range(100):
        b, c = rnd.uniform(-120, 120), rnd.uniform(-400, 400)
        w = [rnd.uniform(-200, 200) for _ in range(3)]
        sb, cb = math.sin(math.radians(b)), math.cos(math.radians(b))
        r = [173.5 * sb * math.cos(math.radians(c)), 173.5 * sb * math.sin(math.radians(c)), -173.5 * cb]
        j = [w[0] - r[0], w[1] - r[1], w[2] - 173.5 - r[2]]
        worst = max(worst, G.norm(G.sub(G.true_table_point(j + [0.0, 0.0, c, b], p5), w)))
    check(worst < 1e-9, "5axis: the probe's two head lines through one pivot (C carrying B) and 5axiskins' s2r form "
          "agree within %.2g mm" % worst)
    if not rotacal:
        print("note: no --rotacal: the head mode against rotacal simulate not checked")
        return
    # rotacal's own simulator (its truth file through the machine, never this script's chain): every
    # trigger it writes puts the harness's true ball on the true sphere, exactly (6 decimals in the LOG)
    import subprocess
    import lateness as LT
    with tempfile.TemporaryDirectory() as d:
        machine, truth = os.path.join(HERE, "bc_head_lcsim.json"), os.path.join(HERE, "truth_bhead.json")
        plan, res = os.path.join(d, "plan.json"), os.path.join(d, "sim.txt")
        for cmd in ([rotacal, "plan", "--cycle", "one_sphere", "--machine", machine, "--set", "tilt_list=-90,-45,0,45,90",
                     "--set", "c_list=0,72,144,216,288", "-o", plan],
                    [rotacal, "simulate", "--plan", plan, "--truth", truth, "--dialect", "linuxcnc", "-o", res]):
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        pj = os.path.join(d, "params.json")
        subprocess.run(["/usr/bin/python3", os.path.join(HERE, "scripts", "truth_params.py"), "--truth", truth,
                        "--machine", machine, "--plan", plan, "-o", pj], check=True)
        p = G.load_params(pj)
        with open(plan) as f:
            pl = json.load(f)
        got = LT.read_log(res)
        art = G.true_artefact(p)
        worst = 0.0
        for pt in pl["points"]:
            j = got[pt["id"]] + [0.0, pt["pose"]["C"], -pt["pose"]["B"]]
            worst = max(worst, abs(G.clearance_table(G.true_table_point(j, p), art)))
        check(worst < 2e-6, "head_table (max): at all %d triggers of rotacal simulate (truth_bhead.json) the harness's "
              "true ball touches the true sphere within %.2g mm (the LOG's 6 decimals)" % (len(pl["points"]), worst))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rotacal", help="the rotacal binary: the head mode against its simulator")
    a = ap.parse_args()
    rnd = random.Random(19)
    ac = params({"machine": {"kins": "xyzac", "y_offset": 0, "z_offset": 0},
                 "eq1": {"dx_AY_um": 14600, "dy_AY_um": 23200, "dz_AY_um": 27700, "dy_CA_um": 3900,
                         "a_AY_mdeg": -500, "b_AY_mdeg": -100, "c_AY_mdeg": -500, "b_CA_mdeg": 200}})
    bc = params({"machine": {"kins": "xyzbc", "z_offset": 0},
                 "eq2": {"dx_BY_um": 12400, "dy_CB_um": -8600, "dz_BY_um": -15300, "dx_CB_um": 9700,
                         "a_BY_mdeg": 24000, "b_BY_mdeg": -31000, "c_BY_mdeg": 18000, "a_CB_mdeg": -27000}})
    ab = params({"machine": {"kins": "xyzab", "z_offset": 0},
                 "eq3": {"dx_BY_um": 12400, "dy_AB_um": -8600, "dz_BY_um": -15300, "dz_AB_um": 9700,
                         "a_BY_mdeg": 24000, "b_BY_mdeg": -31000, "c_BY_mdeg": 18000, "c_AB_mdeg": -27000}})
    for name, p, chain, parts in (("A/C eq1", ac, G.eq1_transform, lambda p: G._eq_parts(p, "eq1")),
                                  ("B/C eq2", bc, G.eq2_transform, lambda p: G._eq_parts(p, "eq2")),
                                  ("A/B eq3", ab, G.eq3_transform, lambda p: G._eq_parts(p, "eq3"))):
        R, _, _, Q, t0 = parts(p)
        worst = 0.0
        for _ in range(300):
            t, c = rnd.uniform(-120, 120), rnd.uniform(-400, 400)
            pw = [rnd.uniform(-300, 300) for _ in range(3)]
            pm = chain(t, c, p, pw)
            pt = G.true_table_point(pm + [t, c], p)
            worst = max(worst, G.norm(G.sub(pt, G.add(R, G.add(t0, Q(G.sub(pw, R)))))))
        check(worst < 1e-9, "%s: the probe's line form = the chain term by term within %.2g mm" % (name, worst))
    for kins, m in (("xyzac", {"x_rot_point": 5, "y_rot_point": -3, "z_rot_point": 7, "y_offset": 20, "z_offset": 10}),
                    ("xyzbc", {"x_rot_point": 5, "y_rot_point": -3, "z_rot_point": 7, "x_offset": 20, "z_offset": -15}),
                    ("xyzab", {"x_rot_point": 5, "y_rot_point": -3, "z_rot_point": 7, "x_offset": 20, "z_offset": -15})):
        p = params({"machine": dict(m, kins=kins)})
        worst = 0.0
        for _ in range(100):
            t, c = rnd.uniform(-120, 120), rnd.uniform(-400, 400)
            pw = [rnd.uniform(-300, 300) for _ in range(3)]
            j = G.nominal_inverse(pw, t, c, p, tool_offset=1.5)
            worst = max(worst, G.norm(G.sub(G.nominal_forward(j + [t, c], p, tool_offset=1.5), pw)))
            worst = max(worst, G.norm(G.sub(G.true_table_point(j[:2] + [j[2] - 1.5, t, c], p), G.sub(pw, [0, 0, 1.5]))))
        check(worst < 1e-9, "%s: nominal forward o inverse, and the probe's nominal map, within %.2g mm" % (kins, worst))
    p0 = params({"machine": {"kins": "xyzbc", "z_offset": 0}})
    b, c, pw = 30.0, 45.0, [10.0, 20.0, 30.0]
    rz = G.rz(math.radians(c), pw)
    want = G.ry(math.radians(b), rz)
    check(G.norm(G.sub(G.nominal_inverse(pw, b, c, p0), want)) < 1e-12, "xyzbc at R = D = 0: p_m = Ry(+B) Rz(+C) p_w")
    # xyzab_tdr_kins' own inverse, as written in its source (type 1, R = D = 0): j = Ry(-B) Rx(-A) p
    pa = params({"machine": {"kins": "xyzab", "z_offset": 0}})
    a_, b_ = 25.0, -40.0
    want = G.ry(math.radians(-b_), G.rx(math.radians(-a_), pw))
    check(G.norm(G.sub(G.nominal_inverse(pw, b_, a_, pa), want)) < 1e-12, "xyzab at R = D = 0: p_m = Ry(-B) Rx(-A) p_w")
    check_head(rnd, a.rotacal)
    check_head_cb(rnd, a.rotacal)
    s = {"center": [0.0, 0.0, 0.0], "stem_u": [0.0, 0.0, -1.0], "stem_length": 60.0, "stem_radius": 4.0}
    for pt, want in (([10.0, 0.0, -30.0], 6.0), ([0.0, 0.0, -70.0], 10.0), ([3.0, 0.0, -30.0], -1.0),
                     ([0.0, 0.0, 5.0], 5.0), ([7.0, 0.0, -64.0], 5.0)):
        got = G.stem_distance(pt, s)
        check(abs(got - want) < 1e-12, "stem distance at %s: %g (expected %g)" % (pt, got, want))
    finish()


if __name__ == "__main__":
    main()
