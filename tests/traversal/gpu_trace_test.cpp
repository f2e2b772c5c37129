// SPDX-License-Identifier: MIT
// GPU tests (ctest label "gpu"), parameterised over the kernel registry: a new kernel is
// tested without new test code. Every kernel x {closest, any} x {binned, SBVH, or the
// kd-tree for kd kernels} on generated scenes and the Cornell box must agree with Embree
// (0 real mismatches) and write every hit (the tracer poisons the hit buffer before each
// launch); the first also over the GPU builders' trees (lbvh, ploc, hploc). Each test skips with the
// reason when there is no device.
#include <gtest/gtest.h>

#include <functional>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/check.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "scene/scene.h"
#include "tests/support/adversarial.h"
#include "tests/support/agreement.h"
#include "tests/support/edge_rays.h"
#include "tests/support/gpu_support.h"
#include "tests/support/pinned_work.h"
#include "tests/support/test_support.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/oracle/compare.h"
#include "traversal/rays/protocol.h"

namespace bvhlab::trav {
namespace {

struct TestScene {
    std::string name;
    scene::TriangleMesh mesh;
    Camera camera;
    uint32_t width, height;
};

std::vector<TestScene> test_scenes() {
    std::vector<TestScene> out;
    TestScene cb{"cornell-box", scene::load_obj(test::data_dir() + "/cornell_box.obj"), {}, 128, 96};
    cb.camera.eye = {278, 273, -800};
    cb.camera.target = {278, 273, 0};
    cb.camera.fov_y_deg = 39.3f;
    out.push_back(std::move(cb));
    for (auto kind : {scene::ProceduralKind::kSoup, scene::ProceduralKind::kStructured}) {
        scene::TriangleMesh m = scene::make_procedural(kind, 30000, 7);
        const Camera cam = framing_camera(m);
        out.push_back({kind == scene::ProceduralKind::kSoup ? "soup" : "structured", std::move(m), cam, 160, 120});
    }
    return out;
}

/// Every hit written (no poison left) and a real triangle id or a miss.
size_t unwritten_or_invalid(const std::vector<Hit>& hits, size_t triangles) {
    size_t bad = 0;
    for (const Hit& h : hits) bad += !(h.tri == -1 || (h.tri >= 0 && size_t(h.tri) < triangles));
    return bad;
}

std::vector<std::string> kernel_names() {
    std::vector<std::string> names;
    for (const KernelInfo& k : registered_kernels()) names.push_back(k.name);
    return names;
}

std::string param_name(const ::testing::TestParamInfo<std::string>& info) {
    std::string s = info.param;
    for (char& c : s)
        if (c == '-') c = '_';
    return s;
}

}  // namespace

class GpuKernel : public ::testing::TestWithParam<std::string> {};
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(GpuKernel);

namespace {

using Variant = std::pair<accel::BuilderKind, accel::CwTris>;

/// Calls fn(structure, tracer) for `kernel` on a structure of each variant, a short-stack
/// kernel with 1, 2 and 8 entries, each under SCOPED_TRACE.
void for_each_gpu_tracer(const KernelInfo& kernel, const scene::TriangleMesh& mesh,
                         const std::vector<Variant>& variants,
                         const std::function<void(const Structure&, Tracer&)>& fn) {
    for (const auto& [builder, tris] : variants) {
        const Structure s = make_structure(mesh, kernel.layout, builder, tris);
        SCOPED_TRACE(s.name);
        auto device = std::make_shared<const DeviceStructure>(s);
        std::vector<GpuTraceOptions> options{{}};
        if (kernel.short_stack) options = {{1, 0}, {2, 0}, {8, 0}};
        for (const GpuTraceOptions& opt : options) {
            SCOPED_TRACE("short stack " + std::to_string(opt.kd_stack));
            fn(s, *make_gpu_tracer(device, kernel, opt));
        }
    }
}

/// `kernel` on a structure of each variant (a short-stack kernel with 1, 2 and 8 entries), on
/// the four protocol ray types of `cfg`: every hit written, 0 real mismatches (the first ones
/// printed), and counted_ties(report) at most max_tie_fraction x rays + slack.
void expect_kernel_agrees(const KernelInfo& kernel, const scene::TriangleMesh& mesh, const ProtocolConfig& cfg,
                          const std::vector<Variant>& variants,
                          const std::function<double(const CompareReport&)>& counted_ties, double max_tie_fraction,
                          double slack) {
    EmbreeOracle oracle(mesh);
    RayProtocol proto(mesh, oracle, cfg);
    // primary and diffuse are closest-hit queries, AO and shadow any-hit ones.
    for_each_gpu_tracer(kernel, mesh, variants, [&](const Structure&, Tracer& tracer) {
        for (RayType t : {RayType::kPrimary, RayType::kAo, RayType::kDiffuse, RayType::kShadow}) {
            SCOPED_TRACE(ray_type_name(t));
            const RaySet set = proto.make(t);
            std::vector<Hit> ours, ref;
            tracer.trace(set, ours);
            ASSERT_EQ(ours.size(), set.rays.size());
            EXPECT_EQ(unwritten_or_invalid(ours, mesh.triangle_count()), 0u);
            oracle.trace(set.rays, set.query, ref);
            const CompareReport rep = test::expect_no_real_mismatch(mesh, oracle, set.rays, set.query, ours, ref);
            EXPECT_LE(counted_ties(rep), double(set.rays.size()) * max_tie_fraction + slack);
        }
    });
}

}  // namespace

TEST_P(GpuKernel, AgreesWithEmbreeOnEveryRayTypeAndStructure) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const KernelInfo& kernel = find_kernel(GetParam());
    for (const TestScene& scene : test_scenes()) {
        SCOPED_TRACE(scene.name);
        ProtocolConfig cfg;
        cfg.camera = scene.camera;
        cfg.primary = {scene.width, scene.height, 1, 0};
        std::vector<Variant> variants{{accel::BuilderKind::kBinned, accel::CwTris::kWoop},
                                      {accel::BuilderKind::kSbvh, accel::CwTris::kWoop}};
        if (kernel.layout == Layout::kKd) variants = {variants[0]};  // one kd-tree
        // A CWBVH's vertex-triple leaves (--cw-tris vertices) are a second kernel instance.
        if (has_cw_tris(kernel.layout)) variants.push_back({accel::BuilderKind::kBinned, accel::CwTris::kVertices});
        // The GPU builders' trees, in every BVH layout.
        if (kernel.layout != Layout::kKd)
            for (auto b : {accel::BuilderKind::kLbvh, accel::BuilderKind::kPloc, accel::BuilderKind::kHploc})
                variants.push_back({b, accel::CwTris::kWoop});
        expect_kernel_agrees(
            kernel, scene.mesh, cfg, variants, [](const CompareReport& rep) { return double(rep.ties); }, 0.001, 1.0);
    }
}

