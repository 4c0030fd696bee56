#!/usr/bin/env bash
# Regenerates the committed screenshots of the HTML reports (docs/img/, shown in the README and
# docs/reports.md): one per report kind, taken by the browser tests in headless Chromium.
# Needs a configured build (scripts/test.sh or the README's cmake lines) and chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --build build -j"$(nproc)" --target rotacal png_stats
ctest --test-dir build --output-on-failure -R '^browser_(analyze_touch154|diagnose|history|(analyze|diagnose)_(spheres3|rtest|tooltip)|(analyze|diagnose)_spaceframe|analyze_(one_sphere|probe_qual))$'
mkdir -p docs/img
cp build/browser/browser_analyze_touch154/analyze_touch154.png docs/img/report_analyze_touch154.png
cp build/browser/browser_diagnose/diagnose.png docs/img/report_diagnose.png
cp build/browser/browser_history/history.png docs/img/report_history.png
for k in analyze_spheres3 diagnose_spheres3 analyze_rtest diagnose_rtest analyze_tooltip diagnose_tooltip analyze_spaceframe diagnose_spaceframe analyze_one_sphere analyze_probe_qual; do
  cp "build/browser/browser_$k/$k.png" "docs/img/report_$k.png"
done
ls -l docs/img/report_*.png
