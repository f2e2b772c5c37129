# The one climb: GPU tests, old vs new binaries (passes' refit, gpu-binned), verify of pass trees.
D=/tmp/w; mkdir -p $D/scenes; C=.dist/carry35
tar xJf $C/slim.tar.xz -C $D
tar xJf $C/scenes.tar.xz -C $D/scenes
xz -dc $C/gpu_tests.xz > $D/gt; chmod +x $D/gt
xz -dc $C/bvhlab-old.xz > $D/gpu/bin/bvhlab-old; chmod +x $D/gpu/bin/bvhlab-old
export BVHLAB_SCENES=$D/scenes BVHLAB_DATA=$PWD/data LD_LIBRARY_PATH=$D/gpu/lib
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
$D/gt --gtest_filter=-GpuRender.DumpedRaysOfEveryBounceVerifyAgainstEmbree > $OUT/gpu-tests.txt 2>&1
tail -3 $OUT/gpu-tests.txt; grep -E "^\[  FAILED|Failure" $OUT/gpu-tests.txt | head
for r in 1 2; do for b in bvhlab-old bvhlab; do
  for sc in gen:soup:10000000:1 gen:soup:1000000:1 dragon-100k; do
    $D/gpu/bin/$b build $sc --builder hploc --reinsert 4 --runs 10 --no-epo --json -q >> $OUT/build-$b.jsonl
    $D/gpu/bin/$b build $sc --builder lbvh --reinsert 4 --runs 10 --no-epo --json -q >> $OUT/build-$b.jsonl
  done
  for sc in gen:soup:1000000:1 dragon-100k; do
    $D/gpu/bin/$b build $sc --builder gpu-binned --runs 10 --no-epo --json -q >> $OUT/build-$b.jsonl
  done
done; done
for b in bvhlab-old bvhlab; do
  ncu --metrics gpu__time_duration.sum --csv -k regex:"refit_from_leaves|leaves_and_climb" $D/gpu/bin/$b build gen:soup:1000000:1 --builder hploc --reinsert 4 --runs 1 --no-epo -q > $OUT/ncu-$b.csv 2>/dev/null
  ncu --metrics gpu__time_duration.sum --csv -k regex:"leaves_and_climb" $D/gpu/bin/$b build gen:soup:1000000:1 --builder gpu-binned --runs 1 --no-epo -q >> $OUT/ncu-$b.csv 2>/dev/null
done
B=$D/gpu/bin/bvhlab
for sc in sibenik stanford-bunny; do $B verify $sc --builder hploc --reinsert 4 --device gpu --kernel all --json -q >> $OUT/verify.jsonl; done
for sc in dragon-100k buddha-100k; do $B verify $sc --builder lbvh --reinsert 4 --device gpu --json -q >> $OUT/verify.jsonl; $B verify $sc --builder gpu-binned --device gpu --json -q >> $OUT/verify.jsonl; done
python3 - <<'PY' | tee $OUT/summary.txt
import json, os, csv, collections
out = os.environ["OUT"]
for b in ("bvhlab-old", "bvhlab"):
    for l in open(f"{out}/build-{b}.jsonl"):
        r = json.loads(l); g = r["gpu_build"]
        print(b, r["commit"], r["scene"], r.get("builder"), r.get("reinsert", r["gpu_build"].get("passes")), "%.3f ms opt %.3f" % (g["median_ms"], g.get("optimize_ms", -1)), "sah %.10f" % r["sah"], r["nodes"])
for b in ("bvhlab-old", "bvhlab"):
    t = collections.defaultdict(float); c = collections.Counter()
    for x in csv.reader(open(f"{out}/ncu-{b}.csv")):
        if len(x) < 10 or x[0] == "ID": continue
        h = ["ID","Process ID","Process Name","Host Name","Kernel Name"]
        k = x[4].split("(")[0]; v = float(x[-1].replace(",", ""))
        t[k] += v / 1e6; c[k] += 1
    print(b, {k: "%.3f ms / %d" % (v, c[k]) for k, v in t.items()})
n = rays = mm = 0
for l in open(out + "/verify.jsonl"):
    r = json.loads(l); n += 1; rays += r.get("rays", 0); mm += r.get("mismatches", 0)
print("verify records", n, "rays", rays, "mismatches", mm)
PY
