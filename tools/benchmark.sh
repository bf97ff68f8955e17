#!/bin/sh
# Run time against error (docs/performance.md): the reference scenes at three
# resolutions each, every error against a reference nobody fitted, and PySPH
# on its own dam break in the same run. A benchmark, never a unit test.
#
#   tools/benchmark.sh [BUILD]        (BUILD: build directory, default build)
#   env: OUT (default runs/benchmark), THREADS (default 2), QUICK=1 (the two
#        coarsest resolutions, shorter runs: a smoke test), PYSPH=0 (skip the
#        peer), CORE=0 (skip tools/bench-core.sh), CASES (default
#        "dam still poiseuille jump speed pysph")
#
# Cases (each a column of the plot):
#   dam         configs/dam_break_2d.yaml to 0.75 s (the surge reaches the far
#               wall at 0.68 s) at dx = 0.04, 0.02, 0.01 m: the worst relative
#               error of the front against Martin & Moyce (1952, a = 2.25 in,
#               n^2 = 2) over T = t sqrt(2 g / L) in [0.5, 2.5]. Variants: the
#               scene's physics (Wendland C2, symplectic, DBC) and one change
#               each: cubic_spline, verlet, predictor_corrector, mdbc,
#               ghost_particles (no-slip), penalty_contact, repulsive_force.
#   still       configs/still_water_2d.yaml to 3 s at dx = H/10, H/20, H/40:
#               pressure 0.1 m above the floor (mean of 3 points over the
#               last second) against rho0 g (H - 0.1).
#   poiseuille  configs/poiseuille_2d.yaml to 1.5 s at L/10, L/20, L/40: L2
#               error of the velocity profile against the steady parabola.
#   jump        configs/hydraulic_jump_jonsson2016.yaml to 5 s at d1/4, d1/5,
#               d1/6: mean conjugate depth at x = 1 m over 2.5-5 s against
#               Belanger's (seed 000's set-up).
#   speed       particle-steps/s of the dam break at 6.5k, 86k and 1M
#               particles (dx = 0.02, 0.005, 0.0014 m, short runs), symplectic
#               and verlet, and on one thread at 86k and 1M (parallel
#               efficiency).
#   pysph       PySPH 1.0 (Debian python3-pysph, installed when missing) on
#               its examples/dam_break_2d (WCSPH, Wendland quintic, h = 1.3 dx,
#               PEC) at dx = 0.03 m to 0.75 s, serial and 2 threads, with the
#               same front error; and Sluice at the same dx, h = 1.3 dx,
#               same end time (matched particle count and physics class)
#               with the predictor-corrector in PySPH's PEC form (one
#               evaluation per step, sluice-matched) and in its EPEC form
#               (two, sluice-epec).
#
# Writes OUT/benchmark.csv (one row per run), OUT/benchmark.md and
# OUT/benchmark.png (wall time against error, log-log, gnuplot), and with
# CORE=1 OUT/core/ (plugin path against hand-fused loops, memory at 1M
# particles). About 45 minutes on the 2-core machine (QUICK=1: 5).
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
sluice=$build/sluice
analyze=$build/tools/sluice-analyze
[ -x "$sluice" ] && [ -x "$analyze" ] ||
    { echo "tools/benchmark.sh: build first: meson setup $build --buildtype=release && ninja -C $build" >&2; exit 2; }
out=${OUT:-runs/benchmark}
threads=${THREADS:-2}
quick=${QUICK:-0}
cases=${CASES:-dam still poiseuille jump speed pysph}
[ "${PYSPH:-1}" = 0 ] && cases=$(echo "$cases" | sed 's/pysph//')
mkdir -p "$out"
csv=$out/benchmark.csv
echo "case,variant,resolution,dx_m,particles,steps,wall_s,particle_steps_per_s,pair_interactions_per_s,state_bytes_per_particle,threads,status,error_name,error" >"$csv"
martin_moyce=tests/scenes/data/martin_moyce_1952_n2.csv

