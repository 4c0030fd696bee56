#!/usr/bin/env bash
# Installs what rotacal needs to build and test, from Debian 12's packages only.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
# linuxcnc-uspace: LinuxCNC's own interpreter (rs274), which reads our LinuxCNC programs in the
# tests, and the controller of the end-to-end tests (tests/e2e); linuxcnc-uspace-dev: halcompile,
# which builds their realtime virtual probe. --no-install-recommends keeps the recommended RT
# kernel and Qt stack off the machine. chromium: the headless browser of the report tests (label
# browser); libpng-dev: their screenshot check; libsqlite3-dev: `rotacal history`;
# libboost-math-dev: the distributions of core/statistics.cpp (header-only); clang and
# libclang-rt-14-dev: libFuzzer and the sanitizer runtimes of scripts/fuzz.sh (tests/fuzz);
# dpkg-dev (dpkg-shlibdeps) and file: the Depends of `cpack -G DEB`; lintian: Debian's checks of
# those packages (both scripts/package-check.sh).
$SUDO apt-get install -y --no-install-recommends \
  build-essential cmake libeigen3-dev libfmt-dev nlohmann-json3-dev libcli11-dev \
  libgtest-dev libgmock-dev linuxcnc-uspace linuxcnc-uspace-dev \
  libsqlite3-dev libpng-dev chromium libboost-math-dev clang libclang-rt-14-dev dpkg-dev file lintian
