#!/bin/bash
# Installs build-gpu here and packs bvhlab (+ its libraries) and the GPU tests for the device.
set -e
cd "$(dirname "$0")"
rm -rf b stage && cmake --install ../../build-gpu --prefix "$PWD/b" > /dev/null
mkdir -p stage/b/bin stage/b/lib stage/t/b/bin
cp -L b/bin/bvhlab stage/b/bin/ && strip stage/b/bin/bvhlab
for l in libembree3.so.3 libdraco.so.7 libtinyobjloader.so.2rc10 libminizip.so.1 libtbb.so.12 libassimp.so.5; do cp -L b/lib/$l stage/b/lib/; done
cp b/bin/bvhlab_gpu_tests stage/t/b/bin/ && strip stage/t/b/bin/bvhlab_gpu_tests
(cd stage && XZ_OPT=-9e tar cJf ../bundle.tar.xz b) && (cd stage/t && XZ_OPT=-9e tar cJf ../../tests.tar.xz b)
rm -rf b stage
ls -la bundle.tar.xz tests.tar.xz
