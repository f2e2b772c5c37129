#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# data/fetch_scenes.sh without the network: the Sibenik converter on a small C-array file, a
# source whose result differs from the tables' file is refused by name, the catalogue writer,
# and bad arguments. (The real downloads were checked byte for byte by hand: experiments/NOTES.md.)
# Usage: fetch_scenes.sh SOURCE_DIR
set -u
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/check_lib.sh"

mkdir -p "$tmp/from/sibenik"
printf 'float sibenik_vertices[] =\n{\n    -0.011057, -15.3, 1e-006, 1.5, 2, 3,\n 0, 1, 0\n};\nunsigned int sibenik_indices[]=\n{\n 0, 1, 2\n};\n' \
    >"$tmp/from/sibenik/sibenik.bin"
"$py" "$src/data/make_benchmark_scenes.py" sibenik "$tmp/from/sibenik/sibenik.bin" "$tmp/s.obj"
check "sibenik converter: vertices as %g, 1-based faces" [ "$(grep -v '^#' "$tmp/s.obj" | tr '\n' '|')" = "v -0.011057 -15.3 1e-06|v 1.5 2 3|v 0 1 0|f 1 2 3|" ]
(cd "$tmp/from" && zip -q -r sibenik.zip sibenik) 2>/dev/null || "$py" -c "
import zipfile, sys; z = zipfile.ZipFile('$tmp/from/sibenik.zip', 'w'); z.write('$tmp/from/sibenik/sibenik.bin', 'sibenik/sibenik.bin'); z.close()"
bash "$src/data/fetch_scenes.sh" --dest "$tmp/scenes" --from "$tmp/from" sibenik >/dev/null 2>"$tmp/err"
rc=$?
check "a source that is not the tables' file fails (rc $rc)" [ "$rc" -ne 0 ]
check "and names the scene and both hashes" grep -q "sibenik: .*sibenik.obj has SHA-256 [0-9a-f]*, not 03658967" "$tmp/err"
check "no scenes.json for a failed fetch" [ ! -e "$tmp/scenes/scenes.json" ]

mkdir -p "$tmp/cat"
"$py" "$src/data/make_benchmark_scenes.py" catalogue "$src/data/benchmark_scenes.json" "$tmp/cat" furball sibenik
check "catalogue: the scenes asked for, their cameras and the protocol" "$py" -c "
import json; d = json.load(open('$tmp/cat/scenes.json'))
assert sorted(d['scenes']) == ['furball', 'sibenik'] and 'camera' in d['scenes']['furball'] and 'ray_protocol' in d, d"

bash "$src/data/fetch_scenes.sh" --dest "$tmp/x" nosuch 2>"$tmp/err"
check "an unknown scene is named with the known ones" grep -q "unknown scene 'nosuch' (known: cornell-box furball" "$tmp/err"
bash "$src/data/fetch_scenes.sh" --from "$tmp/none" 2>"$tmp/err"
check "--from a missing folder is refused" grep -q "from needs an existing folder" "$tmp/err"
check "--list names the benchmark scenes" [ "$(bash "$src/data/fetch_scenes.sh" --list | head -6 | tr '\n' ' ')" = "cornell-box furball sibenik stanford-bunny dragon-100k buddha-100k " ]

# buddha-100k has no public source: skipped with a note naming --from, or taken from --from
# DIR/buddha.obj and checked like the others (the real file when $BVHLAB_SCENES has it).
bash "$src/data/fetch_scenes.sh" --dest "$tmp/b0" buddha-100k >"$tmp/out" 2>&1
check "buddha-100k without --from: skipped, pointing at --from" grep -q "buddha-100k skipped: .*--from DIR (DIR/buddha.obj)" "$tmp/out"
check "and no folder left for it" [ ! -e "$tmp/b0/buddha-100k" ]
mkdir -p "$tmp/fake"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/fake/buddha.obj"
bash "$src/data/fetch_scenes.sh" --dest "$tmp/b1" --from "$tmp/fake" buddha-100k >/dev/null 2>"$tmp/err"
rc=$?
check "a buddha.obj that is not the tables' file is refused (rc $rc)" [ "$rc" -ne 0 ]
check "by name, with both hashes" grep -q "buddha-100k: .*buddha.obj has SHA-256 [0-9a-f]*, not 1b2479c7" "$tmp/err"
if [ -f "${BVHLAB_SCENES:-/nonexistent}/buddha-100k/buddha.obj" ]; then
    mkdir -p "$tmp/real"
    cp "$BVHLAB_SCENES/buddha-100k/buddha.obj" "$tmp/real/"
    bash "$src/data/fetch_scenes.sh" --dest "$tmp/b2" --from "$tmp/real" buddha-100k >"$tmp/out" 2>&1
    check "the tables' buddha.obj from --from is taken" cmp -s "$tmp/real/buddha.obj" "$tmp/b2/buddha-100k/buddha.obj"
    check "and catalogued" "$py" -c "
import json; d = json.load(open('$tmp/b2/scenes.json')); assert list(d['scenes']) == ['buddha-100k'], d"
else
    echo "fetch_scenes.sh test: the tables' buddha.obj is not in \$BVHLAB_SCENES; its --from success case not run"
fi

finish "fetch_scenes.sh test"
