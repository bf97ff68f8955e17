#!/bin/sh
# Stability stress test (docs/stability.md): runs a scene over a grid of
# parameters and writes a stability map: for every cell, whether the run
# completed, was stopped by the watchdog (unstable) or failed otherwise, at
# which step and time it stopped, the watchdog's message, the largest density
# deviation (run.json) and the drift of the total energy (energy_gauge,
# appended to the scene) at the end or at the stop.
#
#   tools/stress.sh [BUILD] SCENE [AXIS=v1,v2,... ...]     (1 to 3 axes)
#     BUILD  build directory (default build; taken as BUILD when it holds a
#            `sluice` program)
#     SCENE  a scene file, or a preset:
#            dam-break  configs/dam_break_2d.yaml, U_max = sqrt(2 g H),
#                       H = 2 m (6.26 m/s); default axes
#                       c0_factor=5,10,20 cfl=0.2,0.4,0.8
#            jump       configs/hydraulic_jump_jonsson2016.yaml, U_max =
#                       V1 + sqrt(g d1), d1 = 0.02 m (1.5 + 0.443 m/s at the
#                       scene's V1); default axes
#                       c0_factor=5,10,20 wall=penalty_contact,dbc,mdbc
#   Axes (the first two span the map; a third gives one PNG per value):
#     c0_factor  tait speed of sound = factor x U_max (U_MAX=... for a scene
#                file; the jump's U_max follows the froude axis)
#     cfl        time_step courant
#     dx         particles.spacing (m)
#     kernel     wendland_c2 | cubic_spline (replaces the kernel's line)
#     wall       dbc | mdbc | ghost_particles | penalty_contact |
#                repulsive_force (replaces the wall scheme's line)
#     alpha      artificial_viscosity alpha
#     froude     inflow Froude number V1 / sqrt(g d1) at the scene's d1
#                (inlet.depth): sets inlet.velocity
#   Environment: END (simulated seconds, default 0.5), OUT (default
#   runs/stress/<scene>), JOBS (cells at once, default 1; each runs on one
#   thread), NICE (nice level, default 10), SET (extra --set arguments for
#   every cell, e.g. SET="--set particles.spacing=0.04"), INTERVAL (energy
#   sample interval, default 0.01 s), U_MAX (m/s, for a scene file).
#
# Writes OUT/stability.csv (one row per cell), OUT/stability.md (the same as
# a table) and OUT/stability.png (or OUT/stability-<axis3>_<value>.png), and
# keeps each cell's run directory OUT/cells/<name>/ (run.json, energy.csv).
# Exit status of a cell: 0 complete, 3 unstable (watchdog), other failed.
set -eu
cd "$(dirname "$0")/.."

# ------------------------------------------------------------ one cell --
if [ "${1:-}" = "__cell" ]; then
    # __cell BUILD SCENE UMAX OUT END INTERVAL "AXES" "VALUES"
    build=$2 scene=$3 umax=$4 out=$5 end=$6 interval=$7 axes=$8 values=$9
    name=$(echo "$values" | tr ' ' '_' | tr -c 'A-Za-z0-9_.\n-' '_')
    run="$out/cells/$name"
    rm -rf "$run"
    mkdir -p "$run"
    cp "$scene" "$run/scene.yaml"
    sets=""
    c0f="" froude=""
    set -- $values
    for axis in $axes; do
        value=$1
        shift
        case $axis in
        c0_factor) c0f=$value ;;
        cfl) sets="$sets --set plugins.time_step.courant=$value" ;;
        dx) sets="$sets --set particles.spacing=$value" ;;
        alpha) sets="$sets --set plugins.artificial_viscosity.alpha=$value" ;;
        froude) froude=$value ;;
        kernel)
            sed -i "s/^  \(wendland_c2\|cubic_spline\):.*\$/  $value: {}/" "$run/scene.yaml"
            grep -q "^  $value: {}\$" "$run/scene.yaml" || { echo "stress: no kernel line to replace" >&2; exit 2; } ;;
        wall)
            sed -i "s/^  \(dbc\|mdbc\|ghost_particles\|penalty_contact\|repulsive_force\):.*\$/  $value: {}/" "$run/scene.yaml"
            grep -q "^  $value: {}\$" "$run/scene.yaml" || { echo "stress: no wall-scheme line to replace" >&2; exit 2; } ;;
        *) echo "stress: unknown axis '$axis'" >&2; exit 2 ;;
        esac
    done
    if [ -n "$froude" ]; then
        # V1 = Fr sqrt(g d1), d1 the inlet's depth; U_max = V1 + sqrt(g d1)
        d1=$(sed -n 's/^    depth: *\([0-9.eE+-]*\).*/\1/p' "$scene" | head -n 1)
        [ -n "$d1" ] || { echo "stress: froude needs an inlet with a depth" >&2; exit 2; }
        v1=$(awk -v f="$froude" -v d="$d1" 'BEGIN { printf "%.6g", f * sqrt(9.81 * d) }')
        umax=$(awk -v v="$v1" -v d="$d1" 'BEGIN { printf "%.6g", v + sqrt(9.81 * d) }')
        sets="$sets --set plugins.inlet.velocity=$v1"
    fi
    [ -n "$c0f" ] && sets="$sets --set plugins.tait.speed_of_sound=$(awk -v f="$c0f" -v u="$umax" 'BEGIN { printf "%.6g", f * u }')"
    printf '  energy_gauge: {interval: %s}\n' "$interval" >>"$run/scene.yaml"
    # outputs that cost time and say nothing about stability: once, at the end
    for p in hdf5 vorticity; do
        grep -q "^  $p:" "$run/scene.yaml" && sets="$sets --set plugins.$p.interval=$end"
    done
    echo "stress: $name ($axes = $values)" >&2
    set +e
    # shellcheck disable=SC2086
    nice -n "${NICE:-10}" "$build/sluice" run "$run/scene.yaml" --out "$run" --quiet --no-progress \
        --threads 1 --set time.end="$end" $sets ${SET:-} 2>"$run/stderr.txt"
    rc=$?
    set -e
    case $rc in 0) status=complete ;; 3) status=unstable ;; *) status=failed ;; esac
    json() { [ -f "$run/run.json" ] && sed -n "s/^  \"$1\": \"\{0,1\}\([^\",]*\).*/\1/p" "$run/run.json" | head -n 1; }
    failure=""
    [ -f "$run/run.json" ] && failure=$(sed -n 's/^  "failure": "\(.*\)",$/\1/p' "$run/run.json" | tr ',' ';' | sed 's/\\"/'"'"'/g')
    [ -z "$failure" ] && [ "$rc" -ne 0 ] && failure=$(head -n 1 "$run/stderr.txt" | tr ',' ';')
    energy="," 
    [ -f "$run/energy.csv" ] && energy=$(awk -F, 'NR > 1 { t = $1; d = $6 } END { printf "%s,%s", d, t }' "$run/energy.csv")
    echo "$(echo "$values" | tr ' ' ','),$status,$rc,$(json steps),$(json simulated_time),$end,$(json max_density_deviation),$energy,$(json wall_seconds),$(json particles_initial),$failure" >"$run/row.csv"
    exit 0
