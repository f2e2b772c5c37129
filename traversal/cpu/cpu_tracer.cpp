// SPDX-License-Identifier: MIT
// The CPU tracers behind make_cpu_tracer: the shared traversals under TBB, wall-clock timed.
#include <chrono>

#include "accel/core/check.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/cpu/kd_trace.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/tracer.h"

namespace bvhlab::trav {

void trace_cpu_counted(const Structure& s, int kd_stack, const RaySet& set, std::vector<Hit>& hits,
                       std::vector<TraversalCounters>* counters) {
    if (s.layout == Layout::kBvh2) {
        trace_cpu(s.bvh2, set.rays, set.query, hits, counters);
    } else if (s.layout == Layout::kCwbvh) {
        trace_cpu(s.cwbvh, set.rays, set.query, hits, counters);
    } else if (is_two_level(s.layout)) {
        trace_cpu(s.two_level, set.rays, set.query, hits, counters);
    } else {
        trace_kd_cpu(s.kd, kd_stack, set.rays, set.query, hits, counters);
    }
}

namespace {

class CpuTracer final : public Tracer {
public:
    CpuTracer(const Structure& s, int kd_stack) : s_(s), kd_stack_(kd_stack) {
        // Refused here, before any ray is traced.
        if (s.layout == Layout::kBvh2) {
            check_bvh2_stack(s.bvh2);
            name_ = "cpu-bvh2-stack";
        } else if (s.layout == Layout::kCwbvh) {
            check_cwbvh_stack(s.cwbvh);
            name_ = "cpu-cwbvh";
        } else if (is_two_level(s.layout)) {
            check_bvh2_stack(s.two_level.tlas);
            for (const accel::Bvh2& b : s.two_level.blas) check_bvh2_stack(b);
            for (const accel::Cwbvh& b : s.two_level.cw_blas) check_cwbvh_stack(b);
            name_ = s.two_level.wide() ? "cpu-two-level-cwbvh" : "cpu-two-level-stack";
        } else {
            check_kd_stack(s.kd, kd_stack);
            name_ = kd_stack == kKdFullStack ? "cpu-kd-stack" : "cpu-kd-shortstack-" + std::to_string(kd_stack);
        }
    }
    std::string name() const override { return name_; }
    std::string device() const override { return "cpu"; }
    int short_stack() const override { return s_.layout == Layout::kKd && kd_stack_ != kKdFullStack ? kd_stack_ : 0; }
    void set_rays(const std::vector<Ray>& rays, Query query) override {
        set_.rays = rays;
        set_.query = query;
    }
    double run() override {
        const auto t0 = std::chrono::steady_clock::now();
        trace_cpu_counted(s_, kd_stack_, set_, hits_, nullptr);
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
    void hits(std::vector<Hit>& out) const override { out = hits_; }

private:
    const Structure& s_;
    int kd_stack_;
    std::string name_;
    RaySet set_;
    std::vector<Hit> hits_;
};

}  // namespace

std::unique_ptr<Tracer> make_cpu_tracer(const Structure& structure, int kd_stack) {
    return std::make_unique<CpuTracer>(structure, kd_stack);
}

}  // namespace bvhlab::trav
