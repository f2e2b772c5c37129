// SPDX-License-Identifier: MIT
// The GPU builders' host side: Morton codes, the LBVH's radix tree and its CPU reference, the
// BuildTree of a BVH2 layout, PLOC's CPU reference and the GPU builders' leaf choice, and the
// options, specs and files of lbvh, ploc and hploc; gpu-binned's clusters and their reference. The GPU
// pipeline itself is tested in tests/traversal/gpu_builder_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>

#include "accel/builders/binned_sah.h"
#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/core/check.h"
#include "accel/core/morton.h"
#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "accel/io/tree_file.h"
#include "accel/layouts/bvh2_convert.h"
#include "scene/io/procedural.h"
#include "tests/support/test_support.h"
#include "traversal/factory.h"
#include "traversal/gpu/gpu_builder.h"

namespace bvhlab::accel {
namespace {

TEST(Morton, CodesSpreadAndOrderTheAxes) {
    EXPECT_EQ(morton::spread10(0x3ff), 0x09249249u);
    EXPECT_EQ(morton::spread10(1), 1u);
    EXPECT_EQ(morton::spread20(0xfffff), 0x0249249249249249ull);
    EXPECT_EQ(morton::spread10(0xfffffc01u), 1u);  // only the low 10 (20) bits count
    EXPECT_EQ(morton::spread20(0xfffffffffff00001ull), 1u);
    const Vec3 lo{0, 0, 0};
    EXPECT_EQ(morton::code30({0, 0, 0}, lo, {1, 1, 1}), 0u);
    EXPECT_EQ(morton::code30({1023.5f, 1023.5f, 1023.5f}, lo, {1, 1, 1}), 0x3fffffffu);
    EXPECT_EQ(morton::code30({5000, 0, 0}, lo, {1, 1, 1}), morton::spread10(1023) << 2);  // clamped
    EXPECT_EQ(morton::code30({1, 0, 0}, lo, {1, 1, 1}), 4u);  // x is the highest of each triple
    EXPECT_EQ(morton::code30({0, 1, 0}, lo, {1, 1, 1}), 2u);
    EXPECT_EQ(morton::code30({0, 0, 1}, lo, {1, 1, 1}), 1u);
    EXPECT_EQ(morton::code60({1, 0, 0}, lo, {1, 1, 1}), 4u);
    EXPECT_EQ(morton::code30({-3, 0, 0}, lo, {1, 1, 1}), 0u);  // below the box: cell 0
    EXPECT_EQ(morton::axis_scale(2.0f, 2.0f, 1024), 0.0f);     // a flat axis
    EXPECT_EQ(morton::axis_scale(0.0f, 2.0f, 1024), 512.0f);
}

TEST(Morton, RadixTreeOfKarrassExample) {
    // Karras 2012, figure 3: eight 5-bit keys; the root splits between keys 3 and 4. Interior
    // node n + i splits between keys i and i + 1; leaves are 0..7.
    const RawHierarchy h = radix_tree({0b00001, 0b00010, 0b00100, 0b00101, 0b10011, 0b11000, 0b11001, 0b11110});
    const uint32_t n = 8;
    EXPECT_EQ(h.root, n + 3);
    const std::vector<uint32_t> left{0, n + 0, 2, n + 1, 4, 5, n + 5}, right{1, n + 2, 3, n + 4, n + 6, 6, 7};
    EXPECT_EQ(h.left, left);  // e.g. node 3 (0..3 | 4..7) over nodes 1 (0..1 | 2..3) and 4 (4 | 5..7)
    EXPECT_EQ(h.right, right);
    // Two keys: one interior node; keys out of order or too few are refused.
    const RawHierarchy two = radix_tree({3, 9});
    EXPECT_EQ(two.root, 2u);
    EXPECT_EQ(two.left, std::vector<uint32_t>{0});
    EXPECT_EQ(two.right, std::vector<uint32_t>{1});
    EXPECT_THROW(radix_tree({9, 3}), Error);
    EXPECT_THROW(radix_tree({3}), Error);
}

TEST(Morton, RadixParentJoinsTheCloserNeighbour) {
    const uint32_t keys[5] = {0b000, 0b001, 0b100, 0b110, 0b111};
    // Leaf 1: key 0 differs from it in the last bit, key 2 in the first: it joins leaf 0.
    morton::RadixParent p = morton::radix_parent(keys, 5, 1, 1);
    EXPECT_EQ(p.split, 0u);
    EXPECT_FALSE(p.left_child);
    p = morton::radix_parent(keys, 5, 3, 3);  // 110 is closer to 111 than to 100
    EXPECT_EQ(p.split, 3u);
    EXPECT_TRUE(p.left_child);
    p = morton::radix_parent(keys, 5, 0, 0);  // the first key has no left neighbour
    EXPECT_EQ(p.split, 0u);
    EXPECT_TRUE(p.left_child);
    p = morton::radix_parent(keys, 5, 2, 4);  // the last range has no right neighbour
    EXPECT_EQ(p.split, 1u);
    EXPECT_FALSE(p.left_child);
}

TEST(Morton, EqualKeysSplitByIndex) {
    // Eight equal keys: the index decides, so the tree is the balanced one over 0..7.
    const RawHierarchy h = radix_tree({7, 7, 7, 7, 7, 7, 7, 7});
    EXPECT_EQ(h.root, 8u + 3);
    EXPECT_EQ(h.left[3], 8u + 1);
    EXPECT_EQ(h.right[3], 8u + 5);
    // Apetrei's distance puts every equal pair below every differing one.
    const uint64_t k2[3] = {5, 5, 6};
    EXPECT_LT(morton::apetrei_delta(k2, 0), morton::apetrei_delta(k2, 1));
}

/// Every node reached once from the root, every leaf 0..n-1 once, every box the union of its
/// children's, keys sorted.
void expect_sound(const RawHierarchy& h, const scene::TriangleMesh& mesh) {
    const size_t n = mesh.triangle_count();
    ASSERT_EQ(h.sorted_ids.size(), n);
    ASSERT_EQ(h.interior_count(), n - 1);
    EXPECT_TRUE(std::is_sorted(h.keys.begin(), h.keys.end()));
    std::vector<uint32_t> ids = h.sorted_ids;
    std::sort(ids.begin(), ids.end());
    for (size_t k = 0; k < n; ++k) ASSERT_EQ(ids[k], k);
    std::vector<int> seen(2 * n - 1, 0);
    std::vector<uint32_t> todo{h.root};
    while (!todo.empty()) {
        const uint32_t x = todo.back();
        todo.pop_back();
        ++seen[x];
        if (x < n) {
            const AABB b = mesh.triangle_bounds(h.sorted_ids[x]);
            EXPECT_EQ(std::memcmp(&b, &h.boxes[x], sizeof b), 0);
            continue;
        }
        const uint32_t a = h.left[x - n], c = h.right[x - n];
        const AABB u = merge(h.boxes[a], h.boxes[c]);
        EXPECT_EQ(std::memcmp(&u, &h.boxes[x], sizeof u), 0) << "node " << x;
        todo.push_back(a);
        todo.push_back(c);
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
}

TEST(LbvhReference, HierarchyIsSoundForBothCodeLengths) {
    for (auto kind : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured}) {
        const scene::TriangleMesh mesh = scene::make_procedural(kind, 3000, 5);
        for (int bits : {30, 60}) {
            SCOPED_TRACE(bits);
            const RawHierarchy h = lbvh_reference(mesh, bits);
            expect_sound(h, mesh);
            std::vector<uint64_t> distinct = h.keys;
            distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
            EXPECT_GT(distinct.size(), mesh.triangle_count() / 2) << "the codes do not spread the triangles";
        }
    }
    // Many triangles with one centre: equal keys, split by index.
    scene::TriangleMesh same;
    for (int k = 0; k < 40; ++k) {
        const float s = 1.0f + float(k);
        scene::add_triangle_checked(same, {-s, -s, 0}, {s, -s, 0}, {0, s, 0}, -1);
    }
    const RawHierarchy h = lbvh_reference(same, 30);
    expect_sound(h, same);
    EXPECT_EQ(h.keys.front(), h.keys.back());
    EXPECT_THROW(lbvh_reference(same, 32), Error);
}

TEST(PlocReference, HierarchyIsSoundForEveryRadius) {
    for (auto kind : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured}) {
        const scene::TriangleMesh mesh = scene::make_procedural(kind, 3000, 5);
        for (int radius : {1, 4, 16}) {
            SCOPED_TRACE(radius);
            const RawHierarchy h = ploc_reference(mesh, 30, radius);
            expect_sound(h, mesh);
            // Nodes are numbered as they are made: children before their parent, the root last.
            for (size_t i = 0; i < h.interior_count(); ++i) {
                EXPECT_LT(h.left[i], mesh.triangle_count() + i);
                EXPECT_LT(h.right[i], mesh.triangle_count() + i);
            }
            EXPECT_EQ(h.root, 2 * mesh.triangle_count() - 2);
        }
    }
    // Equal boxes everywhere: every area ties, and the rounds still end.
    scene::TriangleMesh same;
    for (int k = 0; k < 37; ++k) scene::add_triangle_checked(same, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, -1);
    expect_sound(ploc_reference(same, 60, 3), same);
    const scene::TriangleMesh one = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}});
    EXPECT_EQ(ploc_reference(one, 30, 8).root, 0u);
    EXPECT_THROW(ploc_reference(one, 30, 0), Error);
    EXPECT_THROW(ploc_reference(one, 30, 17), Error);
}

