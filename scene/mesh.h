// SPDX-License-Identifier: MIT
// Indexed triangle mesh: the input of every builder, of the Embree oracle and of the renderer.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/vec3.h"
#include "scene/material.h"

namespace bvhlab::scene {

/// Triangles that the loader or a generator dropped, with the reason.
struct DropCounts {
    uint64_t non_finite = 0;  ///< a vertex had a NaN or inf coordinate
    uint64_t zero_area = 0;   ///< the three vertices are collinear or coincide
    uint64_t total() const { return non_finite + zero_area; }
};

/// Indexed triangle mesh. Triangle i uses vertices indices[3i..3i+2]; ids are dense in
/// [0, triangle_count()). Every triangle kept has finite vertices and a non-zero area.
struct TriangleMesh {
    std::vector<Vec3> vertices;
    std::vector<uint32_t> indices;      ///< 3 per triangle
    std::vector<int32_t> material_ids;  ///< one per triangle, -1 = none
    /// Texture coordinates per corner, 6 floats per triangle (u0 v0 u1 v1 u2 v2), when the OBJ
    /// has `vt` lines; empty otherwise. A face without `vt` references gets zeros.
    std::vector<float> texcoords;
    /// Shading normals per corner, 3 per triangle, when the file gives vertex normals (OBJ `vn`,
    /// glTF NORMAL, PLY nx ny nz); empty otherwise. Each is a unit vector, or all three corners of a
    /// triangle are 0 where the file gives that triangle none (the renderer then uses the
    /// geometric normal). append_corner_normals keeps that rule.
    std::vector<Vec3> normals;
    std::vector<Material> materials;
    DropCounts dropped;

    size_t triangle_count() const { return indices.size() / 3; }
    Vec3 vertex(size_t tri, int corner) const { return vertices[indices[3 * tri + corner]]; }
    AABB triangle_bounds(size_t tri) const;
    AABB bounds() const;
    /// Length of the bounding-box diagonal.
    float diagonal() const;
    /// Sum of the triangles' areas.
    double surface_area() const;
};

/// Verdict of the loader's triangle filter.
enum class TriangleCheck { kOk, kNonFinite, kZeroArea };

/// Classifies a triangle: non-finite coordinates or zero area (tested in double precision,
/// so tiny but valid triangles pass) make it unusable.
TriangleCheck check_triangle(Vec3 a, Vec3 b, Vec3 c);

/// Counts a failed check in `drops`; returns true when the triangle is kept.
bool count_drop(TriangleCheck check, DropCounts& drops);

/// A denormal coordinate (nonzero, below FLT_MIN in magnitude) as +0, anything else (-0
/// too, so that scene hashes of meshes without denormals do not change) as it is. Meshes
/// never hold denormals: Embree's TBB workers run with denormals-are-zero, and a builder whose
/// tasks read the same coordinate as 0 on some threads and as itself on others builds bounds
/// that do not hold the triangle (the adversarial tests' rooms, tiles jittered around 0, found
/// it). Moving a point by under 1.2e-38 is far below any float tolerance.
inline Vec3 flush_denormals(Vec3 v) {
    auto f = [](float x) { return x != 0.0f && std::fabs(x) < 1.17549435e-38f ? 0.0f : x; };  // FLT_MIN; -0 stays
    return {f(v.x), f(v.y), f(v.z)};
}

/// n as a unit vector (normalised in double precision), or 0 when it is not finite or has no
/// length.
Vec3 unit_or_zero(Vec3 n);

/// Appends the shading normals of one triangle's corners to mesh.normals: each made a unit
/// vector, or all three 0 when any of them is 0, non-finite or missing (`given` false).
/// `unit`: the three are unit_or_zero's results already (a loader that normalises per vertex).
void append_corner_normals(TriangleMesh& mesh, bool given, Vec3 n0, Vec3 n1, Vec3 n2, bool unit = false);
/// The same three normals written to out[0..2] instead (a loader that fills arrays in parallel).
void corner_normals(bool given, Vec3 n0, Vec3 n1, Vec3 n2, bool unit, Vec3* out);

/// Appends a triangle unless it has a non-finite vertex or zero area, which it counts in
/// mesh.dropped instead; denormal coordinates become 0 (flush_denormals). Returns true when
/// the triangle was kept.
bool add_triangle_checked(TriangleMesh& mesh, Vec3 a, Vec3 b, Vec3 c, int32_t material);

/// "" when the mesh is inside the numeric domain (scene/domain.h): every vertex coordinate
/// within +-kMaxCoordinate and a bounding-box diagonal of at least kMinSceneDiagonal; else one
/// line naming the first vertex or the diagonal that is not.
std::string domain_problem(const TriangleMesh& mesh);

/// "" when a material's values are ones the renderer can use: Kd and Ks in [0, 1], Ka and Ke
/// in [0, kMaxRadiance], Ns >= 0, Ni in [0, 100] (up to 1 means the default 1.5), d in [0, 1],
/// all finite; else one line naming the key and value.
std::string material_problem(const Material& m);

/// 64-bit FNV-1a over the triangles' vertex coordinates in triangle order, as 16 hex digits.
/// Two meshes with the same triangles give the same hash whatever their vertex sharing.
std::string scene_hash(const TriangleMesh& mesh);

}  // namespace bvhlab::scene
