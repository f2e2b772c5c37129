#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Device-only mutants against the GPU tests.

The CPU campaign (tools/mutate.py) cannot compile the device-only branches of the core's
host/device headers (`#if defined(__CUDA_ARCH__)` up to its `#else`: the GPU's loads of nodes,
triangles, rays and hits, and its bit intrinsics). This tool gives them the same treatment
against the GPU tests, in three steps, because the GPU is usually on another machine:

  build   universalmutator's mutants of those branches, a seeded sample: each in turn replaces
          its file in a CUDA build (--build-dir, configured by you), the target
          bvhlab_gpu_tests is rebuilt, and the binary is kept as OUT/mNN/bvhlab_gpu_tests (a
          mutant that does not compile is stillborn). The file is always restored.
          OUT/mutants.json lists the sample.
  run     on the GPU machine: each kept binary runs with --gtest_fail_fast in the current
          folder and environment; OUT/results.jsonl gets killed (a test failed, or it ran past
          --timeout) or survived (every test passed).
  report  OUT/report.md from both.

Example (docs/mutation.md):
  python3 tools/mutate_device.py build --build-dir build-devmut --sample 8 --seed 1 --out M
  (on the GPU machine) python3 tools/mutate_device.py run M
  python3 tools/mutate_device.py report M
"""

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mutate  # noqa: E402  (the CPU campaign's mutant generation and process handling)

# The headers whose device-only branches the GPU kernels compile.
DEVICE_FILES = ["traversal/device/cwbvh_traverse.h", "traversal/device/ray.h", "accel/layouts/cwbvh_node.h",
                "accel/core/bits.h", "accel/core/morton.h", "accel/core/vec3.h"]


def build_step(a, root):
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    gen = os.path.join(out, "generated")
    mutants = []
    for rel in a.files or DEVICE_FILES:
        mutants += mutate.make_mutants(root, rel, gen, device_only_code=True)
    equivalents = mutate.load_equivalents(os.path.join(root, "tests/mutation/equivalent.txt"))
    mutants = [m for m in mutants if (m["file"], m["original"], m["mutant"]) not in equivalents]
    if not mutants:
        mutate.die("no device-only mutants in the files given")
    rng = random.Random(a.seed)
    rng.shuffle(mutants)
    kept, tried = [], 0
    for m in mutants:
        if a.sample and len(kept) >= a.sample:
            break
        src = os.path.join(root, m["file"])
        backup = src + ".mutate-device-backup"
        shutil.copyfile(src, backup)

        def restore(*_):
            mutate.kill_running()
            if os.path.exists(backup):
                os.replace(backup, src)
            sys.exit(130)

        old = {s: signal.signal(s, restore) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            shutil.copyfile(m["path"], src)
            tried += 1
            rc, log = mutate.sh(["cmake", "--build", a.build_dir, "-j", str(a.jobs), "--target", "bvhlab_gpu_tests"],
                                None)
            status = "stillborn" if rc != 0 else "built"
            entry = {k: m[k] for k in ("file", "line", "original", "mutant")}
            entry["status"] = status
            if rc == 0:
                name = "m%02d" % len(kept)
                os.makedirs(os.path.join(out, name), exist_ok=True)
                shutil.copy2(os.path.join(a.build_dir, "tests", "bvhlab_gpu_tests"), os.path.join(out, name))
                entry["name"] = name
                kept.append(entry)
            print(f"[{len(kept)}/{a.sample or len(mutants)}] {status:9s} {m['file']}:{m['line']}  {m['mutant']}",
                  flush=True)
            with open(os.path.join(out, "mutants.json"), "w") as f:
                json.dump({"seed": a.seed, "sample": a.sample, "tried": tried, "mutants": kept}, f, indent=1)
        finally:
            os.replace(backup, src)
            for s, h in old.items():
                signal.signal(s, h)
    # The restored files built once more, so that the build folder holds the real code again.
    mutate.sh(["cmake", "--build", a.build_dir, "-j", str(a.jobs), "--target", "bvhlab_gpu_tests"], None)
    print(f"mutate_device: {len(kept)} built of {tried} tried; binaries in {out}/mNN/")
    return 0


def run_step(a):
    out = os.path.abspath(a.out)
    with open(os.path.join(out, "mutants.json")) as f:
        spec = json.load(f)
    with open(os.path.join(out, "results.jsonl"), "w") as res:
        for m in spec["mutants"]:
            exe = os.path.join(out, m["name"], "bvhlab_gpu_tests")
            t0 = time.time()
            rc, log = mutate.sh([exe, "--gtest_fail_fast", "--gtest_brief=1"], None, timeout=a.timeout)
            failed = [l.split("]", 1)[1].strip().split(" ")[0].rstrip(",") for l in log.splitlines()
                  if l.startswith("[  FAILED  ]")]
            status = "killed" if rc != 0 else "survived"
            r = dict(m, status=status, killed_by=(failed[0] if failed else ("timeout" if rc is None else "")),
                     seconds=round(time.time() - t0, 1))
            res.write(json.dumps(r) + "\n")
            res.flush()
            print(f"{status:9s} {m['file']}:{m['line']}  {m['mutant']}  {r['killed_by']}", flush=True)
    return 0


def report_step(a):
    out = os.path.abspath(a.out)
    with open(os.path.join(out, "mutants.json")) as f:
        spec = json.load(f)
    results = []
    if os.path.exists(os.path.join(out, "results.jsonl")):
        with open(os.path.join(out, "results.jsonl")) as f:
            results = [json.loads(l) for l in f if l.strip()]
    killed = sum(r["status"] == "killed" for r in results)
    survived = [r for r in results if r["status"] == "survived"]
    stillborn = spec["tried"] - len(spec["mutants"])
    lines = [f"# Device-only mutants against the GPU tests (seed {spec['seed']}, sample {spec['sample']})", "",
             f"{spec['tried']} tried, {stillborn} stillborn, {len(spec['mutants'])} built; of those run: "
             f"{killed} killed, {len(survived)} survived.", "",
             "| file:line | mutant | result | first failing test |", "|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r['file']}:{r['line']} | `{r['mutant'].replace('|', chr(92) + '|')}` | {r['status']} | "
                     f"{r.get('killed_by', '')} |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write(text)
    print(text)
    return 0


def main():
    ap = argparse.ArgumentParser(prog="tools/mutate_device.py", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="step", required=True)
    b = sub.add_parser("build", help="build the sample's GPU test binaries")
    b.add_argument("--build-dir", required=True, help="a CUDA build folder of this tree (configured)")
    b.add_argument("--files", action="append", default=[], help="files to mutate (default: the device headers)")
    b.add_argument("--sample", type=int, default=8, help="mutants that compile to keep (0: all)")
    b.add_argument("--seed", type=int, default=1)
    b.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    b.add_argument("--out", required=True)
    r = sub.add_parser("run", help="run the kept binaries here (the GPU machine)")
    r.add_argument("out")
    r.add_argument("--timeout", type=float, default=600, help="seconds a binary may take (past it: killed)")
    p = sub.add_parser("report", help="write OUT/report.md")
    p.add_argument("out")
    a = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if a.step == "build":
        a.files = [f for arg in a.files for f in arg.split(",") if f]
        if shutil.which("mutate") is None:
            mutate.die("universalmutator's `mutate` is not on PATH (tools/mutate.sh installs it in build-mutate/venv)")
        return build_step(a, root)
    return run_step(a) if a.step == "run" else report_step(a)


if __name__ == "__main__":
    sys.exit(main())