/// Small flat triangles along x at `xs`, in that (Morton) order.
scene::TriangleMesh row_of(std::initializer_list<float> xs) {
    scene::TriangleMesh m;
    for (float x : xs) scene::add_triangle_checked(m, {x, 0, 0}, {x + 0.1f, 0, 0}, {x, 0.1f, 0}, -1);
    return m;
}

TEST(PlocReference, MutualNeighboursMergeAndTiesGoToTheLowerPlace) {
    // 0, 1 | 10, 11: two pairs, then the root.
    using Ids = std::vector<uint32_t>;
    RawHierarchy h = ploc_reference(row_of({0, 1, 10, 11}), 30, 1);
    EXPECT_EQ(h.left, (Ids{0, 2, 4}));
    EXPECT_EQ(h.right, (Ids{1, 3, 5}));
    // 0, 5, 6, 7 with radius 1: 6 is as near to 5 as to 7 and takes the lower place, 5; so
    // (5, 6) is made first, then (56, 7), then the root (0, 567).
    h = ploc_reference(row_of({0, 5, 6, 7}), 30, 1);
    EXPECT_EQ(h.left, (Ids{1, 4, 0}));
    EXPECT_EQ(h.right, (Ids{2, 3, 5}));
    // With radius 3, 0 sees every cluster, but its nearest, 5, prefers 6: the same first node.
    h = ploc_reference(row_of({0, 5, 6, 7}), 30, 3);
    EXPECT_EQ(h.left[0], 1u);
    EXPECT_EQ(h.right[0], 2u);
}

