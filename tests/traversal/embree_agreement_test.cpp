// SPDX-License-Identifier: MIT
// Oracle tests: every ray type, ray by ray against Embree, on the Cornell box, generated
// scenes, and every scene in $BVHLAB_SCENES. Zero real mismatches allowed.
#include <gtest/gtest.h>

#include <functional>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "scene/scene.h"
#include "tests/support/agreement.h"
#include "tests/support/test_support.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/cpu/kd_trace.h"
#include "traversal/oracle/compare.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/scene_catalogue.h"

namespace bvhlab::trav {
namespace {

using test::Tracer;

/// Traces all four ray types with `trace` and expects zero real mismatches.
void expect_agreement_with(const scene::TriangleMesh& mesh, const Camera& cam, float ao_length, uint32_t w, uint32_t h,
                           const Tracer& trace) {
    EmbreeOracle oracle(mesh);
    test::expect_protocol_agreement(mesh, oracle, cam, ao_length, w, h, trace);
}

/// The same with a BVH from `builder`.
void expect_agreement(const scene::TriangleMesh& mesh, const Camera& cam, float ao_length, uint32_t w, uint32_t h,
                      accel::BuilderKind builder) {
    const accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(builder, mesh, {}).tree, mesh);
    expect_agreement_with(mesh, cam, ao_length, w, h, [&](const RaySet& set, std::vector<Hit>& hits) {
        trace_cpu(bvh, set.rays, set.query, hits);
    });
}

/// The same with the CWBVH collapsed from a BVH of `builder` (the CPU reference of 'cwbvh').
void expect_cwbvh_agreement(const scene::TriangleMesh& mesh, const Camera& cam, float ao_length, uint32_t w, uint32_t h,
                            accel::BuilderKind builder, accel::CollapseMethod method,
                            accel::CwTris tris = accel::CwTris::kWoop) {
    const accel::Cwbvh cw = accel::convert_to_cwbvh(
        accel::collapse_to_wide(accel::run_builder(builder, mesh, {}).tree, mesh, method), mesh, tris);
    ASSERT_EQ(cw.tri_format, tris);
    ASSERT_EQ(tris == accel::CwTris::kVertices ? cw.vtris.size() : cw.tris.size(), cw.tri_ids.size());
    expect_agreement_with(mesh, cam, ao_length, w, h,
                          [&](const RaySet& set, std::vector<Hit>& hits) { trace_cpu(cw, set.rays, set.query, hits); });
}

}  // namespace

TEST(EmbreeAgreement, CornellBox) {
    scene::TriangleMesh mesh = scene::load_obj(test::data_dir() + "/cornell_box.obj");
    Camera cam;
    cam.eye = {278, 273, -800};
    cam.target = {278, 273, 0};
    cam.fov_y_deg = 39.3f;
    for (auto b : {accel::BuilderKind::kBinned, accel::BuilderKind::kSweep, accel::BuilderKind::kSbvh}) {
        expect_agreement(mesh, cam, 0.05f * mesh.diagonal(), 160, 120, b);
        for (auto m : {accel::CollapseMethod::kSahOptimal, accel::CollapseMethod::kGreedy})
            expect_cwbvh_agreement(mesh, cam, 0.05f * mesh.diagonal(), 160, 120, b, m);
        expect_cwbvh_agreement(mesh, cam, 0.05f * mesh.diagonal(), 160, 120, b, accel::CollapseMethod::kSahOptimal,
                               accel::CwTris::kVertices);
    }
}

TEST(EmbreeAgreement, GeneratedScenes) {
    for (auto kind : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured}) {
        scene::TriangleMesh mesh = scene::make_procedural(kind, 20000, 3);
        for (auto b : {accel::BuilderKind::kBinned, accel::BuilderKind::kSweep, accel::BuilderKind::kSbvh}) {
            expect_agreement(mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96, b);
            for (auto m : {accel::CollapseMethod::kSahOptimal, accel::CollapseMethod::kGreedy})
                expect_cwbvh_agreement(mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96, b, m);
            expect_cwbvh_agreement(mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96, b,
                                   accel::CollapseMethod::kSahOptimal, accel::CwTris::kVertices);
        }
    }
}

