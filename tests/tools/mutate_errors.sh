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
[ $fails -eq 0 ] && echo "mutate_errors.sh: all cases passed"
exit $((fails > 0))
