// SPDX-License-Identifier: MIT
// The oracle at its own boundaries. Each tolerance of CompareConfig is tested where it alone
// decides: a planted hit at half its window is accepted, one at twice its window is refused.
// The windows are computed here from the documented constants (not read from CompareConfig),
// so a tolerance made 10x looser, or 10x tighter, in the oracle turns a test red; each test
// also shows that its planted lie would pass under a 10x looser setting.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/test_support.h"
#include "traversal/oracle/compare.h"
#include "traversal/reference/ref_intersect.h"

namespace bvhlab::trav {
namespace {

// The documented defaults (compare.h).
constexpr double kTRel = 1e-4;          // t window, relative to t
constexpr double kTAbsRel = 1e-6;       // t window, relative to |o| + |p| over |d| cos
constexpr double kEdgeEps = 1e-4;       // barycentric window, fixed part
constexpr double kEdgeFloatK = 32;      // barycentric window, float part: k x 2^-24 (|o| + |p|) / (h_min cos)
constexpr double kUlp1 = 5.9604645e-8;  // 2^-24

/// The unit right triangle (0,0,0) (1,0,0) (0,1,0) moved by `offset`; u and v of a point
/// (offset + (x, y, 0)) are x and y.
scene::TriangleMesh unit_triangle(Vec3 offset = {0, 0, 0}) {
    const Vec3 a = offset, b = offset + Vec3{1, 0, 0}, c = offset + Vec3{0, 1, 0};
    return test::mesh_of({{a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z}});
}

/// A ray straight down onto the z = offset.z plane at (offset.x + x, offset.y + y), from `height`.
Ray down(Vec3 offset, double x, double y, float height) {
    return Ray{{float(offset.x + x), float(offset.y + y), offset.z + height}, 0.0f, {0, 0, -1}, INFINITY};
}

/// The kind check_claimed_hit gives (-1: a real hit) under `cfg`.
int claim(const scene::TriangleMesh& m, const Ray& r, const Hit& h, const CompareConfig& cfg = {}) {
    std::string why;
    return check_claimed_hit(m, r, h, &why, cfg);
}

/// Ties and mismatches of one closest-hit ray where we miss and the oracle reports `oracle`.
CompareReport one_missed(const scene::TriangleMesh& m, const Ray& r, const Hit& oracle, const CompareConfig& cfg = {}) {
    return compare_hits(
        m, {r}, Query::kClosest, {Hit::miss()}, {oracle}, [](const Ray&) { return Hit::miss(); }, cfg);
}

double altitude_of_unit_triangle() { return 1.0 / std::sqrt(2.0); }  // h_min of the unit right triangle

}  // namespace

TEST(OracleBounds, RelativeTWindow) {
    // From 1000 above: the t window is 1e-4 x 1000 = 0.1; the absolute part is 1e-6 x 1000 = 1e-3.
    const scene::TriangleMesh m = unit_triangle();
    const Ray r = down({0, 0, 0}, 0.3, 0.2, 1000.0f);
    const double window = kTRel * 1000.0 + kTAbsRel * 1000.0;
    const Hit inside{0, float(1000.0 + 0.5 * window), 0.3f, 0.2f}, outside{0, float(1000.0 + 2.0 * window), 0.3f, 0.2f};
    EXPECT_EQ(claim(m, r, inside), -1);
    EXPECT_EQ(claim(m, r, outside), int(MismatchKind::kWrongT));
    EXPECT_NEAR(t_tolerance(r, 1000.0f, m.vertex(0, 0), m.vertex(0, 1), m.vertex(0, 2)), window, 1e-3 * window);
    // Against the oracle's own hit: the same windows decide agreement.
    const Hit truth{0, 1000.0f, 0.3f, 0.2f};
    auto compare = [&](const Hit& ours, const CompareConfig& cfg = {}) {
        return compare_hits(
            m, {r}, Query::kClosest, {ours}, {truth}, [](const Ray&) { return Hit::miss(); }, cfg);
    };
    EXPECT_EQ(compare(inside).agree, 1u);
    EXPECT_EQ(compare(outside).mismatches_by_kind[size_t(MismatchKind::kWrongT)], 1u);
    CompareConfig loose;
    loose.t_rel_tol *= 10.0f;
    EXPECT_EQ(claim(m, r, outside, loose), -1);  // the lie is within reach of a 10x looser window
    EXPECT_EQ(compare(outside, loose).agree, 1u);
}

TEST(OracleBounds, AbsoluteTWindowFarFromTheOrigin) {
    // A triangle 1e4 from the origin, hit from 1 above: t = 1, so the relative part is 1e-4,
    // and the cancellation part is 1e-6 x (|o| + |p|) = 1e-6 x 2e4 = 0.02.
    const Vec3 off{10000.0f, 0.0f, 0.0f};
    const scene::TriangleMesh m = unit_triangle(off);
    const Ray r = down(off, 0.25, 0.25, 1.0f);
    const double scale = 2.0 * 10000.25;  // |o|_inf + |p|_inf
    const double window = kTRel * 1.0 + kTAbsRel * scale;
    const Hit inside{0, float(1.0 + 0.5 * window), 0.25f, 0.25f}, outside{0, float(1.0 + 2.0 * window), 0.25f, 0.25f};
    EXPECT_EQ(claim(m, r, inside), -1);
    EXPECT_EQ(claim(m, r, outside), int(MismatchKind::kWrongT));
    const Hit early{0, float(1.0 - 2.0 * window), 0.25f, 0.25f};
    EXPECT_EQ(claim(m, r, early), int(MismatchKind::kWrongT));
    CompareConfig loose;
    loose.t_abs_rel *= 10.0f;
    EXPECT_EQ(claim(m, r, outside, loose), -1);
    // The interval-end tie uses the same window: a hit of Embree's just past tmax is excused
    // within it and not beyond it.
    Ray bounded = r;
    bounded.tmax = float(1.0 - 0.5 * window);
    EXPECT_EQ(one_missed(m, bounded, {0, 1.0f, 0.25f, 0.25f}).ties_by_kind[size_t(TieKind::kIntervalEnd)], 1u);
    bounded.tmax = float(1.0 - 2.0 * window);
    EXPECT_EQ(one_missed(m, bounded, {0, 1.0f, 0.25f, 0.25f}).mismatches, 1u);
}

TEST(OracleBounds, FixedBarycentricWindow) {
    // From 1 above a unit triangle: the float part is 32 x 2^-24 x (1 + 0.5) / 0.707 = 4e-6,
    // so the window is edge_eps = 1e-4 to within 5%.
    const scene::TriangleMesh m = unit_triangle();
    const double window = kEdgeEps + kEdgeFloatK * kUlp1 * (1.0 + 0.5) / altitude_of_unit_triangle();
    auto ray_outside_by = [&](double w) {  // through (0.5 + w/2, 0.5 + w/2): 1 - u - v = -w
        return down({0, 0, 0}, 0.5 + 0.5 * w, 0.5 + 0.5 * w, 1.0f);
    };
    const Ray near_ray = ray_outside_by(0.5 * window), far_ray = ray_outside_by(2.0 * window);
    auto uv = [](const Ray& r) { return std::pair<float, float>{r.org.x, r.org.y}; };
    // A claimed hit just outside the hypotenuse is accepted within the window, refused beyond.
    EXPECT_EQ(claim(m, near_ray, {0, 1.0f, uv(near_ray).first, uv(near_ray).second}), -1);
    EXPECT_EQ(claim(m, far_ray, {0, 1.0f, uv(far_ray).first, uv(far_ray).second}), int(MismatchKind::kOffTriangle));
    // A miss of ours where Embree hits: near the edge a tie, farther inside a real mismatch.
    auto ray_inside_by = [&](double w) { return down({0, 0, 0}, 0.5 - 0.5 * w, 0.5 - 0.5 * w, 1.0f); };
    const Ray in_near = ray_inside_by(0.5 * window), in_far = ray_inside_by(2.0 * window);
    EXPECT_EQ(one_missed(m, in_near, {0, 1.0f, in_near.org.x, in_near.org.y}).ties_by_kind[size_t(TieKind::kNearEdge)],
              1u);
    EXPECT_EQ(one_missed(m, in_far, {0, 1.0f, in_far.org.x, in_far.org.y})
                  .mismatches_by_kind[size_t(MismatchKind::kMissedHit)],
              1u);
    // Reported u and v: off by half the window accepted, by twice refused.
    const Ray mid = down({0, 0, 0}, 0.25, 0.25, 1.0f);
    EXPECT_EQ(claim(m, mid, {0, 1.0f, float(0.25 + 0.5 * window), 0.25f}), -1);
    EXPECT_EQ(claim(m, mid, {0, 1.0f, float(0.25 + 2.0 * window), 0.25f}), int(MismatchKind::kWrongUv));
    EXPECT_EQ(claim(m, mid, {0, 1.0f, 0.25f, float(0.25 - 2.0 * window)}), int(MismatchKind::kWrongUv));
    CompareConfig loose;
    loose.edge_eps *= 10.0f;
    EXPECT_EQ(claim(m, far_ray, {0, 1.0f, uv(far_ray).first, uv(far_ray).second}, loose), -1);
    EXPECT_EQ(claim(m, mid, {0, 1.0f, float(0.25 + 2.0 * window), 0.25f}, loose), -1);
    EXPECT_EQ(one_missed(m, in_far, {0, 1.0f, in_far.org.x, in_far.org.y}, loose).ties, 1u);
}

TEST(OracleBounds, FloatBarycentricWindowGrowsWithDistance) {
    // From 1000 above: the float part is 32 x 2^-24 x 1000.5 / 0.707 = 2.7e-3, 27x edge_eps.
    // Points near 0.5 are placed to 6e-8, far finer than the window.
    const scene::TriangleMesh m = unit_triangle();
    const double window = kEdgeEps + kEdgeFloatK * kUlp1 * (1000.0 + 0.5) / altitude_of_unit_triangle();
    auto ray_outside_by = [&](double w) { return down({0, 0, 0}, 0.5 + 0.5 * w, 0.5 + 0.5 * w, 1000.0f); };
    const Ray near_ray = ray_outside_by(0.5 * window), far_ray = ray_outside_by(2.0 * window);
    EXPECT_EQ(claim(m, near_ray, {0, 1000.0f, near_ray.org.x, near_ray.org.y}), -1);
    EXPECT_EQ(claim(m, far_ray, {0, 1000.0f, far_ray.org.x, far_ray.org.y}), int(MismatchKind::kOffTriangle));
    auto ray_inside_by = [&](double w) { return down({0, 0, 0}, 0.5 - 0.5 * w, 0.5 - 0.5 * w, 1000.0f); };
    const Ray in_near = ray_inside_by(0.5 * window), in_far = ray_inside_by(2.0 * window);
    EXPECT_EQ(one_missed(m, in_near, {0, 1000.0f, in_near.org.x, in_near.org.y}).ties, 1u);
    EXPECT_EQ(one_missed(m, in_far, {0, 1000.0f, in_far.org.x, in_far.org.y}).mismatches, 1u);
    // Grazing incidence widens it by 1 / cos: at 60 degrees from the normal, twice.
    const float s = std::sqrt(3.0f) / 2.0f;
    const double graze_window =
        kEdgeEps + kEdgeFloatK * kUlp1 * (1000.0 * s + 0.5) / (altitude_of_unit_triangle() * 0.5);
    auto slanted = [&](double w) {  // 1000 along (s, 0, -1/2) from the point (0.5 - w/2, 0.5 - w/2)
        const double x = 0.5 - 0.5 * w, y = 0.5 - 0.5 * w;
        return Ray{{float(x - 1000.0 * s), float(y), 500.0f}, 0.0f, {s, 0.0f, -0.5f}, INFINITY};
    };
    const Ray g_near = slanted(0.5 * graze_window), g_far = slanted(2.0 * graze_window);
    auto plane_hit = [&](const Ray& r) {
        double t, u, v;
        EXPECT_TRUE(plane_hit_reference(r, m.vertex(0, 0), m.vertex(0, 1), m.vertex(0, 2), t, u, v));
        return Hit{0, float(t), float(u), float(v)};
    };
    EXPECT_EQ(one_missed(m, g_near, plane_hit(g_near)).ties, 1u);
    EXPECT_EQ(one_missed(m, g_far, plane_hit(g_far)).mismatches, 1u);
    CompareConfig loose;
    loose.edge_float_k *= 10.0f;
    EXPECT_EQ(claim(m, far_ray, {0, 1000.0f, far_ray.org.x, far_ray.org.y}, loose), -1);
    EXPECT_EQ(one_missed(m, in_far, {0, 1000.0f, in_far.org.x, in_far.org.y}, loose).ties, 1u);
    EXPECT_EQ(one_missed(m, g_far, plane_hit(g_far), loose).ties, 1u);
}

}  // namespace bvhlab::trav
