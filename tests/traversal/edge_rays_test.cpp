// SPDX-License-Identifier: MIT
// Rays on the edges and planes of each structure (tests/support/edge_rays.h) through every CPU
// tracer: along box faces and edges, through and from corners, from faces, with tmin = tmax,
// across and along flat boxes, in a scene whose triangles and vertices lie on the split
// planes. Each agrees with Embree with 0 real mismatches under the strict oracle, closest and
// any hit. The GPU kernels run the same rays in GpuKernel.AgreesWithEmbreeOnEdgeAndPlaneRays.
#include <gtest/gtest.h>

#include <functional>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/layouts/two_level.h"
#include "accel/passes/collapse_wide.h"
#include "tests/support/agreement.h"
#include "tests/support/edge_rays.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/cpu/kd_trace.h"

namespace bvhlab::trav {
namespace {

using Tracer = std::function<void(const std::vector<Ray>&, Query, std::vector<Hit>&)>;

/// The structure's edge rays, closest and any hit, through `trace`: 0 real mismatches.
void expect_edge_rays_agree(const scene::TriangleMesh& mesh, const EmbreeOracle& oracle, const Structure& s,
                            const Tracer& trace, uint32_t seed) {
    const std::vector<Ray> rays = test::edge_rays(test::structure_boxes(s), mesh.bounds(), seed, 400);
    ASSERT_GT(rays.size(), 2000u);
    for (Query q : {Query::kClosest, Query::kAny}) {
        SCOPED_TRACE(q == Query::kClosest ? "closest" : "any");
        std::vector<Hit> ours, ref;
        trace(rays, q, ours);
        oracle.trace(rays, q, ref);
        test::expect_no_real_mismatch(mesh, oracle, rays, q, ours, ref);
    }
}

const std::vector<scene::TriangleMesh>& lattices() {
    static const std::vector<scene::TriangleMesh> m{test::make_lattice_scene(1), test::make_lattice_scene(2)};
    return m;
}

}  // namespace

TEST(EdgeRays, SceneAndRaysAreWhatTheyPromise) {
    const scene::TriangleMesh& m = lattices()[0];
    const AABB b = m.bounds();
    EXPECT_EQ(b.lo.x, 0.0f);
    EXPECT_EQ(b.hi.z, 32.0f);
    size_t flat_on_plane = 0, vertex_on_lattice = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const float a = m.vertex(t, 0)[k];
            flat_on_plane += a == std::floor(a) && a == m.vertex(t, 1)[k] && a == m.vertex(t, 2)[k];
        }
        const Vec3 v = m.vertex(t, 0);
        vertex_on_lattice += v.x == std::floor(v.x) && v.y == std::floor(v.y) && v.z == std::floor(v.z);
    }
    EXPECT_GT(flat_on_plane, 500u);
    EXPECT_EQ(vertex_on_lattice, m.triangle_count());
    // The SBVH cut triangles (references beyond the triangle count), and the kd-tree split on
    // planes that hold flat triangles.
    const accel::BuildTree sbvh = accel::run_builder(accel::BuilderKind::kSbvh, m, {}).tree;
    EXPECT_GT(sbvh.prim_indices.size(), m.triangle_count());
    Structure kd;
    kd.layout = Layout::kKd;
    kd.kd = accel::convert_to_kd_layout(accel::KdTreeBuilder().build(m), m);
    size_t integer_splits = 0, interior = 0;
    for (const accel::KdNode& n : kd.kd.tree.nodes) {
        if (n.is_leaf()) continue;
        ++interior;
        integer_splits += n.split() == std::floor(n.split());
    }
    EXPECT_GT(integer_splits, interior / 2);
    // The rays: in a box's plane with a zero component (both signs), along edges, and with
    // tmin = tmax.
    const std::vector<AABB> boxes = test::structure_boxes(kd);
    const std::vector<Ray> rays = test::edge_rays(boxes, b, 1, 400);
    size_t zero_component = 0, negative_zero = 0, two_zeros = 0, empty_interval = 0, flat_boxes = 0;
    for (const Ray& r : rays) {
        const int zeros = (r.dir.x == 0.0f) + (r.dir.y == 0.0f) + (r.dir.z == 0.0f);
        zero_component += zeros >= 1;
        two_zeros += zeros == 2;
        negative_zero += std::signbit(r.dir.x) && r.dir.x == 0.0f;
        empty_interval += r.tmin == r.tmax;
    }
    // Leaves of one flat quad make flat BVH boxes (kd cells are never flat).
    Structure bvh;
    bvh.bvh2 = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, m, {}).tree, m);
    for (const AABB& x : test::structure_boxes(bvh))
        flat_boxes += x.lo.x == x.hi.x || x.lo.y == x.hi.y || x.lo.z == x.hi.z;
    EXPECT_GT(zero_component, rays.size() / 4);
    EXPECT_GT(two_zeros, 200u);
    EXPECT_GT(negative_zero, 20u);
    EXPECT_GT(empty_interval, 200u);
    EXPECT_GT(flat_boxes, 20u);
}

