#!/usr/bin/env bash
# The manual pages of rotacal, made by help2man from the tool's own --help (so that they cannot
# drift from it): rotacal.1 and one rotacal-<command>.1 per subcommand `rotacal --help` lists
# (rotacal-<command>-<sub>.1 for a command's own subcommands, e.g. rotacal-history-add.1), each
# gzipped as Debian wants them (gzip -9n: no name or time in the header). The build calls it
# (cli/CMakeLists.txt, target rotacal_man) when help2man is installed; the pages are installed
# under share/man/man1 with the tool.
# Usage: scripts/make-man.sh ROTACAL_BINARY VERSION OUTDIR
set -euo pipefail
[ $# = 3 ] || { echo "usage: $0 ROTACAL_BINARY VERSION OUTDIR" >&2; exit 2; }
BIN=$(readlink -f "$1")
VERSION=$2
OUT=$3
command -v help2man >/dev/null || { echo "make-man: help2man is not installed (scripts/install-deps.sh)" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
# The tool is run as `rotacal` from PATH, so that its usage lines name `rotacal`, not the build path;
# a subcommand through a wrapper named rotacal-<command>, the name its page carries.
mkdir -p "$TMP/bin" "$OUT"
ln -s "$BIN" "$TMP/bin/rotacal"
export PATH="$TMP/bin:$PATH"
rm -f "$OUT"/rotacal*.1.gz

# subcommands ARGS...: "name<TAB>description" per subcommand that `rotacal ARGS --help` lists.
subcommands() {
  rotacal "$@" --help | awk '/^Subcommands:/ { s = 1; next }
    s && /^  [a-z]/ { name = $1; sub(/^  [^ ]+ +/, ""); print name "\t" $0 }'
}

page() {  # page NAME DESCRIPTION SEE_ALSO ARGS...: NAME.1.gz from `rotacal ARGS --help`
  local name=$1 desc=$2 see=$3
  shift 3
  if [ $# -gt 0 ]; then
    printf '#!/bin/sh\nexec rotacal %s "$@"\n' "$*" >"$TMP/bin/$name"
    chmod +x "$TMP/bin/$name"
  fi
  printf '[SEE ALSO]\n%s\n' "$see" >"$TMP/$name.h2m"
  help2man --no-info --no-discard-stderr --version-string="$VERSION" --section=1 \
    --source="rotacal $VERSION" --manual="rotacal manual" --name="$desc" \
    --include="$TMP/$name.h2m" --output="$TMP/$name.1" "$name"
  gzip -9nc "$TMP/$name.1" >"$OUT/$name.1.gz"
}

see_main=""
while IFS=$'\t' read -r cmd desc; do
  roff=${cmd//-/\\-}  # a hyphen in roff is \-
  see_main+="${see_main:+,\n}.BR rotacal\\-$roff (1)"
  page "rotacal-$cmd" "$desc" ".BR rotacal (1)" "$cmd"
  while IFS=$'\t' read -r sub sdesc; do
    page "rotacal-$cmd-$sub" "$sdesc" ".BR rotacal\\-$roff (1)" "$cmd" "$sub"
  done < <(subcommands "$cmd")
done < <(subcommands)
page rotacal "calibrate the rotary axes of five-axis machine tools with a touch probe" "$(printf '%b' "$see_main")"
echo "make-man: $(ls "$OUT"/*.1.gz | wc -l) pages in $OUT"
