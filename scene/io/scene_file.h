// SPDX-License-Identifier: MIT
// Scene files of any format: Wavefront OBJ through the project's own loader (obj_loader.h, the
// measured fast path with strict checks), glTF 2.0, PLY and the other formats Assimp reads
// through Assimp, keeping the node hierarchy as instances. The only file pair that includes
// Assimp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/io/obj_loader.h"
#include "scene/io/scene_cache.h"
#include "scene/scene.h"

namespace bvhlab::scene {

/// The Assimp conversion's version: part of every scene-cache key, bumped whenever the same
/// file would convert differently.
constexpr uint32_t kAssimpLoaderVersion = 1;

/// True for a path whose extension (any case) is .obj: the project's own loader reads it.
bool is_obj_path(const std::string& path);

/// Reads a non-OBJ scene file through Assimp. Every node that places meshes becomes an instance
/// of them; meshes (a node's mesh list) placed by one node only are moved into world space and
/// merged into one mesh placed once, so that a scene without reuse is a single instance. Points
/// and lines are ignored; triangles with non-finite vertices or zero area are dropped and
/// counted; glTF metallic-roughness materials map to the renderer's MTL-style parameters
/// (README, "Scene formats"); the first camera becomes scene.camera.
/// Throws bvhlab::Error with one line naming the file for: an extension Assimp does not read, a
/// file Assimp refuses (its reason), a glTF that requires an extension bvhlab does not
/// implement, a file with no triangles, a material outside the renderer's domain.
/// Non-fatal notes (embedded textures, glTF extensions used but ignored, instances dropped for a
/// singular transform) are appended to `warnings`.
InstancedScene load_assimp(const std::string& path, std::vector<std::string>* warnings = nullptr);

/// What load_scene_file did: the scene, and for OBJ files what load_obj_cached says.
struct SceneFileLoad {
    InstancedScene scene;
    std::vector<std::string> warnings;
    std::vector<std::string> material_files, missing_material_files;  ///< OBJ: its `mtllib` files
    std::string scene_hash;   ///< OBJ: scene_hash of its mesh; "" for other formats
    bool from_cache = false;  ///< the scene cache served it
    std::string cache_file;   ///< the cache entry read or written ("" when none)
    std::string cache_warning;
};

/// Any scene file: an OBJ through load_obj_cached (the cache in `cache_dir`, "" for none, with
/// `writer` stamped in entries written), as a single instance; any other format through
/// load_assimp (not cached). Errors as those functions throw them.
SceneFileLoad load_scene_file(const std::string& path, const std::string& cache_dir, const std::string& writer,
                              const LoadProgress& progress = {});

/// The glTF extensions that a file may require and bvhlab implements.
const std::vector<std::string>& supported_gltf_extensions();

}  // namespace bvhlab::scene
