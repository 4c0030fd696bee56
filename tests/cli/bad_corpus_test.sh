#!/usr/bin/env bash
# The bad-input corpus (tests/data/bad/MANIFEST.tsv, issue 14): runs the real `rotacal` on each
# file with its command and checks, twice (once with no output file, once with every output
# already there): the exit code; stderr is exactly one line, `rotacal: error: ` (exit 1) or
# `rotacal: usage error: ` (exit 2), containing the fragment and naming what the manifest says
# (`line`: the input file and a line >= 1, `in`: the input file, `out`: the output path);
# nothing written to stdout; and every file of the scratch directory (the input's copy, the
# history database, an earlier output) byte-identical afterwards, with no file added.
#   bad_corpus_test.sh ROTACAL [MANIFEST] [FILTER]   (FILTER: a substring of the file names to run)
set -uo pipefail
RC=$1
DIR=$(cd "$(dirname "${2:-$(dirname "$0")/../data/bad/MANIFEST.tsv}")" && pwd)
MANIFEST=$DIR/$(basename "${2:-MANIFEST.tsv}")
FILTER=${3:-}
BASE=$DIR/base
RUNAS=()
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null; then
  # root writes into read-only directories: the {rodir} entries run as nobody
  RUNAS=(setpriv --reuid=65534 --regid=65534 --clear-groups)
fi
SCRATCH=$(mktemp -d)
chmod 755 "$SCRATCH"
trap 'chmod -R u+w "$SCRATCH" 2>/dev/null; rm -rf "$SCRATCH"' EXIT
n=0
failed=0
fail() { echo "FAIL $file [$cmd] (run $run): $*"; [ -s "$T/stderr" ] && sed 's/^/    stderr: /' "$T/stderr" | head -c 600; failed=$((failed + 1)); }
snapshot() { (cd "$T" && find . -path ./stdout -prune -o -path ./stderr -prune -o -print | sort | while read -r f; do
  if [ -f "$f" ]; then echo "$f $(sha256sum <"$f" | cut -c1-64)"; else echo "$f"; fi; done); }
while IFS=$'\t' read -r file cmd code fragment names; do
  case "$file" in '#'*|'') continue ;; esac
  if [ -n "$FILTER" ] && [[ "$file" != *"$FILTER"* ]]; then continue; fi
  n=$((n + 1))
  for run in 1 2; do
    T=$SCRATCH/$n.$run
    mkdir -p "$T/in" "$T/out" "$T/ro" "$T/db"
    in=$T/in/$(basename "$file")
    cp "$DIR/$file" "$in"
    cp "$BASE/history.db" "$T/db/history.db"
    chmod -R a+rwX "$T"
    chmod 555 "$T/ro"
    args=${cmd//\{in\}/$in}
    args=${args//\{out\}/$T/out/out}
    args=${args//\{base\}/$BASE}
    args=${args//\{db\}/$T/db/history.db}
    args=${args//\{nodir\}/$T/missing/dir}
    args=${args//\{rodir\}/$T/ro}
    args=${args//\{tmp\}/$T}
    read -r -a argv <<<"$args"
    if [ $run = 2 ]; then
      # every output already there: it must come out byte-identical
      for a in "${argv[@]}"; do
        case "$a" in "$T/out/"*|"$T/ro/"*) [ -d "$(dirname "$a")" ] && printf 'an earlier output\n' >"$a" 2>/dev/null ;; esac
      done
      chmod 555 "$T/ro"
    fi
    before=$(snapshot)
    runas=()
    if [[ "$cmd" == *"{rodir}"* ]]; then runas=("${RUNAS[@]}"); fi
    timeout 120 "${runas[@]}" "$RC" "${argv[@]}" >"$T/stdout" 2>"$T/stderr"
    rc=$?
    after=$(snapshot)
    if [ "$rc" != "$code" ]; then fail "exit $rc, expected $code"; continue 2; fi
    if [ "$(wc -l <"$T/stderr")" != 1 ] || [ "$(tail -c1 "$T/stderr" | od -An -c | tr -d ' ')" != '\n' ]; then
      fail "stderr is not exactly one line"; continue 2
    fi
    msg=$(cat "$T/stderr")
    if [ "$code" = 1 ] && [[ "$msg" != "rotacal: error: "* ]]; then fail "not 'rotacal: error: ...'"; continue 2; fi
    if [ "$code" = 2 ] && [[ "$msg" != "rotacal: usage error: "* ]]; then fail "not 'rotacal: usage error: ...'"; continue 2; fi
    if [ "$fragment" != - ] && [[ "$msg" != *"$fragment"* ]]; then fail "no '$fragment' in the message"; continue 2; fi
    case "$names" in
      line) [[ "$msg" =~ $(basename "$file" | sed 's/[.[\*^$]/\\&/g'):[1-9][0-9]*:\  ]] || { fail "does not name $(basename "$file"):LINE"; continue 2; } ;;
      in) [[ "$msg" == *"$(basename "$file")"* ]] || { fail "does not name the input file"; continue 2; } ;;
      out) [[ "$msg" == *"$T"* ]] || { fail "does not name the output path"; continue 2; } ;;
    esac
    # (check lists every violation on stdout; every other command prints nothing on failure)
    if [ -s "$T/stdout" ] && [[ "$cmd" != check\ * ]]; then fail "wrote to stdout"; continue 2; fi
    if [ "$before" != "$after" ]; then
      fail "files changed or added: $(diff <(echo "$before") <(echo "$after") | grep '^[<>]' | head -3 | tr '\n' ' ')"
      continue 2
    fi
  done
done <"$MANIFEST"
echo "bad-input corpus: $n files, $failed failed"
[ "$n" -ge 1 ] && [ "$failed" = 0 ]
