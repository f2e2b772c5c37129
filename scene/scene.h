// SPDX-License-Identifier: MIT
// A scene as files describe it: meshes, and instances that place them in the world (a 3x4
// transform, a mesh, a material offset), with the camera the file names. A mesh used by several
// instances is stored once. flatten() turns any scene into one TriangleMesh, which is what the
// single-level structures, the oracle and the renderer take.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/vec3.h"
#include "scene/mesh.h"

namespace bvhlab::scene {

/// An affine map from an instance's object space to the world: x' = M x + t, stored as the
/// three rows of [M | t] (row-major 3x4, as Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR).
struct Transform {
    float m[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    Vec3 point(Vec3 p) const {
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
    Vec3 vector(Vec3 v) const {
        return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                m[8] * v.x + m[9] * v.y + m[10] * v.z};
    }
    /// A surface normal of object space in the world: n by the inverse transpose of M, as a unit
    /// vector (0 for a zero or non-finite n). Normals of a non-uniformly scaled, sheared or
    /// mirrored mesh stay perpendicular to its transformed surface.
    Vec3 normal(Vec3 n) const { return unit_or_zero(normal_map().vector(n)); }
    /// The map normal() applies before normalising: M's cofactor matrix (det(M) M^-T) times
    /// the sign of det(M), no translation. For many normals under one transform.
    Transform normal_map() const;
    bool is_identity() const { return *this == Transform{}; }
    /// The determinant of M (0 for a map that flattens space, which no instance may have).
    double determinant() const;
    /// The inverse map. Precondition: determinant() != 0.
    Transform inverse() const;
    /// This map after `inner`: (this * inner)(x) = this(inner(x)).
    Transform operator*(const Transform& inner) const;
    bool operator==(const Transform& o) const {
        for (int i = 0; i < 12; ++i)
            if (m[i] != o.m[i]) return false;
        return true;
    }
};

/// One placement of a mesh in the world.
struct Instance {
    Transform transform;          ///< object space -> world
    uint32_t mesh = 0;            ///< index into InstancedScene::meshes
    int32_t material_offset = 0;  ///< added to the mesh's material ids (-1 stays -1)
};

/// A camera that a scene file gives (glTF cameras): eye, target and up in world space, and the
/// full vertical field of view.
struct SceneCamera {
    Vec3 eye{0, 0, 1}, target{0, 0, 0}, up{0, 1, 0};
    float fov_y_deg = 45.0f;
};

/// Meshes placed by instances. Every mesh's material ids index `materials` (the meshes' own
/// material tables are empty), after adding the instance's material_offset.
struct InstancedScene {
    std::vector<TriangleMesh> meshes;
    std::vector<Instance> instances;
    std::vector<Material> materials;
    std::optional<SceneCamera> camera;  ///< the file's first camera, when it has one
    DropCounts dropped;                 ///< triangles the loader dropped, over all meshes

    /// True when some mesh is placed more than once: the scene is then smaller than its
    /// flattened form, and a single-level structure needs flatten().
    bool is_instanced() const;
    /// Triangles in the world: every instance's mesh counted once per instance.
    uint64_t triangle_count() const;
    /// Triangles stored: every mesh counted once.
    uint64_t stored_triangle_count() const;
    /// World-space bounds of every instance's triangles.
    AABB bounds() const;
};

/// A scene of one mesh placed once, as it is (the mesh's materials become the scene's).
InstancedScene single_instance(TriangleMesh mesh);

/// One mesh with every instance's triangles in world space, in instance order, with the scene's
/// materials (ids offset per instance) and texture coordinates. Throws bvhlab::Error when the
/// result would exceed 2^32 - 1 vertices. Triangles that a transform makes degenerate are
/// dropped (and counted), unless `keep_all`: then triangle ids are the scene-wide ids of
/// two-level hits (instance i's triangle k is the triangles of instances 0..i-1 plus k), which
/// is how hits of a two-level BVH are checked in world space.
TriangleMesh flatten(const InstancedScene& scene, bool keep_all = false);

/// Where each instance's triangles start in the scene-wide numbering of two-level hits and of
/// flatten(scene, true): first[i] is the triangles of instances 0..i-1, and the last entry (one
/// past the instances) is every instance's.
std::vector<uint64_t> instance_first_ids(const InstancedScene& scene);

/// Meshes that some instance places.
uint64_t placed_mesh_count(const InstancedScene& scene);

/// The scene as one mesh, for the single-level structures: its mesh as it is when it is one
/// instance with the identity transform, else flatten(scene). A scene that places some mesh
/// more than once is flattened only when `allow_flatten` (Python's flatten=True); otherwise a one-line
/// bvhlab::Error names `what`, its meshes and instances, and the flattened size.
TriangleMesh single_mesh(InstancedScene scene, bool allow_flatten, const std::string& what);

/// `n` copies of `base` (n >= 1), each turned by a uniformly random rotation, scaled by a
/// factor in [0.5, 1.5] and placed at random in a cube whose side grows as the cube root of n,
/// so that neighbours overlap on purpose: `gen:instances:SCENE:N[:SEED]`. The same for the same
/// (base, n, seed).
InstancedScene make_instances(TriangleMesh base, uint32_t n, uint64_t seed);

}  // namespace bvhlab::scene
