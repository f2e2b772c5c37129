// SPDX-License-Identifier: MIT
// The kd-tree builder's split search: the SAH of a plane, the sweep over a node's sorted events
// that prices every distinct position, and the direct count for small nodes without events.
// Both searches have an AVX2 copy on x86-64. Internal to the builder (not installed).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "accel/builders/kd/events.h"
#include "accel/builders/kdtree.h"
#include "accel/core/aabb.h"

namespace bvhlab::accel::kd {

/// Candidates are priced this many at a time (one AVX2 register, or two SSE or NEON ones).
constexpr uint32_t kLanes = 8;
constexpr uint32_t kMaxSmallNode = KdTreeBuilder::kMaxSmallNodeSize;

struct Plane {
    float cost = INFINITY;
    int axis = -1;
    float pos = 0.0f;
    bool planar_left = true;
};

/// One axis's sweep records, one per distinct plane position, as structure of arrays (the
/// pricing pass loads them kLanes at a time): the position's sort key and the events of each
/// type up to and including it. Entry 0 is the position before the first (all counts zero);
/// position g is entry g + 1, and the arrays run kLanes entries past the last.
struct Sweep {
    std::vector<uint32_t> key, starts, planars, ends;
    size_t groups = 0;  ///< the number of positions
};

/// The SAH of a plane on one axis of a voxel, with the empty-space bonus. A child's area is
/// linear in the plane position: 2 (a b + (a + b) d) for the other two extents a, b and the
/// child's extent d along the axis (face = 2 a b / area, side = 2 (a + b) / area).
struct AxisCost {
    float lo, hi, face, side, ct, ci, bonus;
    /// The small-node search looks for the cheapest plane's position only below this cost
    /// (a plane that costs more loses to an earlier axis or to the leaf).
    float below = INFINITY;
};
AxisCost axis_cost(const AABB& voxel, int k, float inv_area, const KdTreeBuilder::Config& c);

/// A node of at most kMaxSmallNode triangles, held on the stack: no events, no heap. Such a
/// node's children are no larger, so its whole subtree is built from these. The clipped bounds
/// are kept per axis (structure of arrays), so that the plane search loads them kLanes at a
/// time; the entries from n to the next multiple of kLanes hold the voxel's lower face, never
/// a candidate.
struct SmallWork {
    AABB voxel;
    uint32_t n = 0;
    uint32_t flat = 0;  ///< bit k: some bound is flat (lo == hi) on axis k
    uint32_t tris[kMaxSmallNode];
    /// Per slot, the triangle clipped to the voxel, when this fragment has already clipped
    /// it: its place in the thread's polygon arena, as (first vertex << 4) | count; the
    /// builder's kNoPolygon when the triangle is still to be clipped.
    uint32_t poly[kMaxSmallNode];
    alignas(32) float lo[3][kMaxSmallNode];
    alignas(32) float hi[3][kMaxSmallNode];

    void add(uint32_t t, const AABB& b, uint32_t polygon) {
        tris[n] = t;
        poly[n] = polygon;
        for (int k = 0; k < 3; ++k) {
            lo[k][n] = b.lo[k], hi[k][n] = b.hi[k];
            flat |= uint32_t(b.lo[k] == b.hi[k]) << k;
        }
        ++n;
    }
    /// Appends slot s of another small node.
    void add(const SmallWork& w, uint32_t s) {
        tris[n] = w.tris[s];
        poly[n] = w.poly[s];
        for (int k = 0; k < 3; ++k) {
            lo[k][n] = w.lo[k][s], hi[k][n] = w.hi[k][s];
            flat |= uint32_t(w.lo[k][s] == w.hi[k][s]) << k;
        }
        ++n;
    }
    void pad() {
        for (uint32_t s = n; s % kLanes != 0; ++s)
            for (int k = 0; k < 3; ++k) lo[k][s] = hi[k][s] = voxel.lo[k];
    }
};

enum : uint8_t { kBoth = 0, kLeftOnly = 1, kRightOnly = 2 };
/// The side of a plane that a clipped bound lies on, by the rule the sweep counted with.
inline uint8_t classify(float lo, float hi, const Plane& p) {
    if (lo == p.pos && hi == p.pos) return p.planar_left ? kLeftOnly : kRightOnly;
    if (hi <= p.pos) return kLeftOnly;
    if (lo >= p.pos) return kRightOnly;
    return kBoth;
}

/// Whether the AVX2 copies can run here (x86-64 with AVX2, and `wanted`).
bool use_avx2(bool wanted);

/// The sweep's first pass on one axis: one record per distinct position of the sorted
/// events e (on scanned meshes about a third of the events: vertices are shared).
void count_positions(const std::vector<Event>& e, Sweep& s);

/// The sweep's second pass on axis k of a node of n triangles: the cheapest plane among the
/// records' positions inside the voxel (cost.lo, cost.hi); Plane{} when none is.
Plane price_positions(const Sweep& s, uint32_t n, int k, const AxisCost& cost, bool avx2);

/// The cheapest plane of a node without events: every bound inside the voxel is a candidate,
/// counted directly with the sweep's rule, so the choice is the same plane the sweep would
/// make (ties: lower axis, then lower position, left first). A plane that costs no less than
/// the leaf (Ci n) is not returned.
Plane find_plane_small(const SmallWork& w, const KdTreeBuilder::Config& c, bool avx2);

}  // namespace bvhlab::accel::kd
