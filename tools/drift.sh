#!/bin/sh
# Long-run drift (docs/reliability.md, issue: reliability): a still-water
# tank and a uniform open-channel flow run for END seconds (default 60) and
# must keep mass, depth and hydrostatic pressure within 1 % of the imposed
# state. A benchmark, not a unit test (it takes about 5 minutes on 2 threads).
#
#   tools/drift.sh [BUILD]      (BUILD: build directory, default build)
#   env: END (s, default 60), OUT (default runs/drift), THREADS (default 2),
#        CHANNEL_DX (m, default 0.01: d/10), CASES (default "still_water channel"),
#        C0_SCALE (default 1): both scenes' speed of sound times this (the
#        scenes' own c0 are 10 sqrt(g H) = 22.1 m/s and 20 m/s = 40 V),
#        SETTLE (s, default 2): the first seconds, left out of the figures
#        (the start's acoustic transient)
#
# still water: configs/still_water_2d.yaml (H = 0.5 m, dx = 0.02 m, DBC tank)
#   with free-surface gauges at x = 0.25, 0.5, 0.75 m, a pressure point at
#   (0.5, 0.25) m (hydrostatic rho0 g (H - 0.25) = 2452.5 Pa) and the energy
#   gauge (fluid mass, energy drift);
# channel: configs/uniform_channel_2d.yaml (d = 0.1 m, V = 0.5 m/s between a
#   buffer inlet and a tailwater buffer outlet) at dx = CHANNEL_DX: the mass
#   of the reach between them from the boundaries' flux tables
#   (M0 + in - out), which is its mean depth (M / (rho0 L)); the depth and
#   discharge the section gauges read at x = 0.25, 0.5, 0.75 m (kernel-sum
#   surface); the pressure at mid-depth there (490.5 Pa).
#
# Every quantity is averaged over each second (the acoustic oscillations of
# weakly compressible SPH move instantaneous pressures by up to 25 % in the
# channel: its gauges sample every 0.01 s so that a second's mean holds 100);
# the table gives, over the seconds after SETTLE, in per cent of the imposed
# value: the worst one-second mean's deviation from it and when; the first
# and the last one-second means' deviations; and the drift, the largest
# change of a one-second mean from the first one's, and when. Written to OUT/summary.csv and printed.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
sluice=$build/sluice
[ -x "$sluice" ] || { echo "tools/drift.sh: no $sluice (build first: meson setup $build && ninja -C $build)" >&2; exit 2; }
end=${END:-60}
out=${OUT:-runs/drift}
threads=${THREADS:-2}
mkdir -p "$out"

run() { # name scene args...
    name=$1 scene=$2
    shift 2
    echo "tools/drift.sh: $name: $scene to $end s ..." >&2
    OMP_NUM_THREADS=$threads "$sluice" run "$scene" --out "$out/$name" --overwrite --no-progress \
        --set time.end="$end" "$@" >"$out/$name.log" 2>&1 ||
        { echo "tools/drift.sh: $name failed (see $out/$name.log):" >&2; tail -3 "$out/$name.log" >&2; exit 1; }
    grep -E '"(wall_seconds|particle_steps_per_second|steps)"' "$out/$name/run.json" | tr -d ' \n' >&2
    echo >&2
}

cases=${CASES:-still_water channel}
settle=${SETTLE:-2}
c0_still=$(awk -v s="${C0_SCALE:-1}" 'BEGIN { printf "%.6g", 22.1 * s }')
c0_channel=$(awk -v s="${C0_SCALE:-1}" 'BEGIN { printf "%.6g", 20 * s }')
case " $cases " in *" still_water "*)
run still_water configs/still_water_2d.yaml --set plugins.tait.speed_of_sound="$c0_still" \
    --set 'plugins.free_surface_gauge.positions=[0.25,0.5,0.75]' \
    --set 'plugins.free_surface_gauge.interval=0.05' \
    --set 'plugins.point_gauge.points=[[0.5,0.25]]' \
    --set 'plugins.point_gauge.fields=pressure' \
    --set 'plugins.point_gauge.interval=0.05' \
    --set 'plugins.energy_gauge.interval=0.05' \
    --set 'plugins.hdf5.interval=10' ;;
esac
case " $cases " in *" channel "*)
run channel configs/uniform_channel_2d.yaml --set plugins.tait.speed_of_sound="$c0_channel" \
    --set particles.spacing="${CHANNEL_DX:-0.01}" \
    --set plugins.section_gauge.interval=0.01 --set plugins.point_gauge.interval=0.01 ;;
