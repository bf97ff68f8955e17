#!/bin/sh
# Seed 004's abrupt-drop jumps (configs/abrupt_drop_T1.yaml .. T7.yaml):
# runs each test, classifies its jump type from the run's free surface
# (sluice-analyze drop-type over [FROM, END]) next to table 1's observed
# type, and writes the amplitude spectra of the free surface upstream
# (x = 0.7 m) and downstream (x = 1.2 m) of the drop and of the bed pressure
# at x = 0.9 m, with their dominant frequencies (seed 004 figs. 13-17:
# about 0.1 Hz in T1).
#
#   tools/abrupt-drop-study.sh [BUILD_DIR] [TESTS]
#     defaults: build, "T1 T2 T3 T4 T5 T6 T7"
#   END=60 FROM=10 OUT=runs/abrupt-drop-study THREADS= CHECKPOINT=2
#
# Every run writes a checkpoint every CHECKPOINT seconds (the newest kept;
# 0: none). When OUT/<test> already holds a checkpoint, the run continues
# from the newest one to END (sluice run --restart, into the same
# directory, so the gauge tables run on): a study is lengthened by running
# it again with a later END. Appends one line per test to OUT/summary.csv
# (created with its header when missing, so several invocations may share
# one OUT).
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
tests=${2:-T1 T2 T3 T4 T5 T6 T7}
end=${END:-60}
from=${FROM:-10}
out=${OUT:-runs/abrupt-drop-study}
threads=${THREADS:-}
checkpoint=${CHECKPOINT:-2}
analyze="$build/tools/sluice-analyze"
mkdir -p "$out"
pick() { sed -n "s|^$1 = \([^ ]*\).*|\1|p" "$2" | head -n 1; }
[ -f "$out/summary.csv" ] || echo "test,observed_type,status,simulated_s,wall_s,threads,max_density_deviation,window_from_s,window_to_s,fraction_A,fraction_B,fraction_wave,wave_episode_rate_hz,type,f_eta_x0.7_hz,f_eta_x1.2_hz,f_p_x0.9_hz,failure" >"$out/summary.csv"
for t in $tests; do
    scene="configs/abrupt_drop_$t.yaml"
    run="$out/$t"
    observed=$(awk -F, -v t="$t" '$1 == t { print $12 }' tests/scenes/data/depadova2017_table1.csv)
    drop_x=$(sed -n 's|^#   sluice-analyze drop-type [^ ]* --drop-x \([^ ]*\).*|\1|p' "$scene")
    latest=$(ls "$run"/checkpoint_*.h5 2>/dev/null | tail -n 1)
    echo "== $t ($observed), $end s${latest:+, continued from $latest}" >&2
    set +e
    "$build/sluice" run "$scene" --out "$run" --quiet --no-progress ${threads:+--threads "$threads"} \
        ${latest:+--restart "$latest"} --set time.end="$end" \
        --set checkpoint.interval="$checkpoint" --set checkpoint.keep=1 2>>"$run.log"
    rc=$?
    set -e
    status=complete; [ "$rc" = 0 ] || status="failed($rc)"
    json="$run/run.json"
    simulated=$(sed -n 's/.*"simulated_time": \([^,]*\),.*/\1/p' "$json")
    wall=$(sed -n 's/.*"wall_seconds": \([^,]*\),.*/\1/p' "$json")
    nthreads=$(sed -n 's/.*"threads": \([^,]*\),.*/\1/p' "$json")
    deviation=$(sed -n 's/.*"max_density_deviation": \([^,]*\),.*/\1/p' "$json")
    failure=$(sed -n 's/.*"failure": "\(.*\)",$/\1/p' "$json" | tr ',' ';')
    to=$simulated
    fa=; fb=; fw=; rate=; type=; f07=; f12=; fp=
    if awk -v a="$from" -v b="$to" 'BEGIN { exit !(b > a + 1) }'; then
        "$analyze" drop-type "$run" --drop-x "$drop_x" --from "$from" --to "$to" >"$run/drop_type.txt"
        fa=$(pick fraction_A "$run/drop_type.txt"); fb=$(pick fraction_B "$run/drop_type.txt")
        fw=$(pick fraction_wave "$run/drop_type.txt"); rate=$(pick wave_episode_rate "$run/drop_type.txt")
        type=$(pick type "$run/drop_type.txt")
        # columns: free_surface_gauge positions 0.1, 0.15, ... (x = 0.7 m is
        # eta_x12, x = 1.2 m eta_x22); point_gauge p0 at (0.9, 0.01)
        "$analyze" spectrum "$run" --column eta_x12 --from "$from" --to "$to" --fmin 0.02 \
            --out "$run/analysis/eta_x0.7" >"$run/spectrum_eta_x0.7.txt"
        "$analyze" spectrum "$run" --column eta_x22 --from "$from" --to "$to" --fmin 0.02 \
            --out "$run/analysis/eta_x1.2" >"$run/spectrum_eta_x1.2.txt"
        "$analyze" spectrum "$run" --column bed_pressure.csv:p0_pressure --from "$from" --to "$to" \
            --fmin 0.02 --out "$run/analysis/p_x0.9" >"$run/spectrum_p_x0.9.txt"
        f07=$(pick f_peak "$run/spectrum_eta_x0.7.txt")
        f12=$(pick f_peak "$run/spectrum_eta_x1.2.txt")
        fp=$(pick f_peak "$run/spectrum_p_x0.9.txt")
    fi
    echo "$t,$observed,$status,$simulated,$wall,$nthreads,$deviation,$from,$to,$fa,$fb,$fw,$rate,$type,$f07,$f12,$fp,$failure" >>"$out/summary.csv"
done
cat "$out/summary.csv"
