// SPDX-License-Identifier: MIT
// SBVH: validity with duplicates, full coverage of every triangle by its leaves' clipped parts,
// the reference budget, and that spatial splits pay off on long thin triangles.
#include "accel/builders/sbvh.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "accel/builders/builder.h"
#include "accel/core/check.h"
#include "accel/core/clip.h"
#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "scene/io/procedural.h"
#include "tests/support/edge_rays.h"

namespace bvhlab::accel {
namespace {

/// Long thin triangles that all pass through the centre in random directions (a "star"):
/// no object split can separate them, spatial splits can.
scene::TriangleMesh star_slivers(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, 1.0f);
    scene::TriangleMesh m;
    const Vec3 c{0.5f, 0.5f, 0.5f};
    for (int i = 0; i < n; ++i) {
        Vec3 d{g(rng), g(rng), g(rng)};
        d = d * (0.5f / length(d));
        Vec3 e = cross(d, Vec3{0.3f, 0.7f, 0.1f});
        e = e * (0.002f / length(e));
        scene::add_triangle_checked(m, c - d, c + d, c + d + e, -1);
    }
    return m;
}

/// Every triangle's area is covered by the clipped parts in the leaves that reference it.
void expect_full_coverage(const BuildTree& t, const scene::TriangleMesh& m) {
    std::vector<double> covered(m.triangle_count(), 0.0);
    for (const BuildNode& n : t.nodes) {
        if (!n.is_leaf()) continue;
        for (uint32_t k = n.first_index; k < n.first_index + n.prim_count; ++k) {
            const uint32_t id = t.prim_indices[k];
            covered[id] += clip_triangle(m.vertex(id, 0), m.vertex(id, 1), m.vertex(id, 2), n.bounds).area;
        }
    }
    for (size_t i = 0; i < covered.size(); ++i) {
        const Vec3 a = m.vertex(i, 0), b = m.vertex(i, 1), c = m.vertex(i, 2);
        const double area = 0.5 * double(length(cross(b - a, c - a)));
        ASSERT_GE(covered[i], area * (1.0 - 1e-4)) << "triangle " << i << " is not fully inside its leaves";
    }
}

}  // namespace

class SbvhProperty : public ::testing::TestWithParam<std::tuple<scene::ProceduralKind, uint64_t>> {};

TEST_P(SbvhProperty, ValidAndCovering) {
    const auto [kind, n] = GetParam();
    scene::TriangleMesh m = scene::make_procedural(kind, n, 13);
    SbvhBuilder::Config c;
    BuildTree t = SbvhBuilder(c).build(m);
    ValidateOptions vo;
    vo.allow_duplicates = true;
    EXPECT_EQ(validate(t, m, c, vo), "");
    expect_full_coverage(t, m);
    const TreeStats s = compute_stats(t, m, c, false);
    EXPECT_GE(s.references, m.triangle_count());
    EXPECT_LE(double(s.references), c.reference_budget * double(m.triangle_count()) + 1.0);
}

INSTANTIATE_TEST_SUITE_P(Scenes, SbvhProperty,
                         ::testing::Combine(::testing::Values(scene::ProceduralKind::kSoup,
                                                              scene::ProceduralKind::kStructured),
                                            ::testing::Values(1, 7, 500, 20000)));

TEST(SbvhBuilder, LeafBoxesHoldEveryEdgeCrossingExactly) {
    // Where a triangle's edge crosses a face plane of a leaf box that references it, the
    // crossing (in double precision) lies in one of those leaf boxes: spatial splits round the
    // clipped bounds outwards. Rounded to nearest, they miss crossings by up to half an ulp,
    // which the traversal's slab widening happens to absorb; the boxes must not rely on it.
    for (const scene::TriangleMesh& m :
         {test::make_lattice_scene(1), test::make_lattice_scene(2), star_slivers(300, 5)}) {
        const BuildTree t = run_builder(BuilderKind::kSbvh, m, {}).tree;
        std::vector<std::vector<AABB>> boxes(m.triangle_count());
        for (const BuildNode& n : t.nodes)
            if (n.is_leaf())
                for (uint32_t i = n.first_index; i < n.first_index + n.prim_count; ++i)
                    boxes[t.prim_indices[i]].push_back(n.bounds);
        size_t checked = 0, outside = 0;
        std::string first;
        for (size_t id = 0; id < m.triangle_count(); ++id) {
            for (const AABB& face_box : boxes[id]) {
                for (int k = 0; k < 3; ++k) {
                    for (const double f : {double(face_box.lo[k]), double(face_box.hi[k])}) {
                        for (int e = 0; e < 3; ++e) {
                            const Vec3 p = m.vertex(id, e), q = m.vertex(id, (e + 1) % 3);
                            if (!((double(p[k]) - f) * (double(q[k]) - f) < 0.0)) continue;
                            const double s = (f - double(p[k])) / (double(q[k]) - double(p[k]));
                            double x[3];
                            for (int j = 0; j < 3; ++j) x[j] = double(p[j]) + s * (double(q[j]) - double(p[j]));
                            x[k] = f;
                            ++checked;
                            auto inside = [&](const AABB& b) {
                                for (int j = 0; j < 3; ++j) {
                                    const double slack = 4e-16 * std::max(1.0, std::fabs(x[j]));  // double rounding
                                    if (x[j] < double(b.lo[j]) - slack || x[j] > double(b.hi[j]) + slack) return false;
                                }
                                return true;
                            };
                            if (std::none_of(boxes[id].begin(), boxes[id].end(), inside) && outside++ == 0)
                                first = "triangle " + std::to_string(id) + " at (" + std::to_string(x[0]) + ", " +
                                        std::to_string(x[1]) + ", " + std::to_string(x[2]) + ")";
                        }
                    }
                }
            }
        }
        EXPECT_GT(checked, 200u);
        EXPECT_EQ(outside, 0u) << "first: " << first;
    }
}

