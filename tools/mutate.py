#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Mutation campaign over bvhlab's core sources (run through tools/mutate.sh).

universalmutator (PyPI) writes the mutants: one-line changes of operators, constants,
conditions and statements. This driver runs them, because universalmutator's own runner
(analyze_mutants) counts a mutant that does not compile as killed: here such a mutant is
"stillborn" and counts for nothing. For each mutant, one at a time: the mutant replaces its
source file in a CPU-only Release build (build-mutate/), an incremental build runs, then the
CPU tests (ctest -LE gpu) until the first failure; the original file is always restored.
A mutant is killed when a test fails or the tests run past the time limit (a hang), and
survives when every test passes. Survivors that cannot change behaviour are listed, with the
reason, in tests/mutation/equivalent.txt and are not run.

The report (Markdown and JSON) gives the score per file, killed / (killed + survived), and
every survivor by file and line. docs/mutation.md tells how to read and act on it.
"""

import argparse
import datetime
import fcntl
import hashlib
import difflib
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

CORE_DIRS = ["accel/core", "accel/builders", "accel/builders/kd", "accel/layouts", "traversal/reference",
             "traversal/device", "traversal/oracle"]
# The triangle checks and the scene hash, which every builder and the oracle rely on.
CORE_FILES = ["scene/mesh.h", "scene/mesh.cpp"]
# .cuh files hold device-only code: a CPU-only build does not compile them.
EXTENSIONS = (".h", ".cpp")


def die(msg, code=2):
    print(f"mutate: {msg}", file=sys.stderr)
    sys.exit(code)


RUNNING = []  # the child process group in flight, killed before a file is restored


def kill_running():
    for p in RUNNING:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()
    RUNNING.clear()


def sh(cmd, cwd, timeout=None, env=None):
    """Runs cmd in its own process group; returns (returncode or None on timeout, output). On a
    timeout the whole group is killed (a build or test left running would write objects of a
    mutant after its file is restored, and make would keep them)."""
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                         start_new_session=True)
    RUNNING.append(p)
    try:
        out, _ = p.communicate(timeout=timeout)
        return p.returncode, out
    except subprocess.TimeoutExpired:
        kill_running()
        return None, ""
    finally:
        if p in RUNNING:
            RUNNING.remove(p)


def core_files(root):
    files = []
    for d in CORE_DIRS:
        for name in sorted(os.listdir(os.path.join(root, d))):
            if name.endswith(EXTENSIONS):
                files.append(f"{d}/{name}")
    return files + CORE_FILES


def changed_files(root, rev):
    rc, out = sh(["git", "diff", "--name-only", rev, "--"], root)
    if rc != 0:
        die(f"--changed {rev}: git diff failed: {out.strip().splitlines()[-1] if out.strip() else rc}")
    core = set(core_files(root))
    return [f for f in out.split() if f in core]


def load_equivalents(path):
    """tests/mutation/equivalent.txt: file<TAB>original line<TAB>mutated line<TAB>reason."""
    eq = {}
    if not os.path.exists(path):
        return eq
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip() or line.startswith("#"):
                continue
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 4 or not parts[3].strip():
                die(f"{path}:{n}: expected 4 tab-separated fields (file, original, mutant, reason)")
            eq[(parts[0], parts[1].strip(), parts[2].strip())] = parts[3].strip()
    return eq


def device_only_lines(lines):
    """0-based indices of the lines that only the device compiles: the branch of an
    `#if defined(__CUDA_ARCH__)` (or `#ifdef __CUDA_ARCH__`) up to its `#else` or `#endif`. A CPU
    campaign's build never sees them, so their mutants are left to the GPU tests."""
    out, stack = set(), []  # stack: for each open #if, whether it is the device-only branch
    for i, raw in enumerate(lines):
        t = raw.strip()
        if t.startswith("#if"):
            stack.append("__CUDA_ARCH__" in t and "!" not in t)
        elif t.startswith("#el"):
            if stack:
                stack[-1] = False
        elif t.startswith("#endif"):
            if stack:
                stack.pop()
        elif any(stack):
            out.add(i)
    return out


