#!/usr/bin/env bash
# The bash completion (cli/completion/rotacal.bash) against the tool, so that the two cannot drift:
# bash -n accepts it; it names every command `rotacal --help` lists and every option each
# `rotacal COMMAND [SUB] --help` lists (history's add and show included); and, sourced, it
# completes a command, an option of a command and, after --dialect, the dialects --help lists.
# Usage: tests/cli/completion_test.sh ROTACAL COMPLETION_SCRIPT
set -euo pipefail
R=$1
S=$2
fails=0
fail() { echo "completion_test: FAIL: $*" >&2; fails=$((fails + 1)); }
# No `grep -q` after a pipe: it stops reading at the first match, the writer then dies of SIGPIPE
# and, under pipefail, a match reads as a failure (at random, by timing).

bash -n "$S" || { echo "completion_test: FAIL: bash -n rejects $S" >&2; exit 1; }

subcommands() {  # the subcommands `rotacal ARGS --help` lists
  "$R" "$@" --help | awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }'
}
options() {  # the options `rotacal ARGS --help` lists, one a line (-o and --output apart)
  "$R" "$@" --help | grep -oE '^  (-[a-zA-Z],)?--?[a-zA-Z][-a-zA-Z0-9_]*' | sed 's/^ *//' | tr ',' '\n'
}

# The script's list of commands, and each command's branch of its option case.
LIST=$(sed -n 's/^  local commands="\(.*\)"$/\1/p' "$S")
[ -n "$LIST" ] || fail "no 'local commands=\"...\"' line in $S"
branch() {  # the options of COMMAND's case branch ('    plan) opts="..." ;;'), space-padded
  local l
  l=$(sed -n -E "s/^ +$1\) opts=\"([^\"]*)\".*/\1/p" "$S" | head -1)
  [ -z "$l" ] || echo " $l "
}
n_cmd=0
n_opt=0
for cmd in $(subcommands); do
  n_cmd=$((n_cmd + 1))
  [[ " $LIST " == *" $cmd "* ]] || fail "command '$cmd' (rotacal --help) is not in the script's command list"
  subs=$(subcommands "$cmd")
  if [ -n "$subs" ]; then
    for sub in $subs; do
      line=$(branch "$sub")
      [ -n "$line" ] || { fail "no option branch for '$cmd $sub'"; continue; }
      for o in $(options "$cmd" "$sub"); do
        n_opt=$((n_opt + 1))
        [[ "$line" == *" $o "* ]] ||
          [[ $o == -h || $o == --help ]] || fail "option $o of '$cmd $sub' is not in its branch: $line"
      done
    done
    continue
  fi
  line=$(branch "$cmd")
  [ -n "$line" ] || { fail "no option branch for '$cmd'"; continue; }
  for o in $(options "$cmd"); do
    n_opt=$((n_opt + 1))
    [[ "$line" == *" $o "* ]] ||
      [[ $o == -h || $o == --help ]] || fail "option $o of '$cmd' is not in its branch: $line"
  done
done
# Every option that takes a value is in one of the script's value patterns (a file name, a word
# list, or nothing to offer), so that its value is not completed as an option.
for args in $(subcommands | grep -vx history) history:add history:show; do
  for o in $("$R" ${args//:/ } --help | sed -n -E 's/^  (-[a-zA-Z],)?(--[a-zA-Z][-a-zA-Z0-9_]*) [A-Z].*/\2/p'); do
    grep -q -E -- "(^| )$o( \||\))" "$S" || fail "option $o of '${args//:/ }' takes a value: not in a value pattern of the script"
  done
done
[ "$n_cmd" -ge 10 ] || fail "only $n_cmd commands found in rotacal --help"
# And no command in the script that the tool does not have.
for cmd in $LIST; do
  subcommands | grep -x -- "$cmd" >/dev/null || fail "the script completes '$cmd', which rotacal --help does not list"
done

# Sourced: what it offers. compopt works only inside a real completion, so the shell here defines it
# as a no-op (it sets display options, not the words offered).
complete_words() {  # complete_words WORD...: the completions of the last word
  bash -c '
    compopt() { :; }
    source "$0"
    COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1))
    _rotacal
    printf "%s\n" "${COMPREPLY[@]}"' "$S" "$@"
}
[ "$(complete_words rotacal hi)" = history ] || fail "'rotacal hi' does not complete to history"
[ "$(complete_words rotacal compensate --max)" = --max-deviation-um ] || fail "'rotacal compensate --max' does not complete"
[ "$(complete_words rotacal history add --mach)" = --machine-id ] || fail "'rotacal history add --mach' does not complete"
complete_words rotacal analyze --dialect "" | grep -x csv >/dev/null || fail "analyze --dialect does not offer csv"
if complete_words rotacal compensate --dialect "" | grep -x heidenhain >/dev/null; then fail "compensate --dialect offers heidenhain"; fi

# The dialects it offers after --dialect are those the command's --help lists (from the registry).
for c in $(subcommands); do
  want=$("$R" "$c" --help | sed -n 's/^ *--dialect TEXT[A-Z ]* \{2,\}//p' | sed 's/ (.*//' | tr -d '|' | xargs -n1 | sort | xargs)
  [ -n "$want" ] || continue
  got=$(complete_words rotacal "$c" --dialect "" | sort | xargs)
  [ "$got" = "$want" ] || fail "'rotacal $c --dialect' completes to '$got'; its --help lists '$want'"
done

[ "$fails" = 0 ] || exit 1
echo "completion_test: OK: $n_cmd commands and $n_opt options of rotacal --help all in $(basename "$S")"
