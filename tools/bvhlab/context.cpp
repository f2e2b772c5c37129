// SPDX-License-Identifier: MIT
#include "tools/bvhlab/context.h"

#include <tbb/info.h>
#include <unistd.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "renderer/render_scene.h"
#include "scene/domain.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "scene/io/scene_cache.h"
#include "scene/io/scene_file.h"
#include "scene/scene.h"
#include "traversal/rays/scene_catalogue.h"

namespace fs = std::filesystem;

namespace bvhlab::cli {

Stage::Stage(const Globals& g, std::string what)
    : g_(g), what_(std::move(what)), t0_(std::chrono::steady_clock::now()), exceptions_(std::uncaught_exceptions()) {
    if (!g_.quiet) std::fprintf(stderr, "[bvhlab] %s ...\n", what_.c_str());
}

namespace {
// The innermost Stage that an exception ended. A fixed buffer: the destructor that fills it may
// run while unwinding from an allocation failure, where allocating again could terminate.
char g_failed_stage[160] = {};
}  // namespace

std::string failed_stage_clause() { return g_failed_stage[0] ? std::string(" while ") + g_failed_stage : ""; }

Stage::~Stage() {
    if (std::uncaught_exceptions() > exceptions_) {  // failed: the error line follows
        if (!g_failed_stage[0]) std::snprintf(g_failed_stage, sizeof g_failed_stage, "%s", what_.c_str());
        return;
    }
    if (!g_.quiet) std::fprintf(stderr, "[bvhlab] %s: done (%.2f s)\n", what_.c_str(), seconds());
}

CLI::Validator FiniteRange(double lo, double hi) {
    char desc[64];
    std::snprintf(desc, sizeof desc, "FLOAT in [%g - %g]", lo, hi);
    return CLI::Validator(
        [lo, hi](std::string& text) -> std::string {
            double v = 0.0;
            size_t used = 0;
            try {
                v = std::stod(text, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used == 0 || used != text.size()) return "'" + text + "' is not a number";
            if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
            if (v < lo || v > hi) {
                char b[96];
                std::snprintf(b, sizeof b, "%s is not in [%g, %g]", text.c_str(), lo, hi);
                return b;
            }
            return "";
        },
        desc);
}

CLI::Validator Finite() { return FiniteRange(-3.0e38, 3.0e38); }

CLI::Validator UInt64() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
                return "'" + text + "' is not a non-negative integer";
            try {
                std::stoull(text);
            } catch (const std::out_of_range&) {
                return text + " is larger than 2^64 - 1";
            }
            return "";
        },
        "UINT64");
}

trav::RaySet read_rays_for(const std::string& path, const char* command) {
    trav::RaySet set = trav::read_ray_file(path);
    if (set.rays.empty()) throw Error("ray file '" + path + "' has no rays: nothing to " + command);
    return set;
}

double Stage::seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }

void Stage::progress_bytes(size_t done, size_t total) const {
    const double t = seconds();
    if (g_.quiet || t < 1.0 || total == 0 || !isatty(fileno(stderr))) return;
    const double f = double(done) / double(total);
    char left[48] = "";
    if (done > 0 && done < total) std::snprintf(left, sizeof left, ", about %.1f s left", t * (1.0 - f) / f);
    std::fprintf(stderr, "\r[bvhlab] %s: %3d%% (%.0f of %.0f MB%s)   %s", what_.c_str(), int(100.0 * f),
                 double(done) / 1e6, double(total) / 1e6, left, done >= total ? "\n" : "");
}

void Stage::report(uint64_t done, uint64_t total) {
    const double t = seconds();
    if (g_.quiet || t < 1.0 || total == 0 || !isatty(fileno(stderr))) return;
    const double f = double(done) / double(total);
    char left[48] = "";
    if (done > 0 && done < total) std::snprintf(left, sizeof left, " (about %.1f s left)", t * (1.0 - f) / f);
    std::fprintf(stderr, "\r[bvhlab] %s: %3d%%%s   %s", what_.c_str(), int(100.0 * f), left, done >= total ? "\n" : "");
}

void Stage::progress(size_t done, size_t total, const std::string& detail) const {
    if (g_.quiet || !isatty(fileno(stderr))) return;
    std::fprintf(stderr, "\r[bvhlab] %s: %3d%%%s%s%s   %s", what_.c_str(), int(100.0 * double(done) / double(total)),
                 detail.empty() ? "" : " (", detail.c_str(), detail.empty() ? "" : ")", done >= total ? "\n" : "");
}

namespace {

/// A catalogue: scenes.json of the shared benchmark scenes or of data/.
struct Catalogue {
    fs::path dir;
    std::vector<trav::CatalogueEntry> entries;
};

}  // namespace