TEST(PlocReference, LeavesBySahFollowTheRule) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 4000, 2);
    const RawHierarchy h = ploc_reference(mesh, 30, 8);
    BuildConfig c;
    const BuildTree tree = tree_from_hierarchy(h, c);
    EXPECT_EQ(validate(tree, mesh, c), "");
    const TreeStats s = compute_stats(tree, mesh, c, false);
    EXPECT_GT(s.leaves, mesh.triangle_count() / 8);
    EXPECT_LT(s.leaves, mesh.triangle_count());  // some subtrees became leaves
    // Single-triangle leaves: the whole hierarchy, 2n - 1 nodes, and its SAH is the hierarchy's.
    BuildConfig single = c;
    single.max_leaf_size = 1;
    const BuildTree full = tree_from_hierarchy(h, single);
    EXPECT_EQ(full.nodes.size(), 2 * mesh.triangle_count() - 1);
    double sah = 0;
    const double root = h.boxes[h.root].half_area();
    for (size_t x = 0; x < h.boxes.size(); ++x) sah += h.boxes[x].half_area() / root;
    EXPECT_NEAR(compute_stats(full, mesh, single, false).sah, sah, 1e-6 * sah);
    // The leaves' SAH choice never costs more than the full hierarchy.
    EXPECT_LE(s.sah, compute_stats(full, mesh, c, false).sah);
    // Every leaf holds at most max_leaf triangles, every interior node more than min_leaf.
    BuildConfig four = c;
    four.min_leaf_size = 4;
    const BuildTree t4 = tree_from_hierarchy(h, four);
    std::vector<uint32_t> below(t4.nodes.size(), 0);
    for (size_t i = t4.nodes.size(); i-- > 0;) {  // children come after their parents
        const BuildNode& n = t4.nodes[i];
        EXPECT_LE(n.prim_count, four.max_leaf_size);
        below[i] = n.is_leaf() ? n.prim_count : below[n.first_index] + below[n.first_index + 1];
        if (!n.is_leaf()) EXPECT_GT(below[i], four.min_leaf_size) << "node " << i;
    }
    EXPECT_EQ(below[0], mesh.triangle_count());
    EXPECT_LT(compute_stats(t4, mesh, c, false).leaves, s.leaves);
}

/// Two pairs of overlapping unit boxes 10 apart, hierarchy ((A, C), (B, D)): each leaf belongs
/// beside the other of its pair.
RawHierarchy crossed_pairs() {
    RawHierarchy h;
    const auto box = [](float x) { return AABB{{x, 0, 0}, {x + 1, 1, 1}}; };
    h.sorted_ids = {0, 1, 2, 3};
    h.keys = {0, 1, 2, 3};
    h.boxes = {box(0), box(0.5f), box(10), box(10.5f)};  // A, B, C, D
    h.left = {5, 0, 1};
    h.right = {6, 2, 3};
    h.root = 4;
    h.boxes.push_back(merge(merge(h.boxes[0], h.boxes[2]), merge(h.boxes[1], h.boxes[3])));
    h.boxes.push_back(merge(h.boxes[0], h.boxes[2]));
    h.boxes.push_back(merge(h.boxes[1], h.boxes[3]));
    return h;
}

/// The interior nodes' half areas together (what reinsertion lowers).
double interior_area(const RawHierarchy& h) {
    double a = 0;
    for (size_t x = h.sorted_ids.size(); x < h.boxes.size(); ++x) a += h.boxes[x].half_area();
    return a;
}

/// Parent of every node of h (the root's is ~0u).
std::vector<uint32_t> parents(const RawHierarchy& h) {
    const size_t n = h.sorted_ids.size();
    std::vector<uint32_t> p(2 * n - 1, ~0u);
    for (size_t i = 0; i + 1 < n; ++i) p[h.left[i]] = p[h.right[i]] = uint32_t(n + i);
    return p;
}

TEST(ParallelReinsertionReference, MovesLeavesBesideTheirNeighbours) {
    BuildConfig single;
    single.max_leaf_size = 1;  // every pair stays two leaves
    RawHierarchy h = crossed_pairs();
    const double before = interior_area(h);
    // One pass: the four leaves' moves all change the root's children's links; one wins, the
    // largest gain: B beside A (it frees (B, D) and grows (A, C) into A u B u C, which is smaller
    // than the A u B u D that A's move beside B grows (B, D) into).
    ASSERT_TRUE(parallel_reinsertion_reference(h, single, 1));
    std::vector<uint32_t> p = parents(h);
    EXPECT_EQ(p[0], p[1]);
    EXPECT_NE(p[2], p[3]);
    EXPECT_EQ(p[3], h.root);  // D took its old parent's place
    // A second pass moves C beside D (D, now a child of the root, does not move itself).
    ASSERT_TRUE(parallel_reinsertion_reference(h, single, 1));
    p = parents(h);
    EXPECT_EQ(p[0], p[1]);
    EXPECT_EQ(p[2], p[3]);
    for (uint32_t x = 4; x < 7; ++x) {
        const AABB u = merge(h.boxes[h.left[x - 4]], h.boxes[h.right[x - 4]]);
        EXPECT_EQ(std::memcmp(&u, &h.boxes[x], sizeof u), 0) << "node " << x << " refitted";
    }
    EXPECT_LT(interior_area(h), 0.5 * before);
    // A third finds nothing to move.
    const RawHierarchy settled = h;
    ASSERT_TRUE(parallel_reinsertion_reference(h, single, 1));
    EXPECT_EQ(h.left, settled.left);
    EXPECT_EQ(h.right, settled.right);
}

