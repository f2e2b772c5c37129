// SPDX-License-Identifier: MIT
// Ray-by-ray comparison of two hit sets, sorting each disagreement into a tie (an edge,
// vertex or interval-end case that float arithmetic may decide either way) or a real mismatch.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "accel/core/mesh.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

struct CompareConfig {
    /// Two hits are at the same t when |dt| <= t_rel_tol * t + t_abs_rel * (|o| + |p|) / (|d| cos),
    /// with |o| and |p| the largest coordinates of the origin and hit point and cos the angle
    /// between ray and triangle: the second term is float cancellation in the plane distance,
    /// which dominates for short rays leaving a surface and for grazing rays.
    float t_rel_tol = 1e-4f;
    float t_abs_rel = 1e-6f;
    /// A hit is "on an edge" when its smallest barycentric, computed in double precision,
    /// lies within +-(edge_eps + edge_float_k * 2^-24 * (|o| + |p|) / (h_min * cos)) of 0:
    /// a float kernel's barycentric error grows with the coordinates' magnitude, with
    /// 1 / h_min (the triangle's smallest altitude) and with 1 / cos of the incidence angle.
    float edge_eps = 1e-4f;
    float edge_float_k = 32.0f;
};

/// Largest |dt| at which two hits of `ray` at about `t` on triangle (v0, v1, v2) still count
/// as the same t (see CompareConfig).
double t_tolerance(const Ray& ray, float t, Vec3 v0, Vec3 v1, Vec3 v2, const CompareConfig& cfg = {});

/// Why a disagreement is a tie.
enum class TieKind {
    kSharedEdgeOrVertex = 0,  ///< same t on triangles sharing a vertex: the ray crosses their seam
    kNearEdge = 1,            ///< the missed hit is within eps of its triangle's edge
    kIntervalEnd = 2,         ///< the missed hit sits at tmin or tmax
    kCoincident = 3,          ///< both triangles are hit at the same t in double precision
                              ///< (crossing or overlapping triangles: either answer is right)
};
constexpr int kTieKinds = 4;

/// One disagreement, kept for the report.
struct Disagreement {
    size_t ray = 0;
    Hit ours{};
    Hit oracle{};
    bool tie = false;
    std::string reason;
};

struct CompareReport {
    size_t rays = 0;
    size_t agree = 0;
    size_t ties = 0;
    size_t mismatches = 0;
    std::array<size_t, kTieKinds> ties_by_kind{};  ///< indexed by TieKind
    double max_rel_dt = 0.0;                       ///< over agreeing hits on the same triangle
    std::vector<Disagreement> first_mismatches;    ///< at most 16
    std::vector<Disagreement> first_ties;          ///< at most 4
};

/// For any-hit rays, where the oracle only says "occluded": the oracle's closest hit of the
/// same ray, used to find the triangle the other side missed.
using ClosestLookup = std::function<Hit(const Ray&)>;

/// Compares `ours` and `oracle` ray by ray. For closest-hit queries the triangle and t must
/// agree; for any-hit queries only hit/miss. `lookup` is needed for any-hit queries.
CompareReport compare_hits(const accel::TriangleMesh& mesh, const std::vector<Ray>& rays, Query query,
                           const std::vector<Hit>& ours, const std::vector<Hit>& oracle, const ClosestLookup& lookup,
                           const CompareConfig& cfg = {});

}  // namespace bvhlab::trav
