#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Runs the benchmarks and writes JSON to experiments/results/, named by commit and machine.
# Usage: experiments/run_benchmarks.sh [BUILD_DIR] [extra Google Benchmark flags...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
# Name results by the commit baked into the binaries, not by the working tree.
commit=$("$build/tools/bvhlab" --version 2>/dev/null || echo unknown)
host=$(hostname -s)
mkdir -p "$root/experiments/results"
for b in build_bench trace_bench; do
    out="$root/experiments/results/${b}-${commit}-${host}.json"
    "$build/experiments/$b" --benchmark_out="$out" --benchmark_out_format=json "$@"
    echo "wrote $out"
done