fi

# ---------------------------------------------------------------- main --
build=build
if [ $# -gt 0 ] && [ -x "$1/sluice" ]; then
    build=$1
    shift
fi
[ $# -ge 1 ] || { sed -n '2,40p' "$0" >&2; exit 2; }
target=$1
shift
case $target in
dam-break)
    scene=configs/dam_break_2d.yaml
    umax=$(awk 'BEGIN { printf "%.6g", sqrt(2 * 9.81 * 2.0) }')
    [ $# -eq 0 ] && set -- c0_factor=5,10,20 cfl=0.2,0.4,0.8 ;;
jump)
    scene=configs/hydraulic_jump_jonsson2016.yaml
    umax=$(awk 'BEGIN { printf "%.6g", 1.5 + sqrt(9.81 * 0.02) }')
    [ $# -eq 0 ] && set -- c0_factor=5,10,20 wall=penalty_contact,dbc,mdbc ;;
*)
    scene=$target
    umax=${U_MAX:-}
    [ -f "$scene" ] || { echo "stress: no scene '$scene'" >&2; exit 2; } ;;
esac
[ $# -ge 1 ] && [ $# -le 3 ] || { echo "stress: give 1 to 3 axes AXIS=v1,v2,..." >&2; exit 2; }
for a in "$@"; do
    case ${a%%=*} in
    c0_factor) [ -n "$umax" ] || { echo "stress: c0_factor needs U_MAX=... for a scene file" >&2; exit 2; } ;;
    cfl | dx | kernel | wall | alpha | froude) ;;
    *) echo "stress: unknown axis '${a%%=*}'" >&2; exit 2 ;;
    esac
