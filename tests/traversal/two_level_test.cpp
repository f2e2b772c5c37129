// SPDX-License-Identifier: MIT
// Two-level BVHs on the CPU: every ray type against Embree's own instances, on generated
// instanced scenes (randomly turned, scaled, overlapping copies) and the glTF test scene, with
// each BVH builder for the BLAS. Zero real mismatches allowed.
#include <gtest/gtest.h>

#include <algorithm>

#include "accel/builders/builder.h"
#include "accel/core/check.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/two_level.h"
#include "scene/io/procedural.h"
#include "scene/io/scene_file.h"
#include "scene/scene.h"
#include "tests/support/agreement.h"
#include "tests/support/test_support.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::trav {
namespace {

accel::MeshBuilder builder_of(accel::BuilderKind kind) {
    return [kind](const scene::TriangleMesh& m) { return accel::run_builder(kind, m, {}).tree; };
}

/// The two-level BVH of `placed` (BLAS by `kind`, in `layout`) against Embree's instances, every
/// ray type, hits checked in world space on the flattened scene (ids as the two-level numbering).
void expect_two_level_agreement(const scene::InstancedScene& placed, accel::BuilderKind kind,
                                const accel::BlasLayout& layout = {}, uint32_t w = 96, uint32_t h = 72) {
    SCOPED_TRACE(std::string(accel::builder_name(kind)) + (layout.wide ? " cwbvh" : " bvh2") +
                 (layout.tris == accel::CwTris::kVertices ? " vertices" : ""));
    const accel::TwoLevelBvh bvh = accel::build_two_level(placed, builder_of(kind), layout);
    ASSERT_EQ(bvh.wide(), layout.wide);
    const scene::TriangleMesh world = scene::flatten(placed, /*keep_all=*/true);
    ASSERT_EQ(world.triangle_count(), bvh.world_triangles);
    const EmbreeOracle oracle(placed);
    const Camera cam = placed.camera
                           ? Camera{{placed.camera->eye.x, placed.camera->eye.y, placed.camera->eye.z},
                                    {placed.camera->target.x, placed.camera->target.y, placed.camera->target.z},
                                    {placed.camera->up.x, placed.camera->up.y, placed.camera->up.z},
                                    placed.camera->fov_y_deg}
                           : framing_camera(world);
    test::expect_protocol_agreement(
        world, oracle, cam, 0.05f * world.diagonal(), w, h,
        [&](const RaySet& set, std::vector<Hit>& hits) { trace_cpu(bvh, set.rays, set.query, hits); });
}

}  // namespace

TEST(TwoLevel, GeneratedInstancesAgreeWithEmbreeInstances) {
    for (auto kind : {scene::ProceduralKind::kStructured, scene::ProceduralKind::kSoup}) {
        const scene::TriangleMesh base = scene::make_procedural(kind, 2000, 5);
        for (uint32_t n : {1u, 7u, 40u}) {
            SCOPED_TRACE(std::to_string(n) + " instances");
            const scene::InstancedScene placed = scene::make_instances(base, n, 11 + n);
            for (auto b : {accel::BuilderKind::kBinned, accel::BuilderKind::kSweep, accel::BuilderKind::kSbvh})
                expect_two_level_agreement(placed, b);
            // CWBVH BLAS: both collapses, both triangle formats.
            expect_two_level_agreement(placed, accel::BuilderKind::kBinned, {true});
            expect_two_level_agreement(placed, accel::BuilderKind::kSbvh,
                                       {true, accel::CollapseMethod::kGreedy, accel::CwTris::kVertices});
        }
    }
}

TEST(TwoLevel, GltfSceneAgreesWithEmbreeInstances) {
    // Three instances of a cube (one turned by a parent node, one scaled), placed next to and
    // touching each other, over a floor: faces of neighbouring instances are coplanar.
    scene::InstancedScene placed = scene::load_assimp(test::data_dir() + "/instances.glb");
    ASSERT_TRUE(placed.is_instanced());
    // The file's camera looks straight down -z at the middle of a cube face, so a row of pixel
    // centres lies exactly on the face's diagonal: shared-edge ties by construction, beyond the
    // cap meant for scenes without such alignments. A small turn of the view breaks it.
    placed.camera->target = placed.camera->target + Vec3{0.0123f, 0.0071f, 0.0f};
    expect_two_level_agreement(placed, accel::BuilderKind::kBinned, {}, 160, 120);
    expect_two_level_agreement(placed, accel::BuilderKind::kBinned, {true}, 160, 120);
}

