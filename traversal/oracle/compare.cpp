// SPDX-License-Identifier: MIT
// Tie rules. A closest-hit disagreement is a tie when
//   (a) both hit at the same t triangles that share a vertex position (the ray crosses their
//       common edge or vertex), or
//   (b) the closer of the two hits lies within float error of its triangle's edge (judged on
//       double-precision barycentrics), so the other side may have slipped through the crack
//       of a non-watertight test, or
//   (c) the closer hit sits at the end of the ray's [tmin, tmax] interval, or
//   (d) both hit at the same t and a double-precision test confirms that both triangles are
//       hit by the ray at that same t (crossing or coincident triangles; either is closest).
//       Checked first when neither hit is near an edge: overlapping coplanar triangles
//       (duplicates, z-fighting) that share a vertex are coincident, not a seam crossing.
// Everything else is a real mismatch. An any-hit disagreement is a tie under (b) or (c).
// Before any of this, every hit the checked side claims must be a real hit (check_claimed_hit):
// a made-up record (a wrong triangle, t, u or v) is a real mismatch of its own kind, whatever
// the oracle says, so no tie rule can excuse it.
#include "traversal/oracle/compare.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "accel/core/check.h"
#include "traversal/reference/ref_intersect.h"

namespace bvhlab::trav {
namespace {

double rel_dt(float a, float b) {
    const double m = std::max(std::fabs(double(a)), std::fabs(double(b)));
    return m > 0 ? std::fabs(double(a) - double(b)) / m : 0.0;
}

class Classifier {
public:
    Classifier(const scene::TriangleMesh& mesh, const CompareConfig& cfg) : mesh_(mesh), cfg_(cfg) {}

