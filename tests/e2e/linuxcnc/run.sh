#!/usr/bin/env bash
# run.sh -- run one of rotacal's LinuxCNC programs, unchanged, on a real LinuxCNC 2.9
# controller (headless, identity kinematics) whose virtual touch probe plays a machine with
# the location errors of a rotacal TRUTH.json. Adapted from shared/tools/linuxcnc-sim/run.sh.
# An A/C machine ("kinematics": "table_ac") runs on xyzac-trt-kins (config/lcsim_xyzac.ini), a
# B/C machine ("table_bc") on xyzbc-trt-kins (config/lcsim_xyzbc.ini), an A/B table ("table_ab") on
# xyzab_tdr_kins (config/lcsim_xyzab.ini), a B head over a C table ("head_table") on trivkins, the
# joints of maxkins (config/lcsim_max.ini; --kins-tcp: maxkins itself), the bridge mill ("head_cb")
# on 5axiskins, its identity type first (config/lcsim_5axis.ini; --kins-tcp: its TCP type).
#
# Usage: run.sh --ngc PROGRAM (--truth TRUTH.json --machine MACHINE.json | --params params.json) --out DIR
#               [--plan PLAN.json] [--pre-ngc OFFSETS.ngc] [--timeout S] [--comp-build DIR]
#               [--c-from-motor] [--comp-file TABLE] [--linear-comp DIR] [--kins-tcp] [--setp FILE]
#   --ngc FILE        the program (rotacal generate --dialect linuxcnc); it runs as written
#   --truth FILE      rotacal-truth/1: the true machine and piece (scripts/truth_params.py)
#   --params FILE     the harness's params.json itself, in place of --truth and --machine: the
#                     harness's own machine (the 5axiskins read-back and pin sessions)
#   --machine FILE    rotacal-machine/1: the nominal piece and probe ball
#   --plan FILE       rotacal-plan/1 of a sphere cycle: its spheres join the virtual piece
#   --out DIR         run directory: LinuxCNC's INI, var file and the program's LOG land here
#   --pre-ngc FILE    a program run first in the same session (the G10 work-offset program
#                     written by rotacal analyze --offsets X.ngc)
#   --timeout S       hard limit for the whole LinuxCNC session (default 900)
#   --comp-build DIR  where halcompile builds vtouchprobe.so (default /tmp/rotacal-e2e-comp)
#   --c-from-motor    the probe reads C from joint 4's motor command (which carries its
#                     compensation table) instead of the joint command
#   --comp-file TABLE joint 4 (C) loads TABLE: COMP_FILE = TABLE, COMP_FILE_TYPE = 0 in [JOINT_4]
#                     (rotacal comp-table --dialect linuxcnc); implies --c-from-motor
#   --linear-comp DIR joints 0, 1, 2 (X, Y, Z) load DIR/joint0.comp, joint1.comp, joint2.comp
#                     (COMP_FILE_TYPE = 0) and the probe reads X, Y, Z from their motor commands:
#                     the controller itself makes the linear axes' positioning errors
#   --kins-tcp        start in the TCP kinematics instead of identity (the INI without
#                     sparm=identityfirst, or its TCP_KINEMATICS line: maxkins): for the
#                     conventions read-back only. Without it, setp lines for a TCP-only module
#                     (maxkins) are kept in params.hal as comments: not loaded, not applied
#   --setp FILE       'setp PIN VALUE' lines applied after the truth's (read-back: rot-point,
#                     offsets of the kinematics and the probe's matching axis lines)
#   --shared          run LinuxCNC in the machine's own namespaces (one session at a time, as
#                     LinuxCNC itself allows); by default, where `unshare` exists, each session
#                     gets its own (scripts/ns_session.sh), so that sessions run side by side
# The program's (LOGOPEN,name) file is copied to DIR/name. Exit status: 0 ok, 1 program or
# controller error (DIR/driver_status.json has the messages), 2 timeout, 3 setup problem.
set -u -o pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
PY=/usr/bin/python3          # Debian's interpreter: it has the linuxcnc and hal modules
export PYTHONDONTWRITEBYTECODE=1   # no __pycache__ in the source tree

