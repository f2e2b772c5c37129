// SPDX-License-Identifier: MIT
// Out of host memory, with the size asked for: the bvhlab tool replaces the global allocation
// functions (host_memory.cpp) so that a failed allocation throws OutOfHostMemory, which
// std::bad_alloc alone cannot say.
#pragma once

#include <cstddef>
#include <new>
#include <string>

namespace bvhlab::cli {

class OutOfHostMemory : public std::bad_alloc {
public:
    explicit OutOfHostMemory(size_t bytes) : bytes_(bytes) {}
    size_t bytes() const noexcept { return bytes_; }
    const char* what() const noexcept override { return "out of host memory"; }

private:
    size_t bytes_;
};

/// "12.3 GB (12345678901 bytes)".
std::string describe_bytes(size_t bytes);

}  // namespace bvhlab::cli
