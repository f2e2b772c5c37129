// SPDX-License-Identifier: MIT
// SAH and EPO on hand-built trees, and triangle clipping.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "accel/builders/builder.h"
#include "accel/core/clip.h"
#include "accel/core/stats.h"
#include "scene/io/procedural.h"
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

// A clipped part split again (a kd-tree's kept polygon) bounds what the triangle clipped to
// the smaller box anew bounds, to the float rounding of its vertices; its parts are in order.
TEST(ClipTriangle, SplitPolygonAgainMatchesClippingAnew) {
    const Vec3 a{0.1f, 0.2f, 0.3f}, b{3.7f, 0.9f, 1.1f}, c{1.3f, 2.9f, 2.2f};
    const AABB box{{0.5f, 0.4f, 0.2f}, {3.0f, 2.5f, 2.0f}};
    PolygonVertex poly[12];
    const int n = clip_triangle_polygon(a, b, c, box, poly);
    ASSERT_GE(n, 3);
    PolygonVertex lo[24], hi[24];
    int n_lo = 0, n_hi = 0;
    const auto first = split_polygon(poly, n, box, 0, 1.5f, lo, &n_lo, hi, &n_hi);
    const auto same = [](const AABB& x, const AABB& y) {
        return x.lo.x == y.lo.x && x.lo.y == y.lo.y && x.lo.z == y.lo.z && x.hi.x == y.hi.x && x.hi.y == y.hi.y &&
               x.hi.z == y.hi.z;
    };
    const auto whole = split_clipped_triangle(a, b, c, box, 0, 1.5f);  // the same pass, bit for bit
    EXPECT_TRUE(same(first.first, whole.first));
    EXPECT_TRUE(same(first.second, whole.second));
    ASSERT_GE(n_lo, 3);
    ASSERT_GE(n_hi, 3);
    // The lower part split again on y, against clipping the triangle to that box anew.
    AABB left = box;
    left.hi.x = 1.5f;
    PolygonVertex lo2[48], hi2[48];
    int m_lo = 0, m_hi = 0;
    const auto again = split_polygon(lo, n_lo, left, 1, 1.2f, lo2, &m_lo, hi2, &m_hi);
    const auto anew = split_clipped_triangle(a, b, c, left, 1, 1.2f);
    for (int k = 0; k < 3; ++k) {
        const float ulp = 1e-6f;
        EXPECT_NEAR(again.first.lo[k], anew.first.lo[k], ulp) << k;
        EXPECT_NEAR(again.first.hi[k], anew.first.hi[k], ulp) << k;
        EXPECT_NEAR(again.second.lo[k], anew.second.lo[k], ulp) << k;
        EXPECT_NEAR(again.second.hi[k], anew.second.hi[k], ulp) << k;
    }
    EXPECT_FLOAT_EQ(again.first.hi.y, 1.2f);
    EXPECT_FLOAT_EQ(again.second.lo.y, 1.2f);
    // Every vertex of a part lies on its side, and the two parts share the crossings.
    for (int i = 0; i < m_lo; ++i) EXPECT_LE(lo2[i].v[1], double(1.2f));
    for (int i = 0; i < m_hi; ++i) EXPECT_GE(hi2[i].v[1], double(1.2f));
    // A plane below the polygon (its lowest z is the triangle's, 0.3) leaves the lower part
    // empty and the upper one whole.
    const auto miss = split_polygon(poly, n, box, 2, 0.25f, lo, &n_lo, hi, &n_hi);
    EXPECT_TRUE(miss.first.is_empty());
    EXPECT_EQ(n_lo, 0);
    EXPECT_EQ(n_hi, n);
}

TEST(TreeStats, SahOfHandBuiltTree) {
    // Two unit triangles far apart on x; root over both, one leaf each.
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {9, 0, 0, 10, 0, 0, 9, 1, 0}});
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
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 2, 0, 0, 0, 2, 0}, {1, -1, 0, 3, -1, 0, 1, 1, 0}});
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

// EPO and SAH summed over many triangles in parallel (TBB joins partial sums of stolen ranges)
// equal the same figures computed on one thread.
TEST(TreeStats, ParallelFiguresEqualOneThreadsFigures) {
    const scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 30000, 9);
    const BuildTree t = run_builder(BuilderKind::kBinned, m, {}).tree;
    const BuildConfig c;
    TreeStats serial;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = compute_stats(t, m, c);
    }
    tbb::global_control four(tbb::global_control::max_allowed_parallelism, 4);
    for (int run = 0; run < 3; ++run) {
        const TreeStats s = compute_stats(t, m, c);
        EXPECT_NEAR(s.epo, serial.epo, 1e-9 * serial.epo);
        EXPECT_NEAR(s.sah, serial.sah, 1e-9 * serial.sah);
    }
    EXPECT_GT(serial.epo, 0.0);
}

// EPO's work is bounded: a fan of thin triangles around one vertex overlaps every node, so
// the default bound (kEpoTestsPerTriangle a triangle) stops it with a reason instead of taking
// minutes; a small explicit budget stops an ordinary mesh too, and a sufficient one does not.
TEST(TreeStats, EpoStopsAtItsWorkBound) {
    const int n = 20000;
    scene::TriangleMesh fan;
    for (int i = 0; i < n; ++i) {
        const double a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * (i + 1) / n;
        scene::add_triangle_checked(fan, {0, 0, 0}, {float(std::cos(a0)), float(std::sin(a0)), 0},
                                    {float(std::cos(a1)), float(std::sin(a1)), 0}, -1);
    }
    ASSERT_EQ(fan.triangle_count(), size_t(n));
    const BuildTree t = run_builder(BuilderKind::kBinned, fan, {}).tree;
    const TreeStats s = compute_stats(t, fan, BuildConfig{});
    EXPECT_EQ(s.epo, -1.0);
    EXPECT_NE(s.epo_skipped.find("EPO skipped: it needs more than"), std::string::npos) << s.epo_skipped;
    EXPECT_GT(s.sah, 0.0);  // the other figures are still there

    const scene::TriangleMesh soup = scene::make_procedural(scene::ProceduralKind::kSoup, 5000, 3);
    const BuildTree u = run_builder(BuilderKind::kBinned, soup, {}).tree;
    const TreeStats small = compute_stats(u, soup, BuildConfig{}, true, 1 << 16);
    EXPECT_EQ(small.epo, -1.0);
    EXPECT_FALSE(small.epo_skipped.empty());
    const TreeStats full = compute_stats(u, soup, BuildConfig{});
    EXPECT_GT(full.epo, 0.0);
    EXPECT_TRUE(full.epo_skipped.empty());
    const TreeStats off = compute_stats(u, soup, BuildConfig{}, false);
    EXPECT_EQ(off.epo, -1.0);
    EXPECT_TRUE(off.epo_skipped.empty());  // not asked for: nothing to explain
}

}  // namespace bvhlab::accel
