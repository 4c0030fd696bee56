#!/usr/bin/env bash
# The library for CAM posts and the Debian packages, checked from an existing build dir
# (.ci/run calls it after scripts/test.sh):
#   1. `cmake --install` into a temporary prefix: the public headers only, librotacal.so with its
#      SONAME (librotacal.so.<major>), no text relocations, and no symbol exported but the public
#      API's; examples/cam-post configured and built against that prefix only
#      (find_package(rotacal)), with -Werror; a post as a plugin (a shared library) linking it;
#   2. a REPORT.json made with the installed CLI (the bundled example: touch154 on
#      examples/machines/ac_trunnion.json, 000 Table 4's errors, 0.7 um noise); the example's
#      compensated poses compared with `rotacal compensate` on a LinuxCNC program of the same poses
#      (equal to the printed 0.1 um / 0.1 mdeg), and the comparison shown to fail on the
#      uncompensated program;
#   3. `cpack -G DEB`: rotacal_<version>_<arch>.deb (the tool: files, Depends, Maintainer, the
#      extracted binary's --version; a manual page per command that man renders without a warning,
#      the bash completion matching the binary's commands and options, README, LICENSE, CHANGELOG,
#      the example machines), librotacal<major>_<version>_<arch>.deb (the library and its
#      SONAME link) and rotacal-dev_<version>_<arch>.deb (extracted with the library, the example
#      built against them and giving the same output); lintian on the three where it is installed
#      (an error fails, warnings are printed); `apt-get install -s` of the three resolves.
# Usage: scripts/package-check.sh [BUILD_DIR]   (default build, configured; it builds only what it
# packages, and leaves the packages in it)
set -euo pipefail
cd "$(dirname "$0")/.."
SRC=$PWD
BUILD=$(cd "${1:-build}" && pwd)
START=$(date +%s)
# What the packages hold, and only that (the install rules do not build:
# CMAKE_SKIP_INSTALL_ALL_DEPENDENCY).
# rotacal_man: the manual pages (help2man, which scripts/install-deps.sh installs: without it the
# build dir has no such target).
cmake --build "$BUILD" --target rotacal rotacal_shared rotacal_man -j"$(nproc)" >/dev/null ||
  { echo "package-check: cannot build rotacal, librotacal and the manual pages (help2man installed?) in $BUILD" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "package-check: FAIL: $*" >&2; exit 1; }
step() { echo "package-check: $*"; }

# --- 1. install, and build the example against the installed package ---------------------------
PREFIX=$TMP/prefix
cmake --install "$BUILD" --prefix "$PREFIX" >"$TMP/install.log"
for f in bin/rotacal include/rotacal/rotacal.hpp include/rotacal/version.hpp include/rotacal/export.hpp; do
  [ -e "$PREFIX/$f" ] || fail "not installed: $f"
done
# The internal headers and static libraries are no interface: nothing but the public headers.
EXTRA=$(cd "$PREFIX" && find include lib \( -name '*.a' -o -path 'include/rotacal/*/*' \) -print | head -3)
[ -z "$EXTRA" ] || fail "installed beyond the public library: $EXTRA"
CONFIG=$(find "$PREFIX" -name rotacalConfig.cmake)
[ -n "$CONFIG" ] || fail "no rotacalConfig.cmake under $PREFIX"
for f in rotacalConfigVersion.cmake rotacalTargets.cmake; do
  [ -e "$(dirname "$CONFIG")/$f" ] || fail "not installed: $f beside $CONFIG"
