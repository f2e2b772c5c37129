// SPDX-License-Identifier: MIT
// GPU tests (ctest label "gpu"): the plain CUDA kernel runs the same traverse_bvh2 as the CPU
// tracer; its hits must match the CPU's and agree with Embree. Skips without a device.
#include <gtest/gtest.h>

#include "accel/builders/builder.h"
#include "accel/core/check.h"
#include "accel/io/obj_loader.h"
#include "accel/io/procedural.h"
#include "accel/layouts/bvh2_convert.h"
#include "tests/support/test_support.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/launch.h"
#include "traversal/oracle/compare.h"
#include "traversal/rays/protocol.h"

namespace bvhlab::trav {
namespace {

/// Empty when a GPU is usable, else why not. (GTEST_SKIP must be in the test body itself.)
std::string no_gpu_reason() {
    std::string why;
    return gpu_available(&why) ? std::string() : why;
}

#define BVHLAB_SKIP_WITHOUT_GPU()                                       \
    if (const std::string why = no_gpu_reason(); !why.empty()) GTEST_SKIP() << "no GPU: " << why

void expect_gpu_matches(const accel::TriangleMesh& mesh, const Camera& cam, uint32_t w, uint32_t h) {
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, mesh, {}).tree, mesh);
    EmbreeOracle oracle(mesh);
    ProtocolConfig cfg;
    cfg.camera = cam;
    cfg.primary = {w, h, 1, 0};
    RayProtocol proto(mesh, oracle, cfg);
    GpuBvh2 gpu(bvh);
    for (RayType t : {RayType::kPrimary, RayType::kAo, RayType::kDiffuse, RayType::kShadow}) {
        SCOPED_TRACE(ray_type_name(t));
        RaySet set = proto.make(t);
        std::vector<Hit> g, c, ref;
        gpu.trace(set.rays, set.query, g);
        trace_cpu(bvh, set.rays, set.query, c);
        ASSERT_EQ(g.size(), set.rays.size());
        // Same code on both sides; only FMA contraction on the device may move a t by an ulp
        // and flip an edge case, so ids must match on all but a handful of rays.
        size_t differ = 0;
        for (size_t i = 0; i < g.size(); ++i) differ += g[i].tri != c[i].tri;
        EXPECT_LE(differ, set.rays.size() / 10000 + 2);
        oracle.trace(set.rays, set.query, ref);
        CompareReport rep = compare_hits(mesh, set.rays, set.query, g, ref, [&](const Ray& r) { return oracle.intersect(r); });
        EXPECT_EQ(rep.mismatches, 0u);
    }
}

}  // namespace

TEST(GpuTrace, CornellBoxMatchesCpuAndEmbree) {
    BVHLAB_SKIP_WITHOUT_GPU();
    accel::TriangleMesh mesh = accel::load_obj(test::data_dir() + "/cornell_box.obj");
    Camera cam;
    cam.eye = {278, 273, -800};
    cam.target = {278, 273, 0};
    cam.fov_y_deg = 39.3f;
    expect_gpu_matches(mesh, cam, 256, 192);
}

TEST(GpuTrace, GeneratedScenesMatchCpuAndEmbree) {
    BVHLAB_SKIP_WITHOUT_GPU();
    for (auto kind : {accel::ProceduralKind::kSoup, accel::ProceduralKind::kStructured}) {
        accel::TriangleMesh mesh = accel::make_procedural(kind, 100000, 7);
        expect_gpu_matches(mesh, framing_camera(mesh), 320, 240);
    }
}

TEST(GpuTrace, EmptyRaySetAndReuse) {
    BVHLAB_SKIP_WITHOUT_GPU();
    accel::TriangleMesh mesh = accel::make_procedural(accel::ProceduralKind::kSoup, 100, 1);
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, mesh, {}).tree, mesh);
    GpuBvh2 gpu(bvh);
    std::vector<Hit> hits{Hit::miss()};
    gpu.trace({}, Query::kClosest, hits);
    EXPECT_TRUE(hits.empty());
    std::vector<Ray> rays(1000, Ray{{0.5f, 0.5f, -1.0f}, 0.0f, {0, 0, 1}, INFINITY});
    gpu.trace(rays, Query::kAny, hits);
    EXPECT_EQ(hits.size(), 1000u);
}

TEST(GpuTrace, ReportsWhyWithoutDevice) {
    std::string why;
    if (gpu_available(&why)) GTEST_SKIP() << "a GPU is present: " << gpu_description();
    EXPECT_FALSE(why.empty());
    accel::TriangleMesh mesh = accel::make_procedural(accel::ProceduralKind::kSoup, 10, 1);
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, mesh, {}).tree, mesh);
    EXPECT_THROW(GpuBvh2 g(bvh), Error);
}

}  // namespace bvhlab::trav
