// SPDX-License-Identifier: MIT
// 64-bit FNV-1a: the scene hash, and the content checksums of structure, ray and hit files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace bvhlab::accel {

/// The offset basis is 1469598103934665603, not FNV-1a's standard 14695981039346656037: the
/// file formats fixed it (README, "The checksums and the scene hash").
constexpr uint64_t kFnvOffset = 1469598103934665603ull, kFnvPrime = 1099511628211ull;

/// FNV-1a over bytes: the scene hash and structure files (their format is fixed by it).
inline uint64_t fnv1a(const void* data, size_t n, uint64_t h = kFnvOffset) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * kFnvPrime;
    return h;
}

/// FNV-1a over 8-byte little-endian words, the tail bytewise: ray and hit files (version 2).
/// Eight times fewer multiplies than fnv1a, for files of hundreds of megabytes, and still sure
/// to notice any one damaged word (each step is a bijection of the state).
inline uint64_t fnv1a_words(const void* data, size_t n, uint64_t h = kFnvOffset) {
    const auto* p = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        std::memcpy(&w, p + i, 8);
        h = (h ^ w) * kFnvPrime;
    }
    return fnv1a(p + i, n - i, h);
}

/// A hash as 16 hex digits (the scene hash's printed form), and back (0 for text that is not hex).
inline std::string hash_hex(uint64_t h) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}
inline uint64_t hash_from_hex(const std::string& hex) { return std::strtoull(hex.c_str(), nullptr, 16); }

}  // namespace bvhlab::accel