TEST(TwoLevel, SeveralMeshesAndSceneWideIds) {
    // Two meshes, each placed several times, interleaved: ids count every earlier instance.
    scene::InstancedScene placed;
    placed.meshes.push_back(scene::make_procedural(scene::ProceduralKind::kStructured, 300, 1));
    placed.meshes.push_back(scene::make_procedural(scene::ProceduralKind::kSoup, 500, 2));
    placed.meshes.push_back(scene::make_procedural(scene::ProceduralKind::kSoup, 50, 3));  // placed by nobody
    const scene::InstancedScene a = scene::make_instances(placed.meshes[0], 6, 3);
    const scene::InstancedScene b = scene::make_instances(placed.meshes[1], 5, 4);
    for (size_t i = 0; i < 6; ++i) {
        placed.instances.push_back(a.instances[i]);
        if (i < 5) {
            placed.instances.push_back(b.instances[i]);
            placed.instances.back().mesh = 1;
        }
    }
    const accel::TwoLevelBvh bvh = accel::build_two_level(placed, builder_of(accel::BuilderKind::kBinned));
    EXPECT_EQ(bvh.world_triangles, 6u * 300u + 5u * 500u);
    EXPECT_TRUE(bvh.blas[2].nodes.empty()) << "a mesh no instance places gets no BLAS";
    ASSERT_EQ(bvh.instances.size(), 11u);
    EXPECT_EQ(bvh.instances[0].first_id, 0u);
    EXPECT_EQ(bvh.instances[1].first_id, 300u);
    EXPECT_EQ(bvh.instances[2].first_id, 800u);
    EXPECT_EQ(bvh.instance_of_id(0), 0u);
    EXPECT_EQ(bvh.instance_of_id(299), 0u);
    EXPECT_EQ(bvh.instance_of_id(300), 1u);
    EXPECT_EQ(bvh.instance_of_id(799), 1u);
    EXPECT_EQ(bvh.instance_of_id(800), 2u);
    EXPECT_EQ(bvh.instance_of_id(uint32_t(bvh.world_triangles - 1)), 10u);
    EXPECT_EQ(bvh.tlas.tri_ids.size(), 11u) << "one TLAS entry per instance";
    // Bytes: each placed mesh's BLAS once, the TLAS and a record per instance; far less than the
    // flattened scene's BVH2 (4,300 triangles against the BLASes' 800).
    size_t blas_bytes = 0;
    for (const accel::Bvh2& b : bvh.blas) blas_bytes += b.bytes();
    EXPECT_EQ(bvh.bytes(), blas_bytes + bvh.tlas.bytes() + 11 * sizeof(accel::InstanceRecord));
    const scene::TriangleMesh world = scene::flatten(placed, true);
    const size_t flat_bytes =
        accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kBinned, world, {}).tree, world).bytes();
    EXPECT_GT(bvh.bytes(), blas_bytes);
    EXPECT_LT(bvh.bytes(), flat_bytes / 3);
    expect_two_level_agreement(placed, accel::BuilderKind::kBinned);
    const accel::TwoLevelBvh wide = accel::build_two_level(placed, builder_of(accel::BuilderKind::kBinned), {true});
    EXPECT_TRUE(wide.blas.empty());
    ASSERT_EQ(wide.cw_blas.size(), 3u);
    EXPECT_TRUE(wide.cw_blas[2].nodes.empty()) << "a mesh no instance places gets no BLAS";
    EXPECT_EQ(wide.tlas.nodes.size(), bvh.tlas.nodes.size()) << "the same TLAS over the same boxes";
    EXPECT_TRUE(bvh.cw_tlas.nodes.empty());
    ASSERT_FALSE(wide.cw_tlas.nodes.empty()) << "and its 8-wide form";
    size_t cw_bytes = 0;
    for (const accel::Cwbvh& b : wide.cw_blas) cw_bytes += b.bytes();
    EXPECT_EQ(wide.bytes(), cw_bytes + wide.tlas.bytes() + wide.cw_tlas.bytes() + 11 * sizeof(accel::InstanceRecord));
    std::vector<uint32_t> entered = wide.cw_tlas.tri_ids;
    std::sort(entered.begin(), entered.end());
    for (uint32_t i = 0; i < 11; ++i) EXPECT_EQ(entered[i], i) << "each instance in one leaf entry";
    EXPECT_LT(wide.cw_tlas.depth, wide.tlas.depth);
    for (size_t i = 0; i < 11; ++i) EXPECT_EQ(wide.instances[i].first_id, bvh.instances[i].first_id);
    expect_two_level_agreement(placed, accel::BuilderKind::kBinned, {true});
}

