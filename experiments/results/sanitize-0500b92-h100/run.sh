D=/tmp/w; rm -rf $D; mkdir -p $D/scenes; C=.dist/carry35
tar xJf $C/slim.tar.xz -C $D
tar xJf $C/scenes.tar.xz -C $D/scenes
xz -dc $C/gpu_tests.xz > $D/gt; chmod +x $D/gt
export LD_LIBRARY_PATH=$D/gpu/lib BVHLAB_SCENES=$D/scenes BVHLAB_DATA=$PWD/data
$D/gpu/bin/bvhlab --version
$D/gt --gtest_filter=-GpuRender.DumpedRaysOfEveryBounceVerifyAgainstEmbree > $OUT/gpu-tests.txt 2>&1
tail -4 $OUT/gpu-tests.txt; grep -E "^\[  FAILED|Failure" $OUT/gpu-tests.txt | head
B=$D/gpu/bin/bvhlab
for sc in sibenik stanford-bunny; do $B verify $sc --builder hploc --reinsert 4 --device gpu --json -q >> $OUT/verify.jsonl; $B verify $sc --builder gpu-binned --reinsert 2 --device gpu --json -q >> $OUT/verify.jsonl; done
python3 -c "
import json; n=r=m=0
for l in open('$OUT/verify.jsonl'): x=json.loads(l); n+=1; r+=x['rays']; m+=x['mismatches']
print('verify records', n, 'rays', r, 'mismatches', m)"
bash tools/gpu_run.sh $D/gpu $D/scenes $OUT sanitize > /dev/null
grep -E "SUMMARY" $OUT/sanitizer.log | sort | uniq -c
cat $OUT/summary.txt
