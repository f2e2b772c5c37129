#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# tools/mutate.py's refusals: each bad option value gets exit 2 and one line naming it, before
# anything is built or mutated (universalmutator need not be installed).
# Usage: mutate_errors.sh SOURCE_DIR
set -uo pipefail
src=$1
fails=0
expect() {  # expect PATTERN ARGS...: exit 2, the last stderr line matches PATTERN, no traceback
    local pattern=$1
    shift
    local err rc
    err=$(python3 "$src/tools/mutate.py" "$@" 2>&1 >/dev/null)
    rc=$?
    if [ $rc -ne 2 ] || ! tail -1 <<<"$err" | grep -q -- "$pattern" || grep -q Traceback <<<"$err"; then
        echo "FAIL: mutate.py $* -> exit $rc: $err"
        fails=$((fails + 1))
    fi
}
expect "--sample" --sample -1
expect "--jobs" --jobs 0
expect "--sample" --sample abc
expect "--no-baseline needs --timeout" --no-baseline
expect "no such file: no/such.cpp" --files no/such.cpp
expect "README.md is not a C++ source" --files README.md
expect "--changed no-such-rev" --changed no-such-rev
expect "--planted runs every entry" --planted --sample 3
# An interrupted campaign's backup is restored only while the file still holds its mutant; a
# file changed since (restored by hand, another commit checked out) is left as it is.
if ! python3 - "$src/tools/mutate.py" <<'PY'
import importlib.util, os, sys, tempfile
spec = importlib.util.spec_from_file_location("mutate", sys.argv[1])
m = importlib.util.module_from_spec(spec)
spec.loader.exec_module(m)
with tempfile.TemporaryDirectory() as root:
    backup = os.path.join(root, "backup")
    src = os.path.join(root, "a.cpp")
    mutant = os.path.join(root, "mutant.cpp")
    for case in ("still mutated", "changed since"):
        with open(src, "w") as f: f.write("int x = 1;\n")
        with open(mutant, "w") as f: f.write("int x = 0;\n")
        r = m.Restorer(root, backup)
        r.apply("a.cpp", mutant)  # the campaign dies here, mutant in place
        if case == "changed since":
            with open(src, "w") as f: f.write("int x = 2;  // a newer commit\n")
        m.Restorer(root, backup)  # the next campaign starts
        want = "int x = 1;\n" if case == "still mutated" else "int x = 2;  // a newer commit\n"
        assert open(src).read() == want, (case, open(src).read())
        assert not os.path.exists(os.path.join(backup, "mutated-file")), case
PY
then
    echo "FAIL: Restorer's recovery of an interrupted campaign"
    fails=$((fails + 1))
fi
# Device-only lines (an `#if defined(__CUDA_ARCH__)` branch) get no mutants in a CPU campaign;
# the #else branch, nested #ifs and code outside do.
if ! python3 - "$src/tools/mutate.py" <<'PY'
import importlib.util, sys
spec = importlib.util.spec_from_file_location("mutate", sys.argv[1])
m = importlib.util.module_from_spec(spec)
spec.loader.exec_module(m)
lines = ["int a;", "#if defined(__CUDA_ARCH__)", "dev();", "#if X", "nested();", "#endif", "#else", "host();",
         "#endif", "#ifdef __CUDA_ARCH__", "dev2();", "#endif", "#if !defined(__CUDA_ARCH__)", "host2();", "#endif"]
got = sorted(m.device_only_lines(lines))
assert got == [2, 4, 10], got  # preprocessor lines get no mutants anyway
PY
then
    echo "FAIL: device-only lines"
    fails=$((fails + 1))
fi
# universalmutator reads `{-` as a Haskell comment and mutates nothing after it: it is given a
# copy with `{ -` (the same C++); a file without `{-` is read as it is.
if ! python3 - "$src/tools/mutate.py" <<'PY'
import importlib.util, os, sys, tempfile
spec = importlib.util.spec_from_file_location("mutate", sys.argv[1])
m = importlib.util.module_from_spec(spec)
spec.loader.exec_module(m)
with tempfile.TemporaryDirectory() as d, tempfile.TemporaryDirectory() as tmp:
    a, b = os.path.join(d, "a.h"), os.path.join(d, "b.h")
    open(a, "w").write("Hit miss() { return {-1, 0.0f}; }\nint x = y + 1;\n")
    open(b, "w").write("int x = y + 1;\n")
    got = m.mutator_input(a, tmp)
    assert got != a and os.path.basename(got) == "a.h", got
    assert open(got).read() == "Hit miss() { return { -1, 0.0f}; }\nint x = y + 1;\n", open(got).read()
    assert m.mutator_input(b, tmp) == b
# A mutant that only moves spaces next to brackets and commas is the same code; others are not.
assert m.same_code("return {{FLT_MAX, FLT_MAX}, { -FLT_MAX}};", "return { { FLT_MAX,FLT_MAX}, { -FLT_MAX}};")
assert not m.same_code("return a - -b;", "return a --b;")
assert not m.same_code("x = a < b;", "x = a <= b;")
# An unrolling hint alone on its line is not mutated (a device campaign's survivor, m00 of seed 35).
assert m.compiler_hint("        BVHLAB_UNROLL") and m.compiler_hint('_Pragma("unroll")')
assert not m.compiler_hint("BVHLAB_UNROLL for (int i = 0; i < 9; ++i) f[i] = p[i];") and not m.compiler_hint("x = 1;")
PY
then
    echo "FAIL: mutator_input"
    fails=$((fails + 1))
fi
# tools/mutate_device.py: a step without its folder is refused (exit 2), and the report counts
# what the GPU machine's run wrote.
if python3 "$src/tools/mutate_device.py" build --sample 2 >/dev/null 2>&1; then
    echo "FAIL: mutate_device.py build without --build-dir and --out"
    fails=$((fails + 1))
fi
tmp=$(mktemp -d)
cat >"$tmp/mutants.json" <<'JSON'
{"seed": 3, "sample": 2, "tried": 3, "mutants": [
 {"file": "traversal/device/ray.h", "line": 50, "original": "a", "mutant": "b", "status": "built", "name": "m00"},
 {"file": "accel/core/bits.h", "line": 24, "original": "c", "mutant": "d|e", "status": "built", "name": "m01"}]}
JSON
printf '%s
' '{"file": "traversal/device/ray.h", "line": 50, "mutant": "b", "status": "killed", "killed_by": "GpuTrace.X"}' \
    '{"file": "accel/core/bits.h", "line": 24, "mutant": "d|e", "status": "survived", "killed_by": ""}' >"$tmp/results.jsonl"
if ! python3 "$src/tools/mutate_device.py" report "$tmp" >/dev/null ||
    ! grep -q "3 tried, 1 stillborn, 2 built; of those run: 1 killed, 1 survived" "$tmp/report.md" ||
    ! grep -q 'accel/core/bits.h:24 | `d\\|e` | survived' "$tmp/report.md"; then
    echo "FAIL: mutate_device.py report"; cat "$tmp/report.md"
    fails=$((fails + 1))
fi
rm -rf "$tmp"
[ $fails -eq 0 ] && echo "mutate_errors.sh: all cases passed"
exit $((fails > 0))
