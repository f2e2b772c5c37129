#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Compares bvhlab's kernels on one scene and plots Mrays/s per kernel and ray type.

    PYTHONPATH=build/python python3 examples/python/compare_kernels.py data/cornell_box.obj --out kernels.png

On a machine with a GPU every registered kernel of the structure's layout is timed (kernel time
from CUDA events, median of --runs after a warm-up); without one, the CPU tracer. Every kernel's
hits are checked against Embree first: a kernel with a real mismatch is reported and not timed.
"""
import argparse
import json
import sys

import bvhlab


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", help="an OBJ file")
    ap.add_argument("--builder", default="sbvh", help="binned, sweep, sbvh or kdtree (default sbvh)")
    ap.add_argument("--layout", default="bvh2", help="bvh2 or cwbvh (default bvh2)")
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--out", default="kernels.png", help="the plot (PNG)")
    ap.add_argument("--json", action="store_true", help="also print one JSON line per measurement")
    a = ap.parse_args()
    try:
        scene = bvhlab.load(a.scene)
        s = bvhlab.build(scene, builder=a.builder, layout=a.layout, epo=False)
        gpu, why = bvhlab.gpu_available()
        targets = [("gpu", k["name"]) for k in bvhlab.kernels() if k["layout"] == s.layout] if gpu else [("cpu", "")]
        if not gpu:
            print(f"no GPU ({why}): timing the CPU tracer", file=sys.stderr)
        results = {}
        for kind in ("primary", "diffuse"):
            rays, query = bvhlab.rays(scene, kind, width=a.width, height=a.height)
            for device, kernel in targets:
                hits, info = bvhlab.trace(s, rays, query, device=device, kernel=kernel)
                report = bvhlab.verify(scene, rays, hits, query)
                name = info["kernel"]
                if report["mismatches"]:
                    print(f"{name} {kind}: {report['mismatches']} real mismatches against Embree; not timed")
                    continue
                hits, info = bvhlab.trace(s, rays, query, device=device, kernel=kernel, runs=a.runs + 1)
                info["ms"] = info["ms"][1:]  # the first run is the warm-up
                mrays = bvhlab.mrays_per_s(rays, info)
                results.setdefault(name, {})[kind] = mrays
                print(f"{name:32s} {kind:8s} {len(rays):9d} rays {mrays:10.1f} Mrays/s")
                if a.json:
                    print(json.dumps({"scene": scene.source, "scene_hash": scene.hash, "structure": s.name,
                                      "kernel": name, "device": device, "ray_type": kind, "rays": len(rays),
                                      "median_ms": sorted(info["ms"])[len(info["ms"]) // 2],
                                      "mrays_per_s": mrays, "commit": bvhlab.__commit__}))
    except bvhlab.Error as e:
        print(f"compare_kernels: {e}", file=sys.stderr)
        return 1
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = sorted(results, key=lambda n: -results[n].get("diffuse", 0))
    fig, ax = plt.subplots(figsize=(8, 0.4 * len(names) + 1.5))
    y = range(len(names))
    for off, kind in ((-0.2, "primary"), (0.2, "diffuse")):
        ax.barh([i + off for i in y], [results[n].get(kind, 0) for n in names], height=0.4, label=kind)
    ax.set_yticks(list(y), names)
    ax.invert_yaxis()
    ax.set_xlabel("Mrays/s")
    ax.set_title(f"{s.name} on {scene.source} ({scene.triangle_count} triangles)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
