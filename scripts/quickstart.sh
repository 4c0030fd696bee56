#!/usr/bin/env bash
# The README's first command: install, build, and run the main job on the bundled example:
# plan the 154-point cycle of 000, write the LinuxCNC and Fanuc programs, simulate what the
# controller records on a machine with 000 Table 4's errors (plus a misplaced, non-square test
# piece and 0.7 um probe noise), analyze it, and write the report and the offsets.
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
$R simulate --plan "$O/plan.json" --truth examples/truth/table4_mean.json --noise-um 0.7 --seed 1 \
   --dialect linuxcnc -o "$O/results.txt"
$R analyze --plan "$O/plan.json" --results "$O/results.txt" --dialect linuxcnc \
   --json "$O/REPORT.json" --text "$O/REPORT.txt" --html "$O/REPORT.html" --offsets "$O/offsets.hal"
echo
echo "outputs in $O: plan.json touch154.ngc touch154.nc results.txt REPORT.json REPORT.txt REPORT.html offsets.hal"
echo "truth injected: examples/truth/table4_mean.json (000 Table 4 mean column)"