json() { sed -n "s/.*\"$2\": \\([0-9.eE+-]*\\).*/\\1/p" "$1/run.json" | head -n 1; }
has() { case " $cases " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }

# front_error FRONT_CSV (time,x_front): worst relative error against Martin
# & Moyce over T in [0.5, 2.5] (up to the run's last sample)
front_error() {
    awk -F, -f tools/martin-moyce-error.awk "$martin_moyce" "$1"
}

# run CASE VARIANT RESOLUTION DX SCENE ERROR_NAME ERROR_COMMAND [sluice args]:
# runs the scene, then evaluates ERROR_COMMAND (sh, with $run set) and
# appends a row
run() {
    case_=$1 variant=$2 resolution=$3 dx=$4 scene=$5 error_name=$6 error_command=$7
    shift 7
    run=$out/$case_/$variant-dx$dx
    rm -rf "$run"
    mkdir -p "$out/$case_"
    echo "benchmark: $case_ $variant $resolution (dx = $dx m)" >&2
    status=complete
    OMP_NUM_THREADS=$threads "$sluice" run "$scene" --out "$run" --quiet --no-progress \
        --set particles.spacing="$dx" "$@" >"$run.log" 2>&1 || status=failed
    error=nan
    if [ "$status" = complete ]; then
        error=$(eval "$error_command") || error=nan
    fi
    if [ -f "$run/run.json" ]; then
        echo "$case_,$variant,$resolution,$dx,$(json "$run" particles_final),$(json "$run" steps),$(json "$run" wall_seconds),$(json "$run" particle_steps_per_second),$(json "$run" pair_interactions_per_second),$(json "$run" state_bytes_per_particle),$threads,$status,$error_name,$error" >>"$csv"
    else
        echo "$case_,$variant,$resolution,$dx,,,,,,,$threads,$status,$error_name,nan" >>"$csv"
        tail -n 3 "$run.log" >&2 || true
    fi
}

# variant SOURCE VARIANT -> a scene file with the variant's one change
variant_scene() {
    file=$out/scenes/$2-$(basename "$1")
    mkdir -p "$out/scenes"
    case "$2" in
    base) cp "$1" "$file" ;;
    cubic_spline) sed 's/^  wendland_c2: {}$/  cubic_spline: {}/' "$1" >"$file" ;;
    verlet | predictor_corrector) sed "s/^  symplectic: {}\$/  $2: {}/" "$1" >"$file" ;;
    predictor_corrector_pec) sed 's/^  symplectic: {}$/  predictor_corrector: {mode: pec}/' "$1" >"$file" ;;
    ghost_particles) sed 's/^  dbc: {}$/  ghost_particles: {slip: no_slip}/' "$1" >"$file" ;;
    mdbc | penalty_contact | repulsive_force) sed "s/^  dbc: {}\$/  $2: {}/" "$1" >"$file" ;;
    esac
    [ "$2" = base ] || ! cmp -s "$1" "$file" ||
        { echo "tools/benchmark.sh: variant $2 did not change $1" >&2; exit 2; }
    echo "$file"
}

if [ "$quick" = 1 ]; then
    dam_dx="0.04 0.02"; still_dx="0.05 0.025"; pois_dx="1e-4 5e-5"; jump_n="4"
    dam_variants="base cubic_spline verlet penalty_contact"; jump_end=3
    speed_specs="0.02:0.1 0.01:0.02"
else
    dam_dx="0.04 0.02 0.01"; still_dx="0.05 0.025 0.0125"; pois_dx="1e-4 5e-5 2.5e-5"; jump_n="4 5 6"
    dam_variants="base cubic_spline verlet predictor_corrector mdbc ghost_particles penalty_contact repulsive_force"
    jump_end=5
    speed_specs="0.02:0.2 0.005:0.02 0.0014:0.002"
fi

