0 BEGIN PGM ROTACAL_KIN MM
1 ; rotacal kinematics / preset correction, table A/C, TNC 640
2 ; provenance: results.txt; cycle touch154, machine ac_trunnion
3 ; identified (papers' convention), value +- u (k = 1):
4 ;   dx_AY  X0A          14.831 um   +- 4.578 um
5 ;   dy_AY  Y0A          23.156 um   +- 4.061 um
6 ;   dz_AY  Z0A          27.737 um   +- 2.926 um
7 ;   dy_CA  Y0C-Y0A       3.805 um   +- 2.101 um
8 ;   a_AY   A0A          -0.519 mdeg +- 0.322 mdeg
9 ;   b_AY   B0A          -0.119 mdeg +- 0.472 mdeg
10 ;   c_AY   C0A          -0.464 mdeg +- 0.909 mdeg
11 ;   b_CA   B0C-B0A       0.149 mdeg +- 0.515 mdeg
12 ; what it changes: nothing by itself. Direct writes of the kinematics
13 ; description from NC are OEM-protected (UNVERIFIED): enter by hand or let
14 ; KinematicsOpt (cycle 451) optimize. Old values are on the control;
15 ; new = old + change. Lengths mm, machine coordinates, rotaries at 0 deg.
16 ; kinematics, transformation to the A axis: X +0.0148 Y +0.0232 Z +0.0277
17 ; kinematics, transformation A axis to C axis: X +0.0000 Y +0.0038 Z +0.0000
18 ; preset table, A axis of the active preset: -0.0005 deg
19 ; reported only (axis directions): b_AY, c_AY, b_CA
20 END PGM ROTACAL_KIN MM
