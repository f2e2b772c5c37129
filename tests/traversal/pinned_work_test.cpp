// SPDX-License-Identifier: MIT
// Pinned work per ray. For seeded generated scenes and fixed ray sets, each structure's node
// visits, leaf visits and triangle tests per ray (mean and 99th percentile) and each tree's SAH
// cost are stored in tests/traversal/pinned_work.json and must stay within 2%. A change that
// keeps every hit but makes the traversal visit more (a wrong child order, a looser box test,
// a worse split) turns this red. A change that moves them on purpose updates the file in the
// same commit (BVHLAB_UPDATE_PINNED_WORK=1 ./bvhlab_tests --gtest_filter='PinnedWork.*')
// with a line in experiments/NOTES.md saying why.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/stats.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/layouts/two_level.h"
#include "accel/passes/collapse_wide.h"
#include "scene/io/procedural.h"
#include "scene/scene.h"
#include "tests/support/adversarial.h"
#include "tests/support/edge_rays.h"
#include "tests/support/pinned_work.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/cpu/kd_trace.h"

namespace bvhlab::trav {
namespace {

using Counted = std::function<void(const RaySet&, std::vector<TraversalCounters>&)>;

/// Every figure of the pinned scenes, computed now: "scene/structure/ray type" -> work,
/// "scene/structure" -> SAH.
nlohmann::json measure() {
    nlohmann::json work = nlohmann::json::object(), sah = nlohmann::json::object();
    for (const test::PinnedScene& scene : test::pinned_scenes()) {
        const scene::TriangleMesh& mesh = scene.mesh;
        const test::PinnedRays rays(scene);
        auto record = [&](const std::string& structure, const Counted& trace) {
            for (const auto& [type, set] : rays.sets) {
                std::vector<TraversalCounters> c;
                trace(set, c);
                work[scene.name + "/" + structure + "/" + type] = test::summarise_work(c);
            }
        };
        for (accel::BuilderKind kind :
             {accel::BuilderKind::kBinned, accel::BuilderKind::kSweep, accel::BuilderKind::kSbvh}) {
            const std::string name = accel::builder_name(kind);
            const accel::BuildTree tree = accel::run_builder(kind, mesh, {}).tree;
            sah[scene.name + "/bvh2-" + name] = accel::compute_stats(tree, mesh, {}, false).sah;
            const accel::Bvh2 bvh = accel::convert_to_bvh2(tree, mesh);
            record("bvh2-" + name, [&](const RaySet& s, std::vector<TraversalCounters>& c) {
                std::vector<Hit> h;
                trace_cpu(bvh, s.rays, s.query, h, &c);
            });
            if (kind != accel::BuilderKind::kBinned) continue;
            const accel::WideTree wide = accel::collapse_to_wide(tree, mesh, accel::CollapseMethod::kSahOptimal);
            sah[scene.name + "/cwbvh-" + name] = accel::compute_wide_stats(wide).sah;
            const accel::Cwbvh cw = accel::convert_to_cwbvh(wide, mesh, accel::CwTris::kWoop);
            record("cwbvh-" + name, [&](const RaySet& s, std::vector<TraversalCounters>& c) {
                std::vector<Hit> h;
                trace_cpu(cw, s.rays, s.query, h, &c);
            });
        }
        const accel::KdTreeBuilder::Config kd_config;
        const accel::KdTree kd_tree = accel::KdTreeBuilder(kd_config).build(mesh);
        sah[scene.name + "/kdtree"] =
            accel::compute_kd_stats(kd_tree, kd_config.traversal_cost, kd_config.intersection_cost).sah;
        const accel::KdLayout kd = accel::convert_to_kd_layout(kd_tree, mesh);
        for (int stack : {64, 2}) {
            record("kdtree-stack" + std::to_string(stack), [&](const RaySet& s, std::vector<TraversalCounters>& c) {
                std::vector<Hit> h;
                trace_kd_cpu(kd, stack, s.rays, s.query, h, &c);
            });
        }
    }
    // A two-level BVH over overlapping, turned copies: the TLAS's instance boxes decide how many
    // BLAS are entered, so a loose or empty world box shows as work though every hit stays right.
    const scene::InstancedScene placed =
        scene::make_instances(scene::make_procedural(scene::ProceduralKind::kStructured, 1500, 3), 12, 9);
    scene::TriangleMesh flat = scene::flatten(placed, true);
    const Camera camera = framing_camera(flat);
    const test::PinnedScene world{"instances-12", std::move(flat), camera};
    const test::PinnedRays rays(world);
    for (bool wide : {false, true}) {
        const accel::TwoLevelBvh two_level = accel::build_two_level(
            placed,
            [](const scene::TriangleMesh& m) { return accel::run_builder(accel::BuilderKind::kBinned, m, {}).tree; },
            {wide});
        for (const auto& [type, set] : rays.sets) {
            std::vector<TraversalCounters> c;
            std::vector<Hit> h;
            trace_cpu(two_level, set.rays, set.query, h, &c);
            work[world.name + (wide ? "/two-level-cwbvh-binned/" : "/two-level-binned/") + type] =
                test::summarise_work(c);
        }
    }
    return {{"work", work}, {"sah", sah}};
}

}  // namespace

TEST(PinnedWork, WorkPerRayAndSahMatchThePinnedFile) {
    const std::string path = test::pinned_work_path();
    const nlohmann::json now = measure();
    if (const char* update = std::getenv("BVHLAB_UPDATE_PINNED_WORK"); update && std::string(update) == "1") {
        nlohmann::json out = now;
        out["about"] =
            "Work per ray and SAH pinned by tests/traversal/pinned_work_test.cpp; each figure must stay within "
            "tolerance (relative). Rewritten by BVHLAB_UPDATE_PINNED_WORK=1; say why in experiments/NOTES.md.";
        out["tolerance"] = test::kPinnedTolerance;
        std::ofstream(path) << out.dump(1) << "\n";
        std::printf("pinned work rewritten: %s\n", path.c_str());
        return;
    }
    std::ifstream in(path);
    ASSERT_TRUE(in) << "cannot read " << path;
    const nlohmann::json pinned = nlohmann::json::parse(in);
    // Every case pinned is measured and every case measured is pinned.
    for (const char* part : {"work", "sah"}) {
        for (const auto& [key, value] : pinned.at(part).items())
            EXPECT_TRUE(now.at(part).contains(key)) << part << " " << key << " is pinned but no longer measured";
        for (const auto& [key, value] : now.at(part).items())
            EXPECT_TRUE(pinned.at(part).contains(key)) << part << " " << key << " is measured but not pinned";
    }
    const std::vector<std::string> moved = test::compare_pinned(pinned, now, test::kPinnedTolerance);
    for (const std::string& m : moved) ADD_FAILURE() << m;
    if (!moved.empty())
        ADD_FAILURE() << moved.size() << " pinned figures moved by more than " << test::kPinnedTolerance * 100
                      << "%. If the change is meant, rerun with BVHLAB_UPDATE_PINNED_WORK=1 and say why in "
                         "experiments/NOTES.md.";
}

TEST(PinnedWork, TheComparisonCatchesAMovedFigure) {
    const nlohmann::json a = {{"work", {{"s/x/primary", {{"nodes_mean", 10.0}, {"nodes_p99", 40.0}}}}},
                              {"sah", {{"s/x", 50.0}}}};
    nlohmann::json b = a;
    EXPECT_TRUE(test::compare_pinned(a, b, 0.02).empty());
    b["work"]["s/x/primary"]["nodes_mean"] = 10.19;  // +1.9%: within
    EXPECT_TRUE(test::compare_pinned(a, b, 0.02).empty());
    b["work"]["s/x/primary"]["nodes_mean"] = 10.21;  // +2.1%
    ASSERT_EQ(test::compare_pinned(a, b, 0.02).size(), 1u);
    EXPECT_NE(test::compare_pinned(a, b, 0.02)[0].find("nodes_mean"), std::string::npos);
    b = a;
    b["sah"]["s/x"] = 48.9;  // -2.2%
    EXPECT_EQ(test::compare_pinned(a, b, 0.02).size(), 1u);
}

}  // namespace bvhlab::trav