TEST(EmbreeAgreement, FlattenedInstances) {
    // gen:instances: randomly turned, scaled, overlapping copies, flattened into one mesh (what
    // --flatten gives every structure). Copies cross each other everywhere: many triangles
    // intersect, and many rays hit near such crossings.
    const scene::TriangleMesh base = scene::make_procedural(scene::ProceduralKind::kStructured, 1500, 4);
    const scene::TriangleMesh mesh = scene::flatten(scene::make_instances(base, 12, 9));
    ASSERT_EQ(mesh.triangle_count(), 12 * base.triangle_count());
    for (auto b : {accel::BuilderKind::kBinned, accel::BuilderKind::kSbvh}) {
        expect_agreement(mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96, b);
        expect_cwbvh_agreement(mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96, b,
                               accel::CollapseMethod::kSahOptimal);
    }
    const accel::KdLayout kd = accel::convert_to_kd_layout(accel::KdTreeBuilder().build(mesh), mesh);
    expect_agreement_with(
        mesh, framing_camera(mesh), 0.05f * mesh.diagonal(), 128, 96,
        [&](const RaySet& set, std::vector<Hit>& hits) { trace_kd_cpu(kd, 64, set.rays, set.query, hits); });
}

TEST(EmbreeAgreement, DetectsABrokenTracer) {
    // The oracle must notice wrong answers: drop every hit on one triangle in ten.
    scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 5000, 1);
    accel::Bvh2 bvh = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, mesh, {}).tree, mesh);
    EmbreeOracle oracle(mesh);
    ProtocolConfig cfg;
    cfg.camera = framing_camera(mesh);
    cfg.primary = {64, 48, 1, 0};
    RaySet set = RayProtocol(mesh, oracle, cfg).make(RayType::kPrimary);
    std::vector<Hit> ours, ref;
    trace_cpu(bvh, set.rays, set.query, ours);
    oracle.trace(set.rays, set.query, ref);
    for (Hit& h : ours)
        if (h.tri % 10 == 3) h = Hit::miss();
    CompareReport rep = compare_hits(mesh, set.rays, set.query, ours, ref, {});
    EXPECT_GT(rep.mismatches, 10u);
}

TEST(EmbreeAgreement, BenchmarkScenes) {
    const std::string dir = test::scenes_dir();
    if (dir.empty()) GTEST_SKIP() << "BVHLAB_SCENES is not set: skipping the benchmark scenes";
    const std::vector<CatalogueEntry> cat = read_catalogue(dir);
    ASSERT_FALSE(cat.empty()) << "no scenes in " << dir << "/scenes.json";
    for (const CatalogueEntry& e : cat) {
        SCOPED_TRACE(e.name);
        scene::TriangleMesh mesh = scene::load_obj(e.file);
        EXPECT_EQ(mesh.triangle_count(), e.triangles);
        ASSERT_TRUE(e.camera.has_value());
        const Camera cam = *e.camera;
        // Every structure: binned and SBVH BVHs, and the kd-tree with a full and a short stack.
        for (auto b : {accel::BuilderKind::kBinned, accel::BuilderKind::kSbvh}) {
            SCOPED_TRACE(accel::builder_name(b));
            expect_agreement(mesh, cam, e.ao_length, 160, 120, b);
        }
        {
            SCOPED_TRACE("cwbvh from binned");
            expect_cwbvh_agreement(mesh, cam, e.ao_length, 160, 120, accel::BuilderKind::kBinned,
                                   accel::CollapseMethod::kSahOptimal);
        }
        const accel::KdLayout kd = accel::convert_to_kd_layout(accel::KdTreeBuilder().build(mesh), mesh);
        for (int stack : {64, 2}) {
            SCOPED_TRACE("kdtree stack " + std::to_string(stack));
            expect_agreement_with(mesh, cam, e.ao_length, 160, 120, [&](const RaySet& set, std::vector<Hit>& hits) {
                trace_kd_cpu(kd, stack, set.rays, set.query, hits);
            });
        }
    }
}

}  // namespace bvhlab::trav