std::unique_ptr<trav::EmbreeOracle> make_oracle(const Scene& s) {
    return s.placed ? std::make_unique<trav::EmbreeOracle>(*s.placed) : std::make_unique<trav::EmbreeOracle>(s.mesh);
}

std::string data_dir() {
    if (const char* env = std::getenv("BVHLAB_DATA"); env && *env) return env;
    std::error_code ec;
    if (fs::exists(BVHLAB_DATA_DIR, ec)) return BVHLAB_DATA_DIR;
    // An installed tree keeps data/ in share/bvhlab/data next to bin/.
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return (exe.parent_path().parent_path() / "share" / "bvhlab" / "data").string();
}

namespace {

std::vector<Catalogue> catalogues() {
    std::vector<Catalogue> out;
    std::vector<fs::path> dirs;
    if (const char* env = std::getenv("BVHLAB_SCENES"); env && *env) dirs.emplace_back(env);
    dirs.emplace_back(data_dir());
    for (const auto& d : dirs) out.push_back({d, trav::read_catalogue(d.string())});
    return out;
}

void apply_entry(Scene& s, const trav::CatalogueEntry& e) {
    if (e.camera) {
        s.camera = *e.camera;
        s.camera_from_catalogue = true;
    }
    if (e.ao_length > 0.0f) s.ao_length = e.ao_length;
}

}  // namespace

std::vector<std::string> catalogue_scene_names() {
    std::vector<std::string> names;
    const char* env = std::getenv("BVHLAB_SCENES");
    if (!env || !*env) return names;
    // A set variable that finds no scenes is an error: a typo must not make a suite pass on
    // the Cornell box alone.
    const std::string dir = env;
    if (!fs::is_directory(dir)) throw Error("BVHLAB_SCENES='" + dir + "' is not a folder");
    if (!fs::exists(fs::path(dir) / "scenes.json")) throw Error("BVHLAB_SCENES='" + dir + "' has no scenes.json");
    for (const auto& e : trav::read_catalogue(dir)) names.push_back(e.name);
    if (names.empty())
        throw Error("'" + dir + "/scenes.json' lists no scenes (expected {\"scenes\": {NAME: {\"file\": ...}}})");
    return names;
}

std::vector<scene::NamedFile> Scene::input_files() const {
    if (file.empty()) return {};  // generated: no files
    std::vector<scene::NamedFile> files{{"the scene", file}};
    const char* kind = scene::is_obj_path(file) ? "material file" : "a file the scene reads";
    for (const std::string& m : material_files) files.push_back({kind, m});
    const std::string dir = std::filesystem::path(file).parent_path().string();
    for (const scene::Material& m : mesh.materials)
        for (const auto& [role, name] : {std::pair<const char*, const std::string*>{"texture", &m.diffuse_texture},
                                         {"normal map", &m.normal_texture},
                                         {"bump map", &m.bump_texture}})
            if (!name->empty())
                files.push_back({std::string("the ") + role + " of material '" + m.name + "'",
                                 render::resolve_texture_path(dir, *name)});
    return files;
}

namespace {

std::vector<std::string> split_spec(const std::string& spec) {
    std::vector<std::string> parts;
    std::stringstream ss(spec);
    for (std::string p; std::getline(ss, p, ':');) parts.push_back(p);
    return parts;
}

/// A whole number of a gen: spec, or a one-line error naming it.
uint64_t spec_number(const std::string& spec, const std::string& text, const char* what) {
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 19)
        throw Error("generated-scene spec '" + spec + "': " + what + " '" + text + "' is not a whole number");
    return std::stoull(text);
}

/// The count (parts[at], in 1..max) and the optional seed after it (default 1) of a gen: spec.
std::pair<uint64_t, uint64_t> count_and_seed(const std::string& spec, const std::vector<std::string>& parts, size_t at,
                                             const char* what, uint64_t max, const char* max_text) {
    const uint64_t n = spec_number(spec, parts[at], what);
    const uint64_t seed = parts.size() == at + 2 ? spec_number(spec, parts[at + 1], "the seed") : 1;
    if (n < 1 || n > max)
        throw Error("generated-scene spec '" + spec + "': " + what + " must be 1.." + max_text + ", not " + parts[at]);
    return {n, seed};
}

}  // namespace

