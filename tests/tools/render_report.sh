#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# experiments/render_report.py on the committed records of a split render run (three folders,
# no images): the tables list every scene once, in the order rendered; the figures are written
# and linked relative to the Markdown file; the README section is replaced between its markers
# and nowhere else; folders of different commits are refused. Skipped (77) without numpy and
# matplotlib (Debian: python3-matplotlib).
# Usage: render_report.sh SOURCE_DIR
set -u
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/check_lib.sh"
if ! "$py" -c "import numpy, matplotlib" 2>/dev/null; then
    echo "render_report.sh: skipped: numpy and matplotlib are not installed (tools/install_deps.sh installs them)"
    exit 77
fi
run=$src/experiments/results/render-9c0eed4-h100
report=$src/experiments/render_report.py
export MPLBACKEND=Agg

"$py" "$report" "$run/part-a" "$run/part-b" "$run/part-c" --figures "$tmp/fig" --tag t >"$tmp/out.md" 2>"$tmp/err"
check "three folders read together (rc $?)" [ ! -s "$tmp/err" ]
check "says it was one run in 3 calls" grep -q "render\`, in 3 calls at \`9c0eed48d827\` on NVIDIA H100" "$tmp/out.md"
overhead=$(sed -n '/^\*\*Overhead/,/^\*\*Compaction/p' "$tmp/out.md" | grep -c '^| [A-Za-z]')
check "the overhead table has the 7 scenes and its header ($overhead rows)" [ "$overhead" -eq 8 ]
check "in the order rendered, furball last" [ "$(sed -n '/^\*\*Overhead/,/^\*\*Compaction/p' "$tmp/out.md" | grep '^| ' | tail -1 | cut -d'|' -f2)" = " furball " ]
check "furball's ratio as its records give it" grep -q "^| furball | 2,733,030 | 512 | 471 | 511 | \*\*0.92\*\*" "$tmp/out.md"
check "every record was checked against Embree" grep -q "1155 records, 0 real mismatches" "$tmp/out.md"
check "the kernels counted from the records" grep -q "best of the 10 BVH2 kernels" "$tmp/out.md"
for f in paths switches coherence; do
    check "figure $f written" [ -s "$tmp/fig/render-t-$f.png" ]
done
check "no contact sheet without the renders' images" [ ! -e "$tmp/fig/render-t-images.png" ]

mkdir -p "$tmp/docs"
printf 'before\n<!-- render-report:begin -->\nold\n<!-- render-report:end -->\nafter\n' >"$tmp/docs/r.md"
"$py" "$report" "$run/part-a" "$run/part-b" "$run/part-c" --figures "$tmp/fig" --tag t --readme "$tmp/docs/r.md"
check "the section replaced, the text around it kept" [ "$(head -2 "$tmp/docs/r.md" | tr '\n' '|')$(tail -1 "$tmp/docs/r.md")" = "before|<!-- render-report:begin -->|after" ]
check "old section gone" [ "$(grep -c '^old$' "$tmp/docs/r.md")" -eq 0 ]
check "figures linked from the Markdown file's folder" grep -q "(../fig/render-t-paths.png)" "$tmp/docs/r.md"

mkdir -p "$tmp/other"
cp "$run/part-b/"* "$tmp/other/"
sed -i 's/"commit":"9c0eed48d827"/"commit":"0123456789ab"/' "$tmp/other/render.jsonl"
"$py" "$report" "$run/part-a" "$tmp/other" --figures "$tmp/fig" >/dev/null 2>"$tmp/err"
rc=$?
check "folders of two commits refused (rc $rc)" [ "$rc" -ne 0 ]
check "naming both" grep -q "differ in GPU or commit.*0123456789ab.*9c0eed48d827" "$tmp/err"
"$py" "$report" "$tmp/none" --figures "$tmp/fig" >/dev/null 2>"$tmp/err"
check "a folder without render.jsonl refused in one line" [ "$(wc -l <"$tmp/err")" -eq 1 ]
finish render_report.sh
