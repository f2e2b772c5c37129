// SPDX-License-Identifier: MIT
// What the bvhlab subcommands share: scene resolution (paths, catalogue names, generated
// scenes), option groups, progress on stderr and JSON-line output.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/stats.h"
#include "scene/io/atomic_file.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "traversal/factory.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab {

const char* git_commit();  // generated at build time
const char* build_type();

namespace cli {

/// Options every subcommand has.
struct Globals {
    bool json = false;
    bool quiet = false;
    bool no_scene_cache = false;  ///< --no-scene-cache: parse the scene file, neither read nor write the cache
    bool flatten = false;         ///< --flatten: an instanced scene becomes one mesh
};

/// Stage lines on stderr: "[bvhlab] loading X ..." then "... done (1.23 s)".
/// A CLI11 check for a floating-point option: a finite number within [lo, hi] (CLI::Range lets
/// NaN through, since every comparison with NaN is false).
CLI::Validator FiniteRange(double lo, double hi);
/// A CLI11 check for each number of a vector option: finite.
CLI::Validator Finite();
/// A CLI11 check for a 64-bit unsigned option: decimal digits only, at most 2^64 - 1 (CLI11
/// would read 99999999999999999999 as 2^64 - 1 and -1 as 2^64 - 1).
CLI::Validator UInt64();

/// A ray file for `command` (bench, verify): read_ray_file, refusing a file with no rays.
trav::RaySet read_rays_for(const std::string& path, const char* command);

/// Progress on stderr: "what ..." when the stage starts, "what: done (s)" when it ends, and
/// nothing more when it ends by an exception (the error line says why).
class Stage : public trav::StageProgress {
public:
    Stage(const Globals& g, std::string what);
    ~Stage() override;
    /// The library's progress (builds, EPO): "45% (about 1.2 s left)" once the stage has run for
    /// a second (only on a terminal).
    void report(uint64_t done, uint64_t total) override;
    double seconds() const;
    /// Percent updates for long loops (only on a terminal), with an optional detail in brackets.
    void progress(size_t done, size_t total, const std::string& detail = "") const;
    /// "45% (67 of 149 MB, about 1.2 s left)" for work measured in bytes, once the stage has run
    /// for a second (only on a terminal).
    void progress_bytes(size_t done, size_t total) const;

private:
    const Globals& g_;
    std::string what_;
    std::chrono::steady_clock::time_point t0_;
    int exceptions_ = 0;  // std::uncaught_exceptions() at the start
};

/// " while <stage>" for the last Stage that ended by an exception, or "" (for error lines).
std::string failed_stage_clause();

/// A scene ready to use: mesh plus camera and AO length from its catalogue entry (or an
/// automatic framing when it has none).
struct Scene {
    std::string name;
    std::string source;  ///< the scene file read (a catalogue name resolved to its file), or the gen: spec
    /// The scene file its triangles come from: `source`, or for gen:instances the base scene's
    /// file; "" for generated soups (textures are found beside it).
    std::string file;
    /// The triangles in world space. For an instanced scene (`placed` set) every instance's, with
    /// the scene-wide ids of two-level hits: what rays are made on and hits are checked against.
    scene::TriangleMesh mesh;
    /// A scene that places some mesh more than once, without --flatten: structures are built
    /// two-level over it, and Embree checks them with its own instances. Null otherwise.
    std::shared_ptr<const scene::InstancedScene> placed;
    /// The instance numbering of hit ids (trav::InstanceFirstIds): the instances' first ids for
    /// a two-level scene, {0, triangles} for one mesh (--flatten makes any scene one).
    std::vector<uint64_t> first_ids;
    uint64_t instances = 1;  ///< instances in the scene file (1 for a single mesh)
    uint64_t meshes = 1;     ///< distinct meshes they place
    trav::Camera camera;
    bool camera_from_catalogue = false;
    float ao_length = 0.0f;
    std::string hash;
    double load_ms = 0.0;                     ///< loading (or generating) the mesh
    std::string scene_cache = "off";          ///< hit (the cache served the load), miss (parsed, then cached) or off
    std::vector<std::string> material_files;  ///< the `mtllib` files it names (other formats: the files Assimp opened)
    std::vector<std::string> missing_material_files;  ///< those that do not exist