Scene load_scene(const std::string& spec, const Globals& g) {
    Scene s;
    s.source = spec;
    const trav::CatalogueEntry* entry = nullptr;
    fs::path file;
    std::vector<Catalogue> cats = catalogues();
    scene::InstancedScene placed;
    if (spec.rfind("gen:instances:", 0) == 0) {
        // gen:instances:SCENE:N[:SEED]
        const std::vector<std::string> parts = split_spec(spec);
        if (parts.size() < 4 || parts.size() > 5 || parts[2].empty())
            throw Error("bad generated-scene spec '" + spec +
                        "' (expected gen:instances:SCENE:N[:SEED], SCENE a scene name or file without ':')");
        const auto [n, seed] = count_and_seed(spec, parts, 3, "the instance count", 1u << 24, "2^24");
        Scene base = load_scene(parts[2], g);
        s.file = base.file;
        s.material_files = base.material_files;
        s.missing_material_files = base.missing_material_files;
        s.name = spec;
        Stage st(g, "placing " + std::to_string(n) + " instances of " + base.name);
        placed = scene::make_instances(std::move(base.mesh), uint32_t(n), seed);
        s.load_ms = base.load_ms + 1000.0 * st.seconds();
    } else if (spec.rfind("gen:", 0) == 0) {
        // gen:KIND:TRIANGLES[:SEED]
        const std::vector<std::string> parts = split_spec(spec);
        if (parts.size() < 3 || parts.size() > 4)
            throw Error("bad generated-scene spec '" + spec +
                        "' (expected gen:soup|structured:TRIANGLES[:SEED] or gen:instances:SCENE:N[:SEED])");
        const auto [n, seed] = count_and_seed(spec, parts, 2, "the triangle count", 1ull << 30, "2^30");
        Stage st(g, "generating " + spec);
        placed = scene::single_instance(scene::make_procedural(scene::parse_procedural_kind(parts[1]), n, seed));
        s.name = spec;
        s.load_ms = 1000.0 * st.seconds();
    } else {
        for (const auto& c : cats) {
            for (const auto& e : c.entries)
                if (e.name == spec) {
                    entry = &e;
                    file = e.file;
                    s.name = spec;
                    break;
                }
            if (entry) break;
        }
        if (!entry) {
            file = spec;
            if (!fs::exists(file)) {
                std::vector<std::string> names;
                for (const auto& c : cats)
                    for (const auto& e : c.entries) names.push_back(e.name);
                throw Error("no scene '" + spec + "': not a file, and not a name in " +
                            (std::getenv("BVHLAB_SCENES") ? "$BVHLAB_SCENES/scenes.json or " : "") +
                            "data/scenes.json" + did_you_mean(spec, names));
            }
            s.name = file.stem().string();
            // A path inside a catalogue's folder picks up that entry's camera.
            std::error_code ec;
            for (const auto& c : cats)
                for (const auto& e : c.entries)
                    if (fs::equivalent(e.file, file, ec)) {
                        entry = &e;
                        s.name = e.name;
                    }
        }
        s.source = s.file = file.string();  // what a catalogue name resolved to
        const std::string cache_dir = g.no_scene_cache ? "" : scene::default_scene_cache_dir();
        Stage st(g, "loading " + file.string());
        scene::SceneFileLoad load =
            scene::load_scene_file(file.string(), cache_dir, git_commit(),
                                   [&st](size_t done, size_t total) { st.progress_bytes(done, total); });
        placed = std::move(load.scene);
        s.hash = load.scene_hash;
        s.load_ms = 1000.0 * st.seconds();
        s.scene_cache = cache_dir.empty() ? "off" : load.from_cache ? "hit" : "miss";
        s.material_files = load.dependencies;
        s.missing_material_files = load.missing_dependencies;
        if (!g.quiet) {
            if (load.from_cache)
                std::fprintf(stderr, "[bvhlab] served by the scene cache (%s)\n", load.cache_file.c_str());
            for (const auto& w : load.warnings) std::fprintf(stderr, "[bvhlab] warning: %s\n", w.c_str());
            if (!load.cache_warning.empty()) std::fprintf(stderr, "[bvhlab] warning: %s\n", load.cache_warning.c_str());
        }
    }
    s.instances = placed.instances.size();
    s.meshes = scene::placed_mesh_count(placed);
    const bool one_mesh = placed.instances.size() == 1 && placed.instances[0].transform.is_identity();
    std::optional<scene::SceneCamera> file_camera = placed.camera;
    if (placed.is_instanced() && !g.flatten) {
        // Two-level: the world-space triangles are still made, for rays and for checking hits.
        Stage st(g, "placing " + std::to_string(placed.triangle_count()) + " triangles of " +
                        std::to_string(s.instances) + " instances in world space");
        s.mesh = scene::flatten(placed, /*keep_all=*/true);
        s.first_ids = scene::instance_first_ids(placed);
        s.placed = std::make_shared<const scene::InstancedScene>(std::move(placed));
    } else {
        std::optional<Stage> st;
        if (!one_mesh) st.emplace(g, "flattening " + std::to_string(s.instances) + " instances");
        s.mesh = scene::single_mesh(std::move(placed), true, "scene '" + spec + "'");
        s.first_ids = {0, s.mesh.triangle_count()};
    }
    if (!one_mesh) s.hash.clear();  // the file's hash is not the flattened mesh's
    if (file_camera) {
        const scene::SceneCamera& c = *file_camera;
        s.camera = {
            {c.eye.x, c.eye.y, c.eye.z}, {c.target.x, c.target.y, c.target.z}, {c.up.x, c.up.y, c.up.z}, c.fov_y_deg};
        s.camera_from_catalogue = true;  // the file's own camera (a catalogue entry's wins)
    }
    // Outside the numeric domain Embree aborts or misses hits, and float areas overflow or
    // underflow (scene/domain.h).
    if (const std::string p = scene::domain_problem(s.mesh); !p.empty()) throw Error("scene '" + spec + "': " + p);
    if (entry) apply_entry(s, *entry);
    if (!s.camera_from_catalogue) s.camera = trav::framing_camera(s.mesh);
    if (s.ao_length <= 0.0f) s.ao_length = 0.05f * s.mesh.diagonal();
    if (s.hash.empty()) s.hash = scene::scene_hash(s.mesh);  // the cache gives it with the mesh
    if (!g.quiet) {
        std::fprintf(stderr, "[bvhlab] %s: %zu triangles, dropped %llu (%llu non-finite, %llu zero-area)\n",
                     s.name.c_str(), s.mesh.triangle_count(), (unsigned long long)s.mesh.dropped.total(),
                     (unsigned long long)s.mesh.dropped.non_finite, (unsigned long long)s.mesh.dropped.zero_area);
    }
    return s;
}

