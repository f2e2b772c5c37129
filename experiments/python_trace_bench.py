#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The Python module's trace against the command line's bench, on the same ray file and kernel:
one JSON line per (kernel, ray file) with the module's Mrays/s (median of --runs timed runs after
one warm-up, kernel time from CUDA events, as `bvhlab bench` times it) and its hits' checksum.

    PYTHONPATH=build/python python3 experiments/python_trace_bench.py SCENE.obj RAYS... --kernel K [--layout L]
"""
import argparse
import hashlib
import json
import sys

import bvhlab


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("rays", nargs="+")
    ap.add_argument("--kernel", action="append", required=True)
    ap.add_argument("--builder", default="binned")
    ap.add_argument("--layout", default="bvh2")
    ap.add_argument("--runs", type=int, default=10)
    a = ap.parse_args()
    scene = bvhlab.load(a.scene)
    s = bvhlab.build(scene, builder=a.builder, layout=a.layout, epo=False)
    for path in a.rays:
        rays, query = bvhlab.read_rays(path)
        for k in a.kernel:
            hits, info = bvhlab.trace(s, rays, query, device="gpu", kernel=k, runs=a.runs + 1)
            info["ms"] = info["ms"][1:]
            print(json.dumps({"record": "python-bench", "commit": bvhlab.__commit__, "scene_hash": scene.hash,
                              "structure": s.name, "kernel": info["kernel"], "ray_file": path, "rays": len(rays),
                              "runs": a.runs, "median_ms": sorted(info["ms"])[len(info["ms"]) // 2],
                              "mrays_per_s": bvhlab.mrays_per_s(rays, info),
                              "hits_sha1": hashlib.sha1(hits.tobytes()).hexdigest()}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
