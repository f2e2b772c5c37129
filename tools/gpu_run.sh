#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One batched GPU session over an installed bvhlab (cmake --install): GPU tests, verification
# of the GPU kernel against Embree, and GPU + CPU benchmarks, as logs and JSON lines in OUT.
# Usage: tools/gpu_run.sh PREFIX SCENES_DIR OUT [SCENE ...]
set -uo pipefail
prefix=$1 scenes=$2 out=$3
shift 3
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(stanford-bunny dragon-100k buddha-100k furball)
export BVHLAB_SCENES=$scenes BVHLAB_DATA=$prefix/share/bvhlab/data
mkdir -p "$out"
bin=$prefix/bin
status=0
{ nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1; "$bin/bvhlab" --version; } | tee "$out/machine.txt"
"$bin/bvhlab_gpu_tests" 2>&1 | tee "$out/gpu_tests.log" | tail -3 || status=1
grep -q "FAILED" "$out/gpu_tests.log" && status=1
for s in "${names[@]}"; do
    # Protocol rays (1024x768, AO 8, diffuse 4, shadow 1), every hit checked against Embree.
    "$bin/bvhlab" -q verify "$s" --device gpu --json >>"$out/verify.jsonl" || status=1
    "$bin/bvhlab" -q bench "$s" --device gpu --runs 10 --json >>"$out/bench.jsonl" || status=1
    # The tinybvh comparison setting for primary rays: 480x320 pixels, 16 spp, 4x4 tiles.
    "$bin/bvhlab" -q bench "$s" --device gpu --types primary --width 480 --height 320 --spp 16 --tile 4 \
        --runs 10 --json >>"$out/bench.jsonl" || status=1
done
echo "gpu_run.sh: status $status"
exit $status
