// SPDX-License-Identifier: MIT
// Versioned ray-set and hit files (format in README.md, "File formats"). Little-endian.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Version 2 adds the writer (the commit that wrote the file) and a content checksum; version 1
/// files (no checksum) are still read.
constexpr uint32_t kRayFileVersion = 2;
constexpr uint32_t kHitFileVersion = 2;
constexpr size_t kFileWriterBytes = 24;  ///< the writer field: NUL-padded ASCII

/// A ray set with the query it asks for. `writer` is what wrote the file it was read from (a
/// commit; "" for version 1 files), or what write_ray_file stores ("" writes "unknown").
struct RaySet {
    std::vector<Ray> rays;
    Query query = Query::kClosest;
    std::string writer;
    uint32_t version = 0;  ///< the file version it was read from (0: not read from a file)
};

/// A hit set with the query that produced it, and its writer as RaySet's.
struct HitSet {
    std::vector<Hit> hits;
    Query query = Query::kClosest;
    std::string writer;
    uint32_t version = 0;
};

/// Writes `BVHLRAYS`, version, flags (bit 0 = any-hit), count, the writer, then 32 bytes per
/// ray and a 64-bit checksum of all that came before, whole or not at all
/// (scene::write_file_atomically). Throws bvhlab::Error when it cannot.
void write_ray_file(const std::string& path, const RaySet& set);
/// Reads a ray file. Throws bvhlab::Error naming the problem on a missing file, wrong magic,
/// unknown version or flags, a size that does not match the count, a checksum that does not
/// match (the file is damaged), or an invalid ray (its index and why: see invalid_ray).
RaySet read_ray_file(const std::string& path);

/// Why `r` cannot be traced, or "" when it can: origin and direction finite, direction not
/// zero, tmin finite and >= 0, tmax not NaN and >= tmin (+inf allowed).
std::string invalid_ray(const Ray& r);

/// Writes a hit file (same header as a ray file, 16 bytes per hit), whole or not at all.
void write_hit_file(const std::string& path, const HitSet& set);
/// Reads a hit file; the same checks as read_ray_file, and each hit's t, u, v must be finite
/// (a miss is tri -1). Triangle ids are checked against a mesh by check_hit_ids.
HitSet read_hit_file(const std::string& path);

/// Throws bvhlab::Error naming the first hit whose triangle id is not -1 or below
/// `triangle_count` (the hits of another scene, say).
void check_hit_ids(const HitSet& set, size_t triangle_count, const std::string& path);

}  // namespace bvhlab::trav
