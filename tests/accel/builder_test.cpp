// SPDX-License-Identifier: MIT
// Property tests of every builder on seeded soups and structured scenes, plus edge cases.
#include <gtest/gtest.h>

#include <string>
#include <tuple>

#include "accel/builders/binned_sah.h"
#include "accel/builders/builder.h"
#include "accel/core/check.h"
#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "scene/io/procedural.h"
#include "tests/support/test_support.h"

namespace bvhlab::accel {
namespace {

using Param = std::tuple<BuilderKind, scene::ProceduralKind, uint64_t /*triangles*/, uint64_t /*seed*/>;

class BuilderProperty : public ::testing::TestWithParam<Param> {};

TEST_P(BuilderProperty, TreeIsValid) {
    const auto [builder, kind, n, seed] = GetParam();
    scene::TriangleMesh mesh = scene::make_procedural(kind, n, seed);
    BuilderOptions opts;
    BuildResult r = run_builder(builder, mesh, opts);
    // validate(): every triangle exactly once, children inside parents, leaf limits, depth.
    EXPECT_EQ(validate(r.tree, mesh, opts.config), "");
    TreeStats s = compute_stats(r.tree, mesh, opts.config, /*with_epo=*/n <= 20000);
    EXPECT_EQ(s.references, mesh.triangle_count());
    EXPECT_EQ(s.nodes, 2 * s.leaves - 1);
    EXPECT_LE(s.max_leaf_size, opts.config.max_leaf_size);
    // Against the quality reference, the full sweep: a tree built badly (say, split at random)
    // lands far above it.
    const TreeStats sweep = compute_stats(run_builder(BuilderKind::kSweep, mesh, opts).tree, mesh, opts.config, false);
    EXPECT_LE(s.sah, 1.15 * sweep.sah);
}

TEST(BuilderSah, HandComputedOnTwoTriangles) {
    // Two unit triangles in z = 0, ten units apart along x. Every builder must split them
    // (leaf cost 2 against 1 + 2/11), so SAH = Ct * 1 + Ci * (1/11 + 1/11): the root box has
    // half area 11 x 1, each leaf box 1 x 1 (flat in z).
    scene::TriangleMesh m;
    scene::add_triangle_checked(m, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, -1);
    scene::add_triangle_checked(m, {10, 0, 0}, {11, 0, 0}, {10, 1, 0}, -1);
    for (BuilderKind b : {BuilderKind::kBinned, BuilderKind::kSweep, BuilderKind::kSbvh}) {
        SCOPED_TRACE(builder_name(b));
        BuilderOptions o;
        const TreeStats s = compute_stats(run_builder(b, m, o).tree, m, o.config, false);
        EXPECT_EQ(s.nodes, 3u);
        EXPECT_NEAR(s.sah, 1.0 + 2.0 / 11.0, 1e-6);
    }
}

TEST_P(BuilderProperty, Deterministic) {
    const auto [builder, kind, n, seed] = GetParam();
    scene::TriangleMesh mesh = scene::make_procedural(kind, n, seed);
    BuildResult a = run_builder(builder, mesh, {});
    BuildResult b = run_builder(builder, mesh, {});
    ASSERT_EQ(a.tree.nodes.size(), b.tree.nodes.size());
    EXPECT_EQ(a.tree.prim_indices, b.tree.prim_indices);
    for (size_t i = 0; i < a.tree.nodes.size(); ++i) {
        EXPECT_EQ(a.tree.nodes[i].first_index, b.tree.nodes[i].first_index);
        EXPECT_EQ(a.tree.nodes[i].prim_count, b.tree.nodes[i].prim_count);
    }
}

INSTANTIATE_TEST_SUITE_P(Soups, BuilderProperty,
                         ::testing::Combine(::testing::Values(BuilderKind::kBinned, BuilderKind::kSweep),
                                            ::testing::Values(scene::ProceduralKind::kSoup,
                                                              scene::ProceduralKind::kStructured),
                                            ::testing::Values(1, 2, 17, 1000, 50000), ::testing::Values(1, 99)));

TEST(BinnedSahBuilder, IdenticalTrianglesFallBackToMedianSplits) {
    scene::TriangleMesh m;
    for (int i = 0; i < 1000; ++i) scene::add_triangle_checked(m, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, -1);
    for (BuilderKind k : {BuilderKind::kBinned, BuilderKind::kSweep}) {
        BuilderOptions o;
        BuildResult r = run_builder(k, m, o);
        EXPECT_EQ(validate(r.tree, m, o.config), "");
    }
}

TEST(BinnedSahBuilder, DepthLimitIsKept) {
    scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 20000, 3);
    BuilderOptions o;
    o.config.max_depth = 14;  // log2(20000 / 8) = 11.3, so this forces median splits
    o.config.max_leaf_size = 8;
    for (BuilderKind k : {BuilderKind::kBinned, BuilderKind::kSweep}) {
        BuildResult r = run_builder(k, m, o);
        EXPECT_EQ(validate(r.tree, m, o.config), "");
        EXPECT_LT(compute_stats(r.tree, m, o.config, false).depth, 14u);
    }
}

TEST(BinnedSahBuilder, LeafSizeOneAndLargeLeaves) {
    scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kStructured, 3000, 5);
    for (uint32_t max_leaf : {1u, 3u, 32u}) {
        BuilderOptions o;
        o.config.max_leaf_size = max_leaf;
        BuildResult r = run_builder(BuilderKind::kBinned, m, o);
        EXPECT_EQ(validate(r.tree, m, o.config), "");
        EXPECT_LE(compute_stats(r.tree, m, o.config, false).max_leaf_size, max_leaf);
    }
}

