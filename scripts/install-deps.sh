#!/usr/bin/env bash
# Installs what rotacal needs to build and test, from Debian 12's packages only.
#   scripts/install-deps.sh             everything: build, tests, packaging
#   scripts/install-deps.sh --runtime   only what running a built `rotacal` needs on a shop PC: the
#                                       runtime libraries it links (ldd build/cli/rotacal: libc,
#                                       libstdc++, libgcc, libfmt, libsqlite3); no compiler, no
#                                       LinuxCNC, no Chromium. The rotacal .deb pulls the same
#                                       through its Depends (apt install ./rotacal_*.deb).
set -euo pipefail
MODE=all
case "${1:-}" in
  "") ;;
  --runtime) MODE=runtime ;;
  *) echo "usage: $0 [--runtime]" >&2; exit 2 ;;
esac
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
if [ "$MODE" = runtime ]; then
  $SUDO apt-get install -y --no-install-recommends libc6 libstdc++6 libgcc-s1 libfmt9 libsqlite3-0
  exit 0
fi
# linuxcnc-uspace: LinuxCNC's own interpreter (rs274), which reads our LinuxCNC programs in the
# tests, and the controller of the end-to-end tests (tests/e2e); linuxcnc-uspace-dev: halcompile,
# which builds their realtime virtual probe. --no-install-recommends keeps the recommended RT
# kernel and Qt stack off the machine. chromium: the headless browser of the report tests (label
# browser); libpng-dev: their screenshot check; libsqlite3-dev: `rotacal history`;
# libboost-math-dev: the distributions of core/statistics.cpp (header-only); clang and
# libclang-rt-14-dev: libFuzzer and the sanitizer runtimes of scripts/fuzz.sh (tests/fuzz);
# dpkg-dev (dpkg-shlibdeps) and file: the Depends of `cpack -G DEB`; lintian: Debian's checks of
# those packages (both scripts/package-check.sh); help2man: the manual pages, made from
# `rotacal COMMAND --help` at build time (scripts/make-man.sh); man-db: package-check renders them.
$SUDO apt-get install -y --no-install-recommends \
  build-essential cmake libeigen3-dev libfmt-dev nlohmann-json3-dev libcli11-dev \
  libgtest-dev libgmock-dev linuxcnc-uspace linuxcnc-uspace-dev \
  libsqlite3-dev libpng-dev chromium libboost-math-dev clang libclang-rt-14-dev dpkg-dev file lintian \
  help2man man-db
