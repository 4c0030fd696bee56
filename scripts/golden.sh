#!/usr/bin/env bash
# Regenerates the golden example programs in examples/programs/: the touch154 plan of the
# bundled A/C machine (plan.json) and, for every dialect, <dialect>/touch154.<ext> (the program;
# csv has none), <dialect>/results.<ext> (what that program writes on a machine with 000 Table
# 4's errors, the setup and form errors of examples/truth/table4_mean.json, 0.7 um probe noise,
# seed 1, the cycle starting 2023-10-07 13:20:00 on the controllers' clock) and
# <dialect>/offsets.<ext> (what `rotacal analyze --offsets` writes from those results).
# tests/cli/golden_test.cpp runs this script into a temporary directory and compares every file
# byte for byte with the committed ones: a change to a writer shows up as a reviewed diff here.
#
# usage: scripts/golden.sh [ROTACAL [OUTDIR]]   (defaults: build/cli/rotacal, examples/programs)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rotacal=$(realpath "${1:-$root/build/cli/rotacal}")
out=$(realpath -m "${2:-$root/examples/programs}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Relative names inside a scratch directory: the files name their inputs, never a local path.
# The machine names its contributors relative to itself (../contributors/): the same layout here.
mkdir "$work/machines" "$work/contributors"
cp "$root/examples/machines/ac_trunnion.json" "$work/machines/"
cp "$root/examples/contributors/table5.json" "$work/contributors/"
cp "$root/examples/truth/table4_mean.json" "$work/"
cd "$work"
mkdir gen
"$rotacal" plan --cycle touch154 --machine machines/ac_trunnion.json -o gen/plan.json >/dev/null
# Every dialect, as the tool lists them (simulate takes them all); each names its files' extensions
# below, and a dialect without its line stops the script.
dialects=$("$rotacal" simulate --help | sed -n 's/^ *--dialect TEXT REQUIRED *//p' | tr -d '|')
for d in $dialects; do
  case $d in
    csv) prog="" res=.csv off=.csv ;;
    linuxcnc) prog=.ngc res=.txt off=.hal ;;
    fanuc | haas) prog=.nc res=.txt off=.nc ;;
    siemens) prog=.mpf res=.txt off=.mpf ;;
    heidenhain) prog=.h res=.txt off=.h ;;
    okuma) prog=.min res=.txt off=.min ;;
    *) echo "golden.sh: add the file extensions of dialect $d" >&2; exit 1 ;;
  esac
  mkdir "gen/$d"
  if [ -n "$prog" ]; then
    "$rotacal" generate --plan gen/plan.json --dialect "$d" -o "gen/$d/touch154$prog" >/dev/null
  fi
  "$rotacal" simulate --plan gen/plan.json --truth table4_mean.json --noise-um 0.7 --seed 1 --start-s 750000000 \
    --dialect "$d" -o "gen/$d/results$res" >/dev/null
  (cd "gen/$d" && "$rotacal" analyze --plan ../plan.json --results "results$res" --dialect "$d" \
    --offsets "offsets$off" >/dev/null)
done
mkdir -p "$out"
cp gen/plan.json "$out/plan.json"
for d in $dialects; do
  rm -rf "${out:?}/$d"
  cp -r "gen/$d" "$out/$d"
done
