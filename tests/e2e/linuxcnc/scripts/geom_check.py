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
* the stem's signed distance at a few points of known answer.
Exit 0 pass, 1 fail.
"""
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


def main():
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
    s = {"center": [0.0, 0.0, 0.0], "stem_u": [0.0, 0.0, -1.0], "stem_length": 60.0, "stem_radius": 4.0}
    for pt, want in (([10.0, 0.0, -30.0], 6.0), ([0.0, 0.0, -70.0], 10.0), ([3.0, 0.0, -30.0], -1.0),
                     ([0.0, 0.0, 5.0], 5.0), ([7.0, 0.0, -64.0], 5.0)):
        got = G.stem_distance(pt, s)
        check(abs(got - want) < 1e-12, "stem distance at %s: %g (expected %g)" % (pt, got, want))
    finish()


if __name__ == "__main__":
    main()
