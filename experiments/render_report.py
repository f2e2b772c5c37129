#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The renderer's overhead report (issue 19) from tools/gpu_run.sh's render phase: for each
scene, the whole render's Mrays/s (render.jsonl: every ray of every pass over the render's wall
time) against the extend kernel's own Mrays/s on the same bounce rays (render_bench.jsonl:
`bvhlab bench --rays` on the first pass's dumped extension and shadow rays, median of 5 runs).
The kernel-only figure is the dumped rays' total over the sum of their kernel times, so each
bounce counts with its share of the rays. Goal: the ratio >= 0.75.

Also the rays and live paths per bounce, and the time per stage.

Usage: experiments/render_report.py RENDER.jsonl RENDER_BENCH.jsonl  (Markdown on stdout)"""
import json
import os
import sys
from collections import defaultdict


def scene_of_file(path):
    # .../render-<scene>/<kind>-bounce<N>.rays
    return os.path.basename(os.path.dirname(path)).removeprefix("render-")


def main():
    renders = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
    benches = [json.loads(l) for l in open(sys.argv[2]) if l.strip()]
    kernel_ms = defaultdict(float)
    kernel_rays = defaultdict(int)
    bad = defaultdict(int)
    for b in benches:
        s = scene_of_file(b["ray_file"])
        kernel_ms[s] += b["median_ms"]
        kernel_rays[s] += b["rays"]
        bad[s] += b.get("mismatches", 0)
    print("| scene | triangles | spp | render Mrays/s | after set-up | extend kernel Mrays/s (same rays) "
          "| ratio (goal >= 0.75) | after set-up | real mismatches "
          "| ms: set-up / extend / shade / shadow / compact / other |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in renders:
        name = os.path.basename(r["scene_file"]) if "scene_file" in r else r["scene"]
        key = r.get("out", "").split("/")[-1].removesuffix(".pfm") or name
        k = kernel_rays[key] / (kernel_ms[key] * 1e3) if kernel_ms[key] else float("nan")
        ms = r["ms"]
        setup = ms.get("setup", 0.0)
        other = ms["total"] - setup - ms["extend"] - ms["shade"] - ms["shadow"] - ms["compact"]
        passes = r["rays"] / ((ms["total"] - setup) * 1e3)
        print(f"| {r['scene']} | {r['triangles']:,} | {r['spp']} | {r['mrays_per_s']:,.0f} | {passes:,.0f} | "
              f"{k:,.0f} | {r['mrays_per_s'] / k:.2f} | {passes / k:.2f} | {bad[key]} | {setup:.0f} / "
              f"{ms['extend']:.0f} / {ms['shade']:.0f} / {ms['shadow']:.0f} / {ms['compact']:.0f} / {other:.0f} |")
    print()
    print("Rays per bounce (all passes), extension / shadow:")
    print()
    for r in renders:
        cells = ", ".join(f"{b['extension_rays']:,} / {b['shadow_rays']:,}" for b in r["bounces"])
        print(f"- {r['scene']}: {cells}")


if __name__ == "__main__":
    main()
