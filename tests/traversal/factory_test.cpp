// SPDX-License-Identifier: MIT
// The structure factory (traversal/factory.h): every builder and layout from one spec, the
// same trees as the builders give directly, errors named, structure files round-tripped, and
// the registry's default kernels (one per layout, two for kd-trees).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "accel/core/check.h"
#include "accel/layouts/bvh2_convert.h"
#include "scene/io/procedural.h"
#include "tests/support/agreement.h"
#include "tests/support/gpu_support.h"
#include "traversal/factory.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::trav {
namespace {

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

const scene::TriangleMesh& mesh() {
    static const scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kStructured, 3000, 5);
    return m;
}

std::vector<Ray> camera_rays(const scene::TriangleMesh& m) {
    PrimaryConfig pc;
    pc.width = 64;
    pc.height = 48;
    return generate_primary(framing_camera(m), pc);
}

}  // namespace

TEST(StructureFactory, EveryBuilderAndLayoutTracesLikeEmbree) {
    const scene::TriangleMesh& m = mesh();
    const EmbreeOracle oracle(m);
    RaySet set;
    set.rays = camera_rays(m);
    std::vector<Hit> ref;
    oracle.trace(set.rays, set.query, ref);
    struct Case {
        const char* builder;
        const char* layout;
        const char* name;
        Layout want;
    };
    for (const Case& c :
         {Case{"binned", "bvh2", "bvh2/binned", Layout::kBvh2}, Case{"bvh", "bvh2", "bvh2/binned", Layout::kBvh2},
          Case{"sweep", "bvh2", "bvh2/sweep", Layout::kBvh2}, Case{"sbvh", "bvh2", "bvh2/sbvh", Layout::kBvh2},
          Case{"sbvh", "cwbvh", "cwbvh/sbvh", Layout::kCwbvh}, Case{"binned", "cwbvh", "cwbvh/binned", Layout::kCwbvh},
          Case{"kdtree", "bvh2", "kdtree", Layout::kKd}}) {
        StructureSpec spec;
        spec.builder = c.builder;
        spec.layout = c.layout;
        spec.epo = false;
        const AccelStructure s = build_structure(m, spec);
        EXPECT_EQ(s.structure.name, c.name);
        EXPECT_EQ(s.structure.layout, c.want);
        EXPECT_EQ(s.figures["structure"], c.name);
        EXPECT_EQ(s.figures["triangles"], m.triangle_count());
        EXPECT_GT(s.stats.sah, 0.0) << c.name;
        EXPECT_GT(s.figures["nodes"].get<size_t>(), 1u) << c.name;
        std::vector<Hit> ours;
        s.cpu_tracer()->trace(set, ours);
        SCOPED_TRACE(c.name);
        test::expect_no_real_mismatch(m, oracle, set.rays, set.query, ours, ref);
    }
}

TEST(StructureFactory, GivesTheTreeTheBuilderGives) {
    const scene::TriangleMesh& m = mesh();
    StructureSpec spec;
    spec.builder = "sbvh";
    spec.options.config.max_leaf_size = 4;
    spec.epo = false;
    const AccelStructure s = build_structure(m, spec);
    accel::BuilderOptions o;
    o.config.max_leaf_size = 4;
    const accel::Bvh2 direct = accel::convert_to_bvh2(accel::run_builder(accel::BuilderKind::kSbvh, m, o).tree, m);
    ASSERT_EQ(s.structure.bvh2.nodes.size(), direct.nodes.size());
    EXPECT_EQ(0, std::memcmp(s.structure.bvh2.nodes.data(), direct.nodes.data(),
                             direct.nodes.size() * sizeof(accel::Bvh2Node)));
    EXPECT_EQ(s.figures["max_leaf"], 4);
    EXPECT_LE(s.stats.max_leaf_size, 4u);
    EXPECT_EQ(s.spec.builder, "sbvh");
}