TEST(ParallelReinsertionReference, LowersTheSahOfSoundHierarchies) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 3000, 5);
    const BuildConfig c;
    for (const RawHierarchy& built : {lbvh_reference(mesh, 30), ploc_reference(mesh, 30, 8)}) {
        const double before = compute_stats(tree_from_hierarchy(built, c), mesh, c, false).sah;
        RawHierarchy h = built;
        ASSERT_TRUE(parallel_reinsertion_reference(h, c, 0));
        EXPECT_EQ(h.left, built.left);  // no passes: nothing moves
        EXPECT_EQ(h.right, built.right);
        ASSERT_TRUE(parallel_reinsertion_reference(h, c, 3));
        expect_sound(h, mesh);
        const BuildTree tree = tree_from_hierarchy(h, c);
        EXPECT_EQ(validate(tree, mesh, c), "");
        const double after = compute_stats(tree, mesh, c, false).sah;
        std::printf("reference reinsertion: SAH %.4f -> %.4f\n", before, after);
        EXPECT_LT(after, 0.97 * before);
    }
    RawHierarchy two = lbvh_reference(scene::make_procedural(scene::ProceduralKind::kSoup, 2, 1), 30);
    const RawHierarchy two0 = two;
    EXPECT_TRUE(parallel_reinsertion_reference(two, c, 3));  // under 3 leaves: nothing to move
    EXPECT_EQ(two.left, two0.left);
    RawHierarchy broken = two0;
    broken.right.clear();
    EXPECT_THROW(parallel_reinsertion_reference(broken, c, 1), Error);
}

TEST(ParallelReinsertionReference, ManyMovesAtOnceKeepTheHierarchySound) {
    // Overlapping soups, whose passes move many nodes at once: after every pass each node is
    // reached once from the root and every box is its children's union (a move applied wrongly,
    // or a refit that missed a node, breaks one or the other).
    const BuildConfig c;
    for (uint64_t seed : {1, 2, 3}) {
        const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 20000, seed);
        RawHierarchy h = lbvh_reference(mesh, 30);
        for (int pass = 0; pass < 6; ++pass) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", pass " + std::to_string(pass));
            ASSERT_TRUE(parallel_reinsertion_reference(h, c, 1));
            expect_sound(h, mesh);
        }
    }
}

TEST(ParallelReinsertionReference, PassesThatReachMaxDepthAreUndone) {
    // As the GPU's: with max_depth one level above the tree's own depth, passes that deepen the
    // tree are undone, and the hierarchy is the builder's, boxes and all.
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 30000, 7);
    const RawHierarchy built = lbvh_reference(mesh, 30);
    BuildConfig c;
    const uint32_t depth = compute_stats(tree_from_hierarchy(built, c), mesh, c, false).depth;
    RawHierarchy free = built;
    ASSERT_TRUE(parallel_reinsertion_reference(free, c, 3));
    const uint32_t deeper = compute_stats(tree_from_hierarchy(free, c), mesh, c, false).depth;
    ASSERT_GT(deeper, depth) << "reinsertion does not deepen this tree: pick another";
    c.max_depth = depth + 1;
    RawHierarchy held = built;
    EXPECT_FALSE(parallel_reinsertion_reference(held, c, 3));
    EXPECT_EQ(held.left, built.left);
    EXPECT_EQ(held.right, built.right);
    EXPECT_EQ(std::memcmp(held.boxes.data(), built.boxes.data(), built.boxes.size() * sizeof(AABB)), 0);
}

/// `copies` triangles with one box at each x of `xs` (in that order along x).
scene::TriangleMesh stacks_at(std::initializer_list<float> xs, int copies) {
    scene::TriangleMesh m;
    for (float x : xs)
        for (int k = 0; k < copies; ++k) scene::add_triangle_checked(m, {x, 0, 0}, {x + 0.1f, 0, 0}, {x, 0.1f, 0}, -1);
    return m;
}

TEST(TriangleClusters, OrderIgnoresTheCodesLowSixBits) {
    // Centres along x over [0, 1] from triangle 1's: triangle 0 lies 0.002 past it, cell 2 of
    // 1024 (30-bit codes) but cell 0 of 256 (their top 24 bits), where equal codes keep the
    // ids' order. At alpha 1 nothing merges (each union grows a box by 2%).
    const auto c = triangle_clusters(row_of({0.002f, 0.0f, 1.0f}), 1.0f);
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c[0], std::vector<uint32_t>{0u});
    EXPECT_EQ(c[1], std::vector<uint32_t>{1u});
    EXPECT_EQ(c[2], std::vector<uint32_t>{2u});
    static_assert(kClusterOrderIgnoredBits == 6, "8 bits per axis are left");
}

