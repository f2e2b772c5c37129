// SPDX-License-Identifier: MIT
// The GPU wavefront driver; see gpu_render.h.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <functional>

#include "accel/core/check.h"
#include "renderer/gpu/extend.h"
#include "renderer/gpu/gpu_render.h"
#include "renderer/gpu/stage_kernels.h"
#include "renderer/testing.h"
#include "traversal/cuda_check.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::render {

namespace {

/// The preview's copies of the pixel sums: each an asynchronous copy into pinned host memory,
/// queued behind the passes enqueued so far, so the GPU never waits for the host (a
/// synchronous download stalled the stream for about 20 ms per 1920x1080 update). Finished
/// copies are handed to the preview in order; at most two are in flight (a third waits for the
/// oldest), so an update every pass still shows every pass.
class PreviewCopies {
public:
    PreviewCopies(const std::function<void(const Image&, uint32_t)>& preview, uint32_t width, uint32_t height)
        : preview_(preview), width_(width), height_(height) {}
    ~PreviewCopies() {
        for (Slot& s : slots_) {
            if (s.event) cudaEventDestroy(s.event);
            if (s.host) cudaFreeHost(s.host);
        }
    }
    PreviewCopies(const PreviewCopies&) = delete;
    PreviewCopies& operator=(const PreviewCopies&) = delete;

    /// Queues a copy of `sum` (the sums after `spp` samples) on `stream`.
    void snapshot(const Vec3* sum, uint32_t spp, void* stream) {
        Slot& s = slots_[next_ % 2];
        if (s.pending) deliver(s, true);  // the oldest of two in flight
        const size_t n = size_t(width_) * height_;
        if (!s.host) {
            BVHLAB_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&s.host), n * sizeof(Vec3)));
            BVHLAB_CUDA_CHECK(cudaEventCreateWithFlags(&s.event, cudaEventDisableTiming));
        }
        const auto st = static_cast<cudaStream_t>(stream);
        BVHLAB_CUDA_CHECK(cudaMemcpyAsync(s.host, sum, n * sizeof(Vec3), cudaMemcpyDeviceToHost, st));
        BVHLAB_CUDA_CHECK(cudaEventRecord(s.event, st));
        s.spp = spp;
        s.pending = true;
        s.order = next_++;
    }
    /// Hands over the finished copies, oldest first, without waiting.
    void deliver_ready() {
        for (Slot* s = oldest(); s && deliver(*s, false); s = oldest()) {
        }
    }
    /// Hands over every copy, waiting for those still running.
    void deliver_all() {
        for (Slot* s = oldest(); s; s = oldest()) deliver(*s, true);
    }

private:
    struct Slot {
        Vec3* host = nullptr;
        cudaEvent_t event = nullptr;
        uint32_t spp = 0;
        uint64_t order = 0;
        bool pending = false;
    };
    Slot* oldest() {
        Slot* o = nullptr;
        for (Slot& s : slots_)
            if (s.pending && (!o || s.order < o->order)) o = &s;
        return o;
    }
    /// Hands `s` over if its copy has finished (or after waiting for it); false if it has not.
    bool deliver(Slot& s, bool wait) {
        if (wait) {
            BVHLAB_CUDA_CHECK(cudaEventSynchronize(s.event));
        } else {
            const cudaError_t e = cudaEventQuery(s.event);
            if (e == cudaErrorNotReady) return false;
            BVHLAB_CUDA_CHECK(e);
        }
        s.pending = false;
        preview_(mean_image(s.host, s.spp, width_, height_), s.spp);
        return true;
    }

    const std::function<void(const Image&, uint32_t)>& preview_;
    uint32_t width_, height_;
    Slot slots_[2];
    uint64_t next_ = 0;
};

}  // namespace
namespace {

using trav::DeviceBuffer;

/// The scene's arrays on the device and the view the stages read.
struct DeviceScene {
    DeviceBuffer<Vec3> vertices, normals;
    DeviceBuffer<uint32_t> indices, light_tris;
    DeviceBuffer<int32_t> material_ids;
    DeviceBuffer<RenderMaterial> materials;
    DeviceBuffer<AliasEntry> alias;
    DeviceBuffer<float> pick_pdf;
    DeviceBuffer<Vec3> env;
    DeviceBuffer<float> env_row_cdf, env_col_cdf, env_row_pdf, env_col_pdf;
    DeviceBuffer<Vec3> texels;
    DeviceBuffer<TextureInfo> textures;
    DeviceBuffer<float> texcoords;
    SceneView view;