TEST(StructureFactory, RefusesBadSpecsWithOneLineNamingTheValue) {
    const scene::TriangleMesh& m = mesh();
    auto refused = [&](const std::function<void(StructureSpec&)>& edit, const std::string& word) {
        StructureSpec spec;
        edit(spec);
        const std::string e = error_of([&] { build_structure(m, spec); });
        EXPECT_NE(e.find(word), std::string::npos) << "'" << e << "' should name " << word;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    };
    refused([](StructureSpec& s) { s.builder = "octree"; }, "octree");
    refused([](StructureSpec& s) { s.layout = "bvh4"; }, "bvh4");
    refused(
        [](StructureSpec& s) {
            s.builder = "kdtree";
            s.layout = "cwbvh";
        },
        "cwbvh");
    refused([](StructureSpec& s) { s.collapse = "best"; }, "best");
    refused([](StructureSpec& s) { s.cw_tris = "quads"; }, "quads");
    refused([](StructureSpec& s) { s.kd_stack = 9; }, "kd_stack");
    refused([](StructureSpec& s) { s.options.num_bins = 1; }, "bins");
    refused([](StructureSpec& s) { s.options.config.max_leaf_size = 0; }, "max_leaf");
    // The spec's own check names both sizes (a builder's internal check would also say min_leaf).
    refused([](StructureSpec& s) { s.options.config.min_leaf_size = 9; }, "min_leaf 9 is larger than max_leaf 8");
    accel::BuilderOptions crossed;
    crossed.config.min_leaf_size = 5;
    crossed.config.max_leaf_size = 4;
    EXPECT_EQ(accel::options_problem(crossed), "min_leaf 5 is larger than max_leaf 4");
    refused([](StructureSpec& s) { s.options.sbvh_alpha = std::nanf(""); }, "alpha");
    refused([](StructureSpec& s) { s.options.sbvh_budget = 0.5f; }, "budget");
    refused([](StructureSpec& s) { s.kd.traversal_cost = 0.0f; }, "kd_ct");
    refused([](StructureSpec& s) { s.kd.max_depth = 65; }, "kd_max_depth");
    // Every range at both ends, as options_problem() and kd_config_problem() state them.
    refused([](StructureSpec& s) { s.options.num_bins = 257; }, "bins 257 is not in [2, 256]");
    refused([](StructureSpec& s) { s.options.config.max_leaf_size = 65; }, "max_leaf 65 is not in [1, 64]");
    // The BVH2 layout's leaves hold 16 triangles; the CWBVH layout collapses larger BVH leaves.
    refused([](StructureSpec& s) { s.options.config.max_leaf_size = 17; },
            "max_leaf 17 does not fit the bvh2 layout, whose leaves hold at most 16 triangles");
    refused(
        [](StructureSpec& s) {
            s.builder = "hploc";
            s.layout = "cwbvh";
            s.options.config.max_leaf_size = 32;
        },
        "max_leaf 32 does not fit the bvh2 layout");
    refused([](StructureSpec& s) { s.options.config.min_leaf_size = 0; }, "min_leaf 0 is not in [1, 64]");
    refused([](StructureSpec& s) { s.options.config.max_depth = 0; }, "max_depth 0 is not in [1, 64]");
    refused([](StructureSpec& s) { s.options.config.max_depth = 65; }, "max_depth 65");
    refused([](StructureSpec& s) { s.options.config.traversal_cost = 0.0f; }, "ct 0 is not in [0.001, 1e+06]");
    refused([](StructureSpec& s) { s.options.config.intersection_cost = 2e6f; }, "ci 2e+06");
    refused([](StructureSpec& s) { s.options.sbvh_alpha = 1.5f; }, "alpha 1.5 is not in [0, 1]");
    refused([](StructureSpec& s) { s.options.sbvh_budget = 17.0f; }, "budget 17");
    refused([](StructureSpec& s) { s.options.sbvh_spatial_bins = 1; }, "spatial_bins 1 is not in [2, 256]");
    refused([](StructureSpec& s) { s.options.sbvh_spatial_bins = 257; }, "spatial_bins 257");
    refused([](StructureSpec& s) { s.options.reinsertion_passes = -2; }, "reinsertion_passes -2 is not in [-1, 16]");
    refused([](StructureSpec& s) { s.options.reinsertion_passes = 17; }, "reinsertion_passes 17");
    refused([](StructureSpec& s) { s.kd.intersection_cost = 1e7f; }, "kd_ci 1e+07");
    refused([](StructureSpec& s) { s.kd.empty_bonus = 1.0f; }, "kd_bonus 1 is not in [0, 0.99]");
    refused([](StructureSpec& s) { s.kd.max_depth = -2; }, "kd_max_depth -2 is not in [-1, 64]");
    // ... and the ends themselves are accepted.
    StructureSpec edge;
    edge.builder = "sbvh";
    edge.epo = false;
    edge.options.num_bins = 256;
    edge.layout = "cwbvh";  // the BVH2 layout's leaves end at 16 (tested above)
    edge.options.config.min_leaf_size = edge.options.config.max_leaf_size = 64;
    edge.options.config.max_depth = 64;
    edge.options.sbvh_alpha = 1.0f;
    edge.options.sbvh_budget = 16.0f;
    edge.options.sbvh_spatial_bins = 2;
    edge.options.reinsertion_passes = 16;
    EXPECT_NO_THROW(build_structure(m, edge));
    const std::string e = error_of([] { build_structure(scene::TriangleMesh{}, StructureSpec{}); });
    EXPECT_NE(e.find("no triangles"), std::string::npos) << e;
}

