// SPDX-License-Identifier: MIT
// BM_Trace/bvh2/cpu-stack/<scene>/<ray type>: CPU traversal speed on the protocol's rays
// (1024x768 primary, 8 AO and 4 diffuse per hit, 1 shadow). Hits are checked against Embree
// before anything is timed; a mismatch skips the benchmark with an error.
#include <benchmark/benchmark.h>

#include "experiments/bench/bench_common.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/factory.h"
#include "traversal/oracle/compare.h"
#include "traversal/rays/protocol.h"

namespace bvhlab::bench {
namespace {

/// Everything one scene's benchmarks share, built once on first use.
struct Prepared {
    scene::TriangleMesh mesh;
    accel::Bvh2 bvh;
    std::unique_ptr<trav::EmbreeOracle> oracle;
    std::vector<trav::RaySet> sets;  // indexed by RayType
    std::vector<std::string> errors;
};

std::shared_ptr<Prepared> prepare(const BenchScene& scene) {
    auto p = std::make_shared<Prepared>();
    p->mesh = scene.load();
    trav::StructureSpec spec;  // the library's default structure: a binned SAH BVH2
    spec.epo = false;
    p->bvh = trav::build_structure(p->mesh, spec).structure.bvh2;
    p->oracle = std::make_unique<trav::EmbreeOracle>(p->mesh);
    trav::ProtocolConfig cfg;
    cfg.camera = scene.has_camera ? scene.camera : trav::framing_camera(p->mesh);
    cfg.ao_length = scene.ao_length;
    trav::RayProtocol proto(p->mesh, *p->oracle, cfg);
    for (int t = 0; t < 4; ++t) {
        p->sets.push_back(proto.make(trav::RayType(t)));
        const trav::RaySet& set = p->sets.back();
        std::vector<trav::Hit> ours, ref;
        trav::trace_cpu(p->bvh, set.rays, set.query, ours);
        p->oracle->trace(set.rays, set.query, ref);
        trav::CompareReport rep = trav::compare_hits(p->mesh, set.rays, set.query, ours, ref,
                                                     [&](const trav::Ray& r) { return p->oracle->intersect(r); });
        p->errors.push_back(rep.mismatches ? std::to_string(rep.mismatches) + " real mismatches against Embree" : "");
    }
    return p;
}

}  // namespace
}  // namespace bvhlab::bench

int main(int argc, char** argv) {
    using namespace bvhlab;
    return bench::bench_main(argc, argv, [](const bench::BenchScene& scene) {
        auto holder = std::make_shared<std::shared_ptr<bench::Prepared>>();
        for (int t = 0; t < 4; ++t) {
            const std::string name =
                std::string("BM_Trace/bvh2/cpu-stack/") + scene.name + "/" + trav::ray_type_name(trav::RayType(t));
            benchmark::RegisterBenchmark(name.c_str(),
                                         [holder, scene, t](benchmark::State& st) {
                                             if (!*holder) *holder = bench::prepare(scene);
                                             const bench::Prepared& p = **holder;
                                             if (!p.errors[size_t(t)].empty()) {
                                                 st.SkipWithError(p.errors[size_t(t)].c_str());
                                                 return;
                                             }
                                             const trav::RaySet& set = p.sets[size_t(t)];
                                             std::vector<trav::Hit> hits;
                                             for (auto _ : st) {
                                                 trav::trace_cpu(p.bvh, set.rays, set.query, hits);
                                                 benchmark::DoNotOptimize(hits.data());
                                             }
                                             st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(set.rays.size()));
                                             st.counters["rays"] = double(set.rays.size());
                                             st.counters["Mrays_per_s"] =
                                                 benchmark::Counter(double(set.rays.size()) * 1e-6,
                                                                    benchmark::Counter::kIsIterationInvariantRate);
                                         })
                ->Unit(benchmark::kMillisecond)
                ->MinWarmUpTime(0.2)
                ->UseRealTime()
                ->Repetitions(3)
                ->ReportAggregatesOnly(true);
        }
    });
}