TEST(TriangleClusters, NearlyCoincidentNeighboursMergeUpToTheCap) {
    // Three stacks of four equal triangles: at alpha 1 each stack is one cluster (a union that
    // grows no box), and no two stacks meet; at alpha 1e4 the stacks' unions are cheap too.
    const scene::TriangleMesh m = stacks_at({0.0f, 10.0f, 20.0f}, 4);
    const auto c = triangle_clusters(m, 1.0f);
    ASSERT_EQ(c.size(), 3u);
    for (const auto& x : c) {
        ASSERT_EQ(x.size(), 4u);
        const float x0 = m.vertex(x[0], 0).x;
        for (uint32_t t : x) EXPECT_EQ(m.vertex(t, 0).x, x0) << "a cluster mixes stacks";
    }
    // A merge keeps the lower place's triangles first: a stack's first triangle leads it.
    for (const auto& x : c) EXPECT_EQ(x[0] % 4, 0u);
    EXPECT_EQ(triangle_clusters(m, 16.0f).size(), 3u);  // stacks 10 apart cost far more than 16x
    // At most 16 triangles a cluster, and a chunk is 32 triangles of the Morton order: 40 equal
    // triangles make clusters of 16, 16 and 8.
    const auto big = triangle_clusters(stacks_at({0.0f}, 40), 1.0f);
    ASSERT_EQ(big.size(), 3u);
    EXPECT_EQ(big[0].size(), 16u);
    EXPECT_EQ(big[1].size(), 16u);
    EXPECT_EQ(big[2].size(), 8u);
    // Every triangle once; a sparse soup hardly clusters at alpha 1.
    const scene::TriangleMesh soup = scene::make_procedural(scene::ProceduralKind::kSoup, 3000, 5);
    std::vector<uint32_t> all;
    for (const auto& x : triangle_clusters(soup, 1.3f)) all.insert(all.end(), x.begin(), x.end());
    std::sort(all.begin(), all.end());
    ASSERT_EQ(all.size(), soup.triangle_count());
    for (size_t k = 0; k < all.size(); ++k) ASSERT_EQ(all[k], k);
    for (const float bad : {0.5f, std::numeric_limits<float>::quiet_NaN()}) {
        try {
            triangle_clusters(m, bad);
            ADD_FAILURE() << bad << ": no error";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()),
                      bad == 0.5f ? "cluster alpha 0.5 is not at least 1" : "cluster alpha nan is not at least 1");
        }
    }
    EXPECT_THROW(triangle_clusters(scene::TriangleMesh{}, 1.3f), Error);
}

TEST(TriangleClusters, PairKeysOrderAreasThenPlacesAtAnyScale) {
    // The least area first, then the lower place; areas to 2^-18 relative, so nearly equal
    // areas tie and the place decides.
    EXPECT_LT(cluster_pair_key(1.0f, 31), cluster_pair_key(2.0f, 0));
    EXPECT_LT(cluster_pair_key(1.0f, 1), cluster_pair_key(1.0f, 2));
    // One ulp apart is a tie: the lower place wins with the larger area.
    EXPECT_LT(cluster_pair_key(std::nextafter(1.0f, 2.0f), 0), cluster_pair_key(1.0f, 1));
    EXPECT_LT(cluster_pair_key(1.0f, 0), cluster_pair_key(1.0f, 1));
    EXPECT_EQ(cluster_pair_key(1.0f, 7) & 31u, 7u);
    EXPECT_EQ(cluster_key_area(cluster_pair_key(1.5f, 7)), 1.5f);
    EXPECT_EQ(cluster_key_area(cluster_pair_key(0.0f, 3)), 0.0f);
    // Every finite area has a key, whatever the scene's scale; no key for what is not one.
    for (const float a : {1e-30f, 34.0f, 1e6f, 1e30f, 3e38f}) {
        EXPECT_NE(cluster_pair_key(a, 0), kNoClusterPair) << a;
        EXPECT_LT(cluster_pair_key(a, 0), cluster_pair_key(a * 1.5f < 3.4e38f ? a * 1.5f : a, 1)) << a;
    }
    for (const float bad : {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(), -1.0f})
        EXPECT_EQ(cluster_pair_key(bad, 0), kNoClusterPair) << bad;
}

TEST(ClusteredBinnedReference, ClustersBecomeSubtreesUnderBinnedSplits) {
    for (auto kind : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured}) {
        const scene::TriangleMesh mesh = scene::make_procedural(kind, 3000, 5);
        for (float alpha : {1.3f, 4.0f}) {
            SCOPED_TRACE(alpha);
            const RawHierarchy h = clustered_binned_reference(mesh, alpha);
            expect_sound(h, mesh);
            EXPECT_TRUE(h.keys.empty());
            const uint32_t n = uint32_t(mesh.triangle_count());
            // Node n + m - 1 splits the order at place m: its right child's first leaf is m.
            std::vector<uint32_t> first(2 * size_t(n) - 1), count(2 * size_t(n) - 1, 1);
            std::function<void(uint32_t)> walk = [&](uint32_t x) {
                if (x < n) {
                    first[x] = x;
                    return;
                }
                walk(h.left[x - n]);
                walk(h.right[x - n]);
                first[x] = first[h.left[x - n]];
                count[x] = count[h.left[x - n]] + count[h.right[x - n]];
                EXPECT_EQ(x, n + first[h.right[x - n]] - 1) << "node " << x;
                EXPECT_EQ(first[h.right[x - n]], first[x] + count[h.left[x - n]]) << "not a range";
            };
            walk(h.root);
            // Every cluster is one subtree: its triangles are the leaves of one node.
            std::vector<uint32_t> place(n);
            for (uint32_t k = 0; k < n; ++k) place[h.sorted_ids[k]] = k;
            size_t multi = 0;
            for (const auto& c : triangle_clusters(mesh, alpha)) {
                uint32_t lo = n, hi = 0;
                for (uint32_t t : c) lo = std::min(lo, place[t]), hi = std::max(hi, place[t]);
                EXPECT_EQ(hi - lo + 1, c.size()) << "a cluster's triangles are not together";
                if (c.size() > 1) ++multi;
            }
            if (kind == scene::ProceduralKind::kStructured) EXPECT_GT(multi, 0u) << "no cluster formed";
        }
    }
    // Where no cluster forms, the hierarchy is the binned builder's (leaves of one), node for node.
    scene::TriangleMesh soup;  // small triangles on a jittered grid, apart from one another
    for (int i = 0; i < 2000; ++i) {
        const float x = float(i % 50) + 0.37f * float((i * 7919) % 13) / 13.0f, y = float(i / 50);
        const float z = float((i * 104729) % 97) / 9.7f;
        scene::add_triangle_checked(soup, {x, y, z}, {x + 0.1f, y, z}, {x, y + 0.1f, z + 0.05f}, -1);
    }
    ASSERT_EQ(triangle_clusters(soup, 1.0f).size(), soup.triangle_count());
    BuildConfig one;
    one.min_leaf_size = one.max_leaf_size = 1;
    BinnedSahBuilder::Config c;
    static_cast<BuildConfig&>(c) = one;
    const BuildTree binned = build_tree_from_bvh2(convert_to_bvh2(BinnedSahBuilder(c).build(soup), soup));
    const BuildTree ours =
        build_tree_from_bvh2(convert_to_bvh2(tree_from_hierarchy(clustered_binned_reference(soup, 1.0f), one), soup));
    ASSERT_EQ(ours.nodes.size(), binned.nodes.size());
    EXPECT_EQ(std::memcmp(ours.nodes.data(), binned.nodes.data(), ours.nodes.size() * sizeof(BuildNode)), 0);
    EXPECT_EQ(ours.prim_indices, binned.prim_indices);
    // One triangle: a root leaf.
    const scene::TriangleMesh one_tri = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}});
    EXPECT_EQ(clustered_binned_reference(one_tri, 1.3f).root, 0u);
}

