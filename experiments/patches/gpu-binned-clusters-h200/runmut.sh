#!/bin/bash
# Planted bugs in gpu_builder.cu's cluster kernels: each mutant's GPU test binary on the clustered tests.
here=$(cd "$(dirname "$0")" && pwd)
R=/tmp/r; rm -rf $R; mkdir -p $R && tar xJf "$here/bundle.tar.xz" -C $R && tar xJf "$here/mut.tar.xz" -C $R && tar xJf "$here/tests.tar.xz" -C $R
export LD_LIBRARY_PATH=$R/b/lib BVHLAB_DATA=$PWD/data BVHLAB_SCENES=/tmp/scenes
mkdir -p /tmp/scenes && tar xJf "$here/scans.tar.xz" -C /tmp/scenes
$R/b/bin/bvhlab_gpu_tests --gtest_filter="GpuBuilder.*:GpuReinsertion.*" > $OUT/unmutated.txt 2>&1; echo "unmutated rc=$? $(grep -E "^\[  (PASSED|FAILED)" $OUT/unmutated.txt | tr "\n" " ")" >> $OUT/summary.txt
for m in $R/b/bin/m*; do
    timeout 300 $m --gtest_filter='GpuBuilder.Clustered*:GpuBuilder.TreesAreValid*' > $OUT/$(basename $m).txt 2>&1
    echo "$(basename $m) rc=$? $(grep -c 'Failure' $OUT/$(basename $m).txt) failures; $(grep -m1 -A3 'Failure' $OUT/$(basename $m).txt | tr '\n' ' ' | cut -c1-300)" >> $OUT/summary.txt
done
exit 0