    /// The files it was read from (the scene file, its material files and map_Kd textures),
    /// named for scene::refuse_clashing_files().
    std::vector<scene::NamedFile> input_files() const;
};

/// The help text of every command's SCENE argument.
inline constexpr const char* kSceneHelp =
    "scene file (OBJ, glTF, PLY, ...), scene name from scenes.json, gen:KIND:N[:SEED] or gen:instances:SCENE:N[:SEED]";

/// Resolves SPEC: a scene file (OBJ, or glTF, PLY and the other formats Assimp reads), a scene name
/// from $BVHLAB_SCENES/scenes.json or data/scenes.json, gen:KIND:TRIANGLES[:SEED], or
/// gen:instances:SCENE:N[:SEED]. An instanced scene (a mesh placed more than once) keeps its
/// instances (Scene::placed) unless g.flatten makes it one mesh. Prints load progress and
/// dropped-triangle counts on stderr.
Scene load_scene(const std::string& spec, const Globals& g);

/// The Embree oracle of a scene: over its mesh, or with Embree's own instances when it is
/// instanced (the same triangle ids either way).
std::unique_ptr<trav::EmbreeOracle> make_oracle(const Scene& s);

/// The project's data/ folder: $BVHLAB_DATA, else the source tree's, else share/bvhlab/data
/// of an installed tree.
std::string data_dir();

/// Names of the scenes in $BVHLAB_SCENES/scenes.json (empty when unset).
std::vector<std::string> catalogue_scene_names();

/// Builder flags: --builder, --structure, --bins, --max-leaf, --min-leaf, --alpha, --budget.
struct BuildOptions {
    std::string builder = "binned";
    /// --structure: a builder name (bvh = binned, sweep, sbvh, kdtree) or a structure file
    /// written by `bvhlab build --out`, which is then loaded instead of building.
    std::string structure;
    accel::BuilderOptions opts;
    bool epo = true;
    /// --structure all (every structure): set by `verify`, the one command that takes it,
    /// before add_to(); elsewhere the option refuses it.
    bool accepts_all = false;
    int kd_stack = 64;                   ///< kd-tree traversal stack: 64 = full, 1..8 = short stack with restart
    accel::KdTreeBuilder::Config kd;     ///< kd-tree build constants (--kd-*)
    std::vector<CLI::Option*> kd_flags;  ///< kd flags whose explicit values a cache must match
    /// flags whose explicit values a cache must match: --bins, --max-leaf, --min-leaf, --alpha,
    /// --budget, --spatial-bins, --reinsert, --morton-bits, --radius
    std::vector<CLI::Option*> config_flags;
    std::string layout = "bvh2";        ///< --layout of a BVH: bvh2, or cwbvh (collapsed, compressed 8-wide)
    std::string collapse = "sah";       ///< --collapse to 8-wide: sah (Ylitie et al.'s optimum) or greedy
    std::string cw_tris = "woop";       ///< --cw-tris: a CWBVH's leaf triangles, woop (48 B) or vertices (36 B)
    std::string build_device = "auto";  ///< --build-device: cpu, gpu, or auto (the builder's own)
    CLI::Option* build_device_flag = nullptr;
    CLI::Option* builder_flag = nullptr;
    CLI::Option* structure_flag = nullptr;
    CLI::Option* kd_stack_flag = nullptr;
    CLI::Option* layout_flag = nullptr;
    CLI::Option* collapse_flag = nullptr;
    CLI::Option* cw_tris_flag = nullptr;

    bool is_kdtree() const { return structure == "kdtree"; }
    bool is_cwbvh() const { return layout == "cwbvh"; }

