# lcsim_core.tcl -- HAL for the headless XYZAC or XYZBC trunnion, XYZAB dual
# rotary table, B head over C table or bridge mill simulation
# (lcsim_xyzac.ini, lcsim_xyzbc.ini, lcsim_xyzab.ini, lcsim_max.ini,
# lcsim_5axis.ini: the kinematics module is the INI's).
# Run by LinuxCNC (haltcl) with the INI sections available as ::SECTION(item)
# and the environment as ::env().
#
# rotacal's copy: realtime probe only (the Python fallback of the shared
# harness is late by whole servo periods, too coarse for the e2e tolerances),
# and no kinematics switching (identity kinematics throughout; run.sh --kins-tcp
# starts in the TCP kinematics instead, for the conventions read-back).
#
# Environment (exported by ../run.sh):
#   LCSIM_PARAMS_HAL  setp file generated from the truth (truth_params.py + lcsim_params.py)
#   LCSIM_C_FROM_MOTOR 1: the probe reads C from joint.4.motor-pos-cmd (run.sh --c-from-motor)
#   LCSIM_XYZ_FROM_MOTOR 1: X, Y, Z from joints 0-2's motor-pos-cmd (run.sh --linear-comp)

# --- motion, kinematics ------------------------------------------------------
# the INI value is a Tcl list (one element per occurrence): split "module sparm=..." into words
eval loadrt [lindex $::KINS(KINEMATICS) 0]
set kins [lindex [lindex $::KINS(KINEMATICS) 0] 0]   ;# xyzac-trt-kins, xyzbc-trt-kins or xyzab_tdr_kins
loadrt [lindex $::EMCMOT(EMCMOT) 0] servo_period_nsec=$::EMCMOT(SERVO_PERIOD) num_joints=$::KINS(JOINTS)
addf motion-command-handler servo-thread
addf motion-controller      servo-thread

# ideal servo: feedback = command
for {set j 0} {$j < $::KINS(JOINTS)} {incr j} {
    net j${j}-motor joint.$j.motor-pos-cmd => joint.$j.motor-pos-fb
}

# estop / tool change loopbacks (no hardware, no GUI tool-change prompt)
net estop-loop       iocontrol.0.user-enable-out => iocontrol.0.emc-enable-in
net tool-prep-loop   iocontrol.0.tool-prepare    => iocontrol.0.tool-prepared
net tool-change-loop iocontrol.0.tool-change     => iocontrol.0.tool-changed

# motion.switchkins-type stays unconnected at 0: identity kinematics
# (sparm=identityfirst in the INI). G43 still reaches the kinematics module.
# (xyzab_tdr_kins calls its pin tool-offset-z; trivkins and maxkins have none: the head machine's
# programs use no tool length, the ball hangs from the pivot)
set head [info exists ::LCSIM(HEAD_OUTER_JOINT)]
if {$head} {
} elseif {$kins == "xyzab_tdr_kins"} {
    net :tool-offset     motion.tooloffset.z  => $kins.tool-offset-z
} else {
    net :tool-offset     motion.tooloffset.z  => $kins.tool-offset
}

# --- virtual probe -----------------------------------------------------------
loadrt vtouchprobe
# after motion-controller: the sample taken here (commanded joint positions
# of this period) is the one motion reads next period, when it also records
# carte_pos_fb = fwd(same joint positions) as the probe point
# X, Y, Z: the joints' commands, or with LCSIM_XYZ_FROM_MOTOR=1 their motors' commands, which carry
# their compensation tables (run.sh --linear-comp): the linear axes' positioning errors are then
# the controller's own, as on a machine whose scales are read at the motor
if {[info exists ::env(LCSIM_XYZ_FROM_MOTOR)] && $::env(LCSIM_XYZ_FROM_MOTOR) == 1} {
    # the joint's command plus what motion adds for its table (joint.N.backlash-filt): the motor's
    # command without its homing offset (Z homes at HOME_OFFSET 300 with its motor at 0)
    loadrt sum2 names=vtp-x,vtp-y,vtp-z
    foreach {j s} {0 x 1 y 2 z} {
        addf vtp-$s servo-thread
        net :jm$j joint.$j.pos-cmd => vtp-$s.in0
        net :jb$j joint.$j.backlash-filt => vtp-$s.in1
        net :jt$j vtp-$s.out => vtouchprobe.0.joint-$s
    }
} else {
    net :jx joint.0.pos-cmd => vtouchprobe.0.joint-x
    net :jy joint.1.pos-cmd => vtouchprobe.0.joint-y
    net :jz joint.2.pos-cmd => vtouchprobe.0.joint-z
}
# the probe's (pA, uA) line is the axis on the bed, its (pC, uC) line the one that axis carries:
# joint 3 and 4 on the trunnions (A or B, then C); on xyzab_tdr_kins joint 4 (B) carries joint 3 (A).
# A head machine (lcsim_max.ini's [LCSIM]): the probe rides on the head, its outer (and inner)
# rotary joint on joint-h1 (joint-h2), the table's rotary joint, if any, on joint-c; joint-a unwired
if {$head} {
    net :jh1 joint.[lindex $::LCSIM(HEAD_OUTER_JOINT) 0].pos-cmd => vtouchprobe.0.joint-h1
    if {[info exists ::LCSIM(HEAD_INNER_JOINT)]} {
        net :jh2 joint.[lindex $::LCSIM(HEAD_INNER_JOINT) 0].pos-cmd => vtouchprobe.0.joint-h2
    }
    if {[info exists ::LCSIM(TABLE_ROTARY_JOINT)]} {
        net :jc joint.[lindex $::LCSIM(TABLE_ROTARY_JOINT) 0].pos-cmd => vtouchprobe.0.joint-c
    }
} elseif {$kins == "xyzab_tdr_kins"} {
    net :ja joint.4.pos-cmd => vtouchprobe.0.joint-a
    net :jc joint.3.pos-cmd => vtouchprobe.0.joint-c
} else {
    net :ja joint.3.pos-cmd => vtouchprobe.0.joint-a
    # C: the joint's command (default), or with LCSIM_C_FROM_MOTOR=1 the motor's command, which
    # carries the joint's compensation table (COMP_FILE: motor-pos-cmd = pos-cmd + correction); the
    # probe's true angle error is then a function of where the motor really is, as on a machine whose
    # encoder sits on the motor (tests/e2e/linuxcnc: the comp_table case)
    if {[info exists ::env(LCSIM_C_FROM_MOTOR)] && $::env(LCSIM_C_FROM_MOTOR) == 1} {
        net j4-motor => vtouchprobe.0.joint-c
    } else {
        net :jc joint.4.pos-cmd => vtouchprobe.0.joint-c
    }
}
# after motion-controller (and the sums above, when present)
addf vtouchprobe.0 servo-thread
net :probe vtouchprobe.0.probe => motion.probe-input

# --- parameters: nominal kinematics + true machine/artefact ------------------
if {[info exists ::env(LCSIM_PARAMS_HAL)] && [file exists $::env(LCSIM_PARAMS_HAL)]} {
    source $::env(LCSIM_PARAMS_HAL)
} else {
    puts stderr "lcsim_core.tcl: LCSIM_PARAMS_HAL not set, using component defaults"
}
