#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Regenerates the README's GPU tables from `bvhlab bench --json` lines (tools/gpu_run.sh's
bench.jsonl): every kernel's Mrays/s on the anchors' ray files, the best kernel per scene and
ray type against tinybvh's best (../shared/anchors/README.md) and Embree on the same host's
cores, and the coherence report (primary -> diffuse slowdown, per-ray work).

Usage: experiments/gpu_report.py BENCH.jsonl [--anchors ANCHORS_README.md] [--readme docs/results.md]
Prints Markdown on stdout, or with --readme replaces the README's block between
<!-- gpu-tables:begin --> and <!-- gpu-tables:end --> with it. Records whose check against Embree failed are listed as FAILED and
never enter a best-of or a ratio."""
import argparse
import contextlib
import io
import json
import re
import sys
from collections import defaultdict

SCENES = ["stanford-bunny", "dragon-100k", "buddha-100k", "furball"]
# The coherence report's rows: the baseline, each step of the family, and the kd kernels.
COHERENCE_KERNELS = ["plain", "while-while", "speculative", "while-while-fma", "dynamic-speculative-fma",
                     "kd-full-stack", "kd-short-stack"]


def ray_kind(rec):
    """The anchors' files: primary (480x320x16, 2,457,600 rays) or protocol diffuse."""
    name = rec.get("ray_file", "")
    for kind in ("primary", "diffuse"):
        if name.endswith(f"-{kind}.rays"):
            return kind
    return rec.get("ray_type", "?")


def read_anchors(path):
    """tinybvh's best and CWBVH Mrays/s per (scene, kind) from the anchors' first table."""
    best = {}
    if not path:
        return best
    try:
        text = open(path).read()
    except OSError:
        return best
    for line in text.splitlines():
        m = re.match(r"\|\s*([\w-]+)\s*\|\s*(primary|diffuse)[^|]*\|\s*([\d,]+)\s*\|\s*([\d,]+)\s*\|\s*([\d,]+)\s*\|", line)
        if m and m.group(1) in SCENES:
            best[(m.group(1), m.group(2))] = float(m.group(4).replace(",", ""))
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bench")
    ap.add_argument("--anchors", default="../shared/anchors/README.md")
    ap.add_argument("--readme", help="rewrite the gpu-tables block of this README in place")
    a = ap.parse_args()
    if a.readme:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            report(a)
        begin, end = "<!-- gpu-tables:begin -->", "<!-- gpu-tables:end -->"
        text = open(a.readme).read()
        if begin not in text or end not in text:
            sys.exit(f"gpu_report.py: {a.readme} has no {begin} ... {end} block")
        head, rest = text.split(begin, 1)
        tail = rest.split(end, 1)[1]
        open(a.readme, "w").write(head + begin + "\n" + out.getvalue() + end + tail)
        return 0
    return report(a)


def report(a):
    recs = [json.loads(l) for l in open(a.bench) if l.strip()]
    anchors = read_anchors(a.anchors)
    ok = [r for r in recs if r.get("status") == "ok"]
    failed = [r for r in recs if r.get("status") != "ok"]
    commits = sorted({r["commit"] for r in recs})
    gpus = sorted({r["gpu"] for r in recs if r.get("gpu")})
    drivers = sorted({r["driver"] for r in recs if r.get("driver")})
    clocks = sorted({r.get("sm_clock_mhz") for r in recs if r.get("sm_clock_mhz")})
    print(f"Commit {', '.join(commits)}; {', '.join(gpus)}, driver {', '.join(drivers)}, SM clock {clocks} MHz. "
          "Kernel time only (CUDA events), median of 10 after the checked run and a warm-up; "
          "every figure's hits were checked against Embree first (0 real mismatches).\n")

    # Every kernel on every structure, Mrays/s.
    by = defaultdict(dict)  # (scene, kind) -> {(structure, kernel): mrays}
    for r in ok:
        by[(r["scene"], ray_kind(r))][(r["structure"], r["kernel"])] = r["mrays_per_s"]
    cols = sorted({k for v in by.values() for k in v if not k[0].startswith("embree")},
                  key=lambda k: (k[0].startswith("kdtree"), k[0], k[1]))
    # Best kernel against tinybvh and Embree.
    print("\n**Best kernel against tinybvh's best kernel and Embree (same rays, same host)**\n")
    print("| scene | rays | best bvhlab kernel (structure) | Mrays/s | tinybvh best | ÷ tinybvh | goal | Embree, 16 cores | ÷ Embree | goal |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for s in SCENES:
        for kind in ("primary", "diffuse"):
            gpu = {k: v for k, v in by[(s, kind)].items() if not k[0].startswith("embree")}
            emb = {k: v for k, v in by[(s, kind)].items() if k[0].startswith("embree")}
            if not gpu:
                continue
            (st, kn), best = max(gpu.items(), key=lambda kv: kv[1])
            tb = anchors.get((s, kind))
            eb = max(emb.values()) if emb else None
            goal_t = 1.25 if kind == "primary" else 1.5
            goal_e = 100 if kind == "primary" else 50
            print(f"| {s} | {kind} | {kn} ({st}) | {best:,.0f} | {tb:,.0f} | {best / tb:.2f} | {goal_t} |"
                  if tb else f"| {s} | {kind} | {kn} ({st}) | {best:,.0f} | – | – | {goal_t} |", end="")
            print(f" {eb:,.0f} | {best / eb:.0f} | {goal_e} |" if eb else " – | – | – |")

    for kind in ("primary", "diffuse"):
        print(f"\n**{kind} rays, Mrays/s** (structure / kernel down, scene across)\n")
        print("| structure | kernel | " + " | ".join(SCENES) + " |")
        print("|---|---|" + "---:|" * len(SCENES))
        for c in cols:
            cells = [by[(s, kind)].get(c) for s in SCENES]
            print(f"| {c[0]} | {c[1]} | " + " | ".join(f"{x:,.0f}" if x else "–" for x in cells) + " |")

    # Coherence report: primary -> diffuse slowdown per kernel, work per ray.
    print("\n**Coherence report** (after the TRaX argument that single-ray traversal loses little on "
          "incoherent rays): Mrays/s on primary ÷ on diffuse, same kernel and structure; work per ray "
          "counted by the structure's own traversal on the CPU (binned BVH and kd-tree; the SBVH's are alike)\n")
    print("| scene | structure | kernel | primary ÷ diffuse | nodes/ray primary, diffuse | tri tests/ray primary, diffuse |")
    print("|---|---|---|---:|---|---|")
    work = {}
    for r in ok:
        if "work_per_ray" in r:
            work[(r["scene"], ray_kind(r), r["structure"], r["kernel"])] = r["work_per_ray"]
    for s in SCENES:
        for c in cols:
            if c[1] not in COHERENCE_KERNELS or c[0] == "bvh2/sbvh":
                continue
            p, d = by[(s, "primary")].get(c), by[(s, "diffuse")].get(c)
            wp, wd = work.get((s, "primary") + c), work.get((s, "diffuse") + c)
            if p and d and wp and wd:
                print(f"| {s} | {c[0]} | {c[1]} | {p / d:.1f} | {wp['nodes']:.1f}, {wd['nodes']:.1f} | "
                      f"{wp['tri_tests']:.1f}, {wd['tri_tests']:.1f} |")
    if failed:
        print("\n**FAILED (real mismatches against Embree, not timed)**\n")
        for r in failed:
            print(f"- {r['scene']} {ray_kind(r)} {r['structure']} {r['kernel']}: {r['check']['mismatches']} mismatches")


if __name__ == "__main__":
    sys.exit(main())