TEST(SbvhBuilder, SplitsLongThinTriangles) {
    scene::TriangleMesh m = star_slivers(3000, 5);
    BuilderOptions o;
    const BuildTree sbvh = run_builder(BuilderKind::kSbvh, m, o).tree;
    const BuildTree sweep = run_builder(BuilderKind::kSweep, m, o).tree;
    const TreeStats s = compute_stats(sbvh, m, o.config, false);
    const TreeStats w = compute_stats(sweep, m, o.config, false);
    EXPECT_GT(s.references, m.triangle_count() * 3 / 2);  // spatial splits happened
    EXPECT_LT(s.sah, 0.85 * w.sah);                       // and paid off (measured: 0.79x)
    expect_full_coverage(sbvh, m);
}

TEST(SbvhBuilder, BudgetOfOneMeansNoDuplicates) {
    scene::TriangleMesh m = star_slivers(2000, 6);
    SbvhBuilder::Config c;
    c.reference_budget = 1.0f;
    BuildTree t = SbvhBuilder(c).build(m);
    EXPECT_EQ(t.prim_indices.size(), m.triangle_count());
    EXPECT_EQ(validate(t, m, c), "");  // exactly once, like an object-split BVH
}

// When the budget runs out, which references get split must not depend on which thread got
// there first: the same tree with 1 or 2 threads, run after run.
TEST(SbvhBuilder, BindingBudgetIsDeterministic) {
    scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 60000, 8);
    SbvhBuilder::Config c;
    c.reference_budget = 1.02f;
    c.alpha = 0.0f;  // spatial splits wanted everywhere, so the budget binds
    c.spatial_margin = 0.0f;
    c.task_threshold = 256;  // plenty of parallel subtrees
    const auto build_with = [&](size_t threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return SbvhBuilder(c).build(m);
    };
    const BuildTree one = build_with(1);
    EXPECT_LE(double(one.prim_indices.size()), 1.02 * double(m.triangle_count()) + 1.0);
    EXPECT_GT(one.prim_indices.size(), m.triangle_count());  // some splits were paid for
    {
        SbvhBuilder::Config unlimited = c;
        unlimited.reference_budget = 16.0f;
        // ... and many more were wanted: the budget binds (refused splits depend on it).
        EXPECT_GT(double(SbvhBuilder(unlimited).build(m).prim_indices.size()), 1.1 * double(m.triangle_count()));
    }
    for (int run = 0; run < 3; ++run) {
        const BuildTree two = build_with(2);
        ASSERT_EQ(two.nodes.size(), one.nodes.size());
        ASSERT_EQ(two.prim_indices, one.prim_indices);
        for (size_t i = 0; i < one.nodes.size(); ++i) {
            ASSERT_EQ(two.nodes[i].first_index, one.nodes[i].first_index) << i;
            for (int k = 0; k < 3; ++k) {
                ASSERT_EQ(two.nodes[i].bounds.lo[k], one.nodes[i].bounds.lo[k]) << i;
                ASSERT_EQ(two.nodes[i].bounds.hi[k], one.nodes[i].bounds.hi[k]) << i;
            }
        }
    }
}

// The spatial margin drops the marginal spatial splits that a finely tessellated surface
// offers everywhere, and keeps the ones long thin triangles need.
TEST(SbvhBuilder, SpatialMarginDropsMarginalSplits) {
    const scene::TriangleMesh surface = scene::make_procedural(scene::ProceduralKind::kStructured, 40000, 9);
    const scene::TriangleMesh star = star_slivers(3000, 9);
    SbvhBuilder::Config c;
    c.reinsertion_passes = 0;
    c.spatial_margin = 0.0f;
    const size_t surface_all = SbvhBuilder(c).build(surface).prim_indices.size();
    const size_t star_all = SbvhBuilder(c).build(star).prim_indices.size();
    c.spatial_margin = 0.1f;
    const size_t surface_margin = SbvhBuilder(c).build(surface).prim_indices.size();
    const size_t star_margin = SbvhBuilder(c).build(star).prim_indices.size();
    std::printf("surface refs %zu -> %zu, star refs %zu -> %zu\n", surface_all, surface_margin, star_all, star_margin);
    EXPECT_LT(double(surface_margin - surface.triangle_count()), 0.5 * double(surface_all - surface.triangle_count()));
    EXPECT_GT(double(star_margin), 0.9 * double(star_all));
    c.spatial_margin = 1.0f;
    EXPECT_THROW(SbvhBuilder(c).build(star), Error);
}

TEST(SbvhBuilder, HugeAlphaDisablesSpatialSplits) {
    scene::TriangleMesh m = star_slivers(2000, 7);
    SbvhBuilder::Config c;
    c.alpha = 1e9f;
    EXPECT_EQ(SbvhBuilder(c).build(m).prim_indices.size(), m.triangle_count());
}

TEST(SbvhBuilder, RejectsBadConfig) {
    scene::TriangleMesh m = star_slivers(10, 1);
    SbvhBuilder::Config c;
    c.reference_budget = 0.5f;
    EXPECT_THROW(SbvhBuilder(c).build(m), Error);
    c = {};
    c.spatial_bins = 1;
    EXPECT_THROW(SbvhBuilder(c).build(m), Error);
    EXPECT_THROW(SbvhBuilder().build(scene::TriangleMesh{}), Error);
}

}  // namespace bvhlab::accel