TEST(StructureFactory, StructureFilesRoundTripAndStaleOnesAreRefused) {
    const scene::TriangleMesh& m = mesh();
    const std::string hash = scene::scene_hash(m);
    const auto dir = std::filesystem::temp_directory_path() / ("bvhlab_factory_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    for (const char* builder : {"sweep", "kdtree"}) {
        StructureSpec spec;
        spec.builder = builder;
        spec.epo = false;
        const AccelStructure built = build_structure(m, spec);
        const std::string path = (dir / (std::string(builder) + ".bvh")).string();
        built.save(path, hash);
        const AccelStructure loaded = load_structure(m, hash, path, StructureSpec{});
        EXPECT_EQ(loaded.structure.name, built.structure.name);
        EXPECT_EQ(loaded.spec.builder, builder);
        EXPECT_EQ(loaded.structure.bytes(), built.structure.bytes());
        EXPECT_EQ(loaded.figures["structure_file"], path);
        ASSERT_TRUE(loaded.loaded_meta.has_value());
        const std::string stale = error_of([&] { load_structure(m, "0123456789abcdef", path); });
        EXPECT_NE(stale.find("stale structure file"), std::string::npos) << stale;
        const scene::TriangleMesh other = scene::make_procedural(scene::ProceduralKind::kSoup, 100, 1);
        EXPECT_NE(error_of([&] { load_structure(other, scene::scene_hash(other), path); }).find("stale"),
                  std::string::npos);
    }
    // A BVH file loads into the CWBVH layout too; a kd-tree file does not.
    StructureSpec cw;
    cw.layout = "cwbvh";
    EXPECT_EQ(load_structure(m, hash, (dir / "sweep.bvh").string(), cw).structure.name, "cwbvh/sweep");
    EXPECT_NE(error_of([&] { load_structure(m, hash, (dir / "kdtree.bvh").string(), cw); }).find("kd-tree"),
              std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST(StructureFactory, DefaultKernelsComeFromTheRegistry) {
    StructureSpec kd;
    kd.builder = "kdtree";
    kd.epo = false;
    AccelStructure full = build_structure(mesh(), kd);
    kd.kd_stack = 3;
    AccelStructure shorty = build_structure(mesh(), kd);
    if (!built_with_cuda()) {
        EXPECT_NE(error_of([&] { full.default_kernel(); }).find("without CUDA"), std::string::npos);
        GTEST_SKIP() << "built without CUDA: the registry is empty";
    }
    // Exactly one default per layout, and for kd-trees one per stack kind.
    std::set<std::pair<int, bool>> seen;
    for (const KernelInfo& k : registered_kernels())
        if (k.is_default) EXPECT_TRUE(seen.insert({int(k.layout), k.short_stack}).second) << k.name;
    EXPECT_EQ(seen.size(), 6u);  // bvh2, cwbvh, both two-level layouts, and the kd-tree's two
    EXPECT_EQ(default_kernel(Layout::kBvh2).layout, Layout::kBvh2);
    EXPECT_EQ(default_kernel(Layout::kCwbvh).layout, Layout::kCwbvh);
    EXPECT_EQ(default_kernel(Layout::kTwoLevel).layout, Layout::kTwoLevel);
    EXPECT_EQ(default_kernel(Layout::kTwoLevelCwbvh).layout, Layout::kTwoLevelCwbvh);
    EXPECT_FALSE(full.default_kernel().short_stack);
    EXPECT_TRUE(shorty.default_kernel().short_stack);
    EXPECT_EQ(shorty.gpu_options(shorty.default_kernel()).kd_stack, 3);
    EXPECT_TRUE(default_kernel(Layout::kBvh2).is_default);
}

}  // namespace bvhlab::trav
