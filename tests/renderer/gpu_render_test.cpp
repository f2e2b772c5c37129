// SPDX-License-Identifier: MIT
// GPU renderer tests (ctest label "gpu"; each skips with the reason when there is no device):
// the GPU wavefront against the CPU reference integrator (Embree) within statistical error,
// a planted bug that the same comparison must catch, and every bounce's dumped rays verified
// against Embree with 0 real mismatches.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "accel/core/check.h"
#include "renderer/compare.h"
#include "renderer/gpu/gpu_render.h"
#include "renderer/image.h"
#include "renderer/testing.h"
#include "scene/io/obj_loader.h"
#include "scene/scene.h"
#include "tests/support/gpu_support.h"
#include "tests/support/test_support.h"
#include "traversal/factory.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/oracle/compare.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/ray_file.h"
#include "traversal/rays/raygen.h"
#include "traversal/rays/scene_catalogue.h"

namespace bvhlab::render {
namespace {

struct Scene {
    std::string name;
    scene::TriangleMesh mesh;
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
        Scene s{e.name, scene::load_obj(e.file), {}};
        s.camera = e.camera ? *e.camera : trav::framing_camera(s.mesh);
        out.push_back(std::move(s));
    }
    return out;
}

Scene scene_named(const std::string& name) {
    for (Scene& s : scenes(false))
        if (s.name == name) return std::move(s);
    throw Error("no scene " + name + " in data/scenes.json");
}

RenderResult cpu_reference(const Scene& s, uint32_t w, uint32_t h, const RenderSettings& rs,
                           const SkyOption& sky = {}) {
    const RenderScene scene(s.mesh, sky);
    trav::EmbreeOracle oracle(s.mesh);
    auto tracer = trav::make_embree_tracer(oracle, false);
    return render_host(scene, make_camera(s.camera, w, h, {}), rs, *tracer, *tracer);
}

RenderResult gpu_render(const Scene& s, uint32_t w, uint32_t h, const RenderSettings& rs, const std::string& kernel,
                        const SkyOption& sky = {}, const LensOptions& lens = {}) {
    const trav::KernelInfo& k = trav::find_kernel(kernel);
    const trav::Structure st = trav::make_structure(s.mesh, k.layout, accel::BuilderKind::kBinned);
    const trav::DeviceStructure device(st);
    const RenderScene scene(s.mesh, sky);
    return render_gpu(scene, make_camera(s.camera, w, h, lens), rs, device, k);
}

/// The same image, bit for bit (the switches reorder work, never a path's arithmetic).
void expect_identical(const RenderResult& a, const RenderResult& b, const char* what) {
    ASSERT_EQ(a.mean.pixels.size(), b.mean.pixels.size()) << what;
    size_t differ = 0;
    for (size_t i = 0; i < a.mean.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) differ += a.mean.pixels[i][c] != b.mean.pixels[i][c];
    EXPECT_EQ(differ, 0u) << what << ": channels that differ";
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

// An instanced scene (turned, scaled, overlapping copies of the smooth spheres, lamp and floor
// included) traced two-level on the GPU by the layout's default kernel agrees with the CPU
// reference through Embree's instances, within noise.
TEST(GpuRender, AnInstancedSceneTracedTwoLevelAgreesWithTheCpu) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const Scene base = scene_named("smooth-spheres");
    const scene::InstancedScene placed = scene::make_instances(base.mesh, 4, 7);
    const scene::TriangleMesh world = scene::flatten(placed, true);
    const RenderScene rscene(world, {});
    const CameraData cam = make_camera(trav::framing_camera(world), 32, 24, {});
    RenderSettings rs;
    rs.spp = 256;
    const trav::EmbreeOracle oracle(placed);
    auto embree = trav::make_embree_tracer(oracle, false);
    const RenderResult cpu = render_host(rscene, cam, rs, *embree, *embree);
    trav::StructureSpec spec;
    spec.epo = false;
    trav::AccelStructure as = trav::build_structure(placed, spec);
    const trav::KernelInfo& k = trav::find_kernel(as.gpu_tracer()->name());
    EXPECT_EQ(k.layout, trav::Layout::kTwoLevel);
    rs.spp = 1024;
    rs.seed = 2;
    const RenderResult gpu = render_gpu(rscene, cam, rs, *as.device(), k);
    CompareConfig cc;
    cc.pixel_outliers = 0.05;
    const Comparison c = compare_renders(cpu, gpu, cc);
    EXPECT_TRUE(c.agree) << c.summary();
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
    const Scene s = scene_named("glass-mirror");  // open at the front
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

// Material sorting, no compaction and the first-hit cache change the order and amount of work,
// never the image; the counts show each switch did what it says.
TEST(GpuRender, SortingCompactionAndTheFirstHitCacheLeaveTheImageUnchanged) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const uint32_t w = 32, h = 24, npix = w * h;
    LensOptions centres;
    centres.pixel_centres = true;  // what the cache needs; the other runs use it too
    for (const Scene& s : scenes(false)) {
        SCOPED_TRACE(s.name);
        RenderSettings rs;
        rs.spp = 8;
        rs.wave_samples = 4;
        rs.max_depth = 6;
        const RenderResult base = gpu_render(s, w, h, rs, "dynamic-speculative-fma", {}, centres);
        ASSERT_GE(base.bounces.size(), 3u);
        for (const BounceStats& b : base.bounces) EXPECT_EQ(b.queue_entries, b.extension_rays);

        RenderSettings sorted = rs;
        sorted.sort_by_material = true;
        const RenderResult so = gpu_render(s, w, h, sorted, "dynamic-speculative-fma", {}, centres);
        expect_identical(base, so, "sorted by material");

        RenderSettings open = rs;
        open.compaction = false;
        const RenderResult oc = gpu_render(s, w, h, open, "dynamic-speculative-fma", {}, centres);
        expect_identical(base, oc, "no compaction");
        ASSERT_EQ(oc.bounces.size(), size_t(rs.max_depth));
        for (size_t b = 0; b < oc.bounces.size(); ++b) {
            const BounceStats want = b < base.bounces.size() ? base.bounces[b] : BounceStats{};
            EXPECT_EQ(oc.bounces[b].extension_rays, want.extension_rays) << "bounce " << b;
            EXPECT_EQ(oc.bounces[b].shadow_rays, want.shadow_rays) << "bounce " << b;
            EXPECT_EQ(oc.bounces[b].queue_entries, uint64_t(npix) * rs.spp) << "bounce " << b;  // never shrinks
        }

        RenderSettings cached = rs;
        cached.first_hit_cache = true;
        const RenderResult ca = gpu_render(s, w, h, cached, "dynamic-speculative-fma", {}, centres);
        expect_identical(base, ca, "first-hit cache");
        EXPECT_EQ(ca.cached_hits, uint64_t(npix) * 4);                // the second pass's camera rays
        EXPECT_EQ(ca.bounces[0].extension_rays, uint64_t(npix) * 4);  // only the first pass traced
        for (size_t b = 1; b < base.bounces.size(); ++b)
            EXPECT_EQ(ca.bounces[b].extension_rays, base.bounces[b].extension_rays);
    }
    // Jittered samples do not repeat: the cache refuses them.
    RenderSettings rs;
    rs.first_hit_cache = true;
    EXPECT_THROW(gpu_render(scene_named("cornell-box"), w, h, rs, "dynamic-speculative-fma"), Error);
}

/// A 2 x 2 quad facing +z of material m, u = (x + 1) / 2 and v = (y + 1) / 2, framed exactly
/// by its camera, under the default (white) sky.
Scene quad_of(const scene::Material& m) {
    Scene s;
    s.name = "quad of " + m.name;
    s.mesh.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    s.mesh.indices = {0, 1, 2, 0, 2, 3};
    s.mesh.texcoords = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    s.mesh.material_ids = {0, 0};
    s.mesh.materials = {m};
    s.camera.eye = {0.0f, 0.0f, 3.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_y_deg = float(2.0 * std::atan(1.0 / 3.0) * 180.0 / M_PI);
    return s;
}

/// The quad at 16 x 16, 256 spp, with AOVs: the CPU reference (seed 1) and the GPU (seed 2).
std::pair<RenderResult, RenderResult> quad_on_both_devices(const Scene& s) {
    RenderSettings rs;
    rs.spp = 256;
    rs.max_depth = 3;
    rs.aovs = true;
    RenderResult cpu = cpu_reference(s, 16, 16, rs);
    rs.seed = 2;
    return {std::move(cpu), gpu_render(s, 16, 16, rs, "dynamic-speculative-fma")};
}

// A map_Kd texture on the GPU: the same albedo buffer as the CPU's and the same image within
// noise (a quad with a 4 x 1 texture, framed exactly, under the white sky).
TEST(GpuRender, TexturesAgreeWithTheCpu) {
    BVHLAB_SKIP_WITHOUT_GPU();
    test::TempFile tex("gpu_stripes.pfm");
    Image img(4, 1);
    img.pixels = {{0.8f, 0.1f, 0.1f}, {0.6f, 0.3f, 0.1f}, {0.1f, 0.8f, 0.1f}, {0.1f, 0.3f, 0.9f}};
    write_image(img, tex.path());
    scene::Material m;
    m.name = "striped";
    m.diffuse_texture = tex.path();
    const auto [cpu, gpu] = quad_on_both_devices(quad_of(m));
    double diff = 0.0;
    for (size_t i = 0; i < cpu.albedo.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) diff += std::fabs(gpu.albedo.pixels[i][c] - cpu.albedo.pixels[i][c]);
    EXPECT_LT(diff / double(3 * cpu.albedo.pixels.size()), 0.01);  // other seeds: other jitter
    EXPECT_GT(cpu.albedo.at(2, 8).x, 0.7f);                        // the texture, not the grey default
    EXPECT_LT(cpu.albedo.at(2, 8).y, 0.2f);
    const Comparison c = compare_renders(cpu, gpu);
    EXPECT_TRUE(c.agree) << c.summary();
}

// Normal and height maps on the GPU: the normal buffer shows the analytic bent normal, and the
// image agrees with the CPU's (a quad under the white sky, as above).
TEST(GpuRender, NormalAndHeightMapsAgreeWithTheCpuAndTheAnalyticNormal) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const Vec3 t = normalize(Vec3{0.5f, -0.3f, 0.6f});
    test::TempFile normals("gpu_normal_map.pfm"), heights("gpu_height_map.pfm");
    Image n(4, 4), h(64, 4);
    for (Vec3& p : n.pixels) p = (t + splat(1.0f)) * 0.5f;
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 64; ++x) h.at(x, y) = splat((float(x) + 0.5f) / 64.0f);  // h = u
    write_image(n, normals.path());
    write_image(h, heights.path());
    // Tangent space as given; heights h = u with -bm 0.8 on x = 2u - 1: normal (-0.4, 0, 1).
    const std::pair<bool, Vec3> cases[] = {{false, t}, {true, normalize(Vec3{-0.4f, 0.0f, 1.0f})}};
    for (const auto& [height, want] : cases) {
        SCOPED_TRACE(height ? "height map" : "normal map");
        scene::Material m;
        m.name = "bumpy";
        m.diffuse = splat(0.5f);
        (height ? m.bump_texture : m.normal_texture) = height ? heights.path() : normals.path();
        m.bump_multiplier = height ? 0.8f : 1.0f;
        const auto [cpu, gpu] = quad_on_both_devices(quad_of(m));
        for (uint32_t y = 0; y < 16; ++y)
            for (uint32_t x = 2; x < 14; ++x)  // clear of the heights' repeat at u = 0
                EXPECT_LT(length(gpu.normal.at(x, y) - want), 1e-4f) << "pixel " << x << "," << y;
        // 0.5 (1 + cos theta) / 2 under the sky, over the pixels
        double mean = 0.0;
        for (uint32_t y = 0; y < 16; ++y)
            for (uint32_t x = 2; x < 14; ++x) mean += gpu.mean.at(x, y).x / (16.0 * 12.0);
        EXPECT_NEAR(mean, 0.25 * (1.0 + want.z), 0.01);
        const Comparison c = compare_renders(cpu, gpu);
        EXPECT_TRUE(c.agree) << c.summary();
    }
}

