#!/bin/sh
# Strong and weak scaling across MPI ranks on this machine (docs/scaling.md).
#
#   tools/scaling.sh [BUILD_DIR]      (default build-mpi: meson -Dmpi=enabled)
#   REPEATS=3 OUT=runs/scaling CSV=docs/data/scaling/scaling.csv STEPS_END=0.02
#
# Strong: the 3D dam break (configs/dam_break_3d.yaml) at dx = 0.025 m, the
# same scene on 1 rank x 1 thread, 1 rank x 2 threads (OpenMP) and 2 ranks x
# 1 thread (MPI), and more ranks when RANKS lists them (oversubscribed beyond
# the cores). Weak: a still-water tank whose length along x (the direction
# of the slabs) grows with the rank count, 1 thread per rank, so that every
# rank has the particles one rank has alone. Every case runs REPEATS times
# to t = STEPS_END s; the figures are medians. Writes one line per run and
# one per case (median) to CSV; prints the table with the efficiencies.
# Needs an idle machine: a timing of a busy machine says little.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build-mpi}
repeats=${REPEATS:-3}
out=${OUT:-runs/scaling}
csv=${CSV:-docs/data/scaling/scaling.csv}
end=${STEPS_END:-0.02}
ranks_list=${RANKS:-"1 2"}
# --bind-to none: Open MPI binds each rank to one core by default, which
# would put the OpenMP threads of a rank on the same core
mpiexec="mpiexec --oversubscribe --bind-to none"
[ "$(id -u)" = 0 ] && mpiexec="$mpiexec --allow-run-as-root"
mkdir -p "$out" "$(dirname "$csv")"
pick() { sed -n "s/.*\"$1\": \\([^,]*\\),.*/\\1/p" "$2" | head -n 1; }
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
echo "mode,ranks,threads,particles,steps,repeat,wall_s,particle_steps_per_s,pair_interactions_per_s" >"$csv"

# one case: MODE RANKS THREADS SCENE [--set ...]
run_case() {
    mode=$1 ranks=$2 threads=$3 scene=$4
    shift 4
    rates=""
    for k in $(seq 1 "$repeats"); do
        dir="$out/$mode-r$ranks-t$threads-$k"
        rm -rf "$dir"
        OMP_NUM_THREADS=$threads $mpiexec -n "$ranks" "$build/sluice" run "$scene" --out "$dir" \
            --threads "$threads" --quiet --no-progress --set time.end="$end" \
            --set plugins.hdf5.interval=1000 "$@"
        json="$dir/run.json"
        rate=$(pick particle_steps_per_second "$json")
        echo "$mode,$ranks,$threads,$(pick particles_final "$json"),$(pick steps "$json"),$k,$(pick wall_seconds "$json"),$rate,$(pick pair_interactions_per_second "$json")" >>"$csv"
        rates="$rates $rate"
    done
    m=$(echo "$rates" | tr ' ' '\n' | grep . | median)
    echo "$mode,$ranks,$threads,$(pick particles_final "$json"),$(pick steps "$json"),median,,$m," >>"$csv"
    echo "$m"
}

echo "== strong scaling: configs/dam_break_3d.yaml, dx = 0.025 m, to t = $end s, $repeats runs each"
base=$(run_case strong 1 1 configs/dam_break_3d.yaml --set particles.spacing=0.025)
threads2=$(run_case strong 1 2 configs/dam_break_3d.yaml --set particles.spacing=0.025)
printf "  1 rank  x 1 thread : %.4g particle-steps/s\n" "$base"
printf "  1 rank  x 2 threads: %.4g  (speed-up %.3f)\n" "$threads2" "$(echo "$threads2 $base" | awk '{ print $1 / $2 }')"
for r in $ranks_list; do
    [ "$r" = 1 ] && continue
    rate=$(run_case strong "$r" 1 configs/dam_break_3d.yaml --set particles.spacing=0.025)
    printf "  %d ranks x 1 thread : %.4g  (speed-up %.3f, efficiency %.3f)\n" "$r" "$rate" \
        "$(echo "$rate $base" | awk '{ print $1 / $2 }')" "$(echo "$rate $base $r" | awk '{ print $1 / $2 / $3 }')"
done

echo "== weak scaling: still water 1 m deep in a tank 2 m x 0.5 m per rank along x, dx = 0.025 m"
for r in $ranks_list; do
    length=$(echo "$r" | awk '{ print 2 * $1 }')
    rate=$(run_case weak "$r" 1 configs/dam_break_3d.yaml --set particles.spacing=0.025 \
        --set "geometry.fluid.0.max=[$length, 0.5, 1.0]" --set "geometry.walls.0.max=[$length, 0.5, 1.5]" \
        --set "domain.max=[$(echo "$length" | awk '{ print $1 + 0.3 }'), 0.8, 3.0]")
    [ "$r" = 1 ] && weak1=$rate
    printf "  %d rank(s): %.4g particle-steps/s, %.4g per rank (efficiency %.3f)\n" "$r" "$rate" \
        "$(echo "$rate $r" | awk '{ print $1 / $2 }')" "$(echo "$rate ${weak1:-$rate} $r" | awk '{ print $1 / $2 / $3 }')"
done
echo "per-run figures: $csv"
