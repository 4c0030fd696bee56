#!/bin/sh
# The rep5x B-axis tool-tip offsets through rotacal's tooltip analysis and diagnosis.
# Usage: examples/tooltip-rep5x/run.sh [path/to/rotacal] (from the repository root)
set -e
R=${1:-build/cli/rotacal}
D=examples/tooltip-rep5x
OUT=${OUT:-/tmp/rotacal-tooltip-rep5x}
mkdir -p "$OUT"
# Their B axis tilts the head in the plane of err_y and err_z: rotacal's A axis on head_ab (about
# X, reads Y and Z). -90..90 deg in 15 deg steps, zeroed at 0 deg as in the post. R: the post gives
# no pivot-to-nozzle distance; 50 mm is assumed (RADIUS_MM to change it). One value per angle: one
# run (repeats=1).
"$R" plan --cycle tooltip --machine examples/machines/head_ab.json --set units=mm \
  --set radius_mm=${RADIUS_MM:-50} --set step_deg=15 --set start_deg=-90 --set end_deg=90 --set repeats=1 -o "$OUT/plan.json"
"$R" analyze --plan "$OUT/plan.json" --results $D/b_axis_results.csv --dialect csv --json "$OUT/REPORT.json"
"$R" diagnose --plan "$OUT/plan.json" --results $D/b_axis_results.csv --dialect csv --json "$OUT/DIAGNOSIS.json"
