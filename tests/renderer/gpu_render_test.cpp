// SPDX-License-Identifier: MIT
// GPU renderer tests (ctest label "gpu"; each skips with the reason when there is no device):
// the GPU wavefront against the CPU reference integrator (Embree) within statistical error,
// a planted bug that the same comparison must catch, and every bounce's dumped rays verified
// against Embree with 0 real mismatches.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "accel/core/check.h"
#include "accel/io/obj_loader.h"
#include "renderer/compare.h"
#include "renderer/gpu/gpu_render.h"
#include "renderer/image.h"
#include "tests/support/gpu_support.h"
#include "tests/support/test_support.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/oracle/compare.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/ray_file.h"
#include "traversal/rays/scene_catalogue.h"

namespace bvhlab::render {
namespace {

struct Scene {
    std::string name;
    accel::TriangleMesh mesh;
    trav::Camera camera;
};

/// The project's two renderer scenes, then the benchmark scenes when $BVHLAB_SCENES is set
/// (with_benchmarks).
std::vector<Scene> scenes(bool with_benchmarks) {
    std::vector<Scene> out;
    std::vector<trav::CatalogueEntry> entries = trav::read_catalogue(test::data_dir());
    if (with_benchmarks && !test::scenes_dir().empty())
        for (auto& e : trav::read_catalogue(test::scenes_dir()))
            if (e.name != "cornell-box") entries.push_back(e);
    for (const auto& e : entries) {
        Scene s{e.name, accel::load_obj(e.file), {}};
        s.camera = e.camera ? *e.camera : trav::framing_camera(s.mesh);
        out.push_back(std::move(s));
    }
    return out;
}

RenderResult cpu_reference(const Scene& s, uint32_t w, uint32_t h, const RenderSettings& rs,
                           const SkyOption& sky = {}) {
    const RenderScene scene(s.mesh, sky);
    trav::EmbreeOracle oracle(s.mesh);
    auto tracer = trav::make_embree_tracer(oracle, false);
    return render_host(scene, make_camera(s.camera, w, h, {}), rs, *tracer, *tracer);
}

RenderResult gpu_render(const Scene& s, uint32_t w, uint32_t h, const RenderSettings& rs, const std::string& kernel,
                        const SkyOption& sky = {}) {
    const trav::KernelInfo& k = trav::find_kernel(kernel);
    const trav::Structure st = trav::make_structure(s.mesh, k.layout, accel::BuilderKind::kBinned);
    const trav::DeviceStructure device(st);
    const RenderScene scene(s.mesh, sky);
    return render_gpu(scene, make_camera(s.camera, w, h, {}), rs, device, k);
}

// Independent seeds on the two devices, so the comparison is a real test of the means.
TEST(GpuRender, AgreesWithTheCpuReferenceWithinNoise) {
    BVHLAB_SKIP_WITHOUT_GPU();
    RenderSettings rs;
    rs.max_depth = 8;
    for (const Scene& s : scenes(false)) {
        SCOPED_TRACE(s.name);
        rs.spp = 256;
        rs.seed = 1;
        const RenderResult cpu = cpu_reference(s, 32, 24, rs);
        rs.spp = 1024;
        for (const char* kernel : {"dynamic-speculative-fma", "plain", "dynamic-cwbvh"}) {
            SCOPED_TRACE(kernel);
            rs.seed = 2;
            const RenderResult gpu = gpu_render(s, 32, 24, rs, kernel);
            EXPECT_EQ(gpu.spp, 1024u);
            EXPECT_EQ(gpu.bounces.at(0).extension_rays, 1024u * 32 * 24);
            // Caustics through the glass give heavy tails: pixels' variance estimates are
            // poor there, so the regions decide and the outlier bound is loose.
            CompareConfig cc;
            cc.pixel_outliers = 0.05;
            const Comparison c = compare_renders(cpu, gpu, cc);
            EXPECT_TRUE(c.agree) << c.summary();
            RecordProperty(s.name + "/" + kernel, c.summary());
        }
    }
}

// Emitters and an environment map with a bright patch together: next-event estimation picks
// between them, and the GPU agrees with the CPU reference.
TEST(GpuRender, AgreesUnderAnEnvironmentMap) {
    BVHLAB_SKIP_WITHOUT_GPU();
    Image map(64, 32);
    for (uint32_t y = 0; y < 32; ++y)
        for (uint32_t x = 0; x < 64; ++x) map.at(x, y) = (x >= 28 && x < 36 && y < 12) ? splat(40.0f) : splat(0.3f);
    test::TempFile file("gpu_env.pfm");
    write_image(map, file.path());
    SkyOption sky;
    sky.env_file = file.path();
    const Scene s = scenes(false).at(1);  // the glass-and-mirror scene: open at the front
    RenderSettings rs;
    rs.spp = 256;
    const RenderResult cpu = cpu_reference(s, 32, 24, rs, sky);
    rs.spp = 1024;
    rs.seed = 2;
    const RenderResult gpu = gpu_render(s, 32, 24, rs, "dynamic-speculative-fma", sky);
    CompareConfig cc;
    cc.pixel_outliers = 0.05;
    const Comparison c = compare_renders(cpu, gpu, cc);
    EXPECT_TRUE(c.agree) << c.summary();
}

// The GPU's albedo and normal buffers are the CPU's, up to the jitter of other seeds.
TEST(GpuRender, AlbedoAndNormalBuffersMatchTheCpu) {
    BVHLAB_SKIP_WITHOUT_GPU();
    for (const Scene& s : scenes(false)) {
        SCOPED_TRACE(s.name);
        RenderSettings rs;
        rs.spp = 64;
        rs.aovs = true;
        const RenderResult cpu = cpu_reference(s, 32, 24, rs);
        const RenderResult gpu = gpu_render(s, 32, 24, rs, "dynamic-speculative-fma");
        ASSERT_EQ(gpu.albedo.pixels.size(), cpu.albedo.pixels.size());
        double diff = 0.0, total = 0.0;
        for (size_t i = 0; i < cpu.albedo.pixels.size(); ++i) {
            diff += std::fabs(gpu.albedo.pixels[i].y - cpu.albedo.pixels[i].y);
            total += cpu.albedo.pixels[i].y;
            EXPECT_NEAR(dot(gpu.normal.pixels[i], cpu.normal.pixels[i]),
                        length(cpu.normal.pixels[i]) * length(gpu.normal.pixels[i]), 0.2f);
        }
        EXPECT_LT(diff, 0.01 * total);
    }
}

// The same comparison fails for a GPU render with a planted bug.
TEST(GpuRender, APlantedBugFailsTheComparison) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const Scene s = scenes(false).at(0);
    RenderSettings rs;
    rs.spp = 256;
    const RenderResult cpu = cpu_reference(s, 32, 24, rs);
    for (PlantedBug bug : {PlantedBug::kNoCosine, PlantedBug::kBsdfWeightOne}) {
        rs.bug = bug;
        rs.seed = 2;
        const Comparison c = compare_renders(cpu, gpu_render(s, 32, 24, rs, "dynamic-speculative-fma"));
        EXPECT_FALSE(c.agree) << "planted bug " << int(bug) << ": " << c.summary();
    }
}

// Every bounce's extension and shadow rays of a GPU render, traced again by the GPU kernel,
// agree with Embree: 0 real mismatches.
TEST(GpuRender, DumpedRaysOfEveryBounceVerifyAgainstEmbree) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const std::string kernel = "dynamic-speculative-fma";
    for (const Scene& s : scenes(true)) {
        SCOPED_TRACE(s.name);
        test::TempFile dir("gpu_dump_" + s.name);
        RenderSettings rs;
        rs.spp = 1;
        rs.max_depth = 6;
        rs.dump_rays_dir = dir.path();
        const RenderResult r = gpu_render(s, 96, 72, rs, kernel);
        const trav::KernelInfo& k = trav::find_kernel(kernel);
        auto device = std::make_shared<const trav::DeviceStructure>(
            trav::make_structure(s.mesh, k.layout, accel::BuilderKind::kBinned));
        auto tracer = trav::make_gpu_tracer(device, k);
        trav::EmbreeOracle oracle(s.mesh);
        size_t files = 0;
        for (const auto& f : std::filesystem::directory_iterator(dir.path())) {
            SCOPED_TRACE(f.path().filename().string());
            const trav::RaySet set = trav::read_ray_file(f.path().string());
            std::vector<trav::Hit> ours, ref;
            tracer->trace(set, ours);
            oracle.trace(set.rays, set.query, ref);
            const trav::CompareReport rep = trav::compare_hits(
                s.mesh, set.rays, set.query, ours, ref, [&](const trav::Ray& ray) { return oracle.intersect(ray); });
            EXPECT_EQ(rep.mismatches, 0u);
            ++files;
        }
        EXPECT_GE(files, 2u);
        EXPECT_GE(r.bounces.size(), 2u);
        std::filesystem::remove_all(dir.path());
    }
}

}  // namespace
}  // namespace bvhlab::render