TEST(Bvh2Convert, BuildTreeOfTheLayoutKeepsTreeAndFigures) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 4000, 2);
    BuilderOptions o;
    const BuildTree tree = run_builder(BuilderKind::kBinned, mesh, o).tree;
    const Bvh2 bvh = convert_to_bvh2(tree, mesh);
    const BuildTree back = build_tree_from_bvh2(bvh);
    EXPECT_EQ(validate(back, mesh, o.config), "");
    const TreeStats a = compute_stats(tree, mesh, o.config, false), b = compute_stats(back, mesh, o.config, false);
    EXPECT_EQ(a.nodes, b.nodes);
    EXPECT_EQ(a.leaves, b.leaves);
    EXPECT_EQ(a.depth, b.depth);
    EXPECT_NEAR(a.sah, b.sah, 1e-9 * a.sah);
    // The layout of the BuildTree is the same layout again.
    const Bvh2 again = convert_to_bvh2(back, mesh);
    EXPECT_EQ(again.nodes.size(), bvh.nodes.size());
    EXPECT_EQ(again.depth, bvh.depth);
    // A root leaf.
    const scene::TriangleMesh two = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 1, 0, 1, 0, 1, 1}});
    BuilderOptions big;
    big.config.min_leaf_size = 4;
    const BuildTree leaf = run_builder(BuilderKind::kBinned, two, big).tree;
    ASSERT_EQ(leaf.nodes.size(), 1u);
    const BuildTree leaf_back = build_tree_from_bvh2(convert_to_bvh2(leaf, two));
    ASSERT_EQ(leaf_back.nodes.size(), 1u);
    EXPECT_EQ(leaf_back.nodes[0].prim_count, 2u);
    EXPECT_EQ(validate(leaf_back, two, big.config), "");
}

TEST(GpuBuildFigures, NameEveryFigureOfTheBuild) {
    trav::GpuBuild g;
    g.times.bounds_ms = 0.25;
    g.times.convert_ms = 0.5;
    g.times.total_ms = 2.0;
    g.peak_bytes = 12345;
    g.reinsertion_passes = 3;
    g.reinsertion_undone = true;
    nlohmann::json f = trav::gpu_build_figures(g, 4000000);
    EXPECT_EQ(f.at("bounds_ms").get<double>(), 0.25);
    EXPECT_EQ(f.at("convert_ms").get<double>(), 0.5);
    EXPECT_EQ(f.at("total_ms").get<double>(), 2.0);
    EXPECT_EQ(f.at("mtris_per_s").get<double>(), 2000.0);  // 4M triangles in 2 ms
    EXPECT_EQ(f.at("peak_device_bytes").get<size_t>(), 12345u);
    EXPECT_EQ(f.at("reinsertion_passes").get<int>(), 3);
    EXPECT_TRUE(f.at("reinsertion_undone").get<bool>());
    EXPECT_FALSE(f.contains("clusters"));  // named only when gpu-binned made clusters
    g.clusters = 763944;
    g.times.total_ms = 0.0;
    f = trav::gpu_build_figures(g, 4000000);
    EXPECT_EQ(f.at("clusters").get<size_t>(), 763944u);
    EXPECT_EQ(f.at("mtris_per_s").get<double>(), 0.0);  // no time, no rate
}

