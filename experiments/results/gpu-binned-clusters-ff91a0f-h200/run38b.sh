#!/bin/bash
# Session 38's final device runs: gpu-binned --clusters. Usage: run38b.sh PHASE[,PHASE]
#   tests (the GPU tests), scans (builds, bench, verify on the scans), fb (furball)
set -u
here=$(cd "$(dirname "$0")" && pwd)
R=/tmp/r
rm -rf $R; mkdir -p $R && tar xJf "$here/bundle.tar.xz" -C $R
[ -f "$here/tests.tar.xz" ] && tar xJf "$here/tests.tar.xz" -C $R
export LD_LIBRARY_PATH=$R/b/lib
B=$R/b/bin/bvhlab
S=/tmp/scenes
mkdir -p $S
[ -f "$here/scans.tar.xz" ] && tar xJf "$here/scans.tar.xz" -C $S
[ -f "$here/scans-lite.tar.xz" ] && tar xJf "$here/scans-lite.tar.xz" -C $S
export BVHLAB_SCENES=$S BVHLAB_DATA=$PWD/data
phases=",$1,"
{ nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv; $B --version; } > $OUT/machine.txt 2>&1
tag() { sed "s/^{/{\"exp\": \"$1\", /"; }
declare -A OPTS=([gpu-binned]="--builder gpu-binned" [c130]="--builder gpu-binned --clusters 1.3"
                 [c150]="--builder gpu-binned --clusters 1.5" [hploc]="--builder hploc" [binned]="--builder binned")
builds() {  # scene names...
    local s=$1; shift
    for name in "$@"; do $B build $s ${OPTS[$name]} --runs 10 --no-epo --json -q 2>>$OUT/err.txt | tag $name >> $OUT/build.jsonl; done
}
bench() {  # scene names...
    local s=$1; shift
    for name in "$@"; do
        $B bench $s ${OPTS[$name]} --device gpu --kernel dynamic-speculative-fma --types primary,diffuse --json -q 2>>$OUT/err.txt | tag $name >> $OUT/bench.jsonl
    done
}
verify() {  # scene name kernel
    $B verify $1 ${OPTS[$2]} --device gpu --kernel $3 --json -q 2>>$OUT/err.txt | tag $2 > $OUT/v.jsonl
    python3 -c "
import json,sys
rs=[json.loads(l) for l in open('$OUT/v.jsonl')]
print('$1 $2 $3', len(rs), 'records', sum(r.get('rays',0) for r in rs), 'rays', sum(r.get('mismatches',0) for r in rs), 'mismatches', [r.get('status') for r in rs][:1])
" >> $OUT/verify-summary.txt 2>&1
}
if [[ $phases == *,ctest,* ]]; then
    $R/b/bin/bvhlab_gpu_tests --gtest_filter='GpuBuilder.Clustered*' > $OUT/gpu-tests-clustered.txt 2>&1; echo "clustered test rc=$? $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,tests,* ]]; then
    $R/b/bin/bvhlab_gpu_tests > $OUT/gpu-tests.txt 2>&1; echo "gpu tests rc=$? $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,scans,* ]]; then
    for s in stanford-bunny dragon-100k buddha-100k sibenik; do
        builds $s gpu-binned c130 c150 hploc
        bench $s binned gpu-binned c130
    done
    echo "scans done $(date +%T)" >> $OUT/log.txt
    for s in sibenik stanford-bunny gen:soup:100000 cornell-box; do verify $s c130 all; done
    verify dragon-100k c130 dynamic-speculative-fma
    echo "verify done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,fb,* ]]; then
    mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj
    for round in 1 2; do builds furball gpu-binned c130 c150 hploc; done
    bench furball binned gpu-binned c130 c150 hploc
    verify furball c130 dynamic-speculative-fma
    echo "fb done $(date +%T)" >> $OUT/log.txt
fi
exit 0
