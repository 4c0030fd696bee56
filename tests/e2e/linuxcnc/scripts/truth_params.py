#!/usr/bin/python3
"""rotacal TRUTH.json + MACHINE.json -> the harness's params.json (the true machine the
virtual probe plays, the nominal kinematics LinuxCNC believes).

Usage: truth_params.py --truth TRUTH.json --machine MACHINE.json [--plan PLAN.json] -o params.json

The mapping (docs/e2e-linuxcnc.md, "Truth -> component"):

* location_errors: rotacal's Eq. (1) of 000 (docs/conventions.md)
      T_m_w = Dx(dx_AY) Dy(dy_AY) Dz(dz_AY) Da(a_AY) Db(b_AY) Dc(c_AY) Da(-A*) Dy(dy_CA) Db(b_CA) Dc(-C*)
  with A*, C* the papers' angles, is the harness's "eq1" chain term by term, with the same
  names and signs, because the harness evaluates it at A* = -A, C* = -C of the joint angles,
  and rotacal's LinuxCNC programs command A = -A*, C = -C* (machine file dialect_sign -1,
  which this script therefore requires). Values are converted to um and mdeg.
* setup_error: the piece's rigid setup error of core/artefact.hpp (rotation Rz Ry Rx about the
  nominal top centre, then translation, workpiece frame) is the block's pose: centre
  top + R (centre0 - top) + t and roll-pitch-yaw = (rx, ry, rz), which is the component's
  Rz*Ry*Rx.
* probe ball: radius = ball_diameter_mm / 2, tool length 0 (the programs control the ball
  centre), pretravel from probe_pretravel_um.
* c_angular_positioning_error (harness only, not a rotacal truth field): the C axis' angular
  positioning error E_CC of ISO 230-7 in the papers' convention, as first and second harmonics
  {"unit": "mdeg", "ECC_cos1C": .., "ECC_sin1C": .., "ECC_cos2C": .., "ECC_sin2C": ..}. E_CC turns
  the table about +Z; the component's true C angle is c + dc(c) with c the joint angle, and
  c = -C*, so dc(c) = E_CC(-c): C_e1c = cos1, C_e1s = -sin1, C_e2c = cos2, C_e2s = -sin2 (deg).
  It combines with the A/C location errors: they place the true C axis line, E_CC turns the
  table about it (lcsim_geom: "eq1" with the angle harmonics).
* B/C table (machine "kinematics": "table_bc", LinuxCNC's xyzbc-trt-kins: p_m = Ry(+B) Rz(+C) p_w,
  docs/e2e-linuxcnc.md): rotacal's 002 Eq. (2) (docs/conventions.md)
      T_m_w = Da(a_BY) Db(b_BY) Dc(c_BY) Dx(dx_BY) Dy(dy_CB) Dz(dz_BY) Db(-B*) Da(a_CB) Dx(dx_CB) Dc(-C*)
  is the harness's "eq2" chain term by term, same names and signs, evaluated at B* = -B, C* = -C
  (dialect_sign -1 for B and C, required). A B/C machine needs no test piece: without an
  artefact the block is off and the plan's sphere is the piece.
* A/B table (machine "kinematics": "table_ab", LinuxCNC's xyzab_tdr_kins, type 1:
  p_m = Ry(-B) Rx(-A) p_w at R = D = 0, docs/e2e-linuxcnc.md): rotacal's A/B chain
  (docs/conventions.md)
      T_m_w = Da(a_BY) Db(b_BY) Dc(c_BY) Dx(dx_BY) Dy(dy_AB) Dz(dz_BY) Db(-B*) Dz(dz_AB) Dc(c_AB) Da(-A*)
  is the harness's "eq3" chain term by term, same names and signs, evaluated at B* = +B, A* = +A
  (dialect_sign +1 for A and B, required: the module counts as rotacal does). No test piece.
* B head over a C table (machine "kinematics": "head_table" with "head": {"axis": "B",
  "pivot_to_ball_mm": L}; LinuxCNC's maxkins, whose joints the cycle commands in identity kinematics):
  the truth's "location_errors" are rotacal's head_table parameters by their ISO 230-7 names
  (X0C Y0C A0C B0C C0C X0B Z0B A0B C0B B0B dX_T dY_T dL dX_S dY_S dZ_S, core/kinematic_model.hpp),
  the harness's "head_table" section, same names and signs, evaluated exactly (lcsim_geom) at
  B* = sign_B x B, C* = sign_C x C of the joint angles, the signs the machine file's linuxcnc ones
  (maxkins: B -1, C +1, read back by the e2e case). The probe rides on the head, the ball L from
  the pivot that X Y Z read. No test piece.
* C head carrying a B head over a fixed table (machine "kinematics": "head_cb" with "head":
  {"pivot_to_ball_mm": L}; LinuxCNC's 5axiskins bridge mill, the cycle in its identity type): the
  truth's "location_errors" are rotacal's head_cb parameters by their ISO 230-7 names (the same
  sixteen as head_table's, docs/conventions.md's head_cb chain), the harness's "head_cb" section,
  same names and signs, evaluated exactly (lcsim_geom) at B* = sign_B x B, C* = sign_C x C of the
  joint angles, the machine file's linuxcnc signs (5axiskins: B -1, C +1, read back by the e2e
  case). The table stays; no test piece.
* form_error, probe_noise_um and drifts are not modelled by the component: refused.
* --plan: a sphere cycle's plan (spheres3, one_sphere) puts its spheres (ids 1..3: the
  component's sphere, sphere2, sphere3) at the plan's nominal centres and radius, workpiece frame,
  placed on the true table like the block; one_sphere's sphere stands on its stem (the plan's
  options stem_length_mm, stem_diameter_mm; along the table's -Z). The block stays: a path that
  strayed into the test piece (or the stem) trips the probe and stops the program.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcsim_geom as G  # noqa: E402

LENGTH = {"um": 1.0, "mm": 1000.0}                       # -> um
ANGLE = {"mdeg": 1.0, "deg": 1000.0, "urad": 180.0 / math.pi * 1e-3}   # -> mdeg
NAMES = {"table_ac": ("dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"),
         "table_bc": ("dx_BY", "dy_CB", "dz_BY", "dx_CB", "a_BY", "b_BY", "c_BY", "a_CB"),
         "table_ab": ("dx_BY", "dy_AB", "dz_BY", "dz_AB", "a_BY", "b_BY", "c_BY", "c_AB")}
KINS = {"table_ac": ("xyzac", "eq1", "AC"), "table_bc": ("xyzbc", "eq2", "BC"), "table_ab": ("xyzab", "eq3", "AB"),
        "head_table": ("max", "head_table", "BC"), "head_cb": ("5axis", "head_cb", "BC")}
NAMES["head_table"] = G.HEAD_TABLE
NAMES["head_cb"] = G.HEAD_TABLE
# how each module counts the table's angles against rotacal's papers' convention
LINUXCNC_SIGN = {"table_ac": -1, "table_bc": -1, "table_ab": 1}
# maxkins: B against rotacal's head (its source: "the direction of the B axis is the opposite of the
# conventional axis direction"), C as rotacal's table; e2e_test.py reads both back
MAXKINS_SIGN = {"B": -1, "C": 1}
# 5axiskins: B against rotacal's head, C as rotacal's (e2e_test.py reads both back)
FIVEAXIS_SIGN = {"B": -1, "C": 1}
HEAD_SIGNS = {"head_table": ("maxkins", MAXKINS_SIGN), "head_cb": ("5axiskins", FIVEAXIS_SIGN)}
KNOWN_TRUTH_KEYS = {"format", "location_errors", "setup_error", "probe_pretravel_um", "form_error",
                    "probe_noise_um", "start_time_s", "c_angular_positioning_error"}
ECC_KEYS = {"ECC_cos1C": ("C_e1c", 1.0), "ECC_sin1C": ("C_e1s", -1.0), "ECC_cos2C": ("C_e2c", 1.0),
            "ECC_sin2C": ("C_e2s", -1.0)}


def fail(path, msg):
    raise SystemExit("truth_params.py: error: %s: %s" % (path, msg))


def spheres_from(plan, plan_path):
    """{key: sphere section} for the sphere targets of a plan (ids 1..3)."""
    out = {}
    keys = {1: "sphere", 2: "sphere2", 3: "sphere3"}
    for pt in plan.get("points", []):
        s = pt.get("sphere")
        if not s:
            continue
        if s["id"] not in keys:
            fail(plan_path, "the virtual probe models spheres 1..3, the plan has sphere %r" % s["id"])
        sec = {"enable": True, "center": [float(v) for v in s["center_w_mm"]], "radius": float(s["radius_mm"])}
        if s["id"] == 1 and "stem_length_mm" in plan.get("options", {}):
            o = plan["options"]
            sec.update(stem_length=float(o["stem_length_mm"]), stem_radius=float(o["stem_diameter_mm"]) / 2.0)
        old = out.setdefault(keys[s["id"]], sec)
        if old != sec:
            fail(plan_path, "sphere %d has two different centres or radii" % s["id"])
    return out


def params_from(truth, truth_path, machine, machine_path, plan=None, plan_path=None):
    if truth.get("format") != "rotacal-truth/1":
        fail(truth_path, 'not a truth file (expected "format": "rotacal-truth/1")')
    for k in truth:
        if k not in KNOWN_TRUTH_KEYS and not k.startswith("_"):
            fail(truth_path, "unknown field %r" % k)
    for f in truth.get("form_error", {}).values():
        if any(v != 0 for v in f.values()):
            fail(truth_path, "form_error is not modelled by the virtual probe (its block has flat, square faces)")
    if truth.get("probe_noise_um", 0) != 0:
        fail(truth_path, "probe_noise_um is not modelled (the virtual probe is deterministic)")
    kinematics = machine.get("kinematics")
    if kinematics not in KINS:
        fail(machine_path, "the harness models an A/C table (xyzac-trt-kins), a B/C table (xyzbc-trt-kins), an "
             "A/B table (xyzab_tdr_kins), a B head over a C table (maxkins) or a C head carrying a B head "
             "(5axiskins) only")
    kins, chain, axes = KINS[kinematics]
    head = None
    if kinematics == "head_table":
        head = machine.get("head", {})
        if head.get("axis", "B") != "B":
            fail(machine_path, "the harness's head machine is maxkins' B head (head.axis \"B\")")
    if kinematics == "head_cb":
        head = machine.get("head", {})
    for ax in axes:
        if head is not None:
            module, signs = HEAD_SIGNS[kinematics]
            sign = machine["rotary_axes"][ax].get("dialect_sign", {}).get(
                "linuxcnc", machine["rotary_axes"][ax].get("controller_sign", 1))
            if sign != signs[ax]:
                fail(machine_path, "rotary axis %s: the linuxcnc sign must be %+d (%s counts B against rotacal's "
                     "head and C as rotacal does)" % (ax, signs[ax], module))
            continue
        sign = machine["rotary_axes"][ax].get("dialect_sign", {}).get(
            "linuxcnc", machine["rotary_axes"][ax].get("controller_sign", 1))
        if sign != LINUXCNC_SIGN[kinematics] and kinematics == "table_ab":
            fail(machine_path, "rotary axis %s: the linuxcnc sign must be +1 (xyzab_tdr_kins turns the table "
                 "as Ry(-B) Rx(-A), as the papers' style chain does)" % ax)
        if sign != LINUXCNC_SIGN[kinematics]:
            fail(machine_path, "rotary axis %s: the linuxcnc sign must be -1 (%s-trt-kins turns the table "
                 "as D_%s(+%s) D_c(+C), the opposite of the papers' chain)" % (ax, kins, ax.lower(), ax))
    if machine.get("units", "mm") != "mm":
        fail(machine_path, "the harness runs mm programs only")
    eq1 = {}
    for name, e in truth.get("location_errors", {}).items():
        if name not in NAMES[kinematics]:
            fail(truth_path, "unknown location error %r for %s (known: %s)" % (name, kinematics, ", ".join(NAMES[kinematics])))
        unit, v = e.get("unit"), e.get("value")
        if not isinstance(v, (int, float)):
            fail(truth_path, "location error %r needs a numeric value" % name)
        length = name[0] == "d" if head is None else name in ("X0C", "Y0C", "X0B", "Z0B") or name[0] == "d"
        if length:
            if unit not in LENGTH:
                fail(truth_path, "unit of %r must be um or mm" % name)
            eq1[name + "_um"] = v * LENGTH[unit]
        else:
            if unit not in ANGLE:
                fail(truth_path, "unit of %r must be mdeg, urad or deg" % name)
            eq1[name + "_mdeg"] = v * ANGLE[unit]
    art = machine.get("artefact")
    if art is None and kinematics in ("table_bc", "table_ab", "head_table", "head_cb"):
        # no test piece: the block is off, some harmless pose for its unused pins
        art = {"type": "square_column", "top_centre_w_mm": [0.0, 0.0, 150.0], "size_mm": [100.0, 100.0, 150.0]}
        block_on = False
        if "setup_error" in truth:
            fail(truth_path, "setup_error moves the test piece, and the machine has none")
    elif not art or art.get("type") != "square_column":
        fail(machine_path, "needs a square_column artefact")
    else:
        block_on = True
    top = [float(v) for v in art["top_centre_w_mm"]]
    size = [float(v) for v in art["size_mm"]]
    centre0 = [top[0], top[1], top[2] - size[2] / 2.0]
    setup = truth.get("setup_error", {})
    t = [float(v) for v in setup.get("translation_mm", [0.0, 0.0, 0.0])]
    r_mrad = [float(v) for v in setup.get("rotation_mrad", [0.0, 0.0, 0.0])]
    rpy_deg = [v * 1e-3 / G.DEG for v in r_mrad]
    R = G.block_rotation(rpy_deg)          # Rz(rz) Ry(ry) Rx(rx), as core/artefact.cpp
    centre = G.add(G.add(top, R(G.sub(centre0, top))), t)
    out = {
        "_comment": "generated by truth_params.py from %s and %s" % (truth_path, machine_path),
        # the contract's machine frame: origin at the nominal intersection of the axes
        "machine": {"kins": kins, "x_rot_point": 0.0, "y_rot_point": 0.0, "z_rot_point": 0.0, "x_offset": 0.0,
                    "y_offset": 0.0, "z_offset": 0.0},
        chain: eq1,
        "probe": {"radius": float(machine["probe"]["ball_diameter_mm"]) / 2.0, "tool_length": 0.0,
                  "pretravel": float(truth.get("probe_pretravel_um", 0.0)) * 1e-3},
        "block": {"enable": block_on, "center": centre, "size": size, "rpy_deg": rpy_deg},
        "sphere": {"enable": False, "center": [0.0, 0.0, 0.0], "radius": 12.7},
    }
    ecc = truth.get("c_angular_positioning_error")
    if ecc is not None:
        if ecc.get("unit") != "mdeg":
            fail(truth_path, "c_angular_positioning_error needs \"unit\": \"mdeg\"")
        errors = {}
        for k, v in ecc.items():
            if k == "unit" or k.startswith("_"):
                continue
            if k not in ECC_KEYS or not isinstance(v, (int, float)):
                fail(truth_path, "c_angular_positioning_error: unknown or non-numeric %r (known: %s)"
                     % (k, sorted(ECC_KEYS)))
            name, sign = ECC_KEYS[k]
            errors[name] = sign * v * 1e-3
        if kinematics != "table_ac":
            fail(truth_path, "c_angular_positioning_error is modelled on the A/C table only")
        out["errors"] = errors
    if head is not None:
        signs = HEAD_SIGNS[kinematics][1]
        out["head"] = {"enable": True, "axis": "CB" if kinematics == "head_cb" else "B",
                       "pivot_to_ball": float(head["pivot_to_ball_mm"]), "sign": float(signs["B"]),
                       "c_sign": float(signs["C"])}
    if plan is not None:
        out.update(spheres_from(plan, plan_path))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--truth", required=True)
    ap.add_argument("--machine", required=True)
    ap.add_argument("--plan", help="PLAN.json of a sphere cycle: its spheres join the virtual piece")
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args()
    plan = None
    if a.plan:
        with open(a.plan) as f:
            plan = json.load(f)
    with open(a.truth) as f:
        truth = json.load(f)
    with open(a.machine) as f:
        machine = json.load(f)
    p = params_from(truth, a.truth, machine, a.machine, plan, a.plan)
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(p, f, indent=1)
    os.replace(tmp, a.out)
    G.load_params(a.out)   # the harness's own validation (known keys, eq1 needs intersecting axes)


if __name__ == "__main__":
    main()