TEST(GpuBuilderOptions, NamesRangesAndTheCpuPath) {
    EXPECT_EQ(parse_builder_kind("lbvh"), BuilderKind::kLbvh);
    EXPECT_EQ(parse_builder_kind("ploc"), BuilderKind::kPloc);
    EXPECT_EQ(parse_builder_kind("hploc"), BuilderKind::kHploc);
    EXPECT_STREQ(builder_name(BuilderKind::kHploc), "hploc");
    EXPECT_STREQ(builder_name(BuilderKind::kPloc), "ploc");
    EXPECT_TRUE(runs_on_gpu(BuilderKind::kLbvh));
    EXPECT_TRUE(runs_on_gpu(BuilderKind::kPloc));
    EXPECT_FALSE(runs_on_gpu(BuilderKind::kSbvh));
    EXPECT_TRUE(uses_radius(BuilderKind::kPloc));
    EXPECT_FALSE(uses_radius(BuilderKind::kLbvh));
    // Only SBVH's trees may reference a triangle twice: every other tree is validated strictly.
    for (BuilderKind k : {BuilderKind::kBinned, BuilderKind::kSweep, BuilderKind::kSbvh, BuilderKind::kLbvh,
                          BuilderKind::kPloc, BuilderKind::kHploc, BuilderKind::kGpuBinned})
        EXPECT_EQ(splits_references(k), k == BuilderKind::kSbvh) << builder_name(k);
    BuilderOptions o;
    o.morton_bits = 31;
    EXPECT_NE(options_problem(o).find("morton_bits 31"), std::string::npos);
    o.morton_bits = 60;
    o.ploc_radius = 17;
    EXPECT_NE(options_problem(o).find("radius 17"), std::string::npos);
    o.ploc_radius = 16;
    EXPECT_EQ(options_problem(o), "");
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 100, 1);
    try {
        run_builder(BuilderKind::kHploc, mesh, o);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("runs on the GPU"), std::string::npos) << e.what();
    }
    EXPECT_EQ(describe_config(BuilderKind::kHploc, o), "hploc leaf=1..8 max_depth=64 Ct=1 Ci=1 morton=60 radius=16");
    EXPECT_EQ(describe_config(BuilderKind::kPloc, o), "ploc leaf=1..8 max_depth=64 Ct=1 Ci=1 morton=60 radius=16");
    EXPECT_EQ(describe_config(BuilderKind::kLbvh, o), "lbvh leaf=1..8 max_depth=64 Ct=1 Ci=1 morton=60");
    o.reinsertion_passes = 2;  // named only when run, as records before GPU reinsertion read
    EXPECT_EQ(describe_config(BuilderKind::kLbvh, o), "lbvh leaf=1..8 max_depth=64 Ct=1 Ci=1 morton=60 reinsert=2");
    // The GPU's binned SAH: no Morton codes, no radius, its 32 bins named.
    EXPECT_EQ(parse_builder_kind("gpu-binned"), BuilderKind::kGpuBinned);
    EXPECT_STREQ(builder_name(BuilderKind::kGpuBinned), "gpu-binned");
    EXPECT_TRUE(runs_on_gpu(BuilderKind::kGpuBinned));
    EXPECT_FALSE(uses_morton(BuilderKind::kGpuBinned));
    EXPECT_TRUE(uses_morton(BuilderKind::kHploc));
    EXPECT_FALSE(uses_radius(BuilderKind::kGpuBinned));
    EXPECT_EQ(describe_config(BuilderKind::kGpuBinned, o),
              "gpu-binned leaf=1..8 max_depth=64 Ct=1 Ci=1 bins=32 reinsert=2");
    EXPECT_THROW(run_builder(BuilderKind::kGpuBinned, mesh, o), Error);
    // Its cluster alpha: 0 (off, not named, as records before it read) or 1 to 16.
    EXPECT_TRUE(uses_clusters(BuilderKind::kGpuBinned));
    EXPECT_FALSE(uses_clusters(BuilderKind::kHploc));
    o.cluster_alpha = 1.3f;
    EXPECT_EQ(options_problem(o), "");
    EXPECT_EQ(describe_config(BuilderKind::kGpuBinned, o),
              "gpu-binned leaf=1..8 max_depth=64 Ct=1 Ci=1 bins=32 clusters=1.3 reinsert=2");
    EXPECT_EQ(describe_config(BuilderKind::kHploc, o),
              "hploc leaf=1..8 max_depth=64 Ct=1 Ci=1 morton=60 radius=16 reinsert=2");
    o.cluster_alpha = 0.5f;
    EXPECT_EQ(options_problem(o), "clusters 0.5 is neither 0 (off) nor in [1, 16]");
    o.cluster_alpha = 17.0f;
    EXPECT_EQ(options_problem(o), "clusters 17 is not in [0, 16]");
    o.cluster_alpha = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(options_problem(o).find("clusters nan"), std::string::npos) << options_problem(o);
}

TEST(GpuBuilderOptions, SpecsRefuseTheWrongDevice) {
    trav::StructureSpec s;
    s.builder = "hploc";
    EXPECT_TRUE(s.on_gpu());
    s.check();
    s.build_device = "cpu";
    EXPECT_THROW(s.check(), Error);
    s.build_device = "tpu";
    EXPECT_THROW(s.check(), Error);
    s.build_device = "gpu";
    s.check();
    s.options.reinsertion_passes = 2;  // parallel reinsertion on the device
    s.check();
    s.options.reinsertion_passes = 17;
    EXPECT_THROW(s.check(), Error);
    trav::StructureSpec c;
    c.build_device = "gpu";
    EXPECT_THROW(c.check(), Error);  // binned runs on the CPU
    c.builder = "kdtree";
    EXPECT_FALSE(c.on_gpu());
    // A cluster alpha applies to gpu-binned only.
    trav::StructureSpec g;
    g.builder = "gpu-binned";
    g.options.cluster_alpha = 1.3f;
    g.check();
    for (const char* other : {"hploc", "binned", "kdtree"}) {
        g.builder = other;
        try {
            g.check();
            ADD_FAILURE() << other << ": no error";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()), std::string("clusters applies to builder gpu-binned, not ") + other);
        }
    }
}

