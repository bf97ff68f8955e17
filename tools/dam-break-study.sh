#!/bin/sh
# Dam break against Martin & Moyce (1952), n^2 = 2, at several spacings
# (docs/validation.md). Runs configs/dam_break_2d.yaml to t = 0.6 s
# (T = t sqrt(2 g / L) = 2.66) at each dx and compares the front with both
# published series, for T in [0.5, 2.5].
#
#   tools/dam-break-study.sh [BUILD_DIR] [DX ...]     (default: build 0.04 0.02 0.01)
#   SCENE=configs/seed001_model.yaml tools/dam-break-study.sh ...   (another model)
#
# Writes runs/dam-break-study/summary.csv and prints it.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
[ $# -gt 0 ] && shift
spacings=${*:-0.04 0.02 0.01}
scene=${SCENE:-configs/dam_break_2d.yaml}
out=${OUT:-runs/dam-break-study/$(basename "$scene" .yaml)}
data=tests/scenes/data/martin_moyce_1952_n2.csv
mkdir -p "$out"
echo "dx_m,particles,wall_s,series_a_in,worst_error,worst_at_T,mean_error,front_speed_sim,front_speed_exp" >"$out/summary.csv.tmp"
for dx in $spacings; do
    run="$out/dx$dx"
    "$build/sluice" run "$scene" --out "$run" --quiet --no-progress \
        --set time.end=0.6 --set plugins.hdf5.interval=0.3 --set particles.spacing="$dx"
    particles=$(sed -n 's/.*"particles_initial": \([0-9]*\).*/\1/p' "$run/run.json")
    wall=$(sed -n 's/.*"wall_seconds": \([0-9.]*\).*/\1/p' "$run/run.json")
    for a in 2.25 1.125; do
        awk -F, -v a="$a" -v dx="$dx" -v n="$particles" -v w="$wall" '
            function lerp(xs, ys, m, x,   i) {
                for (i = 2; i <= m; i++)
                    if (x <= xs[i])
                        return ys[i-1] + (ys[i] - ys[i-1]) * (x - xs[i-1]) / (xs[i] - xs[i-1])
                return ys[m]
            }
            FNR == 1 { file++ }
            file == 1 && $0 !~ /^#/ && $1 == a { m++; et[m] = $2; ez[m] = $3 }
            file == 2 && FNR > 1 { k++; st[k] = $1; sx[k] = $2 }
            END {
                # the column starts at Z = 1 at T = 0
                for (i = m; i >= 1; i--) { et[i+1] = et[i]; ez[i+1] = ez[i] } et[1] = 0; ez[1] = 1; m++
                s = sqrt(2 * 9.81 / 1.0)
                worst = 0; sum = 0; c = 0
                for (T = 0.5; T <= 2.5 + 1e-9; T += 0.05) {
                    zs = lerp(st, sx, k, T / s); ze = lerp(et, ez, m, T)
                    e = (zs - ze) / ze; sum += e; c++
                    if ((e < 0 ? -e : e) > (worst < 0 ? -worst : worst)) { worst = e; wT = T }
                }
                vs = lerp(st, sx, k, 2.5 / s) - lerp(st, sx, k, 1.5 / s)
                ve = lerp(et, ez, m, 2.5) - lerp(et, ez, m, 1.5)
                printf "%s,%s,%s,%s,%.4f,%.2f,%.4f,%.4f,%.4f\n", dx, n, w, a, worst, wT, sum / c, vs, ve
            }' "$data" "$run/front.csv" >>"$out/summary.csv.tmp"
    done
done
mv "$out/summary.csv.tmp" "$out/summary.csv"
cat "$out/summary.csv"