done
LIBDIR=$(cd "$(dirname "$CONFIG")/../.." && pwd)
[ -L "$LIBDIR/librotacal.so" ] || fail "no link librotacal.so in $LIBDIR"
REAL=$(readlink -f "$LIBDIR/librotacal.so")
readelf -d "$REAL" >"$TMP/dynamic.txt"
SONAME=$(sed -n 's/.*Library soname: \[\(.*\)\]/\1/p' "$TMP/dynamic.txt")
MAJOR=$(sed -n 's/^#define ROTACAL_VERSION_MAJOR \([0-9]*\)$/\1/p' "$PREFIX/include/rotacal/version.hpp")
[ -n "$MAJOR" ] && [ "$SONAME" = "librotacal.so.$MAJOR" ] || fail "$REAL: SONAME '$SONAME', expected librotacal.so.$MAJOR"
[ "$(readlink -f "$LIBDIR/$SONAME")" = "$REAL" ] || fail "no link $SONAME to $(basename "$REAL")"
if grep -q TEXTREL "$TMP/dynamic.txt"; then fail "$REAL has text relocations: a static library in it is not PIC"; fi
# Exported: the public API and nothing else (no Eigen, fmt, nlohmann, nor the internal code,
# whose types would otherwise be part of the ABI).
nm -D --defined-only -C "$REAL" | cut -d' ' -f3- >"$TMP/exported.txt"
BAD=$(grep -v -E '^((typeinfo|typeinfo name|vtable) for )?rotacal::(Error|Compensator|compensate|check|version)\b' "$TMP/exported.txt" | head -5 || true)
[ -z "$BAD" ] || fail "$REAL exports more than the public API: $BAD"
step "installed into a temporary prefix ($(find "$PREFIX" -type f | wc -l) files); $(basename "$REAL"): SONAME $SONAME, no TEXTREL, $(wc -l <"$TMP/exported.txt") symbols exported, all of the public API"

build_example() {  # build_example PREFIX_PATH BUILD_DIR
  cmake -S "$SRC/examples/cam-post" -B "$2" -DCMAKE_PREFIX_PATH="$1" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS=-Werror >"$2.log" 2>&1 || { cat "$2.log" >&2; fail "examples/cam-post does not configure against $1"; }
  cmake --build "$2" -j2 >>"$2.log" 2>&1 || { cat "$2.log" >&2; fail "examples/cam-post does not build against $1"; }
}
build_example "$PREFIX" "$TMP/post"
POST=$TMP/post/cam_post
step "examples/cam-post built against the installed package"

# A post as a plugin (a shared library the CAM system loads) links the library too.
mkdir -p "$TMP/plugin"
cat >"$TMP/plugin/CMakeLists.txt" <<'EOF'
cmake_minimum_required(VERSION 3.22)
project(rotacal_plugin_check LANGUAGES CXX)
find_package(rotacal 0.1 REQUIRED)
add_library(post_plugin SHARED plugin.cpp)
target_link_libraries(post_plugin PRIVATE rotacal::rotacal)
target_link_options(post_plugin PRIVATE -Wl,--no-undefined)
EOF
cat >"$TMP/plugin/plugin.cpp" <<'EOF'
#include <rotacal/rotacal.hpp>
extern "C" double post_plugin_shift_um(const char* report_json, double x, double y, double z, double a, double c) {
  const rotacal::Compensator comp({{"REPORT.json", report_json}}, "linuxcnc");
  return comp.compensate({x, y, z, {a, c}}).shift_um;
}
EOF
{ cmake -S "$TMP/plugin" -B "$TMP/plugin/build" -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_BUILD_TYPE=Release &&
  cmake --build "$TMP/plugin/build" -j2; } >"$TMP/plugin.log" 2>&1 ||
  { cat "$TMP/plugin.log" >&2; fail "a shared library does not link rotacal::rotacal"; }