    explicit DeviceScene(const RenderScene& s)
        : vertices(s.mesh().vertices),
          normals(s.mesh().normals),
          indices(s.mesh().indices),
          light_tris(s.light_tris()),
          material_ids(s.material_ids()),
          materials(s.materials()),
          alias(s.alias_table()),
          pick_pdf(s.pick_pdf()),
          env(s.env().pixels),
          env_row_cdf(s.env_row_cdf()),
          env_col_cdf(s.env_col_cdf()),
          env_row_pdf(s.env_row_pdf()),
          env_col_pdf(s.env_col_pdf()),
          texels(s.texels()),
          textures(s.textures()),
          texcoords(s.texcoords()) {
        view = s.view();  // the host view's scalars, then the device pointers
        view.vertices = vertices.data();
        view.indices = indices.data();
        view.material_ids = material_ids.data();
        view.normals = s.mesh().normals.empty() ? nullptr : normals.data();
        view.materials = materials.data();
        view.lights.tris = light_tris.data();
        view.lights.table = alias.data();
        view.lights.pick_pdf = pick_pdf.data();
        view.lights.env.pixels = env.data();
        view.lights.env.row_cdf = env_row_cdf.data();
        view.lights.env.col_cdf = env_col_cdf.data();
        view.lights.env.row_pdf = env_row_pdf.data();
        view.lights.env.col_pdf = env_col_pdf.data();
        view.textures = {texels.data(), textures.data(), s.texcoords().empty() ? nullptr : texcoords.data()};
    }
};

/// One CUDA event per stage boundary of a pass, for the per-stage times.
class Timeline {
public:
    explicit Timeline(size_t n) : events_(n) {
        for (auto& e : events_) BVHLAB_CUDA_CHECK(cudaEventCreate(&e));
    }
    ~Timeline() {
        for (auto& e : events_) BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(e));
    }
    Timeline(const Timeline&) = delete;
    Timeline& operator=(const Timeline&) = delete;
    void mark(size_t i) { BVHLAB_CUDA_CHECK(cudaEventRecord(events_[i])); }
    double ms(size_t a, size_t b) const {
        float t = 0.0f;
        BVHLAB_CUDA_CHECK(cudaEventElapsedTime(&t, events_[a], events_[b]));
        return double(t);
    }
    void wait(size_t i) const { BVHLAB_CUDA_CHECK(cudaEventSynchronize(events_[i])); }

private:
    std::vector<cudaEvent_t> events_;
};

/// --dump-rays on the GPU: copies a queue back (a synchronisation, only when asked for).
void dump_queue(const RenderSettings& s, const char* kind, uint32_t bounce, trav::RayQueue& q, trav::Query query) {
    if (s.dump_rays_dir.empty()) return;
    uint32_t n = 0;
    trav::detail::copy_to_host(&n, q.view().count, sizeof n);
    std::vector<trav::Ray> rays(n);
    if (n) trav::detail::copy_to_host(rays.data(), q.view().rays, n * sizeof(trav::Ray));
    dump_rays(s, kind, bounce, std::move(rays), query);
}

}  // namespace

