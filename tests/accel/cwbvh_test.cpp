// SPDX-License-Identifier: MIT
// The collapse pass (BuildTree -> 8-wide) and the CWBVH layout: structure invariants, the
// dynamic programme against the greedy collapse, conservative quantisation over random
// scenes and trees, the node encoding, and the refusal of trees deeper than the stack.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "accel/builders/builder.h"
#include "accel/core/check.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/passes/collapse_wide.h"
#include "scene/io/procedural.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/tracer.h"

namespace bvhlab::accel {
namespace {

struct Case {
    BuilderKind builder;
    scene::ProceduralKind kind;
    uint32_t max_leaf;
};

std::vector<Case> cases() {
    std::vector<Case> out;
    for (BuilderKind b : {BuilderKind::kBinned, BuilderKind::kSweep, BuilderKind::kSbvh})
        for (scene::ProceduralKind k : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured})
            for (uint32_t leaf : {1u, 8u, 16u}) out.push_back({b, k, leaf});
    return out;
}

BuildTree build(const scene::TriangleMesh& mesh, BuilderKind builder, uint32_t max_leaf) {
    BuilderOptions o;
    o.config.max_leaf_size = max_leaf;
    return run_builder(builder, mesh, o).tree;
}

TEST(Collapse, ValidTreesFromEveryBuilderAndLeafSize) {
    for (const Case& c : cases()) {
        SCOPED_TRACE(std::string(builder_name(c.builder)) + " max leaf " + std::to_string(c.max_leaf));
        const scene::TriangleMesh mesh = scene::make_procedural(c.kind, 5000, 11);
        const BuildTree tree = build(mesh, c.builder, c.max_leaf);
        for (CollapseMethod m : {CollapseMethod::kSahOptimal, CollapseMethod::kGreedy}) {
            const WideTree w = collapse_to_wide(tree, mesh, m);
            EXPECT_EQ(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
            const WideStats s = compute_wide_stats(w);
            EXPECT_GT(s.mean_children, 2.0);  // a collapse that kept binary nodes would be pointless
            EXPECT_LE(s.mean_children, 8.0);
            EXPECT_EQ(s.references, tree.prim_indices.size());
        }
    }
}

TEST(Collapse, DynamicProgrammeIsNeverWorseThanGreedy) {
    // The greedy collapse is one of the collapses the programme searches over, so its wide SAH
    // bounds the optimum from above; on these scenes the optimum is strictly lower.
    for (const Case& c : cases()) {
        SCOPED_TRACE(std::string(builder_name(c.builder)) + " max leaf " + std::to_string(c.max_leaf));
        const scene::TriangleMesh mesh = scene::make_procedural(c.kind, 5000, 12);
        const BuildTree tree = build(mesh, c.builder, c.max_leaf);
        const double dp = compute_wide_stats(collapse_to_wide(tree, mesh, CollapseMethod::kSahOptimal)).sah;
        const double greedy = compute_wide_stats(collapse_to_wide(tree, mesh, CollapseMethod::kGreedy)).sah;
        EXPECT_LE(dp, greedy * (1.0 + 1e-6));
        EXPECT_LT(dp, greedy);
    }
}

TEST(Collapse, TinyMeshes) {
    for (uint64_t n : {1u, 2u, 3u, 4u, 9u, 25u}) {
        SCOPED_TRACE(n);
        const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, n, 5);
        const BuildTree tree = build(mesh, BuilderKind::kBinned, 8);
        for (CollapseMethod m : {CollapseMethod::kSahOptimal, CollapseMethod::kGreedy}) {
            const WideTree w = collapse_to_wide(tree, mesh, m);
            EXPECT_EQ(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
            const Cwbvh cw = convert_to_cwbvh(w, mesh);
            EXPECT_EQ(cw.tri_ids.size(), tree.prim_indices.size());
        }
    }
}

TEST(Collapse, ValidatorCatchesDamage) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 500, 2);
    const BuildTree tree = build(mesh, BuilderKind::kBinned, 4);
    const WideTree good = collapse_to_wide(tree, mesh, CollapseMethod::kSahOptimal);
    ASSERT_EQ(validate_wide(good, mesh.triangle_count(), tree.prim_indices), "");
    WideTree w = good;
    w.prim_indices.back() = uint32_t(mesh.triangle_count());  // id out of range
    EXPECT_NE(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
    w = good;
    w.prim_indices[0] = w.prim_indices[1];  // a reference lost, another doubled
    EXPECT_NE(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
    w = good;
    w.nodes[0].child[0].box.hi.x += 10.0f;  // child outside its node
    EXPECT_NE(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
    w = good;
    ++w.depth;
    EXPECT_NE(validate_wide(w, mesh.triangle_count(), tree.prim_indices), "");
}

/// A random tree over a random scene: random extents (2^-12 to 2^12) and offsets of up to 300
/// times the extent from the origin stress the quantisation's rounding.
scene::TriangleMesh random_scene(std::mt19937& rng) {
    std::uniform_real_distribution<float> scale_exp(-12.0f, 12.0f), offset(-300.0f, 300.0f);
    const float scale = std::exp2(scale_exp(rng));
    const Vec3 shift = Vec3{offset(rng), offset(rng), offset(rng)} * scale;
    scene::TriangleMesh m = scene::make_procedural(
        rng() % 2 ? scene::ProceduralKind::kSoup : scene::ProceduralKind::kStructured, 200 + rng() % 3000, rng());
    for (Vec3& v : m.vertices) v = v * scale + shift;
    scene::TriangleMesh kept;  // drop the triangles that the shift rounded to zero area
    for (size_t t = 0; t < m.triangle_count(); ++t)
        scene::add_triangle_checked(kept, m.vertex(t, 0), m.vertex(t, 1), m.vertex(t, 2), -1);
    return kept;
}

TEST(Cwbvh, QuantisedBoxesContainTheExactBoxes) {
    std::mt19937 rng(2017);
    size_t slots = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const scene::TriangleMesh mesh = random_scene(rng);
        const BuilderKind b = trial % 3 == 0 ? BuilderKind::kSbvh : BuilderKind::kBinned;
        const BuildTree tree = build(mesh, b, 1 + rng() % 8);
        const CollapseMethod m = trial % 2 ? CollapseMethod::kGreedy : CollapseMethod::kSahOptimal;
        std::vector<std::array<AABB, kWideArity>> exact;
        const Cwbvh cw = convert_to_cwbvh(collapse_to_wide(tree, mesh, m), mesh, CwTris::kWoop, &exact);
        ASSERT_EQ(exact.size(), cw.nodes.size());
        for (size_t n = 0; n < cw.nodes.size(); ++n)
            for (uint32_t s = 0; s < kWideArity; ++s) {
                if (cw.nodes[n].meta[s] == 0) continue;
                double lo[3], hi[3];
                decode_child_box(cw.nodes[n], s, lo, hi);
                const AABB& e = exact[n][s];
                for (int k = 0; k < 3; ++k) {
                    ASSERT_LE(lo[k], double(e.lo[k])) << "node " << n << " slot " << s << " axis " << k;
                    ASSERT_GE(hi[k], double(e.hi[k])) << "node " << n << " slot " << s << " axis " << k;
                }
                ++slots;
            }
    }
    EXPECT_GT(slots, 10000u);
}

TEST(Cwbvh, NodeEncoding) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 20000, 4);
    const BuildTree tree = build(mesh, BuilderKind::kBinned, 8);
    const Cwbvh cw = convert_to_cwbvh(collapse_to_wide(tree, mesh, CollapseMethod::kSahOptimal), mesh);
    std::vector<int> reached(cw.nodes.size(), 0), tri_used(cw.tris.size(), 0);
    reached[0] = 1;
    for (size_t n = 0; n < cw.nodes.size(); ++n) {
        const CwbvhNode& node = cw.nodes[n];
        uint32_t interior = 0;
        for (uint32_t s = 0; s < kWideArity; ++s) {
            const uint32_t meta = node.meta[s];
            const bool inner = (node.imask >> s) & 1u;
            if (meta == 0) {
                EXPECT_FALSE(inner);
                for (int k = 0; k < 3; ++k) EXPECT_GT(node.qlo[k][s], node.qhi[k][s]);  // an empty box
                continue;
            }
            if (inner) {
                EXPECT_EQ(meta, CwbvhNode::interior_meta(s));
                ASSERT_LT(node.child_base + interior, cw.nodes.size());
                ++reached[node.child_base + interior++];
                continue;
            }
            const uint32_t count = popc32(meta >> 5), offset = meta & 31u;
            EXPECT_EQ(meta >> 5, (1u << count) - 1u) << "unary triangle count";
            EXPECT_GE(count, 1u);
            EXPECT_LE(offset + count, 24u);
            for (uint32_t k = 0; k < count; ++k) {
                ASSERT_LT(node.tri_base + offset + k, cw.tris.size());
                ++tri_used[node.tri_base + offset + k];
            }
        }
    }
    for (size_t n = 0; n < reached.size(); ++n) EXPECT_EQ(reached[n], 1) << "node " << n;
    for (size_t t = 0; t < tri_used.size(); ++t) EXPECT_EQ(tri_used[t], 1) << "triangle " << t;
    EXPECT_EQ(sizeof(CwbvhNode), 80u);
}

