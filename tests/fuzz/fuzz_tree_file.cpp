// SPDX-License-Identifier: MIT
// Fuzz target: the structure-file reader (BVH and kd-tree files), then the validation every
// loaded structure goes through before use.
#include "accel/io/tree_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "input.tree");
    return bvhlab::fuzz::expect_success_or_error([&] { (void)bvhlab::accel::read_tree_file(path); });
}