void BuildOptions::add_to(CLI::App& app) {
    builder_flag = app.add_option("--builder", builder,
                                  "BVH builder: binned (binned SAH), sweep (full-sweep SAH) or sbvh (spatial splits) "
                                  "on the CPU; lbvh (Karras 2012), ploc (Meister & Bittner 2018), hploc (H-PLOC, "
                                  "Benthin et al. 2024) or gpu-binned (binned SAH, top down) on the GPU")
                       ->check(CLI::IsMember({"binned", "sweep", "sbvh", "lbvh", "ploc", "hploc", "gpu-binned"}))
                       ->capture_default_str();
    build_device_flag =
        app.add_option(
               "--build-device", build_device,
               "where the builder runs: cpu (binned, sweep, sbvh), gpu (lbvh, ploc, hploc, gpu-binned), or auto "
               "(the builder's own)")
            ->check(CLI::IsMember({"auto", "cpu", "gpu"}))
            ->capture_default_str();
    auto* st = structure_flag = app.add_option(
        "--structure", structure,
        "what to build: binned (or bvh), sweep, sbvh, lbvh, ploc, hploc, gpu-binned or kdtree; or a structure file "
        "from `bvhlab "
        "build --out` to load instead of building (verify also takes all: every structure and its tracers). "
        "--builder NAME is the same for the BVH builders");
    st->excludes(builder_flag);
    st->check(CLI::Validator(
        [this](std::string& v) -> std::string {
            return v == "all" && !accepts_all ? "all applies to `bvhlab verify` only" : std::string();
        },
        "", "not all"));
    config_flags = {
        app.add_option("--bins", opts.num_bins, "bins per axis (binned builder, SBVH object splits)")
            ->check(CLI::Range(2, 256))
            ->capture_default_str(),
        app.add_option("--max-leaf", opts.config.max_leaf_size,
                       "largest leaf (triangles; at most 16 for the bvh2 layout and the GPU builders)")
            ->check(CLI::Range(1, 64))
            ->capture_default_str(),
        app.add_option("--min-leaf", opts.config.min_leaf_size, "nodes this small always become leaves")
            ->check(CLI::Range(1, 64))
            ->capture_default_str(),
        app.add_option("--alpha", opts.sbvh_alpha,
                       "SBVH: try spatial splits where child overlap exceeds alpha x root area")
            ->check(FiniteRange(0.0, 1.0))
            ->capture_default_str(),
        app.add_option("--budget", opts.sbvh_budget, "SBVH: at most this many references per triangle in all")
            ->check(FiniteRange(1.0, 16.0))
            ->capture_default_str(),
        app.add_option("--spatial-bins", opts.sbvh_spatial_bins, "SBVH: bins per axis for spatial splits")
            ->check(CLI::Range(2, 256))
            ->capture_default_str(),
        app.add_option(
               "--reinsert", opts.reinsertion_passes,
               "at most this many passes of SAH-lowering subtree reinsertion after the BVH build (CPU builders: "
               "it stops after a pass that gains under 1%; GPU builders: parallel reinsertion on the device, "
               "every pass run); -1 = the builder's default (3 for sbvh, 0 for the others)")
            ->check(CLI::Range(-1, 16))
            ->capture_default_str(),
        app.add_option("--morton-bits", opts.morton_bits, "lbvh, ploc, hploc: bits of the Morton codes (30 or 60)")
            ->check(CLI::IsMember({30, 60}))
            ->capture_default_str(),
        app.add_option("--radius", opts.ploc_radius,
                       "ploc, hploc: clusters to each side that a cluster searches for its nearest neighbour")
            ->check(CLI::Range(1, 16))
            ->capture_default_str(),
        app.add_option("--clusters", opts.cluster_alpha,
                       "gpu-binned: 0 bins every triangle (the CPU binned tree); 1 to 16 bins clusters of nearly "
                       "coincident triangles, Morton-order neighbours merged while their box grows at most this "
                       "many times in area, at most 16 a cluster (1.3: binned-quality trees, faster on hair and fur)")
            ->check(FiniteRange(0.0, 16.0))
            ->capture_default_str(),
    };
    // --structure NAME picks the builder; a path is checked when the command runs.
    st->each([this](const std::string& v) {
        if (v == "bvh" || v == "binned")
            builder = "binned";
        else if (v == "sweep" || v == "sbvh" || v == "lbvh" || v == "ploc" || v == "hploc" || v == "gpu-binned")
            builder = v;
    });
    layout_flag =
        app.add_option("--layout", layout,
                       "BVH traversal layout: bvh2 (binary, Aila-Laine nodes) or cwbvh (collapsed to a compressed "
                       "8-wide BVH, Ylitie et al. 2017); default: bvh2, or the layout that --kernel traces")
            ->check(CLI::IsMember({"bvh2", "cwbvh"}))
            ->capture_default_str();
    collapse_flag =
        app.add_option("--collapse", collapse,
                       "--layout cwbvh: sah (the least wide-SAH collapse, by dynamic programming) or greedy "
                       "(open the largest child until 8)")
            ->check(CLI::IsMember({"sah", "greedy"}))
            ->capture_default_str();
    cw_tris_flag = app.add_option("--cw-tris", cw_tris,
                                  "--layout cwbvh: leaf triangles as woop (48-byte Woop maps) or vertices (36-byte "
                                  "vertex and edges, Moller-Trumbore: 0.75x the triangle bytes)")
                       ->check(CLI::IsMember({"woop", "vertices"}))
                       ->capture_default_str();
    kd_stack_flag = app.add_option("--kd-stack", kd_stack,
                                   "kd-tree traversal stack: 64 = full stack, 1..8 = short stack with restart")
                        ->check(CLI::IsMember({1, 2, 3, 4, 5, 6, 7, 8, 64}))
                        ->capture_default_str();
    kd_flags = {
        app.add_option("--kd-ct", kd.traversal_cost, "kd-tree SAH: cost of a traversal step (Wald-Havran K_T)")
            ->check(FiniteRange(0.001, 1e6))
            ->capture_default_str(),
        app.add_option("--kd-ci", kd.intersection_cost, "kd-tree SAH: cost of a triangle test (K_I)")
            ->check(FiniteRange(0.001, 1e6))
            ->capture_default_str(),
        app.add_option("--kd-bonus", kd.empty_bonus, "kd-tree SAH: cost reduction for a split with an empty side")
            ->check(FiniteRange(0.0, 0.99))
            ->capture_default_str(),
        app.add_option("--kd-max-depth", kd.max_depth, "kd-tree depth limit; -1 = 8 + 1.3 log2(N), at most 64")
            ->check(CLI::Range(-1, 64))
            ->capture_default_str(),
    };
}

