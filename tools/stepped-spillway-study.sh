#!/bin/sh
# Seed 001's stepped spillways (docs/validation.md, "Seed 001's stepped
# spillways"): runs the Chanson chute and/or the Cheng spillway at a chosen
# spacing and length, then
#   chanson: sluice-analyze step-profiles at the step edges 1-8 over
#            [FROM, END] (U/Uc against y/dc, Y90, C_mean, the inception
#            step; Uc = 0.668 m/s as seed 001 prints it, dc = 0.0700 m);
#   cheng:   tools/cheng-do.awk at points 2-7 over [FROM, END] against seed
#            001's tables 4 and 5, then sluice-analyze dissolved-oxygen with
#            the source calibrated on point 4 (station 3: 4.01 mg/L), the
#            other points being predictions.
# Every run writes a checkpoint every CHECKPOINT seconds (the newest kept);
# when OUT/<scene> already holds one, the run continues from it to END.
#
#   tools/stepped-spillway-study.sh [BUILD_DIR] [SCENES]
#     defaults: build, "chanson cheng"
#   DX_CHANSON=0.008 DX_CHENG=0.008 (the scenes'; seed 001 ran Cheng at 0.004) END_CHANSON=8 END_CHENG=3
#   FROM_CHANSON=4 FROM_CHENG=2 VARIANT= (e.g. seed_model, no_cohesion, single_phase)
#   OUT=runs/stepped-spillway-study THREADS= CHECKPOINT=0.5
#   SETS="key=value ..." (extra --set overrides for both scenes)
#   SPINUP=T: start the two-phase run from a single-phase spin-up instead
#     of from rest (docs/validation.md, "Cheng at the seed's spacing from a
#     single-phase spin-up"): the scene's single_phase variant runs T
#     seconds (OUT/<scene>-spinup-1p), the two-phase scene 0.0002 s for a
#     template checkpoint (OUT/<scene>-spinup-template), and
#     tools/spinup-two-phase.py (python3-h5py, python3-yaml) makes the
#     two-phase state: the single-phase water, the air everywhere else, and
#     for Cheng the step cavities under the pseudo-bottom filled with water
#     (WATER_BELOW="X0 Y0 X1 Y1", default the line through Cheng's first
#     and last step edges; "" for none). The two-phase run's clock starts
#     at the template's 0.0002 s, so FROM and END count from the switch.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
scenes=${2:-chanson cheng}
out=${OUT:-runs/stepped-spillway-study}
checkpoint=${CHECKPOINT:-0.5}
variant=${VARIANT:-}
mkdir -p "$out"
for scene in $scenes; do
    case $scene in
    chanson)
        config=configs/stepped_chute_chanson.yaml
        dx=${DX_CHANSON:-0.008} end=${END_CHANSON:-8} from=${FROM_CHANSON:-4} ;;
    cheng)
        config=configs/stepped_spillway_cheng.yaml
        dx=${DX_CHENG:-0.008} end=${END_CHENG:-3} from=${FROM_CHENG:-2} ;;
    *)
        echo "stepped-spillway-study.sh: unknown scene '$scene' (chanson or cheng)" >&2
        exit 2 ;;
    esac
    dir="$out/$scene${variant:+-$variant}"
    set -- run "$config" --out "$dir" --set particles.spacing="$dx" --set time.end="$end" \
        --set checkpoint.interval="$checkpoint" --no-progress
    [ -n "$variant" ] && set -- "$@" --variant "$variant"
    [ -n "${THREADS:-}" ] && set -- "$@" --threads "$THREADS"
    for s in ${SETS:-}; do set -- "$@" --set "$s"; done
    newest=$(ls "$dir"/checkpoint_*.h5 2>/dev/null | sort | tail -n 1 || true)
    if [ -z "$newest" ] && [ -n "${SPINUP:-}" ]; then
        one="$out/$scene-spinup-1p" template="$out/$scene-spinup-template"
        [ "$scene" = cheng ] && below=${WATER_BELOW-0.7144 1.3213 1.7144 0.0013} ||
            below=${WATER_BELOW:-}
        "$build/sluice" run "$config" --variant single_phase --out "$one" --overwrite \
            --set particles.spacing="$dx" --set time.end="$SPINUP" --no-progress \
            ${THREADS:+--threads "$THREADS"}
        # the template: the same run as below, 0.0002 s long (later
        # --set and --out override the earlier ones)
        "$build/sluice" "$@" --set time.end=0.0002 --set checkpoint.interval=0.0002 \
            --out "$template" --overwrite
        mkdir -p "$dir"
        newest="$dir/spinup.h5"
        # shellcheck disable=SC2086 # WATER_BELOW is four numbers
        tools/spinup-two-phase.py "$(ls "$template"/checkpoint_*.h5 | sort | tail -n 1)" \
            "$(ls "$one"/particles_0*.h5 | sort | tail -n 1)" "$template/particles_000000.h5" \
            "$newest" "$dx" ${below:+--water-below $below}
    fi
    [ -n "$newest" ] && set -- "$@" --restart "$newest"
    start=$(date +%s)
    "$build/sluice" "$@"
    seconds=$(( $(date +%s) - start ))
    echo "$scene${variant:+ ($variant)}: dx = $dx m, $end s simulated in $seconds s of wall time"
    case $scene in
    chanson)
        "$build/tools/sluice-analyze" step-profiles "$dir/points.csv" --per-line 30 \
            --edges "$(cat configs/stepped_chute_chanson.edges)" --theta 21.8 --dc 0.0700 \
            --uc 0.668 --first-step 1 --from "$from" --to "$end" > "$dir/step-profiles.csv" ||
            true
        tail -n 12 "$dir/step-profiles.csv" ;;
    cheng)
        awk -F, -f tools/cheng-do.awk -v from="$from" -v to="$end" "$dir/points.csv" |
            tee "$dir/dissolved-oxygen.csv"
        "$build/tools/sluice-analyze" dissolved-oxygen "$dir/points.csv" --per-line 15 \
            --cs 10.48 --cu 1.29 --from "$from" --to "$end" --calibrate 3 --target 4.01 |
            tee "$dir/dissolved-oxygen-calibrated.csv" || true ;;
    esac
done
