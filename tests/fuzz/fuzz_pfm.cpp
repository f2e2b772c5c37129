// SPDX-License-Identifier: MIT
// Fuzz target: the PFM reader (environment maps and textures in builds without OpenImageIO).
#include "renderer/image.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "input.pfm");
    return bvhlab::fuzz::expect_success_or_error([&] { (void)bvhlab::render::read_pfm(path); });
}
