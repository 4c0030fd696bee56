#!/usr/bin/env bash
# One Definition Rule check: `rotacal` linked under link-time optimisation (ROTACAL_ODR_CHECK), where
# GCC sees every library at once and reports two different definitions of one name (-Wodr) as an
# error. CI's build has it on (scripts/test.sh with CI=true), so there the build is the check; this
# script makes it in a build directory of its own (build-lto), tests and bench left out: the binary
# links every library layer.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-lto -DCMAKE_BUILD_TYPE=Release -DROTACAL_BUILD_TESTS=OFF -DROTACAL_BUILD_BENCH=OFF \
  -DROTACAL_ODR_CHECK=ON
cmake --build build-lto -j"$(nproc)" --target rotacal
echo "odr-check: rotacal links under LTO with -Werror=odr"
