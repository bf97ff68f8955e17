#!/bin/sh
# Wall pressures on every wall scheme at three spacings (docs/loads.md).
#
#   tools/wall-pressure-study.sh [BUILD_DIR]          (default: build)
#   CASES="still" SCHEMES="dbc mdbc" JOBS=2 tools/wall-pressure-study.sh
#   SCHEMES="mdbc+backstop" ...                      (mdbc with wall_backstop)
#   RUN=0 tools/wall-pressure-study.sh               (the summary of the runs there)
#   C0_STILL=31.4 OUT=runs/still-c0x2 CASES=still tools/wall-pressure-study.sh
#
# Cases:
#   still     a still tank 0.5 m long, water H = 0.25 m, 10 s, at
#             dx = H/12.5, H/25, H/50 (SPACINGS_STILL): wall_pressure
#             sensors on the side wall at y = 0.025, 0.125, 0.225 m and on
#             the floor's middle; per sensor the mean over 5-10 s against
#             rho0 g (H - y) and the largest departure of the 0.1 s-filtered
#             series over 1-10 s (the acoustic start-up settled).
#   lobovsky  configs/dam_break_lobovsky_2d.yaml (Lobovsky et al. 2014,
#             H = 300 mm) at dx = H/30, H/60, H/120 (SPACINGS_LOBOVSKY), to
#             t = 1 s, sampled at 10 kHz: per sensor (3, 15, 30, 80 mm) the
#             first-impact peak p / (rho g H) and its time t (g/H)^(1/2) in
#             t* in [2, 3.2], the impulse of the impact (the integral of
#             p / (rho g H) over t* from the arrival, the first p > 0.1 rho g H
#             after t* = 1.5, for 0.5 units of t*: a fixed window, so that a
#             numerical spike does not shrink it) and the quasi-static mean
#             over t* in [3.5, 5];
#             the same from the experiment's event 5
#             (tests/scenes/data/lobovsky2014_h300_event5.csv).
#   jump      configs/hydraulic_jump_jonsson2016.yaml (seed 000, Fr1 = 3.4,
#             dx = d1/4) to JUMP_END s (default 10): its 21 floor sensors
#             (bed_pressure.csv, x = 0.05-1.05 m); per sensor over
#             2.5 s-JUMP_END the mean bed pressure against rho g eta, eta the
#             free-surface gauge's mean elevation above the bed there, and the
#             fluctuation coefficient C'p = p' / (rho V1^2 / 2), p' the
#             standard deviation (V1 = 1.5 m/s); the toe and the roller's end
#             from sluice-analyze toe and roller over the same window.
# Runs are ordinary run directories under OUT (default
# runs/wall-pressure-study); a finished run (run.json with status complete)
# is not redone, and a failed or unstable one is recorded, not fatal.
# Writes OUT/summary.csv (one row per case, scheme, spacing and sensor, with
# the observed order of convergence of each measure from the three spacings:
# p = log2(|f1 - f2| / |f2 - f3|), the spacings halving) and OUT/summary.md.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
sluice="$build/sluice"
out=${OUT:-runs/wall-pressure-study}
cases=${CASES:-still lobovsky jump}
jump_end=${JUMP_END:-10}
c0_still=${C0_STILL:-15.7}
schemes=${SCHEMES:-dbc mdbc ghost_particles penalty_contact repulsive_force}
spacings_still=${SPACINGS_STILL:-0.02 0.01 0.005}
spacings_lobovsky=${SPACINGS_LOBOVSKY:-0.01 0.005 0.0025}
jobs=${JOBS:-1}
data=tests/scenes/data/lobovsky2014_h300_event5.csv
mkdir -p "$out"
[ -x "$sluice" ] || { echo "wall-pressure-study: no $sluice (build first)" >&2; exit 2; }

# The plugin lines of a scheme: a plugin name, or NAME+backstop for the
# scheme with penalty_contact's wall_backstop under it (the safety net that
# keeps mdbc and ghost walls from leaking at an impact; docs/validation.md).
scheme_lines() {
    case "$1" in
    *+backstop) printf '  %s: {}\n  wall_backstop: {}\n' "${1%+backstop}" ;;
    *) printf '  %s: {}\n' "$1" ;;
    esac
}
# swap_scheme LINE_REGEX SCHEME FILE: the line matching LINE_REGEX replaced
swap_scheme() {
    lines=$(scheme_lines "$2")
    awk -v re="$1" -v lines="$lines" '$0 ~ re && !done { print lines; done = 1; next } { print }' "$3"
}