TEST(TwoLevel, DetectsABrokenTwoLevelBvh) {
    // The comparison must notice a wrong transform or a wrong id range.
    const scene::InstancedScene placed =
        scene::make_instances(scene::make_procedural(scene::ProceduralKind::kStructured, 2000, 1), 6, 2);
    const scene::TriangleMesh world = scene::flatten(placed, true);
    const EmbreeOracle oracle(placed);
    ProtocolConfig cfg;
    cfg.camera = framing_camera(world);
    cfg.primary = {64, 48, 1, 0};
    const RaySet set = RayProtocol(world, oracle, cfg).make(RayType::kPrimary);
    std::vector<Hit> ref;
    oracle.trace(set.rays, set.query, ref);
    for (int defect = 0; defect < 4; ++defect) {
        // Defects 0 and 1 on BVH2 BLAS, 2 and 3 on CWBVH BLAS.
        accel::TwoLevelBvh bvh = accel::build_two_level(placed, builder_of(accel::BuilderKind::kBinned), {defect >= 2});
        if (defect >= 2) {
            if (defect == 2) bvh.instances[1].world_to_object[3] += 0.05f * world.diagonal();
            if (defect == 3) std::swap(bvh.instances[2].first_id, bvh.instances[3].first_id);
        }
        if (defect == 0) bvh.instances[1].world_to_object[3] += 0.05f * world.diagonal();  // moved
        if (defect == 1) std::swap(bvh.instances[2].first_id, bvh.instances[3].first_id);  // ids swapped
        std::vector<Hit> ours;
        trace_cpu(bvh, set.rays, set.query, ours);
        const CompareReport rep = compare_hits(world, set.rays, set.query, ours, ref, {});
        EXPECT_GT(rep.mismatches, 20u) << "defect " << defect;
    }
}

TEST(TwoLevel, EmbreeInstancesAgreeWithTheFlattenedScene) {
    // The oracle itself: Embree's instances and Embree over the flattened triangles give the
    // same closest hits (up to ties), with the same ids.
    const scene::InstancedScene placed =
        scene::make_instances(scene::make_procedural(scene::ProceduralKind::kSoup, 3000, 8), 20, 6);
    const scene::TriangleMesh world = scene::flatten(placed, true);
    const EmbreeOracle instanced(placed), flat(world);
    ProtocolConfig cfg;
    cfg.camera = framing_camera(world);
    cfg.primary = {96, 72, 1, 0};
    RayProtocol proto(world, flat, cfg);
    for (RayType t : {RayType::kPrimary, RayType::kDiffuse}) {
        const RaySet set = proto.make(t);
        std::vector<Hit> a, b;
        instanced.trace(set.rays, set.query, a);
        flat.trace(set.rays, set.query, b);
        const CompareReport rep = test::expect_no_real_mismatch(world, flat, set.rays, set.query, a, b);
        EXPECT_GT(rep.agree, rep.rays * 99 / 100);
    }
}

TEST(TwoLevel, RefusesWhatItCannotNumber) {
    scene::InstancedScene empty;
    empty.meshes.push_back(scene::make_procedural(scene::ProceduralKind::kSoup, 10, 1));
    EXPECT_THROW(accel::build_two_level(empty, builder_of(accel::BuilderKind::kBinned)), Error);
    scene::InstancedScene singular = scene::make_instances(empty.meshes[0], 2, 1);
    for (int k = 0; k < 3; ++k) singular.instances[1].transform.m[4 * k] = 0.0f;  // x maps to 0
    try {
        accel::build_two_level(singular, builder_of(accel::BuilderKind::kBinned));
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("instance 1 has a singular"), std::string::npos) << e.what();
    }
}

}  // namespace bvhlab::trav
