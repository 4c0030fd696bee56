#!/usr/bin/env bash
# browser_check.sh PNG_STATS HTML SCREENSHOT.png MIN_SVG
# Opens a report in headless Chromium (Debian package `chromium`) and checks that it rendered:
#  - no script error (the page records any in <html data-script-error>, and Chromium's console
#    log must hold no "Uncaught"),
#  - the page's script ran to its end (<body data-report-ready=N>, N = number of SVG elements)
#    and the DOM holds at least MIN_SVG <svg> elements, with drawn marks (circle/polyline),
#  - the screenshot is not blank: at least 8 distinct colours and 1 % non-white pixels.
set -euo pipefail
PNG_STATS=$1 HTML=$2 PNG=$3 MIN_SVG=$4
command -v chromium >/dev/null || { echo "browser_check: chromium not installed (scripts/install-deps.sh)"; exit 1; }
HTML=$(readlink -f "$HTML")
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
FLAGS=(--headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run --disable-extensions
       --user-data-dir="$WORK/profile" --enable-logging=stderr --v=0)
# The DOM after the scripts ran (--virtual-time-budget lets them finish).
timeout 120 chromium "${FLAGS[@]}" --virtual-time-budget=2000 --dump-dom "file://$HTML" >"$WORK/dom.html" 2>"$WORK/dom.log" || {
  echo "browser_check: chromium --dump-dom failed"; tail -20 "$WORK/dom.log"; exit 1; }
timeout 120 chromium "${FLAGS[@]}" --window-size=1300,2400 --screenshot="$PNG" "file://$HTML" >"$WORK/shot.log" 2>&1 || {
  echo "browser_check: chromium --screenshot failed"; tail -20 "$WORK/shot.log"; exit 1; }
fail=0
if grep -q 'data-script-error="' "$WORK/dom.html"; then
  echo "browser_check: script error: $(grep -o 'data-script-error="[^"]*"' "$WORK/dom.html")"; fail=1; fi
if grep -h 'CONSOLE' "$WORK/dom.log" "$WORK/shot.log" | grep -i 'uncaught\|error' >/dev/null; then
  echo "browser_check: console errors:"; grep -h 'CONSOLE' "$WORK/dom.log" "$WORK/shot.log"; fail=1; fi
ready=$(grep -o 'data-report-ready="[0-9]*"' "$WORK/dom.html" | grep -o '[0-9]*' || true)
svgs=$(grep -o '<svg' "$WORK/dom.html" | wc -l)
marks=$(grep -o '<circle\|<polyline' "$WORK/dom.html" | wc -l)
if [ -z "$ready" ]; then echo "browser_check: the page's script did not run to its end"; fail=1; fi
if [ "$svgs" -lt "$MIN_SVG" ]; then echo "browser_check: $svgs <svg> elements, expected at least $MIN_SVG"; fail=1; fi
if [ -n "$ready" ] && [ "$ready" != "$svgs" ]; then echo "browser_check: script saw $ready svg, DOM has $svgs"; fail=1; fi
if [ "$marks" -lt 1 ]; then echo "browser_check: no plotted marks"; fail=1; fi
read -r w h colours nonwhite < <("$PNG_STATS" "$PNG")
if [ "$colours" -lt 8 ]; then echo "browser_check: screenshot has $colours colours (blank?)"; fail=1; fi
if awk "BEGIN{exit !($nonwhite < 0.01)}"; then echo "browser_check: screenshot $nonwhite non-white (blank?)"; fail=1; fi
echo "browser_check: $(basename "$HTML"): $svgs svg, $marks marks, screenshot ${w}x${h} with $colours colours, non-white $nonwhite"
exit $fail