NGC="" PRE="" TRUTH="" MACHINE="" PARAMS="" PLAN="" OUT="" TIMEOUT=900 BUILD=/tmp/rotacal-e2e-comp C_MOTOR=0 COMP="" LINCOMP="" TCP=0 SETP="" ISOLATE=1
while [ $# -gt 0 ]; do
    case "$1" in
        --ngc) NGC="$2"; shift 2;;
        --pre-ngc) PRE="$2"; shift 2;;
        --truth) TRUTH="$2"; shift 2;;
        --params) PARAMS="$2"; shift 2;;
        --machine) MACHINE="$2"; shift 2;;
        --plan) PLAN="$2"; shift 2;;
        --out) OUT="$2"; shift 2;;
        --timeout) TIMEOUT="$2"; shift 2;;
        --comp-build) BUILD="$2"; shift 2;;
        --c-from-motor) C_MOTOR=1; shift;;
        --comp-file) COMP="$2"; C_MOTOR=1; shift 2;;
        --linear-comp) LINCOMP="$2"; shift 2;;
        --kins-tcp) TCP=1; shift;;
        --setp) SETP="$2"; shift 2;;
        --shared) ISOLATE=0; shift;;
        -h|--help) sed -n '2,42p' "$0" | sed 's/^# \{0,1\}//'; exit 0;;
        *) echo "run.sh: unknown option $1 (see --help)" >&2; exit 3;;
    esac
done
die() { echo "run.sh: $*" >&2; exit 3; }
abspath() { echo "$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"; }
if [ -n "$PARAMS" ]; then
    [ -n "$NGC" ] && [ -n "$OUT" ] && [ -z "$TRUTH$MACHINE$PLAN" ] || die "--params takes --ngc and --out, not --truth, --machine or --plan"
else
    [ -n "$NGC" ] && [ -n "$TRUTH" ] && [ -n "$MACHINE" ] && [ -n "$OUT" ] || die "--ngc, --truth, --machine and --out are required"
fi
for f in "$NGC" ${TRUTH:+"$TRUTH"} ${MACHINE:+"$MACHINE"} ${PARAMS:+"$PARAMS"} ${PRE:+"$PRE"} ${PLAN:+"$PLAN"} ${COMP:+"$COMP"} ${SETP:+"$SETP"}; do
    [ -f "$f" ] || die "file not found: $f"
done
[[ "$TIMEOUT" =~ ^[0-9]+$ ]] || die "--timeout must be whole seconds"
NGC="$(abspath "$NGC")"
[ -n "$TRUTH" ] && TRUTH="$(abspath "$TRUTH")" MACHINE="$(abspath "$MACHINE")"
[ -n "$PRE" ] && PRE="$(abspath "$PRE")"
[ -n "$PLAN" ] && PLAN="$(abspath "$PLAN")"
[ -n "$COMP" ] && COMP="$(abspath "$COMP")"
if [ -n "$LINCOMP" ]; then
    for j in 0 1 2; do [ -f "$LINCOMP/joint$j.comp" ] || die "file not found: $LINCOMP/joint$j.comp"; done
    LINCOMP="$(cd "$LINCOMP" && pwd)"
fi

command -v linuxcnc >/dev/null || die "linuxcnc not found (Debian package linuxcnc-uspace)"
command -v halcompile >/dev/null || die "halcompile not found (Debian package linuxcnc-uspace-dev)"
"$PY" -c "import linuxcnc, hal" 2>/dev/null || die "$PY cannot import linuxcnc/hal (linuxcnc-uspace)"
[ "$(id -u)" = 0 ] || die "needs root: rtapi_app loads realtime modules only from /usr/lib/linuxcnc/modules"
command -v unshare >/dev/null && command -v nsenter >/dev/null || ISOLATE=0
LOCK=/tmp/linuxcnc.lock      # LinuxCNC allows one instance per namespace set
if [ "$ISOLATE" = 0 ] && [ -e "$LOCK" ]; then
    if pidof milltask rtapi_app linuxcncsvr >/dev/null 2>&1; then
        die "another LinuxCNC instance is running ($LOCK); not starting"
    fi
    echo "run.sh: removing stale $LOCK (no LinuxCNC process alive)"
    rm -f "$LOCK"