# ------------------------------------------------------------- dam break
if has dam; then
    for v in $dam_variants; do
        scene=$(variant_scene configs/dam_break_2d.yaml "$v")
        for dx in $dam_dx; do
            run dam "$v" "dx=$dx" "$dx" "$scene" front_error_worst 'front_error "$run/front.csv"' \
                --set time.end=0.75 --set plugins.hdf5.interval=0.75
        done
    done
fi

# ----------------------------------------------------------- still water
if has still; then
    for dx in $still_dx; do
        n=$(awk -v d="$dx" 'BEGIN { printf "%d", 0.5 / d + 0.5 }')
        run still base "H/$n" "$dx" configs/still_water_2d.yaml bottom_pressure_error \
            'awk -F, "NR > 1 && \$1 >= 2 - 1e-9 { s += \$2 + \$3 + \$4; n += 3 } END { e = 1000 * 9.81 * 0.4; printf \"%.4f\", (s / n - e) / e }" "$run/bottom.csv"' \
            --set time.end=3 --set plugins.hdf5.interval=3 \
            --set 'plugins.point_gauge.points=[[0.3,0.1],[0.5,0.1],[0.7,0.1]]' \
            --set plugins.point_gauge.fields=pressure --set plugins.point_gauge.interval=0.05 \
            --set plugins.point_gauge.file=bottom.csv
    done
fi

# ------------------------------------------------------------ Poiseuille
if has poiseuille; then
    pts=$(awk 'BEGIN { for (k = 0; k < 20; k++) printf "%s[0,%.6g]", k ? "," : "", (k + 0.5) * 5e-5 }')
    for dx in $pois_dx; do
        n=$(awk -v d="$dx" 'BEGIN { printf "%d", 1e-3 / d + 0.5 }')
        # the periodic length must hold 3 kernel supports: 12 dx (the scene's 3e-4 m at L/40)
        width=$(awk -v d="$dx" 'BEGIN { printf "%.6g", 12 * d }')
        mkdir -p "$out/scenes"
        sed "s/3\.0e-4/$width/g" configs/poiseuille_2d.yaml >"$out/scenes/poiseuille-$n.yaml"
        run poiseuille base "L/$n" "$dx" "$out/scenes/poiseuille-$n.yaml" profile_l2_error \
            'awk -F, "END { nu = 1e-6; F = 1e-4; L = 1e-3; for (k = 0; k < 20; k++) { y = (k + 0.5) * 5e-5; u = \$(2 + 2 * k); a = F / (2 * nu) * y * (L - y); d += (u - a) ^ 2; n2 += a ^ 2 } printf \"%.4f\", sqrt(d / n2) }" "$run/profile.csv"' \
            --set plugins.hdf5.interval=1.5 --set "plugins.point_gauge.points=[$pts]" \
            --set plugins.point_gauge.fields=velocity --set plugins.point_gauge.interval=0.1 \
            --set plugins.point_gauge.min_kernel_sum=0.2 --set plugins.point_gauge.file=profile.csv
    done
fi

# ------------------------------------------------------- hydraulic jump
if has jump; then
    for n in $jump_n; do
        dx=$(awk -v n="$n" 'BEGIN { printf "%.10g", 0.02 / n }')
        from=$(awk -v e="$jump_end" 'BEGIN { printf "%g", e / 2 }')
        run jump base "d1/$n" "$dx" configs/hydraulic_jump_jonsson2016.yaml conjugate_depth_error \
            '"$analyze" conjugate "$run" --d1 0.02 --v1 1.5 --x 1.0 --from '"$from"' --to '"$jump_end"' --no-plot >"$run/conjugate.txt" && sed -n "s|^d2_mean/d2_Belanger = \\([^ ]*\\).*|\\1|p" "$run/conjugate.txt" | awk "{ printf \"%.4f\", \$1 - 1 }"' \
            --set time.end="$jump_end" --set plugins.hdf5.interval="$jump_end"
    done
