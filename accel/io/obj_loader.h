// SPDX-License-Identifier: MIT
// Wavefront OBJ input through tinyobjloader, with strict checks of the lines it would
// otherwise accept silently. The only file pair that includes tinyobjloader.
#pragma once

#include <string>
#include <vector>

#include "accel/core/mesh.h"

namespace bvhlab::accel {

/// Loads and triangulates `path`, keeping material ids and names (from its .mtl files).
/// Triangles with non-finite vertices or zero area are dropped and counted in mesh.dropped.
/// Throws bvhlab::Error with a one-line message on a missing or unreadable file, a malformed
/// v/vt/vn/f line, a face index out of range, or a mesh with no usable triangle.
/// Non-fatal loader messages (a missing .mtl, say) are appended to `warnings`.
TriangleMesh load_obj(const std::string& path, std::vector<std::string>* warnings = nullptr);

/// Writes `mesh` as OBJ (v and f lines, usemtl per material run). Throws on I/O errors.
void write_obj(const TriangleMesh& mesh, const std::string& path);

}  // namespace bvhlab::accel