fi

mkdir -p "$OUT" || die "cannot create $OUT"
OUT="$(cd "$OUT" && pwd)"
rm -rf "$OUT/config" && mkdir -p "$OUT/config" || die "cannot create $OUT/config"
T_START=$SECONDS

# ---------------------------------------------------- realtime component
# uspace rtapi_app loads realtime modules only from LinuxCNC's module dir
MODDIR=/usr/lib/linuxcnc/modules
mkdir -p "$BUILD" || die "cannot create $BUILD"
# sessions side by side: one builds and installs at a time, and the module is replaced by a
# rename, never rewritten under a running session's loaded copy
exec 9>"$BUILD/.lock" && flock 9 || die "cannot lock $BUILD/.lock"
if [ ! -f "$BUILD/vtouchprobe.so" ] || ! cmp -s "$HERE/comp/vtouchprobe.comp" "$BUILD/vtouchprobe.comp"; then
    cp "$HERE/comp/vtouchprobe.comp" "$BUILD/vtouchprobe.comp"
    (cd "$BUILD" && halcompile --compile vtouchprobe.comp) > "$OUT/build.log" 2>&1 \
        || { rm -f "$BUILD/vtouchprobe.comp"; die "halcompile vtouchprobe.comp failed (see $OUT/build.log)"; }
fi
if ! cmp -s "$BUILD/vtouchprobe.so" "$MODDIR/vtouchprobe.so"; then
    { cp "$BUILD/vtouchprobe.so" "$MODDIR/.vtouchprobe.so.new" && mv -f "$MODDIR/.vtouchprobe.so.new" "$MODDIR/vtouchprobe.so"; } \
        || die "cannot install vtouchprobe.so into $MODDIR"
fi
flock -u 9
exec 9>&-

# ------------------------------------------------------ truth -> HAL pins
if [ -n "$PARAMS" ]; then
    cp "$PARAMS" "$OUT/params.json" || die "cannot copy $PARAMS"
else
    "$PY" "$HERE/scripts/truth_params.py" --truth "$TRUTH" --machine "$MACHINE" ${PLAN:+--plan "$PLAN"} -o "$OUT/params.json" \
        || die "cannot turn $TRUTH into the probe's parameters"
fi
"$PY" "$HERE/scripts/lcsim_params.py" "$OUT/params.json" "$OUT/params.hal" || die "bad parameters $OUT/params.json"
if [ -n "$SETP" ]; then
    grep -Evq '^[[:space:]]*(#.*)?$|^setp [A-Za-z0-9_.-]+ [-+0-9.eE]+[[:space:]]*$' "$SETP" \
        && die "$SETP: only 'setp PIN VALUE' lines and comments"
    { echo "# --setp $SETP"; cat "$SETP"; } >> "$OUT/params.hal"
fi

# ---------------------------------------------- per-run LinuxCNC configuration
# the kinematics: params.json machine.kins (truth_params.py: table_ac -> xyzac, table_bc -> xyzbc)
KINS="$("$PY" -c 'import json, sys; print(json.load(open(sys.argv[1]))["machine"].get("kins", "xyzac"))' "$OUT/params.json")" \
    || die "cannot read machine.kins from $OUT/params.json"
INI="lcsim_$KINS.ini"
[ -f "$HERE/config/$INI" ] || die "no LinuxCNC configuration config/$INI for kinematics $KINS"
sed "s#@HARNESS@#$HERE#g" "$HERE/config/$INI" > "$OUT/config/$INI"
# a kinematics with no identity type (maxkins) has its own line: the cycle's session runs the INI's
# identity module, --kins-tcp the TCP one
TCPKINS="$(sed -n 's/^# TCP_KINEMATICS = \([A-Za-z0-9_-]*\)$/\1/p' "$OUT/config/$INI")"
if [ "$TCP" = 1 ] && [ -n "$TCPKINS" ]; then
    sed -i "s#^KINEMATICS = .*\$#KINEMATICS = $TCPKINS#" "$OUT/config/$INI"
    grep -q "^KINEMATICS = $TCPKINS\$" "$OUT/config/$INI" || die "could not select $TCPKINS in $INI"