    /// The barycentric window of float error for a hit of `r` at t on triangle `tri`: the
    /// near-edge rule's, and the slack allowed on reported u and v.
    double barycentric_tolerance(int32_t tri, const Ray& r, double t) const {
        const Vec3 a = mesh_.vertex(tri, 0), b = mesh_.vertex(tri, 1), c = mesh_.vertex(tri, 2);
        const Vec3 n = cross(b - a, c - a);
        const double area2 = length(n);
        const double longest = std::max({length(b - a), length(c - b), length(a - c)});
        const double h_min = area2 / longest;
        const double cosv = std::fabs(double(dot(n, r.dir))) / (area2 * double(length(r.dir)));
        auto inf = [](Vec3 x) { return double(std::max({std::fabs(x.x), std::fabs(x.y), std::fabs(x.z)})); };
        const double scale = inf(r.org) + inf(r.org + r.dir * float(t));
        return cfg_.edge_eps + cfg_.edge_float_k * 5.9604645e-8 * scale / (h_min * std::max(cosv, 1e-6));
    }
    /// True when the ray passes within float error of an edge of h.tri. Decided on the double-
    /// precision barycentrics, not the reported ones, so a float kernel's own error cannot
    /// excuse itself.
    bool near_edge(const Hit& h, const Ray& r) const {
        const Vec3 a = mesh_.vertex(h.tri, 0), b = mesh_.vertex(h.tri, 1), c = mesh_.vertex(h.tri, 2);
        double t, u, v;
        if (!plane_hit_reference(r, a, b, c, t, u, v)) return true;  // ray in the plane: all edge
        return std::fabs(std::min({u, v, 1.0 - u - v})) <= barycentric_tolerance(h.tri, r, t);
    }
    /// check_claimed_hit(): -1 for a real hit, else the MismatchKind.
    int claim(const Hit& h, const Ray& r, std::string* why) const {
        auto fail = [why](MismatchKind k, const std::string& detail) {
            if (why) *why = detail;
            return int(k);
        };
        if (h.tri < 0 || size_t(h.tri) >= mesh_.triangle_count())
            return fail(MismatchKind::kInvalidRecord, "triangle " + std::to_string(h.tri) + " does not exist");
        if (!std::isfinite(h.t) || !std::isfinite(h.u) || !std::isfinite(h.v))
            return fail(MismatchKind::kInvalidRecord, "t, u or v is not a finite number");
        const Vec3 a = mesh_.vertex(h.tri, 0), b = mesh_.vertex(h.tri, 1), c = mesh_.vertex(h.tri, 2);
        const double t_tol = t_tolerance(r, h.t, a, b, c, cfg_);
        if (double(h.t) < double(r.tmin) - t_tol || double(h.t) > double(r.tmax) + t_tol)
            return fail(MismatchKind::kOutsideInterval, "t=" + std::to_string(h.t) + " is outside the ray's [" +
                                                            std::to_string(r.tmin) + ", " + std::to_string(r.tmax) +
                                                            "]");
        double t, u, v;
        if (!plane_hit_reference(r, a, b, c, t, u, v))
            return fail(MismatchKind::kWrongT, "the ray is parallel to triangle " + std::to_string(h.tri));
        if (std::fabs(double(h.t) - t) > t_tol)
            return fail(MismatchKind::kWrongT, "the ray meets triangle " + std::to_string(h.tri) + "'s plane at t=" +
                                                   std::to_string(t) + ", not " + std::to_string(h.t));
        const double b_tol = barycentric_tolerance(h.tri, r, t);
        if (std::min({u, v, 1.0 - u - v}) < -b_tol)
            return fail(MismatchKind::kOffTriangle, "the ray passes outside triangle " + std::to_string(h.tri) +
                                                        " (barycentrics " + std::to_string(u) + ", " +
                                                        std::to_string(v) + ")");
        if (std::fabs(double(h.u) - u) > b_tol || std::fabs(double(h.v) - v) > b_tol)
            return fail(MismatchKind::kWrongUv, "u, v = " + std::to_string(h.u) + ", " + std::to_string(h.v) +
                                                    " where the ray hits at " + std::to_string(u) + ", " +
                                                    std::to_string(v));
        return -1;
    }
    /// The hit lies at tmin or tmax within the float error of its t (an absolute bound: at
    /// tmin = 0 a relative one would be meaningless).
    bool at_interval_end(const Hit& h, const Ray& r) const {
        const double tol =
            t_tolerance(r, h.t, mesh_.vertex(h.tri, 0), mesh_.vertex(h.tri, 1), mesh_.vertex(h.tri, 2), cfg_);
        return std::fabs(double(h.t) - double(r.tmax)) <= tol || std::fabs(double(h.t) - double(r.tmin)) <= tol;
    }
    bool share_vertex(int32_t s, int32_t t) const {
        for (int i = 0; i < 3; ++i) {
            const Vec3 a = mesh_.vertex(s, i);
            for (int j = 0; j < 3; ++j) {
                const Vec3 b = mesh_.vertex(t, j);
                if (a.x == b.x && a.y == b.y && a.z == b.z) return true;
            }
        }
        return false;
    }
    /// True when two t values of `ray` on triangle `tri` agree within float error.
    bool same_t(float ta, float tb, const Ray& r, int32_t tri) const {
        const double tol =
            t_tolerance(r, std::max(ta, tb), mesh_.vertex(tri, 0), mesh_.vertex(tri, 1), mesh_.vertex(tri, 2), cfg_);
        return std::fabs(double(ta) - double(tb)) <= tol;
    }
    /// Both triangles hit by the ray in double precision, at t values within float error.
    bool coincident(const Ray& r, int32_t s, int32_t t) const {
        double ts, tt, u, v;
        if (!intersect_reference(r, mesh_.vertex(s, 0), mesh_.vertex(s, 1), mesh_.vertex(s, 2), ts, u, v)) return false;
        if (!intersect_reference(r, mesh_.vertex(t, 0), mesh_.vertex(t, 1), mesh_.vertex(t, 2), tt, u, v)) return false;
        return std::fabs(ts - tt) <=
               t_tolerance(r, float(ts), mesh_.vertex(s, 0), mesh_.vertex(s, 1), mesh_.vertex(s, 2), cfg_);
    }
    /// Tie kind for the hit that the other side did not report, or -1 for a real mismatch.
    int tie_for(const Hit& h, const Ray& r) const {
        if (near_edge(h, r)) return int(TieKind::kNearEdge);
        if (at_interval_end(h, r)) return int(TieKind::kIntervalEnd);
        return -1;
    }

private:
    const scene::TriangleMesh& mesh_;
    const CompareConfig& cfg_;
};

}  // namespace

const char* mismatch_kind_name(MismatchKind k) {
    static const char* const names[kMismatchKinds] = {"invalid-record", "outside-interval", "wrong-t",
                                                      "off-triangle",   "wrong-uv",         "extra-hit",
                                                      "missed-hit",     "farther-hit",      "closer-hit"};
    return names[size_t(k)];
}

int check_claimed_hit(const scene::TriangleMesh& mesh, const Ray& ray, const Hit& h, std::string* why,
                      const CompareConfig& cfg) {
    return Classifier(mesh, cfg).claim(h, ray, why);
}

double t_tolerance(const Ray& r, float t, Vec3 a, Vec3 b, Vec3 c, const CompareConfig& cfg) {
    const Vec3 n = cross(b - a, c - a);
    const double dl = length(r.dir);
    const double cosv = std::fabs(double(dot(n, r.dir))) / (double(length(n)) * dl);
    auto inf = [](Vec3 v) { return double(std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)})); };
    const double scale = inf(r.org) + inf(r.org + r.dir * t);
    return cfg.t_rel_tol * double(t) + cfg.t_abs_rel * scale / (dl * std::max(cosv, 1e-6));
}

