#!/bin/bash
# Session 38's device run: gpu-binned over clusters of nearly coincident triangles
# (BVHLAB_CLUSTER_ALPHA). Usage: run38.sh PHASE[,PHASE] (fb, scans, verify, tests, ncu)
set -u
here=$(cd "$(dirname "$0")" && pwd)
R=/tmp/r
rm -rf $R; mkdir -p $R && tar xJf "$here/bundle.tar.xz" -C $R
[ -f "$here/tests.tar.xz" ] && tar xJf "$here/tests.tar.xz" -C $R
export LD_LIBRARY_PATH=$R/b/lib
B=$R/b/bin/bvhlab
S=/tmp/scenes
[ -d $S/cornell-box ] || { mkdir -p $S && tar xJf "$here/scans.tar.xz" -C $S; }
export BVHLAB_SCENES=$S BVHLAB_DATA=$PWD/data
phases=",$1,"
{ nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv; $B --version; } > $OUT/machine.txt 2>&1
tag() { sed "s/^{/{\"exp\": \"$1\", /"; }
declare -A ENVS=([base]="" [a130]="BVHLAB_CLUSTER_ALPHA=1.3" [a150]="BVHLAB_CLUSTER_ALPHA=1.5" [a200]="BVHLAB_CLUSTER_ALPHA=2.0")
furball() { [ -f $S/furball/furball.obj ] || { mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj; }; }
builds() {  # scene runs names...
    local s=$1 r=$2; shift 2
    for name in "$@"; do
        env ${ENVS[$name]} BVHLAB_CLUSTER_VERBOSE=1 $B build $s --builder gpu-binned --runs 1 -q >/dev/null 2>>$OUT/clusters.txt; echo "$s $name" >> $OUT/clusters.txt
        env ${ENVS[$name]} $B build $s --builder gpu-binned --runs $r --no-epo --json -q 2>>$OUT/err.txt | tag $name >> $OUT/build.jsonl
    done
    $B build $s --builder hploc --runs $r --no-epo --json -q 2>>$OUT/err.txt | tag hploc >> $OUT/build.jsonl
}
bench() {  # scene kernel names...
    local s=$1 k=$2; shift 2
    $B bench $s --builder binned --device gpu --kernel $k --types primary,diffuse --json -q 2>>$OUT/err.txt | tag cpu-binned >> $OUT/bench.jsonl
    for name in "$@"; do
        env ${ENVS[$name]} $B bench $s --builder gpu-binned --device gpu --kernel $k --types primary,diffuse --json -q 2>>$OUT/err.txt | tag $name >> $OUT/bench.jsonl
    done
}
if [[ $phases == *,fb,* ]]; then
    furball
    echo "fb start $(date +%T)" >> $OUT/log.txt
    for round in 1 2; do builds furball 10 base a130 a150 a200; done
    echo "fb bench $(date +%T)" >> $OUT/log.txt
    bench furball dynamic-speculative-fma a130 a150 a200
    echo "fb done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,fb2,* ]]; then
    furball
    for round in 1 2; do builds furball 10 a130 a150; done
    BVHLAB_CLUSTER_ALPHA=1.3 ncu --metrics gpu__time_duration.sum --csv $B build furball --builder gpu-binned --runs 1 --no-epo -q > $OUT/ncu-a130.csv 2>&1
    echo "fb2 done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,ncu2,* ]]; then
    furball
    BVHLAB_CLUSTER_ALPHA=1.3 ncu --kernel-name regex:'cluster_chunks|sah_bin|leaves_and_climb' --launch-count 3 \
        --section SpeedOfLight --section Occupancy --section WarpStateStats --section LaunchStats --section SchedulerStats --section ComputeWorkloadAnalysis --section MemoryWorkloadAnalysis \
        $B build furball --builder gpu-binned --runs 1 --no-epo -q > $OUT/ncu2-a130.txt 2>&1
    echo "ncu2 done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,scans,* ]]; then
    for s in stanford-bunny dragon-100k buddha-100k sibenik; do
        builds $s 10 base a130 a150
        bench $s dynamic-speculative-fma a130 a150
    done
    echo "scans done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,verify,* ]]; then
    for s in sibenik stanford-bunny gen:soup:100000 cornell-box; do
        for name in a130; do
            env ${ENVS[$name]} $B verify $s --builder gpu-binned --device gpu --kernel all --json -q 2>>$OUT/err.txt | tag $name >> $OUT/verify.jsonl
        done
    done
    furball
    env ${ENVS[a130]} $B verify furball --builder gpu-binned --device gpu --json -q 2>>$OUT/err.txt | tag a130 >> $OUT/verify.jsonl
    echo "verify done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,tests,* ]]; then
    furball
    $R/b/bin/bvhlab_gpu_tests > $OUT/gpu-tests.txt 2>&1; echo "gpu tests rc=$?" >> $OUT/log.txt
    BVHLAB_CLUSTER_ALPHA=1.3 $R/b/bin/bvhlab_gpu_tests --gtest_filter='GpuBuilder*:GpuReinsertion*' > $OUT/gpu-tests-a130.txt 2>&1; echo "a130 tests rc=$?" >> $OUT/log.txt
fi
if [[ $phases == *,ncu,* ]]; then
    furball
    for name in a130 a200 base; do
        env ${ENVS[$name]} ncu --metrics gpu__time_duration.sum --csv $B build furball --builder gpu-binned --runs 1 --no-epo -q > $OUT/ncu-$name.csv 2>&1
    done
    echo "ncu done $(date +%T)" >> $OUT/log.txt
fi
exit 0
