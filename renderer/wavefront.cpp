// SPDX-License-Identifier: MIT
#include "renderer/wavefront.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "accel/core/check.h"
#include "renderer/testing.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab::render {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

template <typename F>
void parallel(size_t n, F f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) f(uint32_t(i));
    });
}

/// Path state of one pass, structure-of-arrays, sized for every slot of a wave.
struct HostPaths {
    std::vector<trav::Ray> ray, next_ray, shadow_ray;
    std::vector<trav::Hit> hit, occlusion;
    std::vector<Vec3> throughput, next_throughput, shadow_radiance;
    std::vector<uint32_t> slot, shadow_slot;
    std::vector<float> prev_pdf, next_pdf;
    std::vector<uint8_t> alive, shadow;
    std::vector<Vec3> albedo, normal;  // per slot, when asked for

    explicit HostPaths(size_t n, bool aovs)
        : ray(n),
          next_ray(n),
          shadow_ray(n),
          throughput(n),
          next_throughput(n),
          shadow_radiance(n),
          slot(n),
          shadow_slot(n),
          prev_pdf(n),
          next_pdf(n),
          alive(n),
          shadow(n),
          albedo(aovs ? n : 0),
          normal(aovs ? n : 0) {}
    PathView view() { return {ray.data(), hit.data(), throughput.data(), slot.data(), prev_pdf.data()}; }
    ShadeOut out() {
        return {next_ray.data(),
                next_throughput.data(),
                next_pdf.data(),
                alive.data(),
                shadow_ray.data(),
                shadow_radiance.data(),
                shadow.data(),
                albedo.empty() ? nullptr : albedo.data(),
                normal.empty() ? nullptr : normal.data()};
    }
};

}  // namespace

Image mean_image(const std::vector<Vec3>& sum, uint32_t spp, uint32_t width, uint32_t height) {
    BVHLAB_CHECK(sum.size() == size_t(width) * height, "pixel sums do not match the image size");
    return mean_image(sum.data(), spp, width, height);
}

Image mean_image(const Vec3* sum, uint32_t spp, uint32_t width, uint32_t height) {
    Image img(width, height);
    const float inv = spp ? 1.0f / float(spp) : 0.0f;
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = sum[i] * inv;
    return img;
}