TEST(GpuBuilderOptions, WithoutADeviceTheBuildSaysWhy) {
    std::string why;
    if (trav::gpu_available(&why)) GTEST_SKIP() << "a GPU is present: the GPU tests build on it";
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 100, 1);
    trav::StructureSpec s;
    s.builder = "lbvh";
    try {
        trav::build_structure(mesh, s);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("builder 'lbvh' runs on the GPU, and there is none"), std::string::npos)
            << e.what();
    }
}

TEST(TreeFile, GpuBuildersKeepMortonBitsAndRadius) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 500, 3);
    TreeFileMeta meta;
    meta.builder = BuilderKind::kPloc;
    meta.options.morton_bits = 60;
    meta.options.ploc_radius = 5;
    meta.triangles = mesh.triangle_count();
    meta.scene_hash = scene::scene_hash(mesh);
    // Any valid tree over the mesh stands in for the GPU's.
    const BuildTree tree = run_builder(BuilderKind::kBinned, mesh, BuilderOptions{}).tree;
    test::TempFile f("hploc.tree");
    write_tree_file(f.path(), tree, meta);
    const TreeFile r = read_tree_file(f.path());
    EXPECT_EQ(r.meta.builder, BuilderKind::kPloc);
    EXPECT_EQ(r.meta.options.morton_bits, 60);
    EXPECT_EQ(r.meta.options.ploc_radius, 5);
    EXPECT_EQ(r.meta.options.num_bins, BuilderOptions{}.num_bins);
    EXPECT_EQ(describe_config(r.meta), describe_config(meta.builder, meta.options));
    // Loaded without a GPU: the tree is in the file.
    const trav::AccelStructure a = trav::load_structure(mesh, meta.scene_hash, f.path());
    EXPECT_EQ(a.figures["builder"], "ploc");
    EXPECT_EQ(a.figures["build_device"], "gpu");
    EXPECT_EQ(a.figures["radius"], 5);
    // A gpu-binned file: its builder and bins come back, no Morton bits or radius are claimed.
    meta.builder = BuilderKind::kGpuBinned;
    meta.options = BuilderOptions{};
    test::TempFile g("gpu-binned.tree");
    write_tree_file(g.path(), tree, meta);
    const TreeFile rg = read_tree_file(g.path());
    EXPECT_EQ(rg.meta.builder, BuilderKind::kGpuBinned);
    // The header's builder field holds the codes docs/formats.md gives: 5 ploc, 7 gpu-binned.
    auto builder_code = [](const std::string& path) {
        uint32_t code = 0;
        std::FILE* fp = std::fopen(path.c_str(), "rb");
        EXPECT_NE(fp, nullptr);
        if (!fp) return code;
        EXPECT_EQ(std::fseek(fp, 12, SEEK_SET), 0);
        EXPECT_EQ(std::fread(&code, sizeof code, 1, fp), 1u);
        std::fclose(fp);
        return code;
    };
    EXPECT_EQ(builder_code(f.path()), 5u);
    EXPECT_EQ(builder_code(g.path()), 7u);
    EXPECT_EQ(describe_config(rg.meta), "gpu-binned leaf=1..8 max_depth=64 Ct=1 Ci=1 bins=32");
    const trav::AccelStructure b = trav::load_structure(mesh, meta.scene_hash, g.path());
    EXPECT_EQ(b.figures["builder"], "gpu-binned");
    EXPECT_EQ(b.figures["build_device"], "gpu");
    EXPECT_EQ(b.figures["bins"], 32);
    EXPECT_FALSE(b.figures.contains("morton_bits"));
    EXPECT_FALSE(b.figures.contains("radius"));
    EXPECT_EQ(b.figures["cluster_alpha"], 0.0);
    // With clusters: the alpha comes back (in SBVH alpha's field) and is named.
    meta.options.cluster_alpha = 1.5f;
    test::TempFile gc("gpu-binned-clusters.tree");
    write_tree_file(gc.path(), tree, meta);
    const TreeFile rc = read_tree_file(gc.path());
    EXPECT_EQ(rc.meta.options.cluster_alpha, 1.5f);
    EXPECT_EQ(rc.meta.options.sbvh_alpha, BuilderOptions{}.sbvh_alpha);
    EXPECT_EQ(describe_config(rc.meta), "gpu-binned leaf=1..8 max_depth=64 Ct=1 Ci=1 bins=32 clusters=1.5");
    EXPECT_EQ(trav::load_structure(mesh, meta.scene_hash, gc.path()).figures["cluster_alpha"], 1.5);
    // A header alpha out of range (a damaged or forged file) is refused in one line naming it.
    meta.options.cluster_alpha = 20.0f;
    test::TempFile bad("gpu-binned-clusters-20.tree");
    write_tree_file(bad.path(), tree, meta);
    try {
        read_tree_file(bad.path());
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "structure file '" + bad.path() + "' has a header value out of range: clusters 20 is not in [0, 16]");
    }
    EXPECT_EQ(rg.meta.options.cluster_alpha, 0.0f);
    // A file of another version, older or newer, is refused with its version named.
    for (const uint32_t version : {kTreeFileVersion - 1, kTreeFileVersion + 1}) {
        std::FILE* fp = std::fopen(g.path().c_str(), "r+b");
        ASSERT_NE(fp, nullptr);
        ASSERT_EQ(std::fseek(fp, 8, SEEK_SET), 0);
        ASSERT_EQ(std::fwrite(&version, sizeof version, 1, fp), 1u);
        std::fclose(fp);
        try {
            read_tree_file(g.path());
            ADD_FAILURE() << "version " << version << " was read";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("has version " + std::to_string(version)), std::string::npos)
                << e.what();
        }
    }
}

}  // namespace
}  // namespace bvhlab::accel