std::string BuildOptions::structure_file() const {
    if (structure.empty() || structure == "bvh" || structure == "binned" || structure == "sweep" ||
        structure == "sbvh" || structure == "lbvh" || structure == "ploc" || structure == "hploc" ||
        structure == "gpu-binned" || structure == "kdtree" || structure == "all")
        return {};
    return structure;
}

trav::StructureSpec BuildOptions::spec() const {
    trav::StructureSpec s;
    s.builder = is_kdtree() ? "kdtree" : builder;
    s.layout = layout;
    s.options = opts;
    s.kd = kd;
    s.collapse = collapse;
    s.cw_tris = cw_tris;
    s.kd_stack = kd_stack;
    s.epo = epo;
    s.build_device = build_device;
    return s;
}

void BuildOptions::check_applicable() const {
    if (collapse_flag->count() && !is_cwbvh()) throw Error("--collapse applies to --layout cwbvh");
    if (cw_tris_flag->count() && !is_cwbvh()) throw Error("--cw-tris applies to --layout cwbvh");
    if (!structure_file().empty()) {
        std::error_code ec;
        if (!fs::exists(structure_file(), ec))
            throw Error(
                "--structure '" + structure_file() +
                "' is neither a structure (binned, sweep, sbvh, lbvh, ploc, hploc, gpu-binned, kdtree) nor an existing "
                "file" +
                did_you_mean(structure_file(), {"binned", "bvh", "sweep", "sbvh", "lbvh", "ploc", "hploc", "gpu-binned",
                                                "kdtree", "all"}));
        if (build_device_flag->count())
            throw Error("--build-device applies when a structure is built, not to structure file '" + structure_file() +
                        "'");
        return;
    }
    // config_flags: --bins, --max-leaf, --min-leaf, --alpha, --budget, --spatial-bins, --reinsert, --morton-bits,
    // --radius, --clusters.
    auto refuse = [](const CLI::Option* f, const std::string& why) {
        if (f->count()) throw Error(f->get_name() + " " + why);
    };
    if (is_kdtree()) {
        for (const CLI::Option* f : config_flags) refuse(f, "applies to BVH builders, not --structure kdtree");
        refuse(layout_flag, "applies to BVHs; a kd-tree has its own layout");
        if (build_device == "gpu")
            throw Error("--build-device gpu applies to the GPU builders (lbvh, ploc, hploc, gpu-binned), not kdtree");
        return;
    }
    for (const CLI::Option* f : kd_flags) refuse(f, "applies to --structure kdtree, not a BVH");
    if (opts.config.min_leaf_size > opts.config.max_leaf_size)
        throw Error("--min-leaf " + std::to_string(opts.config.min_leaf_size) + " is larger than --max-leaf " +
                    std::to_string(opts.config.max_leaf_size));
    refuse(kd_stack_flag, "applies to kd-trees, not a BVH");
    const accel::BuilderKind k = kind();
    if (k != accel::BuilderKind::kSbvh)
        for (size_t i : {3, 4, 5}) refuse(config_flags[i], "applies to --builder sbvh, not " + builder);
    if (k == accel::BuilderKind::kSweep)
        refuse(config_flags[0], "does not apply to the sweep builder (it has no bins)");
    const bool gpu = accel::runs_on_gpu(k);
    if (gpu) {
        refuse(config_flags[0],
               "does not apply to the GPU builders (gpu-binned's are 32 a side, the others have none)");
        if (build_device == "cpu")
            throw Error("--build-device cpu does not apply: builder " + builder + " runs on the GPU");
    } else {
        if (build_device == "gpu")
            throw Error("--build-device gpu applies to the GPU builders (lbvh, ploc, hploc, gpu-binned), not " +
                        builder);
    }
    if (!accel::uses_morton(k)) refuse(config_flags[7], "applies to --builder lbvh, ploc or hploc, not " + builder);
    if (!accel::uses_radius(k)) refuse(config_flags[8], "applies to --builder ploc or hploc, not " + builder);
    if (!accel::uses_clusters(k)) refuse(config_flags[9], "applies to --builder gpu-binned, not " + builder);
    if (opts.cluster_alpha > 0.0f && opts.cluster_alpha < 1.0f) {
        std::ostringstream s;
        s << "--clusters " << opts.cluster_alpha << " is neither 0 (off) nor in [1, 16]";
        throw Error(s.str());
    }
}

