#!/usr/bin/python3
"""How late each recorded trigger is: the controller's recorded ball centre against the exact
first contact of the TRUE machine and piece (params.json), on the plan's probing line.

Usage: lateness.py --params params.json --plan PLAN.json --results rotacal_touch154.txt
                   [--offsets OFFSETS.ngc] [--linear-comp DIR] [--json out.json]

The recorded touch moves along the plan's approach line through the nominal trigger (both the
single and the double touch: the second touch starts on that line, retract_mm back from where
the first stopped). The exact contact on that line is found by bisection (lcsim_geom.first_contact,
~1e-10 of the move), with joints A = -A*, C = -C* (the LinuxCNC sign of rotacal's machine
file; B = -B* on a B/C table; B = +B*, A = +A* on the A/B table; on maxkins' B head over a C
table B = -B*, C = +C*, the ball through the true head; on 5axiskins' C head carrying the B head
likewise B = -B*, C = +C*). With --offsets (rotacal's G10 L2 P1 work-offset program),
machine = program + offset.
Reported per point, in um: over = (recorded - contact) . approach (> 0: late) and across =
the part perpendicular to the approach. Exit 1 on a missing point or a result file that is not
rotacal's LinuxCNC LOG.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcsim_geom as G  # noqa: E402


def read_log(path):
    """rotacal LinuxCNC results: header line, then 'P<id> x y z a c ok'."""
    out = {}
    with open(path) as f:
        for n, line in enumerate(f, 1):
            t = line.split()
            if not t or t[0] == "rotacal-results/1":
                continue
            if not t[0].startswith("P") or len(t) != 7:
                raise SystemExit("%s:%d: expected 'P<id> x y z a c ok', got %r" % (path, n, line.strip()))
            out[int(t[0][1:])] = [float(v) for v in t[1:4]]
    return out


def read_offsets(path):
    """X Y Z A B C (those it gives) of the 'G10 L2 P1' line of rotacal's work-offset program."""
    o = {"X": 0.0, "Y": 0.0, "Z": 0.0, "A": 0.0, "B": 0.0, "C": 0.0}
    if not path:
        return o
    with open(path) as f:
        for line in f:
            code = line.split("(")[0].upper().split()
            if code[:3] == ["G10", "L2", "P1"]:
                for w in code[3:]:
                    o[w[0]] = float(w[1:])
                return o
    raise SystemExit("%s: no 'G10 L2 P1' line" % path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--params", required=True)
    ap.add_argument("--plan", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--offsets")
    ap.add_argument("--linear-comp", help="DIR with joint0..2.comp: the linear joints' tables (run.sh --linear-comp)")
    ap.add_argument("--json")
    a = ap.parse_args()
    p = G.load_params(a.params)
    if a.linear_comp:
        p["linear_comp"] = [G.read_comp_table(os.path.join(a.linear_comp, "joint%d.comp" % j)) for j in range(3)]
    with open(a.plan) as f:
        plan = json.load(f)
    got = read_log(a.results)
    o = read_offsets(a.offsets)
    off = [o["X"], o["Y"], o["Z"]]
    m = plan["machine"]
    before, past = float(m["approach_mm"]), float(m["overtravel_mm"])
    rows, missing = [], []
    for pt in plan["points"]:
        if pt["id"] not in got:
            missing.append(pt["id"])
            continue
        u = pt["approach_m"]
        tr = G.add(pt["trigger_m_mm"], off)
        # joint 3 is the tilt axis: A on xyzac-trt-kins, B on xyzbc-trt-kins (each with its G54 zero shift)
        head = []
        if p["machine"]["kins"] == "5axis":
            # the bridge mill's [X, Y, Z, 0, 0, C, B] (its head's outer C, inner B): joint = sign x the
            # papers' angle (+ its G54 B, C); the table's joints unwired
            ja, jc = 0.0, 0.0
            head = [p["head"]["c_sign"] * pt["pose"]["C"] + o.get("C", 0.0),
                    p["head"]["sign"] * pt["pose"]["B"] + o.get("B", 0.0)]
        elif p["machine"]["kins"] == "max":
            # the head machine's [X, Y, Z, 0, C, B]: joint B = sign x B* (+ its G54 B), C = sign x C*
            ja, jc = 0.0, p["head"]["c_sign"] * pt["pose"]["C"]
            head = [p["head"]["sign"] * pt["pose"]["B"] + o.get("B", 0.0)]
        elif p["machine"]["kins"] == "xyzab":
            # the harness's [outer, inner] = [B, A]; xyzab_tdr_kins counts as rotacal: B = +B*, A = +A*
            ja, jc = pt["pose"]["B"] + o.get("B", 0.0), pt["pose"]["A"]
        else:
            tilt = -pt["pose"]["B"] + o["B"] if p["machine"]["kins"] == "xyzbc" else -pt["pose"]["A"] + o["A"]
            ja, jc = tilt, -pt["pose"]["C"]
        j0 = G.add(tr, G.scale(u, -before)) + [ja, jc] + head
        j1 = G.add(tr, G.scale(u, past)) + [ja, jc] + head
        hit = G.first_contact(j0, j1, p, step=0.01)
        if hit is None:
            raise SystemExit("point %d: the true piece is not on the probing line" % pt["id"])
        contact = hit[1][:3]
        rec = G.add(got[pt["id"]], off)
        d = G.sub(rec, contact)
        over = G.dot(d, u) * 1000.0
        across = G.norm(G.sub(d, G.scale(u, G.dot(d, u)))) * 1000.0
        effect = G.dot(G.sub(contact, tr), u) * 1000.0
        rows.append({"id": pt["id"], "over_um": over, "across_um": across, "effect_um": effect})
    if missing:
        print("lateness.py: no result for point(s) %s" % missing)
        sys.exit(1)
    ov = [r["over_um"] for r in rows]
    n = len(ov)
    mean = sum(ov) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in ov) / (n - 1)) if n > 1 else 0.0
    summary = {"points": n, "over_um": {"min": min(ov), "max": max(ov), "mean": mean, "sd": sd},
               "across_um_max": max(r["across_um"] for r in rows),
               "effect_um": {"min": min(r["effect_um"] for r in rows), "max": max(r["effect_um"] for r in rows)}}
    print("lateness: %d points, over %.3f .. %.3f um (mean %.3f, sd %.3f), across <= %.4f um; "
          "error effect on the contacts %.2f .. %.2f um"
          % (n, min(ov), max(ov), mean, sd, summary["across_um_max"], summary["effect_um"]["min"],
             summary["effect_um"]["max"]))
    if a.json:
        with open(a.json + ".tmp", "w") as f:
            json.dump({"summary": summary, "points": rows}, f, indent=1)
        os.replace(a.json + ".tmp", a.json)


if __name__ == "__main__":
    main()
