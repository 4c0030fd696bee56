#!/usr/bin/env bash
# The build's CPU profile (docs/build-profile.md): a clean build of every target in BUILD_DIR
# (default build-profile) with each compile's and link's CPU time logged (ROTACAL_CPU_PROFILE,
# scripts/cputime-launcher.sh), ccache off; then the summary: totals by kind, the 15 costliest
# translation units.
#   scripts/build-profile.sh [BUILD_DIR [CMAKE_ARGS...]]
#   scripts/build-profile.sh --summary LOG      (the summary of an existing log)
set -euo pipefail
cd "$(dirname "$0")/.."
summary() {
  awk -F'\t' '
    { t = $1 + 0; f = $2
      kind = (f ~ /\.o$/) ? "compile" : "link"
      n[kind]++; s[kind] += t
      if (f ~ /\.gch$|cmake_pch/) { n["pch"]++; s["pch"] += t }
    }
    END {
      printf "compiles: %d, %.0f s of CPU (%.1f min)\n", n["compile"], s["compile"], s["compile"] / 60
      printf "links:    %d, %.0f s of CPU\n", n["link"], s["link"]
      if (n["pch"]) printf "of the compiles, precompiled headers: %d, %.0f s\n", n["pch"], s["pch"]
      printf "total:    %.0f s of CPU (%.1f min)\n", s["compile"] + s["link"], (s["compile"] + s["link"]) / 60
    }' "$1"
  echo "the 15 costliest:"
  sort -t$'\t' -k1,1 -rn "$1" | head -15 | awk -F'\t' '{ printf "  %7.1f s  %s\n", $1, $2 }'
}
if [ "${1:-}" = "--summary" ]; then summary "$2"; exit 0; fi
B=${1:-build-profile}
shift || true
LOG=$PWD/$B/cpu-profile.log
rm -rf "$B"
mkdir -p "$B"
cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=Release -DROTACAL_CPU_PROFILE="$LOG" "$@" >/dev/null
CCACHE_DISABLE=1 cmake --build "$B" -j"$(nproc)"
summary "$LOG"