void RayOptions::add_to(CLI::App& app) {
    flags.push_back(app.add_option("--width", cfg.primary.width, "image width in pixels")
                        ->check(CLI::Range(1, 65536))
                        ->capture_default_str());
    flags.push_back(app.add_option("--height", cfg.primary.height, "image height in pixels")
                        ->check(CLI::Range(1, 65536))
                        ->capture_default_str());
    flags.push_back(
        app.add_option("--spp", cfg.primary.samples, "samples per pixel, a perfect square (regular sub-grid)")
            ->check(CLI::Range(1, 1024))
            ->check(CLI::Validator(
                [](std::string& text) -> std::string {
                    const long n = std::strtol(text.c_str(), nullptr, 10);
                    long k = 1;
                    while (k * k < n) ++k;
                    return k * k == n ? ""
                                      : "--spp " + text +
                                            " is not a perfect square (1, 4, 9, 16, ...): the samples form a regular "
                                            "sub-grid";
                },
                "a perfect square"))
            ->capture_default_str());
    flags.push_back(app.add_option("--tile", cfg.primary.tile, "order primary rays in TxT pixel tiles (0 = row-major)")
                        ->check(CLI::Range(0, 4096))
                        ->capture_default_str());
    ao_rays_flag = app.add_option("--ao-rays", cfg.ao_rays, "AO rays per primary hit")
                       ->check(CLI::Range(1, 1024))
                       ->capture_default_str();
    diffuse_rays_flag = app.add_option("--diffuse-rays", cfg.diffuse_rays, "diffuse rays per primary hit")
                            ->check(CLI::Range(1, 1024))
                            ->capture_default_str();
    flags.push_back(ao_rays_flag);
    flags.push_back(diffuse_rays_flag);
    flags.push_back(
        app.add_option("--seed", cfg.seed, "seed of every random choice")->check(UInt64())->capture_default_str());
    camera.add_to(app);
    flags.insert(flags.end(), camera.flags.begin(), camera.flags.end());
}

