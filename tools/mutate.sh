#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Mutation campaign over the core sources: tools/mutate.py does the work (its --help lists
# the options; docs/mutation.md explains the report). This wrapper provides universalmutator
# (PyPI) in build-mutate/venv when `mutate` is not on PATH.
# Examples:
#   bash tools/mutate.sh --sample 40 --seed 3 --budget 60        # 40 mutants of the whole core
#   bash tools/mutate.sh --files traversal/oracle/compare.cpp     # every mutant of one file
#   bash tools/mutate.sh --changed HEAD~1 --sample 4              # what CI runs
set -euo pipefail
cd "$(dirname "$0")/.."
py=python3
if ! command -v mutate >/dev/null; then
    venv=build-mutate/venv
    if [ ! -x "$venv/bin/mutate" ]; then
        mkdir -p build-mutate
        python3 -m venv "$venv" >/dev/null 2>&1 || {
            echo "mutate.sh: cannot make a Python venv (Debian: apt-get install python3-venv), or pip install universalmutator" >&2
            exit 2
        }
        "$venv/bin/pip" install -q universalmutator==1.14.1 || {
            echo "mutate.sh: pip could not install universalmutator" >&2
            exit 2
        }
    fi
    export PATH="$PWD/$venv/bin:$PATH"
    py=$venv/bin/python3
fi
exec "$py" tools/mutate.py "$@"