// The same comparison fails for a GPU render with a planted bug.
TEST(GpuRender, APlantedBugFailsTheComparison) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const Scene s = scene_named("cornell-box");
    RenderSettings rs;
    rs.spp = 256;
    const RenderResult cpu = cpu_reference(s, 32, 24, rs);
    for (PlantedBug bug : {PlantedBug::kNoCosine, PlantedBug::kBsdfWeightOne}) {
        const testing::ScopedPlantedBug planted(bug);
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

namespace bvhlab::render {

// The fish-eye and panorama cameras on the GPU agree with the CPU reference within noise.
TEST(GpuRender, FisheyeAndPanoramaAgreeWithTheCpu) {
    BVHLAB_SKIP_WITHOUT_GPU();
    for (trav::Projection p : {trav::Projection::kFisheye, trav::Projection::kPanorama}) {
        SCOPED_TRACE(trav::projection_name(p));
        Scene s = scene_named("glass-mirror");
        s.camera.projection = p;
        s.camera.fisheye_fov_deg = 160.0f;
        RenderSettings rs;
        rs.max_depth = 8;
        rs.spp = 256;
        rs.seed = 1;
        const RenderResult cpu = cpu_reference(s, 48, 24, rs);
        rs.spp = 1024;
        rs.seed = 2;
        const RenderResult gpu = gpu_render(s, 48, 24, rs, "dynamic-speculative-fma");
        CompareConfig cc;
        cc.pixel_outliers = 0.05;
        const Comparison c = compare_renders(cpu, gpu, cc);
        EXPECT_TRUE(c.agree) << c.summary();
    }
}

}  // namespace bvhlab::render

namespace bvhlab::render {

// On the GPU the preview copies the pixel sums back: the running mean after each pass, the
// last one the final image bit for bit.
TEST(GpuRender, PreviewShowsTheRunningMean) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const Scene s = scene_named("cornell-box");
    RenderSettings rs;
    rs.spp = 12;
    rs.wave_samples = 4;
    rs.preview_every_s = 0.0;
    std::vector<uint32_t> spps;
    Image last;
    rs.preview = [&](const Image& mean, uint32_t spp) {
        spps.push_back(spp);
        last = mean;
    };
    const RenderResult r = gpu_render(s, 32, 24, rs, "dynamic-speculative-fma");
    EXPECT_EQ(spps, (std::vector<uint32_t>{4, 8, 12}));
    ASSERT_EQ(last.pixels.size(), r.mean.pixels.size());
    size_t differ = 0;
    for (size_t i = 0; i < last.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) differ += last.pixels[i][c] != r.mean.pixels[i][c];
    EXPECT_EQ(differ, 0u);
}

}  // namespace bvhlab::render
