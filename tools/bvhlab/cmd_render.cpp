// SPDX-License-Identifier: MIT
// `bvhlab render`: the wavefront path tracer (issue 19). --device embree (the default) is the
// reference integrator: the shared stages on the host with Embree tracing every ray; --device
// cpu traces with bvhlab's CPU traversal of the structure, --device gpu with a kernel.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <memory>

#include "accel/core/check.h"
#include "renderer/denoise.h"
#include "renderer/gpu/gpu_render.h"
#include "renderer/image.h"
#include "renderer/preview_server.h"
#include "renderer/wavefront.h"
#include "scene/domain.h"
#include "scene/io/atomic_file.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/oracle/embree_oracle.h"

namespace bvhlab::cli {
namespace {

struct RenderOpts {
    std::string scene, out, dump_rays, strategy = "mis", cost_image, missing = "error";
    bool aov = false, pixel_centres = false, no_compaction = false, denoise = false;
    std::string oidn, denoise_device = "auto", preview, serve_bind = "127.0.0.1";
    double preview_every = 1.0;
    int serve = -1;  // --serve PORT; -1: no server
    BuildOptions build;
    TraceOptions trace;
    uint32_t width = 640, height = 480;
    render::RenderSettings rs;
    CameraOptions camera;
    std::vector<float> sky, eye_end, shutter;
    float aperture = 0.0f, focus = 0.0f, env_scale = 1.0f;
    std::string env;
};

Vec3 vec3_of(const std::vector<float>& v) { return {v[0], v[1], v[2]}; }

nlohmann::json vec_json(Vec3 v) { return {v.x, v.y, v.z}; }

/// "dir/name-KIND.ext" for --out "dir/name.ext".
std::string aov_path(const std::string& out, const char* kind) {
    const std::filesystem::path p(out);
    return (p.parent_path() / (p.stem().string() + "-" + kind + p.extension().string())).string();
}

/// The primary rays' traversal work per pixel (sample 0 of each pixel), as an image and as
/// means for the summary line.
/// The cost image (nodes, triangle tests, leaves per pixel as R, G, B) in `img`, and its
/// figures.
nlohmann::json cost_image(const Built& built, int kd_stack, const render::CameraData& cd, uint32_t seed,
                          const std::string& path, render::Image& img) {
    trav::RaySet set;
    const uint32_t npix = cd.width * cd.height;
    set.rays.resize(npix);
    for (uint32_t px = 0; px < npix; ++px) set.rays[px] = render::camera_ray(cd, px, 0, seed);
    std::vector<trav::Hit> hits;
    std::vector<trav::TraversalCounters> counters;
    trav::trace_cpu_counted(built.structure, kd_stack, set, hits, &counters);
    img = render::Image(cd.width, cd.height);
    double nodes = 0.0, tests = 0.0, leaves = 0.0;
    for (uint32_t px = 0; px < npix; ++px) {
        const trav::TraversalCounters& c = counters[px];
        img.pixels[px] = {float(c.nodes), float(c.tri_tests), float(c.leaves)};
        nodes += c.nodes;
        tests += c.tri_tests;
        leaves += c.leaves;
    }
    return {{"file", path},
            {"nodes_per_ray", nodes / npix},
            {"tri_tests_per_ray", tests / npix},
            {"leaves_per_ray", leaves / npix},
            {"counted_by", "the structure's shared traversal on the CPU, sample 0 of each pixel"}};
}

}  // namespace

void register_render(CLI::App& app, Globals& g) {
    auto o = std::make_shared<RenderOpts>();
    CLI::App* sub = app.add_subcommand("render", "render an image with the wavefront path tracer");
    sub->add_option("scene", o->scene, kSceneHelp)->required();
    sub->add_option("-o,--out", o->out, "image to write: .exr or .hdr (float), .png (sRGB, 8 bits), .pfm")->required();
    sub->add_option("--width", o->width, "image width in pixels")->check(CLI::Range(1, 16384))->capture_default_str();
    sub->add_option("--height", o->height, "image height in pixels")
        ->check(CLI::Range(1, 16384))
        ->capture_default_str();
    sub->add_option("--spp", o->rs.spp, "samples per pixel")->check(CLI::Range(1, 1 << 20))->capture_default_str();
    sub->add_option("--time-limit", o->rs.time_limit_s,
                    "seconds: stop after the sample pass that crosses it (at least one pass)")
        ->check(FiniteRange(0.0, 1e7));
    sub->add_option("--max-depth", o->rs.max_depth, "most segments per path (1: direct view of emitters only)")
        ->check(CLI::Range(1, 1024))
        ->capture_default_str();
    sub->add_option("--rr-depth", o->rs.rr_depth, "Russian roulette from this bounce on")
        ->check(CLI::Range(0, 1024))
        ->capture_default_str();
    sub->add_option("--seed", o->rs.seed, "seed of every random number")->capture_default_str();
    sub->add_option("--wave", o->rs.wave_samples,
                    "samples of every pixel traced together per pass (default: about 2M paths on the gpu, 1 on the "
                    "cpu); the image does not depend on it")
        ->check(CLI::Range(1, 1 << 20));
    o->trace.device = "embree";  // the reference integrator unless told
    o->trace.add_to(*sub, true);
    sub->get_option("--device")
        ->description(
            "embree (the reference integrator: the stages on every core, Embree 3 tracing every ray), cpu (the "
            "same stages, bvhlab's CPU traversal of the structure) or gpu (the wavefront path tracer on the GPU, "
            "tracing with --kernel)");
    o->build.add_to(*sub);
    sub->add_option("--sky", o->sky,
                    "constant sky radiance R G B (default: white 1 when the scene has no emitters, else black)")
        ->expected(3)
        ->check(FiniteRange(0.0, 1e30));
    auto* env = sub->add_option("--env", o->env,
                                "lat-long (equirectangular) environment map, linear radiance: .exr, .hdr, .pfm (+y up, "
                                "the image centre along -z)");
    sub->add_option("--env-scale", o->env_scale, "multiplies the environment map (needs --env)")
        ->check(FiniteRange(0.0, 1e30))
        ->capture_default_str()
        ->needs(env);
    env->excludes("--sky");
    o->camera.add_to(*sub);
    auto* aperture = sub->add_option("--aperture", o->aperture, "thin-lens aperture radius (0: pinhole)")
                         ->check(FiniteRange(0.0, 1e30));
    sub->add_option("--focus", o->focus, "focus distance of the thin lens (needs --aperture; default: eye to target)")
        ->check(FiniteRange(0.0, 1e30))
        ->needs(aperture);
    sub->add_option("--eye-end", o->eye_end, "eye position at the end of the camera's motion (motion blur)")
        ->expected(3)
        ->check(Finite());
    sub->add_option("--shutter", o->shutter, "shutter open and close times in [0, 1] of the motion")
        ->expected(2)
        ->check(FiniteRange(0.0, 1.0));
    sub->add_option("--missing-textures", o->missing,
                    "a material file, map_Kd texture or --env map that does not exist: error (default), or warn "
                    "and render without it (the default material, the material's Kd, the default sky), one warning "
                    "per file")
        ->check(CLI::IsMember({"error", "warn"}))
        ->capture_default_str();
    auto* denoise = sub->add_flag(
        "--denoise", o->denoise,
        "also write NAME-denoised.EXT: Intel Open Image Denoise's RT filter on the image with its albedo and normal "
        "AOVs (prefiltered), on OIDN's CUDA device when it has one, else the CPU (pip install pyoidn)");
    sub->add_option("--oidn", o->oidn,
                    "--denoise: libOpenImageDenoise.so.2 or its folder (default: $BVHLAB_OIDN, then an installed "
                    "pyoidn wheel, then the system's)")
        ->needs(denoise);
    sub->add_option("--denoise-device", o->denoise_device, "--denoise: auto, cpu or cuda")
        ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
        ->capture_default_str()
        ->needs(denoise);
    auto* preview = sub->add_option("--preview", o->preview,
                                    "rewrite this image with the running mean while the render runs (atomically; "
                                    "PNG, EXR, HDR or PFM), and with the final mean at the end");
    auto* serve = sub->add_option("--serve", o->serve,
                                  "serve a page on http://127.0.0.1:PORT/ that shows the image as it converges, with "
                                  "spp, Mrays/s and the time left (0: any free port; the URL is printed); it stops "
                                  "with the render")
                      ->check(CLI::Range(0, 65535));
    sub->add_option("--serve-bind", o->serve_bind,
                    "--serve: the address to listen on (default 127.0.0.1, this machine only; 0.0.0.0 opens it to "
                    "every interface)")
        ->needs(serve);
    auto* every =
        sub->add_option("--preview-every", o->preview_every, "--preview, --serve: seconds between updates (default 1)")
            ->check(FiniteRange(0.05, 3600.0));
    sub->add_flag("--aov", o->aov,
                  "also write the first hits' albedo and normal (for denoisers) beside --out, as NAME-albedo.EXT and "
                  "NAME-normal.EXT (normals in [-1, 1]: use .exr or .pfm)");
    sub->add_option(
        "--cost-image", o->cost_image,
        "write the primary rays' traversal cost per pixel (R: interior nodes visited, G: triangle tests, B: "
        "leaves), counted by the structure's shared CPU traversal");
    sub->add_flag("--pixel-centres", o->pixel_centres,
                  "every sample through its pixel's centre: no anti-aliasing (what --first-hit-cache implies)");
    sub->add_flag("--first-hit-cache", o->rs.first_hit_cache,
                  "trace the camera rays' hits once and reuse them in every later sample; implies --pixel-centres and "
                  "needs a pinhole, still camera");
    sub->add_flag("--sort-materials", o->rs.sort_by_material,
                  "gpu: sort each bounce's paths by the material they hit (CUB radix sort) before shading");
    sub->add_flag("--no-compaction", o->no_compaction,
                  "gpu: keep dead paths in the queues instead of compacting them (the compaction experiment's "
                  "baseline; the image is the same)");
    sub->add_option("--dump-rays", o->dump_rays,
                    "folder: write the first sample pass's extension and shadow rays of every bounce as ray files");
    sub->add_option("--strategy", o->strategy,
                    "how emitters are reached: mis (default), bsdf or light alone (for checking the estimators)")
        ->check(CLI::IsMember({"mis", "bsdf", "light"}))
        ->capture_default_str();
    sub->callback([o, &g, every, preview, serve] {
        if (every->count() && !preview->count() && !serve->count())
            throw Error("--preview-every applies to --preview or --serve");
        // --device embree is the reference integrator: Embree traces every ray.
        const bool reference = o->trace.device == "embree";
        if (o->trace.kernel == "all") throw Error("render traces with one kernel; name it with --kernel, not all");
        if (!reference) o->trace.validate(o->build);
        if (reference) {  // Embree traces every ray: no kernel runs, and a structure only for --cost-image
            const CLI::Option* f = o->cost_image.empty() ? given_structure_flag(o->build) : nullptr;
            for (const CLI::Option* g : {o->trace.kernel_flag, o->trace.block_flag, o->trace.fetch_flag})
                if (!f && g && g->count()) f = g;
            if (f)
                throw Error(f->get_name() +
                            " does not apply to render --device embree (the reference integrator: Embree traces "
                            "every ray; structure options apply to its --cost-image; --device cpu or gpu trace "
                            "with bvhlab's structures)");
        }
        std::vector<scene::NamedFile> outputs{{"--out", o->out}};
        if (o->aov) {
            outputs.push_back({"the albedo AOV", aov_path(o->out, "albedo")});
            outputs.push_back({"the normal AOV", aov_path(o->out, "normal")});
        }
        outputs.push_back({"--cost-image", o->cost_image});
        if (!o->preview.empty()) outputs.push_back({"--preview", o->preview});
        const size_t denoised_at = outputs.size();
        if (o->denoise) outputs.push_back({"the denoised image", aov_path(o->out, "denoised")});
        render::DenoiseOptions dopts;
        dopts.library = o->oidn;
        dopts.device = o->denoise_device;
        if (o->denoise) {
            std::string why;
            if (render::find_oidn(dopts, &why).empty()) throw Error("--denoise: " + why);
        }
        for (const scene::NamedFile& f : outputs) {
            if (f.path.empty()) continue;
            std::string why;
            if (!render::can_write_image(f.path, &why)) throw Error("cannot write " + f.path + ": " + why);
            const std::filesystem::path folder = std::filesystem::path(f.path).parent_path();
            if (!folder.empty() && !std::filesystem::is_directory(folder))
                throw Error("cannot write " + f.path + ": its folder " + folder.string() + " does not exist");
        }
        std::vector<scene::NamedFile> inputs{
            {"the scene", o->scene}, {"--env", o->env}, {"--structure", o->build.structure_file()}};
        scene::refuse_clashing_files(outputs, inputs);  // before the load, and again with its files
        o->rs.aovs = o->aov || o->denoise;              // the denoiser takes the albedo and normal AOVs
        // An instanced scene is traced two-level (unless --flatten) and shaded on its world-space
        // mesh, whose triangle ids are the two-level hits' scene-wide ids.
        Scene s = load_scene(o->scene, g);
        for (auto& f : s.input_files()) inputs.push_back(std::move(f));
        scene::refuse_clashing_files(outputs, inputs);
        for (const std::string& f : s.missing_material_files) {
            // A folder or a device is an error whatever --missing-textures says.
            if (const std::string problem = scene::regular_file_problem(f); problem != scene::kDoesNotExist)
                throw Error("cannot render " + o->scene + ": its material file " + f + ": " + problem);
            if (o->missing == "error")
                throw Error("cannot render " + o->scene + ": its material file " + f +
                            " does not exist (--missing-textures warn renders with the default material)");
            if (!g.quiet)
                std::fprintf(stderr,
                             "[bvhlab] warning: material file %s does not exist: its materials render as the "
                             "default grey\n",
                             f.c_str());
        }
        if (s.mesh.triangle_count() == 0) throw Error("cannot render " + o->scene + ": it has no triangles");

        const trav::Camera cam = o->camera.apply(s.camera);
        // --camera thin-lens needs an aperture; an aperture alone makes the camera a thin lens
        // (unless --camera says pinhole); the wide projections have no lens.
        const std::string& kind = o->camera.kind;
        const bool camera_given = o->camera.kind_flag->count() > 0;
        if (kind == "thin-lens" && !(o->aperture > 0.0f))
            throw Error("--camera thin-lens needs --aperture R (a radius above 0)");
        if (camera_given && kind == "pinhole" && o->aperture > 0.0f)
            throw Error("--aperture applies to --camera thin-lens (a pinhole has no lens)");
        if ((kind == "fisheye" || kind == "panorama") && (o->aperture > 0.0f || o->focus > 0.0f))
            throw Error(std::string(o->aperture > 0.0f ? "--aperture" : "--focus") +
                        " applies to --camera thin-lens, not " + kind);
        render::LensOptions lens;
        lens.aperture_radius = o->aperture;
        lens.focus_distance = o->focus;
        for (const std::string& p : {range_problem("--aperture", o->aperture, 0.0f, scene::kMaxCoordinate),
                                     range_problem("--focus", o->focus, 0.0f, scene::kMaxCoordinate)})
            if (!p.empty()) throw Error(p + ", the numeric domain bvhlab supports");
        if (o->eye_end.size() == 3) {
            lens.moving = true;
            lens.eye_end = vec3_of(o->eye_end);
            if (const std::string p = scene::vec_problem("--eye-end", lens.eye_end); !p.empty()) throw Error(p);
        }
        if (o->shutter.size() == 2) {
            if (!lens.moving) throw Error("--shutter applies to a moving camera: give --eye-end too");
            lens.shutter_open = o->shutter[0];
            lens.shutter_close = o->shutter[1];
        }
        lens.pixel_centres = o->pixel_centres || o->rs.first_hit_cache;
        o->rs.compaction = !o->no_compaction;
        const render::CameraData cd = render::make_camera(cam, o->width, o->height, lens);
        render::SkyOption sky;
        if (o->sky.size() == 3) {
            sky.given = true;
            sky.radiance = vec3_of(o->sky);
        }
        if (!o->env.empty()) {
            const std::string problem = scene::regular_file_problem(o->env);
            if (problem.empty()) {
                sky.env_file = o->env;
                sky.env_scale = o->env_scale;
            } else if (problem != scene::kDoesNotExist) {
                throw Error("cannot render with --env " + o->env + ": " + problem);
            } else if (o->missing == "error") {
                throw Error("cannot render with --env " + o->env +
                            ": no such file (--missing-textures warn renders with the default sky)");
            } else if (!g.quiet) {
                std::fprintf(stderr, "[bvhlab] warning: environment map %s does not exist: the default sky is used\n",
                             o->env.c_str());
            }
        }
        render::TextureOptions topts;
        topts.base_dir = std::filesystem::path(s.file).parent_path().string();
        topts.warn_missing = o->missing == "warn";
        std::vector<std::string> texture_warnings;
        topts.warnings = &texture_warnings;
        render::RenderScene rscene(s.mesh, sky, topts);
        if (!g.quiet) {
            for (const std::string& w : texture_warnings) std::fprintf(stderr, "[bvhlab] warning: %s\n", w.c_str());
            std::fprintf(stderr, "[bvhlab] lighting: %s\n", rscene.lighting().c_str());
        }
        o->rs.strategy = o->strategy == "mis"    ? render::Strategy::kMis
                         : o->strategy == "bsdf" ? render::Strategy::kBsdfOnly
                                                 : render::Strategy::kLightOnly;
        o->rs.dump_rays_dir = o->dump_rays;
        o->rs.writer = git_commit();

        std::unique_ptr<trav::EmbreeOracle> oracle;
        std::unique_ptr<trav::Tracer> tracer;
        Built built;
        if (reference) {
            oracle = make_oracle(s);  // Embree's own instances for an instanced scene
            tracer = trav::make_embree_tracer(*oracle, false);
        } else {
            o->build.epo = false;  // a build figure; the render does not need it
            built = build_scene(s, o->build, g);
            tracer = std::move(make_tracers(built, o->trace, o->build, nullptr).at(0));
        }
        render::RenderResult res;
        // The preview is written on another thread, so the render does not wait for the disk; an
        // update that comes while the last one is still being written is skipped.
        // --serve encodes its PNG on that thread too.
        // (The server outlives the writer, which may still be updating it.)
        size_t previews = 0;
        std::unique_ptr<render::PreviewServer> server;
        std::future<void> writing;
        if (o->serve >= 0) {
            render::PreviewServerOptions sopts;
            sopts.bind = o->serve_bind;
            sopts.port = o->serve;
            sopts.title = s.name + ": " + std::to_string(o->width) + "x" + std::to_string(o->height) + ", " +
                          std::to_string(o->rs.spp) + " spp on the " + (o->trace.device == "gpu" ? "gpu" : "cpu") +
                          " -> " + o->out;
            server = std::make_unique<render::PreviewServer>(sopts);
            std::fprintf(stderr, "[bvhlab] serving the render's progress at %s\n", server->url().c_str());
        }
        if (!o->preview.empty() || server) {
            o->rs.preview_every_s = o->preview_every;
            o->rs.preview = [&](const render::Image& mean, uint32_t spp) {
                if (writing.valid() && writing.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
                if (writing.valid()) writing.get();  // a failed write ends the render with its error
                writing = std::async(std::launch::async, [&o, &server, img = mean, spp] {
                    if (!o->preview.empty()) render::write_images({{&img, o->preview}});
                    // The last samples' image goes to the page once, as the final one (finish):
                    // a preview of it as well would show the page two images of the same spp.
                    if (server && spp < o->rs.spp) server->update_image(img, spp);
                });
                ++previews;
            };
        }
        {
            Stage st(g, "rendering " + std::to_string(o->width) + "x" + std::to_string(o->height) + " at " +
                            std::to_string(o->rs.spp) + " spp on the " + (o->trace.device == "gpu" ? "gpu" : "cpu") +
                            " (" + tracer->name() + ")");
            auto progress = [&](uint32_t done, uint32_t total, const render::RenderResult& r) {
                const double sec = st.seconds();
                char detail[96];
                std::snprintf(detail, sizeof detail, "%u of %u spp, %.1f spp/s, %.1f Mrays/s", done, total,
                              double(done) / sec, double(r.rays()) / (sec * 1e6));
                st.progress(done, total, detail);
                if (server) server->update_progress(done, total, double(r.rays()) / (sec * 1e6), sec);
            };
            if (o->trace.device == "gpu") {
                trav::GpuTraceOptions gopts;
                if (tracer->short_stack()) gopts.kd_stack = tracer->short_stack();
                gopts.block_size = o->trace.block_size;
                gopts.fetch_threshold = o->trace.fetch_threshold;
                res = render::render_gpu(rscene, cd, o->rs, *built.device(), trav::find_kernel(tracer->name()), gopts,
                                         progress);
            } else {
                res = render::render_host(rscene, cd, o->rs, *tracer, *tracer, progress);
            }
        }
        // Every image is written, or none is (render::write_images).
        std::vector<std::pair<const render::Image*, std::string>> images{{&res.mean, o->out}};
        if (o->aov) {
            images.push_back({&res.albedo, outputs[1].path});
            images.push_back({&res.normal, outputs[2].path});
        }
        render::Image cost_img;
        nlohmann::json cost;
        if (!o->cost_image.empty()) {
            if (reference) {
                o->build.epo = false;
                built = build_scene(s, o->build, g);
            }
            cost = cost_image(built, o->build.kd_stack, cd, o->rs.seed, o->cost_image, cost_img);
            images.push_back({&cost_img, o->cost_image});
        }
        render::DenoiseResult dn;
        if (o->denoise) {
            Stage st(g, "denoising with Open Image Denoise");
            dn = render::denoise(res.mean, res.albedo, res.normal, dopts);
            images.push_back({&dn.image, outputs[denoised_at].path});
        }
        if (writing.valid()) writing.get();
        o->rs.preview = nullptr;
        if (server) server->finish(res.mean, res.spp);
        if (!o->preview.empty()) images.push_back({&res.mean, o->preview});  // the preview ends as the image
        render::write_images(images);

        nlohmann::json bounces = nlohmann::json::array();
        for (const render::BounceStats& b : res.bounces)
            bounces.push_back({{"extension_rays", b.extension_rays},
                               {"shadow_rays", b.shadow_rays},
                               {"queue_entries", b.queue_entries}});
        nlohmann::json j = base_record("render", s);
        if (reference) {
            j["device"] = "embree";
            j["kernel"] = tracer->name();
        } else {
            j.update(tracer_fields(built, *tracer));
        }
        j["width"] = o->width;
        j["height"] = o->height;
        j["spp"] = res.spp;
        j["spp_asked"] = o->rs.spp;
        j["max_depth"] = o->rs.max_depth;
        j["rr_depth"] = o->rs.rr_depth;
        j["seed"] = o->rs.seed;
        j["wave_samples"] = res.wave_samples;
        j["strategy"] = o->strategy;
        j["pixel_centres"] = lens.pixel_centres;
        j["camera"] = kind == "pinhole" && o->aperture > 0.0f ? std::string("thin-lens") : kind;
        if (kind == "fisheye") j["fisheye_fov_deg"] = o->camera.fisheye_fov;
        j["first_hit_cache"] = o->rs.first_hit_cache;
        j["cached_hits"] = res.cached_hits;
        j["sort_materials"] = o->rs.sort_by_material;
        j["compaction"] = o->rs.compaction;
        j["lighting"] = rscene.lighting();
        j["sky"] = vec_json(rscene.sky());
        if (rscene.env().width > 0)
            j["env"] = {{"file", o->env},
                        {"width", rscene.env().width},
                        {"height", rscene.env().height},
                        {"scale", o->env_scale}};
        j["emissive_triangles"] = rscene.light_tris().size();
        j["textures"] = rscene.textures().size();
        j["out"] = o->out;
        j["rays"] = res.rays();
        j["ms"] = {{"total", res.ms_total},           {"generate", res.ms_generate}, {"extend", res.ms_extend},
                   {"shade", res.ms_shade},           {"shadow", res.ms_shadow},     {"compact", res.ms_compact},
                   {"accumulate", res.ms_accumulate}, {"setup", res.ms_setup}};
        j["mrays_per_s"] = res.ms_total > 0.0 ? double(res.rays()) / (res.ms_total * 1e3) : 0.0;
        j["bounces"] = bounces;
        if (o->aov) j["aov"] = {outputs[1].path, outputs[2].path};
        if (o->denoise)
            j["denoise"] = {
                {"out", outputs[denoised_at].path}, {"device", dn.device}, {"library", dn.library}, {"ms", dn.ms}};
        if (!cost.is_null()) j["primary_cost"] = cost;
        if (!o->preview.empty())
            j["preview"] = {{"out", o->preview}, {"every_s", o->preview_every}, {"updates", previews}};
        if (server)
            j["serve"] = {{"url", server->url()},
                          {"every_s", o->preview_every},
                          {"updates", server->image_updates()},
                          {"requests", server->page_requests()}};
        if (g.json)
            emit(j);
        else {
            std::printf("%s: %ux%u, %u spp, %llu rays in %.2f s (%.1f Mrays/s), written to %s\n", s.name.c_str(),
                        o->width, o->height, res.spp, (unsigned long long)res.rays(), res.ms_total / 1e3,
                        j["mrays_per_s"].get<double>(), o->out.c_str());
            if (o->denoise)
                std::printf("denoised by Open Image Denoise on its %s device in %.1f ms, written to %s\n",
                            dn.device.c_str(), dn.ms, outputs[denoised_at].path.c_str());
        }
    });
}

}  // namespace bvhlab::cli