TEST_P(GpuKernel, AgreesWithEmbreeOnAdversarialScenes) {
    // tests/support/adversarial.h: near-flat tiles, faces on shared planes, slivers, T-junctions,
    // huge beside tiny triangles, offsets up to 1e6. The CPU tracers run them in
    // Adversarial.* (tests/traversal/adversarial_test.cpp), over more structures.
    BVHLAB_SKIP_WITHOUT_GPU();
    const KernelInfo& kernel = find_kernel(GetParam());
    for (const test::AdversarialScene& scene : test::adversarial_scenes()) {
        SCOPED_TRACE(scene.name);
        ProtocolConfig cfg;
        cfg.camera = scene.camera;
        cfg.primary = {96, 64, 1, 0};
        cfg.ao_length = scene.ao_length;
        std::vector<Variant> variants{{accel::BuilderKind::kBinned, accel::CwTris::kWoop},
                                      {accel::BuilderKind::kSbvh, accel::CwTris::kWoop}};
        if (kernel.layout == Layout::kKd) variants = {variants[0]};  // one kd-tree
        // Coincident ties are proven (the rooms overlap coplanar triangles on purpose); the ties
        // that excuse float error are capped.
        expect_kernel_agrees(
            kernel, scene.mesh, cfg, variants,
            [](const CompareReport& rep) { return double(rep.ties - rep.ties_by_kind[size_t(TieKind::kCoincident)]); },
            scene.max_tie_fraction, 5.0);
    }
}