done
end=${END:-0.5}
interval=${INTERVAL:-0.01}
jobs=${JOBS:-1}
out=${OUT:-runs/stress/$(basename "$scene" .yaml)}
mkdir -p "$out"
axes=""
for a in "$@"; do axes="$axes ${a%%=*}"; done
axes=${axes# }
# the cells: the cartesian product of the axes' values, first axis slowest
cells=$(for a in "$@"; do echo "${a#*=}"; done | awk -F, '
    { n[NR] = NF; for (k = 1; k <= NF; k++) v[NR, k] = $k; count = NR }
    END {
        total = 1; for (a = 1; a <= count; a++) total *= n[a]
        for (c = 0; c < total; c++) {
            r = c; line = ""
            for (a = count; a >= 1; a--) { k = r % n[a]; r = int(r / n[a]); line = v[a, k + 1] (line == "" ? "" : " ") line }
            print line
        }
    }')
echo "stress: $(echo "$cells" | wc -l) cells of $axes, $scene to $end s, $jobs at a time" >&2
echo "$cells" | tr ' ' ':' | xargs -P "$jobs" -I{} sh -c \
    'sh "$0" __cell "$1" "$2" "$3" "$4" "$5" "$6" "$7" "$(echo "$8" | tr ":" " ")"' \
    "$0" "$build" "$scene" "${umax:-0}" "$out" "$end" "$interval" "$axes" {}
header="$(echo "$axes" | tr ' ' ','),status,exit_code,steps,simulated_time_s,end_s,max_density_deviation,energy_drift,energy_time_s,wall_s,particles,failure"
{
    echo "$header"
    echo "$cells" | while read -r line; do
        name=$(echo "$line" | tr ' ' '_' | tr -c 'A-Za-z0-9_.\n-' '_')
        cat "$out/cells/$name/row.csv"
    done
} >"$out/stability.csv"
naxes=$(echo "$axes" | wc -w)
{
    echo "| $(echo "$axes" | sed 's/ / | /g') | status | steps | stopped at (s) | max density deviation | energy drift | wall (s) | watchdog |"
    echo "|$(for a in $axes; do printf -- '---|'; done)---|---|---|---|---|---|---|"
    awk -F, -v n="$naxes" 'NR > 1 {
        line = "|"; for (k = 1; k <= n; k++) line = line " " $k " |"
        printf "%s %s | %s | %s | %s | %s | %s | %s |\n", line, $(n+1), $(n+3), $(n+4), $(n+6), $(n+7), $(n+9), $(n+11) }' "$out/stability.csv"
} >"$out/stability.md"

# ---------------------------------------------------------------- map --
# x: the first axis, y: the second (one row when there is none), one PNG per
# value of a third. Complete runs: green circles labelled with the energy
# drift; unstable: red crosses labelled with the time the watchdog stopped
# them; failed: black squares.
plot_map() { # plot_map FILTER_VALUE PNG TITLE
    awk -F, -v n="$naxes" -v want="$1" '
        NR == 1 { next }
        n == 3 && $3 != want { next }
        {
            if (!($1 in xi)) { xi[$1] = nx++; xl[nx - 1] = $1 }
            y = n >= 2 ? $2 : "-"
            if (!(y in yi)) { yi[y] = ny++; yl[ny - 1] = y }
            s = $(n+1); code = s == "complete" ? 0 : s == "unstable" ? 1 : 2
            label = code == 0 ? sprintf("%+.2g", $(n+7)) : code == 1 ? sprintf("t=%.3g s", $(n+4)) : "failed"
            printf "%d %d %d \"%s\"\n", xi[$1], yi[y], code, label > "/dev/stdout"
        }
        END {
            printf "# xtics (" > "/dev/stderr"
            for (k = 0; k < nx; k++) printf "%s\"%s\" %d", k ? ", " : "", xl[k], k > "/dev/stderr"
            printf ")\n# ytics (" > "/dev/stderr"
            for (k = 0; k < ny; k++) printf "%s\"%s\" %d", k ? ", " : "", yl[k], k > "/dev/stderr"
            printf ")\n# %d %d\n", nx, ny > "/dev/stderr"
        }' "$out/stability.csv" >"$out/map.dat" 2>"$out/map.tics"
    xt=$(sed -n '1s/^# xtics //p' "$out/map.tics")
    yt=$(sed -n '2s/^# ytics //p' "$out/map.tics")
    nx=$(sed -n '3s/^# \([0-9]*\) \([0-9]*\)/\1/p' "$out/map.tics")
    ny=$(sed -n '3s/^# \([0-9]*\) \([0-9]*\)/\2/p' "$out/map.tics")
    xlabel=$(echo "$axes" | cut -d' ' -f1)
    ylabel=$(echo "$axes" | cut -d' ' -f2 -s)
    gnuplot <<EOF
set terminal pngcairo size $((260 + 170 * nx)),$((200 + 110 * ny)) noenhanced font ',11'
set output '$2'
set title "$3"
set xrange [-0.6:$nx - 0.4]; set yrange [-0.6:$ny - 0.4]
set xtics $xt; set ytics $yt
set xlabel '$xlabel'; set ylabel '${ylabel:-}'
set key below
set style fill solid
plot '$out/map.dat' using (\$3 == 0 ? \$1 : 1/0):2 with points pt 7 ps 3 lc rgb '#2ca02c' title 'complete (label: energy drift)', \
     '' using (\$3 == 1 ? \$1 : 1/0):2 with points pt 2 ps 3 lw 3 lc rgb '#d62728' title 'unstable (label: stop time)', \
     '' using (\$3 == 2 ? \$1 : 1/0):2 with points pt 5 ps 3 lc rgb 'black' title 'failed', \
     '' using 1:(\$2 - 0.28):4 with labels notitle
EOF
}
if command -v gnuplot >/dev/null 2>&1; then
    base="$(basename "$scene" .yaml), to $end s"
    if [ "$naxes" -eq 3 ]; then
        for v in $(echo "$3" | sed 's/^[^=]*=//' | tr ',' ' '); do
            plot_map "$v" "$out/stability-$(echo "$axes" | cut -d' ' -f3)_$v.png" "$base, $(echo "$axes" | cut -d' ' -f3) = $v"
        done
    else
        plot_map "" "$out/stability.png" "$base"
    fi
    rm -f "$out/map.dat" "$out/map.tics"
else
    echo "stress: gnuplot not found: no map drawn" >&2
fi
cat "$out/stability.md"
