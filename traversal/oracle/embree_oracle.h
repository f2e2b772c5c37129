// SPDX-License-Identifier: MIT
// The Embree 3 oracle: the same triangles in an Embree scene (robust mode), traced one ray at
// a time. The only file pair in bvhlab that includes Embree.
#pragma once

#include <memory>
#include <vector>

#include "accel/core/mesh.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

class EmbreeOracle {
public:
    /// Builds an Embree scene over `mesh` (triangle ids = Embree primIDs). Throws bvhlab::Error
    /// if Embree reports an error.
    explicit EmbreeOracle(const accel::TriangleMesh& mesh);
    ~EmbreeOracle();
    EmbreeOracle(const EmbreeOracle&) = delete;
    EmbreeOracle& operator=(const EmbreeOracle&) = delete;

    /// Closest hit with rtcIntersect1; t in [tmin, tmax].
    Hit intersect(const Ray& ray) const;
    /// Any-hit occlusion with rtcOccluded1.
    bool occluded(const Ray& ray) const;

    /// Traces a whole ray set in parallel (TBB), one rtc*1 call per ray. Any-hit results
    /// carry tri = 0 for "occluded" (Embree does not say which triangle) and -1 for a miss.
    void trace(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits) const;

    struct Impl;  // Embree handles; public only so the error callback can name it

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace bvhlab::trav
