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
constexpr uint32_t kAssimpLoaderVersion = 3;  // 2: vertex normals per corner; 3: normal/height maps

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
/// The files Assimp opened besides `path` (a glTF's buffers, say) are appended to
/// `dependencies`: the scene cache checks them as it checks an OBJ's material files.
InstancedScene load_assimp(const std::string& path, std::vector<std::string>* warnings = nullptr,
                           std::vector<std::string>* dependencies = nullptr);

/// What load_scene_file did: the scene, its warnings, the files it depends on (an OBJ's
/// `mtllib` files; the files Assimp opened beside the scene) and what the cache did.
using SceneFileLoad = CachedScene;

/// Any scene file through the scene cache in `cache_dir` ("" for none, with `writer` stamped in
/// entries written): an OBJ through load_obj as a single instance (kObjLoaderVersion), any other
/// format through load_assimp (kAssimpLoaderVersion), each cached by load_cached.
/// Errors as those functions throw them.
SceneFileLoad load_scene_file(const std::string& path, const std::string& cache_dir, const std::string& writer,
                              const LoadProgress& progress = {});

/// The glTF extensions that a file may require and bvhlab implements.
const std::vector<std::string>& supported_gltf_extensions();

}  // namespace bvhlab::scene
