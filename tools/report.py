#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""`bvhlab report`: merges bvhlab result files (JSON lines) and writes Markdown tables and plots.

    bvhlab report RESULTS... --out DIR [--baseline LABEL] [--compare A B] [--title TEXT]

What comes out in DIR:
  report.md       tables: Mrays/s per scene, ray type and tracer (median over repetitions, with
                  the run-to-run spread), speed-up against --baseline, verification (mismatches,
                  ties), builds (time, Mtris/s, SAH), renders (Mrays/s, paths per bounce);
                  with --compare, the ratio of B to A per matching record
  *.png           the plots (matplotlib): Mrays/s per tracer and scene, speed-up, build time
                  against triangles, active paths per bounce, B against A
  summary.json    the aggregated figures, machine-readable

A tracer's label is "device kernel" and, when one result set has several structures for the
same kernel, the structure's configuration too. Records are grouped by everything that names
them (scene, scene hash, ray type, structure configuration, device, kernel, GPU, commit), so that
repetitions (a sweep's "repetitions", or files given twice) become one median with its spread.
"""
import argparse
import collections
import json
import math
import os
import statistics
import sys


def fail(msg):
    print(f"bvhlab: error: {msg}", file=sys.stderr)
    sys.exit(1)


def load(paths):
    """Every JSON object line of every file; a line that is not one is named and skipped."""
    records = []
    for p in paths:
        if not os.path.exists(p):
            fail(f"'{p}' does not exist")
        if os.path.isdir(p):
            fail(f"'{p}' is a folder (give result files)")
        with open(p, encoding="utf-8", errors="replace") as f:
            for n, line in enumerate(f, 1):
                line = line.strip()
                if not line:
                    continue
                try:
                    j = json.loads(line)
                except ValueError:
                    print(f"[bvhlab] warning: '{p}': line {n} is not JSON; skipped", file=sys.stderr)
                    continue
                if isinstance(j, dict) and "record" in j:
                    j["_file"] = p
                    records.append(j)
    if not records:
        fail("the result files hold no bvhlab record")
    return records


def tracer_label(r):
    dev = r.get("device") or ""
    kernel = r.get("kernel") or ""
    return f"{dev} {kernel}".strip()


def group_key(r):
    """What makes two records repetitions of one measurement."""
    return (r.get("record"), r.get("scene"), r.get("scene_hash"), r.get("ray_type"), r.get("structure"),
            r.get("config"), r.get("device"), r.get("kernel"), r.get("block_size"), r.get("gpu"), r.get("commit"),
            json.dumps(r.get("protocol"), sort_keys=True), r.get("ray_file_hash"))


def aggregate(records, field):
    """Median, spread ((max - min) / median) and count of `field` per group."""
    groups = collections.OrderedDict()
    for r in records:
        v = r.get(field)
        if isinstance(v, (int, float)) and math.isfinite(v):
            groups.setdefault(group_key(r), []).append((r, float(v)))
    out = []
    for key, rows in groups.items():
        vals = [v for _, v in rows]
        med = statistics.median(vals)
        out.append({
            "record": rows[0][0],
            "median": med,
            "min": min(vals),
            "max": max(vals),
            "n": len(vals),
            "spread": (max(vals) - min(vals)) / med if med and len(vals) > 1 else None,
        })
    return out


def labels_for(aggs):
    """Tracer labels, with what tells them apart where one label would name several: the parts of
    the structure configuration that differ (the builder and, say, leaf=1..2), then the commit."""
    configs = collections.defaultdict(set)
    for a in aggs:
        configs[tracer_label(a["record"])].add(a["record"].get("config") or "")
    for a in aggs:
        r = a["record"]
        base = tracer_label(r)
        a["label"] = base
        if len(configs[base]) > 1:
            # The builder (a configuration's first word), and the settings that differ between
            # configurations of that builder.
            toks = (r.get("config") or "").split()
            same_builder = [c.split() for c in configs[base] if c.split()[:1] == toks[:1]]
            common = set.intersection(*(set(t) for t in same_builder))
            a["label"] = f"{base} [{' '.join(t for i, t in enumerate(toks) if i == 0 or t not in common)}]"
    seen = collections.Counter((a["record"].get("scene"), a["record"].get("ray_type"), a["label"]) for a in aggs)
    clash = {lab for (_, _, lab), n in seen.items() if n > 1}
    for a in aggs:
        if a["label"] in clash:
            a["label"] += f" @{str(a['record'].get('commit', '?'))[:7]}"
    return aggs


def fmt(v, digits=1):
    if v is None:
        return ""
    if abs(v) >= 100:
        return f"{v:,.0f}"
    return f"{v:.{digits}f}" if abs(v) >= 1 else f"{v:.3g}"


def md_table(header, rows):
    """A Markdown table; columns whose cells are all numbers are right-aligned."""
    def numeric(i):
        cells = [str(r[i]) for r in rows if i < len(r) and str(r[i])]
        return bool(cells) and all(c[0].isdigit() or c[0] in "-+." for c in cells)
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---:" if numeric(i) else "---" for i in range(len(header))) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def machines(records):
    seen = collections.OrderedDict()
    for r in records:
        gpu = r.get("gpu")
        m = f"{gpu} (driver {r.get('driver')})" if gpu else r.get("machine", "unknown machine")
        seen[m] = True
    return list(seen)


def write_figure(plt, fig, out, name):
    """A PNG written whole or not at all: into a temporary beside it, then renamed."""
    tmp = os.path.join(out, f".{name}.tmp")
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    os.replace(tmp, os.path.join(out, name))


def save_plot(plt, fig, ax, out, name, xlabel, ylabel, alt):
    """Labels, legend and file of a plot; returns its Markdown lines."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize="small")
    fig.tight_layout()
    write_figure(plt, fig, out, name)
    return [f"![{alt}]({name})", ""]


def bench_section(records, out, baseline, plt):
    bench = [r for r in records if r["record"] == "bench" and r.get("status", "ok") == "ok"]
    if not bench:
        return [], {}
    aggs = labels_for(aggregate(bench, "mrays_per_s"))
    lines = ["## Traversal: Mrays/s", ""]
    summary = {"bench": []}
    types = list(collections.OrderedDict((a["record"].get("ray_type"), 0) for a in aggs))
    labels = list(collections.OrderedDict((a["label"], 0) for a in aggs))
    scenes = list(collections.OrderedDict((a["record"].get("scene"), 0) for a in aggs))
    spreads = [a["spread"] for a in aggs if a["spread"] is not None]
    if spreads:
        lines.append(f"Median over repetitions; run-to-run spread (max - min over the median) is "
                     f"{100 * statistics.median(spreads):.1f}% at the median and {100 * max(spreads):.1f}% at most "
                     f"over {len(spreads)} measurements with repetitions.")
    else:
        lines.append("One run per measurement (no repetitions: the run-to-run spread is not known).")
    lines.append("")
    cell = {(a["record"].get("scene"), a["record"].get("ray_type"), a["label"]): a for a in aggs}
    if baseline and baseline not in labels:
        # A part of one label is enough ("binned leaf=1..8", or a kernel's name).
        matches = [lab for lab in labels if baseline in lab]
        if len(matches) != 1:
            fail(f"--baseline '{baseline}' {'names several tracers' if matches else 'is not a tracer'} of these "
                 f"results (tracers: {'; '.join(matches or labels)})")
        baseline = matches[0]
    # The headline: the fastest tracer of each scene and ray type.
    best_rows = []
    for t in types:
        for s in scenes:
            here = [a for (sc, ty, _), a in cell.items() if sc == s and ty == t]
            if not here:
                continue
            b = max(here, key=lambda a: a["median"])
            row = [s, t, b["label"], fmt(b["median"]) + (f" ±{100 * b['spread'] / 2:.1f}%" if b["spread"] else "")]
            if baseline:
                base = cell.get((s, t, baseline))
                row += [fmt(base["median"]) if base else "", f"{b['median'] / base['median']:.2f}×" if base else ""]
            best_rows.append(row)
    header = ["scene", "rays", "fastest tracer", "Mrays/s"] + ([baseline, "speed-up"] if baseline else [])
    headline = ["### Fastest tracer per scene and ray type", "", md_table(header, best_rows), ""]
    lines += headline
    summary["_headline"] = [lines[2]] + [""] + headline
    for t in types:
        lines += [f"### {t} rays", ""]
        rows = []
        for s in scenes:
            row = [s]
            for lab in labels:
                a = cell.get((s, t, lab))
                row.append(fmt(a["median"]) + (f" ±{100 * a['spread'] / 2:.1f}%" if a and a["spread"] else "") if a else "")
            rows.append(row)
        lines += [md_table(["scene"] + labels, rows), ""]
    for a in aggs:
        r = a["record"]
        summary["bench"].append({"scene": r.get("scene"), "ray_type": r.get("ray_type"), "tracer": a["label"],
                                 "mrays_per_s": a["median"], "min": a["min"], "max": a["max"], "n": a["n"],
                                 "config": r.get("config"), "commit": r.get("commit"), "gpu": r.get("gpu")})
    if plt:
        for t in types:
            fig, ax = plt.subplots(figsize=(min(12, max(5, 0.22 * len(scenes) * max(1, len(labels)))) + 4, 4.5))
            width = 0.8 / max(1, len(labels))
            for i, lab in enumerate(labels):
                vals = [cell[(s, t, lab)]["median"] if (s, t, lab) in cell else 0 for s in scenes]
                ax.bar([x + i * width for x in range(len(scenes))], vals, width, label=lab)
            ax.set_xticks([x + width * (len(labels) - 1) / 2 for x in range(len(scenes))])
            ax.set_xticklabels(scenes, rotation=20, ha="right")
            ax.set_ylabel("Mrays/s")
            ax.set_title(f"{t} rays")
            ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
            fig.tight_layout()
            name = f"mrays-{t}.png"
            write_figure(plt, fig, out, name)
            lines += [f"![Mrays/s, {t} rays]({name})", ""]
            summary.setdefault("_plots", []).append((f"Mrays/s, {t} rays", name))
    if baseline:
        lines += [f"### Speed-up against {baseline}", ""]
        others = [lab for lab in labels if lab != baseline]
        rows = []
        speedups = collections.defaultdict(list)
        for t in types:
            for s in scenes:
                b = cell.get((s, t, baseline))
                if not b:
                    continue
                row = [s, t]
                for lab in others:
                    a = cell.get((s, t, lab))
                    x = a["median"] / b["median"] if a and b["median"] else None
                    if x:
                        speedups[lab].append((f"{s}\n{t}", x))
                    row.append(f"{x:.2f}×" if x else "")
                rows.append(row)
        lines += [md_table(["scene", "rays"] + others, rows), ""]
        summary["baseline"] = baseline
        if plt and speedups:
            fig, ax = plt.subplots(figsize=(11, 4))
            for lab, pts in speedups.items():
                ax.plot(range(len(pts)), [x for _, x in pts], "o-", label=lab)
                ax.set_xticks(range(len(pts)))
                ax.set_xticklabels([n for n, _ in pts], fontsize="x-small", rotation=30, ha="right")
            ax.axhline(1.0, color="grey", lw=0.8)
            ax.set_ylabel("speed-up")
            ax.set_title(f"against {baseline}", fontsize="small")
            ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
            fig.tight_layout()
            write_figure(plt, fig, out, "speedup.png")
            lines += ["![speed-up](speedup.png)", ""]
    return lines, summary


def verify_section(records):
    ver = [r for r in records if r["record"] == "verify"]
    if not ver:
        return [], {}
    rows, total = [], {"rays": 0, "mismatches": 0, "ties": 0}
    for r in ver:
        rows.append([r.get("scene"), r.get("ray_type"), r.get("structure"), tracer_label(r), f"{r.get('rays', 0):,}",
                     r.get("mismatches", 0), r.get("ties", 0)])
        for k in total:
            total[k] += int(r.get(k, 0) or 0)
    lines = ["## Verification against Embree", "",
             f"{total['rays']:,} rays, {total['mismatches']} real mismatches, {total['ties']} ties.", "",
             md_table(["scene", "rays", "structure", "tracer", "rays", "mismatches", "ties"], rows), ""]
    return lines, {"verify": total}


def build_section(records, out, plt):
    builds = [r for r in records if r["record"] == "build"]
    if not builds:
        return [], {}
    aggs = aggregate(builds, "build_ms")
    rows, pts = [], collections.defaultdict(list)
    for a in aggs:
        r = a["record"]
        gb = r.get("gpu_build") or {}
        ms = gb.get("median_ms", gb.get("total_ms")) if isinstance(gb, dict) and gb else None
        ms = ms if isinstance(ms, (int, float)) else a["median"]
        tris = r.get("triangles", 0)
        who = f"{r.get('builder', '')} ({r.get('build_device', 'cpu')})"
        rows.append([r.get("scene"), f"{tris:,}", who, fmt(ms, 2), fmt(tris / ms / 1e3 if ms else None),
                     fmt(r.get("sah")), fmt(r.get("epo"))])
        pts[who].append((tris, ms))
    lines = ["## Builds", "", md_table(["scene", "triangles", "builder", "ms", "Mtris/s", "SAH", "EPO"], rows), ""]
    if plt:
        fig, ax = plt.subplots(figsize=(6, 4))
        for who, p in sorted(pts.items()):
            p.sort()
            ax.loglog([t for t, _ in p], [m for _, m in p], "o-", label=who)
        lines += save_plot(plt, fig, ax, out, "build-time.png", "triangles", "build time (ms)",
                           "build time against triangles")
    return lines, {"builds": len(aggs)}


def render_section(records, out, plt):
    renders = [r for r in records if r["record"] == "render"]
    if not renders:
        return [], {}
    rows = []
    for r in renders:
        ms = (r.get("ms") or {}).get("total")
        rows.append([r.get("scene"), tracer_label(r), f"{r.get('width')}×{r.get('height')}", r.get("spp"),
                     fmt(r.get("mrays_per_s")), fmt(ms, 2)])
    lines = ["## Renders", "", md_table(["scene", "tracer", "image", "spp", "Mrays/s", "ms"], rows), ""]
    if plt and any(r.get("bounces") for r in renders):
        fig, ax = plt.subplots(figsize=(6, 4))
        for r in renders:
            b = r.get("bounces") or []
            if b:
                ax.semilogy(range(len(b)), [max(1, x.get("extension_rays", 0)) for x in b], "o-",
                            label=f"{r.get('scene')} {tracer_label(r)}")
        lines += save_plot(plt, fig, ax, out, "paths-per-bounce.png", "bounce", "active paths (extension rays)",
                           "active paths per bounce")
    return lines, {"renders": len(renders)}


def compare_section(a_recs, b_recs, names, out, plt):
    """B against A for records of the same measurement, whatever commit or machine made them."""
    def key(r):
        return (r.get("record"), r.get("scene"), r.get("ray_type"), r.get("structure"), r.get("config"),
                r.get("device"), r.get("kernel"))
    fields = {"bench": "mrays_per_s", "build": "build_ms", "render": "mrays_per_s"}
    med = []
    for recs in (a_recs, b_recs):
        m = collections.defaultdict(list)
        for r in recs:
            f = fields.get(r.get("record"))
            if f and isinstance(r.get(f), (int, float)):
                m[key(r)].append(r[f])
        med.append({k: statistics.median(v) for k, v in m.items()})
    common = [k for k in med[0] if k in med[1]]
    if not common:
        fail(f"--compare: no measurement is in both '{names[0]}' and '{names[1]}'")
    rows, ratios = [], []
    for k in common:
        x = med[1][k] / med[0][k] if med[0][k] else None
        label = " ".join(str(p) for p in (k[1], k[2], k[5], k[6]) if p)
        rows.append([k[0], label, fmt(med[0][k]), fmt(med[1][k]), f"{x:.3f}" if x else ""])
        if x:
            ratios.append((label, x))
    geo = math.exp(statistics.mean(math.log(x) for _, x in ratios)) if ratios else None
    lines = [f"## {names[1]} against {names[0]}", "",
             f"{len(common)} measurements in both; geometric mean of B/A: {geo:.3f}." if geo else "", "",
             md_table(["record", "measurement", "A", "B", "B/A"], rows), ""]
    if plt and ratios:
        fig, ax = plt.subplots(figsize=(8, max(3, 0.25 * len(ratios))))
        ax.barh(range(len(ratios)), [x for _, x in ratios])
        ax.set_yticks(range(len(ratios)))
        ax.set_yticklabels([n for n, _ in ratios], fontsize="x-small")
        ax.axvline(1.0, color="grey", lw=0.8)
        ax.set_xlabel("B / A")
        fig.tight_layout()
        write_figure(plt, fig, out, "compare.png")
        lines += ["![B against A](compare.png)", ""]
    return lines, {"compare": {"a": names[0], "b": names[1], "measurements": len(common), "geomean": geo}}


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, as every bvhlab error
        fail(f"{message} (see bvhlab report --help)")


def main(argv=None):
    ap = Parser(prog="bvhlab report", description=__doc__.split("\n\n")[0])
    ap.add_argument("results", nargs="*", help="result files (JSON lines from bvhlab --json or bvhlab sweep)")
    ap.add_argument("--out", required=True, help="folder for report.md, the plots and summary.json")
    ap.add_argument("--baseline", help="the tracer label that speed-ups are measured against (report.md lists them)")
    ap.add_argument("--compare", nargs=2, metavar=("A", "B"), help="two result files: B's figures against A's")
    ap.add_argument("--title", default="bvhlab results")
    ap.add_argument("--no-plots", action="store_true", help="tables only (no matplotlib needed)")
    ap.add_argument("--readme", metavar="FILE",
                    help="also write the headline (machines, spread, fastest tracer per scene, the plots) into FILE "
                         "between its '<!-- bvhlab-report:begin -->' and '<!-- bvhlab-report:end -->' lines")
    args = ap.parse_args(argv)
    if not args.results and not args.compare:
        fail("give result files, or --compare A B")
    inputs = [os.path.realpath(p) for p in args.results + (args.compare or [])]
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        fail(f"--out '{args.out}' is a file, not a folder")
    if os.path.realpath(args.out) in inputs:
        fail(f"--out '{args.out}' is one of the result files")
    plt = None
    if not args.no_plots:
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt  # noqa: F811
        except ImportError:
            fail("the plots need matplotlib (tools/install_deps.sh installs python3-matplotlib); "
                 "--no-plots writes the tables only")
    os.makedirs(args.out, exist_ok=True)
    lines = [f"# {args.title}", ""]
    summary = {}
    if args.results:
        records = load(args.results)
        commits = sorted({r.get("commit", "?") for r in records})
        lines += [f"{len(records)} records from {len(args.results)} file{'s' if len(args.results) > 1 else ''}; commits {', '.join(commits)}; "
                  f"machines: {'; '.join(machines(records))}.", ""]
        for part, s in (bench_section(records, args.out, args.baseline, plt), verify_section(records),
                        build_section(records, args.out, plt), render_section(records, args.out, plt)):
            lines += part
            summary.update(s)
    elif args.baseline:
        fail("--baseline applies to the result files' tables, and none were given")
    if args.compare:
        part, s = compare_section(load([args.compare[0]]), load([args.compare[1]]), args.compare, args.out, plt)
        lines += part
        summary.update(s)
    headline = summary.pop("_headline", None)
    plots = summary.pop("_plots", [])
    if args.readme:
        begin, end = "<!-- bvhlab-report:begin -->", "<!-- bvhlab-report:end -->"
        try:
            text = open(args.readme, encoding="utf-8").read()
        except OSError as e:
            fail(f"--readme '{args.readme}': {e.strerror}")
        if text.count(begin) != 1 or text.count(end) != 1 or text.index(begin) > text.index(end):
            fail(f"--readme '{args.readme}' needs one '{begin}' line and one '{end}' line after it")
        if not headline:
            fail("--readme: the result files hold no bench record to summarise")
        rel = os.path.relpath(os.path.realpath(args.out), os.path.dirname(os.path.realpath(args.readme)))
        block = [lines[2], ""] + headline + [f"![{alt}]({rel}/{name})" for alt, name in plots] + [""]
        generated = (f"<!-- generated by: bvhlab report {' '.join(args.results)} --out {args.out}"
                     f"{' --baseline ' + repr(args.baseline) if args.baseline else ''} --readme {args.readme} -->")
        text = text[:text.index(begin) + len(begin)] + "\n" + generated + "\n" + "\n".join(block) + text[text.index(end):]
        tmp = args.readme + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, args.readme)
    for name, text in (("report.md", "\n".join(lines) + "\n"), ("summary.json", json.dumps(summary, indent=1) + "\n")):
        tmp = os.path.join(args.out, f".{name}.tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, os.path.join(args.out, name))
    print(f"report: {os.path.join(args.out, 'report.md')}")


if __name__ == "__main__":
    main()
