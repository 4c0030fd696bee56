#!/usr/bin/env bash
# Every battery of the throwaway's test program runs on the throwaway dialect and passes:
# the dialect battery (Dialects/EveryDialect) and the malformed-results battery
# (AllDialects/Malformed) each hold every one of their tests for it, and the check that the
# dialect battery takes every dialect of the registry passes with it there. A battery that lists
# its dialects by hand instead of reading the registry loses the throwaway and fails here.
#   every_battery_takes_it.sh CONTROLLERS_THROWAWAY_TEST
set -euo pipefail
exe=$1
# Full test names, "Suite.Test/param", from gtest's listing ("Suite." then "  Test/param  # ...").
names=$("$exe" --gtest_list_tests | awk '/^[^ ]/ {suite=$1} /^  / {print suite $1}')
expected=1  # EveryDialectBattery.TakesEveryDialectWithPrograms
for suite in Dialects/EveryDialect AllDialects/Malformed; do
  all=$(grep "^$suite\." <<<"$names" | sed 's#/[^/]*$##' | sort -u)
  mine=$(grep "^$suite\..*/throwaway$" <<<"$names" | sed 's#/[^/]*$##' | sort -u || true)
  if [ -z "$all" ]; then echo "FAIL: no test of $suite in $exe" >&2; exit 1; fi
  if [ "$all" != "$mine" ]; then
    echo "FAIL: $suite does not run every one of its tests on the throwaway dialect; missing:" >&2
    comm -23 <(echo "$all") <(echo "$mine") >&2
    exit 1
  fi
  n=$(grep -c . <<<"$mine")
  echo "$suite: $n tests on the throwaway dialect"
  expected=$((expected + n))
done
grep -qx "EveryDialectBattery.TakesEveryDialectWithPrograms" <<<"$names" ||
  { echo "FAIL: EveryDialectBattery.TakesEveryDialectWithPrograms is gone" >&2; exit 1; }
out=$("$exe" --gtest_filter='*/throwaway:EveryDialectBattery.TakesEveryDialectWithPrograms' 2>&1) ||
  { echo "$out" >&2; echo "FAIL: a battery fails on the throwaway dialect" >&2; exit 1; }
passed=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) tests\?\.$/\1/p' <<<"$out")
if [ "$passed" != "$expected" ]; then
  echo "$out" >&2
  echo "FAIL: $passed tests passed, expected $expected (none skipped)" >&2
  exit 1
fi
echo "ok: $passed battery tests passed on the throwaway dialect"
