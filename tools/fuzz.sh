#!/bin/sh
# Fuzzes the scene loader (tests/core/fuzz/fuzz_scene.c: YAML, schema, plugin
# lookup and parameters, plugin creation, geometry, the initial state and two
# steps of a valid scene) with libFuzzer under AddressSanitizer and
# UndefinedBehaviorSanitizer, starting from the corpus in tests/core/fuzz/corpus
# (every scene of configs/ and small scenes using every plugin).
#
#   tools/fuzz.sh [SECONDS] [WORKERS]     defaults: 60 s, 1 worker
#   BUILD=build-fuzz WORK=BUILD/fuzz-work
#
# Needs clang (Debian 12: clang, libclang-rt-14-dev). Prints executions,
# corpus size and crashes (inputs that crash are kept in WORK/artifacts);
# exits 1 when there is any. docs/reliability.md has the figures.
set -eu
cd "$(dirname "$0")/.."
seconds=${1:-60}
workers=${2:-1}
build=${BUILD:-build-fuzz}
work=${WORK:-$build/fuzz-work}
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
cp -n tests/core/fuzz/corpus/* "$work/corpus/"
export SLUICE_PLUGIN_PATH="$PWD/$build/plugins"
export ASAN_OPTIONS="detect_leaks=1:intercept_tls_get_addr=0:allocator_may_return_null=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export OMP_NUM_THREADS=1
set +e
"$build/tests/core/fuzz/fuzz_scene" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 \
    -max_len=16384 -dict=tests/core/fuzz/scene.dict -artifact_prefix="$work/artifacts/" \
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
echo "fuzz: $seconds s, $workers worker(s): $executions executions, corpus $corpus inputs, $crashes crash(es) (exit $rc); log $work/fuzz.log"
if [ "$crashes" -gt 0 ] || [ "$rc" -ne 0 ]; then
    grep -m 5 -E "ERROR|runtime error|SUMMARY" "$work/fuzz.log" >&2 || true
    exit 1
fi