TEST_P(GpuKernel, AgreesWithEmbreeOnEdgeAndPlaneRays) {
    // tests/support/edge_rays.h: rays along the faces and edges of the structure's own boxes,
    // through and from corners, from faces, with tmin = tmax, across and along flat boxes, in
    // a scene on the split planes. The CPU tracers run them in EdgeRays.*.
    BVHLAB_SKIP_WITHOUT_GPU();
    const KernelInfo& kernel = find_kernel(GetParam());
    for (uint32_t seed : {1u, 2u}) {
        SCOPED_TRACE("lattice " + std::to_string(seed));
        const scene::TriangleMesh mesh = test::make_lattice_scene(seed);
        const EmbreeOracle oracle(mesh);
        std::vector<Variant> variants{{accel::BuilderKind::kBinned, accel::CwTris::kWoop},
                                      {accel::BuilderKind::kSbvh, accel::CwTris::kWoop}};
        if (has_cw_tris(kernel.layout)) variants.push_back({accel::BuilderKind::kSbvh, accel::CwTris::kVertices});
        if (kernel.layout == Layout::kKd) variants = {variants[0]};  // one kd-tree
        for_each_gpu_tracer(kernel, mesh, variants, [&](const Structure& s, Tracer& tracer) {
            const std::vector<Ray> rays = test::edge_rays(test::structure_boxes(s), mesh.bounds(), seed + 6, 400);
            for (Query q : {Query::kClosest, Query::kAny}) {
                std::vector<Hit> ours, ref;
                tracer.trace({rays, q}, ours);
                ASSERT_EQ(ours.size(), rays.size());
                EXPECT_EQ(unwritten_or_invalid(ours, mesh.triangle_count()), 0u);
                oracle.trace(rays, q, ref);
                test::expect_no_real_mismatch(mesh, oracle, rays, q, ours, ref);
            }
        });
    }
}

TEST_P(GpuKernel, CountersEqualTheCpuReferences) {
    // A kernel that runs a shared traversal counts its work (trace_gpu_counted); on the pinned
    // scenes and rays (tests/support/pinned_work.h) its nodes, leaves, triangle tests and
    // restarts equal the CPU traversal's ray by ray. Kernels that traverse in another order do
    // not count, and say so.
    BVHLAB_SKIP_WITHOUT_GPU();
    const KernelInfo& kernel = find_kernel(GetParam());
    for (const test::PinnedScene& scene : test::pinned_scenes()) {
        SCOPED_TRACE(scene.name);
        const test::PinnedRays rays(scene);
        std::vector<accel::CwTris> formats{accel::CwTris::kWoop};
        if (has_cw_tris(kernel.layout)) formats.push_back(accel::CwTris::kVertices);
        for (accel::CwTris tris : formats) {
            const Structure s = make_structure(scene.mesh, kernel.layout, accel::BuilderKind::kBinned, tris);
            SCOPED_TRACE(s.name);
            const DeviceStructure device(s);
            std::vector<Hit> hits;
            std::vector<TraversalCounters> gpu;
            if (!kernel.counts) {
                EXPECT_THROW(trace_gpu_counted(device, kernel, rays.sets[0].second, hits, gpu), Error);
                return;
            }
            const std::vector<int> stacks = kernel.short_stack ? std::vector<int>{1, 2, 8} : std::vector<int>{64};
            for (int stack : stacks) {
                for (const auto& [type, set] : rays.sets) {
                    SCOPED_TRACE(type + " stack " + std::to_string(stack));
                    GpuTraceOptions opts;
                    if (kernel.short_stack) opts.kd_stack = stack;
                    trace_gpu_counted(device, kernel, set, hits, gpu, opts);
                    std::vector<Hit> cpu_hits;
                    std::vector<TraversalCounters> cpu;
                    trace_cpu_counted(s, stack, set, cpu_hits, &cpu);
                    ASSERT_EQ(gpu.size(), cpu.size());
                    size_t differ = 0, first = 0;
                    uint64_t gpu_nodes = 0, cpu_nodes = 0;
                    for (size_t i = 0; i < cpu.size(); ++i) {
                        const bool same = gpu[i].nodes == cpu[i].nodes && gpu[i].leaves == cpu[i].leaves &&
                                          gpu[i].tri_tests == cpu[i].tri_tests && gpu[i].restarts == cpu[i].restarts;
                        if (!same && differ++ == 0) first = i;
                        gpu_nodes += gpu[i].nodes;
                        cpu_nodes += cpu[i].nodes;
                    }
                    EXPECT_EQ(differ, 0u)
                        << "first at ray " << first << ": gpu nodes " << gpu[first].nodes << " leaves "
                        << gpu[first].leaves << " tests " << gpu[first].tri_tests << ", cpu " << cpu[first].nodes << " "
                        << cpu[first].leaves << " " << cpu[first].tri_tests;
                    EXPECT_EQ(gpu_nodes, cpu_nodes);
                    EXPECT_GT(cpu_nodes, cpu.size());  // real work was counted
                }
            }
        }
    }
}

