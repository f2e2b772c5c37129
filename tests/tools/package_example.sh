#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The CMake package as a user meets it: install bvhlab's "dev" component (libraries, headers,
# bvhlabConfig.cmake) into a temporary prefix, configure examples/cpp against it with
# find_package(bvhlab CONFIG REQUIRED), build it, and run both programs.
# Usage: package_example.sh BUILD_DIR SOURCE_DIR BUILD_TYPE "CXX_FLAGS" "EXE_LINKER_FLAGS"
set -euo pipefail
build=$1 src=$2 type=$3 cxxflags=${4:-} ldflags=${5:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "package_example: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$tmp/prefix" --component dev >"$tmp/install.log" || {
    cat "$tmp/install.log"; fail "cmake --install failed"; }
for f in lib/cmake/bvhlab/bvhlabConfig.cmake lib/cmake/bvhlab/bvhlabConfigVersion.cmake \
         lib/cmake/bvhlab/bvhlabTargets.cmake include/bvhlab/traversal/factory.h include/bvhlab/scene/mesh.h; do
    [ -f "$tmp/prefix/$f" ] || fail "the install lacks $f"
done
# Nothing of the source or build tree may leak into the installed targets.
if grep -q -e "$src" -e "$(cd "$build" && pwd)" "$tmp"/prefix/lib/cmake/bvhlab/*.cmake; then
    fail "the installed package names the source or build tree"
fi

# Another version is refused: the version file is checked.
mkdir -p "$tmp/ver"
cat >"$tmp/ver/CMakeLists.txt" <<'CM'
cmake_minimum_required(VERSION 3.24)
project(v LANGUAGES CXX)
find_package(bvhlab 99 CONFIG QUIET)
if(bvhlab_FOUND)
  message(FATAL_ERROR "bvhlab 99 was accepted")
endif()
CM
cmake -S "$tmp/ver" -B "$tmp/ver/b" -DCMAKE_PREFIX_PATH="$tmp/prefix" >"$tmp/ver.log" 2>&1 || {
    cat "$tmp/ver.log"; fail "find_package(bvhlab 99) did not refuse the installed version"; }

cmake -S "$src/examples/cpp" -B "$tmp/example" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE="$type" \
    -DCMAKE_CXX_FLAGS="$cxxflags" -DCMAKE_EXE_LINKER_FLAGS="$ldflags" >"$tmp/configure.log" 2>&1 || {
    cat "$tmp/configure.log"; fail "configuring examples/cpp against the installed package failed"; }
cmake --build "$tmp/example" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; fail "building examples/cpp failed"; }

"$tmp/example/build_only" | tee "$tmp/build_only.out"
[ "$(grep -c 'SAH' "$tmp/build_only.out")" -eq 2 ] || fail "build_only did not print two builds"

"$tmp/example/trace_scene" "$src/data/cornell_box.obj" sbvh bvh2 | tee "$tmp/trace.out"
grep -q "^bvh2/sbvh over" "$tmp/trace.out" || fail "trace_scene did not build an SBVH"
grep -q "every hit agrees with Embree" "$tmp/trace.out" || fail "trace_scene did not agree with Embree"
"$tmp/example/trace_scene" "$src/data/cornell_box.obj" binned cwbvh | grep -q "every hit agrees with Embree" ||
    fail "trace_scene (cwbvh) did not agree with Embree"
# Errors come back as one line and a non-zero exit.
if "$tmp/example/trace_scene" "$src/data/cornell_box.obj" octree 2>"$tmp/err.txt"; then
    fail "an unknown builder was accepted"
fi
grep -q "octree" "$tmp/err.txt" || fail "the error does not name the builder: $(cat "$tmp/err.txt")"
echo "package_example: ok"