elif [ "$TCP" = 1 ]; then
    sed -i 's#^\(KINEMATICS = [a-z0-9-]*\( coordinates=[a-z]*\)\{0,1\}\) sparm=identityfirst$#\1#' "$OUT/config/$INI"
    grep -q '^KINEMATICS = [a-z0-9-]*\( coordinates=[a-z]*\)\{0,1\}$' "$OUT/config/$INI" \
        || die "could not drop sparm=identityfirst from $INI"
elif [ -n "$TCPKINS" ] && grep -q "^setp $TCPKINS\." "$OUT/params.hal"; then
    # its pins do not exist in the identity session (the module is not loaded): they cannot act, and
    # the session says so in its params.hal instead of failing on them
    sed -i "s#^setp $TCPKINS\.\(.*\)\$#\# not loaded in this session ($TCPKINS: identity kinematics run instead), not applied: setp $TCPKINS.\1#" "$OUT/params.hal"
fi
if [ -n "$COMP" ]; then
    # the C joint's compensation table (LinuxCNC ini-config: COMP_FILE, COMP_FILE_TYPE per joint)
    cp "$COMP" "$OUT/config/joint4.comp" || die "cannot copy $COMP"
    sed -i "s#^\[JOINT_4\]\$#[JOINT_4]\nCOMP_FILE = $OUT/config/joint4.comp\nCOMP_FILE_TYPE = 0#" "$OUT/config/$INI"
    grep -q '^COMP_FILE = ' "$OUT/config/$INI" || die "could not add COMP_FILE to [JOINT_4]"
fi
if [ -n "$LINCOMP" ]; then
    # the linear joints' compensation tables: the controller adds them to the motor commands
    for j in 0 1 2; do
        cp "$LINCOMP/joint$j.comp" "$OUT/config/joint$j.comp" || die "cannot copy $LINCOMP/joint$j.comp"
        sed -i "s#^\[JOINT_$j\]\$#[JOINT_$j]\nCOMP_FILE = $OUT/config/joint$j.comp\nCOMP_FILE_TYPE = 0#" "$OUT/config/$INI"
        grep -q "^COMP_FILE = $OUT/config/joint$j.comp" "$OUT/config/$INI" || die "could not add COMP_FILE to [JOINT_$j]"
    done
fi
cp "$HERE/config/lcsim.tbl" "$OUT/config/"
# the program's relative LOGOPEN file resolves in the INI's directory
LOGNAME_="$(sed -n 's/^[[:space:]]*([Ll][Oo][Gg][Oo][Pp][Ee][Nn],\([^)]*\)).*/\1/p' "$NGC" | head -1)"

export LCSIM_NGC="$NGC" LCSIM_PRE_NGC="$PRE" LCSIM_OUT="$OUT" LCSIM_PARAMS_HAL="$OUT/params.hal" LCSIM_C_FROM_MOTOR="$C_MOTOR" LCSIM_XYZ_FROM_MOTOR="$([ -n "$LINCOMP" ] && echo 1 || echo 0)"
export LCSIM_TIMEOUT=$(( TIMEOUT > 40 ? TIMEOUT - 30 : TIMEOUT * 3 / 4 ))   # the driver's own limit
# rtapi_app refuses to run as root unless given a fallback uid
export RTAPI_UID="${RTAPI_UID:-65534}"
export RTAPI_FIFO_PATH="/tmp/rotacal-e2e-rtapi-$$.fifo"
rm -f "$OUT/driver_status.json" "$OUT/driver.log"
tmp_before="$(ls -d /tmp/linuxcnc.debug.* /tmp/linuxcnc.print.* 2>/dev/null | sort)"

