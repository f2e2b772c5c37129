#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Python package as a user installs it: `pip install .` (scikit-build-core builds the
# libraries and the module with CMake) into a fresh virtual environment of Debian's python3
# that sees its numpy and pytest, then the module's tests against the installed copy, from
# outside the source tree. CUDA is left out to save time (the GPU tests skip without a GPU
# anyway); the ctest suite tests the module of the main build. Used by .ci/run.
# Usage: tools/pip_check.sh [VENV_DIR]   (default build-pip/venv)
set -euo pipefail
cd "$(dirname "$0")/.."
src=$(pwd)
venv=$(realpath -m "${1:-build-pip/venv}")  # absolute: the tests run from another folder
rm -rf "$venv"
/usr/bin/python3 -m venv --system-site-packages "$venv"
# --config-settings works with Debian 12's pip 23.0 (its short form -C came with 23.1).
"$venv/bin/pip" install --quiet "$src" --config-settings=cmake.define.BVHLAB_ENABLE_CUDA=OFF \
    --config-settings=build-dir=build-pip/cmake || { echo "pip_check: pip install . failed" >&2; exit 1; }
# Open Image Denoise as users get it: the pyoidn wheel from PyPI (it ships the library), so that
# the module's denoising test runs too.
"$venv/bin/pip" install --quiet pyoidn || { echo "pip_check: pip install pyoidn failed" >&2; exit 1; }
cd "$(mktemp -d)"  # not the source tree: `import bvhlab` must find the installed package
BVHLAB_DATA="$src/data" "$venv/bin/python" -m pytest -q -p no:cacheprovider "$src/python/tests"
"$venv/bin/python" -c "import bvhlab; assert 'site-packages' in bvhlab.__file__, bvhlab.__file__; print('pip_check: bvhlab', bvhlab.__commit__, 'from', bvhlab.__file__)"

# The denoiser's test of the main build (README command 2's build/) against the wheel's library,
# found as `render --denoise` finds it, through $VIRTUAL_ENV.
if [ -x "$src/build/tests/bvhlab_tests" ]; then
    log=$(VIRTUAL_ENV="$venv" "$src/build/tests/bvhlab_tests" --gtest_filter='Denoise.*' 2>&1) || true
    echo "$log" | tail -3
    grep -q "PASSED .*1 test" <<<"$log" || { echo "pip_check: the denoiser's test did not pass" >&2; exit 1; }
    echo "pip_check: denoised with OIDN from $venv"
fi
