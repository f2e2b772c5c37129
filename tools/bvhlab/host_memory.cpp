// SPDX-License-Identifier: MIT
// The replaceable global allocation functions ([new.delete]) for the bvhlab tool: malloc and
// free as libstdc++'s own, except that a failure throws OutOfHostMemory with its size. The
// nothrow and array forms of the standard library call these.
#include "tools/bvhlab/host_memory.h"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace bvhlab::cli {

std::string describe_bytes(size_t bytes) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.1f GB (%zu bytes)", double(bytes) / 1e9, bytes);
    return buf;
}

}  // namespace bvhlab::cli

void* operator new(std::size_t n) {
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw bvhlab::cli::OutOfHostMemory(n);
}

void* operator new(std::size_t n, std::align_val_t a) {
    const auto align = static_cast<std::size_t>(a);
    // aligned_alloc wants a size that is a multiple of the alignment.
    if (void* p = std::aligned_alloc(align, ((n ? n : 1) + align - 1) / align * align)) return p;
    throw bvhlab::cli::OutOfHostMemory(n);
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
