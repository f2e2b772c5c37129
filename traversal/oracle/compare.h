// SPDX-License-Identifier: MIT
// Ray-by-ray comparison of two hit sets, sorting each disagreement into a tie (an edge,
// vertex or interval-end case that float arithmetic may decide either way) or a real mismatch.
// Every hit the checked side claims must itself be a real hit (checked in double precision
// against the claimed triangle) before any disagreement about it can be excused as a tie.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "scene/mesh.h"
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
    /// The checked side's any-hit records are bare occlusion flags with no triangle (Embree's
    /// own rtcOccluded, benchmarked as a tracer), so they are not checked as hits.
    bool any_hit_flags = false;
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
                              ///< (crossing or overlapping triangles: either answer is right).
                              ///< Proven, not excused: the other kinds invoke float error
};
constexpr int kTieKinds = 4;

/// Why a ray is a real mismatch. The first five say that the claimed hit is not a hit at all;
/// the last four that a real hit (or a miss) disagrees with Embree and no tie rule covers it.
enum class MismatchKind {
    kInvalidRecord = 0,    ///< triangle id out of range, or t, u or v not a finite number
    kOutsideInterval = 1,  ///< the claimed t lies outside the ray's [tmin, tmax]
    kWrongT = 2,           ///< the ray meets the claimed triangle's plane at another t (or never)
    kOffTriangle = 3,      ///< the ray meets the plane at the claimed t, but outside the triangle
    kWrongUv = 4,          ///< u and v are not the barycentrics of the point the ray hits
    kExtraHit = 5,         ///< a real hit where Embree finds none
    kMissedHit = 6,        ///< a miss where Embree finds a hit
    kFartherHit = 7,       ///< a real hit beyond Embree's closest hit
    kCloserHit = 8,        ///< a real hit before Embree's closest hit that Embree does not report
};
constexpr int kMismatchKinds = 9;
/// "invalid-record", "outside-interval", "wrong-t", "off-triangle", "wrong-uv", "extra-hit",
/// "missed-hit", "farther-hit", "closer-hit".
const char* mismatch_kind_name(MismatchKind k);

/// Whether `h` (a hit, h.tri >= 0) is a real hit of `ray` on `mesh`: the triangle id exists,
/// t lies in the ray's interval, the ray meets the triangle's plane at t and inside the
/// triangle, and u, v are the barycentrics of that point (Embree's convention), each within
/// the tolerances of `cfg` (the t window of t_tolerance, the barycentric window of the
/// near-edge rule). Returns the kind of lie, or -1 for a real hit; `why` gets the details.
int check_claimed_hit(const scene::TriangleMesh& mesh, const Ray& ray, const Hit& h, std::string* why = nullptr,
                      const CompareConfig& cfg = {});
/// One disagreement, kept for the report.
struct Disagreement {
    size_t ray = 0;
    Hit ours{};
    Hit oracle{};
    bool tie = false;
    int kind = -1;  ///< TieKind for a tie, MismatchKind for a mismatch
    std::string reason;
};

struct CompareReport {
    size_t rays = 0;
    size_t agree = 0;
    size_t ties = 0;
    size_t mismatches = 0;
    std::array<size_t, kTieKinds> ties_by_kind{};             ///< indexed by TieKind
    std::array<size_t, kMismatchKinds> mismatches_by_kind{};  ///< indexed by MismatchKind
    double max_rel_dt = 0.0;                                  ///< over agreeing hits on the same triangle
    std::vector<Disagreement> first_mismatches;               ///< at most 16
    std::vector<Disagreement> first_ties;                     ///< at most 4
};

/// For any-hit rays, where the oracle only says "occluded": the oracle's closest hit of the
/// same ray, used to find the triangle the other side missed.
using ClosestLookup = std::function<Hit(const Ray&)>;

/// Compares `ours` and `oracle` ray by ray. Every hit of `ours` must pass check_claimed_hit;
/// then for closest-hit queries the triangle and t must agree, for any-hit queries hit/miss.
/// `oracle` is trusted. `lookup` is needed for any-hit queries.
CompareReport compare_hits(const scene::TriangleMesh& mesh, const std::vector<Ray>& rays, Query query,
                           const std::vector<Hit>& ours, const std::vector<Hit>& oracle, const ClosestLookup& lookup,
                           const CompareConfig& cfg = {});

/// The report's counts as JSON, as `bvhlab verify --json` and Python's verify() give them: rays,
/// agree, ties and ties_<kind>, mismatches and mismatch_kinds, max_rel_dt, and the tolerances.
nlohmann::json report_json(const CompareReport& rep, const CompareConfig& cfg);

}  // namespace bvhlab::trav
