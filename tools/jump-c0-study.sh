#!/bin/sh
# The speed of sound each wall scheme needs on seed 000's hydraulic jump
# (configs/hydraulic_jump_jonsson2016.yaml at d1/4): for each scheme, runs
# the scene with c0 going up a ladder until a run reaches time.end without
# the watchdog stopping it, and reports for every run how it ended (the
# watchdog's message names step, particle and field), the largest density
# deviation it reached, and the conjugate depth statistics A and P at
# x = 1 m over the window (sluice-analyze conjugate). A scheme written
# "a+b" runs wall scheme a with plugin b loaded too (wall_backstop under a
# particle scheme). Seed 000 needed
# c0 = 1484 m/s with LS-DYNA's penalty walls; docs/validation.md discusses
# the figures.
#
#   tools/jump-c0-study.sh [BUILD_DIR] [SCHEMES] [C0_LADDER]
#     defaults: build, "penalty_contact dbc mdbc ghost_particles repulsive_force
#               ghost_particles+wall_backstop mdbc+wall_backstop",
#               "10 20 40 80"
#   END=5 FROM=2.5 TO=5 DIVISOR=4 OUT=runs/jump-c0-study
#
# Writes OUT/summary.csv and OUT/summary.md.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
schemes=${2:-penalty_contact dbc mdbc ghost_particles repulsive_force ghost_particles+wall_backstop mdbc+wall_backstop}
ladder=${3:-10 20 40 80}
end=${END:-5}
from=${FROM:-2.5}
to=${TO:-5}
divisor=${DIVISOR:-4}
out=${OUT:-runs/jump-c0-study}
threads=${THREADS:-}
mkdir -p "$out"
dx=$(awk -v n="$divisor" 'BEGIN { printf "%.10g", 0.02 / n }')
analyze="$build/tools/sluice-analyze"
pick() { sed -n "s|^$1 = \([^ ]*\).*|\1|p" "$2" | head -n 1; }
echo "scheme,c0_m_s,divisor,status,simulated_s,end_s,steps,wall_s,threads,max_density_deviation,A,P,failure" >"$out/summary.csv"
for scheme in $schemes; do
    scene="$out/scene-$scheme.yaml"
    # "ghost_particles+wall_backstop": the scheme and the plugins after the +
    lines=$(echo "$scheme" | sed 's/+/: {}\\n  /g')
    sed "s/^  penalty_contact: {}.*\$/  $lines: {}/" configs/hydraulic_jump_jonsson2016.yaml >"$scene"
    grep -q "^  ${scheme%%+*}: {}\$" "$scene" || { echo "jump-c0-study: cannot set the wall scheme" >&2; exit 2; }
    for c0 in $ladder; do
        run="$out/$scheme-c0_$c0"
        echo "== $scheme, c0 = $c0 m/s, d1/$divisor, $end s" >&2
        set +e
        "$build/sluice" run "$scene" --out "$run" --quiet --no-progress ${threads:+--threads "$threads"} \
            --set particles.spacing="$dx" --set time.end="$end" --set plugins.hdf5.interval="$end" \
            --set plugins.tait.speed_of_sound="$c0"
        rc=$?
        set -e
        json() { sed -n "s/.*\"$1\": \"\{0,1\}\([^\",]*\).*/\1/p" "$run/run.json" | head -n 1; }
        failure=$(sed -n 's/.*"failure": "\(.*\)",$/\1/p' "$run/run.json" | tr ',' ';')
        A=; P=
        if [ "$rc" -eq 0 ]; then
            "$analyze" conjugate "$run" --d1 0.02 --v1 1.5 --from "$from" --to "$to" --x 1.0 >"$run/conjugate.txt"
            A=$(pick A "$run/conjugate.txt"); P=$(pick P "$run/conjugate.txt")
        fi
        dev=$(json max_density_deviation)
        echo "$scheme,$c0,$divisor,$(json status),$(json simulated_time),$end,$(json steps),$(json wall_seconds),$(json threads),$dev,$A,$P,$failure" >>"$out/summary.csv"
        [ "$rc" -eq 0 ] && break
    done
done
{
    echo "| wall scheme | c0 (m/s) | status | reached (s) | steps | wall time (s) | A | P | watchdog |"
    echo "|---|---|---|---|---|---|---|---|---|"
    awk -F, 'NR > 1 { printf "| %s | %s | %s | %.3f | %s | %.0f | %s | %s | %s |\n", $1, $2, $4, $5, $7, $8, $11, $12, $13 }' "$out/summary.csv"
} >"$out/summary.md"
cat "$out/summary.md"
