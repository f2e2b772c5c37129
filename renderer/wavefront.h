// SPDX-License-Identifier: MIT
// The wavefront render loop: per sample pass, generate -> (extend -> shade -> shadow ->
// compact)* -> accumulate. This is the host driver (bvhlab render --device cpu): the stages of
// renderer/core/stages.h in TBB loops, any Tracer for the two trace stages (Embree for the
// reference integrator).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "renderer/image.h"
#include "renderer/render_scene.h"
#include "traversal/tracer.h"

namespace bvhlab::render {

struct RenderSettings {
    uint32_t spp = 16;
    uint32_t max_depth = 8;  ///< most segments per path
    uint32_t rr_depth = 3;   ///< Russian roulette from this bounce on
    uint32_t seed = 1;
    double time_limit_s = 0.0;  ///< > 0: stop after the pass that crosses it (at least one pass)
    Strategy strategy = Strategy::kMis;
    std::string dump_rays_dir;  ///< non-empty: each bounce's rays of pass 0 as ray files here
    std::string writer;         ///< the commit recorded in dumped ray files
    /// Samples of every pixel traced together in one pass (a wave); 0: the driver's default
    /// (the GPU: enough for about 2M paths; the CPU: 1).
    uint32_t wave_samples = 0;
    bool aovs = false;  ///< also the first hits' albedo and normal, averaged per pixel
    /// The camera rays' hits traced once and reused by every later sample. Needs a camera whose
    /// rays repeat (camera_rays_repeat: pixel centres, pinhole, still), so it costs the
    /// anti-aliasing; the image equals the same camera's without the cache.
    bool first_hit_cache = false;
    /// GPU only: each bounce's paths sorted by the material they hit (CUB radix sort) before
    /// shading, which then reads them in that order.
    bool sort_by_material = false;
    /// GPU only: false keeps dead paths in the queues (placeholder rays that miss at once), the
    /// baseline of the compaction experiment. The image is the same either way.
    bool compaction = true;
    /// A progressive preview: called with the running mean and its samples per pixel about every
    /// preview_every_s seconds while the render runs (after the pass that crosses the time), and
    /// never when empty. On the GPU each call copies the pixel sums back once.
    std::function<void(const Image& mean, uint32_t spp)> preview;
    double preview_every_s = 1.0;
};

/// The mean of `spp` samples from per-pixel sums, as an image.
Image mean_image(const std::vector<Vec3>& sum, uint32_t spp, uint32_t width, uint32_t height);
/// The same from width x height sums in host memory (the GPU preview's pinned copy).
Image mean_image(const Vec3* sum, uint32_t spp, uint32_t width, uint32_t height);

/// Per bounce: rays traced (extension rays = paths alive), summed over the passes.
struct BounceStats {
    uint64_t extension_rays = 0;  ///< live paths traced (cached first hits not included)
    uint64_t shadow_rays = 0;
    uint64_t queue_entries = 0;  ///< extension queue entries launched: with compaction, the live paths
};

struct RenderResult {
    Image mean;                 ///< radiance per pixel, averaged over the samples
    Image variance_of_mean;     ///< per channel: sample variance / samples (0 with one sample)
    Image albedo, normal;       ///< with RenderSettings::aovs: mean albedo, normalised mean normal
    uint32_t spp = 0;           ///< samples per pixel done
    uint32_t wave_samples = 0;  ///< samples per pixel traced per pass
    uint64_t cached_hits = 0;   ///< camera rays answered from the first-hit cache, not traced
    std::vector<BounceStats> bounces;
    double ms_generate = 0, ms_extend = 0, ms_shade = 0, ms_shadow = 0, ms_compact = 0, ms_accumulate = 0;
    double ms_setup = 0;  ///< before the first pass: uploads, allocations, the first launches
    double ms_total = 0;
    uint64_t rays() const;
};

/// Paths per wave the GPU driver aims for unless told (NOTES.md, session 15: one sample of
/// 640x480 per pass, ~300k rays per trace, left the H100 idle between launches).
constexpr uint32_t kGpuWavePaths = 2u << 20;

/// The driver's default samples per pass: about kGpuWavePaths paths on the GPU, 1 on the CPU.
inline uint32_t default_wave(bool gpu, uint32_t pixels) {
    return gpu && pixels < kGpuWavePaths ? kGpuWavePaths / pixels : 1u;
}

/// The samples per pass for `pixels` pixels: settings.wave_samples, else `automatic`, at most
/// spp and at least 1. Throws bvhlab::Error when the wave would hold 2^31 paths or more.
uint32_t wave_samples(const RenderSettings& s, uint32_t pixels, uint32_t automatic);

/// What both drivers check and prepare before a render: spp, max depth, that the first-hit
/// cache has a camera whose rays repeat, that --dump-rays has compaction, and the --dump-rays
/// folder (created). Throws bvhlab::Error naming the problem.
void check_settings(const RenderSettings& s, const CameraData& camera);

/// --dump-rays: one bounce's rays as DIR/KIND-bounceN.rays (nothing when no folder is set or
/// there are no rays).
void dump_rays(const RenderSettings& s, const char* kind, uint32_t bounce, std::vector<trav::Ray> rays,
               trav::Query query);

/// Per-pixel sums over res.spp samples, as the accumulate stage leaves them; albedo and normal
/// are empty unless RenderSettings::aovs.
struct PixelTotals {
    std::vector<Vec3> sum, sum_sq, albedo, normal;
};

/// Fills res.mean, res.variance_of_mean and (with AOVs) res.albedo and res.normal, and drops
/// trailing bounces that traced nothing. Shared by the host and GPU drivers.
void finish_result(RenderResult& res, const PixelTotals& totals, uint32_t width, uint32_t height);

/// Progress after each pass: samples per pixel done, and asked for.
using RenderProgress = std::function<void(uint32_t done, uint32_t total, const RenderResult& so_far)>;

/// Renders on the host. `extend` answers closest-hit rays, `shadow` any-hit rays (they may be
/// the same tracer). Throws bvhlab::Error for bad settings.
RenderResult render_host(const RenderScene& scene, const CameraData& camera, const RenderSettings& settings,
                         trav::Tracer& extend, trav::Tracer& shadow, const RenderProgress& progress = {});

}  // namespace bvhlab::render