still_scene() { # SCHEME DX -> scene text on stdout
    cat <<EOF
title: still tank with wall pressure sensors
dimensions: 2
particles: {spacing: $2, smoothing_length_ratio: 1.5, rest_density: 1000}
time: {end: 10.0}
domain: {min: [-0.1, -0.1], max: [0.6, 0.5]}
geometry:
  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.25]}]
  walls: [{shape: tank, min: [0, 0], max: [0.5, 0.4], name: tank}]
initial: {density: hydrostatic}
plugins:
  wendland_c2: {}
  tait: {speed_of_sound: $c0_still}   # default 10 (g H)^(1/2)
  continuity: {}
  delta_sph: {delta: 0.1, form: fourtakas}
  pressure_gradient: {}
  artificial_viscosity: {alpha: 0.1}
  gravity: {}
$(scheme_lines "$1")
  time_step: {}
  symplectic: {}
  wall_pressure:
    positions: [[0.5, 0.025], [0.5, 0.125], [0.5, 0.225], [0.25, 0]]
    names: side025,side125,side225,floor
    size: [0.01, 0.01, 0.01, 0.1]
    interval: 0.01
    time_constant: 0.1
EOF
}

# run CASE SCHEME DX: one run directory, skipped when complete
run_one() {
    dir="$out/$1-$2-$3"
    if [ -f "$dir/run.json" ] && grep -q '"status": "complete"' "$dir/run.json"; then
        return 0
    fi
    rm -rf "$dir"
    mkdir -p "$dir.scene"
    case "$1" in
    still) still_scene "$2" "$3" >"$dir.scene/scene.yaml" ;;
    lobovsky)
        swap_scheme '^  dbc: [{][}]$' "$2" configs/dam_break_lobovsky_2d.yaml >"$dir.scene/scene.yaml" ;;
    jump)
        swap_scheme '^  penalty_contact: [{][}]' "$2" configs/hydraulic_jump_jonsson2016.yaml \
            >"$dir.scene/scene.yaml" ;;
    esac
    extra=""
    [ "$1" = lobovsky ] && extra="--set time.end=1.0 --set plugins.wall_pressure.interval=1e-4 --set plugins.hdf5.interval=1.0"
    [ "$1" = jump ] && extra="--set time.end=$jump_end --set plugins.hdf5.interval=$jump_end"
    # shellcheck disable=SC2086
    OMP_NUM_THREADS=${THREADS:-1} "$sluice" run "$dir.scene/scene.yaml" --out "$dir" --quiet \
        --set particles.spacing="$3" $extra >"$dir.scene/log.txt" 2>&1 || true
    echo "$1 $2 dx=$3: $(sed -n 's/.*"status": "\([a-z]*\)".*/\1/p' "$dir/run.json" 2>/dev/null | head -n 1)"
}

# one run per call of this script with --one CASE:SCHEME:DX (xargs -P)
if [ "${2:-}" = --one ]; then
    c=${3%%:*}; rest=${3#*:}; s=${rest%%:*}; dx=${rest#*:}
    run_one "$c" "$s" "$dx"
    exit 0
fi

list=""
for c in $cases; do
    case "$c" in still) sp=$spacings_still ;; lobovsky) sp=$spacings_lobovsky ;; jump) sp=0.005 ;;
    *) echo "wall-pressure-study: unknown case '$c'" >&2; exit 2 ;; esac
    for s in $schemes; do for dx in $sp; do list="$list $c:$s:$dx"; done; done
done
total=$(echo $list | wc -w)
echo "wall-pressure-study: $total runs, $jobs at a time, into $out"
# RUN=0: only the summary of the runs already there
if [ "${RUN:-1}" != 0 ]; then
    # shellcheck disable=SC2086
    printf '%s\n' $list | xargs -P "$jobs" -n 1 sh "$0" "$build" --one
fi

