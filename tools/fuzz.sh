#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets of tests/fuzz with clang-14 (ASan + UBSan, every bvhlab
# library instrumented) in build-fuzz/, then fuzzes each target for SECONDS, JOBS at a time,
# starting from the seed corpus in tests/fuzz/corpus/<target>/. Crashing inputs are copied
# into that corpus folder (as crash-*), where ctest replays them from then on; the per-target
# stats (executions, coverage, corpus size) go to build-fuzz/fuzz-summary.txt.
# Needs clang-14 and libclang-rt-14-dev (tools/install_deps.sh --with-fuzz).
# Usage: tools/fuzz.sh [SECONDS per target, default 60] [JOBS, default nproc] [TARGET ...]
set -uo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
jobs=${2:-$(nproc)}
shift $(( $# > 2 ? 2 : $# ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(obj ray_file hit_file tree_file scenes_json mtl pfm scene_cache scene_file)
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g"
mkdir -p build-fuzz
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DBVHLAB_FUZZ=ON -DBVHLAB_ENABLE_CUDA=OFF -DBVHLAB_BUILD_BENCHMARKS=OFF -DBVHLAB_WITH_OIIO=OFF \
    -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" >/dev/null || exit 1
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]/#/fuzz_}" >build-fuzz/build.log 2>&1 || {
    tail -20 build-fuzz/build.log
    exit 1
}
summary=build-fuzz/fuzz-summary.txt
: >"$summary"
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
run_one() {
    local t=$1 work=build-fuzz/corpus/$1 found=build-fuzz/findings/$1
    rm -rf "$found"
    mkdir -p "$work" "$found"
    build-fuzz/tests/fuzz/fuzz_"$t" "$work" "tests/fuzz/corpus/$t" -max_total_time="$secs" -timeout=10 \
        -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 -artifact_prefix="$found/" >"build-fuzz/fuzz-$t.log" 2>&1
    local rc=$?
    local execs cov
    execs=$(grep -o "stat::number_of_executed_units: *[0-9]*" "build-fuzz/fuzz-$t.log" | grep -o "[0-9]*$")
    cov=$(grep -o "cov: [0-9]*" "build-fuzz/fuzz-$t.log" | tail -1)
    for f in "$found"/*; do [ -e "$f" ] && cp "$f" "tests/fuzz/corpus/$t/$(basename "$f")"; done
    echo "$t: exit $rc, ${execs:-?} executions in ${secs} s, ${cov:-cov: ?} edges, corpus $(ls "$work" | wc -l) inputs, findings $(ls "$found" | wc -l)" >>"$summary"
}
running=0
for t in "${targets[@]}"; do
    run_one "$t" &
    running=$((running + 1))
    if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
cat "$summary"
! grep -q "findings [1-9]" "$summary"
