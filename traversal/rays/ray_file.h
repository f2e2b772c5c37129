// SPDX-License-Identifier: MIT
// Versioned ray-set and hit files (format in README.md, "File formats"). Little-endian.
#pragma once

#include <string>
#include <vector>

#include "traversal/device/ray.h"

namespace bvhlab::trav {

constexpr uint32_t kRayFileVersion = 1;
constexpr uint32_t kHitFileVersion = 1;

/// A ray set with the query it asks for.
struct RaySet {
    std::vector<Ray> rays;
    Query query = Query::kClosest;
};

/// A hit set with the query that produced it.
struct HitSet {
    std::vector<Hit> hits;
    Query query = Query::kClosest;
};

/// Writes `BVHLRAYS`, version, flags (bit 0 = any-hit), count, then 32 bytes per ray.
/// Throws bvhlab::Error when the file cannot be written.
void write_ray_file(const std::string& path, const RaySet& set);
/// Reads a ray file. Throws bvhlab::Error naming the problem on a missing file, wrong magic,
/// unknown version or flags, or a size that does not match the count.
RaySet read_ray_file(const std::string& path);

void write_hit_file(const std::string& path, const HitSet& set);
HitSet read_hit_file(const std::string& path);

}  // namespace bvhlab::trav
