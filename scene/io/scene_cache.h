// SPDX-License-Identifier: MIT
// The binary scene cache: after an OBJ loads, the cleaned mesh (positions, indices, material ids
// and table, drop counts, the loader's warnings, the scene hash) is written to one versioned,
// checksummed file, atomically; the next load of the same OBJ reads that file instead of
// parsing. A cache entry is used only when the OBJ's bytes, each material file's bytes (or its
// absence) and the loader version are those it was made from: the OBJ and material files are
// hashed on every load (README, "Scene cache", says what that costs).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/io/obj_loader.h"
#include "scene/mesh.h"

namespace bvhlab::scene {

constexpr uint32_t kSceneCacheVersion = 3;  // 2: the renderer's material parameters; 3: texcoords

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
