// SPDX-License-Identifier: MIT
// Instanced scenes: transforms, flattening, and the generated gen:instances scenes.
#include "scene/scene.h"

#include <algorithm>
#include <cmath>

#include "accel/core/check.h"
#include "accel/core/random.h"

namespace bvhlab::scene {

double Transform::determinant() const {
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
}

Transform Transform::inverse() const {
    const double det = determinant();
    BVHLAB_CHECK(det != 0.0, "the inverse of a singular transform");
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    const double r[9] = {(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det,
                         (f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det,
                         (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det};
    Transform inv;
    for (int row = 0; row < 3; ++row) {
        double t = 0.0;
        for (int k = 0; k < 3; ++k) {
            inv.m[4 * row + k] = float(r[3 * row + k]);
            t -= r[3 * row + k] * m[4 * k + 3];
        }
        inv.m[4 * row + 3] = float(t);
    }
    return inv;
}

Transform Transform::normal_map() const {
    // The cofactor matrix of M is det(M) M^-T; with det's sign it keeps a normal's side.
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    const double s = determinant() < 0.0 ? -1.0 : 1.0;
    const double r[9] = {e * i - f * h, f * g - d * i, d * h - e * g, c * h - b * i, a * i - c * g,
                         b * g - a * h, b * f - c * e, c * d - a * f, a * e - b * d};
    Transform out;
    for (int row = 0; row < 3; ++row) {
        for (int k = 0; k < 3; ++k) out.m[4 * row + k] = float(s * r[3 * row + k]);
        out.m[4 * row + 3] = 0.0f;
    }
    return out;
}

Transform Transform::operator*(const Transform& inner) const {
    Transform out;
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 4; ++col) {
            double s = col == 3 ? m[4 * row + 3] : 0.0;
            for (int k = 0; k < 3; ++k) s += double(m[4 * row + k]) * inner.m[4 * k + col];
            out.m[4 * row + col] = float(s);
        }
    }
    return out;
}

bool InstancedScene::is_instanced() const {
    std::vector<uint32_t> uses(meshes.size(), 0);
    for (const Instance& inst : instances)
        if (++uses[inst.mesh] > 1) return true;
    return false;
}

uint64_t InstancedScene::triangle_count() const {
    uint64_t n = 0;
    for (const Instance& inst : instances) n += meshes[inst.mesh].triangle_count();
    return n;
}

uint64_t InstancedScene::stored_triangle_count() const {
    uint64_t n = 0;
    for (const TriangleMesh& mesh : meshes) n += mesh.triangle_count();
    return n;
}

AABB InstancedScene::bounds() const {
    AABB b = AABB::empty();
    for (const Instance& inst : instances) {
        const TriangleMesh& mesh = meshes[inst.mesh];
        for (uint32_t v : mesh.indices) b.extend(inst.transform.point(mesh.vertices[v]));
    }
    return b;
}

InstancedScene single_instance(TriangleMesh mesh) {
    InstancedScene s;
    s.materials = std::move(mesh.materials);
    mesh.materials.clear();
    s.dropped = mesh.dropped;
    s.meshes.push_back(std::move(mesh));
    s.instances.push_back(Instance{});
    return s;
}

TriangleMesh flatten(const InstancedScene& scene, bool keep_all) {
    TriangleMesh out;
    out.materials = scene.materials;
    out.dropped = scene.dropped;
    bool texcoords = false, normals = false;
    uint64_t vertices = 0;
    for (const Instance& inst : scene.instances) {
        texcoords = texcoords || !scene.meshes[inst.mesh].texcoords.empty();
        normals = normals || !scene.meshes[inst.mesh].normals.empty();
        vertices += scene.meshes[inst.mesh].vertices.size();
    }
    if (vertices > 0xffffffffull)
        throw Error("the flattened scene would have " + std::to_string(vertices) +
                    " vertices, more than a mesh can index (2^32 - 1)");
    out.vertices.reserve(vertices);
    out.indices.reserve(3 * scene.triangle_count());
    out.material_ids.reserve(scene.triangle_count());
    for (const Instance& inst : scene.instances) {
        const TriangleMesh& mesh = scene.meshes[inst.mesh];
        const Transform normal_map = inst.transform.normal_map();
        const auto base = uint32_t(out.vertices.size());
        for (const Vec3& v : mesh.vertices) out.vertices.push_back(flush_denormals(inst.transform.point(v)));
        for (size_t t = 0; t < mesh.triangle_count(); ++t) {
            const uint32_t* idx = &mesh.indices[3 * t];
            const Vec3 a = out.vertices[base + idx[0]], b = out.vertices[base + idx[1]],
                       c = out.vertices[base + idx[2]];
            const TriangleCheck check = check_triangle(a, b, c);
            if (!keep_all && !count_drop(check, out.dropped)) continue;
            out.indices.insert(out.indices.end(), {base + idx[0], base + idx[1], base + idx[2]});
            const int32_t id = mesh.material_ids.empty() ? -1 : mesh.material_ids[t];
            out.material_ids.push_back(id < 0 ? -1 : id + inst.material_offset);
            if (texcoords) {
                if (mesh.texcoords.empty())
                    out.texcoords.insert(out.texcoords.end(), 6, 0.0f);
                else
                    out.texcoords.insert(out.texcoords.end(), mesh.texcoords.begin() + 6 * t,
                                         mesh.texcoords.begin() + 6 * t + 6);
            }
            if (normals) {
                const bool given = !mesh.normals.empty();
                const Vec3* n = given ? &mesh.normals[3 * t] : nullptr;
                append_corner_normals(out, given, given ? normal_map.vector(n[0]) : Vec3{},
                                      given ? normal_map.vector(n[1]) : Vec3{},
                                      given ? normal_map.vector(n[2]) : Vec3{});
            }
        }
    }
    return out;
}

std::vector<uint64_t> instance_first_ids(const InstancedScene& scene) {
    std::vector<uint64_t> first(1, 0);
    for (const Instance& inst : scene.instances)
        first.push_back(first.back() + scene.meshes[inst.mesh].triangle_count());
    return first;
}

uint64_t placed_mesh_count(const InstancedScene& scene) {
    std::vector<bool> used(scene.meshes.size(), false);
    for (const Instance& i : scene.instances) used[i.mesh] = true;
    return uint64_t(std::count(used.begin(), used.end(), true));
}

TriangleMesh single_mesh(InstancedScene scene, bool allow_flatten, const std::string& what) {
    if (scene.is_instanced() && !allow_flatten) {
        const uint64_t meshes = placed_mesh_count(scene);
        throw Error(what + " places " + std::to_string(meshes) + (meshes == 1 ? " mesh " : " meshes ") +
                    std::to_string(scene.instances.size()) +
                    " times (a mesh more than once), and one mesh is needed here: flattening makes it one mesh of " +
                    std::to_string(scene.triangle_count()) + " triangles");
    }
    if (scene.instances.size() == 1 && scene.instances[0].transform.is_identity()) {
        TriangleMesh mesh = std::move(scene.meshes[scene.instances[0].mesh]);
        mesh.materials = std::move(scene.materials);
        mesh.dropped = scene.dropped;
        return mesh;
    }
    return flatten(scene);
}

InstancedScene make_instances(TriangleMesh base, uint32_t n, uint64_t seed) {
    BVHLAB_CHECK(n >= 1, "gen:instances needs at least one instance");
    const AABB box = base.bounds();
    const Vec3 centre = box.center();
    const float size = length(box.extent());
    InstancedScene s = single_instance(std::move(base));
    s.instances.clear();
    // Instances of mean scale 1 in a cube of side 0.6 cbrt(n) diagonals: neighbours overlap.
    const float side = 0.6f * size * std::cbrt(float(n));
    auto unit = [seed](uint64_t i, uint64_t k) { return double(unit_float(splitmix64(seed * 0x9e37 + 8 * i + k))); };
    for (uint32_t i = 0; i < n; ++i) {
        // A uniform rotation from a uniform unit quaternion (Shoemake 1992).
        const double u1 = unit(i, 0), u2 = 2.0 * M_PI * unit(i, 1), u3 = 2.0 * M_PI * unit(i, 2);
        const double qx = std::sqrt(1 - u1) * std::sin(u2), qy = std::sqrt(1 - u1) * std::cos(u2);
        const double qz = std::sqrt(u1) * std::sin(u3), qw = std::sqrt(u1) * std::cos(u3);
        const double r[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw),     2 * (qx * qz + qy * qw),
                             2 * (qx * qy + qz * qw),     1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw),
                             2 * (qx * qz - qy * qw),     2 * (qy * qz + qx * qw),     1 - 2 * (qx * qx + qy * qy)};
        const double scale = 0.5 + unit(i, 3);
        const Vec3 place{float(side * (unit(i, 4) - 0.5)), float(side * (unit(i, 5) - 0.5)),
                         float(side * (unit(i, 6) - 0.5))};
        Instance inst;
        for (int row = 0; row < 3; ++row) {
            double t = place[row];
            for (int k = 0; k < 3; ++k) {
                inst.transform.m[4 * row + k] = float(scale * r[3 * row + k]);
                t -= scale * r[3 * row + k] * centre[k];  // turn about the mesh's centre
            }
            inst.transform.m[4 * row + 3] = float(t);
        }
        s.instances.push_back(inst);
    }
    return s;
}

}  // namespace bvhlab::scene
