// SPDX-License-Identifier: MIT
// TriangleMesh helpers: bounds, the checked append that drops bad triangles, the scene hash.
#include "scene/mesh.h"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/domain.h"

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

Vec3 unit_or_zero(Vec3 n) {
    // Float unless the squared length leaves float's normal range (tiny or huge components).
    const float len2 = n.x * n.x + n.y * n.y + n.z * n.z;
    if (len2 > 1e-30f && len2 < 1e30f) {
        const float len = std::sqrt(len2);
        return {n.x / len, n.y / len, n.z / len};
    }
    const double x = n.x, y = n.y, z = n.z, len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 0.0) || !std::isfinite(len)) return {0.0f, 0.0f, 0.0f};
    return {float(x / len), float(y / len), float(z / len)};
}

void corner_normals(bool given, Vec3 n0, Vec3 n1, Vec3 n2, bool unit, Vec3* out) {
    out[0] = n0, out[1] = n1, out[2] = n2;
    if (!unit)
        for (int k = 0; k < 3; ++k) out[k] = unit_or_zero(out[k]);
    bool ok = given;
    for (int k = 0; k < 3; ++k) ok = ok && (out[k].x != 0.0f || out[k].y != 0.0f || out[k].z != 0.0f);
    if (!ok)
        for (int k = 0; k < 3; ++k) out[k] = {0.0f, 0.0f, 0.0f};
}

void append_corner_normals(TriangleMesh& mesh, bool given, Vec3 n0, Vec3 n1, Vec3 n2, bool unit) {
    Vec3 u[3];
    corner_normals(given, n0, n1, n2, unit, u);
    mesh.normals.insert(mesh.normals.end(), u, u + 3);
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

namespace {

bool within(Vec3 v, float limit) {
    const auto in = [limit](float x) { return x >= -limit && x <= limit; };  // NaN is not
    return in(v.x) && in(v.y) && in(v.z);
}

}  // namespace

std::string vec_problem(const char* what, Vec3 v, float limit) {
    if (within(v, limit)) return "";
    char b[160];
    std::snprintf(b, sizeof b, "%s (%g, %g, %g) is outside [-%g, %g], the numeric domain bvhlab supports", what, v.x,
                  v.y, v.z, limit, limit);
    return b;
}

std::string domain_problem(const TriangleMesh& mesh) {
    for (size_t i = 0; i < mesh.vertices.size(); ++i)  // the name is made only for the vertex reported
        if (!within(mesh.vertices[i], kMaxCoordinate))
            return vec_problem(("vertex " + std::to_string(i + 1)).c_str(), mesh.vertices[i]);
    if (mesh.triangle_count() > 0 && !(mesh.diagonal() >= kMinSceneDiagonal)) {
        char b[160];
        std::snprintf(b, sizeof b,
                      "the scene's bounding-box diagonal %g is below %g, the numeric domain bvhlab supports",
                      mesh.diagonal(), kMinSceneDiagonal);
        return b;
    }
    return "";
}

std::string material_problem(const Material& m) {
    const auto color = [](const char* key, Vec3 c, float hi) {
        for (float x : {c.x, c.y, c.z})
            if (!(x >= 0.0f && x <= hi)) {
                char b[128];
                std::snprintf(b, sizeof b, "%s %g %g %g is not in [0, %g]", key, c.x, c.y, c.z, hi);
                return std::string(b);
            }
        return std::string();
    };
    for (const std::string& p :
         {color("Kd", m.diffuse, 1.0f), color("Ks", m.specular, 1.0f), color("Ka", m.ambient, kMaxRadiance),
          color("Ke", m.emission, kMaxRadiance), range_problem("Ns", m.shininess, 0.0f, 1e30f),
          range_problem("Ni", m.ior, 0.0f, 100.0f), range_problem("d", m.dissolve, 0.0f, 1.0f),
          range_problem("-bm", m.bump_multiplier, -1e6f, 1e6f)})
        if (!p.empty()) return p;
    return "";
}

}  // namespace bvhlab::scene
