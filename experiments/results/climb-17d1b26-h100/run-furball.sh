# Furball: H-PLOC, H-PLOC + 4 passes and gpu-binned builds; trace of their trees beside binned.
D=/tmp/w; mkdir -p $D/scenes/furball; C=.dist/carry35f
tar xJf $C/slim.tar.xz -C $D
cp $C/scenes.json $D/scenes/
xz -dc $C/verts.obj.xz > $D/verts.obj && python3 $C/rebuild.py $D/verts.obj $D/scenes/furball/furball.obj && rm $D/verts.obj
md5sum $D/scenes/furball/furball.obj
export BVHLAB_SCENES=$D/scenes BVHLAB_DATA=$PWD/data LD_LIBRARY_PATH=$D/gpu/lib
B=$D/gpu/bin/bvhlab
for r in 1 2; do
  $B build furball --builder gpu-binned --runs 10 --no-epo --json -q >> $OUT/build.jsonl
  $B build furball --builder hploc --runs 10 --no-epo --json -q >> $OUT/build.jsonl
  $B build furball --builder hploc --reinsert 4 --runs 10 --no-epo --json -q >> $OUT/build.jsonl
done
for bl in "binned" "gpu-binned" "hploc" "hploc --reinsert 4"; do
  $B bench furball --builder $bl --device gpu --kernel dynamic-speculative-fma --types primary,diffuse --json -q >> $OUT/bench.jsonl
done
python3 - <<'PY' | tee $OUT/summary.txt
import json, os
out = os.environ["OUT"]
for l in open(out + "/build.jsonl"):
    r = json.loads(l); g = r["gpu_build"]
    print(r["commit"], r["config"], "%.3f ms (%.0f Mtris/s)" % (g["median_ms"], g["median_mtris_per_s"]), "sah %.10f" % r["sah"], r["nodes"])
base = {}
for l in open(out + "/bench.jsonl"):
    r = json.loads(l)
    if r["config"].startswith("binned"): base[r["ray_type"]] = r["mrays_per_s"]
    print(r["config"], r["ray_type"], "%.0f Mrays/s" % r["mrays_per_s"], "x binned %.3f" % (r["mrays_per_s"] / base[r["ray_type"]]), "mismatches", r["check"]["mismatches"])
PY