# ------------------------------------------------------------ measures --
# still: sensor k's columns are 1 + 3k (raw), 2 + 3k (filtered)
still_measures() { # DIR -> "sensor reference mean max_departure" lines (Pa)
    awk -F, 'BEGIN { y[0] = 0.025; y[1] = 0.125; y[2] = 0.225; y[3] = 0
                name[0] = "side025"; name[1] = "side125"; name[2] = "side225"; name[3] = "floor"
                for (k = 0; k < 4; k++) ref[k] = 1000 * 9.81 * (0.25 - y[k]) }
        NR == 1 { next }
        { t = $1; for (k = 0; k < 4; k++) { p = $(2 + 3 * k); f = $(3 + 3 * k)
            if (t >= 5) { sum[k] += p; n[k]++ }
            if (t >= 1) { d = f - ref[k]; if (d < 0) d = -d; if (d > dev[k]) dev[k] = d } } }
        END { for (k = 0; k < 4; k++)
                printf "%s %.6g %.6g %.6g\n", name[k], ref[k], n[k] ? sum[k] / n[k] : "nan", dev[k] }' \
        "$1/wall_pressure.csv"
}

# impact measures of one series: lines "t_star p_star" on stdin
impact_awk='
    { t[n] = $1; p[n] = $2; n++ }
    END {
        peak = -1e30; ip = -1
        for (i = 0; i < n; i++) if (t[i] >= 2 && t[i] <= 3.2 && p[i] > peak) { peak = p[i]; ip = i }
        if (ip < 0) { print "nan nan nan nan"; exit }
        ta = -1; for (i = 0; i < n && ta < 0; i++) if (t[i] >= 1.5 && p[i] > 0.1) ta = t[i]
        imp = 0
        for (i = 1; i < n; i++) if (t[i - 1] >= ta && t[i] <= ta + 0.5) imp += (t[i] - t[i - 1]) * (p[i] + p[i - 1]) / 2
        qs = 0; m = 0
        for (i = 0; i < n; i++) if (t[i] >= 3.5 && t[i] <= 5) { qs += p[i]; m++ }
        printf "%.6g %.6g %.6g %.6g\n", peak, t[ip], imp, m ? qs / m : "nan"
    }'
lobovsky_measures() { # DIR -> "sensor peak t_peak impulse quasi_static" (dimensionless)
    for k in 1 2 3 4; do
        printf 'sensor%s ' "$k"
        awk -F, -v k="$k" 'NR > 1 { printf "%.9g %.9g\n", $1 * sqrt(9.81 / 0.3), $(2 * k) / (1000 * 9.81 * 0.3) }' \
            "$1/wall_pressure.csv" | awk "$impact_awk"
    done
}
experiment_measures() {
    for k in 1 2 4 5; do # columns: sensor1, sensor2, (sensor2L), sensor3, sensor4
        case $k in 1) s=1 ;; 2) s=2 ;; 4) s=3 ;; 5) s=4 ;; esac
        printf 'sensor%s ' "$s"
        awk -F, -v c=$((k + 1)) '!/^#/ && !/^t_star/ { print $1, $c }' "$data" | awk "$impact_awk"
    done
}

# jump: "x mean_p rho_g_eta p_std" per floor sensor over [2.5, end]
jump_measures() { # DIR
    awk -F, -v end="$jump_end" '
        FNR == 1 { file++; next }
        file == 1 && $1 >= 2.5 && $1 <= end { for (k = 0; k < 21; k++) { e = $(2 * k + 3); if (e == e + 0) { eta[k] += e; ne[k]++ } } }
        file == 2 && $1 >= 2.5 && $1 <= end { for (k = 0; k < 21; k++) { p = $(2 + 2 * k); s[k] += p; q[k] += p * p; n[k]++ } }
        END { for (k = 0; k < 21; k++) { m = s[k] / n[k]; v = q[k] / n[k] - m * m; if (v < 0) v = 0
                printf "%.2f %.6g %.6g %.6g\n", 0.05 * (k + 1), m, 1000 * 9.81 * eta[k] / ne[k], sqrt(v) } }' \
        "$1/free_surface.csv" "$1/bed_pressure.csv"
}