void check_settings(const RenderSettings& s, const CameraData& camera) {
    BVHLAB_CHECK(s.spp >= 1, "--spp must be at least 1");
    BVHLAB_CHECK(s.max_depth >= 1 && s.max_depth <= 1024, "--max-depth must be in [1, 1024]");
    BVHLAB_CHECK(!s.first_hit_cache || camera_rays_repeat(camera),
                 "--first-hit-cache needs camera rays that repeat: pixel centres, no --aperture and no --eye-end");
    BVHLAB_CHECK(s.compaction || s.dump_rays_dir.empty(),
                 "--dump-rays needs compaction (without it the queues hold dead paths' placeholder rays)");
    if (s.dump_rays_dir.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(s.dump_rays_dir, ec);
    if (ec) throw Error("cannot create --dump-rays folder " + s.dump_rays_dir + ": " + ec.message());
}

void dump_rays(const RenderSettings& s, const char* kind, uint32_t bounce, std::vector<trav::Ray> rays,
               trav::Query query) {
    if (s.dump_rays_dir.empty() || rays.empty()) return;
    trav::RaySet set;
    set.rays = std::move(rays);
    set.query = query;
    set.writer = s.writer;
    const std::string name = std::string(kind) + "-bounce" + std::to_string(bounce) + ".rays";
    trav::write_ray_file((std::filesystem::path(s.dump_rays_dir) / name).string(), set);
}

void finish_result(RenderResult& res, const PixelTotals& t, uint32_t width, uint32_t height) {
    res.mean = Image(width, height);
    res.variance_of_mean = Image(width, height);
    const float k = float(res.spp);
    for (size_t px = 0; px < res.mean.pixels.size(); ++px) {
        const Vec3 m = t.sum[px] * (1.0f / k);
        res.mean.pixels[px] = m;
        if (res.spp > 1) {
            // Unbiased sample variance, then that of the mean.
            const Vec3 var = (t.sum_sq[px] - m * m * k) * (1.0f / (k - 1.0f));
            res.variance_of_mean.pixels[px] = vmax(var, splat(0.0f)) * (1.0f / k);
        }
    }
    if (!t.albedo.empty()) {
        res.albedo = Image(width, height);
        res.normal = Image(width, height);
        for (size_t px = 0; px < t.albedo.size(); ++px) {
            res.albedo.pixels[px] = t.albedo[px] * (1.0f / k);
            const float len = length(t.normal[px]);
            res.normal.pixels[px] = len > 0.0f ? t.normal[px] * (1.0f / len) : splat(0.0f);
        }
    }
    while (!res.bounces.empty() && res.bounces.back().extension_rays == 0 && res.bounces.back().queue_entries == 0)
        res.bounces.pop_back();
}

uint32_t wave_samples(const RenderSettings& s, uint32_t pixels, uint32_t automatic) {
    uint32_t k = s.wave_samples ? s.wave_samples : automatic;
    k = std::max(1u, std::min(k, s.spp));
    BVHLAB_CHECK(uint64_t(pixels) * k < (uint64_t(1) << 31), "a wave of " + std::to_string(k) + " samples of " +
                                                                 std::to_string(pixels) +
                                                                 " pixels is too many paths (2^31 or more)");
    return k;
}

uint64_t RenderResult::rays() const {
    uint64_t n = 0;
    for (const BounceStats& b : bounces) n += b.extension_rays + b.shadow_rays;
    return n;
}

RenderResult render_host(const RenderScene& scene, const CameraData& camera, const RenderSettings& settings,
                         trav::Tracer& extend, trav::Tracer& shadow, const RenderProgress& progress) {
    check_settings(settings, camera);
    BVHLAB_CHECK(!settings.sort_by_material && settings.compaction,
                 "--sort-materials and --no-compaction apply to --device gpu");
    const auto t_start = Clock::now();
    const uint32_t npix = camera.width * camera.height;
    const uint32_t wave = wave_samples(settings, npix, default_wave(false, npix));
    const size_t cap = size_t(npix) * wave;
    const SceneView sv = scene.view();
    HostPaths paths(cap, settings.aovs);
    std::vector<Vec3> radiance(cap, splat(0.0f));
    PixelTotals totals;
    totals.sum.assign(npix, splat(0.0f));
    totals.sum_sq.assign(npix, splat(0.0f));
    totals.albedo.assign(settings.aovs ? npix : 0, splat(0.0f));
    totals.normal.assign(totals.albedo.size(), splat(0.0f));
    std::vector<trav::Ray> shadow_rays;  // reused by every bounce
    std::vector<trav::Hit> first_hits;   // the first-hit cache: one per pixel, once traced
    RenderResult res;
    res.wave_samples = wave;
    res.bounces.resize(settings.max_depth);
    PathParams pp{settings.max_depth, settings.rr_depth,     settings.seed, 0, npix,
                  settings.strategy,  testing::planted_bug()};
    res.ms_setup = ms_since(t_start);
    auto last_preview = Clock::now();
    for (uint32_t pass = 0; res.spp < settings.spp; ++pass) {
        pp.first_sample = res.spp;
        const uint32_t k = std::min(wave, settings.spp - res.spp);
        const size_t n_gen = size_t(npix) * k;
        auto t0 = Clock::now();
        paths.ray.resize(n_gen);
        paths.throughput.resize(n_gen);
        paths.slot.resize(n_gen);
        paths.prev_pdf.resize(n_gen);
        PathView pv = paths.view();
        parallel(n_gen, [&](uint32_t i) { generate_path(i, camera, pp, pv); });
        res.ms_generate += ms_since(t0);
        for (uint32_t bounce = 0; bounce < settings.max_depth && !paths.ray.empty(); ++bounce) {
            const size_t n = paths.ray.size();
            res.bounces[bounce].queue_entries += n;
            if (pass == 0) dump_rays(settings, "extension", bounce, paths.ray, trav::Query::kClosest);
            t0 = Clock::now();
            if (bounce == 0 && !first_hits.empty()) {
                // Bounce 0 holds slot i at entry i, and slot i is pixel i % npix.
                paths.hit.resize(n);
                parallel(n, [&](uint32_t i) { paths.hit[i] = first_hits[i % npix]; });
                res.cached_hits += n;
            } else {
                res.bounces[bounce].extension_rays += n;
                extend.set_rays(paths.ray, trav::Query::kClosest);
                extend.run();
                extend.hits(paths.hit);
                if (bounce == 0 && settings.first_hit_cache)
                    first_hits.assign(paths.hit.begin(), paths.hit.begin() + npix);
            }
            res.ms_extend += ms_since(t0);

            t0 = Clock::now();
            pv = paths.view();
            const ShadeOut so = paths.out();
            Vec3* rad = radiance.data();
            parallel(n, [&](uint32_t i) { shade_path(i, bounce, sv, pp, pv, so, rad); });
            res.ms_shade += ms_since(t0);

            // Compact the shadow rays, trace them, add the unoccluded ones.
            t0 = Clock::now();
            shadow_rays.clear();
            size_t ns = 0;
            for (size_t i = 0; i < n; ++i)
                if (paths.shadow[i]) {
                    shadow_rays.push_back(paths.shadow_ray[i]);
                    paths.shadow_slot[ns] = paths.slot[i];
                    paths.shadow_radiance[ns++] = paths.shadow_radiance[i];
                }
            res.ms_compact += ms_since(t0);
            if (ns) {
                res.bounces[bounce].shadow_rays += ns;
                if (pass == 0) dump_rays(settings, "shadow", bounce, shadow_rays, trav::Query::kAny);
                t0 = Clock::now();
                shadow.set_rays(shadow_rays, trav::Query::kAny);
                shadow.run();
                shadow.hits(paths.occlusion);
                const trav::Hit* occ = paths.occlusion.data();
                const uint32_t* spx = paths.shadow_slot.data();
                const Vec3* srad = paths.shadow_radiance.data();
                parallel(ns, [&](uint32_t i) { resolve_shadow(i, occ, spx, srad, rad); });
                res.ms_shadow += ms_since(t0);
            }

            // Compact the live paths into the next bounce's arrays (order kept).
            t0 = Clock::now();
            size_t live = 0;
            for (size_t i = 0; i < n; ++i)
                if (paths.alive[i]) {
                    paths.ray[live] = paths.next_ray[i];
                    paths.throughput[live] = paths.next_throughput[i];
                    paths.slot[live] = paths.slot[i];
                    paths.prev_pdf[live] = paths.next_pdf[i];
                    ++live;
                }
            paths.ray.resize(live);
            paths.throughput.resize(live);
            paths.slot.resize(live);
            paths.prev_pdf.resize(live);
            res.ms_compact += ms_since(t0);
        }
        t0 = Clock::now();
        Vec3* rad = radiance.data();
        const ShadeOut so = paths.out();
        const PixelSums sums{totals.sum.data(), totals.sum_sq.data(), settings.aovs ? totals.albedo.data() : nullptr,
                             settings.aovs ? totals.normal.data() : nullptr};
        parallel(npix, [&](uint32_t px) { accumulate_pixel(px, npix, k, rad, so.albedo, so.normal, sums); });
        res.ms_accumulate += ms_since(t0);
        res.spp += k;
        if (progress) progress(res.spp, settings.spp, res);
        if (settings.preview && ms_since(last_preview) >= 1000.0 * settings.preview_every_s) {
            settings.preview(mean_image(totals.sum, res.spp, camera.width, camera.height), res.spp);
            last_preview = Clock::now();
        }
        if (settings.time_limit_s > 0.0 && ms_since(t_start) >= 1000.0 * settings.time_limit_s) break;
    }
    finish_result(res, totals, camera.width, camera.height);
    res.ms_total = ms_since(t_start);
    return res;
}

}  // namespace bvhlab::render
