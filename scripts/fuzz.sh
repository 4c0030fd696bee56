#!/usr/bin/env bash
# libFuzzer + AddressSanitizer + UndefinedBehaviorSanitizer on every input boundary
# (tests/fuzz/): builds the harnesses with clang in build-fuzz/, makes seed corpora from
# examples/ (plans, results of every dialect, programs, machines, truths, contributors, reports)
# and tests/data/bad/, then runs each harness for SECONDS (default 20) on one core. Fails on
# any crash, leak, timeout, out-of-memory, sanitizer report or escaped exception; the input that
# found it is left in build-fuzz/findings/HARNESS/.
#   scripts/fuzz.sh [SECONDS_PER_HARNESS] [HARNESS...]     (FUZZ_JOBS=2: two harnesses at a time)
#   scripts/fuzz.sh --configure-only    (the sanitizer build's configuration alone: scripts/sanitize-corpus.sh)
#   scripts/fuzz.sh --build-only        (configure and build every harness and the corpus' `rotacal`;
#                                        .ci/run builds them beside the tests)
set -euo pipefail
cd "$(dirname "$0")/.."
CONFIGURE_ONLY=0
BUILD_ONLY=0
if [ "${1:-}" = "--configure-only" ]; then CONFIGURE_ONLY=1; shift; fi
if [ "${1:-}" = "--build-only" ]; then BUILD_ONLY=1; shift; fi
SECONDS_PER=${1:-20}
shift || true
ROOT=$PWD
B=$ROOT/build-fuzz
HARNESSES=("$@")
if [ ${#HARNESSES[@]} -eq 0 ]; then
  HARNESSES=(fuzz_results fuzz_rtest_results fuzz_tooltip_results fuzz_program fuzz_machine fuzz_plan fuzz_truth
             fuzz_contributors fuzz_report)
fi
JOBS=${FUZZ_JOBS:-1}
CC_=${FUZZ_CC:-clang}
CXX_=${FUZZ_CXX:-clang++}
if ! command -v "$CXX_" >/dev/null; then
  echo "fuzz: $CXX_ not found (scripts/install-deps.sh installs clang and libclang-rt-14-dev)" >&2
  exit 1
fi
# -O1 -gline-tables-only: what libFuzzer's documentation uses; a third less compile time than
# -O2 -g (cycles/touch154/identification.cpp: 53 s of CPU instead of 77 s), with file:line in every report.
SAN="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -O1 -gline-tables-only"
cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=None -DCMAKE_C_COMPILER="$CC_" -DCMAKE_CXX_COMPILER="$CXX_" \
  -DROTACAL_FUZZ=ON -DROTACAL_BUILD_TESTS=OFF -DROTACAL_BUILD_BENCH=OFF -DROTACAL_WERROR=OFF \
  -DCMAKE_CXX_FLAGS="$SAN" >/dev/null
if [ $CONFIGURE_ONLY = 1 ]; then exit 0; fi
if [ $BUILD_ONLY = 1 ]; then
  cmake --build "$B" --target "${HARNESSES[@]}" rotacal -j"$(nproc)"
  exit 0
fi
cmake --build "$B" --target "${HARNESSES[@]}" -j"$(nproc)"

# Seeds: the real files each boundary reads, made by the normal build's rotacal (built if absent).
RC=${ROTACAL_BIN:-$ROOT/build/cli/rotacal}
if [ ! -x "$RC" ]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build --target rotacal -j"$(nproc)"
fi
S=$B/seeds
rm -rf "$S"
mkdir -p "$S"/{fuzz_results,fuzz_rtest_results,fuzz_tooltip_results,fuzz_program,fuzz_machine,fuzz_plan,fuzz_truth,fuzz_contributors,fuzz_report} "$S/work"
W=$S/work
# prefix BYTE FILE OUT: OUT = one selector byte (decimal) followed by FILE
prefix() { { printf "\\$(printf '%03o' "$1")"; cat "$2"; } >"$3"; }
# The dialects in the registry's order, as the tool's --help lists them (the harnesses pick by that
# order): every dialect reads results, those with programs are the ones `generate` takes.
dialectsOf() { "$RC" "$1" --help | sed -n 's/^ *--dialect TEXT REQUIRED *//p' | tr -d '|'; }
read -r -a DIALECTS <<<"$(dialectsOf simulate)"
read -r -a PROGRAM_DIALECTS <<<"$(dialectsOf generate)"
BASE=tests/data/bad/base  # the plans the results harnesses read against (tests/fuzz/fuzz_plans.hpp)
W=$S/work
# results of every dialect: fuzz_results's selector byte = plan index * (number of dialects) + dialect index
for pi in 0 1; do
  plan=$BASE/small.plan.json
  [ $pi = 1 ] && plan=$BASE/spheres3.plan.json
  for di in "${!DIALECTS[@]}"; do
    d=${DIALECTS[$di]}
    if "$RC" -q simulate --plan "$plan" --truth examples/truth/table4_mean.json --noise-um 0.5 --dialect "$d" \
         -o "$W/$pi.$d.res" 2>/dev/null; then
      prefix $((pi * ${#DIALECTS[@]} + di)) "$W/$pi.$d.res" "$S/fuzz_results/$pi.$d"
    fi
  done
done
"$RC" -q simulate --plan $BASE/rtest.plan.json --truth examples/truth/rtest_002.json --dialect csv -o "$W/rtest.csv"
cp "$W/rtest.csv" "$S/fuzz_rtest_results/"; cp $BASE/rtest.csv "$S/fuzz_rtest_results/base.csv"
cp $BASE/tooltip.csv "$S/fuzz_tooltip_results/"
# programs and plans of every cycle on its bundled example; fuzz_program's selector = dialect index
declare -A MACHINE=([touch154]=ac_trunnion [spheres3]=ac_trunnion [spaceframe]=ac_trunnion [rtest]=bc_trunnion [tooltip]=head_ab
                   [one_sphere]=ac_trunnion [probe_qual]=ac_trunnion)
declare -A SETS=([spaceframe]="--set phi_list=-90,-45,0")
declare -A RULES=([touch154]=0 [spheres3]=1 [rtest]=2 [tooltip]=3 [spaceframe]=4 [one_sphere]=5 [probe_qual]=6)  # fuzz_plan's selector
for cycle in touch154 spheres3 spaceframe rtest tooltip one_sphere probe_qual; do
  # shellcheck disable=SC2086
  "$RC" -q plan --cycle $cycle --machine examples/machines/${MACHINE[$cycle]}.json ${SETS[$cycle]:-} -o "$W/$cycle.plan.json"
  prefix "${RULES[$cycle]}" "$W/$cycle.plan.json" "$S/fuzz_plan/$cycle.json"
  for pi in "${!PROGRAM_DIALECTS[@]}"; do
    d=${PROGRAM_DIALECTS[$pi]}
    if "$RC" -q generate --plan "$W/$cycle.plan.json" --dialect "$d" -o "$W/$cycle.$d.prog" 2>/dev/null; then
      prefix "$pi" "$W/$cycle.$d.prog" "$S/fuzz_program/$cycle.$d"
    fi
  done
done
# one_sphere under a spindle head and a head/head (MACHINE.json "head", the ball carried along the spindle)
"$RC" -q plan --cycle one_sphere --machine examples/machines/bc_head_table.json -o "$W/one_sphere_head.plan.json"
prefix "${RULES[one_sphere]}" "$W/one_sphere_head.plan.json" "$S/fuzz_plan/one_sphere_head.json"
"$RC" -q plan --cycle one_sphere --machine examples/machines/ab_head.json -o "$W/one_sphere_ab_head.plan.json"
prefix "${RULES[one_sphere]}" "$W/one_sphere_ab_head.plan.json" "$S/fuzz_plan/one_sphere_ab_head.json"
for f in $BASE/small.*.prog; do
  d=$(basename "$f" .prog); d=${d#small.}
  for pi in "${!PROGRAM_DIALECTS[@]}"; do
    [ "${PROGRAM_DIALECTS[$pi]}" = "$d" ] && prefix "$pi" "$f" "$S/fuzz_program/small.$d"
  done
done
cp $BASE/report.json "$S/fuzz_report/small.json"
cp examples/machines/*.json "$S/fuzz_machine/"
cp examples/contributors/*.json "$S/fuzz_contributors/"
for f in examples/truth/*.json; do
  for k in 0 1; do prefix $k "$f" "$S/fuzz_truth/$k.$(basename "$f")"; done
done
cp examples/tooltip-rep5x/b_axis_results.csv "$S/fuzz_tooltip_results/rep5x.csv" 2>/dev/null || true
# The bad-input corpus: each file where its kind is read.
if [ -d tests/data/bad ]; then
  for f in tests/data/bad/machine/*; do [ -f "$f" ] && cp "$f" "$S/fuzz_machine/bad.$(basename "$f")"; done
  for f in tests/data/bad/plan/*; do [ -f "$f" ] && prefix 0 "$f" "$S/fuzz_plan/bad.$(basename "$f")"; done
  for f in tests/data/bad/contributors/*; do [ -f "$f" ] && cp "$f" "$S/fuzz_contributors/bad.$(basename "$f")"; done
  for f in tests/data/bad/report/*; do [ -f "$f" ] && cp "$f" "$S/fuzz_report/bad.$(basename "$f")"; done
  for f in tests/data/bad/truth/*; do [ -f "$f" ] && prefix 0 "$f" "$S/fuzz_truth/bad.$(basename "$f")"; done
  for f in tests/data/bad/program/*; do
    [ -f "$f" ] && [ "$(stat -c %s "$f")" -lt 100000 ] && prefix 1 "$f" "$S/fuzz_program/bad.$(basename "$f")"
  done
  for f in tests/data/bad/results/*; do [ -f "$f" ] && prefix 2 "$f" "$S/fuzz_results/bad.$(basename "$f")"; done
fi
rm -rf "$W"

# Run. -max_len 64 kB (4 kB for programs): the files are small (the 1 MB lines are the corpus's job); -timeout 10 s
# per input, -rss_limit_mb 2048: a hang or a runaway allocation is a finding.
mkdir -p "$B/logs" "$B/corpus" "$B/findings"
run_one() {
  local h=$1
  mkdir -p "$B/corpus/$h" "$B/findings/$h"
  local max_len=65536
  # programs: a few kB of blocks (the seeds are whole programs, cut there); every input runs the
  # tokenizer, a motion reader and compensate with its checker, about 50 ms on 64 kB
  [ "$h" = fuzz_program ] && max_len=4096
  if "$B/tests/fuzz/$h" "$B/corpus/$h" "$S/$h" -max_total_time="$SECONDS_PER" -max_len=$max_len -timeout=10 -seed="$FUZZ_SEED" \
       -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$B/findings/$h/" \
       >"$B/logs/$h.log" 2>&1; then
    echo "fuzz: $h: $(grep -E '^stat::number_of_executed_units' "$B/logs/$h.log" | awk '{print $2}') executions," \
         "$(grep -oE 'cov: [0-9]+' "$B/logs/$h.log" | tail -1) edges, corpus $(ls "$B/corpus/$h" | wc -l), 0 findings"
  else
    echo "fuzz: $h FAILED (log $B/logs/$h.log, input in $B/findings/$h/):" >&2
    grep -E "FUZZ FINDING|ERROR: |SUMMARY|runtime error" "$B/logs/$h.log" | head -5 >&2
    return 1
  fi
}
export -f run_one
# FUZZ_SEED: libFuzzer's seed (0 = a new one each run); CI fixes it so that a red run can be replayed.
FUZZ_SEED=${FUZZ_SEED:-0}
export B S SECONDS_PER FUZZ_SEED
fail=0
printf '%s\n' "${HARNESSES[@]}" | xargs -P "$JOBS" -I{} bash -c 'run_one {}' || fail=1
if [ $fail -ne 0 ]; then echo "fuzz: FAILED" >&2; exit 1; fi
echo "fuzz: ${#HARNESSES[@]} harnesses x ${SECONDS_PER} s: no crash, leak, timeout or sanitizer report"
