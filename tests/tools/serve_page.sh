#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `render --serve`: headless Chromium (Debian's chromium) loads the page while a render runs and
# must see the image change: several images, their samples per pixel rising, their pixels
# different, the last one the finished render's, the page saying done. The server listens on
# 127.0.0.1 only (not on this machine's other addresses), is gone when the render ends, and a
# taken port is a one-line error.
# Exits 77 (skipped) with a reason when chromium or curl is not installed.
# Usage: serve_page.sh BVHLAB DATA_DIR
set -u
bin=$(readlink -f "$1")
data=$(readlink -f "$2")
for p in chromium curl python3; do
    if ! command -v "$p" >/dev/null; then
        echo "serve_page.sh: skipped: '$p' is not installed (tools/install_deps.sh installs chromium)"
        exit 77
    fi
done
if "$bin" render "$data/cornell_box.obj" --serve 0 --width 1 --height 1 --spp 1 -o /dev/null 2>&1 |
    grep -q "this build has no preview server"; then
    echo "serve_page.sh: skipped: this bvhlab was built without the preview server (-DBVHLAB_WITH_SERVER=OFF)"
    exit 77
fi
tmp=$(mktemp -d)
render_pid=""
cleanup() {
    [ -n "$render_pid" ] && kill "$render_pid" 2>/dev/null
    rm -rf "$tmp"
}
trap cleanup EXIT
. "$(dirname "$0")/check_lib.sh"
export BVHLAB_CACHE_DIR=$tmp/cache

# A render of a few seconds with an update every 0.2 s.
spp=3000
"$bin" render "$data/cornell_box.obj" --spp $spp --width 64 --height 48 --serve 0 --preview-every 0.2 \
    -o "$tmp/final.pfm" --json >"$tmp/record.json" 2>"$tmp/render.err" &
render_pid=$!
url=""
for _ in $(seq 1 300); do
    url=$(grep -o 'http://127[.]0[.]0[.]1:[0-9]*/' "$tmp/render.err" | head -1)
    [ -n "$url" ] && break
    sleep 0.1
done
if [ -z "$url" ]; then
    echo "serve_page.sh: the render printed no URL"; cat "$tmp/render.err"; exit 1
fi
port=${url##*:}
port=${port%/}

# Loopback only: the same port on this machine's other addresses refuses the connection.
for addr in $(hostname -I 2>/dev/null); do
    case "$addr" in 127.*|::1|*:*) continue ;; esac
    check "not-on-$addr" bash -c "! curl -s --max-time 2 -o /dev/null 'http://$addr:$port/status'"
done

# The page, watched by Chromium until the render ends: the page's own loop stops then, and
# --virtual-time-budget ends the run (virtual time stands still while a request is pending).
timeout 120 chromium --headless --no-sandbox --disable-gpu --user-data-dir="$tmp/chrome" \
    --virtual-time-budget=600000 --dump-dom "$url" >"$tmp/dom.html" 2>"$tmp/chrome.err"
wait "$render_pid"
rc=$?
render_pid=""
check render-exit-0 test "$rc" -eq 0
python3 - "$tmp/dom.html" "$spp" <<'EOF' >"$tmp/page.txt" 2>&1
import re, sys
dom = open(sys.argv[1]).read()
spp = int(sys.argv[2])
items = [(int(v), int(s), int(c)) for v, s, c in
         re.findall(r'<li data-version="(\d+)" data-spp="(\d+)" data-sum="(\d+)"', dom)]
state = re.search(r'<span id="state">([^<]*)</span>', dom)
problems = []
if len(items) < 3:
    problems.append("the page showed %d images, expected at least 3" % len(items))
if any(b[1] <= a[1] for a, b in zip(items, items[1:])):
    problems.append("the images' spp do not rise: %s" % [i[1] for i in items])
if items and items[-1][1] != spp:
    problems.append("the last image has %d spp, the render %d" % (items[-1][1], spp))
if len(set(i[2] for i in items)) < min(len(items), 3):
    problems.append("the images' pixels do not change: %s" % [i[2] for i in items])
if not state or state.group(1) != "done":
    problems.append("the page's state is %r, expected 'done'" % (state.group(1) if state else None))
print("\n".join(problems) if problems else "ok: %d images, spp %s" % (len(items), [i[1] for i in items]))
sys.exit(1 if problems else 0)
EOF
check page-saw-the-image-converge test $? -eq 0
cat "$tmp/page.txt"
check record-names-the-server python3 -c "
import json, sys
r = json.load(open('$tmp/record.json'))
s = r['serve']
assert s['url'] == '$url', s
assert s['updates'] >= 3 and s['requests'] >= 3, s
"
check server-gone-after-the-render bash -c "! curl -s --max-time 2 -o /dev/null '${url}status'"
check final-image-written test -s "$tmp/final.pfm"

# A taken port: one line naming it, exit 1, no image.
python3 -c "
import socket, time
s = socket.socket()
s.bind(('127.0.0.1', 0))
s.listen()
print(s.getsockname()[1], flush=True)
time.sleep(30)
" >"$tmp/port" &
holder=$!
for _ in $(seq 1 50); do [ -s "$tmp/port" ] && break; sleep 0.1; done
taken=$(cat "$tmp/port")
"$bin" render "$data/cornell_box.obj" --spp 1 --width 8 --height 8 --serve "$taken" -o "$tmp/taken.pfm" \
    >/dev/null 2>"$tmp/taken.err"
rc=$?
kill "$holder" 2>/dev/null
check taken-port-exit-1 test "$rc" -eq 1
check taken-port-one-line grep -q "error: --serve: cannot listen on 127.0.0.1:$taken" "$tmp/taken.err"
check taken-port-no-image test ! -e "$tmp/taken.pfm"
finish serve_page.sh
