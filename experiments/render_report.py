#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The renderer's experiment report (issue 19): turns one run of `tools/gpu_run.sh ... render`
into the README's renderer section, its plots and its images.

A run split over several calls (RENDER_DATA_SCENES=0 and a list of scenes) gives several folders:
they are read together, on one GPU and driver, one commit.

Each run folder holds:
  render.jsonl           one timed render per scene (RENDER_SPP), with its time per stage
  render_bench.jsonl     `bvhlab bench --rays` on the first wave's dumped rays of every bounce,
                         every BVH2 kernel and dynamic-cwbvh, each checked against Embree first
  render_switches.jsonl  every scene rendered through pixel centres: plain, material sorting,
                         the first-hit cache, both, and without compaction
  renders.tar.xz         the timed renders as PFM
  machine.txt            the GPU and driver

What comes out:
  - the overhead table: the whole render's Mrays/s against the extend kernel's own on the same
    bounce rays (goal >= 0.75), with the time per stage;
  - active paths per bounce with and without compaction, open and closed Cornell box;
  - time per sample with material sorting and the first-hit cache on and off;
  - Mrays/s per bounce for each kernel (the coherence report on real path-tracer rays);
  - PNG plots of the last three (matplotlib) and a PNG contact sheet of the renders.

Usage:
  experiments/render_report.py RUN_DIR... [--readme docs/results.md] [--figures experiments/results]
                               [--tag NAME]
Without --readme the section goes to stdout. With it, the text between the README's
'<!-- render-report:begin -->' and '<!-- render-report:end -->' lines is replaced.
Needs numpy and matplotlib (Debian: python3-matplotlib)."""
import argparse
import json
import os
import re
import sys
import tarfile
from collections import defaultdict

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BEGIN = "<!-- render-report:begin -->"
END = "<!-- render-report:end -->"

# Scene order and labels in tables and plots.
LABELS = {
    "cornell-box": "Cornell box",
    "cornell-closed": "Cornell box, closed",
    "glass-mirror": "glass-and-mirror",
}
# The kernels the coherence plot draws (every kernel is in the table's best-of).
PLOT_KERNELS = ["plain", "while-while-fma", "speculative-fma", "dynamic-while-while-fma", "dynamic-speculative-fma",
                "dynamic-cwbvh"]


def load_jsonl(path):
    if not os.path.exists(path):
        return []
    return [json.loads(line) for line in open(path) if line.strip()]


def label(scene):
    return LABELS.get(scene, scene)


def bench_key(record):
    """(folder stem of the render, kind, bounce) from .../render-<stem>/<kind>-bounce<N>.rays."""
    path = record["ray_file"]
    stem = os.path.basename(os.path.dirname(path)).removeprefix("render-")
    m = re.match(r"(extension|shadow)-bounce(\d+)\.rays$", os.path.basename(path))
    return stem, m.group(1), int(m.group(2))


def render_stem(record):
    return os.path.basename(record["out"]).removesuffix(".pfm")


def ms_per_sample(r):
    ms = r["ms"]
    return (ms["total"] - ms.get("setup", 0.0)) / r["spp"]


def read_pfm(data):
    """A PFM file's bytes as an (h, w, 3) float array, top row first."""
    tokens, pos = [], 0
    while len(tokens) < 4:  # "PF" or "Pf", width, height, scale (negative: little-endian)
        end = data.index(b"\n", pos)
        tokens.extend(data[pos:end].split())
        pos = end + 1
    kind, w, h, scale = tokens[0], int(tokens[1]), int(tokens[2]), float(tokens[3])
    channels = 3 if kind == b"PF" else 1
    img = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=w * h * channels, offset=pos)
    img = img.reshape(h, w, channels)[::-1]  # PFM rows run bottom to top
    return np.repeat(img, 3, axis=2) if channels == 1 else img


