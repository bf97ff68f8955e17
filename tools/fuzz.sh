#!/bin/sh
# Fuzzes with libFuzzer under AddressSanitizer and UndefinedBehaviorSanitizer,
# one of two targets:
#  - scene (tests/core/fuzz/fuzz_scene.c): the scene loader (YAML, schema,
#    plugin lookup and parameters, plugin creation, geometry, the initial
#    state and two steps of a valid scene), starting from the corpus in
#    tests/core/fuzz/corpus (every scene of configs/ and small scenes using
#    every plugin);
#  - checkpoint (tests/core/fuzz/fuzz_checkpoint.c): the checkpoint reader
#    behind the checksum (edits of a valid checkpoint through the HDF5 API,
#    a valid trailer, the restart and two steps), starting from
#    tests/core/fuzz/checkpoint_corpus; checkpoint-raw adds raw byte flips
#    of the HDF5 file behind the valid trailer, which test the HDF5 library
#    itself (docs/reliability.md).
#
#   tools/fuzz.sh [SECONDS] [WORKERS] [TARGET]   defaults: 60 s, 1 worker, scene
#   BUILD=build-fuzz WORK=BUILD/fuzz-work (scene), BUILD/fuzz-work-TARGET (others)
#
# Needs clang (Debian 12: clang, libclang-rt-14-dev). Prints executions,
# corpus size and crashes (inputs that crash are kept in WORK/artifacts);
# exits 1 when there is any. docs/reliability.md has the figures.
set -eu
cd "$(dirname "$0")/.."
seconds=${1:-60}
workers=${2:-1}
target=${3:-scene}
build=${BUILD:-build-fuzz}
case "$target" in
scene)
    work=${WORK:-$build/fuzz-work}
    program=fuzz_scene seeds=tests/core/fuzz/corpus label="fuzz"
    options="-max_len=16384 -dict=tests/core/fuzz/scene.dict" ;;
checkpoint|checkpoint-raw)
    work=${WORK:-$build/fuzz-work-$target}
    program=fuzz_checkpoint seeds=tests/core/fuzz/checkpoint_corpus label="fuzz $target"
    options="-max_len=512" ;;
*)
    echo "fuzz: unknown target '$target' (scene, checkpoint or checkpoint-raw)" >&2
    exit 2 ;;
esac
command -v clang >/dev/null 2>&1 || { echo "fuzz: clang is missing (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
if [ ! -f "$build/build.ninja" ]; then
    CC=clang meson setup "$build" --buildtype=debugoptimized -Dfuzz=true -Dtests=false \
        -Db_sanitize=address,undefined -Db_lundef=false \
        -Dc_args="-fsanitize=fuzzer-no-link -fno-sanitize-recover=all -Wno-pass-failed" >/dev/null
fi
rm -rf "$work/artifacts"   # the inputs of the previous campaign's findings
mkdir -p "$work/corpus" "$work/artifacts"
# (-Wno-pass-failed: clang reports the `omp simd` loops it leaves scalar
# under the sanitizers' instrumentation)
meson compile -C "$build" >"$work/build.log" 2>&1 || { tail -n 20 "$work/build.log" >&2; exit 2; }
cp -n "$seeds"/* "$work/corpus/"
export SLUICE_PLUGIN_PATH="$PWD/$build/plugins"
leaks=1
if [ "$target" = checkpoint-raw ]; then
    export SLUICE_FUZZ_RAW_BYTES=1
    leaks=0 # HDF5 leaks on some of its error paths (docs/reliability.md)
fi
export ASAN_OPTIONS="detect_leaks=$leaks:intercept_tls_get_addr=0:allocator_may_return_null=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export OMP_NUM_THREADS=1
set +e
# shellcheck disable=SC2086 # $options holds several options
"$build/tests/core/fuzz/$program" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 \
    $options -artifact_prefix="$work/artifacts/" \
    -print_final_stats=1 -close_fd_mask=1 \
    $([ "$workers" -gt 1 ] && echo "-jobs=$workers -workers=$workers") \
    "$work/corpus" >"$work/fuzz.log" 2>&1
rc=$?
set -e
[ "$workers" -gt 1 ] && cat fuzz-*.log >>"$work/fuzz.log" 2>/dev/null && rm -f fuzz-*.log
executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/fuzz.log" | awk '{ s += $1 } END { print s + 0 }')
# crash-, leak-, timeout- and oom- inputs (slow- ones are only slow)
crashes=$(find "$work/artifacts" -type f ! -name 'slow-unit-*' | wc -l)
corpus=$(ls "$work/corpus" | wc -l)
echo "$label: $seconds s, $workers worker(s): $executions executions, corpus $corpus inputs, $crashes crash(es) (exit $rc); log $work/fuzz.log"
if [ "$crashes" -gt 0 ] || [ "$rc" -ne 0 ]; then
    grep -m 5 -E "ERROR|runtime error|SUMMARY" "$work/fuzz.log" >&2 || true
    exit 1
fi
