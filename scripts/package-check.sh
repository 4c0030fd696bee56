#!/usr/bin/env bash
# The library for CAM posts and the Debian packages, checked from an existing build dir
# (.ci/run calls it after scripts/test.sh):
#   1. `cmake --install` into a temporary prefix; examples/cam-post configured and built against
#      that prefix only (find_package(rotacal)), with -Werror; a shared library (a post as a CAM
#      plugin) linked against the static libraries;
#   2. a REPORT.json made with the installed CLI (the bundled example: touch154 on
#      examples/machines/ac_trunnion.json, 000 Table 4's errors, 0.7 um noise); the example's
#      compensated poses compared with `rotacal compensate` on a LinuxCNC program of the same poses
#      (equal to the printed 0.1 um / 0.1 mdeg), and the comparison shown to fail on the
#      uncompensated program;
#   3. `cpack -G DEB`: rotacal_<version>_<arch>.deb (the tool: files, Depends, Maintainer, the
#      extracted binary's --version) and rotacal-dev_<version>_<arch>.deb (extracted, the example
#      built against it and giving the same output); `apt-get install -s` of both resolves.
# Usage: scripts/package-check.sh [BUILD_DIR]   (default build, configured; it builds only what it
# packages, and leaves the packages in it)
set -euo pipefail
cd "$(dirname "$0")/.."
SRC=$PWD
BUILD=$(cd "${1:-build}" && pwd)
START=$(date +%s)
# What the packages hold, and only that: `rotacal` links the four exported libraries (the install
# rules do not build: CMAKE_SKIP_INSTALL_ALL_DEPENDENCY).
cmake --build "$BUILD" --target rotacal -j"$(nproc)" >/dev/null || { echo "package-check: cannot build rotacal in $BUILD" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "package-check: FAIL: $*" >&2; exit 1; }
step() { echo "package-check: $*"; }

# --- 1. install, and build the example against the installed package ---------------------------
PREFIX=$TMP/prefix
cmake --install "$BUILD" --prefix "$PREFIX" >"$TMP/install.log"
for f in bin/rotacal include/rotacal/core/compensation.hpp include/rotacal/core/json_io.hpp \
         include/rotacal/postproc/compensate_program.hpp include/rotacal/gcode/program.hpp; do
  [ -e "$PREFIX/$f" ] || fail "not installed: $f"
done
CONFIG=$(find "$PREFIX" -name rotacalConfig.cmake)
[ -n "$CONFIG" ] || fail "no rotacalConfig.cmake under $PREFIX"
for f in rotacalConfigVersion.cmake rotacalTargets.cmake; do
  [ -e "$(dirname "$CONFIG")/$f" ] || fail "not installed: $f beside $CONFIG"
done
step "installed into a temporary prefix ($(find "$PREFIX" -type f | wc -l) files)"

build_example() {  # build_example PREFIX_PATH BUILD_DIR
  cmake -S "$SRC/examples/cam-post" -B "$2" -DCMAKE_PREFIX_PATH="$1" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS=-Werror >"$2.log" 2>&1 || { cat "$2.log" >&2; fail "examples/cam-post does not configure against $1"; }
  cmake --build "$2" -j2 >>"$2.log" 2>&1 || { cat "$2.log" >&2; fail "examples/cam-post does not build against $1"; }
}
build_example "$PREFIX" "$TMP/post"
POST=$TMP/post/cam_post
step "examples/cam-post built against the installed package"

# A post as a plugin: the static libraries must link into a shared library (position-independent).
mkdir -p "$TMP/plugin"
cat >"$TMP/plugin/CMakeLists.txt" <<'EOF'
cmake_minimum_required(VERSION 3.22)
project(rotacal_plugin_check LANGUAGES CXX)
find_package(rotacal REQUIRED)
add_library(post_plugin SHARED plugin.cpp)
target_link_libraries(post_plugin PRIVATE rotacal::postproc)
EOF
cat >"$TMP/plugin/plugin.cpp" <<'EOF'
#include "core/compensation.hpp"
#include "core/json_io.hpp"
#include "postproc/report_errors.hpp"
extern "C" double post_plugin_shift_um(const char* report, double x, double y, double z, double a, double c) {
  const rotacal::JsonDoc doc = rotacal::readJsonFile(report);
  const rotacal::GeometricErrors e = rotacal::errorsFromReport(doc, rotacal::Kinematics::TableAC, false);
  const rotacal::Pose q{a, 0.0, c};
  const rotacal::Pose q_cmd = rotacal::compensatePose(e, q).pose;
  return (rotacal::compensatedPosition(e, q, Eigen::Vector3d(x, y, z), q_cmd) - Eigen::Vector3d(x, y, z)).norm() * 1e3;
}
EOF
{ cmake -S "$TMP/plugin" -B "$TMP/plugin/build" -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_BUILD_TYPE=Release &&
  cmake --build "$TMP/plugin/build" -j2; } >"$TMP/plugin.log" 2>&1 ||
  { cat "$TMP/plugin.log" >&2; fail "a shared library does not link rotacal::postproc"; }