def mutator_input(src, tmp):
    """The file universalmutator reads for `src`: the file itself, or a copy with each `{-`
    written `{ -` (the same C++). universalmutator takes `{-` for the start of a Haskell block
    comment and mutates nothing after it until a `-}`: a brace initialiser such as `{-1, 0.0f}`
    left the rest of accel/core/aabb.h, binning.h, binned_sah.cpp and traversal/device/ray.h
    without mutants. Its mutants are then whole copies of that text, which compile the same."""
    with open(src) as f:
        text = f.read()
    if "{-" not in text:
        return src
    path = os.path.join(tmp, os.path.basename(src))
    with open(path, "w") as f:
        f.write(text.replace("{-", "{ -"))
    return path


def same_code(a, b):
    """Whether two lines differ only in spaces next to brackets, braces, commas or semicolons,
    which never change C++ (some of universalmutator's mutants move such a space: equivalent
    by construction, so they are not run)."""
    def norm(t):
        return re.sub(r"\s*([{}()\[\],;])\s*", r"\1", t.strip())
    return norm(a) == norm(b)


def compiler_hint(text):
    """Whether a line is only an unrolling hint (BVHLAB_UNROLL, `#pragma unroll`): dropping or
    changing it can move speed, never a result a test could see, so its mutants are not run."""
    return re.fullmatch(r"BVHLAB_UNROLL|_Pragma\(.*\)", text.strip()) is not None


