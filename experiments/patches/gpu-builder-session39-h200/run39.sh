#!/bin/bash
# Session 39's device runs: gpu-binned --clusters with a cached pair-area matrix in the clustering.
# Usage: run39.sh PHASE[,PHASE]  (ctest: the builders' GPU tests; fb: furball builds, bench, ncu; scans: builds)
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
if [[ $phases == *,alltests,* ]]; then
    $R/b/bin/bvhlab_gpu_tests --gtest_filter='-GpuRender.DumpedRaysOfEveryBounceVerifyAgainstEmbree' > $OUT/gpu-tests.txt 2>&1
    echo "gpu tests rc=$? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $OUT/gpu-tests.txt | tr '\n' ' ') $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,fbrec,* ]]; then
    mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj
    for round in 1 2; do builds furball gpu-binned c130 c150 hploc; done
    bench furball binned gpu-binned c130 c150 hploc
    echo "fbrec done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,ctest,* ]]; then
    $R/b/bin/bvhlab_gpu_tests --gtest_filter='GpuBuilder.*:GpuReinsertion.*' > $OUT/gpu-tests-builders.txt 2>&1; echo "builder tests rc=$? $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,fb,* ]]; then
    mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj
    for round in 1 2; do builds furball gpu-binned c130 c150 hploc; done
    bench furball binned c130
    echo "fb done $(date +%T)" >> $OUT/log.txt
    ncu --metrics gpu__time_duration.sum --csv $B build furball --builder gpu-binned --clusters 1.3 --runs 1 --no-epo -q > $OUT/ncu-c130.csv 2>&1
    ncu --kernel-name regex:cluster_chunks --launch-count 1 --section SpeedOfLight --section Occupancy --section LaunchStats --section WarpStateStats \
        $B build furball --builder gpu-binned --clusters 1.3 --runs 1 --no-epo -q > $OUT/ncu-cluster-chunks.txt 2>&1
    echo "ncu done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,prof,* ]]; then
    [ -f $S/furball/furball.obj ] || { mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj; }
    ncu --set full --import-source no --kernel-name regex:"${KREGEX:-cluster_chunks}" --launch-count 1 -o $OUT/prof \
        $B build furball --builder gpu-binned --clusters 1.3 --runs 1 --no-epo -q > $OUT/ncu.log 2>&1
    ncu -i $OUT/prof.ncu-rep --page source --csv --print-source sass > $OUT/prof-sass.csv 2>&1
    ncu -i $OUT/prof.ncu-rep --page details --print-details all > $OUT/prof-details.txt 2>&1
    rm -f $OUT/prof.ncu-rep
    echo "prof done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,verify,* ]]; then
    for s in sibenik stanford-bunny cornell-box gen:soup:100000; do
        for o in "" "--clusters 1.3"; do
            $B verify $s --builder gpu-binned $o --device gpu --kernel all --json -q 2>>$OUT/err.txt | sed "s/^{/{\"exp\": \"${o:-plain}\", /" >> $OUT/verify.jsonl
        done
    done
    python3 - "$OUT" >> $OUT/log.txt <<'PY'
import json, sys
v = [json.loads(l) for l in open(sys.argv[1] + '/verify.jsonl')]
print('verify', len(v), 'records', sum(r.get('rays', 0) for r in v), 'rays', sum(r.get('mismatches', 0) for r in v), 'mismatches')
PY
    rm -f $OUT/verify.jsonl
    echo "verify done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,scans,* ]]; then
    for s in stanford-bunny dragon-100k buddha-100k sibenik; do builds $s gpu-binned c130 hploc; bench $s binned c130; done
    echo "scans done $(date +%T)" >> $OUT/log.txt
fi
exit 0
