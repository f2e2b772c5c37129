// SPDX-License-Identifier: MIT
// TriangleMesh helpers: bounds, the checked append that drops bad triangles, the scene hash.
#include "scene/mesh.h"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "accel/core/check.h"
#include "accel/core/checksum.h"

namespace bvhlab::scene {

AABB TriangleMesh::triangle_bounds(size_t tri) const {
    AABB b = AABB::empty();
    for (int k = 0; k < 3; ++k) b.extend(vertex(tri, k));
    return b;
}

AABB TriangleMesh::bounds() const {
    AABB b = AABB::empty();
    for (size_t i = 0; i < triangle_count(); ++i) b.extend(triangle_bounds(i));
    return b;
}

float TriangleMesh::diagonal() const {
    AABB b = bounds();
    return b.is_empty() ? 0.0f : length(b.extent());
}

double TriangleMesh::surface_area() const {
    double sum = 0.0;
    for (size_t i = 0; i < triangle_count(); ++i) {
        Vec3 a = vertex(i, 0), b = vertex(i, 1), c = vertex(i, 2);
        sum += 0.5 * double(length(cross(b - a, c - a)));
    }
    return sum;
}

static bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

TriangleCheck check_triangle(Vec3 a, Vec3 b, Vec3 c) {
    if (!finite(a) || !finite(b) || !finite(c)) return TriangleCheck::kNonFinite;
    double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) return TriangleCheck::kZeroArea;
    return TriangleCheck::kOk;
}

bool count_drop(TriangleCheck check, DropCounts& drops) {
    if (check == TriangleCheck::kNonFinite) ++drops.non_finite;
    if (check == TriangleCheck::kZeroArea) ++drops.zero_area;
    return check == TriangleCheck::kOk;
}

bool add_triangle_checked(TriangleMesh& mesh, Vec3 a, Vec3 b, Vec3 c, int32_t material) {
    a = flush_denormals(a);
    b = flush_denormals(b);
    c = flush_denormals(c);
    if (!count_drop(check_triangle(a, b, c), mesh.dropped)) return false;
    auto base = uint32_t(mesh.vertices.size());
    mesh.vertices.push_back(a);
    mesh.vertices.push_back(b);
    mesh.vertices.push_back(c);
    mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
    mesh.material_ids.push_back(material);
    return true;
}

std::string scene_hash(const TriangleMesh& mesh) {
    uint64_t h = accel::kFnvOffset;
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = mesh.vertex(i, k);
            h = accel::fnv1a(&v, 12, h);
        }
    }
    return accel::hash_hex(h);
}

}  // namespace bvhlab::scene