step "a shared library (post plugin) links rotacal::postproc"

# --- 2. the example's poses against rotacal compensate --------------------------------------------
R=$PREFIX/bin/rotacal
W=$TMP/work
mkdir -p "$W"
"$R" plan --cycle touch154 --machine "$SRC/examples/machines/ac_trunnion.json" -o "$W/plan.json" >/dev/null
"$R" simulate --plan "$W/plan.json" --truth "$SRC/examples/truth/table4_mean.json" --noise-um 0.7 --seed 1 \
  --dialect linuxcnc -o "$W/results.txt" >/dev/null
"$R" analyze --plan "$W/plan.json" --results "$W/results.txt" --dialect linuxcnc --json "$W/REPORT.json" >/dev/null
POSES=$SRC/examples/cam-post/poses.csv
# The CSV's angles read as LinuxCNC counts them, so that the program below carries them unchanged.
"$POST" "$W/REPORT.json" "$POSES" linuxcnc >"$W/post.csv" || fail "cam_post failed"
# The same poses as a LinuxCNC program: a safe first move of Z alone (what `rotacal check` wants),
# then one G1 per pose.
{
  echo "G21"
  echo "G17 G40 G49 G54 G80 G90 G94"
  echo "G0 Z390.0000"
  grep -v -E '^(#|[A-Za-z]|$)' "$POSES" |
    awk -F, '{printf "G1 X%.4f Y%.4f Z%.4f A%.4f C%.4f F1000.0\n", $1, $2, $3, $4, $5}'
  echo "M2"
} >"$W/poses.ngc"
# End points against end points: a deviation bound so large that compensate splits no move (the
# example does not subdivide; compensateMove is the call for that).
"$R" compensate --program "$W/poses.ngc" --report "$W/REPORT.json" --dialect linuxcnc --max-deviation-um 1000 \
  -o "$W/poses_c.ngc" >/dev/null

# compare PROGRAM: the G1 end points of PROGRAM (axis words are modal: compensate writes a word
# only where it changes) against the example's rows, to one unit of the printed 4th decimal (both
# round the same numbers: a mismatch is a different computation).
compare() {
  awk -F, -v prog="$1" '
    BEGIN {
      while ((getline line < prog) > 0) {
        if (line !~ /^G1 /) continue
        n_p++
        split(line, w, " ")
        for (i in w) { l = substr(w[i], 1, 1); if (index("XYZAC", l)) last[l] = substr(w[i], 2) + 0 }
        for (k = 1; k <= 5; k++) { l = substr("XYZAC", k, 1); p[n_p, l] = last[l] }
      }
    }
    /^#/ || /^[a-z]/ { next }
    {
      n++
      split("X Y Z A C", L, " ")
      for (k = 1; k <= 5; k++) { d = $k - p[n, L[k]]; if (d < 0) d = -d; if (d > worst) worst = d }
      if ($6 > shift) shift = $6
    }
    END {
      printf "%d poses, %d program moves, largest difference %.4f (mm or deg), largest compensation shift %.2f um\n", n, n_p, worst, shift
      exit !(n > 0 && n == n_p && worst <= 1.01e-4 && shift > 10)
    }' "$W/post.csv"
}
OUT=$(compare "$W/poses_c.ngc") || { cat "$W/post.csv" "$W/poses_c.ngc" >&2; fail "cam_post disagrees with rotacal compensate: $OUT"; }
step "cam_post = rotacal compensate: $OUT"
# The comparison can fail: the uncompensated program differs by the compensation itself.
if OUT=$(compare "$W/poses.ngc"); then fail "the comparison does not tell the uncompensated program apart: $OUT"; fi
step "and it refuses the uncompensated program: $OUT"