summary="$out/summary.csv"
echo "case,scheme,spacing_m,status,sensor,measure,value,reference,relative_error,observed_order" >"$summary"
for c in $cases; do
    case "$c" in still) sp=$spacings_still ;; lobovsky) sp=$spacings_lobovsky ;; jump) sp=0.005 ;; esac
    [ "$c" = lobovsky ] && experiment_measures >"$out/experiment.txt"
    for s in $schemes; do
        vals=""
        for dx in $sp; do
            dir="$out/$c-$s-$dx"
            status=$(sed -n 's/.*"status": "\([a-z]*\)".*/\1/p' "$dir/run.json" 2>/dev/null | head -n 1)
            [ -n "$status" ] || status=missing
            [ -f "$dir/wall_pressure.csv" ] || [ -f "$dir/bed_pressure.csv" ] || continue
            if [ "$c" = jump ]; then
                "$build/tools/sluice-analyze" toe "$dir" --d1 0.02 --v1 1.5 --from 2.5 --to "$jump_end" \
                    >"$dir.scene/toe.txt" 2>&1 || true
                "$build/tools/sluice-analyze" roller "$dir" --d1 0.02 --v1 1.5 --from 2.5 --to "$jump_end" \
                    >"$dir.scene/roller.txt" 2>&1 || true
                x1=$(sed -n 's/^x1_mean = \([0-9.eE+-]*\).*/\1/p' "$dir.scene/toe.txt")
                xr=$(sed -n 's/^x_roller_end = \([0-9.eE+-]*\).*/\1/p' "$dir.scene/roller.txt")
                {
                    echo "$c,$s,$dx,$status,toe,x1_mean_m,$x1,,,"
                    echo "$c,$s,$dx,$status,roller,x_roller_end_m,$xr,,,"
                    jump_measures "$dir" | while read -r x mean hydro std; do
                        rel=$(awk -v v="$mean" -v r="$hydro" 'BEGIN { printf "%.4f", (v - r) / r }')
                        echo "$c,$s,$dx,$status,bed_x$x,mean_bed_pressure_Pa,$mean,$hydro,$rel,"
                        cp=$(awk -v v="$std" 'BEGIN { printf "%.5f", v / (1000 * 1.5 * 1.5 / 2) }')
                        echo "$c,$s,$dx,$status,bed_x$x,Cp_fluctuation,$cp,,,"
                    done
                } >>"$summary"
            elif [ "$c" = still ]; then
                still_measures "$dir" | while read -r name ref mean dev; do
                    rel=$(awk -v v="$mean" -v r="$ref" 'BEGIN { printf "%.5f", (v - r) / r }')
                    echo "$c,$s,$dx,$status,$name,mean_Pa_5_10s,$mean,$ref,$rel,"
                    rel=$(awk -v v="$dev" -v r="$ref" 'BEGIN { printf "%.5f", v / r }')
                    echo "$c,$s,$dx,$status,$name,largest_filtered_departure_Pa_1_10s,$dev,$ref,$rel,"
                done >>"$summary"
            else
                lobovsky_measures "$dir" | while read -r name peak tp imp qs; do
                    ref=$(grep "^$name " "$out/experiment.txt")
                    set -- $ref
                    for m in "peak $peak $2" "t_peak $tp $3" "impulse $imp $4" "quasi_static $qs $5"; do
                        set -- $m
                        rel=$(awk -v v="$2" -v r="$3" 'BEGIN { if (v == "nan" || r == 0) print "nan"; else printf "%.4f", (v - r) / r }')
                        echo "$c,$s,$dx,$status,$name,$1,$2,$3,$rel,"
                    done
                done >>"$summary"
            fi
        done
    done
done
# observed orders: per case, scheme, sensor and measure with three spacings
awk -F, 'NR == 1 { print; next } { key = $1 "," $2 "," $5 "," $6; row[NR] = $0; k[NR] = key
    v[key] = v[key] " " $7; count[key]++ } END {
    for (i = 2; i <= NR; i++) { split(v[k[i]], a, " "); o = ""
        if (count[k[i]] == 3 && a[1] != "nan" && a[3] != "nan") { d1 = a[1] - a[2]; d2 = a[2] - a[3]
            if (d1 < 0) d1 = -d1; if (d2 < 0) d2 = -d2; if (d1 > 0 && d2 > 0) o = sprintf("%.2f", log(d1 / d2) / log(2)) }
        sub(/,$/, "," o, row[i]); print row[i] } }' "$summary" >"$summary.tmp" && mv "$summary.tmp" "$summary"
{
    echo "| case | scheme | dx (m) | status | sensor | measure | value | reference | relative error | observed order |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9, $10 }' "$summary"
} >"$out/summary.md"
echo "wall-pressure-study: $summary, $out/summary.md"
