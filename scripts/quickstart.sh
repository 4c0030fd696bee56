#!/usr/bin/env bash
# The README's first command: install, build, and run the main job on the bundled example:
# plan the 154-point cycle of 000, write the LinuxCNC and Fanuc programs, simulate what the
# controller records on a real machine: 000 Table 4's errors on a machine drawn from its own
# contributors file (000 Table 5: linear axes, squareness, the test piece's set-up and form,
# repeatability and roughness), analyze it, and write the report and the offsets.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target rotacal
R=build/cli/rotacal
O=out/example
mkdir -p "$O"
$R plan --cycle touch154 --machine examples/machines/ac_trunnion.json -o "$O/plan.json"
$R generate --plan "$O/plan.json" --dialect linuxcnc -o "$O/touch154.ngc"
$R generate --plan "$O/plan.json" --dialect fanuc -o "$O/touch154.nc"
$R simulate --plan "$O/plan.json" --truth examples/truth/table4_mean.json --seed 1 \
   --contributors examples/contributors/table5.json --machine-seed 1 --truth-out "$O/truth_drawn.json" \
   --dialect linuxcnc -o "$O/results.txt"
$R analyze --plan "$O/plan.json" --results "$O/results.txt" --dialect linuxcnc \
   --json "$O/REPORT.json" --text "$O/REPORT.txt" --html "$O/REPORT.html" --offsets "$O/offsets.hal"
echo
echo "outputs in $O: plan.json touch154.ngc touch154.nc results.txt truth_drawn.json REPORT.json REPORT.txt REPORT.html offsets.hal"
echo "truth injected: examples/truth/table4_mean.json (000 Table 4 mean column) on a machine drawn from"
echo "examples/contributors/table5.json (what was drawn: $O/truth_drawn.json)"
