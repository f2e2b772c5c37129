#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The scene cache through the CLI: eight runs started at once on one scene with an empty cache
# all succeed and leave one whole entry; the next run is served by it; --no-scene-cache and
# `cache info|clear` do what they say; a damaged entry is a warning, not a failure.
# Usage: scene_cache.sh BVHLAB
set -u
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BVHLAB_CACHE_DIR=$tmp/cache
. "$(dirname "$0")/check_lib.sh"
field() {  # field KEY < one JSON line
    python3 -c "import json,sys; print(json.loads(sys.stdin.readline())['$1'])"
}

"$bin" -q gen --kind soup --triangles 300000 --seed 5 --out "$tmp/soup.obj" >/dev/null || exit 1

pids=()
for i in 1 2 3 4 5 6 7 8; do
    "$bin" build "$tmp/soup.obj" --no-epo --json >"$tmp/run$i.json" 2>"$tmp/run$i.err" &
    pids+=($!)
done
ok=0
for p in "${pids[@]}"; do wait "$p" && ok=$((ok + 1)); done
check "eight concurrent runs all succeed ($ok of 8)" [ "$ok" -eq 8 ]
hashes=$(for i in 1 2 3 4 5 6 7 8; do field scene_hash <"$tmp/run$i.json"; done | sort -u | wc -l)
check "eight concurrent runs, one scene hash" [ "$hashes" -eq 1 ]
warned=$(cat "$tmp"/run*.err | grep -ciE "warning|error")
check "no warnings or errors from the concurrent runs ($warned)" [ "$warned" -eq 0 ]
usable=$("$bin" cache info --json | python3 -c "import json,sys; print(sum(1 for l in sys.stdin if json.loads(l).get('usable')))")
check "one usable entry after the concurrent runs ($usable)" [ "$usable" -eq 1 ]
leftovers=$(find "$tmp/cache" -name '.*tmp-*' | wc -l)
check "no temporaries left ($leftovers)" [ "$leftovers" -eq 0 ]

state=$("$bin" -q build "$tmp/soup.obj" --no-epo --json | field scene_cache)
check "the next run is served by the cache ($state)" [ "$state" = hit ]
state=$("$bin" -q build "$tmp/soup.obj" --no-epo --no-scene-cache --json | field scene_cache)
check "--no-scene-cache bypasses it ($state)" [ "$state" = off ]

entry=$(find "$tmp/cache" -name '*.bvhscene' | head -1)
printf 'garbage' | dd of="$entry" bs=1 seek=300 conv=notrunc 2>/dev/null
"$bin" build "$tmp/soup.obj" --no-epo --json >"$tmp/dmg.json" 2>"$tmp/dmg.err"
rc=$?
check "a damaged entry does not fail the run (rc $rc)" [ "$rc" -eq 0 ]
check "a damaged entry is one warning" grep -q "warning: scene cache entry .* ignored and rebuilt: it is damaged" "$tmp/dmg.err"
check "and the run parsed the OBJ" [ "$(field scene_cache <"$tmp/dmg.json")" = miss ]

# Entries that are not regular files are ignored with a warning, never read (a FIFO would
# hang), never replaced, and left alone by `cache clear`.
rm -f "$entry" && mkdir "$entry"
"$bin" build "$tmp/soup.obj" --no-epo --json >"$tmp/dir.json" 2>"$tmp/dir.err"
check "an entry that is a folder does not fail the run (rc $?)" [ -s "$tmp/dir.json" ]
check "an entry that is a folder is one warning" grep -q "warning: scene cache entry .* is not a regular file: ignored" "$tmp/dir.err"
check "and stays a folder" [ -d "$entry" ]
rmdir "$entry" && mkfifo "$entry"
timeout 60 "$bin" build "$tmp/soup.obj" --no-epo --json >"$tmp/fifo.json" 2>"$tmp/fifo.err"
rc=$?
check "an entry that is a FIFO neither hangs nor fails the run (rc $rc)" [ "$rc" -eq 0 ]
check "an entry that is a FIFO is one warning" grep -q "is not a regular file: ignored" "$tmp/fifo.err"
timeout 60 "$bin" cache info --json >"$tmp/fifo-info.json"
check "cache info lists the FIFO as unusable without reading it (rc $?)" grep -q "not a regular file" "$tmp/fifo-info.json"
timeout 60 "$bin" cache clear >/dev/null
check "cache clear leaves the FIFO" [ -p "$entry" ]
rm -f "$entry"

# A glTF's converted scene is cached too: the second run is served, with the same instances.
data=$(dirname "$0")/../../data
g1=$("$bin" -q build "$data/instances.glb" --json | tail -1)
g2=$("$bin" -q build "$data/instances.glb" --json | tail -1)
check "a glTF's first load is a miss" [ "$(echo "$g1" | field scene_cache)" = miss ]
check "a glTF's second load is a hit" [ "$(echo "$g2" | field scene_cache)" = hit ]
check "with the same instances" [ "$(echo "$g2" | field instances)" = "$(echo "$g1" | field instances)" ]
check "and the same scene hash" [ "$(echo "$g2" | field scene_hash)" = "$(echo "$g1" | field scene_hash)" ]

"$bin" cache clear >/dev/null
left=$("$bin" cache info --json | tail -1 | field entries)
check "cache clear empties it ($left entries)" [ "$left" -eq 0 ]
BVHLAB_CACHE_DIR= HOME= XDG_CACHE_HOME= "$bin" -q cache info >/dev/null 2>"$tmp/nodir.err"
check "no cache folder at all is an error" grep -q "no scene cache folder" "$tmp/nodir.err"

finish "scene_cache.sh"
