#!/usr/bin/env bash
# Builds rotacal and runs every test (the README's second command; .ci/run calls it).
# One CTest run: the LinuxCNC cases (label e2e) start first (their COST) and take as many of its
# slots, while the rest of the suite runs on the machine's cores beside them. A LinuxCNC session
# waits on the controller's motion, not on a core, and each has its own namespaces (tests/e2e).
#   scripts/test.sh [--build-only | --test-only]   (.ci/run builds first, then runs the tests
#   beside its other builds)
set -euo pipefail
STEP=${1:-all}
case "$STEP" in all|--build-only|--test-only) ;; *) echo "test.sh: unknown option $STEP" >&2; exit 2;; esac
cd "$(dirname "$0")/.."
WERROR=OFF
if [ "${CI:-}" = "true" ]; then WERROR=ON; fi
if [ "$STEP" != --test-only ]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DROTACAL_WERROR=$WERROR
  cmake --build build -j"$(nproc)"
fi
[ "$STEP" = --build-only ] && exit 0
ctest --test-dir build --output-on-failure -j"$(( $(nproc) + 4 ))"
