// SPDX-License-Identifier: MIT
// The binary scene cache: after an OBJ loads, the cleaned mesh (positions, indices, material ids
// and table, drop counts, the loader's warnings, the scene hash) is written to one versioned,
// checksummed file, atomically; the next load of the same OBJ reads that file instead of
// parsing. A cache entry is used only when the OBJ's bytes, each material file's bytes (or its
// absence) and the loader version are those it was made from: the OBJ and material files are
// hashed on every load (README, "Scene cache", says what that costs).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "scene/io/obj_loader.h"
#include "scene/mesh.h"
#include "scene/scene.h"

namespace bvhlab::scene {

// 2: material parameters; 3: texcoords; 4: meshes, instances, camera; 5: shading normals;
// 6: normal and bump maps
constexpr uint32_t kSceneCacheVersion = 6;

/// $BVHLAB_CACHE_DIR, else $XDG_CACHE_HOME/bvhlab, else $HOME/.cache/bvhlab ("" when none is set).
std::string default_scene_cache_dir();

/// A 64-bit hash of a file's bytes: FNV-1a over 8-byte words of 4 MiB chunks, hashed in
/// parallel and combined in order. `exists` is set false (and 0 returned) for a missing file;
/// other failures throw bvhlab::Error.
uint64_t hash_file(const std::string& path, bool* exists = nullptr);

/// What load_obj_cached did.
struct SceneLoad {
    TriangleMesh mesh;
    std::vector<std::string> warnings;  ///< the loader's (a missing .mtl, say), cached ones included
    /// The material files the OBJ names (`mtllib`, resolved against its folder), and which of
    /// them do not exist: the renderer refuses those (issue 19), the other commands warn.
    std::vector<std::string> material_files, missing_material_files;
    std::string scene_hash;   ///< scene_hash(mesh)
    bool from_cache = false;  ///< the cache served it
    std::string cache_file;   ///< the entry read or written ("" when the cache is off)
    /// A one-line warning when the cache could not be used or written (a damaged or foreign
    /// entry, an unwritable folder): the load itself succeeded.
    std::string cache_warning;
};

/// Loads `obj_path` through the cache in `cache_dir` ("" = no cache: load_obj alone). Errors of
/// the OBJ itself throw as load_obj's do; a damaged, foreign or unreadable cache entry is never
/// trusted and never fatal: the OBJ is parsed and the entry written again. `writer` (a commit)
/// is stored in entries written.
/// `progress` reports a parse as load_obj's does (a hit is not reported).
SceneLoad load_obj_cached(const std::string& obj_path, const std::string& cache_dir, const std::string& writer,
                          const LoadProgress& progress = {});

/// What load_cached did, for any format.
struct CachedScene {
    InstancedScene scene;
    std::vector<std::string> warnings;  ///< the parser's, cached ones included
    /// The files the scene file depends on (an OBJ's material files; the files an importer opened
    /// beside the scene), and which of them do not exist.
    std::vector<std::string> dependencies, missing_dependencies;
    std::string scene_hash;  ///< scene_hash of the mesh of a one-mesh scene (one identity instance), else ""
    bool from_cache = false;
    std::string cache_file;
    std::string cache_warning;
};

/// Parses a scene file: the scene, with warnings and the files it depends on appended.
using SceneParser =
    std::function<InstancedScene(std::vector<std::string>* warnings, std::vector<std::string>* dependencies)>;

/// Loads `path` through the cache in `cache_dir` ("" = no cache: `parse` alone), as
/// load_obj_cached does for OBJ files: an entry is used only when the file's bytes, each
/// dependency's bytes (or its absence) and `loader_version` are those it was made from; a
/// damaged, foreign or unreadable entry is never trusted and never fatal.
CachedScene load_cached(const std::string& path, uint32_t loader_version, const std::string& cache_dir,
                        const std::string& writer, const SceneParser& parse);

/// One entry of a cache folder, as `bvhlab cache info` shows it.
struct SceneCacheEntry {
    std::string file;
    uint64_t bytes = 0;
    std::string source;  ///< the OBJ it was made from
    uint64_t triangles = 0;
    std::string writer;
    std::string problem;  ///< why the entry cannot be used ("" when it reads whole)
};

/// The entries of `dir` (none when it does not exist), sorted by file name.
std::vector<SceneCacheEntry> list_scene_cache(const std::string& dir);

/// Removes every entry of `dir` (and temporaries left by killed writers). Returns how many
/// files were removed and their bytes in `bytes`.
size_t clear_scene_cache(const std::string& dir, uint64_t* bytes = nullptr);

}  // namespace bvhlab::scene