def to_srgb(img):
    x = np.clip(img, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def machine(run_dir):
    path = os.path.join(run_dir, "machine.txt")
    if not os.path.exists(path):
        return "unknown GPU"
    lines = open(path).read().splitlines()
    gpu = lines[1].split(",") if len(lines) > 1 else ["unknown GPU"]
    return f"{gpu[0].strip()}, driver {gpu[1].strip()}" if len(gpu) > 1 else gpu[0]


def load_runs(run_dirs, name):
    """The JSON lines of file `name` in every run folder, in order."""
    return [r for d in run_dirs for r in load_jsonl(os.path.join(d, name))]


class Report:
    def __init__(self, run_dirs, figures, tag, link_base="."):
        self.run_dirs = run_dirs
        self.link_base = link_base
        self.figures = figures
        self.renders = load_runs(run_dirs, "render.jsonl")
        self.benches = load_runs(run_dirs, "render_bench.jsonl")
        self.switches = load_runs(run_dirs, "render_switches.jsonl")
        if not self.renders:
            sys.exit(f"render_report.py: {', '.join(run_dirs)} have no render.jsonl")
        machines = {machine(d) for d in run_dirs}
        commits = {r.get("commit", "unknown") for r in self.renders}
        if len(machines) > 1 or len(commits) > 1:
            sys.exit(f"render_report.py: the run folders differ in GPU or commit: {sorted(machines | commits)}")
        self.machine = machines.pop()
        self.commit = self.renders[0].get("commit", "unknown")
        self.tag = tag or f"{self.commit[:7]}-h100"
        self.kernel = self.renders[0]["kernel"]
        self.scenes = [r["scene"] for r in self.renders]
        self.out = []

    def figure_path(self, what):
        return os.path.join(self.figures, f"render-{self.tag}-{what}.png")

    def link(self, what):
        """The figure's path as the Markdown that shows it sees it (relative to its folder)."""
        return os.path.relpath(self.figure_path(what), self.link_base)

    def md(self, line=""):
        self.out.append(line)

    # The overhead table -------------------------------------------------------------------
    def overhead(self):
        ms_k = defaultdict(float)
        rays_k = defaultdict(int)
        bad = defaultdict(int)
        for b in self.benches:
            if b["kernel"] != self.kernel:
                continue
            stem, _, _ = bench_key(b)
            ms_k[stem] += b["median_ms"]
            rays_k[stem] += b["rays"]
            bad[stem] += b.get("check", {}).get("mismatches", 0)
        self.md("| scene | triangles | spp | render Mrays/s | kernel Mrays/s, same rays | ratio (goal ≥ 0.75) "
                "| ms per sample | ms: extend / shade+compact / shadow / generate / accumulate / set-up |")
        self.md("|---|---:|---:|---:|---:|---:|---:|---|")
        for r in self.renders:
            stem = render_stem(r)
            k = rays_k[stem] / (ms_k[stem] * 1e3) if ms_k[stem] else float("nan")
            ratio = r["mrays_per_s"] / k
            ms = r["ms"]
            bold = "**" if ratio >= 0.75 else ""
            self.md(f"| {label(r['scene'])} | {r['triangles']:,} | {r['spp']} | {r['mrays_per_s']:,.0f} | {k:,.0f} | "
                    f"{bold}{ratio:.2f}{bold} | {ms_per_sample(r):.2f} | {ms['extend']:.0f} / {ms['shade']:.0f} / "
                    f"{ms['shadow']:.0f} / {ms['generate']:.0f} / {ms['accumulate']:.0f} / {ms.get('setup', 0):.0f} |")
        self.mismatches = sum(bad.values())
        self.checked = sum(1 for b in self.benches)

    # Compaction ---------------------------------------------------------------------------
    def compaction(self):
        rows = {}
        times = defaultdict(list)
        for r in self.switches:
            if r["scene"] not in ("cornell-box", "cornell-closed") or r["sort_materials"] or r["first_hit_cache"]:
                continue
            paths = r["width"] * r["height"] * r["spp"]
            key = (r["scene"], r["compaction"])
            times[key].append(ms_per_sample(r))
            rows[key] = (
                [b["queue_entries"] / paths for b in r["bounces"]],
                [b["extension_rays"] / paths for b in r["bounces"]],
                float(np.median(times[key])),
            )
        if not rows:
            return
        depth = max(len(v[0]) for v in rows.values())
        self.md("| box | compaction | paths launched per bounce, per camera path (bounce 0, 1, 2, ...) "
                "| live paths | ms per sample |")
        self.md("|---|---|---|---|---:|")
        for (scene, comp), (queue, live, ms) in sorted(rows.items(), key=lambda kv: (kv[0][0], not kv[0][1])):
            self.md(f"| {'open' if scene == 'cornell-box' else 'closed'} | {'on' if comp else 'off'} | "
                    f"{', '.join(f'{x:.2f}' for x in queue)} | {', '.join(f'{x:.2f}' for x in live)} | {ms:.2f} |")
        fig, ax = plt.subplots(figsize=(6.4, 3.6))
        for (scene, comp), (queue, _, _) in sorted(rows.items()):
            style = "-" if comp else "--"
            colour = "tab:blue" if scene == "cornell-box" else "tab:red"
            box = "open" if scene == "cornell-box" else "closed"
            ax.plot(range(len(queue)), queue, style, color=colour, marker="o",
                    label=f"{box} box, compaction {'on' if comp else 'off'}")
        ax.set_xlabel("bounce")
        ax.set_ylabel("paths launched / camera paths")
        ax.set_xticks(range(depth))
        ax.set_ylim(0, 1.05)
        ax.set_title("Active paths per bounce (Cornell box, 640x480)")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(self.figure_path("paths"), dpi=110)
        plt.close(fig)

    # Sorting and the first-hit cache ------------------------------------------------------
    def switches_table(self):
        runs = defaultdict(lambda: defaultdict(list))
        for r in self.switches:
            if not r["compaction"]:
                name = "no compaction"
            else:
                name = {(False, False): "plain", (True, False): "sorted", (False, True): "cache",
                        (True, True): "sorted + cache"}[(r["sort_materials"], r["first_hit_cache"])]
            runs[r["scene"]][name].append(ms_per_sample(r))
        by = {scene: {name: float(np.median(v)) for name, v in names.items()} for scene, names in runs.items()}
        self.rounds = max((len(v) for names in runs.values() for v in names.values()), default=0)
        if not by:
            return
        cols = ["plain", "sorted", "cache", "sorted + cache", "no compaction"]
        self.md("| scene | " + " | ".join(cols) + " |")
        self.md("|---|" + "---:|" * len(cols))
        for scene in self.scenes:
            v = by.get(scene, {})
            base = v.get("plain")
            cells = []
            for c in cols:
                if c not in v:
                    cells.append("–")
                elif c == "plain":
                    cells.append(f"{v[c]:.2f}")
                else:
                    cells.append(f"{v[c]:.2f} ({v[c] / base - 1:+.0%})")
            self.md(f"| {label(scene)} | " + " | ".join(cells) + " |")
        fig, ax = plt.subplots(figsize=(8, 3.6))
        width = 0.16
        scenes = [s for s in self.scenes if s in by]
        for i, c in enumerate(cols):
            ys = [by[s].get(c, 0) / by[s]["plain"] for s in scenes]
            ax.bar(np.arange(len(scenes)) + (i - 2) * width, ys, width, label=c)
        ax.axhline(1.0, color="black", linewidth=0.8)
        ax.set_xticks(np.arange(len(scenes)))
        ax.set_xticklabels([label(s) for s in scenes], fontsize=8, rotation=15)
        ax.set_ylabel("time per sample / plain")
        ax.set_title("Material sorting, first-hit cache and compaction (pixel centres, 640x480)")
        ax.legend(fontsize=7, ncol=5)
        fig.tight_layout()
        fig.savefig(self.figure_path("switches"), dpi=110)
        plt.close(fig)

    # Coherence: Mrays/s per bounce per kernel -------------------------------------------
    def coherence(self):
        stems = {render_stem(r): r["scene"] for r in self.renders}
        rate = defaultdict(dict)  # (scene, kind, bounce) -> kernel -> Mrays/s
        for b in self.benches:
            stem, kind, bounce = bench_key(b)
            rate[(stems.get(stem, stem), kind, bounce)][b["kernel"]] = b["mrays_per_s"]
        if not rate:
            return
        self.md("| scene | rays | bounce 0 | bounce 1 | bounce 2 | bounce 3 | best kernel, bounces 1+ |")
        self.md("|---|---|---:|---:|---:|---:|---|")
        for scene in self.scenes:
            for kind in ("extension", "shadow"):
                cells = []
                wins = defaultdict(int)
                for bounce in range(4):
                    k = rate.get((scene, kind, bounce))
                    if not k:
                        cells.append("–")
                        continue
                    best = max(k, key=k.get)
                    mine = k.get(self.kernel, float("nan"))
                    cells.append(f"{mine:,.0f} ({k[best]:,.0f})")
                for (s, kd, bounce), k in rate.items():
                    if s == scene and kd == kind and bounce >= 1:
                        wins[max(k, key=k.get)] += 1
                top = max(wins, key=wins.get) if wins else "–"
                self.md(f"| {label(scene)} | {kind} | " + " | ".join(cells) + f" | {top} |")
        n = len(self.scenes)
        cols = 4
        rows = (n + cols - 1) // cols
        fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False)
        for ax, scene in zip(axes.flat, self.scenes):
            for kernel in PLOT_KERNELS:
                pts = sorted((bounce, k[kernel]) for (s, kd, bounce), k in rate.items()
                             if s == scene and kd == "extension" and kernel in k)
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=".", label=kernel)
            ax.set_title(label(scene), fontsize=9)
            ax.set_xlabel("bounce", fontsize=8)
            ax.set_ylabel("Mrays/s (extension rays)", fontsize=8)
            ax.set_ylim(bottom=0)
            ax.tick_params(labelsize=7)
        for ax in list(axes.flat)[n:]:
            ax.axis("off")
        handles, names = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, names, loc="lower right", fontsize=8)
        fig.suptitle("Kernels on the path tracer's own rays, per bounce (first wave, 6 spp)")
        fig.tight_layout()
        fig.savefig(self.figure_path("coherence"), dpi=100)
        plt.close(fig)

    # Renders ------------------------------------------------------------------------------
    def images(self):
        paths = [os.path.join(d, "renders.tar.xz") for d in self.run_dirs]
        paths = [p for p in paths if os.path.exists(p)]
        if not paths:
            return False
        imgs = {}
        for path in paths:
            with tarfile.open(path) as tar:
                for m in tar.getmembers():
                    name = os.path.basename(m.name)
                    if name.endswith(".pfm") and not name.startswith("sanitized"):
                        imgs[name.removesuffix(".pfm")] = read_pfm(tar.extractfile(m).read())
        order = [render_stem(r) for r in self.renders if render_stem(r) in imgs]
        names = {render_stem(r): label(r["scene"]) for r in self.renders}
        cols = 4
        rows = (len(order) + cols - 1) // cols
        fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False)
        for ax, stem in zip(axes.flat, order):
            ax.imshow(to_srgb(imgs[stem]))
            ax.set_title(names[stem], fontsize=9)
            ax.axis("off")
        for ax in list(axes.flat)[len(order):]:
            ax.axis("off")
        fig.tight_layout()
        fig.savefig(self.figure_path("images"), dpi=100)
        plt.close(fig)
        return True

    def build(self):
        r0 = self.renders[0]
        calls = f", in {len(self.run_dirs)} calls" if len(self.run_dirs) > 1 else ""
        self.md(f"Generated by `experiments/render_report.py` from one run of `tools/gpu_run.sh ... render`{calls} at "
                f"`{self.commit}` on {self.machine}: 640×480, max depth 8, Russian roulette from bounce "
                f"{r0['rr_depth']}, MIS, `{self.kernel}` on a binned BVH.")
        self.md()
        if self.images():
            self.md(f"![The renders]({self.link('images')})")
            self.md()
        self.md("**Overhead.** *Render Mrays/s* is every ray of the render over its wall time; the *kernel* figure "
                "is the same kernel in `bvhlab bench` on the render's own first-wave rays of every bounce (dumped "
                "with `--dump-rays`), so the ratio is what shading, compaction and the other stages cost on top of "
                "tracing.")
        self.md()
        self.overhead()
        self.md()
        self.md(f"Every dumped ray set was checked against Embree before timing: {self.checked} records, "
                f"{self.mismatches} real mismatches.")
        self.md()
        self.md("**Compaction.** Paths the extend stage is launched for, per camera path, with the dead paths "
                "compacted away or left in the queues (`--no-compaction`); the open box loses paths to the "
                "black background at every bounce, the closed one only to Russian roulette (from bounce "
                f"{r0['rr_depth']}) and the depth limit.")
        self.md()
        self.compaction()
        self.md()
        self.md(f"![Active paths per bounce]({self.link('paths')})")
        self.md()
        self.md("**Material sorting and the first-hit cache.** Milliseconds per sample of 640×480 (set-up "
                "excluded), every variant through pixel centres so that the cache (which needs repeating camera "
                "rays) compares like with like; the median of the rounds, interleaved; in brackets the change "
                "against plain.")
        self.md()
        self.switches_table()
        self.md()
        self.md(f"({self.rounds} rounds of {self.switches[0]['spp'] if self.switches else 0} spp each.)")
        self.md()
        self.md(f"![Sorting, caching and compaction]({self.link('switches')})")
        self.md()
        bvh2 = len({b["kernel"] for b in self.benches if b.get("layout", "bvh2") == "bvh2"})
        self.md(f"**Kernels per bounce.** Mrays/s of `{self.kernel}` on each bounce's rays, and in brackets the "
                f"best of the {bvh2} BVH2 kernels and `dynamic-cwbvh` on the same rays; the last column names the "
                "kernel that wins most bounces after the camera rays.")
        self.md()
        self.coherence()
        self.md()
        self.md(f"![Mrays/s per bounce and kernel]({self.link('coherence')})")
        return "\n".join(self.out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dirs", nargs="+", metavar="run_dir")
    ap.add_argument("--readme", help="README to update between the render-report markers")
    ap.add_argument("--figures", default="experiments/results", help="folder for the PNG figures")
    ap.add_argument("--tag", help="name part of the figures (default: COMMIT-h100)")
    args = ap.parse_args()
    os.makedirs(args.figures, exist_ok=True)
    link_base = os.path.dirname(os.path.abspath(args.readme)) if args.readme else os.getcwd()
    text = Report(args.run_dirs, args.figures, args.tag, link_base).build()
    if not args.readme:
        sys.stdout.write(text)
        return
    readme = open(args.readme).read()
    if BEGIN not in readme or END not in readme:
        sys.exit(f"render_report.py: {args.readme} has no '{BEGIN}' ... '{END}' section")
    head, rest = readme.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(args.readme, "w") as f:
        f.write(head + BEGIN + "\n" + text + END + tail)


if __name__ == "__main__":
    main()
