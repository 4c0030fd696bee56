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
# CI: warnings are errors, and the build is the One Definition Rule check too (ROTACAL_ODR_CHECK:
# `rotacal` linked under LTO with -Werror=odr from the libraries' fat objects; scripts/odr-check.sh).
WERROR=OFF
ODR=OFF
if [ "${CI:-}" = "true" ]; then WERROR=ON; ODR=ON; fi
if [ "$STEP" != --test-only ]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DROTACAL_WERROR=$WERROR -DROTACAL_ODR_CHECK=$ODR
  cmake --build build -j"$(nproc)"
fi
[ "$STEP" = --build-only ] && exit 0
ctest --test-dir build --output-on-failure -j"$(( $(nproc) + 4 ))"
