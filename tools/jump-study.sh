#!/bin/sh
# Seed 000's hydraulic jump (configs/hydraulic_jump_jonsson2016.yaml) at the
# resolutions of its table 2: the conjugate depth d2 at x = 1 m against
# Belanger (d2 = 0.0864 m for v1 = 1.5 m/s, d1 = 0.02 m) through the
# paper's statistics (its eqs. 19-20) over a time window,
#   A = sqrt(sum d2_SPH^2 / sum d2_th^2),  P = sqrt(sum (d2_SPH - d2_th)^2 / sum d2_th^2),
# from the section gauge's depth at x = 1 m (every 0.01 s, as the paper's
# output), next to the paper's values; and, through build/tools/sluice-analyze
# (docs/analysis.md), the toe position, the roller length against Hager et
# al., the largest free-surface fluctuation against Murzyn & Chanson, the
# decay of the largest mean velocity against Chanson (2010) and the
# dominant free-surface frequency as a Strouhal number against Chachereau &
# Chanson.
#
#   tools/jump-study.sh [BUILD_DIR] [DIVISORS]        (default: build, "4 5 6 10")
#   END=30 FROM=15 TO=30 tools/jump-study.sh build 4  (the paper's long run)
#   SCHEME=dbc tools/jump-study.sh build 4            (another wall scheme)
#
# Writes runs/jump-study/summary.csv and summary.md. dx = d1 / DIVISOR.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
divisors=${2:-4 5 6 10}
end=${END:-5}
from=${FROM:-2.5}
to=${TO:-5}
scheme=${SCHEME:-penalty_contact}
out=${OUT:-runs/jump-study}
table=tests/scenes/data/jonsson2016_table2.csv
mkdir -p "$out"
scene="$out/scene-$scheme.yaml"
sed "s/^  penalty_contact: {}.*\$/  $scheme: {}/" configs/hydraulic_jump_jonsson2016.yaml >"$scene"
grep -q "^  $scheme: {}\$" "$scene" || { echo "jump-study: cannot set the wall scheme" >&2; exit 2; }

analyze="$build/tools/sluice-analyze"
# value of `key = value` in an analysis's output
pick() { sed -n "s|^$1 = \([^ ]*\).*|\1|p" "$2" | head -n 1; }

echo "divisor,dx_m,scheme,end_s,window,particles_final,steps,wall_s,threads,mean_d2_m,A,P,paper_A,paper_P,toe_mean_m,toe_std_m,roller_length_m,roller_hager_m,eta_std_max_over_d1,murzyn_chanson,vmax_decay_rate,vmax_decay_chanson,f_peak_hz,strouhal,strouhal_chachereau_chanson" >"$out/summary.csv"
for n in $divisors; do
    dx=$(awk -v n="$n" 'BEGIN { printf "%.10g", 0.02 / n }')
    run="$out/d1_$n-$scheme-$end"
    echo "== d1/$n (dx = $dx m), $scheme, $end s" >&2
    "$build/sluice" run "$scene" --out "$run" --quiet --no-progress \
        --set particles.spacing="$dx" --set time.end="$end" --set plugins.hdf5.interval="$end"
    w="--d1 0.02 --v1 1.5 --from $from --to $to"
    "$analyze" conjugate "$run" $w --x 1.0 >"$run/conjugate.txt"
    "$analyze" toe "$run" $w >"$run/toe.txt" || true
    "$analyze" roller "$run" $w >"$run/roller.txt" || true
    "$analyze" surface "$run" $w >"$run/surface.txt" || true
    "$analyze" vmax "$run" $w >"$run/vmax.txt" || true
    # the free surface 0.1 m downstream of the basin's middle (x = 0.75 m)
    "$analyze" spectrum "$run" $w --column free_surface.csv:eta_x29 >"$run/spectrum.txt" || true
    json() { sed -n "s/.*\"$1\": \([0-9.eE+-]*\).*/\1/p" "$run/run.json" | head -n 1; }
    paper=$(awk -F, -v c="d1/$n" -v w="$from-$to" '$1 == c && $3 == w { print $4 "," $5 }' "$table")
    [ -n "$paper" ] || paper=","
    echo "$n,$dx,$scheme,$end,$from-$to,$(json particles_final),$(json steps),$(json wall_seconds),$(json threads),$(pick d2_mean "$run/conjugate.txt"),$(pick A "$run/conjugate.txt"),$(pick P "$run/conjugate.txt"),$paper,$(pick x1_mean "$run/toe.txt"),$(pick x1_std "$run/toe.txt"),$(pick L_r "$run/roller.txt"),$(pick L_r_Hager "$run/roller.txt"),$(pick eta_std_max/d1 "$run/surface.txt"),$(pick eta_std_max/d1_Murzyn_Chanson "$run/surface.txt"),$(pick decay_rate "$run/vmax.txt"),$(pick decay_rate_Chanson "$run/vmax.txt"),$(pick f_peak "$run/spectrum.txt"),$(pick St "$run/spectrum.txt"),$(pick St_Chachereau_Chanson "$run/spectrum.txt")" >>"$out/summary.csv"
done
{
    echo "| dx | wall scheme | simulated | window | particles | wall time (s) | threads | mean d2 (m) | A | P | paper's A | paper's P | toe x1 (m) | roller (m) / Hager | max eta'/d1 / Murzyn-Chanson | Vmax decay k / Chanson | f (Hz), St / Chachereau-Chanson |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    awk -F, 'NR > 1 { printf "| d1/%s | %s | %s s | %s s | %s | %.0f | %s | %.4f | %.3f | %.3f | %s | %s | %s +- %s | %s / %s | %s / %s | %s / %s | %s, %s / %s |\n", $1, $3, $4, $5, $6, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22, $23, $24, $25 }' "$out/summary.csv"
} >"$out/summary.md"
cat "$out/summary.md"
