// SPDX-License-Identifier: MIT
// BM_Build/<builder>/<scene>: build time (Mtris/s) with SAH, EPO, nodes, references and bytes
// as counters, so speed and quality land in one JSON. Builders run with their defaults (SBVH
// includes its 3 reinsertion passes); "sbvh-r0" is the SBVH without them and "sweep-r3" the
// sweep with them, so the optimiser's share can be read off.
#include <benchmark/benchmark.h>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "experiments/bench/bench_common.h"

namespace bvhlab::bench {
namespace {

void bm_build(benchmark::State& state, accel::BuilderKind kind, int reinsertion,
              std::shared_ptr<accel::TriangleMesh> mesh) {
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
void bm_build_kd(benchmark::State& state, std::shared_ptr<accel::TriangleMesh> mesh) {
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
    const accel::KdTreeStats s = accel::compute_kd_stats(last, builder.config());
    state.counters["kd_sah"] = s.sah;
    state.counters["nodes"] = double(s.nodes);
    state.counters["references"] = double(s.references);
    state.counters["bytes"] = double(last.bytes());
    state.counters["depth"] = double(s.depth);
    state.counters["duplication"] = double(s.references) / double(mesh->triangle_count());
}

}  // namespace
}  // namespace bvhlab::bench

int main(int argc, char** argv) {
    using namespace bvhlab;
    return bench::bench_main(argc, argv, [](const bench::BenchScene& scene) {
        // Shared, loaded lazily on first use, so filtered-out scenes cost nothing.
        auto holder = std::make_shared<std::shared_ptr<accel::TriangleMesh>>();
        auto load = scene.load;
        const std::pair<accel::BuilderKind, int> variants[] = {{accel::BuilderKind::kBinned, -1},
                                                               {accel::BuilderKind::kSweep, -1},
                                                               {accel::BuilderKind::kSweep, 3},
                                                               {accel::BuilderKind::kSbvh, -1},
                                                               {accel::BuilderKind::kSbvh, 0}};
        for (const auto& [kind, reinsertion] : variants) {
            const std::string suffix = reinsertion < 0 ? "" : "-r" + std::to_string(reinsertion);
            const std::string name = std::string("BM_Build/") + accel::builder_name(kind) + suffix + "/" + scene.name;
            benchmark::RegisterBenchmark(name.c_str(),
                                         [holder, load, kind = kind, reinsertion = reinsertion](benchmark::State& st) {
                                             if (!*holder) *holder = std::make_shared<accel::TriangleMesh>(load());
                                             bench::bm_build(st, kind, reinsertion, *holder);
                                         })
                ->Unit(benchmark::kMillisecond)
                ->MinWarmUpTime(0.2)
                ->UseRealTime()
                ->Repetitions(3)
                ->ReportAggregatesOnly(true);
        }
        // The same protocol as the BVH builders (a warm-up, then 3 repetitions), so that the
        // kd build / binned build ratio compares like with like.
        benchmark::RegisterBenchmark(("BM_Build/kdtree/" + scene.name).c_str(),
                                     [holder, load](benchmark::State& st) {
                                         if (!*holder) *holder = std::make_shared<accel::TriangleMesh>(load());
                                         bench::bm_build_kd(st, *holder);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->MinWarmUpTime(0.2)
            ->UseRealTime()
            ->Repetitions(3)
            ->ReportAggregatesOnly(true);
    });
}
