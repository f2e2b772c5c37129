// SPDX-License-Identifier: MIT
// SAH and EPO on hand-built trees, and triangle clipping.
#include <gtest/gtest.h>

#include "accel/core/clip.h"
#include "accel/core/stats.h"
#include "tests/support/test_support.h"

namespace bvhlab::accel {

TEST(ClipTriangle, InsideOutsideAndHalf) {
    const Vec3 a{0, 0, 0}, b{2, 0, 0}, c{0, 2, 0};
    EXPECT_NEAR(clip_triangle(a, b, c, {{-1, -1, -1}, {3, 3, 1}}).area, 2.0, 1e-9);
    EXPECT_EQ(clip_triangle(a, b, c, {{5, 5, 5}, {6, 6, 6}}).area, 0.0);
    ClipResult half = clip_triangle(a, b, c, {{-1, -1, -1}, {1, 3, 1}});  // x <= 1
    EXPECT_NEAR(half.area, 2.0 - 0.5, 1e-9);
    EXPECT_FLOAT_EQ(half.bounds.hi.x, 1.0f);
    EXPECT_FLOAT_EQ(half.bounds.hi.y, 2.0f);
}

TEST(TreeStats, SahOfHandBuiltTree) {
    // Two unit triangles far apart on x; root over both, one leaf each.
    TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {9, 0, 0, 10, 0, 0, 9, 1, 0}});
    BuildTree t;
    t.prim_indices = {0, 1};
    t.nodes = {{{{0, 0, 0}, {10, 1, 0}}, 1, 0}, {m.triangle_bounds(0), 0, 1}, {m.triangle_bounds(1), 1, 1}};
    BuildConfig c;
    TreeStats s = compute_stats(t, m, c);
    // root: Ct * 1; leaves: Ci * 1 * (1 / 10) each (flat boxes: half areas 1 and 10).
    EXPECT_NEAR(s.sah, 1.0 + 0.1 + 0.1, 1e-6);
    EXPECT_EQ(s.nodes, 3u);
    EXPECT_EQ(s.leaves, 2u);
    EXPECT_EQ(s.depth, 1u);
    EXPECT_NEAR(s.epo, 0.0, 1e-12);  // no triangle lies inside another subtree's box
}

TEST(TreeStats, EpoCountsOverlap) {
    // Triangle 1 crosses leaf 0's box, which does not contain it: its part inside that box
    // counts once (Ci = 1) against the total area.
    TriangleMesh m = test::mesh_of({{0, 0, 0, 2, 0, 0, 0, 2, 0}, {1, -1, 0, 3, -1, 0, 1, 1, 0}});
    BuildTree t;
    t.prim_indices = {0, 1};
    AABB root = merge(m.triangle_bounds(0), m.triangle_bounds(1));
    t.nodes = {{root, 1, 0}, {m.triangle_bounds(0), 0, 1}, {m.triangle_bounds(1), 1, 1}};
    BuildConfig c;
    TreeStats s = compute_stats(t, m, c);
    const double inside01 = clip_triangle(m.vertex(1, 0), m.vertex(1, 1), m.vertex(1, 2), m.triangle_bounds(0)).area;
    const double inside10 = clip_triangle(m.vertex(0, 0), m.vertex(0, 1), m.vertex(0, 2), m.triangle_bounds(1)).area;
    EXPECT_GT(inside01, 0.0);
    EXPECT_NEAR(s.epo, (inside01 + inside10) / m.surface_area(), 1e-9);
}

}  // namespace bvhlab::accel
