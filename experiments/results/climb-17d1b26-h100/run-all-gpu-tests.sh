# Every GPU test, furball's render test included (scans and furball carried; the test binary's libraries only).
D=/tmp/w; mkdir -p $D/scenes/furball $D/lib; C=.dist/carry35g
tar xJf $C/libs.tar.xz -C $D/lib
tar xJf $C/scenes.tar.xz -C $D/scenes
xz -dc $C/verts.obj.xz > $D/verts.obj && python3 $C/rebuild.py $D/verts.obj $D/scenes/furball/furball.obj && rm $D/verts.obj
md5sum $D/scenes/furball/furball.obj; ls $D/scenes
xz -dc $C/gpu_tests.xz > $D/gt; chmod +x $D/gt
export BVHLAB_SCENES=$D/scenes BVHLAB_DATA=$PWD/data LD_LIBRARY_PATH=$D/lib
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
$D/gt > $OUT/gpu-tests-all.txt 2>&1; echo "gt rc=$?"
tail -4 $OUT/gpu-tests-all.txt; grep -E "^\[  FAILED|Failure" $OUT/gpu-tests-all.txt | head
grep -E "GpuRender.DumpedRays" $OUT/gpu-tests-all.txt
