#!/bin/sh
# Wall schemes compared on the same scenes (docs/boundary-study.md).
#
#   tools/boundary-study.sh [BUILD_DIR]            (default: build)
#   SCHEMES="dbc mdbc" tools/boundary-study.sh     (a subset)
#   QUICK=1 tools/boundary-study.sh                (short runs: a smoke test)
#
# For every wall scheme it runs, with the walls' geometry unchanged and only
# the scheme's line of YAML switched:
#   still     configs/still_water_2d.yaml, 10 s: hydrostatic pressure error at
#             the bottom (point gauges 2h above the floor, mean over the last
#             second, against rho g (H - y)), particles that crossed a wall,
#             the first-layer gap between fluid and wall;
#   dam       configs/dam_break_2d.yaml, 1.5 s: front error against Martin &
#             Moyce (a = 2.25 in, T in [0.5, 2.5]), crossings through the
#             impact on the far wall;
#   poiseuille configs/poiseuille_2d.yaml (no-slip schemes): L2 error of the
#             steady profile against the analytic one, 40 particles across;
#   obstacles configs/dam_break_obstacles_2d.yaml, 1 s: the dam break with
#             a weir and a plate 2 dx thick in the surge's path: crossings
#             and the smallest fluid-wall distance through the impacts;
#   channel   configs/inclined_channel_2d.yaml, 20 s: the wall-parallel
#             velocity profile of a uniform flow down a slope with only the
#             artificial viscosity (the "artificial boundary layer" of seed
#             000): slip ratio u(dx/2) / u_surface;
# and the run time and steps/s of each run. The scheme `mixed` runs the
# obstacles scene as configs/ has it: dbc for the tank, penalty_contact for
# the weir, repulsive_force for the plate. Writes runs/boundary-study/
# summary.csv, summary.md, and PNG plots (gnuplot; `apt-get install
# gnuplot-nox` if missing: the plots are skipped without it).
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
out=${OUT:-runs/boundary-study}
quick=${QUICK:-0}
schemes=${SCHEMES:-dbc mdbc ghost_no_slip ghost_free_slip penalty_contact repulsive_force mixed}
data=tests/scenes/data/martin_moyce_1952_n2.csv
mkdir -p "$out"

# The YAML line of each scheme (the scenes' walls are handled by `dbc: {}`).
scheme_line() {
    case "$1" in
    dbc) echo "dbc: {}" ;;
    mdbc) echo "mdbc: {}" ;;
    ghost_no_slip) echo "ghost_particles: {slip: no_slip}" ;;
    ghost_free_slip) echo "ghost_particles: {slip: free_slip}" ;;
    penalty_contact) echo "penalty_contact: {}" ;;
    repulsive_force) echo "repulsive_force: {}" ;;
    mixed) echo "mixed" ;;
    *) echo "boundary-study: unknown scheme '$1'" >&2; exit 2 ;;
    esac
}
# the plugin (the walls' `scheme` key) of each scheme
plugin_name() {
    case "$1" in ghost_*) echo ghost_particles ;; *) echo "$1" ;; esac
}
no_slip() {
    case "$1" in dbc | mdbc | ghost_no_slip) return 0 ;; *) return 1 ;; esac
}

# scene SCHEME SOURCE EXTRA_PLUGIN_LINES -> path of the scene with the scheme
scene() {
    file="$out/$1-$(basename "$2")"
    line=$(scheme_line "$1")
    sed "s/^  dbc: {}\$/  $line/" "$2" >"$file"
    grep -q "^  $line\$" "$file" || { echo "boundary-study: no 'dbc: {}' line in $2" >&2; exit 2; }
    printf '%s' "$3" >>"$file"
    echo "$file"
}

json() { sed -n "s/.*\"$2\": \\([0-9.eE+-]*\\).*/\\1/p" "$1/run.json" | head -n 1; }
# last value of column $2 of a CSV (header skipped)
last() { awk -F, -v c="$2" 'NR > 1 { v = $c } END { print v }' "$1"; }

end_still=10; end_dam=1.5; end_obstacles=1.0; end_pois=1.5; end_channel=20
if [ "$quick" = 1 ]; then end_still=1; end_dam=0.6; end_obstacles=0.6; end_pois=0.2; end_channel=2; fi

# row SCHEME CASE STATUS RUN_DIR METRIC VALUE WITH_WALLS: one line of summary.csv
row() {
    steps=$(json "$4" steps); seconds=$(json "$4" wall_seconds)
    crossed=""; gap=""
    if [ "$7" = 1 ] && [ -f "$4/walls.csv" ]; then crossed=$(last "$4/walls.csv" 3); gap=$(last "$4/walls.csv" 5); fi
    echo "$1,$2,$3,$steps,$seconds,$(awk -v a="$steps" -v b="$seconds" 'BEGIN { printf "%.1f", a / b }'),$(json "$4" particle_steps_per_second),$5,$6,$crossed,$gap" >>"$out/summary.csv"
}