def make_mutants(root, rel, out_dir, device_only_code=False):
    """Mutants of one file as dicts: file, path, line, original, mutant (texts stripped): those
    of the code every build compiles, or with device_only_code those of the device-only
    branches alone (tools/mutate_device.py)."""
    src = os.path.join(root, rel)
    d = os.path.join(out_dir, rel.replace("/", "__"))
    os.makedirs(d, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:  # universalmutator leaves files in its cwd
        read = mutator_input(src, tmp)
        rc, out = sh(["mutate", read, "cpp", "--noCheck", "--mutantDir", d], tmp)
        with open(read) as f:
            original = f.read().splitlines()
    if rc != 0:
        die(f"universalmutator failed on {rel}: {out.strip()[-300:]}")
    device_only = device_only_lines(original)
    mutants = []
    for name in sorted(os.listdir(d), key=lambda n: int(n.split(".mutant.")[1].split(".")[0])):
        with open(os.path.join(d, name)) as f:
            lines = f.read().splitlines()
        sm = difflib.SequenceMatcher(a=original, b=lines, autojunk=False)
        ops = [op for op in sm.get_opcodes() if op[0] != "equal"]
        if len(ops) != 1:
            continue
        tag, i1, i2, j1, j2 = ops[0]
        text = " ".join(x.strip() for x in original[i1:i2])
        if text.startswith(("//", "/*", "*", "#")) or compiler_hint(text):
            continue  # comments, preprocessor lines and unrolling hints: nothing a test could see
        if any(k in device_only for k in range(i1, max(i2, i1 + 1))) != device_only_code:
            continue  # device-only code: the CPU build does not compile it (and the reverse)
        if same_code(" ".join(original[i1:i2]), " ".join(lines[j1:j2])):
            continue  # only spacing moved
        mutants.append({
            "file": rel,
            "path": os.path.join(d, name),
            "line": i1 + 1,
            "original": " ".join(x.strip() for x in original[i1:i2]),
            "mutant": " ".join(x.strip() for x in lines[j1:j2]),
        })
    return mutants


def planted_mutants(root, path, out_dir):
    """Hand-written one-line bugs (tests/mutation/planted.txt): file<TAB>original line<TAB>
    replacement<TAB>what kind of bug. The original must match exactly one line of the file
    (stripped); the replacement keeps its indentation."""
    mutants = []
    with open(path) as f:
        entries = [(n, line.rstrip("\n").split("\t")) for n, line in enumerate(f, 1)
                   if line.strip() and not line.startswith("#")]
    for n, parts in entries:
        if len(parts) != 4:
            die(f"{path}:{n}: expected 4 tab-separated fields (file, original, replacement, kind)")
        rel, orig, repl, kind = parts
        src = os.path.join(root, rel)
        if not os.path.isfile(src):
            die(f"{path}:{n}: no such file: {rel}")
        with open(src) as f:
            lines = f.read().split("\n")
        hits = [i for i, ln in enumerate(lines) if ln.strip() == orig.strip()]
        if len(hits) != 1:
            die(f"{path}:{n}: the original line occurs {len(hits)} times in {rel} (it must occur once)")
        i = hits[0]
        indent = lines[i][:len(lines[i]) - len(lines[i].lstrip())]
        lines[i] = indent + repl.strip()
        d = os.path.join(out_dir, "planted")
        os.makedirs(d, exist_ok=True)
        mpath = os.path.join(d, f"{n}_{os.path.basename(rel)}")
        with open(mpath, "w") as f:
            f.write("\n".join(lines))
        mutants.append({"file": rel, "path": mpath, "line": i + 1, "original": orig.strip(),
                        "mutant": repl.strip(), "kind": kind.strip()})
    return mutants


class Restorer:
    """Keeps the original of the file being mutated and puts it back on exit or signal."""

    def __init__(self, root, backup_dir):
        self.root = root
        self.backup_dir = backup_dir
        self.current = None
        os.makedirs(backup_dir, exist_ok=True)
        self.recover()
        signal.signal(signal.SIGINT, self.on_signal)
        signal.signal(signal.SIGTERM, self.on_signal)

    def manifest(self):
        return os.path.join(self.backup_dir, "mutated-file")

    def recover(self):
        """A campaign killed mid-mutant left its original here: put it back first, but only
        while the file still holds that mutant. If the file changed since (restored by hand, a
        checkout of another commit), the backup is stale and restoring it would undo that."""
        if os.path.exists(self.manifest()):
            with open(self.manifest()) as f:
                lines = f.read().split("\n")
            rel = lines[0].strip()
            mutant_hash = lines[1].strip() if len(lines) > 1 else ""
            path = os.path.join(self.root, rel)
            if mutant_hash and os.path.exists(path) and file_hash(path) == mutant_hash:
                shutil.copyfile(os.path.join(self.backup_dir, "original"), path)
                print(f"mutate: restored {rel} from an interrupted campaign", file=sys.stderr)
            else:
                print(f"mutate: an interrupted campaign's backup of {rel} is stale (the file changed since); "
                      "left as it is", file=sys.stderr)
            os.remove(self.manifest())

    def apply(self, rel, mutant_path):
        shutil.copyfile(os.path.join(self.root, rel), os.path.join(self.backup_dir, "original"))
        with open(self.manifest(), "w") as f:
            f.write(rel + "\n" + file_hash(mutant_path))
        self.current = rel
        shutil.copyfile(mutant_path, os.path.join(self.root, rel))

    def restore(self):
        if self.current is None:
            return
        dst = os.path.join(self.root, self.current)
        shutil.copyfile(os.path.join(self.backup_dir, "original"), dst)
        os.utime(dst)  # newer than the mutant's objects, so the next build recompiles
        os.remove(self.manifest())
        self.current = None

    def on_signal(self, signum, frame):
        kill_running()  # no build or test of the mutant may outlive it
        rel = self.current
        self.restore()
        die(f"interrupted (signal {signum})" + (f"; {rel} restored" if rel else ""), 130)


def file_hash(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def build(build_dir, jobs):
    return sh(["cmake", "--build", build_dir, "-j", str(jobs)], None)


def run_tests(build_dir, jobs, timeout):
    """(status, failing test or None): 'pass', 'fail' or 'timeout'. Fast tests first, then the
    slow benchmark-scene test, each stopping at the first failure."""
    t0 = time.time()
    # A fresh scene cache for each run: a mutant's loader must not leave meshes for the next.
    with tempfile.TemporaryDirectory(prefix="bvhlab-mutate-cache-") as cache:
        env = dict(os.environ, BVHLAB_CACHE_DIR=cache)
        return run_tests_in(build_dir, jobs, timeout, t0, env)


def run_tests_in(build_dir, jobs, timeout, t0, env):
    for sel in (["-E", "BenchmarkScenes"], ["-R", "BenchmarkScenes"]):
        left = timeout - (time.time() - t0)
        if left <= 0:
            return "timeout", None
        rc, out = sh(["ctest", "--test-dir", build_dir, "-LE", "gpu", "--stop-on-failure", "-j", str(jobs),
                      "--timeout", str(int(max(left, 1)))] + sel, None, timeout=left + 30, env=env)
        if rc is None:
            return "timeout", None
        if rc != 0:
            failed = [ln.split("-", 1)[-1].strip().split(" (")[0] for ln in out.splitlines()
                      if ln.strip().endswith(("(Failed)", "(Timeout)", "(SEGFAULT)", "(Subprocess aborted)",
                                              "(Child aborted)", "(Exception)"))]
            if any("(Timeout)" in ln for ln in out.splitlines() if "tests FAILED" not in ln):
                return "timeout", failed[0] if failed else None
            return "fail", failed[0] if failed else "ctest exit %d" % rc
    return "pass", None


def write_atomic(path, text):
    """Writes `path` through a temporary file and a rename: a reader never sees half a report."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def write_report(results, meta, out_dir):
    per_file = {}
    for r in results:
        s = per_file.setdefault(r["file"], {"killed": 0, "survived": 0, "equivalent": 0, "stillborn": 0})
        key = {"killed": "killed", "timeout": "killed", "survived": "survived", "equivalent": "equivalent",
               "stillborn": "stillborn"}[r["status"]]
        s[key] += 1
    total = {k: sum(s[k] for s in per_file.values()) for k in ("killed", "survived", "equivalent", "stillborn")}

    def score(s):
        n = s["killed"] + s["survived"]
        return s["killed"] / n if n else None

    meta["score"] = score(total)
    meta["totals"] = total
    write_atomic(os.path.join(out_dir, "report.json"),
                 json.dumps({"campaign": meta, "files": per_file, "mutants": results}, indent=1))
    lines = [f"# Mutation campaign at {meta['commit']}", "",
             f"{meta['date']}; {meta['mutants_run']} mutants run of {meta['mutants_total']} generated "
             f"(sample {meta['sample']}, seed {meta['seed']}); {meta['minutes']:.1f} minutes.", "",
             "Score = killed / (killed + survived); stillborn mutants (do not compile) and equivalent ones "
             "(tests/mutation/equivalent.txt) are not counted.", "",
             "| file | killed | survived | equivalent | stillborn | score |", "|---|---|---|---|---|---|"]
    for f, s in sorted(per_file.items()):
        sc = score(s)
        lines.append(f"| {f} | {s['killed']} | {s['survived']} | {s['equivalent']} | {s['stillborn']} | "
                     f"{'-' if sc is None else '%.0f%%' % (100 * sc)} |")
    sc = meta["score"]
    lines.append(f"| **all** | {total['killed']} | {total['survived']} | {total['equivalent']} | "
                 f"{total['stillborn']} | {'-' if sc is None else '%.1f%%' % (100 * sc)} |")
    lines += ["", "## Survivors", ""]
    surv = [r for r in results if r["status"] == "survived"]
    if not surv:
        lines.append("None.")
    for r in surv:
        lines += [f"- `{r['file']}:{r['line']}`" + (f" ({r['kind']})" if r.get("kind") else ""),
                  f"  - `{r['original']}`", f"  + `{r['mutant']}`"]
    lines += ["", "## Killed by", ""]
    by_test = {}
    for r in results:
        if r["status"] in ("killed", "timeout"):
            by_test[r.get("killed_by") or "timeout"] = by_test.get(r.get("killed_by") or "timeout", 0) + 1
    for t, n in sorted(by_test.items(), key=lambda x: -x[1]):
        lines.append(f"- {t}: {n}")
    write_atomic(os.path.join(out_dir, "report.md"), "\n".join(lines) + "\n")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(prog="tools/mutate.sh", description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", action="append", default=[],
                    help="source files to mutate (repeatable or comma-separated; default: every core file)")
    ap.add_argument("--changed", metavar="REV", help="the core files changed since git revision REV")
    ap.add_argument("--sample", type=int, default=0,
                    help="run this many mutants that compile, drawn at random (0: all); stillborn ones are "
                         "drawn past")
    ap.add_argument("--seed", type=int, default=1, help="seed of the sample and of the order (default 1)")
    ap.add_argument("--budget", type=float, default=0, help="start no mutant after this many minutes (0: none)")
    ap.add_argument("--build-dir", default="build-mutate", help="CPU-only build folder (default build-mutate)")
    ap.add_argument("--out", help="report folder (default BUILD_DIR/campaign-COMMIT)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="build and test jobs")
    ap.add_argument("--timeout", type=float, default=0,
                    help="seconds the tests of one mutant may take (default: 3x the unmutated run, at least 120)")
    ap.add_argument("--planted", action="store_true",
                    help="run the hand-written bugs of tests/mutation/planted.txt instead (all of them)")
    ap.add_argument("--no-baseline", action="store_true",
                    help="skip the unmutated test run a campaign starts with (needs --timeout)")
    ap.add_argument("--list", action="store_true", help="list the mutants of the sample and stop")
    ap.add_argument("--fail-under", type=float, default=-1,
                    help="exit 1 when the score is below this fraction (default: report only)")
    a = ap.parse_args()

    rc, root = sh(["git", "rev-parse", "--show-toplevel"], os.path.dirname(os.path.abspath(__file__)))
    root = root.strip()
    os.chdir(root)
    if a.sample < 0 or a.budget < 0 or a.timeout < 0 or a.jobs < 1:
        die("--sample, --budget and --timeout take values >= 0, --jobs >= 1")
    if a.no_baseline and not a.timeout:
        die("--no-baseline needs --timeout (the limit is otherwise 3x the baseline run)")
    core = core_files(root)
    files = [f for arg in a.files for f in arg.split(",") if f]
    for f in files:
        if not os.path.isfile(os.path.join(root, f)):
            die(f"--files: no such file: {f}")
        if not f.endswith(EXTENSIONS):
            die(f"--files: {f} is not a C++ source or header of the CPU build")
    if a.changed:
        files += changed_files(root, a.changed)
        if not files:
            print(f"mutate: no core file changed since {a.changed}; nothing to do")
            return 0
    if not files:
        files = core
    files = sorted(set(files))
    if a.planted and (a.files or a.changed or a.sample):
        die("--planted runs every entry of tests/mutation/planted.txt; it takes no --files, --changed or --sample")
    if shutil.which("mutate") is None:
        die("universalmutator's `mutate` is not on PATH (tools/mutate.sh installs it into build-mutate/venv)")
    commit = sh(["git", "rev-parse", "--short=12", "HEAD"], root)[1].strip()
    dirty = sh(["git", "status", "--porcelain", "--untracked-files=no"], root)[1].strip() != ""
    build_dir = os.path.abspath(a.build_dir)
    out_dir = os.path.abspath(a.out or os.path.join(build_dir, ("planted-" if a.planted else "campaign-") + commit))
    os.makedirs(out_dir, exist_ok=True)
    # One campaign per build folder: two would share the backup of the mutated file, and each
    # would "recover" the other's mutant into the sources (seen: a header holding another
    # file's text). The lock lasts as long as this process.
    lock = open(os.path.join(build_dir, "mutate.lock"), "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        die(f"another campaign is running with the build folder {a.build_dir} (its lock {lock.name} is held)")
    restorer = Restorer(root, os.path.join(build_dir, "mutate-backup"))

    mutants = []
    if a.planted:
        mutants = planted_mutants(root, os.path.join(root, "tests/mutation/planted.txt"), out_dir)
        files = sorted({m["file"] for m in mutants})
    else:
        for f in files:
            mutants += make_mutants(root, f, os.path.join(out_dir, "mutants"))
    rng = random.Random(a.seed)
    rng.shuffle(mutants)
    total_generated = len(mutants)
    if a.list:
        for m in mutants[:a.sample or len(mutants)]:
            print(f"{m['file']}:{m['line']}: {m['original']}  =>  {m['mutant']}")
        return 0
    equivalents = load_equivalents(os.path.join(root, "tests/mutation/equivalent.txt"))

    if not os.path.exists(os.path.join(build_dir, "CMakeCache.txt")):
        rc, out = sh(["cmake", "-S", root, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release", "-DBVHLAB_ENABLE_CUDA=OFF",
                      "-DBVHLAB_BUILD_BENCHMARKS=OFF"], root)
        if rc != 0:
            die("configuring " + build_dir + " failed:\n" + out[-2000:])
    print(f"mutate: building the unmutated tree in {a.build_dir}", flush=True)
    rc, out = build(build_dir, a.jobs)
    if rc != 0:
        die("the unmutated tree does not build:\n" + out[-2000:])
    t0 = time.time()
    if not a.no_baseline:
        status, failed = run_tests(build_dir, a.jobs, 3600)
        if status != "pass":
            die(f"the unmutated tests do not pass ({failed}); a campaign needs a green suite")
    timeout = a.timeout or max(120.0, 3.0 * (time.time() - t0))
    print(f"mutate: {a.sample or 'all'} mutants of {total_generated} in {len(files)} files; "
          + ("" if a.no_baseline else f"tests took {time.time() - t0:.0f} s unmutated, ")
          + f"limit {timeout:.0f} s per mutant", flush=True)

    start = time.time()
    results = []
    if os.path.exists(os.path.join(out_dir, "progress.jsonl")):
        os.remove(os.path.join(out_dir, "progress.jsonl"))
    alive = 0  # mutants that compiled
    for i, m in enumerate(mutants):
        if a.sample and alive >= a.sample:
            break
        if a.budget and time.time() - start > 60 * a.budget:
            print(f"mutate: time budget of {a.budget} minutes spent after {i} mutants", flush=True)
            break
        r = {k: m[k] for k in ("file", "line", "original", "mutant", "kind") if k in m}
        why = equivalents.get((m["file"], m["original"], m["mutant"]))
        if why:
            r["status"], r["reason"] = "equivalent", why
        else:
            t = time.time()
            restorer.apply(m["file"], m["path"])
            try:
                rc, out = build(build_dir, a.jobs)
                if rc != 0:
                    r["status"] = "stillborn"
                else:
                    status, failed = run_tests(build_dir, a.jobs, timeout)
                    r["status"] = {"pass": "survived", "fail": "killed", "timeout": "timeout"}[status]
                    if failed:
                        r["killed_by"] = failed
            finally:
                restorer.restore()
            r["seconds"] = round(time.time() - t, 1)
        results.append(r)
        alive += r["status"] != "stillborn"
        with open(os.path.join(out_dir, "progress.jsonl"), "a") as f:  # kept if the campaign is cut short
            f.write(json.dumps(r) + "\n")
        print(f"[{alive}/{a.sample or len(mutants)}] {r['status']:<10} {m['file']}:{m['line']}  {m['mutant'][:90]}"
              + (f"  ({r['killed_by']})" if r.get("killed_by") else ""), flush=True)
    build(build_dir, a.jobs)  # leave the build matching the sources

    meta = {"commit": commit + ("-dirty" if dirty else ""), "date": datetime.date.today().isoformat(),
            "kind": "planted" if a.planted else "sampled",
            "files": files, "sample": a.sample or "all", "seed": a.seed, "mutants_total": total_generated,
            "mutants_run": len(results), "minutes": (time.time() - start) / 60.0,
            "tool": "universalmutator " + mutator_version()}
    print(write_report(results, meta, out_dir))
    print(f"\nmutate: report in {os.path.relpath(out_dir, root)}/report.md and report.json")
    if a.fail_under >= 0 and meta["score"] is not None and meta["score"] < a.fail_under:
        print(f"mutate: score {meta['score']:.3f} is below {a.fail_under}", file=sys.stderr)
        return 1
    return 0


def mutator_version():
    try:
        from importlib.metadata import version
        return version("universalmutator")
    except Exception:  # noqa: BLE001 - the version is informative only
        return "unknown"


if __name__ == "__main__":
    sys.exit(main())