# --- 3. Debian packages ---------------------------------------------------------------------------
VERSION=$("$R" --version | awk '{print $2}')
ARCH=$(dpkg --print-architecture)
rm -f "$BUILD"/rotacal_*.deb "$BUILD"/rotacal-dev_*.deb
(cd "$BUILD" && cpack -G DEB) >"$TMP/cpack.log" 2>&1 || { cat "$TMP/cpack.log" >&2; fail "cpack -G DEB failed"; }
DEB=$BUILD/rotacal_${VERSION}_${ARCH}.deb
DEV=$BUILD/rotacal-dev_${VERSION}_${ARCH}.deb
[ -f "$DEB" ] || { ls "$BUILD"/*.deb >&2 || true; fail "no $DEB"; }
[ -f "$DEV" ] || fail "no $DEV"
dpkg-deb -c "$DEB" >"$TMP/deb.list"
grep -q ' \./usr/bin/rotacal$' "$TMP/deb.list" || fail "$DEB has no /usr/bin/rotacal"
if grep -q -E '\.(hpp|a)$' "$TMP/deb.list"; then fail "$DEB carries development files"; fi
DEPENDS=$(dpkg-deb -f "$DEB" Depends)
for lib in libc6 libstdc++6 libfmt libsqlite3; do
  [[ "$DEPENDS" == *"$lib"* ]] || fail "$DEB: Depends ($DEPENDS) lacks $lib"
done
[ -n "$(dpkg-deb -f "$DEB" Maintainer)" ] || fail "$DEB has no Maintainer"
DESC=$(dpkg-deb -f "$DEB" Description)
SYNOPSIS=${DESC%%$'\n'*}
[ -n "$SYNOPSIS" ] && [ ${#SYNOPSIS} -le 80 ] && [ "$DESC" != "$SYNOPSIS" ] ||
  fail "$DEB: Description needs a synopsis of at most 80 characters and an extended description: '$DESC'"
[ "$(dpkg-deb -f "$DEB" Version)" = "$VERSION" ] || fail "$DEB: Version is not $VERSION"
X=$TMP/extracted
dpkg-deb -x "$DEB" "$X"
[ "$("$X/usr/bin/rotacal" --version)" = "rotacal $VERSION" ] || fail "the packaged rotacal --version is not 'rotacal $VERSION'"
"$X/usr/bin/rotacal" compensate --help >/dev/null || fail "the packaged rotacal compensate --help fails"
step "$(basename "$DEB"): $(stat -c %s "$DEB") bytes, Depends: $DEPENDS"

dpkg-deb -c "$DEV" >"$TMP/dev.list"  # a list first: grep -q closing the pipe would fail dpkg-deb
grep -q '/usr/include/rotacal/postproc/compensate_program.hpp$' "$TMP/dev.list" || fail "$DEV lacks the headers"
grep -q '/rotacalConfig.cmake$' "$TMP/dev.list" || fail "$DEV lacks rotacalConfig.cmake"
if grep -q '/usr/bin/' "$TMP/dev.list"; then fail "$DEV carries the executable"; fi
dpkg-deb -x "$DEV" "$X"
build_example "$X/usr" "$TMP/post-deb"
"$TMP/post-deb/cam_post" "$W/REPORT.json" "$POSES" linuxcnc | cmp -s - "$W/post.csv" ||
  fail "the example built against $DEV prints something else"
step "$(basename "$DEV"): $(stat -c %s "$DEV") bytes, Depends: $(dpkg-deb -f "$DEV" Depends); the example builds against it"
# What `apt install ./rotacal_*.deb` would do (simulated: nothing is installed): the Depends resolve.
apt-get install -s "$DEB" "$DEV" >"$TMP/apt.log" 2>&1 && grep -q '^Inst rotacal ' "$TMP/apt.log" &&
  grep -q '^Inst rotacal-dev ' "$TMP/apt.log" || { cat "$TMP/apt.log" >&2; fail "apt-get install -s of the packages fails"; }
step "apt-get install -s: $(grep -c '^Inst ' "$TMP/apt.log") packages to install, the Depends resolve"
step "OK in $(($(date +%s) - START)) s"
