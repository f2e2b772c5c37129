// SPDX-License-Identifier: MIT
// Versioned ray-set and hit files (format in README.md, "File formats"). Little-endian.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Version 2 adds the writer (the commit that wrote the file) and a content checksum; version 1
/// files (no checksum) are still read. Hit files' version 3 adds each hit's instance and the
/// triangle of that instance's mesh; versions 1 and 2 are still read.
constexpr uint32_t kRayFileVersion = 2;
constexpr uint32_t kHitFileVersion = 3;
constexpr size_t kFileWriterBytes = 24;  ///< the writer field: NUL-padded ASCII

/// A ray set with the query it asks for. `writer` is what wrote the file it was read from (a
/// commit; "" for version 1 files), or what write_ray_file stores ("" writes "unknown").
struct RaySet {
    std::vector<Ray> rays;
    Query query = Query::kClosest;
    std::string writer;
    uint32_t version = 0;  ///< the file version it was read from (0: not read from a file)
};

/// Where a hit lies in an instanced scene: the instance, and the triangle of its mesh; -1 and -1
/// for a miss.
struct HitInstance {
    int32_t instance;
    int32_t tri;
};

/// How scene-wide triangle ids (Hit::tri) split into instances: instance i's triangle k has id
/// first[i] + k, and first.back() is the world's triangle count. {0, n}: one mesh of n
/// triangles, or any scene made one mesh.
using InstanceFirstIds = std::vector<uint64_t>;

/// A hit set with the query that produced it, and its writer as RaySet's. Hits name triangles by
/// scene-wide ids.
struct HitSet {
    std::vector<Hit> hits;
    Query query = Query::kClosest;
    std::string writer;
    uint32_t version = 0;
    /// Read from a version 3 file: each hit's instance and triangle of its mesh, as the file gives
    /// them (check_hit_ids holds them against the scene). Empty for older versions.
    std::vector<HitInstance> instances{};
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

/// Writes a hit file (same header as a ray file; version 3, 24 bytes per hit: the 16 of Hit, then
/// the instance and the triangle of its mesh that `first` gives the scene-wide id; empty `first`:
/// one instance, 0), whole or not at all. Throws bvhlab::Error for a hit whose id `first` does
/// not hold.
void write_hit_file(const std::string& path, const HitSet& set, const InstanceFirstIds& first = {});
/// Reads a hit file of version 1, 2 or 3; the same checks as read_ray_file, each hit's t, u, v
/// must be finite (a miss is tri -1), and in version 3 a miss has instance -1 and a hit none
/// below 0. Triangle ids are checked against a scene by check_hit_ids.
HitSet read_hit_file(const std::string& path);

/// Throws bvhlab::Error naming the first hit whose triangle id is not -1 or below first.back()
/// (the hits of another scene, say), or, for a version 3 set, whose instance and triangle are
/// not the ones `first` gives its id.
void check_hit_ids(const HitSet& set, const InstanceFirstIds& first, const std::string& path);

/// The instance whose ids hold scene-wide id `id` (< first.back()), and its triangle there.
HitInstance split_hit_id(const InstanceFirstIds& first, uint64_t id);

}  // namespace bvhlab::trav