step "a shared library (post plugin) links rotacal::rotacal"

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
rm -f "$BUILD"/rotacal_*.deb "$BUILD"/librotacal*.deb "$BUILD"/rotacal-dev_*.deb
(cd "$BUILD" && cpack -G DEB) >"$TMP/cpack.log" 2>&1 || { cat "$TMP/cpack.log" >&2; fail "cpack -G DEB failed"; }
DEB=$BUILD/rotacal_${VERSION}_${ARCH}.deb
LIBDEB=$BUILD/librotacal${MAJOR}_${VERSION}_${ARCH}.deb
DEV=$BUILD/rotacal-dev_${VERSION}_${ARCH}.deb
for f in "$DEB" "$LIBDEB" "$DEV"; do
  [ -f "$f" ] || { ls "$BUILD"/*.deb >&2 || true; fail "no $f"; }
done
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
[[ "$("$X/usr/bin/rotacal" --version)" =~ ^rotacal\ $VERSION\ \(git\ [^\ ]+\)$ ]] ||
  fail "the packaged rotacal --version is not 'rotacal $VERSION (git REVISION)'"
"$X/usr/bin/rotacal" compensate --help >/dev/null || fail "the packaged rotacal compensate --help fails"
# What a shop gets with the tool: a manual page per command (gzipped), each rendered by man without
# a warning; the bash completion, which bash accepts and which names every command and option of
# the packaged binary; the documents; the example machines.
COMMANDS=$("$X/usr/bin/rotacal" --help | awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }')
for page in rotacal $(printf 'rotacal-%s\n' $COMMANDS); do
  grep -q " \./usr/share/man/man1/$page\.1\.gz\$" "$TMP/deb.list" || fail "$DEB has no manual page $page.1.gz"
done
N_MAN=$(grep -c '/usr/share/man/man1/.*\.1\.gz$' "$TMP/deb.list")
for page in "$X"/usr/share/man/man1/*.1.gz; do
  MAN_WARN=$(LC_ALL=C.UTF-8 MANWIDTH=80 man --warnings -E UTF-8 -l "$page" 2>&1 >/dev/null) || fail "man -l $page fails: $MAN_WARN"
  [ -z "$MAN_WARN" ] || fail "man -l $(basename "$page") warns: $MAN_WARN"
done
MAN_LINES=$(LC_ALL=C.UTF-8 MANWIDTH=80 man -l "$X/usr/share/man/man1/rotacal-compensate.1.gz" 2>/dev/null | wc -l)
[ "$MAN_LINES" -gt 20 ] || fail "man -l rotacal-compensate.1.gz renders $MAN_LINES lines"
COMPLETION=$X/usr/share/bash-completion/completions/rotacal
[ -f "$COMPLETION" ] || fail "$DEB has no bash completion"
bash -n "$COMPLETION" || fail "bash -n rejects the packaged completion"
COMP_OUT=$(bash "$SRC/tests/cli/completion_test.sh" "$X/usr/bin/rotacal" "$COMPLETION" 2>&1) ||
  fail "the packaged completion does not match the packaged rotacal: $COMP_OUT"
for f in README.md LICENSE CHANGELOG.md copyright changelog.gz examples/machines/ac_trunnion.json; do
  [ -f "$X/usr/share/doc/rotacal/$f" ] || fail "$DEB has no /usr/share/doc/rotacal/$f"
done
# Every link of the packaged README that stays inside the package must lead to a packaged file.
for link in $(grep -o '](\(docs/[^)#]*\)' "$X/usr/share/doc/rotacal/README.md" | sed 's/^](//'); do
  [ -f "$X/usr/share/doc/rotacal/$link" ] || fail "$DEB: README links to $link, which is not in the package"
done
N_EX=$(ls "$X"/usr/share/doc/rotacal/examples/machines/*.json | wc -l)
[ "$N_EX" = "$(ls "$SRC"/examples/machines/*.json | wc -l)" ] || fail "$DEB has $N_EX of the example machines"
step "$(basename "$DEB"): $N_MAN manual pages (each rendered by man -l without a warning), the bash completion (${COMP_OUT#completion_test: OK: }), README with docs/, LICENSE, CHANGELOG, $N_EX example machines"
step "$(basename "$DEB"): $(stat -c %s "$DEB") bytes, Depends: $DEPENDS"

dpkg-deb -c "$LIBDEB" >"$TMP/lib.list"
# Debian policy 9.1.1: shared libraries in the multiarch directory.
MULTIARCH=$(dpkg-architecture -qDEB_HOST_MULTIARCH)
grep -q "/usr/lib/$MULTIARCH/$SONAME -> $(basename "$REAL")\$" "$TMP/lib.list" || fail "$LIBDEB lacks the link $SONAME in /usr/lib/$MULTIARCH"
grep -q "/usr/lib/$MULTIARCH/$(basename "$REAL")\$" "$TMP/lib.list" || fail "$LIBDEB lacks /usr/lib/$MULTIARCH/$(basename "$REAL")"
if grep -q -E '(\.hpp|\.cmake|librotacal\.so)$' "$TMP/lib.list"; then fail "$LIBDEB carries development files"; fi
# What a post's package will depend on (dpkg-shlibdeps reads it): the compatibility rule.
SHLIBS=$(dpkg-deb -I "$LIBDEB" shlibs) || fail "$LIBDEB has no shlibs file"
[[ "$SHLIBS" == "librotacal $MAJOR librotacal$MAJOR (>= $VERSION), librotacal$MAJOR (<< "* ]] ||
  fail "$LIBDEB: shlibs is '$SHLIBS'"
[ "$(dpkg-deb -I "$LIBDEB" triggers)" = "activate-noawait ldconfig" ] || fail "$LIBDEB has no ldconfig trigger"
step "$(basename "$LIBDEB"): $(stat -c %s "$LIBDEB") bytes, Depends: $(dpkg-deb -f "$LIBDEB" Depends); shlibs: $SHLIBS"

dpkg-deb -c "$DEV" >"$TMP/dev.list"  # a list first: grep -q closing the pipe would fail dpkg-deb
grep -q '/usr/include/rotacal/rotacal.hpp$' "$TMP/dev.list" || fail "$DEV lacks the headers"
grep -q '/rotacalConfig.cmake$' "$TMP/dev.list" || fail "$DEV lacks rotacalConfig.cmake"
grep -q "/usr/lib/$MULTIARCH/librotacal.so -> $SONAME\$" "$TMP/dev.list" || fail "$DEV lacks the link librotacal.so in /usr/lib/$MULTIARCH"
if grep -q -E '/usr/bin/|/usr/include/rotacal/[a-z_]+/' "$TMP/dev.list"; then fail "$DEV carries the executable or internal headers"; fi
XD=$TMP/extracted-dev
dpkg-deb -x "$DEV" "$XD"
dpkg-deb -x "$LIBDEB" "$XD"
build_example "$XD/usr" "$TMP/post-deb"
"$TMP/post-deb/cam_post" "$W/REPORT.json" "$POSES" linuxcnc | cmp -s - "$W/post.csv" ||
  fail "the example built against $DEV prints something else"
step "$(basename "$DEV"): $(stat -c %s "$DEV") bytes, Depends: $(dpkg-deb -f "$DEV" Depends); the example builds against it"
# Debian's own checks, where lintian is installed (scripts/install-deps.sh installs it): errors
# fail, warnings are shown. Left out: the maintainer's mail host (the project has no public
# address yet: cmake/install.cmake's CPACK_PACKAGE_CONTACT), an error in any published package.
if command -v lintian >/dev/null; then
  lintian --suppress-tags bogus-mail-host,bogus-mail-host-in-debian-changelog "$DEB" "$LIBDEB" "$DEV" \
    >"$TMP/lintian.txt" 2>&1 || true
  grep -v 'running with root privileges' "$TMP/lintian.txt" | sed 's/^/package-check: lintian: /' || true
  if grep -q '^E: ' "$TMP/lintian.txt"; then fail "lintian reports errors"; fi
  step "lintian: $(grep -c '^E: ' "$TMP/lintian.txt") errors, $(grep -c '^W: ' "$TMP/lintian.txt") warnings"
else
  step "lintian: not installed, not run"
fi
# What `apt install ./rotacal_*.deb` would do (simulated: nothing is installed): the Depends resolve.
apt-get install -s "$DEB" "$LIBDEB" "$DEV" >"$TMP/apt.log" 2>&1 && grep -q '^Inst rotacal ' "$TMP/apt.log" &&
  grep -q "^Inst librotacal$MAJOR " "$TMP/apt.log" && grep -q '^Inst rotacal-dev ' "$TMP/apt.log" || { cat "$TMP/apt.log" >&2; fail "apt-get install -s of the packages fails"; }
step "apt-get install -s: $(grep -c '^Inst ' "$TMP/apt.log") packages to install, the Depends resolve"
step "OK in $(($(date +%s) - START)) s"
