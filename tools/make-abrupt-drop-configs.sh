#!/bin/sh
# Writes configs/abrupt_drop_T1.yaml .. T7.yaml from seed 004's table 1
# (tests/scenes/data/depadova2017_table1.csv): the seven jumps differ only in their
# inflow, tailwater and spacing. Run it after changing the template below.
cd "$(dirname "$0")/.."
tail -n +5 tests/scenes/data/depadova2017_table1.csv | while IFS=, read t run y1 yt v1 vt f1 ratio re s sy type; do
y1m=$(awk -v a=$y1 'BEGIN{printf "%.4f", a/100}'); ytm=$(awk -v a=$yt 'BEGIN{printf "%.4f", a/100}')
dx=$(awk -v a=$y1m 'BEGIN{printf "%.6g", a/4}')
xd=$(awk -v d=$dx 'BEGIN{printf "%.6g", int(0.8/d+0.5)*d}')
xo=$(awk -v d=$dx 'BEGIN{printf "%.6g", int(2.0/d+0.5)*d}')
xb=$(awk -v d=$dx 'BEGIN{printf "%.6g", (int(0.8/d+0.5)-4)*d}')
top=$(awk -v a=$y1m 'BEGIN{printf "%.4f", 0.032+a}')
fr=$(awk -v v=$v1 -v d=$y1m 'BEGIN{printf "%.2f", v/sqrt(9.81*d)}')
lmax=$(awk -v a=$ytm 'BEGIN{printf "%.4f", 0.5*a}')
xf=$(awk -v x=$xd -v d=$dx 'BEGIN{printf "%.6g", x+1.5*d}')
xfa=$(awk -v x=$xd -v d=$dx 'BEGIN{printf "%.6g", x-d}')
xfb=$(awk -v x=$xd -v d=$dx 'BEGIN{printf "%.6g", x+d}')
cat > configs/abrupt_drop_$t.yaml <<EOF
# Hydraulic jump at an abrupt drop: seed 004 (De Padova, Mossa & Sibilla
# 2017), test $t (run $run of Mossa et al. 2003; tests/scenes/data/depadova2017_table1.csv):
# y1 = $y1 cm, V1 = $v1 m/s (Fr1 = $fr by V1/sqrt(g y1); the table prints
# $f1), tailwater yt = $yt cm, Vt = $vt m/s, drop s = 3.2 cm. Observed jump
# type: $type.
#
# Seed 004's set-up: a 2 m x 0.4 m domain, a supercritical inflow on the
# upper bed (a 2h-wide buffer layer), the drop, a tailwater buffer imposing
# yt and Vt at the outlet; Wendland C2, h = 1.5 dx, c = 30 m/s, kernel
# renormalisation everywhere but the pressure gradient, mixing length
# (c_mu = 0.09, l_max = 0.5 yt), XSPH velocity smoothing phi_v = 0.01,
# periodic smoothing of p - p_hydrostatic and the two-stage
# predictor-corrector. The seed's walls are ghost particles; here they are
# dynamic boundary particles. One departure from the seed: the continuity
# equation is not renormalised. With the renormalised form every wall scheme
# stopped in T1's first 2.1 s (a density run-away under the plunging stream
# or at the drop's edges, where the kernel support is truncated and the
# correction matrix amplifies the velocity divergence); with the plain form
# dbc and penalty_contact run (docs/validation.md). Where the seed leaves the set-up open: the drop
# lies 0.8 m downstream of the inflow (as the gate in the experiment; here
# rounded to whole spacings), and dx = y1/4 = $dx m (the seed's 0.01 m puts
# 3.5 spacings across y1; a whole number keeps the inflow's depth and
# discharge exact). The upper stream and its bed have their own lattice
# (lattice_origin), since the drop is not a whole number of spacings.
# The seed reports the jump type over tens of seconds (oscillations near
# 0.1 Hz): time.end = 60 s; a reduced run:
#   sluice run configs/abrupt_drop_$t.yaml --out runs/$t --set time.end=0.1
# The jump type from the run's free surface (docs/analysis.md, drop-type):
#   sluice-analyze drop-type runs/$t --drop-x $xd --from 10 --to 60
title: abrupt drop $t (seed 004), Fr1 = $fr
dimensions: 2

