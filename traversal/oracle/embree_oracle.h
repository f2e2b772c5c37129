// SPDX-License-Identifier: MIT
// The Embree 3 oracle: the same triangles in an Embree scene (robust mode), traced one ray at
// a time. The only file pair in bvhlab that includes Embree.
#pragma once

#include <memory>
#include <vector>

#include "scene/mesh.h"
#include "scene/scene.h"
#include "traversal/device/ray.h"
#include "traversal/tracer.h"

namespace bvhlab::trav {

class EmbreeOracle {
public:
    /// Builds an Embree scene over `mesh` (triangle ids = Embree primIDs). Throws bvhlab::Error
    /// if Embree reports an error.
    explicit EmbreeOracle(const scene::TriangleMesh& mesh);
    /// Builds Embree's own two-level scene: one Embree scene per placed mesh and one Embree
    /// instance per instance. Hits name triangles by scene-wide ids (accel::TwoLevelBvh's
    /// numbering: instance i's triangle k is the triangles of instances 0..i-1 plus k).
    explicit EmbreeOracle(const scene::InstancedScene& scene);
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
    /// The same with 16-wide packets (rtcIntersect16 / rtcOccluded16) of consecutive rays.
    void trace16(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits) const;

    struct Impl;  // Embree handles; public only so the error callback can name it

private:
    std::unique_ptr<Impl> impl_;
};

/// Embree as a tracer for `bvhlab bench --device embree`, on every core (TBB): one ray per
/// call ("embree-rtcIntersect1") or 16-wide packets ("embree-rtcIntersect16"). Any-hit hits
/// carry tri 0, as trace() gives them. `oracle` must outlive the tracer.
std::unique_ptr<Tracer> make_embree_tracer(const EmbreeOracle& oracle, bool packets16);

}  // namespace bvhlab::trav