void RayOptions::excluded_by(CLI::Option* rays_file) const {
    for (CLI::Option* f : flags) rays_file->excludes(f);
}

void RayOptions::check_types(const std::vector<trav::RayType>& types, const std::string& list) const {
    const auto has = [&](trav::RayType t) { return std::find(types.begin(), types.end(), t) != types.end(); };
    if (ao_rays_flag->count() && !has(trav::RayType::kAo))
        throw Error("--ao-rays applies to ao rays; --types " + list + " has none");
    if (diffuse_rays_flag->count() && !has(trav::RayType::kDiffuse))
        throw Error("--diffuse-rays applies to diffuse rays; --types " + list + " has none");
}

void CameraOptions::add_to(CLI::App& app) {
    kind_flag = app.add_option("--camera", kind,
                               "projection: pinhole, thin-lens (render, with --aperture), fisheye (equidistant, "
                               "--fisheye-fov) or panorama (equirectangular, 360 x 180 degrees)")
                    ->check(CLI::IsMember({"pinhole", "thin-lens", "fisheye", "panorama"}))
                    ->capture_default_str();
    fisheye_fov_flag =
        app.add_option("--fisheye-fov", fisheye_fov,
                       "--camera fisheye: degrees seen across the circle inscribed in the image (default 180)")
            ->check(FiniteRange(1.0, 360.0));
    flags.push_back(kind_flag);
    flags.push_back(fisheye_fov_flag);
    flags.push_back(app.add_option("--eye", eye, "camera position x y z (default: the scene's camera)")
                        ->expected(3)
                        ->check(Finite()));
    flags.push_back(app.add_option("--target", target, "camera target x y z")->expected(3)->check(Finite()));
    flags.push_back(app.add_option("--up", up, "camera up vector x y z")->expected(3)->check(Finite()));
    fov_flag = app.add_option("--fov", fov, "vertical field of view in degrees (pinhole and thin-lens cameras)")
                   ->check(FiniteRange(0.01, 179.0));
    flags.push_back(fov_flag);
}

trav::Camera CameraOptions::apply(trav::Camera c) const {
    const bool wide = kind == "fisheye" || kind == "panorama";
    if (wide && fov_flag->count())
        throw Error(
            "--fov applies to --camera pinhole or thin-lens" +
            std::string(kind == "fisheye" ? "; a fish-eye takes --fisheye-fov" : "; a panorama sees 360 x 180"));
    if (fisheye_fov_flag->count() && kind != "fisheye") throw Error("--fisheye-fov applies to --camera fisheye");
    c.projection = kind == "fisheye"    ? trav::Projection::kFisheye
                   : kind == "panorama" ? trav::Projection::kPanorama
                                        : trav::Projection::kPerspective;
    c.fisheye_fov_deg = fisheye_fov;
    if (eye.size() == 3) c.eye = {eye[0], eye[1], eye[2]};
    if (target.size() == 3) c.target = {target[0], target[1], target[2]};
    if (up.size() == 3) c.up = {up[0], up[1], up[2]};
    if (fov > 0.0f) c.fov_y_deg = fov;
    for (const auto& [what, v] : {std::pair{"the camera's eye", c.eye}, std::pair{"the camera's target", c.target}})
        if (const std::string p = scene::vec_problem(what, {v.x, v.y, v.z}); !p.empty()) throw Error(p);
    return c;
}

trav::ProtocolConfig RayOptions::for_scene(const Scene& s) const {
    if (camera.kind == "thin-lens")
        throw Error(
            "--camera thin-lens applies to render (the ray generators have no lens): use pinhole, fisheye or "
            "panorama");
    trav::ProtocolConfig c = cfg;
    c.camera = camera.apply(s.camera);
    c.ao_length = s.ao_length;
    return c;
}

