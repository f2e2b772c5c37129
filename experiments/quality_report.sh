#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Per-ray cost of every structure side by side: `bvhlab quality --json` for each structure and
# scene, into experiments/results/quality-<commit>-<host>.jsonl.
# Usage: experiments/quality_report.sh [BUILD_DIR] [SCENE ...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(stanford-bunny dragon-100k buddha-100k furball)
bin=$build/tools/bvhlab
out="$root/experiments/results/quality-$("$bin" --version)-$(hostname -s).jsonl"
: >"$out"
for s in "${scenes[@]}"; do
    for st in bvh sweep sbvh kdtree; do
        epo=()
        [ "$s" = furball ] && epo=(--no-epo)  # EPO of 2.7M triangles takes minutes
        "$bin" -q quality "$s" --structure "$st" "${epo[@]}" --json >>"$out"
    done
done
echo "wrote $out"