TEST(EdgeRays, EveryBvhAndCwbvhAgreesWithEmbree) {
    for (size_t i = 0; i < lattices().size(); ++i) {
        const scene::TriangleMesh& mesh = lattices()[i];
        SCOPED_TRACE("lattice " + std::to_string(i + 1));
        const EmbreeOracle oracle(mesh);
        for (const test::BvhVariant& v : test::bvh_variants()) {
            const accel::BuildTree tree = v.build(mesh);
            SCOPED_TRACE(v.name());
            Structure bvh;
            bvh.bvh2 = accel::convert_to_bvh2(tree, mesh);
            expect_edge_rays_agree(
                mesh, oracle, bvh,
                [&](const std::vector<Ray>& r, Query q, std::vector<Hit>& h) { trace_cpu(bvh.bvh2, r, q, h); }, 7);
            for (auto tris : {accel::CwTris::kWoop, accel::CwTris::kVertices}) {
                SCOPED_TRACE(tris == accel::CwTris::kWoop ? "cwbvh woop" : "cwbvh vertices");
                Structure cw;
                cw.layout = Layout::kCwbvh;
                cw.cwbvh = accel::convert_to_cwbvh(
                    accel::collapse_to_wide(tree, mesh, accel::CollapseMethod::kSahOptimal), mesh, tris);
                expect_edge_rays_agree(
                    mesh, oracle, cw,
                    [&](const std::vector<Ray>& r, Query q, std::vector<Hit>& h) { trace_cpu(cw.cwbvh, r, q, h); }, 8);
            }
        }
    }
}

TEST(EdgeRays, TwoLevelBvhsAgreeWithEmbree) {
    // The lattice placed once (identity): the rays graze the TLAS's box and each BLAS's, BVH2
    // and CWBVH, through the two-level traversals.
    for (size_t i = 0; i < lattices().size(); ++i) {
        const scene::TriangleMesh& mesh = lattices()[i];
        SCOPED_TRACE("lattice " + std::to_string(i + 1));
        const EmbreeOracle oracle(mesh);
        for (auto builder : {accel::BuilderKind::kBinned, accel::BuilderKind::kSbvh}) {
            for (bool wide : {false, true}) {
                Structure s;
                s.layout = wide ? Layout::kTwoLevelCwbvh : Layout::kTwoLevel;
                s.two_level = accel::build_two_level(
                    scene::single_instance(mesh),
                    [&](const scene::TriangleMesh& m) { return accel::run_builder(builder, m, {}).tree; }, {wide});
                SCOPED_TRACE(std::string(accel::builder_name(builder)) + (wide ? " two-level cwbvh" : " two-level"));
                expect_edge_rays_agree(
                    mesh, oracle, s,
                    [&](const std::vector<Ray>& r, Query q, std::vector<Hit>& h) { trace_cpu(s.two_level, r, q, h); },
                    10);
            }
        }
    }
}

TEST(EdgeRays, EveryKdTreeAndStackAgreesWithEmbree) {
    accel::KdTreeBuilder::Config wh;  // Wald & Havran's constants: deeper trees, more flat cells
    wh.traversal_cost = 15.0f;
    wh.intersection_cost = 20.0f;
    wh.empty_bonus = 0.2f;
    for (size_t i = 0; i < lattices().size(); ++i) {
        const scene::TriangleMesh& mesh = lattices()[i];
        SCOPED_TRACE("lattice " + std::to_string(i + 1));
        const EmbreeOracle oracle(mesh);
        for (const auto& config : {accel::KdTreeBuilder::Config{}, wh}) {
            Structure kd;
            kd.layout = Layout::kKd;
            kd.kd = accel::convert_to_kd_layout(accel::KdTreeBuilder(config).build(mesh), mesh);
            for (int stack : {64, 1, 2, 8}) {
                SCOPED_TRACE("kd stack " + std::to_string(stack));
                expect_edge_rays_agree(
                    mesh, oracle, kd,
                    [&](const std::vector<Ray>& r, Query q, std::vector<Hit>& h) {
                        trace_kd_cpu(kd.kd, stack, r, q, h);
                    },
                    9);
            }
        }
    }
}