TEST(BinnedSahBuilder, SweepOfTheLargestSmallNodeIsExact) {
    // sweep_threshold's largest value, 64: a 64-triangle scene is one small node whose exact
    // sweep must give the full-sweep builder's tree (every triangle once, the same SAH).
    for (uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
        const scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 64, seed);
        BinnedSahBuilder::Config cfg;
        cfg.sweep_threshold = 64;
        cfg.max_leaf_size = 4;
        const BuildTree t = BinnedSahBuilder(cfg).build(m);
        ASSERT_EQ(validate(t, m, cfg), "") << "seed " << seed;
        BuilderOptions o;
        o.config.max_leaf_size = 4;
        const double sweep = compute_stats(run_builder(BuilderKind::kSweep, m, o).tree, m, o.config, false).sah;
        EXPECT_NEAR(compute_stats(t, m, cfg, false).sah, sweep, 1e-4 * sweep) << "seed " << seed;
    }
}

TEST(BinnedSahBuilder, RejectsEmptyMeshAndBadConfig) {
    EXPECT_THROW(run_builder(BuilderKind::kBinned, scene::TriangleMesh{}, {}), Error);
    EXPECT_THROW(run_builder(BuilderKind::kSweep, scene::TriangleMesh{}, {}), Error);
    BuilderOptions o;
    o.num_bins = 1;
    EXPECT_THROW(run_builder(BuilderKind::kBinned, scene::make_procedural(scene::ProceduralKind::kSoup, 10, 1), o),
                 Error);
}

TEST(BinnedSahBuilder, SahWithinThreePercentOfFullSweep) {
    for (scene::ProceduralKind k : {scene::ProceduralKind::kStructured, scene::ProceduralKind::kSoup}) {
        scene::TriangleMesh m = scene::make_procedural(k, 30000, 4);
        BuilderOptions o;
        const double binned = compute_stats(run_builder(BuilderKind::kBinned, m, o).tree, m, o.config, false).sah;
        const double sweep = compute_stats(run_builder(BuilderKind::kSweep, m, o).tree, m, o.config, false).sah;
        EXPECT_LE(binned, 1.03 * sweep);
        EXPECT_GE(binned, 0.97 * sweep);
    }
}

TEST(Validate, CatchesBrokenTrees) {
    scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 100, 1);
    BuilderOptions o;
    BuildTree t = run_builder(BuilderKind::kBinned, m, o).tree;
    ASSERT_EQ(validate(t, m, o.config), "");
    BuildTree dup = t;
    dup.prim_indices[0] = dup.prim_indices[1];
    EXPECT_NE(validate(dup, m, o.config), "");
    BuildTree shrunk = t;
    shrunk.nodes[1].bounds.hi.x += 10.0f;  // child sticks out of the root
    EXPECT_NE(validate(shrunk, m, o.config), "");
    // A node that no parent reaches (a copy of a leaf appended at the end): every triangle is
    // still referenced once, so only the reachability check can see it.
    BuildTree orphan = t;
    uint32_t leaf = 0;
    while (!orphan.nodes[leaf].is_leaf()) ++leaf;
    orphan.nodes.push_back(orphan.nodes[leaf]);
    orphan.nodes.back().prim_count = 0;
    EXPECT_EQ(validate(orphan, m, o.config), "node " + std::to_string(t.nodes.size()) + " is unreachable");
    BuildTree big = t;
    o.config.max_leaf_size = 0;
    EXPECT_NE(validate(big, m, o.config), "");
}

}  // namespace
}  // namespace bvhlab::accel
