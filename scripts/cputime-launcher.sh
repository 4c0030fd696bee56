#!/usr/bin/env bash
# cputime-launcher.sh LOG COMMAND...: runs COMMAND (a compile or a link, as CMake's
# RULE_LAUNCH_COMPILE / RULE_LAUNCH_LINK) and appends "user+sys seconds<TAB>output file" to LOG.
# CPU time, not wall time: on a machine shared with other builds, wall time measures the others.
# scripts/build-profile.sh sets it up and sums the log.
log=$1
shift
out=""
prev=""
for a in "$@"; do
  [ "$prev" = "-o" ] && out=$a
  [ -z "$out" ] && [[ "$a" == *.a ]] && out=$a    # ar qc LIB.a OBJECTS...
  prev=$a
done
tf=$(mktemp)
/usr/bin/time -f "%U %S" -o "$tf" "$@"
rc=$?
read -r u s <"$tf" || true
rm -f "$tf"
[ -n "${u:-}" ] && awk -v u="$u" -v s="$s" -v o="$out" 'BEGIN { printf "%.2f\t%s\n", u + s, o }' >>"$log"
exit $rc