RenderResult render_gpu(const RenderScene& scene, const CameraData& camera, const RenderSettings& settings,
                        const trav::DeviceStructure& structure, const trav::KernelInfo& kernel,
                        const trav::GpuTraceOptions& opts, const RenderProgress& progress) {
    check_settings(settings, camera);
    trav::check_kernel_fits(kernel, structure.layout(), structure.depth(), opts);
    using Clock = std::chrono::steady_clock;
    const auto t_start = Clock::now();
    const uint32_t npix = camera.width * camera.height;
    const uint32_t wave = wave_samples(settings, npix, default_wave(true, npix));
    const uint32_t cap = npix * wave;
    void* stream = nullptr;  // the default stream: every stage in order, no host waits

    DeviceScene ds(scene);
    // Path state in two sets: the shade stage reads set `cur` and writes the survivors into
    // the other, compacted (compact.cuh).
    trav::RayQueue ext[2] = {trav::RayQueue(cap), trav::RayQueue(cap)};
    // Two shadow queues, by bounce parity, so that the resolve stage can zero the next
    // bounce's count while its own is still read.
    trav::RayQueue shadow_q[2] = {trav::RayQueue(cap), trav::RayQueue(cap)};
    DeviceBuffer<Vec3> tp[2] = {DeviceBuffer<Vec3>(cap), DeviceBuffer<Vec3>(cap)};
    DeviceBuffer<float> pdf[2] = {DeviceBuffer<float>(cap), DeviceBuffer<float>(cap)};
    DeviceBuffer<uint32_t> slot[2] = {DeviceBuffer<uint32_t>(cap), DeviceBuffer<uint32_t>(cap)};
    DeviceBuffer<Vec3> shadow_rad(cap), radiance(cap), sum(npix), sum_sq(npix);
    // The persistent kernels' fetch counters, one per trace of a pass, zeroed by generate.
    DeviceBuffer<uint32_t> shadow_slot(cap), trace_counters(2 * settings.max_depth);
    const size_t aov_slots = settings.aovs ? cap : 0, aov_pixels = settings.aovs ? npix : 0;
    DeviceBuffer<Vec3> albedo(aov_slots), normal(aov_slots), albedo_sum(aov_pixels), normal_sum(aov_pixels);
    DeviceBuffer<unsigned long long> ext_stats(settings.max_depth), shadow_stats(settings.max_depth),
        queue_stats(settings.max_depth);
    for (auto* b : {&radiance, &sum, &sum_sq, &albedo_sum, &normal_sum}) b->fill_bytes(0, stream);
    for (auto* b : {&ext_stats, &shadow_stats, &queue_stats}) b->fill_bytes(0, stream);
    // Without compaction: the live paths and shadow rays each bounce leaves, counted apart
    // from the queues (which keep every entry).
    DeviceBuffer<uint32_t> live_counts(settings.compaction ? 0 : 4);
    // The material sort's keys, orders and CUB scratch.
    const size_t sort_n = settings.sort_by_material ? cap : 0;
    DeviceBuffer<uint32_t> sort_keys[2] = {DeviceBuffer<uint32_t>(sort_n), DeviceBuffer<uint32_t>(sort_n)};
    DeviceBuffer<uint32_t> sort_order[2] = {DeviceBuffer<uint32_t>(sort_n), DeviceBuffer<uint32_t>(sort_n)};
    const int sort_bits = settings.sort_by_material ? gpu::material_sort_bits(scene.materials().size()) : 0;
    DeviceBuffer<unsigned char> sort_temp(settings.sort_by_material ? gpu::material_sort_temp_bytes(cap, sort_bits)
                                                                    : 0);
    const gpu::MaterialSortBuffers sort{sort_keys[0].data(),
                                        sort_keys[1].data(),
                                        sort_order[0].data(),
                                        sort_order[1].data(),
                                        sort_temp.data(),
                                        sort_temp.size(),
                                        sort_bits};
    // The first-hit cache: one hit per pixel, filled by pass 0's camera rays.
    DeviceBuffer<trav::Hit> first_hits(settings.first_hit_cache ? npix : 0);

    Vec3* const slot_albedo = settings.aovs ? albedo.data() : nullptr;
    Vec3* const slot_normal = settings.aovs ? normal.data() : nullptr;
    const PixelSums sums{sum.data(), sum_sq.data(), settings.aovs ? albedo_sum.data() : nullptr,
                         settings.aovs ? normal_sum.data() : nullptr};
    auto path_set = [&](int c) {
        const trav::RayQueueView q = ext[c].view();
        return PathView{q.rays, q.hits, tp[c].data(), slot[c].data(), pdf[c].data()};
    };
    // Events per pass: 0 start, 1 generated, then 3 per bounce (extended, shaded and
    // compacted, shadows traced and resolved), then accumulated. Two timelines: pass p is
    // enqueued before the host waits for pass p - 1, so the GPU never idles between passes.
    const size_t per_bounce = 3, n_events = 2 + per_bounce * settings.max_depth + 1, last = n_events - 1;
    Timeline tl[2] = {Timeline(n_events), Timeline(n_events)};
    RenderResult res;
    res.wave_samples = wave;
    auto read_bounces = [&] {
        std::vector<unsigned long long> ec, sc, qc;
        ext_stats.download(ec);
        shadow_stats.download(sc);
        queue_stats.download(qc);
        res.bounces.assign(settings.max_depth, {});
        for (uint32_t b = 0; b < settings.max_depth; ++b) res.bounces[b] = {ec[b], sc[b], qc[b]};
    };
    auto collect = [&](const Timeline& t, uint32_t samples) {
        t.wait(last);
        res.ms_generate += t.ms(0, 1);
        for (uint32_t b = 0; b < settings.max_depth; ++b) {
            const size_t e = 2 + per_bounce * b;
            res.ms_extend += t.ms(e - 1, e);  // from the previous bounce's end (or generation)
            res.ms_shade += t.ms(e, e + 1);   // shading and compaction, fused
            res.ms_shadow += t.ms(e + 1, e + 2);
        }
        res.ms_accumulate += t.ms(last - 1, last);
        res.spp += samples;
    };
    PathParams pp{settings.max_depth, settings.rr_depth,     settings.seed, 0, npix,
                  settings.strategy,  testing::planted_bug()};
    BVHLAB_CUDA_CHECK(cudaDeviceSynchronize());
    res.ms_setup = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
    uint32_t enqueued = 0, in_flight = 0;  // samples enqueued; those of the pass not yet collected
    uint32_t pass = 0;
    auto last_report = Clock::now(), last_preview = Clock::now();
    PreviewCopies previews(settings.preview, camera.width, camera.height);
    for (; enqueued < settings.spp; ++pass) {
        Timeline& t = tl[pass % 2];
        pp.first_sample = enqueued;
        const uint32_t k = std::min(wave, settings.spp - enqueued);
        int cur = 0;
        t.mark(0);
        gpu::Chores gen;  // the counts bounce 0 needs at zero, and every trace's fetch counter
        gen.zero[0] = ext[1].view().count;
        gen.zero[1] = shadow_q[0].view().count;
        gen.zero_run = trace_counters.data();
        gen.zero_run_n = 2 * settings.max_depth;
        gpu::launch_generate(camera, pp, path_set(cur), npix * k, ext[cur].view().count, gen, stream);
        t.mark(1);
        for (uint32_t b = 0; b < settings.max_depth; ++b) {
            const size_t e = 2 + per_bounce * b;
            const int nxt = 1 - cur, sq = int(b % 2);
            trav::RayQueue& shadows = shadow_q[sq];
            uint32_t* const queue_count = ext[cur].view().count;
            // The live paths: the queue's count, except without compaction after bounce 0.
            const uint32_t* live = settings.compaction || b == 0 ? queue_count : live_counts.data() + 2 * cur;
            gpu::Chores shade_chores;  // the bounce's totals, added by the shade kernel
            shade_chores.total[0] = queue_stats.data() + b;
            shade_chores.count[0] = queue_count;
            if (pass == 0) dump_queue(settings, "extension", b, ext[cur], trav::Query::kClosest);
            if (b == 0 && settings.first_hit_cache && pass > 0) {
                gpu::launch_cached_hits(first_hits.data(), npix, ext[cur].view().hits, queue_count, cap, stream);
                res.cached_hits += uint64_t(npix) * k;
            } else {
                shade_chores.total[1] = ext_stats.data() + b;
                shade_chores.count[1] = live;
                gpu::extend(structure, kernel, ext[cur], trav::Query::kClosest, trace_counters.data() + 2 * b, opts,
                            stream);
                if (b == 0 && settings.first_hit_cache)
                    BVHLAB_CUDA_CHECK(cudaMemcpyAsync(first_hits.data(), ext[cur].view().hits, npix * sizeof(trav::Hit),
                                                      cudaMemcpyDeviceToDevice, static_cast<cudaStream_t>(stream)));
            }
            t.mark(e);
            uint32_t* const next_live = settings.compaction ? nullptr : live_counts.data() + 2 * nxt;
            if (next_live) trav::detail::fill_device_bytes(next_live, 0, 2 * sizeof(uint32_t), stream);
            const uint32_t* order = nullptr;
            if (settings.sort_by_material) {
                gpu::launch_material_sort(ext[cur].view().hits, ds.view.material_ids, queue_count, cap, sort, stream);
                order = sort.order_out;
            }
            const gpu::NextQueues q{path_set(nxt),     ext[nxt].view().count, shadows.view().rays,
                                    shadow_rad.data(), shadow_slot.data(),    shadows.view().count,
                                    next_live};
            gpu::launch_shade(b, ds.view, pp, path_set(cur), order, q, radiance.data(), slot_albedo, slot_normal,
                              queue_count, cap, shade_chores, stream);
            t.mark(e + 1);
            if (pass == 0) dump_queue(settings, "shadow", b, shadows, trav::Query::kAny);
            gpu::extend(structure, kernel, shadows, trav::Query::kAny, trace_counters.data() + 2 * b + 1, opts, stream);
            gpu::Chores resolve_chores;  // the shadow total; the counts the next bounce fills, zeroed
            resolve_chores.total[0] = shadow_stats.data() + b;
            resolve_chores.count[0] = settings.compaction ? shadows.view().count : next_live + 1;
            resolve_chores.zero[0] = queue_count;
            resolve_chores.zero[1] = shadow_q[1 - sq].view().count;
            gpu::launch_resolve_shadow(shadows.view().hits, shadow_slot.data(), shadow_rad.data(), radiance.data(),
                                       shadows.view().count, cap, resolve_chores, stream);
            t.mark(e + 2);
            cur = nxt;
        }
        gpu::launch_accumulate(radiance.data(), slot_albedo, slot_normal, sums, npix, k, stream);
        t.mark(last);
        enqueued += k;
        if (pass > 0) collect(tl[(pass - 1) % 2], in_flight);
        in_flight = k;
        if (progress && std::chrono::duration<double>(Clock::now() - last_report).count() >= 0.5) {
            read_bounces();  // a copy: waits for the pass just enqueued, twice a second at most
            last_report = Clock::now();
            progress(res.spp, settings.spp, res);
        }
        if (settings.preview) {
            previews.deliver_ready();
            if (std::chrono::duration<double>(Clock::now() - last_preview).count() >= settings.preview_every_s) {
                previews.snapshot(sum.data(), enqueued, stream);
                last_preview = Clock::now();
            }
        }
        if (settings.time_limit_s > 0.0 &&
            std::chrono::duration<double>(Clock::now() - t_start).count() >= settings.time_limit_s) {
            ++pass;
            break;
        }
    }
    if (pass > 0) collect(tl[(pass - 1) % 2], in_flight);
    previews.deliver_all();
    read_bounces();
    PixelTotals totals;
    sum.download(totals.sum);
    sum_sq.download(totals.sum_sq);
    albedo_sum.download(totals.albedo);
    normal_sum.download(totals.normal);
    finish_result(res, totals, camera.width, camera.height);
    res.ms_total = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
    return res;
}

}  // namespace bvhlab::render