    void add_to(CLI::App& app);
    accel::BuilderKind kind() const { return accel::parse_builder_kind(builder); }
    /// The structure file named by --structure, or "" when --structure names a builder.
    std::string structure_file() const;
    /// Refuses, with a one-line bvhlab::Error, an option given explicitly that the chosen
    /// builder does not use (--bins with a kd-tree, --alpha with binned, --kd-ct with a BVH,
    /// --layout with a kd-tree, --collapse or --cw-tris without --layout cwbvh).
    /// Structure files are checked against their own config when loaded.
    void check_applicable() const;
    /// The library's structure spec of these options.
    trav::StructureSpec spec() const;
};

/// Ray-protocol flags: --width, --height, --spp, --tile, --ao-rays, --diffuse-rays, --seed.
/// Camera overrides: --eye, --target, --up (3 floats each), --fov.
struct CameraOptions {
    std::vector<CLI::Option*> flags;
    std::vector<float> eye, target, up;  ///< empty = the scene's
    float fov = 0.0f;                    ///< fov_y in degrees, 0 = the scene's
    std::string kind = "pinhole";        ///< --camera: pinhole, thin-lens, fisheye or panorama
    float fisheye_fov = 180.0f;          ///< --fisheye-fov in degrees
    CLI::Option* kind_flag = nullptr;
    CLI::Option* fov_flag = nullptr;
    CLI::Option* fisheye_fov_flag = nullptr;
    void add_to(CLI::App& app);
    /// `scene_camera` with the overrides given and the projection; refuses --fov for a wide
    /// projection and --fisheye-fov without a fish-eye (one-line bvhlab::Error).
    trav::Camera apply(trav::Camera scene_camera) const;
};

struct RayOptions {
    trav::ProtocolConfig cfg;
    CameraOptions camera;
    std::vector<CLI::Option*> flags;  ///< every option that shapes protocol rays (camera ones too)
    CLI::Option* ao_rays_flag = nullptr;
    CLI::Option* diffuse_rays_flag = nullptr;
    void add_to(CLI::App& app);
    /// Makes `rays_file` (--rays) exclude every protocol option: a ray file's rays are fixed.
    void excluded_by(CLI::Option* rays_file) const;
    /// Refuses --ao-rays and --diffuse-rays when `types` has no rays of that kind.
    void check_types(const std::vector<trav::RayType>& types, const std::string& list) const;
    /// The protocol config for a scene: its camera and AO length unless overridden.
    trav::ProtocolConfig for_scene(const Scene& s) const;
};

/// The protocol settings as JSON, so a figure records how its rays were made.
nlohmann::json protocol_json(const trav::ProtocolConfig& c);

/// "primary,ao" -> types; "all" -> the four.
std::vector<trav::RayType> parse_ray_types(const std::string& list);

/// Machine description: hostname, CPU model, hardware threads.
std::string machine_description();

/// Fields every JSON line carries: commit, build type, scene name and hash.
nlohmann::json base_record(const char* kind, const Scene& scene);

/// The version of the JSON-lines schema (README, "JSON lines"): bumped when a field changes meaning.
constexpr int kJsonSchemaVersion = 1;

/// Prints a JSON object as one line on stdout, stamped with the identifying fields every record
/// carries: schema, tool, commit, build_type, machine (and its own "record" kind).
void emit(const nlohmann::json& j);

/// The command line and working folder every JSON line records ("argv", "cwd"), so that
/// `bvhlab rerun` can repeat it; set once by main.
void set_command_line(int argc, char** argv);

/// A file's content hash as 16 hex digits (scene::hash_file), for records naming input files.
std::string file_hash(const std::string& path);

/// " (did you mean X?)" or " (did you mean X or Y?)" for the names of `known` closest to `word`
/// by edit distance (at most a third of its length, and at least 1 apart from the rest), or ""
/// when none is close. For the errors about unknown names.
std::string did_you_mean(const std::string& word, const std::vector<std::string>& known);

}  // namespace cli
}  // namespace bvhlab
