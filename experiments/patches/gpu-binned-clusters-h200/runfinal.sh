#!/bin/bash
# The final batch: every GPU test (furball not carried: its render test left out), verify with
# every kernel and bench with every kernel, gpu-binned with and without --clusters 1.3.
here=$(cd "$(dirname "$0")" && pwd)
R=/tmp/r; rm -rf $R; mkdir -p $R && tar xJf "$here/bundle.tar.xz" -C $R && tar xJf "$here/tests.tar.xz" -C $R
S=/tmp/scenes; mkdir -p $S && tar xJf "$here/scans.tar.xz" -C $S
export LD_LIBRARY_PATH=$R/b/lib BVHLAB_DATA=$PWD/data BVHLAB_SCENES=$S
B=$R/b/bin/bvhlab
{ nvidia-smi --query-gpu=name,driver_version --format=csv; $B --version; } > $OUT/machine.txt 2>&1
$R/b/bin/bvhlab_gpu_tests --gtest_filter='-GpuRender.DumpedRaysOfEveryBounceVerifyAgainstEmbree' > $OUT/gpu-tests.txt 2>&1
echo "gpu tests rc=$? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $OUT/gpu-tests.txt | tr '\n' ' ')" >> $OUT/summary.txt
for s in sibenik stanford-bunny cornell-box gen:soup:100000; do
    for o in "" "--clusters 1.3"; do
        $B verify $s --builder gpu-binned $o --device gpu --kernel all --json -q 2>>$OUT/err.txt | sed "s/^{/{\"exp\": \"${o:-plain}\", /" >> $OUT/verify.jsonl
    done
done
for s in sibenik stanford-bunny dragon-100k buddha-100k; do
    for o in "" "--clusters 1.3"; do
        $B bench $s --builder gpu-binned $o --device gpu --kernel all --types primary,diffuse --json -q 2>>$OUT/err.txt | sed "s/^{/{\"exp\": \"${o:-plain}\", /" >> $OUT/bench.jsonl
    done
done
python3 - "$OUT" >> $OUT/summary.txt <<'PY'
import json, sys, collections
o = sys.argv[1]
v = [json.loads(l) for l in open(o + '/verify.jsonl')]
print('verify', len(v), 'records', sum(r.get('rays', 0) for r in v), 'rays', sum(r.get('mismatches', 0) for r in v), 'mismatches')
b = [json.loads(l) for l in open(o + '/bench.jsonl')]
print('bench', len(b), 'records', sum(r['check']['mismatches'] for r in b), 'mismatches')
PY
rm -f $OUT/verify.jsonl
exit 0
