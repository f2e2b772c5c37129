# SPDX-License-Identifier: MIT
# Sourced by the shell tests: `check NAME COMMAND...` counts COMMAND's success in pass or fail
# and names each failure; the script ends with `finish NAME`, whose status is the result. It
# also sets `py`.
pass=0
fail=0
check() {
    local name=$1
    shift
    if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $name"; fi
}
finish() {
    echo "$1: $pass passed, $fail failed"
    [ "$fail" -eq 0 ]
}
# Debian's python3, which has the packages tools/install_deps.sh installs (numpy, matplotlib),
# before the first one on PATH (a pyenv shim may lack them).
py=/usr/bin/python3
[ -x "$py" ] || py=python3