namespace {

/// Points where an SBVH leaf box's edges pass through the interior of a triangle the leaf
/// holds (a box edge made by split planes across the triangle), and rays in general directions
/// aimed at them. Such a point lies on the edges of every box around it, so a slab test whose
/// entry and exit round across each other there loses all of them, and with them a hit in the
/// middle of a triangle: a real mismatch, not a tie.
std::vector<Ray> sbvh_leaf_edge_rays(const scene::TriangleMesh& mesh, const accel::BuildTree& tree, uint32_t seed,
                                     size_t* points) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Ray> rays;
    *points = 0;
    for (const accel::BuildNode& n : tree.nodes) {
        if (!n.is_leaf()) continue;
        const AABB& b = n.bounds;
        for (uint32_t i = 0; i < n.prim_count; ++i) {
            const uint32_t t = tree.prim_indices[n.first_index + i];
            const Vec3 v0 = mesh.vertex(t, 0), v1 = mesh.vertex(t, 1), v2 = mesh.vertex(t, 2);
            // In double: the triangle's plane and barycentrics.
            const double e1[3] = {double(v1.x) - v0.x, double(v1.y) - v0.y, double(v1.z) - v0.z};
            const double e2[3] = {double(v2.x) - v0.x, double(v2.y) - v0.y, double(v2.z) - v0.z};
            const double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                   e1[0] * e2[1] - e1[1] * e2[0]};
            for (int j = 0; j < 3; ++j) {  // edges along axis j: the other two coordinates on box planes
                const int k1 = (j + 1) % 3, k2 = (j + 2) % 3;
                if (std::fabs(nrm[j]) < 1e-9) continue;  // the triangle is parallel to the edge
                for (int c = 0; c < 4; ++c) {
                    double p[3];
                    p[k1] = (c & 1) ? b.hi[k1] : b.lo[k1];
                    p[k2] = (c & 2) ? b.hi[k2] : b.lo[k2];
                    // The edge line meets the triangle's plane at p[j].
                    p[j] = v0[j] - (nrm[k1] * (p[k1] - v0[k1]) + nrm[k2] * (p[k2] - v0[k2])) / nrm[j];
                    if (!(p[j] > b.lo[j] && p[j] < b.hi[j])) continue;  // not on this edge of the box
                    // Barycentrics of p, well inside the triangle (not an edge tie).
                    const double w[3] = {p[0] - v0.x, p[1] - v0.y, p[2] - v0.z};
                    const double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
                    const double d12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
                    const double d22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
                    const double dw1 = w[0] * e1[0] + w[1] * e1[1] + w[2] * e1[2];
                    const double dw2 = w[0] * e2[0] + w[1] * e2[1] + w[2] * e2[2];
                    const double den = d11 * d22 - d12 * d12;
                    const double u = (d22 * dw1 - d12 * dw2) / den, v = (d11 * dw2 - d12 * dw1) / den;
                    if (u < 0.02 || v < 0.02 || u + v > 0.98) continue;
                    ++*points;
                    for (int r = 0; r < 32; ++r) {  // general directions from outside the scene
                        const double z = 2.0 * unit(rng) - 1.0, a = 6.283185307179586 * unit(rng);
                        const double s = std::sqrt(1.0 - z * z);
                        const Vec3 d{float(s * std::cos(a)), float(s * std::sin(a)), float(z)};
                        const Vec3 target{float(p[0]), float(p[1]), float(p[2])};
                        rays.push_back({target - d * 100.0f, 0.0f, d, 1000.0f});
                    }
                }
            }
        }
    }
    return rays;
}

}  // namespace

// Rays through the points where SBVH leaf edges cross the interior of their triangles, in
// general directions: 0 real mismatches for the BVH2 and CWBVH traversals. Without the slab
// exit's widening (x 1.0000004) some of these boxes are lost to rounding together with every
// neighbour at the same edge.
TEST(EdgeRays, SbvhLeafEdgesInsideTrianglesAgreeWithEmbree) {
    for (size_t i = 0; i < lattices().size(); ++i) {
        const scene::TriangleMesh& mesh = lattices()[i];
        SCOPED_TRACE("lattice " + std::to_string(i + 1));
        const EmbreeOracle oracle(mesh);
        accel::BuilderOptions o;
        o.config.max_leaf_size = 2;  // small leaves: more split-made edges
        o.sbvh_alpha = 0.0f;         // spatial splits wherever they pay
        const accel::BuildTree tree = accel::run_builder(accel::BuilderKind::kSbvh, mesh, o).tree;
        size_t points = 0;
        const std::vector<Ray> rays = sbvh_leaf_edge_rays(mesh, tree, 11 + uint32_t(i), &points);
        EXPECT_GT(points, 50u) << "too few leaf edges cross a triangle's interior";
        Structure bvh;
        bvh.bvh2 = accel::convert_to_bvh2(tree, mesh);
        Structure cw;
        cw.layout = Layout::kCwbvh;
        cw.cwbvh = accel::convert_to_cwbvh(accel::collapse_to_wide(tree, mesh, accel::CollapseMethod::kSahOptimal),
                                           mesh, accel::CwTris::kWoop);
        std::vector<Hit> ref, ours;
        oracle.trace(rays, Query::kClosest, ref);
        trace_cpu(bvh.bvh2, rays, Query::kClosest, ours);
        test::expect_no_real_mismatch(mesh, oracle, rays, Query::kClosest, ours, ref);
        trace_cpu(cw.cwbvh, rays, Query::kClosest, ours);
        test::expect_no_real_mismatch(mesh, oracle, rays, Query::kClosest, ours, ref);
    }
}

}  // namespace bvhlab::trav
