#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `bvhlab sweep` on CPU cells: every cell runs once and is keyed in the results; a second run
# skips them; a sweep killed with -9 takes its running cell with it and resumes with no cell
# run twice; shards and --merge; a failing cell is named and retried on the next run; bad specs
# and options get one line and a non-zero exit. And `bvhlab rerun` of records: side by side,
# refused across commits and changed scenes, never over the old outputs.
# Usage: sweep.sh BVHLAB
set -u
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BVHLAB_CACHE_DIR=$tmp/cache
. "$(dirname "$0")/check_lib.sh"
# Distinct cells in a results file, and the largest number of records one cell has.
cells_in() { python3 -c "
import collections, json, sys
n = collections.Counter()
for f in sys.argv[1:]:
    for line in open(f):
        if line.strip(): n[json.loads(line)['sweep']['key']] += 1
print(len(n), max(n.values()) if n else 0)" "$@"; }

cat >"$tmp/grid.json" <<'EOF'
{"name": "grid", "command": "bench", "scenes": ["gen:soup:3000:1", "gen:soup:3000:2"],
 "grid": {"--builder": ["binned", "sbvh"], "--max-leaf": [2, 8]},
 "args": ["--device", "cpu", "--width", "16", "--height", "16", "--types", "primary", "--runs", "1"],
 "repetitions": 2}
EOF
"$bin" sweep "$tmp/grid.json" --dry-run >"$tmp/dry.txt"
check "dry run lists 16 cells" [ "$(grep -c '^cell .* cpu to run: bvhlab bench gen:soup' "$tmp/dry.txt")" -eq 16 ]
check "the last axis varies fastest" grep -q "^cell 1 cpu to run: .*--builder binned --max-leaf 8" "$tmp/dry.txt"
check "the dry run writes no results" [ ! -e "$tmp/grid.results.jsonl" ]

"$bin" -q sweep "$tmp/grid.json" --json >"$tmp/run1.json"
rc=$?
check "a sweep runs (rc $rc)" [ "$rc" -eq 0 ]
check "16 cells, one record each" [ "$(cells_in "$tmp/grid.results.jsonl")" = "16 1" ]
check "each record names its cell's builder and leaf size" python3 -c "
import json, sys
for line in open('$tmp/grid.results.jsonl'):
    j = json.loads(line); k = json.loads(j['sweep']['key'])
    assert j['record'] == 'bench' and j['scene'] == k['scene'], j
    assert j['config'].startswith(k['options']['--builder'] + ' leaf=1..' + str(k['options']['--max-leaf'])), (j['config'], k)
"
check "the summary line says 16 ran" grep -q '"ran":16' "$tmp/run1.json"
"$bin" -q sweep "$tmp/grid.json" --json >"$tmp/run2.json"
check "a second run skips every cell" grep -q '"ran":0,.*"skipped_done":16\|"skipped_done":16' "$tmp/run2.json"
check "and adds no record" [ "$(wc -l <"$tmp/grid.results.jsonl")" -eq 16 ]
"$bin" sweep "$tmp/grid.json" --status >"$tmp/status.txt"
check "--status: 16 of 16 done" grep -q "16 of 16 cells done" "$tmp/status.txt"

# Kill -9 in the middle, then resume: every cell once.
cat >"$tmp/slow.json" <<'EOF'
{"command": "bench", "scenes": ["gen:soup:60000:3"], "grid": {"--max-leaf": [1, 2, 3, 4, 5, 6, 7, 8]},
 "args": ["--device", "cpu", "--width", "64", "--height", "64", "--types", "primary,diffuse", "--runs", "3"]}
EOF
"$bin" -q sweep "$tmp/slow.json" --results "$tmp/slow.jsonl" &
pid=$!
for _ in $(seq 1 600); do
    [ -s "$tmp/slow.jsonl" ] && [ "$(wc -l <"$tmp/slow.jsonl")" -ge 4 ] && break
    sleep 0.1
done
kill -9 "$pid"
wait "$pid" 2>/dev/null
sleep 0.5
orphans=$(pgrep -f "bench gen:soup:60000:3" | wc -l)
check "a killed sweep leaves no cell running ($orphans)" [ "$orphans" -eq 0 ]
read -r before _ < <(cells_in "$tmp/slow.jsonl")
check "the kill came after some cells and before the end ($before of 8)" [ "$before" -ge 2 ] && [ "$before" -lt 8 ]
"$bin" -q sweep "$tmp/slow.json" --results "$tmp/slow.jsonl" --json >"$tmp/resume.json"
check "the resumed sweep skipped the $before done cells" grep -q "\"skipped_done\":$before" "$tmp/resume.json"
check "after the resume: 8 cells, each with its 2 records once" [ "$(cells_in "$tmp/slow.jsonl")" = "8 2" ]

# Shards and merge.
"$bin" -q sweep "$tmp/grid.json" --results "$tmp/sh.jsonl" --shard 0/3 >/dev/null &&
    "$bin" -q sweep "$tmp/grid.json" --results "$tmp/sh.jsonl" --shard 2/3 >/dev/null
"$bin" sweep "$tmp/grid.json" --results "$tmp/sh.jsonl" --status >"$tmp/st1.txt"
check "two of three shards: 11 of 16 done" grep -q "11 of 16 cells done" "$tmp/st1.txt"
check "shard parts are named" grep -q "2 part files" "$tmp/st1.txt"
"$bin" -q sweep "$tmp/grid.json" --results "$tmp/sh.jsonl" --shard 1/3 >/dev/null
"$bin" sweep "$tmp/grid.json" --results "$tmp/sh.jsonl" --merge >"$tmp/merge.txt"
check "merge folds 16 cells in" grep -q "16 cells merged" "$tmp/merge.txt"
check "merge removes the parts" [ -z "$(ls "$tmp"/sh.jsonl.part-* 2>/dev/null)" ]
check "merged: 16 cells once each" [ "$(cells_in "$tmp/sh.jsonl")" = "16 1" ]

# A failing cell: named, the others run, exit non-zero; the next run retries only it.
cat >"$tmp/fails.json" <<EOF
{"command": "bench", "scenes": ["gen:soup:500:1", "$tmp/missing.obj"], "args": ["--device", "cpu", "--width", "8",
 "--height", "8", "--types", "primary", "--runs", "1"]}
EOF
"$bin" -q sweep "$tmp/fails.json" >/dev/null 2>"$tmp/fails.err"
rc=$?
check "a failed cell fails the sweep (rc $rc)" [ "$rc" -ne 0 ]
check "the failed cell is named with its error" grep -q "cell 1 failed (bench .*missing.obj): exit 1: .*missing.obj" "$tmp/fails.err"
check "the other cell ran" [ "$(cells_in "$tmp/fails.results.jsonl")" = "1 1" ]
"$bin" sweep "$tmp/fails.json" >/dev/null 2>"$tmp/fails2.err"
check "the next run retries only the failed cell" grep -q "1 done, 1 to run" "$tmp/fails2.err"

# Bad specs and options: one line naming the problem, exit non-zero, no results written.
bad() {  # bad NAME PATTERN SPEC-TEXT [extra args]
    local name=$1 pattern=$2 text=$3
    shift 3
    printf '%s' "$text" >"$tmp/bad.json"
    "$bin" sweep "$tmp/bad.json" "$@" >"$tmp/bad.out" 2>"$tmp/bad.err"
    local rc=$?
    if [ "$rc" -ne 0 ] && [ "$(wc -l <"$tmp/bad.err")" -eq 1 ] && grep -q -- "$pattern" "$tmp/bad.err" &&
        [ ! -e "$tmp/bad.results.jsonl" ]; then
        pass=$((pass + 1))
    else
        fail=$((fail + 1))
        echo "FAIL bad spec $name (rc $rc): $(cat "$tmp/bad.err")"
    fi
}
ok='"command": "bench", "scenes": ["gen:soup:100"]'
bad not-json "is not valid JSON" '{"command": '
bad not-object "must hold one JSON object" '[1, 2]'
bad unknown-key "unknown key 'grids'" "{$ok, \"grids\": {}}"
bad no-command "needs \"command\"" '{"scenes": ["x"]}'
bad wrong-command "command 'rays' cannot be swept" '{"command": "rays", "scenes": ["x"]}'
bad no-scenes "\"scenes\" is empty" '{"command": "bench", "scenes": []}'
bad typo "bench has no option --max-leef (did you mean --max-leaf?)" "{$ok, \"grid\": {\"--max-leef\": [1]}}"
bad typo-args "\"args\": bench has no option --runz (did you mean --runs?)" "{$ok, \"args\": [\"--runz\", \"3\"]}"
bad not-option "grid axis 'builder' is not an option" "{$ok, \"grid\": {\"builder\": [\"sbvh\"]}}"
bad empty-axis "grid axis '--max-leaf' needs a non-empty list" "{$ok, \"grid\": {\"--max-leaf\": []}}"
bad twice "lists 2 twice" "{$ok, \"grid\": {\"--max-leaf\": [2, 2]}}"
bad flag-value "--no-scene-cache is a flag: its values are true and false" "{$ok, \"grid\": {\"--no-scene-cache\": [1]}}"
bad value-flag "--max-leaf takes a value, not true" "{$ok, \"grid\": {\"--max-leaf\": [true]}}"
bad object-value "holds {}" "{$ok, \"grid\": {\"--max-leaf\": [{}]}}"
bad json-in-args "holds --json, which the sweep sets itself" "{$ok, \"args\": [\"--json\"]}"
bad reps "\"repetitions\" must be a whole number from 1 to 1000" "{$ok, \"repetitions\": 0}"
bad device "\"device\" must be \"cpu\" or \"gpu\"" "{$ok, \"device\": \"tpu\"}"
export CUDA_VISIBLE_DEVICES=
bad no-gpu "the sweep has 1 GPU cells left and this machine has no GPU" "{$ok, \"device\": \"gpu\"}"
unset CUDA_VISIBLE_DEVICES
bad gpus-empty "--gpus names no GPU" "{$ok, \"device\": \"gpu\"}" --gpus ","
bad results-is-spec "is the spec file" "{$ok}" --results "$tmp/bad.json"
bad results-folder "is a folder" "{$ok}" --results "$tmp"
bad shard "--shard 3/3: expected I/N" "{$ok}" --shard 3/3
bad shard-text "--shard x: expected I/N" "{$ok}" --shard x
bad tasks-alone "--tasks applies to --slurm only" "{$ok}" --tasks 2
bad two-modes "give one of them" "{$ok}" --status --merge
export BVHLAB_SBATCH=$tmp/no-sbatch
bad no-sbatch "cannot run '$tmp/no-sbatch'" "{$ok}" --slurm
unset BVHLAB_SBATCH
"$bin" sweep "$tmp/missing.json" 2>"$tmp/missing.err"
check "a missing spec is one line" grep -q "sweep spec '.*missing.json': does not exist" "$tmp/missing.err"

# report: the grid's 16 cells are 8 measurements of 2 repetitions, each the median of its two.
"$bin" report "$tmp/grid.results.jsonl" --out "$tmp/report" --baseline "binned leaf=1..2" >/dev/null
rc=$?
check "report runs (rc $rc)" [ "$rc" -eq 0 ]
check "report: 8 medians of 2 runs, equal to the records'" python3 -c "
import collections, json, statistics
runs = collections.defaultdict(list)
for line in open('$tmp/grid.results.jsonl'):
    j = json.loads(line); runs[(j['scene'], j['config'])].append(j['mrays_per_s'])
s = json.load(open('$tmp/report/summary.json'))['bench']
assert len(s) == 8 and all(e['n'] == 2 for e in s), s
for e in s:
    assert abs(e['mrays_per_s'] - statistics.median(runs[(e['scene'], e['config'])])) < 1e-9, e
"
check "report.md has the table, the spread and the speed-up" python3 -c "
t = open('$tmp/report/report.md').read()
assert '| gen:soup:3000:1 |' in t and 'run-to-run spread' in t and 'Speed-up against cpu cpu-bvh2-stack [binned leaf=1..2' in t, t"
check "report draws the plots" [ -s "$tmp/report/mrays-primary.png" ] && [ -s "$tmp/report/speedup.png" ]
"$bin" report --compare "$tmp/grid.results.jsonl" "$tmp/sh.jsonl" --out "$tmp/cmp" >/dev/null
check "report --compare: 8 measurements in both" grep -q "8 measurements in both" "$tmp/cmp/report.md"
"$bin" report "$tmp/grid.results.jsonl" --out "$tmp/grid.json" 2>"$tmp/rep.err"
check "report --out over a file is refused" grep -q "is a file, not a folder" "$tmp/rep.err"
"$bin" report "$tmp/grid.results.jsonl" --out "$tmp/r3" --baseline nothing-like-it 2>"$tmp/rep.err"
check "an unknown baseline names the tracers" grep -q "is not a tracer of these results (tracers: cpu cpu-bvh2-stack" "$tmp/rep.err"
"$bin" report "$tmp/none.jsonl" --out "$tmp/r4" 2>"$tmp/rep.err"
check "a missing result file is one line" grep -q "none.jsonl' does not exist" "$tmp/rep.err"

# rerun: a record's command line again, old and new side by side; refusals.
"$bin" -q bench gen:soup:2000:4 --device cpu --types primary,diffuse --width 16 --height 16 --runs 1 --json >"$tmp/b.jsonl"
"$bin" -q rerun "$tmp/b.jsonl" >"$tmp/rerun.txt"
rc=$?
check "rerun runs (rc $rc)" [ "$rc" -eq 0 ]
check "rerun shows old and new Mrays/s for both ray types" [ "$(grep -c "gen:soup:2000:4 \(primary\|diffuse\) .*mrays_per_s" "$tmp/rerun.txt")" -eq 2 ]
"$bin" -q rerun "$tmp/b.jsonl" --line 2 --json >"$tmp/rerun.json"
check "rerun --line 2 --json: the diffuse record with its old figures" python3 -c "
import json; rows = [json.loads(l) for l in open('$tmp/rerun.json')]
assert len(rows) == 1 and rows[0]['ray_type'] == 'diffuse' and rows[0]['rerun_of']['figures']['mrays_per_s']['old'] > 0, rows"
sed 's/"commit":"[^"]*"/"commit":"0000000"/' "$tmp/b.jsonl" >"$tmp/oldcommit.jsonl"
"$bin" -q rerun "$tmp/oldcommit.jsonl" >/dev/null 2>"$tmp/oc.err"
check "a record of another commit is refused" grep -q "a record comes from commit 0000000 and this bvhlab is .*--force" "$tmp/oc.err"
"$bin" -q rerun "$tmp/oldcommit.jsonl" --force >"$tmp/oc.txt" 2>&1
check "--force reruns it" grep -q "mrays_per_s" "$tmp/oc.txt"
sed 's/"scene_hash":"[^"]*"/"scene_hash":"0123456789abcdef"/' "$tmp/b.jsonl" >"$tmp/oldscene.jsonl"
"$bin" -q rerun "$tmp/oldscene.jsonl" >/dev/null 2>"$tmp/os.err"
rc=$?
check "a changed scene is not compared (rc $rc)" [ "$rc" -ne 0 ] && grep -q "not compared: the scene changed (scene_hash 0123456789abcdef then" "$tmp/os.err"
"$bin" -q render gen:soup:500:1 --device cpu --width 8 --height 8 --spp 1 -o "$tmp/img.pfm" --json >"$tmp/render.jsonl"
touch -d '2000-01-01' "$tmp/img.pfm"
"$bin" -q rerun "$tmp/render.jsonl" >/dev/null
check "rerun of a render leaves its image alone" [ "$(stat -c %Y "$tmp/img.pfm")" = "$(date -d '2000-01-01' +%s)" ]
echo '{"record": "bench", "commit": "x"}' >"$tmp/noargv.jsonl"
"$bin" -q rerun "$tmp/noargv.jsonl" 2>"$tmp/na.err"
check "a record without a command line is one line" grep -q "the record names no command line" "$tmp/na.err"
"$bin" -q rerun "$tmp/b.jsonl" --line 9 2>"$tmp/l9.err"
check "a line past the end is named" grep -q "has no record on line 9 (it has 2 lines)" "$tmp/l9.err"

finish "sweep.sh"
