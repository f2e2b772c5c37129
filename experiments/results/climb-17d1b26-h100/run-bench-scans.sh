# Trace of gpu-binned trees beside the CPU binned tree, every kernel, the four scans.
D=/tmp/w; mkdir -p $D/scenes; C=.dist/carry35
tar xJf $C/slim.tar.xz -C $D
tar xJf $C/scenes.tar.xz -C $D/scenes
export BVHLAB_SCENES=$D/scenes BVHLAB_DATA=$PWD/data LD_LIBRARY_PATH=$D/gpu/lib
B=$D/gpu/bin/bvhlab
for sc in stanford-bunny dragon-100k buddha-100k sibenik; do for bl in binned gpu-binned; do
  $B bench $sc --builder $bl --device gpu --kernel all --types primary,diffuse --json -q >> $OUT/bench.jsonl
done; done
python3 - <<'PY' | tee $OUT/summary.txt
import json, os, collections
best = collections.defaultdict(dict); mm = n = 0
for l in open(os.environ["OUT"] + "/bench.jsonl"):
    r = json.loads(l); n += 1; mm += r["check"]["mismatches"]
    b = r["config"].split()[0]; k = (r["scene"], r["ray_type"])
    best[k][b] = max(best[k].get(b, (0, "")), (r["mrays_per_s"], r["kernel"]))
print("records", n, "mismatches", mm, "commit", r["commit"])
for k, v in best.items():
    print(k, {b: "%.0f %s" % x for b, x in v.items()}, "ratio %.3f" % (v["gpu-binned"][0] / v["binned"][0]))
PY