TEST_P(GpuKernel, OddCountsEmptySetsAndTheDeviceCount) {
    BVHLAB_SKIP_WITHOUT_GPU();
    const KernelInfo& kernel = find_kernel(GetParam());
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 2000, 3);
    const Structure s = make_structure(mesh, kernel.layout, accel::BuilderKind::kBinned);
    auto device = std::make_shared<const DeviceStructure>(s);
    auto tracer = make_gpu_tracer(device, kernel);
    EmbreeOracle oracle(mesh);
    ProtocolConfig cfg;
    cfg.camera = framing_camera(mesh);
    cfg.primary = {37, 29, 1, 0};  // 1073 rays: not a multiple of the warp or block size
    RayProtocol proto(mesh, oracle, cfg);
    const RaySet set = proto.make(RayType::kPrimary);
    for (size_t n : {size_t(0), size_t(1), size_t(31), size_t(33), set.rays.size()}) {
        SCOPED_TRACE(n);
        const std::vector<Ray> rays(set.rays.begin(), set.rays.begin() + long(n));
        std::vector<Hit> ours, ref;
        tracer->trace({rays, Query::kClosest}, ours);
        ASSERT_EQ(ours.size(), n);
        oracle.trace(rays, Query::kClosest, ref);
        EXPECT_EQ(
            compare_hits(mesh, rays, Query::kClosest, ours, ref, [&](const Ray& r) { return oracle.intersect(r); })
                .mismatches,
            0u);
    }
    // A queue whose device count is below its capacity: rays past the count stay untouched
    // (poisoned), the first `count` are traced. This is how a wavefront renderer calls it.
    RayQueue queue;
    queue.upload(set.rays);
    queue.set_count(100);
    queue.poison_hits();
    DeviceBuffer<uint32_t> next(1);
    next.fill_bytes(0);
    launch_on_queue(*device, kernel, queue, Query::kClosest, next.data());
    std::vector<Hit> hits;
    queue.download_hits(hits, set.rays.size());
    std::vector<Hit> ref;
    oracle.trace(set.rays, Query::kClosest, ref);
    for (size_t i = 0; i < hits.size(); ++i) {
        if (i < 100) {
            EXPECT_EQ(hits[i].tri, ref[i].tri) << i;
        } else {
            EXPECT_EQ(hits[i].tri, 0x7F7F7F7F) << i;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Registry, GpuKernel, ::testing::ValuesIn(kernel_names()), param_name);

TEST(GpuTrace, TwoLevelKernelsAgreeWithEmbreeInstances) {
    // Randomly turned, scaled, overlapping instances (gen:instances) of two meshes, each BLAS
    // builder, every two-level kernel: every ray type against Embree's own instances, and the
    // same hits as the CPU two-level traversal up to ties.
    BVHLAB_SKIP_WITHOUT_GPU();
    for (auto kind : {scene::ProceduralKind::kStructured, scene::ProceduralKind::kSoup}) {
        const scene::InstancedScene placed = scene::make_instances(scene::make_procedural(kind, 3000, 2), 25, 5);
        const scene::TriangleMesh world = scene::flatten(placed, true);
        const EmbreeOracle oracle(placed);
        ProtocolConfig cfg;
        cfg.camera = framing_camera(world);
        cfg.primary = {128, 96, 1, 0};
        cfg.ao_length = 0.05f * world.diagonal();
        RayProtocol proto(world, oracle, cfg);
        for (const auto& [builder, layout] :
             std::vector<std::pair<accel::BuilderKind, std::string>>{{accel::BuilderKind::kBinned, "bvh2"},
                                                                     {accel::BuilderKind::kSbvh, "bvh2"},
                                                                     {accel::BuilderKind::kBinned, "cwbvh"},
                                                                     {accel::BuilderKind::kSbvh, "cwbvh"}}) {
            StructureSpec spec;
            spec.builder = accel::builder_name(builder);
            spec.layout = layout;
            spec.epo = false;
            AccelStructure as = build_structure(placed, spec);
            SCOPED_TRACE(as.structure.name);
            EXPECT_EQ(as.gpu_tracer()->name(),
                      layout == "bvh2" ? "two-level-dynamic-speculative-fma" : "two-level-dynamic-cwbvh")
                << "the layout's default kernel";
            auto cpu = as.cpu_tracer();
            size_t kernels = 0;
            for (const KernelInfo& k : registered_kernels()) {
                if (k.layout != as.structure.layout) continue;
                ++kernels;
                auto gpu = as.gpu_tracer(k.name);
                for (RayType t : {RayType::kPrimary, RayType::kAo, RayType::kDiffuse, RayType::kShadow}) {
                    SCOPED_TRACE(std::string(k.name) + " " + ray_type_name(t));
                    const RaySet set = proto.make(t);
                    std::vector<Hit> ours, ref, cpu_hits;
                    gpu->trace(set, ours);
                    EXPECT_EQ(unwritten_or_invalid(ours, world.triangle_count()), 0u);
                    oracle.trace(set.rays, set.query, ref);
                    const CompareReport rep =
                        test::expect_no_real_mismatch(world, oracle, set.rays, set.query, ours, ref);
                    EXPECT_LE(double(rep.ties - rep.ties_by_kind[size_t(TieKind::kCoincident)]),
                              0.001 * double(set.rays.size()) + 3);
                    cpu->trace(set, cpu_hits);
                    // Closest hits are the CPU's up to ties; an any-hit ray ends at the first hit
                    // its traversal order meets, so only a kernel that runs the CPU's traversal
                    // (KernelInfo::counts) names the same triangle, and the others the same verdict.
                    const bool same_order = k.counts || set.query == Query::kClosest;
                    size_t same = 0;
                    for (size_t i = 0; i < ours.size(); ++i)
                        same += same_order ? ours[i].tri == cpu_hits[i].tri : ours[i].is_hit() == cpu_hits[i].is_hit();
                    EXPECT_GE(same, ours.size() * 999 / 1000) << "GPU and CPU run the same traversal";
                }
            }
            EXPECT_GE(kernels, layout == "bvh2" ? 3u : 1u) << "two-level, the while-while forms; dynamic-cwbvh";
        }
    }
}

TEST(GpuTrace, OutOfDeviceMemoryNamesTheSize) {
    BVHLAB_SKIP_WITHOUT_GPU();
    // 4 TB: more than any GPU has. The error names the bytes asked for, and the device still works.
    const size_t bytes = size_t(1) << 42;
    try {
        DeviceBuffer<uint8_t> b;
        b.resize(bytes);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cannot allocate " + std::to_string(bytes) + " bytes of GPU memory"),
                  std::string::npos)
            << e.what();
    }
    DeviceBuffer<uint32_t> ok(std::vector<uint32_t>{1, 2, 3});
    std::vector<uint32_t> back;
    ok.download(back);
    EXPECT_EQ(back, (std::vector<uint32_t>{1, 2, 3}));
}

TEST(GpuTrace, ReportsWhyWithoutDevice) {
    std::string why;
    if (gpu_available(&why)) GTEST_SKIP() << "a GPU is present: " << gpu_description();
    EXPECT_FALSE(why.empty());
    Structure s;
    s.bvh2 = accel::convert_to_bvh2(
        accel::run_builder(accel::BuilderKind::kBinned, scene::make_procedural(scene::ProceduralKind::kSoup, 10, 1), {})
            .tree,
        scene::make_procedural(scene::ProceduralKind::kSoup, 10, 1));
    EXPECT_THROW(DeviceStructure d(s), Error);
}

}  // namespace bvhlab::trav
