// SPDX-License-Identifier: MIT
#include "traversal/gpu/gpu_tracer.h"

#include "accel/core/check.h"
#include "traversal/device/kd_traverse.h"

namespace bvhlab::trav {

void check_kernel_fits(const KernelInfo& k, Layout layout, uint32_t depth, const GpuTraceOptions& opts) {
    if (k.layout != layout)
        throw Error(std::string("kernel '") + k.name + "' traces " + layout_name(k.layout) + " structures, not " +
                    layout_name(layout) + " (`bvhlab kernels` lists which kernel traces which)");
    if (k.stack_entries != kNoStackLimit && depth > k.stack_entries)
        throw Error("the tree is " + std::to_string(depth) + " interior nodes deep, more than kernel '" + k.name +
                    "' has stack for (" + std::to_string(k.stack_entries) + " entries)");
    if (k.short_stack && (opts.kd_stack < 1 || opts.kd_stack > kKdMaxShortStack))
        throw Error(std::string("kernel '") + k.name + "' takes a short stack of 1..8 entries, not " +
                    std::to_string(opts.kd_stack));
    if (opts.fetch_threshold != 0 && !k.dynamic_fetch)
        throw Error(std::string("a fetch threshold applies to the dynamic-fetch kernels, not '") + k.name + "'");
    if (opts.fetch_threshold < 0 || opts.fetch_threshold > 32)
        throw Error("the fetch threshold is 1..32 idle lanes, not " + std::to_string(opts.fetch_threshold));
    if (opts.block_size != 0 && (opts.block_size < 32 || opts.block_size > k.max_block || opts.block_size % 32 != 0))
        throw Error(std::string("kernel '") + k.name + "' takes a block size that is a multiple of 32 in 32.." +
                    std::to_string(k.max_block) + ", not " + std::to_string(opts.block_size));
}

namespace {

LaunchArgs make_args(const DeviceStructure& s, RayQueue& queue, Query query, uint32_t* d_next_ray,
                     const GpuTraceOptions& opts, void* stream) {
    LaunchArgs a;
    if (s.layout() == Layout::kBvh2)
        a.bvh2 = s.bvh2();
    else if (s.layout() == Layout::kCwbvh)
        a.cwbvh = s.cwbvh();
    else if (is_two_level(s.layout()))
        a.two_level = s.two_level();
    else
        a.kd = s.kd();
    a.queue = queue.view();
    a.capacity = uint32_t(queue.capacity());
    a.query = query;
    a.kd_stack = opts.kd_stack;
    a.block_size = opts.block_size;
    a.fetch_threshold = uint32_t(opts.fetch_threshold);
    a.d_next_ray = d_next_ray;
    a.stream = stream;
    return a;
}

class GpuTracer final : public Tracer {
public:
    GpuTracer(std::shared_ptr<const DeviceStructure> s, const KernelInfo& k, const GpuTraceOptions& opts)
        : s_(std::move(s)), k_(k), opts_(opts), next_ray_(1) {
        check_kernel_fits(k_, s_->layout(), s_->depth(), opts_);
    }
    std::string name() const override { return k_.name; }
    std::string device() const override { return "gpu"; }
    int block_size() const override { return opts_.block_size ? opts_.block_size : k_.default_block; }
    int short_stack() const override { return k_.short_stack ? opts_.kd_stack : 0; }
    int fetch_threshold() const override {
        return k_.dynamic_fetch ? (opts_.fetch_threshold ? opts_.fetch_threshold : kDefaultFetchThreshold) : 0;
    }
    void set_rays(const std::vector<Ray>& rays, Query query) override {
        queue_.upload(rays);
        count_ = rays.size();
        query_ = query;
    }
    double run() override {
        if (count_ == 0) return 0.0;
        queue_.poison_hits();
        next_ray_.fill_bytes(0);
        timer_.start();
        k_.launch(make_args(*s_, queue_, query_, next_ray_.data(), opts_, nullptr));
        return timer_.stop();
    }
    void hits(std::vector<Hit>& out) const override { queue_.download_hits(out, count_); }

private:
    std::shared_ptr<const DeviceStructure> s_;
    KernelInfo k_;
    GpuTraceOptions opts_;
    RayQueue queue_;
    DeviceBuffer<uint32_t> next_ray_;
    DeviceTimer timer_;
    size_t count_ = 0;
    Query query_ = Query::kClosest;
};

}  // namespace

std::unique_ptr<Tracer> make_gpu_tracer(std::shared_ptr<const DeviceStructure> structure, const KernelInfo& kernel,
                                        const GpuTraceOptions& opts) {
    return std::make_unique<GpuTracer>(std::move(structure), kernel, opts);
}

void trace_gpu_counted(const DeviceStructure& structure, const KernelInfo& kernel, const RaySet& set,
                       std::vector<Hit>& hits, std::vector<TraversalCounters>& counters, const GpuTraceOptions& opts) {
    if (!kernel.counts) throw Error(std::string("kernel '") + kernel.name + "' does not count its work");
    check_kernel_fits(kernel, structure.layout(), structure.depth(), opts);
    hits.clear();
    counters.clear();
    if (set.rays.empty()) return;
    RayQueue queue;
    queue.upload(set.rays);
    queue.poison_hits();
    DeviceBuffer<TraversalCounters> c(set.rays.size());
    c.fill_bytes(0xFF);  // poisoned: a ray the kernel skips shows
    LaunchArgs a = make_args(structure, queue, set.query, nullptr, opts, nullptr);
    a.counters = c.data();
    kernel.launch(a);
    queue.download_hits(hits, set.rays.size());
    c.download(counters);
}

void launch_on_queue(const DeviceStructure& structure, const KernelInfo& kernel, RayQueue& queue, Query query,
                     uint32_t* d_next_ray, const GpuTraceOptions& opts, void* stream) {
    check_kernel_fits(kernel, structure.layout(), structure.depth(), opts);
    if (queue.capacity() == 0) return;
    kernel.launch(make_args(structure, queue, query, d_next_ray, opts, stream));
}

}  // namespace bvhlab::trav
