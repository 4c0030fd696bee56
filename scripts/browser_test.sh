#!/usr/bin/env bash
# browser_test.sh ROTACAL PNG_STATS WORKDIR MIN_SVG CMD...
# Runs each CMD (a bash command; $ROTACAL is the rotacal binary, $SRC the source tree) in a fresh
# WORKDIR, then checks every *.html it produced in headless Chromium (scripts/browser_check.sh),
# leaving the screenshots beside them. CMake's add_browser_test() calls this.
set -euo pipefail
export ROTACAL=$1 PNG_STATS=$2
WORKDIR=$3 MIN_SVG=$4
shift 4
SRC=$(cd "$(dirname "$0")/.." && pwd)
export SRC
rm -rf "$WORKDIR"
mkdir -p "$WORKDIR"
cd "$WORKDIR"
for cmd in "$@"; do
  echo "+ $cmd"
  bash -c "$cmd" >/dev/null
done
shopt -s nullglob
pages=(*.html)
[ ${#pages[@]} -gt 0 ] || { echo "browser_test: the commands wrote no .html"; exit 1; }
status=0
for page in "${pages[@]}"; do
  bash "$SRC/scripts/browser_check.sh" "$PNG_STATS" "$page" "${page%.html}.png" "$MIN_SVG" || status=1
  # Every analysis answers first: its verdict block opens the page.
  if [[ $page == analyze_* ]] && ! grep -q 'id="verdict"' "$page"; then
    echo "browser_test: $page has no verdict block"
    status=1
  fi
done
exit $status