TEST(Cwbvh, SmallerThanTheBinaryLayout) {
    // Nodes alone: one 80-byte node per ~6 children against a 64-byte node per 2.
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 20000, 9);
    const BuildTree tree = build(mesh, BuilderKind::kBinned, 8);
    const Cwbvh cw = convert_to_cwbvh(collapse_to_wide(tree, mesh, CollapseMethod::kSahOptimal), mesh);
    size_t interior = 0;
    for (const BuildNode& n : tree.nodes) interior += !n.is_leaf();
    EXPECT_LT(cw.nodes.size() * sizeof(CwbvhNode), interior * 64 / 2);
}

TEST(Cwbvh, VertexTrianglesSameTreeFewerBytes) {
    // --cw-tris vertices: the same nodes and leaf order, 36 bytes per triangle instead of 48.
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 5000, 4);
    const WideTree w = collapse_to_wide(build(mesh, BuilderKind::kBinned, 8), mesh, CollapseMethod::kSahOptimal);
    const Cwbvh woop = convert_to_cwbvh(w, mesh), vert = convert_to_cwbvh(w, mesh, CwTris::kVertices);
    ASSERT_EQ(vert.tri_format, CwTris::kVertices);
    ASSERT_EQ(vert.nodes.size(), woop.nodes.size());
    EXPECT_EQ(0, std::memcmp(vert.nodes.data(), woop.nodes.data(), woop.nodes.size() * sizeof(CwbvhNode)));
    EXPECT_EQ(vert.tri_ids, woop.tri_ids);
    EXPECT_TRUE(vert.tris.empty());
    ASSERT_EQ(vert.vtris.size(), woop.tris.size());
    EXPECT_EQ(woop.bytes() - vert.bytes(), woop.tris.size() * 12);
    for (size_t i = 0; i < vert.vtris.size(); i += 97) {  // v0 and the edges of the mesh triangle
        const uint32_t t = vert.tri_ids[i];
        const Vec3 v0 = mesh.vertex(t, 0), e2 = mesh.vertex(t, 2) - v0;
        EXPECT_EQ(vert.vtris[i].f[0], v0.x);
        EXPECT_EQ(vert.vtris[i].f[8], e2.z);
    }
}