echo "run.sh: LinuxCNC starting (timeout ${TIMEOUT}s, $([ "$ISOLATE" = 1 ] && echo "own namespaces" || echo "shared namespaces")), run directory $OUT"
# own session: the watchdog can address the whole tree by its process group
if [ "$ISOLATE" = 1 ]; then
    # --kill-child: TERM to unshare reaches the namespace's first process (the linuxcnc script,
    # which cleans up on TERM); when that process ends, the kernel ends the whole namespace
    HOME="$OUT" setsid unshare --ipc --net --mount --pid --fork --mount-proc --kill-child=SIGTERM \
        bash "$HERE/scripts/ns_session.sh" "$OUT/config/$INI" "$OUT" "$HERE" "$NGC" ${PRE:+"$PRE"} \
        > "$OUT/linuxcnc.log" 2>&1 < /dev/null &
else
    HOME="$OUT" setsid linuxcnc -r "$OUT/config/$INI" > "$OUT/linuxcnc.log" 2>&1 < /dev/null &
fi
LPID=$!
# unshare's child: the namespace's first process (its pid out here)
ns_init() { cut -d' ' -f1 "/proc/$LPID/task/$LPID/children" 2>/dev/null; }
# the driver's pid in driver.pid is its pid in the session's namespace: signal it from there
ns_kill() {  # ns_kill SIGNAL PID
    if [ "$ISOLATE" = 1 ]; then
        local init
        init=$(ns_init)
        [ -n "$init" ] && nsenter -t "$init" -p -- kill -"$1" "$2" 2>/dev/null
    else
        kill -"$1" "$2" 2>/dev/null
    fi
}
deadline=$(( SECONDS + TIMEOUT ))
stage=0
while kill -0 "$LPID" 2>/dev/null; do
    if [ $SECONDS -ge $deadline ]; then
        stage=$((stage + 1))
        case $stage in
            1) echo "run.sh: TIMEOUT -- stopping the driver (clean LinuxCNC shutdown follows)"
               [ -f "$OUT/driver.pid" ] && ns_kill TERM "$(cat "$OUT/driver.pid")";;
            2) echo "run.sh: still running -- TERM to the linuxcnc script ($LPID)"
               kill -TERM "$LPID" 2>/dev/null;;
            *) echo "run.sh: still running -- KILL process group $LPID, stop realtime"
               if [ "$ISOLATE" = 1 ]; then
                   # the namespace's first process: killing it ends every process of the session,
                   # and its shared memory goes with its IPC namespace
                   init=$(ns_init)
                   [ -n "$init" ] && kill -KILL "$init" 2>/dev/null
                   kill -KILL -- "-$LPID" 2>/dev/null
               else
                   kill -KILL -- "-$LPID" 2>/dev/null
                   /usr/lib/linuxcnc/realtime stop >/dev/null 2>&1
                   rm -f "$LOCK"
               fi
               break;;
        esac
        deadline=$(( SECONDS + 20 ))
    fi
    sleep 0.2
done
wait "$LPID" 2>/dev/null
LRC=$?
rm -f "$RTAPI_FIFO_PATH"
for f in $(ls -d /tmp/linuxcnc.debug.* /tmp/linuxcnc.print.* 2>/dev/null | sort); do
    grep -qxF "$f" <<< "$tmp_before" || rm -f "$f"     # linuxcnc's own mktemp files of this run
done
T_RUN=$(( SECONDS - T_START ))

RC=0
[ $LRC -eq 0 ] || RC=1
grep -q '"result": "ok"' "$OUT/driver_status.json" 2>/dev/null || RC=1
grep -q '"result": "timeout"' "$OUT/driver_status.json" 2>/dev/null && RC=2
[ $stage -gt 0 ] && RC=2
if [ -n "$LOGNAME_" ] && [ -f "$OUT/config/$LOGNAME_" ]; then cp "$OUT/config/$LOGNAME_" "$OUT/$LOGNAME_"; fi
echo "run.sh: LinuxCNC session finished in ${T_RUN}s (linuxcnc exit $LRC)"
if [ -f "$OUT/driver_status.json" ]; then
    "$PY" - "$OUT/driver_status.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
print("run.sh: driver result=%s, program %s s, driver total %s s"
      % (s["result"], s["phases"].get("program_s", "-"), s.get("wall_s")))
for e in s["errors"]:
    print("run.sh: ERROR: %s" % e)
EOF
fi
echo "run.sh: exit $RC"
exit $RC
