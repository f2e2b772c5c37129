// SPDX-License-Identifier: MIT
// BVH2 traversal (the shared host/device code) against a double-precision brute force.
#include <gtest/gtest.h>

#include <random>

#include "accel/builders/builder.h"
#include "accel/layouts/bvh2_convert.h"
#include "scene/io/procedural.h"
#include "tests/support/test_support.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/oracle/compare.h"
#include "traversal/reference/ref_intersect.h"

namespace bvhlab::trav {
namespace {

std::vector<Ray> random_rays(size_t n, uint32_t seed, float tmax) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.5f, 1.5f), d(-1.0f, 1.0f);
    std::vector<Ray> rays(n);
    for (auto& r : rays) r = {{u(rng), u(rng), u(rng)}, 0.0f, {d(rng), d(rng), d(rng)}, tmax};
    return rays;
}

class TraverseVsBruteForce : public ::testing::TestWithParam<std::tuple<accel::BuilderKind, scene::ProceduralKind>> {};

TEST_P(TraverseVsBruteForce, ClosestAndAnyHit) {
    const auto [builder, kind] = GetParam();
    scene::TriangleMesh mesh = scene::make_procedural(kind, 3000, 21);
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(builder, mesh, {}).tree, mesh);
    for (float tmax : {INFINITY, 0.3f}) {
        std::vector<Ray> rays = random_rays(4000, 5, tmax);
        std::vector<Hit> closest, any;
        trace_cpu(bvh, rays, Query::kClosest, closest);
        trace_cpu(bvh, rays, Query::kAny, any);
        int hits = 0, edge = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const Hit ref = trace_brute_force(mesh, rays[i]);
            hits += ref.is_hit();
            if (closest[i].tri != ref.tri) {
                // Only a hit within float error of an edge (or the same t) may differ.
                const Hit& h = ref.is_hit() ? ref : closest[i];
                const float w = 1.0f - h.u - h.v;
                const bool tie =
                    std::min({h.u, h.v, w}) < 1e-4f ||
                    (ref.is_hit() && closest[i].is_hit() &&
                     std::fabs(ref.t - closest[i].t) <= t_tolerance(rays[i], ref.t, mesh.vertex(ref.tri, 0),
                                                                    mesh.vertex(ref.tri, 1), mesh.vertex(ref.tri, 2)));
                EXPECT_TRUE(tie) << "ray " << i << " ref " << ref.tri << " got " << closest[i].tri;
                ++edge;
            } else if (ref.is_hit()) {
                EXPECT_NEAR(closest[i].t, ref.t,
                            t_tolerance(rays[i], ref.t, mesh.vertex(ref.tri, 0), mesh.vertex(ref.tri, 1),
                                        mesh.vertex(ref.tri, 2)));
            }
            // Any-hit reports a hit exactly when a closest hit exists (up to edge ties).
            if (any[i].is_hit() != closest[i].is_hit()) ++edge;
            if (any[i].is_hit()) {
                EXPECT_GE(any[i].t, closest[i].is_hit() ? closest[i].t : 0.0f);
                EXPECT_LE(any[i].t, tmax);
            }
        }
        EXPECT_GT(hits, 50);  // short rays (tmax 0.3) over the height field hit less often
        EXPECT_LT(edge, 5);
    }
}

INSTANTIATE_TEST_SUITE_P(Builders, TraverseVsBruteForce,
                         ::testing::Combine(::testing::Values(accel::BuilderKind::kBinned, accel::BuilderKind::kSweep),
                                            ::testing::Values(scene::ProceduralKind::kSoup,
                                                              scene::ProceduralKind::kStructured)));

TEST(Traverse, SingleTriangleRootLeafAndAxisAlignedRays) {
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}});
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, m, {}).tree, m);
    ASSERT_EQ(bvh.nodes.size(), 1u);
    // Axis-aligned direction (zero components) onto a flat box.
    Hit h = traverse_bvh2<false>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(),
                                 Ray{{0.25f, 0.25f, 5.0f}, 0.0f, {0, 0, -1}, INFINITY});
    EXPECT_EQ(h.tri, 0);
    EXPECT_FLOAT_EQ(h.t, 5.0f);
    h = traverse_bvh2<false>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(),
                             Ray{{2.0f, 0.25f, 5.0f}, 0.0f, {0, 0, -1}, INFINITY});
    EXPECT_FALSE(h.is_hit());
}

TEST(Traverse, CountersCountWork) {
    scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 5000, 2);
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, mesh, {}).tree, mesh);
    std::vector<Ray> rays = random_rays(500, 3, INFINITY);
    std::vector<Hit> a, b;
    std::vector<TraversalCounters> c;
    trace_cpu(bvh, rays, Query::kClosest, a);
    trace_cpu(bvh, rays, Query::kClosest, b, &c);
    uint64_t tests = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(a[i].tri, b[i].tri);
        EXPECT_GE(c[i].nodes, 1u);
        if (b[i].is_hit()) EXPECT_GE(c[i].tri_tests, 1u);
        tests += c[i].tri_tests;
    }
    EXPECT_LT(tests, uint64_t(rays.size()) * 5000 / 10);  // far fewer than brute force
}

}  // namespace
}  // namespace bvhlab::trav
