# bash completion for rotacal: its commands, each command's options, the values of the options
# that take one of a few words (--dialect, --cycle, ...), and file names for the rest.
# Installed as /usr/share/bash-completion/completions/rotacal. tests/cli/completion_test.sh checks
# that it names every command and option that `rotacal --help` and `rotacal COMMAND --help` list.

_rotacal() {
  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]}
  local commands="plan generate simulate analyze diagnose uncertainty design compensate report history check comp-table"
  local cmd="" sub="" i w
  for ((i = 1; i < COMP_CWORD; i++)); do
    w=${COMP_WORDS[i]}
    case $w in
      -*) ;;
      *)
        if [[ -z $cmd && " $commands " == *" $w "* ]]; then
          cmd=$w
        elif [[ $cmd == history && -z $sub && ($w == add || $w == show) ]]; then
          sub=$w
        fi
        ;;
    esac
  done

  # The value of the previous option.
  local dialects="linuxcnc fanuc haas siemens heidenhain okuma"
  case $prev in
    --dialect)
      case $cmd in
        simulate | analyze | diagnose) dialects="csv $dialects" ;;
        compensate) dialects="linuxcnc fanuc haas siemens okuma" ;;
        comp-table) dialects="linuxcnc fanuc siemens csv" ;;
      esac
      mapfile -t COMPREPLY < <(compgen -W "$dialects" -- "$cur")
      return
      ;;
    --cycle)
      mapfile -t COMPREPLY < <(compgen -W "touch154 spheres3 rtest spaceframe tooltip one_sphere probe_qual" -- "$cur")
      return
      ;;
    --method)
      mapfile -t COMPREPLY < <(compgen -W "lsq_per_point lsq_rigid_setup closed_form" -- "$cur")
      return
      ;;
    --criterion)
      mapfile -t COMPREPLY < <(compgen -W "A D" -- "$cur")
      return
      ;;
    --axis)
      mapfile -t COMPREPLY < <(compgen -W "A B C" -- "$cur")
      return
      ;;
    --seed | --noise-um | --start-s | --machine-seed | --mc-runs | --mc-seed | --alpha | --runs | --threads | \
      --points | --a-deg | --c-deg | --exchange-passes | --sweep | --max-deviation-um | --step-deg | \
      --program-origin | --time | --machine-id | --set | --methods | --table-holds | --tolerance)
      return  # a number or a name: nothing to offer
      ;;
    -o | --output | --machine | --plan | --truth | --contributors | --truth-out | --results | --json | --html | \
      --text | --offsets | --compensated-with | --program | --report | --db)
      compopt -o filenames 2>/dev/null
      mapfile -t COMPREPLY < <(compgen -f -- "$cur")
      return
      ;;
  esac

  local opts
  case $cmd in
    "") opts="$commands -h --help --version -q --quiet" ;;
    plan) opts="--cycle --machine --set -o --output --show-options" ;;
    generate) opts="--plan --dialect -o --output" ;;
    simulate) opts="--plan --truth --noise-um --seed --start-s --contributors --machine-seed --truth-out --dialect -o --output" ;;
    analyze) opts="--plan --results --dialect --method --json --html --text --offsets --force --write-insignificant --tolerance --contributors --mc-runs --mc-seed --compensated-with" ;;
    diagnose) opts="--plan --results --dialect --json --html --text --alpha --contributors" ;;
    uncertainty) opts="--plan --contributors --runs --seed --combined-only --json --exact --threads --methods --truth --text" ;;
    design) opts="--cycle --machine --contributors --points --criterion --a-deg --c-deg --exchange-passes --sweep --runs --seed -o --output --json" ;;
    compensate) opts="--program --report --dialect --machine --program-origin -o --output --max-deviation-um --table-holds --force" ;;
    report) opts="--html" ;;
    history)
      case $sub in
        "") opts="add show" ;;
        add) opts="--machine-id --db --time --plan" ;;
        show) opts="--machine-id --db --html --json --alpha" ;;
      esac
      ;;
    check) opts="--dialect --machine --plan --part-program" ;;
    comp-table) opts="--report --dialect --axis --machine --step-deg -o --output --force --write-insignificant" ;;
  esac
  [[ -n $cmd ]] && opts="$opts -h --help -q --quiet"
  # A positional argument (report's document, check's program, history add's report): a file name.
  if [[ $cur != -* && ($cmd == report || $cmd == check || $sub == add) ]]; then
    compopt -o filenames 2>/dev/null
    mapfile -t COMPREPLY < <(compgen -f -- "$cur")
  else
    mapfile -t COMPREPLY < <(compgen -W "$opts" -- "$cur")
  fi
}
complete -F _rotacal rotacal
