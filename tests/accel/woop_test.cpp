// SPDX-License-Identifier: MIT
// Woop's unit-triangle test against the double-precision reference, on random and
// near-degenerate triangles.
#include <gtest/gtest.h>

#include <random>

#include "accel/layouts/woop_tri.h"
#include "traversal/reference/ref_intersect.h"

namespace bvhlab {
namespace {

struct Counts {
    int agree = 0, near_edge = 0, disagree = 0, hits = 0, grazing = 0;
};

/// Fires rays at random points around each triangle and compares with the reference.
Counts compare_random(std::mt19937& rng, float sliver, int triangles, int rays_per_tri) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Counts c;
    for (int k = 0; k < triangles; ++k) {
        Vec3 v0{u(rng), u(rng), u(rng)}, v1{u(rng), u(rng), u(rng)};
        // v2 lies near the line v0-v1 when sliver is small: a near-degenerate triangle.
        Vec3 mid = (v0 + v1) * 0.5f;
        Vec3 v2 = mid + Vec3{u(rng), u(rng), u(rng)} * sliver;
        if (scene::check_triangle(v0, v1, v2) != scene::TriangleCheck::kOk) continue;
        const accel::WoopTriangle w = accel::make_woop_triangle(v0, v1, v2);
        for (int r = 0; r < rays_per_tri; ++r) {
            // Aim at a point with barycentrics slightly outside [0,1] too.
            float b1 = 0.6f * (u(rng) + 1.0f) - 0.1f, b2 = 0.6f * (u(rng) + 1.0f) - 0.1f;
            Vec3 target = v0 + (v1 - v0) * b1 + (v2 - v0) * b2;
            Vec3 org{3.0f * u(rng), 3.0f * u(rng), 3.0f + u(rng)};
            trav::Ray ray{org, 0.0f, target - org, INFINITY};
            // Float error in t and the barycentrics grows as 1 / cos(angle to the normal) and,
            // for the barycentrics, as 1 / sliver: scale the tolerances accordingly.
            const Vec3 n = cross(v1 - v0, v2 - v0);
            const double cosv = std::fabs(dot(n, ray.dir)) / (double(length(n)) * length(ray.dir));
            if (cosv < 1e-3) {
                ++c.grazing;
                continue;
            }
            // Woop's u = ox + t dx inherits t's error times |row1 . d| ~ |d| / altitude.
            const double alt = 2.0 * 0.5 * length(n) / std::max({length(v1 - v0), length(v2 - v1), length(v0 - v2)});
            const double tol_t = 1e-5 / cosv;
            const double tol_b = 1e-5 + 1e-6 * (length(org) + length(ray.dir)) / (alt * cosv);
            double rt, ru, rv;
            const bool ref = trav::intersect_reference(ray, v0, v1, v2, rt, ru, rv);
            float t, uu, vv;
            const bool got = w.intersect(ray.org, ray.dir, ray.tmin, ray.tmax, t, uu, vv);
            c.hits += ref;
            if (ref == got) {
                ++c.agree;
                if (ref) {
                    EXPECT_NEAR(t, rt, tol_t * std::max(1.0, rt));
                    EXPECT_NEAR(uu, ru, tol_b);
                    EXPECT_NEAR(vv, rv, tol_b);
                }
            } else if (std::fabs(std::min({ru, rv, 1.0 - ru - rv})) < tol_b) {
                ++c.near_edge;  // within float error of an edge: either answer is right
            } else {
                ++c.disagree;
            }
        }
    }
    return c;
}

}  // namespace

TEST(WoopTriangle, MatchesDoubleReferenceOnRandomTriangles) {
    std::mt19937 rng(7);
    Counts c = compare_random(rng, 1.0f, 2000, 50);
    EXPECT_EQ(c.disagree, 0);
    EXPECT_GT(c.hits, 20000);  // the test really exercises hits
    EXPECT_LT(c.near_edge, c.agree / 1000);
    EXPECT_LT(c.grazing, c.agree / 100);
}

TEST(WoopTriangle, MatchesDoubleReferenceOnSlivers) {
    std::mt19937 rng(11);
    Counts c = compare_random(rng, 1e-3f, 2000, 50);
    EXPECT_EQ(c.disagree, 0);
    EXPECT_GT(c.hits, 1000);
}

TEST(WoopTriangle, BarycentricsFollowEmbreeConvention) {
    const Vec3 v0{0, 0, 0}, v1{1, 0, 0}, v2{0, 1, 0};
    const accel::WoopTriangle w = accel::make_woop_triangle(v0, v1, v2);
    float t, u, v;
    ASSERT_TRUE(w.intersect({0.25f, 0.5f, 1.0f}, {0, 0, -1}, 0.0f, INFINITY, t, u, v));
    EXPECT_FLOAT_EQ(t, 1.0f);
    EXPECT_FLOAT_EQ(u, 0.25f);  // weight of v1
    EXPECT_FLOAT_EQ(v, 0.5f);   // weight of v2
}

TEST(WoopTriangle, RespectsIntervalAndRejectsParallelRays) {
    const accel::WoopTriangle w = accel::make_woop_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    float t, u, v;
    EXPECT_FALSE(w.intersect({0.2f, 0.2f, 1.0f}, {0, 0, -1}, 0.0f, 0.5f, t, u, v));     // beyond tmax
    EXPECT_FALSE(w.intersect({0.2f, 0.2f, 1.0f}, {0, 0, -1}, 1.5f, 9.0f, t, u, v));     // before tmin
    EXPECT_FALSE(w.intersect({0.2f, 0.2f, 1.0f}, {1, 0, 0}, 0.0f, INFINITY, t, u, v));  // parallel
    EXPECT_FALSE(w.intersect({0.2f, 0.2f, 0.0f}, {1, 0, 0}, 0.0f, INFINITY, t, u, v));  // in-plane
    EXPECT_TRUE(w.intersect({0.2f, 0.2f, -1.0f}, {0, 0, 1}, 0.0f, INFINITY, t, u, v));  // back face
}

}  // namespace bvhlab
