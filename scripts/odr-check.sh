#!/usr/bin/env bash
# One Definition Rule check: the rotacal binary built with link-time optimisation, where
# GCC sees every library at once and reports two different definitions of one name (-Wodr) as an
# error. Tests and bench are left out: the binary links every library layer.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-lto -DCMAKE_BUILD_TYPE=Release -DROTACAL_BUILD_TESTS=OFF -DROTACAL_BUILD_BENCH=OFF \
  -DCMAKE_INTERPROCEDURAL_OPTIMIZATION=ON -DCMAKE_CXX_FLAGS="-Werror=odr -Werror=lto-type-mismatch"
cmake --build build-lto -j"$(nproc)" --target rotacal
echo "odr-check: rotacal links under LTO with -Werror=odr"
