#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Checks that every tracked C++/CUDA source is formatted as .clang-format says, with Debian 12's
# clang-format 14 (tools/install_deps.sh installs it). CI runs it before the build.
# Usage: tools/check_format.sh [--fix]   (--fix formats the files in place)
set -euo pipefail
cd "$(dirname "$0")/.."
cf=$(command -v clang-format-14 || command -v clang-format || true)
if [ -z "$cf" ]; then
    echo "check_format.sh: clang-format-14 not found (tools/install_deps.sh installs it)" >&2
    exit 1
fi
mapfile -t files < <(git ls-files '*.cpp' '*.h' '*.cu' '*.cuh')
if [ "${1:-}" = "--fix" ]; then
    "$cf" -i "${files[@]}"
    echo "check_format.sh: formatted ${#files[@]} files"
    exit 0
fi
report=$(mktemp)
trap 'rm -f "$report"' EXIT
if "$cf" --dry-run -Werror "${files[@]}" 2>"$report"; then
    echo "check_format.sh: ${#files[@]} files formatted as .clang-format says"
    exit 0
fi
bad=$(grep -oE '^[^:]+:[0-9]+:[0-9]+: (error|warning)' "$report" | cut -d: -f1 | sort -u)
echo "check_format.sh: $(echo "$bad" | wc -l) files are not formatted as .clang-format says (fix: bash tools/check_format.sh --fix):" >&2
echo "$bad" | sed 's/^/    /' >&2
head -20 "$report" >&2
exit 1
