// SPDX-License-Identifier: MIT
// The replaceable global allocation functions ([new.delete]) for the bvhlab tool: malloc and
// free as libstdc++'s own, except that a failure throws OutOfHostMemory with its size.
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

// Every form is replaced, not just the throwing scalar one: a sanitizer runtime (ASan) supplies
// its own for the forms left out, and memory from its operator new[] freed by ours would be an
// alloc-dealloc mismatch.
namespace {

void* allocate(std::size_t n) {
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw bvhlab::cli::OutOfHostMemory(n);
}

/// Null on failure. aligned_alloc wants a size that is a multiple of the alignment.
void* try_allocate_aligned(std::size_t n, std::align_val_t a) noexcept {
    const auto align = static_cast<std::size_t>(a);
    return std::aligned_alloc(align, ((n ? n : 1) + align - 1) / align * align);
}

void* allocate_aligned(std::size_t n, std::align_val_t a) {
    if (void* p = try_allocate_aligned(n, a)) return p;
    throw bvhlab::cli::OutOfHostMemory(n);
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, std::align_val_t a) { return allocate_aligned(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocate_aligned(n, a); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return std::malloc(n ? n : 1); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return std::malloc(n ? n : 1); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return try_allocate_aligned(n, a);
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return try_allocate_aligned(n, a);
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