echo "scheme,case,status,steps,wall_s,steps_per_s,particle_steps_per_s,metric,value,crossed_total,gap_layer_m" >"$out/summary.csv"
for s in $schemes; do
    echo "== $s" >&2
    scheme_line "$s" >/dev/null
    # --------------------------------------------------------------- obstacles
    run="$out/$s/obstacles"
    sc="$out/$s-dam_break_obstacles_2d.yaml"
    if [ "$s" = mixed ]; then
        cp configs/dam_break_obstacles_2d.yaml "$sc"
    else
        sed -e '/^  penalty_contact: {}  *# the weir$/d' -e '/^  repulsive_force: {}  *# the plate$/d' \
            -e "s/^  dbc: {}  *# the tank\$/  $(scheme_line "$s")/" \
            -e "s/scheme: [a-z_]*}/scheme: $(plugin_name "$s")}/" configs/dam_break_obstacles_2d.yaml >"$sc"
        [ "$(grep -c "scheme: $(plugin_name "$s")}" "$sc")" = 3 ] && grep -q "^  $(scheme_line "$s")\$" "$sc" ||
            { echo "boundary-study: configs/dam_break_obstacles_2d.yaml is not in the expected form" >&2; exit 2; }
    fi
    status=complete
    "$build/sluice" run "$sc" --out "$run" --quiet --no-progress --set time.end=$end_obstacles \
        --set plugins.hdf5.interval=$end_obstacles >/dev/null 2>&1 || status=failed
    if [ -f "$run/run.json" ]; then
        gap=$(awk -F, 'NR > 1 && $4 == $4 + 0 && (g == "" || $4 < g) { g = $4 } END { printf "%.4f", g / 0.02 }' "$run/walls.csv")
        row "$s" obstacles "$status" "$run" smallest_gap_dx "$gap" 1
    fi
    [ "$s" = mixed ] && continue
    # ------------------------------------------------------------- still tank
    run="$out/$s/still"
    sc=$(scene "$s" configs/still_water_2d.yaml "  point_gauge: {points: [[0.3, 0.06], [0.5, 0.06], [0.7, 0.06]], fields: pressure, interval: 0.1, file: bottom.csv}
  wall_monitor: {interval: 0.1}
")
    status=complete
    "$build/sluice" run "$sc" --out "$run" --quiet --no-progress --set time.end=$end_still \
        --set plugins.hdf5.interval=$end_still >/dev/null 2>&1 || status=failed
    if [ -f "$run/run.json" ]; then
        err=$(awk -F, -v t0="$end_still" '
            NR > 1 && $1 >= t0 - 1 - 1e-9 { for (k = 2; k <= 4; k++) if ($k == $k + 0) { s += $k; n++ } }
            END { e = 1000 * 9.81 * (0.5 - 0.06); if (n) printf "%.4f", (s / n - e) / e; else print "nan" }' "$run/bottom.csv")
        row "$s" still "$status" "$run" bottom_pressure_error "$err" 1
    fi
    # -------------------------------------------------------------- dam break
    run="$out/$s/dam"
    sc=$(scene "$s" configs/dam_break_2d.yaml "  wall_monitor: {interval: 0.01}
")
    status=complete
    "$build/sluice" run "$sc" --out "$run" --quiet --no-progress --set time.end=$end_dam \
        --set plugins.hdf5.interval=$end_dam >/dev/null 2>&1 || status=failed
    if [ -f "$run/run.json" ]; then
        err=$(awk -F, -f tools/martin-moyce-error.awk "$data" "$run/front.csv")
        row "$s" dam "$status" "$run" front_error_worst "$err" 1
    fi
    # ------------------------------------------------------------- Poiseuille
    if no_slip "$s"; then
        run="$out/$s/poiseuille"
        pts=$(awk 'BEGIN { for (k = 0; k < 20; k++) printf "%s[1.5e-4, %.6g]", k ? ", " : "", (k + 0.5) * 5e-5 }')
        sc=$(scene "$s" configs/poiseuille_2d.yaml "  point_gauge: {points: [$pts], fields: velocity, interval: 0.1, min_kernel_sum: 0.2, file: profile.csv}
")
        status=complete
        "$build/sluice" run "$sc" --out "$run" --quiet --no-progress --set time.end=$end_pois \
            --set plugins.hdf5.interval=$end_pois >/dev/null 2>&1 || status=failed
        if [ -f "$run/run.json" ]; then
            err=$(awk -F, 'END {
                    nu = 1e-6; F = 1e-4; L = 1e-3
                    for (k = 0; k < 20; k++) {
                        y = (k + 0.5) * 5e-5; u = $(2 + 2 * k); a = F / (2 * nu) * y * (L - y)
                        d += (u - a) ^ 2; n2 += a ^ 2
                    }
                    printf "%.4f", sqrt(d / n2)
                }' "$run/profile.csv")
            row "$s" poiseuille "$status" "$run" profile_l2_error "$err" 0
        fi
    fi
    # --------------------------------------------------------- inclined channel
    run="$out/$s/channel"
    sc=$(scene "$s" configs/inclined_channel_2d.yaml "")
    status=complete
    "$build/sluice" run "$sc" --out "$run" --quiet --no-progress --set time.end=$end_channel \
        >/dev/null 2>&1 || status=failed
    if [ -f "$run/run.json" ]; then
        slip=$(awk -F, 'END { top = 0; for (k = 2; k <= NF; k += 2) if ($k == $k + 0 && $k > top) top = $k
                              if (top > 0) printf "%.4f", $2 / top; else print "nan" }' "$run/points.csv")
        row "$s" channel "$status" "$run" slip_ratio "$slip" 1
    fi
done

# ------------------------------------------------------------ Markdown table
{
    echo "| scheme | case | status | steps | wall s | steps/s | particle-steps/s | metric | value | crossed | first-layer gap (m) |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
    awk -F, 'NR > 1 { printf "| %s |", $1; for (k = 2; k <= NF; k++) printf " %s |", $k; printf "\n" }' "$out/summary.csv"
} >"$out/summary.md"

# ------------------------------------------------------------------- plots
if command -v gnuplot >/dev/null 2>&1; then
    plot=""
    for s in $schemes; do
        [ -f "$out/$s/dam/front.csv" ] && plot="$plot${plot:+, }'$out/$s/dam/front.csv' every ::1 using (\$1*sqrt(2*9.81)):(\$2) with lines title '$s'"
    done
    [ -n "$plot" ] && gnuplot <<EOF
set terminal pngcairo size 900,600 noenhanced
set output '$out/dam_front.png'
set datafile separator ','
set xlabel 'T = t sqrt(2g/L)'; set ylabel 'Z = x_front / L'; set key left top
set xrange [0:3]
plot $plot, '$data' using (\$1 == 2.25 ? \$2 : 1/0):3 with points pt 7 title 'Martin & Moyce a = 2.25 in'
EOF
    plot=""
    for s in $schemes; do
        [ -f "$out/$s/still/bottom.csv" ] && plot="$plot${plot:+, }'$out/$s/still/bottom.csv' every ::1 using 1:((\$2+\$3+\$4)/3/(1000*9.81*0.44)-1) with lines title '$s'"
    done
    [ -n "$plot" ] && gnuplot <<EOF
set terminal pngcairo size 900,600 noenhanced
set output '$out/still_pressure.png'
set datafile separator ','
set xlabel 't (s)'; set ylabel 'p / (rho g (H - y)) - 1 at y = 2h'
plot $plot
EOF
    plot=""
    for s in $schemes; do
        [ -f "$out/$s/poiseuille/profile.csv" ] &&
            awk -F, 'END { for (k = 0; k < 20; k++) print (k + 0.5) * 5e-5, $(2 + 2 * k) }' "$out/$s/poiseuille/profile.csv" >"$out/$s/poiseuille/profile.dat" &&
            plot="$plot${plot:+, }'$out/$s/poiseuille/profile.dat' using 2:1 with linespoints title '$s'"
    done
    [ -n "$plot" ] && gnuplot <<EOF
set terminal pngcairo size 900,600 noenhanced
set output '$out/poiseuille_profile.png'
set xlabel 'u (m/s)'; set ylabel 'y (m)'; set key left top
plot $plot, [0:1e-3] (1e-4/(2e-6))*x*(1e-3-x) with lines lw 2 title 'analytic', '+' using (0):(0) notitle with dots
EOF
    plot=""
    for s in $schemes; do
        [ -f "$out/$s/channel/points.csv" ] &&
            awk -F, 'END { for (k = 0; k < 18; k++) print 0.0025 + 0.005 * k, $(2 + 2 * k) }' "$out/$s/channel/points.csv" >"$out/$s/channel/profile.dat" &&
            plot="$plot${plot:+, }'$out/$s/channel/profile.dat' using 2:1 with linespoints title '$s'"
    done
    [ -n "$plot" ] && gnuplot <<EOF
set terminal pngcairo size 900,600 noenhanced
set output '$out/channel_profile.png'
set xlabel 'u (m/s)'; set ylabel 'y (m)'; set key left top
plot $plot
EOF
else
    echo "boundary-study: gnuplot not found; plots skipped (apt-get install gnuplot-nox)" >&2
fi
cat "$out/summary.md"