esac

# block_stats FILE NAME UNIT REFERENCE SCENE EXPRESSION: one-second means of
# EXPRESSION (awk, over the columns $1..) in FILE, against REFERENCE
block_stats() {
    awk -F, -v name="$2" -v unit="$3" -v ref="$4" -v scene="$5" -v settle="$settle" "
    NR == 1 { next }
    { t = \$1; v = $6; b = (t > 0) ? int(t - 1e-9) : -1
      if (b < 0) next
      sum[b] += v; n[b]++; if (b > last) last = b }
    END {
      worst = 0; wt = 0; drift = 0; dt = 0
      for (k = settle; k <= last; k++) {
        if (!n[k]) continue
        e = 100 * (sum[k] / n[k] / ref - 1)
        if (k == settle) first = e
        if (e * e > worst * worst) { worst = e; wt = k + 1 }
        if ((e - first) ^ 2 > drift * drift) { drift = e - first; dt = k + 1 }
        lastv = e
      }
      printf \"%s,%s,%s,%.6g,%+.3f,%d,%+.3f,%+.3f,%+.3f,%d\\n\", scene, name, unit, ref, worst, wt, first, lastv, drift, dt
    }" "$1"
}

summary=$out/summary.csv
echo "scene,quantity,unit,reference,worst_1s_mean_pct,at_s,first_1s_pct,last_1s_pct,drift_pct,at_s" >"$summary"
s=$out/still_water
if [ -f "$s/run.json" ]; then
    m0=$(awk -F, 'NR == 2 { print $7 }' "$s/energy.csv")
    block_stats "$s/energy.csv" "fluid mass" kg/m "$m0" still_water '$7' >>"$summary"
    block_stats "$s/free_surface.csv" "depth: mean of 3 free-surface gauges" m 0.5 still_water '($2 + $3 + $4) / 3' >>"$summary"
    block_stats "$s/points.csv" "pressure at x 0.5 y 0.25 m against rho0 g (H - y)" Pa 2452.5 still_water '$2' >>"$summary"
    # hydrostatic: the same pressure over rho0 g (eta - y), eta the measured
    # surface (the gauges sample at the same times: rows pair up)
    paste -d, "$s/free_surface.csv" "$s/points.csv" >"$s/hydrostatic.csv"
    block_stats "$s/hydrostatic.csv" "pressure at y 0.25 m over rho0 g (eta - y)" 1 1 still_water \
        '$6 / (9810 * (($2 + $3 + $4) / 3 - 0.25))' >>"$summary"
fi
c=$out/channel
if [ -f "$c/run.json" ]; then
    # reach mass: M0 + in - out, M0 = rho0 d L = 100 kg/m; the flux rows are
    # every 0.5 s (cumulative mass in column 5); its mean depth is M / (rho0 L)
    paste -d, "$c/inlet.csv" "$c/outlet.csv" |
        awk -F, 'NR == 1 { print "time,mass"; next } { print $1 "," (100 + $5 - $11) }' >"$c/reach_mass.csv"
    block_stats "$c/reach_mass.csv" "reach mass = mean depth x rho0 L" kg/m 100 channel '$2' >>"$summary"
    block_stats "$c/sections.csv" "depth: mean of 3 section gauges" m 0.1 channel '($2 + $6 + $10) / 3' >>"$summary"
    block_stats "$c/sections.csv" "discharge: mean of 3 section gauges" m^2/s 0.05 channel '($3 + $7 + $11) / 3' >>"$summary"
    block_stats "$c/points.csv" "pressure at mid-depth: mean of 3 points" Pa 490.5 channel '($2 + $3 + $4) / 3' >>"$summary"
    # hydrostatic: each point's pressure over rho0 g (eta - y), eta the
    # section gauge's surface at the same x and time
    paste -d, "$c/sections.csv" "$c/points.csv" >"$c/hydrostatic.csv"
    block_stats "$c/hydrostatic.csv" "pressure at mid-depth over rho0 g (eta - y)" 1 1 channel \
        '($15 / ($2 - 0.05) + $16 / ($6 - 0.05) + $17 / ($10 - 0.05)) / (3 * 9810)' >>"$summary"
fi
column -s, -t "$summary" 2>/dev/null || cat "$summary"
[ -f "$s/energy.csv" ] &&
    echo "still water: energy drift (E - E0) / S at $end s: $(awk -F, 'END { print $6 }' "$s/energy.csv")"
exit 0