TEST(VertexTriangle, AgreesWithWoopAwayFromEdges) {
    // Moller-Trumbore and Woop's map round differently, so they may disagree only where a
    // barycentric is within rounding of an edge; elsewhere (rays not grazing) the hit, t, u and v agree.
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> U(-1.0f, 1.0f);
    size_t hits = 0, compared = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 a{U(rng), U(rng), U(rng)}, b{U(rng), U(rng), U(rng)}, c{U(rng), U(rng), U(rng)};
        if (length(cross(b - a, c - a)) < 1e-3f) continue;
        const WoopTriangle wt = make_woop_triangle(a, b, c);
        const VertexTriangle vt = make_vertex_triangle(a, b, c);
        const Vec3 o{4 * U(rng), 4 * U(rng), 4 * U(rng)};
        const float bu = (1.2f * U(rng) + 0.4f) * 0.5f, bv = (1.2f * U(rng) + 0.4f) * 0.5f;  // the aim's barycentrics
        const Vec3 target = a + (b - a) * bu + (c - a) * bv;
        const Vec3 d = target - o, n = cross(b - a, c - a);
        if (std::fabs(dot(n, d)) < 0.1f * length(n) * length(d)) continue;  // grazing: ill-conditioned in both
        float tw = 0, uw = 0, vw = 0, tv = 0, uv = 0, vv = 0;
        const bool hw = wt.intersect(o, d, 0.0f, 1e30f, tw, uw, vw);
        const bool hv = vt.intersect(o, d, 0.0f, 1e30f, tv, uv, vv);
        const bool near_edge = std::min({std::fabs(bu), std::fabs(bv), std::fabs(1 - bu - bv)}) < 1e-4f;
        if (near_edge) continue;
        ++compared;
        ASSERT_EQ(hw, hv) << "ray " << i;
        if (!hw) continue;
        ++hits;
        EXPECT_NEAR(tv, tw, 1e-4f * std::fabs(tw));
        EXPECT_NEAR(uv, uw, 1e-4f);
        EXPECT_NEAR(vv, vw, 1e-4f);
    }
    EXPECT_GT(hits, compared / 4);  // the rays aim at the triangles: most of them hit
    EXPECT_GT(compared - hits, compared / 10);
}

TEST(Cwbvh, DeeperThanTheStackIsRefused) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 100, 1);
    trav::Structure s;
    s.layout = trav::Layout::kCwbvh;
    s.cwbvh = convert_to_cwbvh(
        collapse_to_wide(build(mesh, BuilderKind::kBinned, 4), mesh, CollapseMethod::kSahOptimal), mesh);
    EXPECT_NO_THROW(trav::make_cpu_tracer(s));
    s.cwbvh.depth = trav::kCwbvhStackSize + 1;  // a forged depth: refused before any ray
    EXPECT_THROW(trav::make_cpu_tracer(s), Error);
    std::vector<trav::Hit> hits;
    EXPECT_THROW(trav::trace_cpu(s.cwbvh, {}, trav::Query::kClosest, hits), Error);
}

}  // namespace
}  // namespace bvhlab::accel
