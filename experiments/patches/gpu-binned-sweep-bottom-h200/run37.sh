#!/bin/bash
# Session 37's device run: gpu-binned with the block-wide sweep bottom (BVHLAB_SWEEP_BOTTOM) and
# the Morton top (BVHLAB_LBVH_TOP). Usage: run37.sh PHASE[,PHASE] (fb, scans, tests, verify)
set -u
here=$(cd "$(dirname "$0")" && pwd)
R=/tmp/r
[ -x $R/b/bin/bvhlab ] || { mkdir -p $R && tar xJf "$here/bundle.tar.xz" -C $R; }
export LD_LIBRARY_PATH=$R/b/lib
B=$R/b/bin/bvhlab
S=/tmp/scenes
[ -f $S/scenes.json ] || { mkdir -p $S && tar xJf "$here/scans.tar.xz" -C $S; }
export BVHLAB_SCENES=$S BVHLAB_DATA=$PWD/data
phases=",$1,"
{ nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv; $B --version; } > $OUT/machine.txt 2>&1
tag() { sed "s/^{/{\"exp\": \"$1\", /"; }
# name: environment of each configuration
declare -A ENVS=([base]="" [sweep]="BVHLAB_SWEEP_BOTTOM=1" [sweep-top4096]="BVHLAB_SWEEP_BOTTOM=1 BVHLAB_LBVH_TOP=4096"
                 [sweep-top1024]="BVHLAB_SWEEP_BOTTOM=1 BVHLAB_LBVH_TOP=1024" [top4096]="BVHLAB_LBVH_TOP=4096")
builds() {  # scene runs names...
    local s=$1 r=$2; shift 2
    for name in "$@"; do
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
    [ -f $S/furball/furball.obj ] || { mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj; }
    echo "fb start $(date +%T)" >> $OUT/log.txt
    for round in 1 2; do builds furball 10 base sweep sweep-top4096 sweep-top1024 top4096; done
    echo "fb bench $(date +%T)" >> $OUT/log.txt
    bench furball dynamic-speculative-fma sweep sweep-top4096 sweep-top1024
    echo "fb done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,scans,* ]]; then
    for s in stanford-bunny dragon-100k buddha-100k sibenik; do
        builds $s 10 base sweep sweep-top4096
        bench $s dynamic-speculative-fma sweep sweep-top4096
    done
    echo "scans done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,verify,* ]]; then
    for s in sibenik stanford-bunny; do
        for name in sweep sweep-top4096; do
            env ${ENVS[$name]} $B verify $s --builder gpu-binned --device gpu --kernel all --json -q 2>>$OUT/err.txt | tag $name >> $OUT/verify.jsonl
        done
    done
    env ${ENVS[sweep]} $B verify gen:soup:100000 --builder gpu-binned --device gpu --kernel all --json -q 2>>$OUT/err.txt | tag sweep >> $OUT/verify.jsonl
    echo "verify done $(date +%T)" >> $OUT/log.txt
fi
if [[ $phases == *,tests,* ]]; then
    $R/b/bin/bvhlab_gpu_tests > $OUT/gpu-tests.txt 2>&1; echo "gpu tests rc=$?" >> $OUT/log.txt
    BVHLAB_SWEEP_BOTTOM=1 $R/b/bin/bvhlab_gpu_tests --gtest_filter='GpuBuilder*:GpuReinsertion*' > $OUT/gpu-tests-sweep.txt 2>&1; echo "sweep tests rc=$?" >> $OUT/log.txt
fi
if [[ $phases == *,ncu,* ]]; then
    [ -f $S/furball/furball.obj ] || { mkdir -p $S/furball && python3 "$here/rebuild.py" "$here/furball-v.xz" $S/furball/furball.obj; }
    for name in sweep base; do
        env ${ENVS[$name]} ncu --kernel-name regex:'sah_sweep_block|sah_small|sah_tiny' --launch-count 2 \
            --section SpeedOfLight --section Occupancy --section WarpStateStats --section LaunchStats --section SchedulerStats \
            $B build furball --builder gpu-binned --runs 1 --no-epo -q > $OUT/ncu-$name.txt 2>&1
    done
    echo "ncu done $(date +%T)" >> $OUT/log.txt
fi
exit 0
