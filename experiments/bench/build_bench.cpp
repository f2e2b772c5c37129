// SPDX-License-Identifier: MIT
// BM_Build/<builder>/<scene>: build time (Mtris/s) with SAH, EPO, nodes, references and bytes
// as counters, so speed and quality land in one JSON. Builders run with their defaults (SBVH
// includes its 3 reinsertion passes); "sbvh-r0" is the SBVH without them and "sweep-r3" the
// sweep with them, so the optimiser's share can be read off. BM_Build/embree-medium is Embree's
// own build of the same triangles, in the same run (issue 21).
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <chrono>
#include <cstring>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "experiments/bench/bench_common.h"

namespace bvhlab::bench {
namespace {

void bm_build(benchmark::State& state, accel::BuilderKind kind, int reinsertion,
              std::shared_ptr<scene::TriangleMesh> mesh) {
    accel::BuilderOptions opts;
    opts.reinsertion_passes = reinsertion;
    accel::BuildResult last;
    for (auto _ : state) {
        last = accel::run_builder(kind, *mesh, opts);
        benchmark::DoNotOptimize(last.tree.nodes.data());
    }
    // Check the result before trusting the time; then the quality figures (untimed).
    accel::ValidateOptions vo;
    vo.allow_duplicates = kind == accel::BuilderKind::kSbvh;
    const std::string err = accel::validate(last.tree, *mesh, opts.config, vo);
    if (!err.empty()) {
        state.SkipWithError(("invalid tree: " + err).c_str());
        return;
    }
    const accel::TreeStats s = accel::compute_stats(last.tree, *mesh, opts.config, mesh->triangle_count() <= 3000000);
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh->triangle_count()));
    state.counters["triangles"] = double(mesh->triangle_count());
    state.counters["sah"] = s.sah;
    state.counters["epo"] = s.epo;
    state.counters["nodes"] = double(s.nodes);
    state.counters["leaves"] = double(s.leaves);
    state.counters["references"] = double(s.references);
    state.counters["bytes"] = double(s.bytes);
    state.counters["depth"] = double(s.depth);
    state.counters["duplication"] = double(s.references) / double(mesh->triangle_count());
}

/// kd-tree builds: kd SAH with the kd constants, nodes, references, bytes.
void bm_build_kd(benchmark::State& state, std::shared_ptr<scene::TriangleMesh> mesh) {
    accel::KdTreeBuilder builder;
    accel::KdTree last;
    for (auto _ : state) {
        last = builder.build(*mesh);
        benchmark::DoNotOptimize(last.nodes.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh->triangle_count()));
    state.counters["triangles"] = double(mesh->triangle_count());
    if (const std::string err = accel::validate_kd(last, mesh->triangle_count()); !err.empty()) {
        state.SkipWithError(("invalid kd-tree: " + err).c_str());
        return;
    }
    const accel::KdTreeStats s =
        accel::compute_kd_stats(last, builder.config().traversal_cost, builder.config().intersection_cost);
    state.counters["kd_sah"] = s.sah;
    state.counters["nodes"] = double(s.nodes);
    state.counters["references"] = double(s.references);
    state.counters["bytes"] = double(last.bytes());
    state.counters["depth"] = double(s.depth);
    state.counters["duplication"] = double(s.references) / double(mesh->triangle_count());
}

/// Embree's own scene build on the same triangles (issue 21's yardstick): rtcCommitScene of one
/// triangle geometry at RTC_BUILD_QUALITY_MEDIUM on every core, timed alone (the buffers are
/// shared, set up outside the timed region).
void bm_build_embree(benchmark::State& state, RTCBuildQuality quality, std::shared_ptr<scene::TriangleMesh> mesh) {
    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) {
        state.SkipWithError("rtcNewDevice failed");
        return;
    }
    // Embree reads vertex buffers with 16-byte loads: one float of padding after the last vertex.
    std::vector<float> vertices(3 * mesh->vertices.size() + 4);
    std::memcpy(vertices.data(), mesh->vertices.data(), mesh->vertices.size() * sizeof(Vec3));
    for (auto _ : state) {
        RTCScene scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene, quality);
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(geom, quality);
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices.data(), 0,
                                   3 * sizeof(float), mesh->vertices.size());
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh->indices.data(), 0,
                                   3 * sizeof(uint32_t), mesh->triangle_count());
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        const auto t0 = std::chrono::steady_clock::now();
        rtcCommitScene(scene);
        state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        rtcReleaseScene(scene);
    }
    rtcReleaseDevice(device);
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh->triangle_count()));
    state.counters["triangles"] = double(mesh->triangle_count());
}

}  // namespace
}  // namespace bvhlab::bench

int main(int argc, char** argv) {
    using namespace bvhlab;
    return bench::bench_main(argc, argv, [](const bench::BenchScene& scene) {
        // Shared, loaded lazily on first use, so filtered-out scenes cost nothing.
        auto holder = std::make_shared<std::shared_ptr<scene::TriangleMesh>>();
        auto mesh = [holder, load = scene.load] {
            if (!*holder) *holder = std::make_shared<scene::TriangleMesh>(load());
            return *holder;
        };
        // Every build the same protocol (a warm-up, then 3 repetitions), so that the ratios
        // between builders (kd / binned, binned / Embree) compare like with like.
        auto protocol = [](benchmark::internal::Benchmark* b) {
            return b->Unit(benchmark::kMillisecond)->MinWarmUpTime(0.2)->Repetitions(3)->ReportAggregatesOnly(true);
        };
        const std::pair<accel::BuilderKind, int> variants[] = {{accel::BuilderKind::kBinned, -1},
                                                               {accel::BuilderKind::kSweep, -1},
                                                               {accel::BuilderKind::kSweep, 3},
                                                               {accel::BuilderKind::kSbvh, -1},
                                                               {accel::BuilderKind::kSbvh, 0}};
        for (const auto& [kind, reinsertion] : variants) {
            const std::string suffix = reinsertion < 0 ? "" : "-r" + std::to_string(reinsertion);
            const std::string name = std::string("BM_Build/") + accel::builder_name(kind) + suffix + "/" + scene.name;
            protocol(benchmark::RegisterBenchmark(name.c_str(), [mesh, kind = kind,
                                                                 reinsertion = reinsertion](benchmark::State& st) {
                bench::bm_build(st, kind, reinsertion, mesh());
            }))->UseRealTime();
        }
        protocol(benchmark::RegisterBenchmark(
                     ("BM_Build/embree-medium/" + scene.name).c_str(),
                     [mesh](benchmark::State& st) { bench::bm_build_embree(st, RTC_BUILD_QUALITY_MEDIUM, mesh()); }))
            ->UseManualTime();
        protocol(benchmark::RegisterBenchmark(("BM_Build/kdtree/" + scene.name).c_str(), [mesh](benchmark::State& st) {
            bench::bm_build_kd(st, mesh());
        }))->UseRealTime();
    });
}