CompareReport compare_hits(const scene::TriangleMesh& mesh, const std::vector<Ray>& rays, Query query,
                           const std::vector<Hit>& ours, const std::vector<Hit>& oracle, const ClosestLookup& lookup,
                           const CompareConfig& cfg) {
    BVHLAB_CHECK(ours.size() == rays.size() && oracle.size() == rays.size(), "hit sets and ray set differ in size");
    BVHLAB_CHECK(query == Query::kClosest || lookup, "any-hit comparison needs a closest-hit lookup");
    const Classifier cls(mesh, cfg);
    CompareReport rep;
    rep.rays = rays.size();
    std::mutex mu;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const auto& range) {
        CompareReport local;
        std::vector<Disagreement> found;
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const Hit& a = ours[i];
            const Hit& b = oracle[i];
            const Ray& r = rays[i];
            Disagreement d{i, a, b, false, -1, ""};
            int kind = -1;      // TieKind when >= 0
            int mismatch = -1;  // MismatchKind when no tie rule applies
            if (a.is_hit() && !(query == Query::kAny && cfg.any_hit_flags)) mismatch = cls.claim(a, r, &d.reason);
            if (mismatch >= 0) {
                // Not a hit at all: nothing to excuse.
            } else if (a.is_hit() == b.is_hit() && (!a.is_hit() || query == Query::kAny)) {
                ++local.agree;
                continue;
            } else if (query == Query::kClosest && a.is_hit() && b.is_hit() && a.tri == b.tri &&
                       cls.same_t(a.t, b.t, r, a.tri)) {
                ++local.agree;
                local.max_rel_dt = std::max(local.max_rel_dt, rel_dt(a.t, b.t));
                continue;
            } else if (query == Query::kClosest) {
                const bool a_closer = a.is_hit() && (!b.is_hit() || a.t <= b.t);
                const Hit& closer = a_closer ? a : b;
                const bool same_t = a.is_hit() && b.is_hit() && cls.same_t(a.t, b.t, r, a.tri);
                if (same_t && !cls.near_edge(a, r) && !cls.near_edge(b, r) && cls.coincident(r, a.tri, b.tri)) {
                    // Overlapping surfaces (duplicate or z-fighting triangles), both hit well
                    // inside at the same t in double precision: either answer is right.
                    kind = int(TieKind::kCoincident);
                } else if (same_t && cls.share_vertex(a.tri, b.tri)) {
                    kind = int(TieKind::kSharedEdgeOrVertex);
                } else {
                    kind = cls.tie_for(closer, r);
                    if (kind < 0 && same_t && cls.coincident(r, a.tri, b.tri)) kind = int(TieKind::kCoincident);
                }
                mismatch = int(!b.is_hit()   ? MismatchKind::kExtraHit
                               : !a.is_hit() ? MismatchKind::kMissedHit
                               : a_closer    ? MismatchKind::kCloserHit
                                             : MismatchKind::kFartherHit);
                d.reason = std::string(a_closer ? "ours" : "oracle") + " is closer: triangle " +
                           std::to_string(closer.tri) + " at t=" + std::to_string(closer.t);
            } else {
                // Any-hit: only one side hit. Find a triangle that side found.
                Hit h = a.is_hit() ? a : lookup(r);
                if (h.is_hit()) {
                    kind = cls.tie_for(h, r);
                    d.reason = std::string(a.is_hit() ? "only ours" : "only the oracle") + " hit: triangle " +
                               std::to_string(h.tri) + " at t=" + std::to_string(h.t);
                } else {
                    d.reason = "oracle reports occlusion but its closest-hit query finds nothing";
                }
                if (!a.is_hit()) d.oracle = h;
                mismatch = int(a.is_hit() ? MismatchKind::kExtraHit : MismatchKind::kMissedHit);
            }
            if (kind < 0) d.reason = std::string(mismatch_kind_name(MismatchKind(mismatch))) + ": " + d.reason;
            d.tie = kind >= 0;
            d.kind = d.tie ? kind : mismatch;
            // A chunk's first few of each sort are enough to keep the global lowest indices.
            if (d.tie ? local.ties < 4 : local.mismatches < 16) found.push_back(std::move(d));
            if (d.tie) {
                ++local.ties;
                ++local.ties_by_kind[size_t(kind)];
            } else {
                ++local.mismatches;
                ++local.mismatches_by_kind[size_t(mismatch)];
            }
        }
        std::lock_guard<std::mutex> lock(mu);
        rep.agree += local.agree;
        rep.ties += local.ties;
        rep.mismatches += local.mismatches;
        for (size_t k = 0; k < size_t(kTieKinds); ++k) rep.ties_by_kind[k] += local.ties_by_kind[k];
        for (size_t k = 0; k < size_t(kMismatchKinds); ++k) rep.mismatches_by_kind[k] += local.mismatches_by_kind[k];
        rep.max_rel_dt = std::max(rep.max_rel_dt, local.max_rel_dt);
        for (auto& d : found) {
            auto& list = d.tie ? rep.first_ties : rep.first_mismatches;
            list.push_back(std::move(d));
        }
    });
    // Keep the lowest ray indices so the report does not depend on thread scheduling.
    auto trim = [](std::vector<Disagreement>& v, size_t n) {
        std::sort(v.begin(), v.end(), [](const auto& x, const auto& y) { return x.ray < y.ray; });
        if (v.size() > n) v.resize(n);
    };
    trim(rep.first_mismatches, 16);
    trim(rep.first_ties, 4);
    return rep;
}

nlohmann::json report_json(const CompareReport& rep, const CompareConfig& cfg) {
    nlohmann::json j;
    j["rays"] = rep.rays;
    j["agree"] = rep.agree;
    j["ties"] = rep.ties;
    j["ties_shared_edge"] = rep.ties_by_kind[size_t(TieKind::kSharedEdgeOrVertex)];
    j["ties_near_edge"] = rep.ties_by_kind[size_t(TieKind::kNearEdge)];
    j["ties_interval_end"] = rep.ties_by_kind[size_t(TieKind::kIntervalEnd)];
    j["ties_coincident"] = rep.ties_by_kind[size_t(TieKind::kCoincident)];
    j["mismatches"] = rep.mismatches;
    nlohmann::json kinds = nlohmann::json::object();
    for (int k = 0; k < kMismatchKinds; ++k)
        kinds[mismatch_kind_name(MismatchKind(k))] = rep.mismatches_by_kind[size_t(k)];
    j["mismatch_kinds"] = kinds;
    j["max_rel_dt"] = rep.max_rel_dt;
    j["edge_eps"] = cfg.edge_eps;
    j["t_rel_tol"] = cfg.t_rel_tol;
    return j;
}

}  // namespace bvhlab::trav
