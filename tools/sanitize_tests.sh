#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The sanitizer half of the test suite (README command 2, CI): a second build with GCC's
# -fsanitize=address,undefined (Debug, -O0: optimisation had hidden the kd-tree's vector ABI
# bug from a -O2 sanitizer build), CUDA off, then every CPU test, the CLI cases and the fuzz
# corpus replay through it. Which tests run, and why:
# - not the benchmark scenes (BVHLAB_SCENES is unset here): furball alone takes tens of
#   minutes under ASan at -O0, and the generated scenes and the Cornell box exercise the
#   same code; the Release run before this one covers the benchmark scenes;
# - not the GPU tests: a sanitizer build has no CUDA; on the H100 they run under
#   compute-sanitizer instead (tools/gpu_run.sh sanitize).
# Leak detection is off: Embree's and TBB's worker threads keep allocations until exit.
set -euo pipefail
cd "$(dirname "$0")/.."
unset BVHLAB_SCENES
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DBVHLAB_ENABLE_CUDA=OFF -DBVHLAB_BUILD_BENCHMARKS=OFF -DBVHLAB_BUILD_PYTHON=OFF \
    -DBVHLAB_WITH_OIIO=OFF -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined"
cmake --build build-asan -j"$(nproc)"
ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j"$(nproc)" -LE gpu