nlohmann::json protocol_json(const trav::ProtocolConfig& c) {
    nlohmann::json j = {{"width", c.primary.width},
                        {"height", c.primary.height},
                        {"spp", c.primary.samples},
                        {"tile", c.primary.tile},
                        {"ao_rays", c.ao_rays},
                        {"diffuse_rays", c.diffuse_rays},
                        {"ao_length", c.ao_length},
                        {"seed", c.seed},
                        {"camera",
                         {{"eye", {c.camera.eye.x, c.camera.eye.y, c.camera.eye.z}},
                          {"target", {c.camera.target.x, c.camera.target.y, c.camera.target.z}},
                          {"up", {c.camera.up.x, c.camera.up.y, c.camera.up.z}},
                          {"fov_y_deg", c.camera.fov_y_deg}}}};
    // A wide projection is named; a pinhole protocol keeps the fields it always had.
    if (c.camera.projection != trav::Projection::kPerspective) {
        j["camera"]["projection"] = trav::projection_name(c.camera.projection);
        j["camera"].erase("fov_y_deg");
        if (c.camera.projection == trav::Projection::kFisheye)
            j["camera"]["fisheye_fov_deg"] = c.camera.fisheye_fov_deg;
    }
    return j;
}

std::vector<trav::RayType> parse_ray_types(const std::string& list) {
    if (list == "all")
        return {trav::RayType::kPrimary, trav::RayType::kAo, trav::RayType::kDiffuse, trav::RayType::kShadow};
    std::vector<trav::RayType> out;
    std::stringstream ss(list);
    for (std::string t; std::getline(ss, t, ',');) out.push_back(trav::parse_ray_type(t));
    if (out.empty()) throw Error("no ray types given");
    return out;
}

std::string machine_description() {
    char host[256] = "unknown";
    gethostname(host, sizeof host - 1);
    std::string cpu = "unknown CPU";
    std::ifstream in("/proc/cpuinfo");
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("model name", 0) == 0) {
            cpu = line.substr(line.find(':') + 2);
            break;
        }
    }
    return std::string(host) + " (" + cpu + ", " + std::to_string(tbb::info::default_concurrency()) + " threads)";
}

nlohmann::json base_record(const char* kind, const Scene& scene) {
    return {{"record", kind},           {"commit", git_commit()},           {"build_type", build_type()},
            {"scene", scene.name},      {"scene_hash", scene.hash},         {"triangles", scene.mesh.triangle_count()},
            {"load_ms", scene.load_ms}, {"scene_cache", scene.scene_cache}, {"instances", scene.instances},
            {"meshes", scene.meshes}};
}

namespace {
std::vector<std::string>& command_line() {
    static std::vector<std::string> argv;
    return argv;
}
std::string& working_folder() {
    static std::string cwd;
    return cwd;
}
}  // namespace

void set_command_line(int argc, char** argv) {
    command_line().assign(argv + 1, argv + argc);
    std::error_code ec;
    working_folder() = fs::current_path(ec).string();
}

std::string file_hash(const std::string& path) { return accel::hash_hex(scene::hash_file(path)); }

void emit(const nlohmann::json& record) {
    // The identifying fields every record carries (README, "JSON lines"), stamped here so that
    // no command can leave them out; a record that set one keeps its own value.
    static const std::string machine = machine_description();
    BVHLAB_CHECK(record.is_object() && record.contains("record"), "a JSON line without a record kind");
    nlohmann::json j = record;
    auto stamp = [&](const char* key, const nlohmann::json& v) {
        if (!j.contains(key)) j[key] = v;
    };
    stamp("schema", kJsonSchemaVersion);
    stamp("tool", "bvhlab");
    stamp("commit", git_commit());
    stamp("build_type", build_type());
    stamp("machine", machine);
    if (!command_line().empty()) {
        stamp("argv", command_line());
        stamp("cwd", working_folder());
    }
    std::cout << j.dump() << std::endl;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& known) {
    const auto distance = [](const std::string& a, const std::string& b) {
        std::vector<size_t> row(b.size() + 1);
        for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
        for (size_t i = 1; i <= a.size(); ++i) {
            size_t diag = row[0];
            row[0] = i;
            for (size_t j = 1; j <= b.size(); ++j) {
                const size_t up = row[j];
                row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
                diag = up;
            }
        }
        return row[b.size()];
    };
    size_t best = std::max<size_t>(1, word.size() / 3) + 1;
    std::vector<std::string> names;
    for (const std::string& k : known) {
        const size_t d = distance(word, k);
        if (d < best) {
            best = d;
            names.clear();
        }
        if (d == best && std::find(names.begin(), names.end(), k) == names.end()) names.push_back(k);
    }
    if (names.empty() || names.size() > 3) return "";
    std::string out = " (did you mean " + names[0];
    for (size_t i = 1; i < names.size(); ++i) out += (i + 1 == names.size() ? " or " : ", ") + names[i];
    return out + "?)";
}

}  // namespace bvhlab::cli