particles:
  spacing: $dx
  smoothing_length_ratio: 1.5
  rest_density: 1000

time:
  end: 60.0

domain:
  min: [-0.1, -0.1]
  max: [2.2, 0.4]

geometry:
  fluid:
    - {shape: box, min: [0, 0.032], max: [$xd, $top], velocity: [$v1, 0], lattice_origin: [0, 0.032]}
    - {shape: box, min: [$xd, 0], max: [$xo, $ytm], velocity: [$vt, 0]}
  walls:
    - {shape: polyline, points: [[-0.1, 0.032], [$xd, 0.032], [$xd, 0]], name: upper_bed_and_drop,
       lattice_origin: [0, 0.032]}
    # the lower bed starts inside the step, so that its layers fill the
    # block behind the concave corner at the foot of the drop; it ends at
    # the outlet
    - {shape: polyline, points: [[$xb, 0], [$xo, 0]], name: lower_bed}

initial:
  density: hydrostatic

plugins:
  wendland_c2: {}
  linear_eos:
    speed_of_sound: 30
  kernel_correction: {}
  continuity:                   # not renormalised (see above)
    form: mass
  pressure_gradient:
    form: symmetric
  velocity_gradient:
    renormalise: true
  mixing_length:
    c_mu: 0.09
    l_max: $lmax
  turbulent_stress:
    form: tensor
    renormalise: true
  xsph:
    form: velocity_smoothing
    phi: 0.01
  pressure_smoothing:
    every: 20
  gravity: {}
  dbc: {}                       # seed 004: ghost particles (see above)
  time_step:
    courant: 0.2
  predictor_corrector: {}
  inlet:
    position: 0
    bed: 0.032
    depth: $y1m
    velocity: $v1
  outlet:
    form: buffer
    position: $xo
    depth: $ytm
    velocity: $vt
  free_surface_gauge:            # every 5 cm on the upper reach (the toe: sluice-analyze drop-type)
    positions: [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75,
                0.8, 0.85, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8]
    interval: 0.02
  section_gauge:                # depth, discharge, Froude number and the momentum function
    positions: [0.05, 0.4, 0.7, $xf, 1.0, 1.2, 1.5, 1.8]   # $xf: the face (1.5 dx in front of it, 0-0.032 m)
    bed_elevation: [0.032, 0.032, 0.032, 0, 0, 0, 0, 0]
    top: [0.4, 0.4, 0.4, 0.032, 0.4, 0.4, 0.4, 0.4]
    forces: true
    interval: 0.02
  wall_force:                   # the fluid's force on the drop's face (sluice-analyze momentum)
    walls: upper_bed_and_drop
    box_min: [$xfa, 0.0005]
    box_max: [$xfb, 0.0315]
    interval: 0.02
  point_gauge:                  # bed pressure downstream of the drop
    points: [[0.9, 0.01], [1.0, 0.01], [1.1, 0.01], [1.2, 0.01], [1.3, 0.01]]
    fields: pressure
    interval: 0.02
    file: bed_pressure.csv
  vorticity:
    interval: 0.5
  hdf5:
    interval: 0.5

variants:
  controlled_tailwater:
    description: "the layer's velocity adjusted (a tailgate) until the depth at x = 1.5 m, past the roller, is yt (with Vt imposed it settles 1-4 % above; docs/validation.md)"
    set: {plugins.outlet.tailwater: controlled, plugins.outlet.control_position: 1.5}
  ghost_walls:
    description: "seed 004's walls: no-slip ghost particles (with wall_backstop), the continuity equation at the walls' rest velocity (Adami et al. 2012); the stream keeps a smooth bed's friction where dbc loses 23 % in 0.2 m (docs/validation.md)"
    remove: [plugins.dbc]
    set:
      plugins.ghost_particles: {determinant_threshold: 0.1}
      plugins.wall_backstop: {}
      plugins.continuity.wall_velocity: rest
EOF
done