fi

# --------------------------------------------------------------- speed
# particle-steps/s from 6.5k to 1M particles (the dam break, early: the
# column collapsing), both main integrators, and 1 against 2 threads at 86k
# and 1M (parallel efficiency); no error (the runs are too short)
if has speed; then
    for spec in $speed_specs; do
        dx=${spec%:*} end=${spec#*:}
        for v in base verlet; do
            scene=$(variant_scene configs/dam_break_2d.yaml "$v")
            run speed "$v" "dx=$dx" "$dx" "$scene" none 'echo nan' \
                --set time.end="$end" --set plugins.hdf5.interval=1e9 --set plugins.front_gauge.interval=1e9
            if [ "$dx" != 0.02 ] && [ "$threads" != 1 ]; then
                saved=$threads threads=1
                run speed "$v-1thread" "dx=$dx" "$dx" "$scene" none 'echo nan' \
                    --set time.end="$end" --set plugins.hdf5.interval=1e9 --set plugins.front_gauge.interval=1e9
                threads=$saved
            fi
        done
    done
fi

# ----------------------------------------------------------------- PySPH
if has pysph; then
    if ! /usr/bin/python3 -c 'import pysph' >/dev/null 2>&1; then
        echo "benchmark: installing python3-pysph (apt)" >&2
        DEBIAN_FRONTEND=noninteractive apt-get install -y python3-pysph >&2 ||
            echo "benchmark: python3-pysph could not be installed" >&2
    fi
    # PySPH's own dam break (tools/peers/pysph-dam-break, the wrapper the
    # studies use), serial and on 2 threads; its wall time is PySPH's solver
    # time (without compiling its kernels)
    for t in 1 2; do
        mode=serial; [ "$t" = 2 ] && mode=openmp
        d=$out/pysph/dx0.03_$mode
        rm -rf "$d"
        tools/peers/pysph-dam-break "$d" --dx 0.03 --end 0.75 --threads "$t" >&2 ||
            echo "benchmark: PySPH ($mode) did not complete (see $d)" >&2
        [ -f "$d/run.json" ] || continue
        n=$(json "$d" particles_initial) steps=$(json "$d" steps) wall=$(json "$d" wall_seconds)
        status=$(sed -n 's/.*"status": "\([a-z]*\)".*/\1/p' "$d/run.json")
        rate=$(awk -v n="$n" -v s="$steps" -v w="$wall" 'BEGIN { printf "%.4g", n * s / w }')
        echo "pysph,pysph-$mode,dx=0.03,0.03,$n,$steps,$wall,$rate,,,$t,$status,front_error_worst,$(front_error "$d/front.csv")" >>"$csv"
    done
    # Sluice at PySPH's dx, h/dx and integrator (DBC, delta-SPH kept): its
    # PECIntegrator evaluates once per step (the predictor reuses the previous
    # step's rates), as predictor_corrector's mode pec; mode epec (two
    # evaluations per step) for comparison
    for pc in predictor_corrector_pec:sluice-matched predictor_corrector:sluice-epec; do
        scene=$(variant_scene configs/dam_break_2d.yaml "${pc%:*}")
        run pysph "${pc#*:}" dx=0.03 0.03 "$scene" front_error_worst 'front_error "$run/front.csv"' \
            --set time.end=0.75 --set plugins.hdf5.interval=0.75 --set particles.smoothing_length_ratio=1.3
    done
fi

# --------------------------------------------------- plugin path, memory
if [ "${CORE:-1}" = 1 ] && [ "$quick" != 1 ]; then
    OUT=$out/core tools/bench-core.sh "$build" >&2 || echo "benchmark: bench-core failed" >&2
fi

# ------------------------------------------------------------- summary
{
    echo "| case | variant | resolution | particles | wall s | particle-steps/s | pair interactions/s | bytes/particle | threads | status | error |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
    awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %.4g | %.3g | %.3g | %s | %s | %s | %s = %s |\n", $1, $2, $3, $5, $7, $8, $9, $10, $11, $12, $13, $14 }' "$csv"
    # Sluice against PySPH on 2 threads: particle-steps/s and time to the
    # same end time (the two codes choose their own time steps)
    awk -F, 'NR > 1 && $1 == "pysph" && $12 == "complete" { rate[$2] = $8; wall[$2] = $7 }
        END { if (("pysph-openmp" in rate) && rate["pysph-openmp"] > 0)
                  for (v in rate) if (v ~ /^sluice-/)
                      printf "\n%s against PySPH on 2 threads: %.2fx the particle-steps/s, %.2fx faster to the same end time\n",
                             v, rate[v] / rate["pysph-openmp"], wall["pysph-openmp"] / wall[v] }' "$csv"
    # parallel efficiency: each speed run against its one-thread twin
    awk -F, 'NR > 1 && $1 == "speed" && $12 == "complete" { rate[$2 "|" $3] = $8; n[$2 "|" $3] = $5; t[$2 "|" $3] = $11 }
        END { for (k in rate) { split(k, a, "|"); one = a[1] "-1thread|" a[2]
                  if (a[1] !~ /-1thread$/ && (one in rate) && rate[one] > 0)
                      printf "\nspeed %s, %s (%s particles): %s threads / 1 thread = %.2f (target 1.8 at 100k+)\n",
                             a[1], a[2], n[k], t[k], rate[k] / rate[one] } }' "$csv"
    if [ -f "$out/core/summary.md" ]; then
        echo
        cat "$out/core/summary.md"
    fi
} >"$out/benchmark.md"
cat "$out/benchmark.md"

if command -v gnuplot >/dev/null 2>&1; then
    plot_case() { # CASE TITLE
        series=""
        for v in $(awk -F, -v c="$1" 'NR > 1 && $1 == c && $12 == "complete" { print $2 }' "$csv" | awk '!seen[$0]++'); do
            awk -F, -v c="$1" -v v="$v" 'NR > 1 && $1 == c && $2 == v && $12 == "complete" && $14 != "nan" { e = $14 < 0 ? -$14 : $14; print $7, e, $3 }' "$csv" >"$out/plot-$1-$v.dat"
            [ -s "$out/plot-$1-$v.dat" ] || continue
            series="$series${series:+, }'$out/plot-$1-$v.dat' using 1:2 with linespoints title '$v'"
        done
        [ -n "$series" ] && printf "set title '%s'\nplot %s\n" "$2" "$series"
    }
    {
        echo "set terminal pngcairo noenhanced size 1400,1000 font ',10'"
        echo "set output '$out/benchmark.png'"
        echo "set multiplot layout 2,3"
        echo "set logscale xy"
        echo "set offsets graph 0.1, graph 0.1, graph 0.1, graph 0.1"
        echo "set xlabel 'wall time (s), $threads threads'"
        echo "set ylabel '|error|'"
        echo "set key left bottom"
        plot_case dam "dam break: front vs Martin and Moyce (0.75 s)" || echo "set multiplot next"
        plot_case still "still water: pressure 0.1 m above the floor vs rho0 g (H - y)" || echo "set multiplot next"
        plot_case poiseuille "Poiseuille: profile L2 error" || echo "set multiplot next"
        plot_case jump "Jonsson jump: conjugate depth vs Belanger" || echo "set multiplot next"
        plot_case pysph "dam break, dx 0.03 m: PySPH and Sluice matched" || echo "set multiplot next"
        echo "unset multiplot"
    } >"$out/benchmark.gp"
    gnuplot "$out/benchmark.gp" 2>"$out/gnuplot.log" || echo "benchmark: gnuplot failed (see $out/gnuplot.log)" >&2
fi
echo "benchmark: wrote $csv, $out/benchmark.md${out:+, $out/benchmark.png}" >&2
