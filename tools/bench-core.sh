#!/bin/sh
# Core benchmark (docs/performance.md): the 2D dam break at three resolutions
# through the plugin path and through a hand-fused loop of the same physics,
# and the memory per particle at about one million particles.
#
#   tools/bench-core.sh [BUILD_DIR]     (default: build)
#
# Writes runs/bench-core/core.csv, memory.csv and summary.md. Never a test:
# timings depend on the machine. Outputs (HDF5, front gauge) are pushed past
# the end time so that both paths take identical steps.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
out=${OUT:-runs/bench-core}
bench="$build/tools/sluice-bench"
scene=configs/dam_break_2d.yaml
quiet="--set plugins.hdf5.interval=1e9 --set plugins.front_gauge.interval=1e9"
mkdir -p "$out"
[ -x "$bench" ] || { echo "bench-core: build first (meson compile -C $build)" >&2; exit 2; }

: >"$out/core.csv.tmp"
header_written=""
for spec in 0.02:200 0.01:100 0.005:40; do
    dx=${spec%:*}
    steps=${spec#*:}
    line=$("$bench" ratio "$scene" --steps "$steps" --repeat 5 --warmup-time 0.1 $quiet \
        --set particles.spacing="$dx" | tail -n 2)
    if [ -z "$header_written" ]; then
        echo "spacing_m,$(echo "$line" | head -n 1)" >>"$out/core.csv.tmp"
        header_written=1
    fi
    echo "$dx,$(echo "$line" | tail -n 1)" >>"$out/core.csv.tmp"
done
mv "$out/core.csv.tmp" "$out/core.csv"

: >"$out/memory.csv.tmp"
header_written=""
for spec in 0.02:50 0.005:10 0.0014:3; do
    dx=${spec%:*}
    steps=${spec#*:}
    line=$("$bench" memory "$scene" --steps "$steps" $quiet --set particles.spacing="$dx" |
        tail -n 2)
    if [ -z "$header_written" ]; then
        echo "spacing_m,$(echo "$line" | head -n 1)" >>"$out/memory.csv.tmp"
        header_written=1
    fi
    echo "$dx,$(echo "$line" | tail -n 1)" >>"$out/memory.csv.tmp"
done
mv "$out/memory.csv.tmp" "$out/memory.csv"

{
    echo "| dx (m) | particles | threads | plugin particle-steps/s | pair interactions/s | fused: scalar / flat / batched (ms per step) | plugin / fastest fused |"
    echo "|---|---|---|---|---|---|---|"
    tail -n +2 "$out/core.csv" | awk -F, '{printf "| %s | %s | %s | %.3g | %.3g | %.3g / %.3g / %.3g | %.3f |\n", $1, $2, $3, $12, $14, 1e3 * $8, 1e3 * $9, 1e3 * $10, $15}'
    echo
    echo "| dx (m) | particles | peak RSS (MB) | bytes / particle (peak RSS) | bytes / particle (particle store, grid, list) |"
    echo "|---|---|---|---|---|"
    tail -n +2 "$out/memory.csv" | awk -F, '{printf "| %s | %s | %.1f | %.0f | %.0f |\n", $1, $2, $4 / 1e6, $5, $6}'
} >"$out/summary.md"
cat "$out/summary.md"
