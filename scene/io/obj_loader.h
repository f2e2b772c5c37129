// SPDX-License-Identifier: MIT
// Wavefront OBJ input through tinyobjloader, with strict checks of the lines it would
// otherwise accept silently. The only file pair that includes tinyobjloader.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "scene/mesh.h"

namespace bvhlab::scene {

/// Loads and triangulates `path`, keeping material ids and names (from its .mtl files).
/// Triangles with non-finite vertices or zero area are dropped and counted in mesh.dropped.
/// Throws bvhlab::Error with a one-line message on a missing or unreadable file, a malformed
/// v/vt/vn/f line, a face index out of range, or a mesh with no usable triangle.
/// Non-fatal loader messages (a missing .mtl, say) are appended to `warnings`, and the material
/// files that the OBJ names (`mtllib`, resolved against its folder, whether or not they exist)
/// to `mtl_files`.
/// `progress`, when given, is called on the calling thread with the bytes parsed so far and the
/// total, every 8 MiB and at the end.
using LoadProgress = std::function<void(size_t done, size_t total)>;
TriangleMesh load_obj(const std::string& path, std::vector<std::string>* warnings = nullptr,
                      std::vector<std::string>* mtl_files = nullptr, const LoadProgress& progress = {});

/// The loader's version: part of every scene-cache key, bumped whenever the same OBJ would load
/// differently (scene_cache.h).
// 2: materials keep Ks, Ns, Ni, d, illum, map_Kd; 3: texcoords; 4: denormal coordinates as 0;
// 5: hexadecimal numbers refused (tinyobjloader read them as 0)
// 6: vt/vn references checked, absolute mtllib, MTL numbers scanned; 7: vn normals per corner;
// 8: norm, map_Bump/bump and -bm
constexpr uint32_t kObjLoaderVersion = 8;

/// Writes `mesh` as OBJ (v and f lines, usemtl per material run). Throws on I/O errors.
void write_obj(const TriangleMesh& mesh, const std::string& path);

}  // namespace bvhlab::scene
