// SPDX-License-Identifier: MIT
// Scene files through Assimp (glTF, GLB, PLY), instanced scenes and their flattening, and the
// generated gen:instances scenes.
#include "scene/io/scene_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "accel/core/check.h"
#include "scene/io/procedural.h"
#include "scene/scene.h"
#include "tests/support/test_support.h"

namespace bvhlab::scene {
namespace {

using test::TempFile;

/// Loads `path` and expects one error line containing `what`.
void expect_error(const std::string& path, const std::string& what) {
    try {
        load_assimp(path);
        FAIL() << "no error for " << path;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
        EXPECT_NE(msg.find(path), std::string::npos) << "the message names the file: " << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
}

void expect_near(Vec3 a, Vec3 b, float eps = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}

const Material& material_named(const InstancedScene& s, const std::string& name) {
    for (const Material& m : s.materials)
        if (m.name == name) return m;
    throw Error("no material " + name);
}

/// The world-space triangles of every instance, each as its three vertices, sorted.
std::vector<std::array<float, 9>> world_triangles(const TriangleMesh& m) {
    std::vector<std::array<float, 9>> out;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        std::array<float, 9> v{};
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) v[3 * k + c] = m.vertex(t, k)[c];
        out.push_back(v);
    }
    std::sort(out.begin(), out.end());
    return out;
}

Transform rotation_about_y_90() {
    Transform t;
    const float m[12] = {0, 0, 1, 0, 0, 1, 0, 0, -1, 0, 0, 0};
    std::copy(m, m + 12, t.m);
    return t;
}

}  // namespace

TEST(SceneFile, PlyAsciiAndBinaryGiveTheSameCube) {
    const InstancedScene a = load_assimp(test::data_dir() + "/cube_ascii.ply");
    const InstancedScene b = load_assimp(test::data_dir() + "/cube_binary.ply");
    for (const InstancedScene* s : {&a, &b}) {
        EXPECT_FALSE(s->is_instanced());
        ASSERT_EQ(s->instances.size(), 1u);
        EXPECT_TRUE(s->instances[0].transform.is_identity());
        EXPECT_EQ(s->triangle_count(), 12u);
        EXPECT_TRUE(s->materials.empty()) << "PLY has no materials: Assimp's made-up one is not used";
        for (int32_t id : s->meshes[0].material_ids) EXPECT_EQ(id, -1);
        expect_near(s->bounds().lo, {0, 0, 0});
        expect_near(s->bounds().hi, {1, 1, 1});
        EXPECT_NEAR(flatten(*s).surface_area(), 6.0, 1e-9);
        EXPECT_FALSE(s->camera.has_value());
    }
    EXPECT_EQ(world_triangles(flatten(a)), world_triangles(flatten(b)));
}

TEST(SceneFile, GltfNodesBecomeInstancesOfSharedMeshes) {
    for (const char* name : {"/instances.gltf", "/instances.glb"}) {
        SCOPED_TRACE(name);
        std::vector<std::string> warnings;
        const InstancedScene s = load_assimp(test::data_dir() + name, &warnings);
        // The cube (two primitives) is placed by three nodes: one mesh, three instances. The
        // floor and the lamp, placed once each, are merged into one world-space mesh.
        EXPECT_TRUE(s.is_instanced());
        ASSERT_EQ(s.meshes.size(), 2u);
        ASSERT_EQ(s.instances.size(), 4u);
        EXPECT_EQ(s.meshes[0].triangle_count(), 4u);  // floor + lamp
        EXPECT_EQ(s.meshes[1].triangle_count(), 12u);
        EXPECT_EQ(s.stored_triangle_count(), 16u);
        EXPECT_EQ(s.triangle_count(), 4u + 3u * 12u);
        EXPECT_TRUE(s.instances[0].transform.is_identity());
        EXPECT_EQ(s.instances[0].mesh, 0u);
        // cube-a at the origin; cube-b at (2, 0, 0) scaled by 0.5; cube-c one unit along the
        // x of a parent turned 90 degrees about y, i.e. at (0, 0, -1) with x turned to -z.
        const Transform& ta = s.instances[1].transform;
        const Transform& tb = s.instances[2].transform;
        const Transform& tc = s.instances[3].transform;
        EXPECT_TRUE(ta.is_identity());
        expect_near(tb.point({1, 1, 1}), {2.5f, 0.5f, 0.5f});
        expect_near(tc.point({0, 0, 0}), {0, 0, -1});
        expect_near(tc.point({1, 0, 0}), {0, 0, -2});
        expect_near(tc.vector({0, 1, 0}), {0, 1, 0});
        expect_near(s.bounds().lo, {-2, -0.5f, -2});
        expect_near(s.bounds().hi, {2.5f, 3, 2});

        // Materials: plastic, conductor, glass and emitter, as the README's table maps them.
        const Material& plastic = material_named(s, "red-plastic");
        EXPECT_EQ(plastic.illum, 2);
        expect_near(plastic.diffuse, {0.8f, 0.1f, 0.1f});
        EXPECT_NEAR(plastic.shininess, 2.0f / std::pow(0.3f, 4.0f) - 2.0f, 1e-2f);
        const Material& gold = material_named(s, "gold");
        EXPECT_EQ(gold.illum, 3);
        expect_near(gold.specular, {1.0f, 0.78f, 0.34f});
        const Material& glass = material_named(s, "glass");
        EXPECT_LT(glass.dissolve, 1.0f);
        EXPECT_NEAR(glass.ior, 1.5f, 1e-6f);
        expect_near(material_named(s, "lamp").emission, {1.0f, 0.9f, 0.8f});
        for (const Material& m : s.materials) EXPECT_EQ(material_problem(m), "") << m.name;
        // The cube's two primitives keep their own materials.
        const TriangleMesh& cube = s.meshes[1];
        EXPECT_EQ(s.materials[cube.material_ids.front()].name, "red-plastic");
        EXPECT_EQ(s.materials[cube.material_ids.back()].name, "glass");

        // The camera: at its node's translation, looking down -z, yfov 0.8 rad.
        ASSERT_TRUE(s.camera.has_value());
        expect_near(s.camera->eye, {0.5f, 0.5f, 6});
        expect_near(s.camera->target, {0.5f, 0.5f, 5});
        expect_near(s.camera->up, {0, 1, 0});
        EXPECT_NEAR(s.camera->fov_y_deg, 0.8 * 180.0 / M_PI, 1e-3);
        EXPECT_TRUE(warnings.empty()) << warnings.front();  // KHR_materials_transmission is implemented
    }
    EXPECT_EQ(scene_hash(flatten(load_assimp(test::data_dir() + "/instances.gltf"))),
              scene_hash(flatten(load_assimp(test::data_dir() + "/instances.glb"))));
}

TEST(SceneFile, FlattenPlacesEveryInstanceInTheWorld) {
    const InstancedScene s = load_assimp(test::data_dir() + "/instances.gltf");
    const TriangleMesh flat = flatten(s);
    ASSERT_EQ(flat.triangle_count(), 40u);
    EXPECT_EQ(flat.materials.size(), s.materials.size());
    EXPECT_EQ(flat.texcoords.size(), 6 * flat.triangle_count()) << "the floor's texcoords, zeros elsewhere";
    // The area: floor 16, lamp 1, cubes 6 + 6 / 4 + 6.
    EXPECT_NEAR(flat.surface_area(), 16.0 + 1.0 + 6.0 + 1.5 + 6.0, 1e-4);
    // Instance by instance, the same triangles as transforming the mesh by hand.
    TriangleMesh by_hand;
    for (const Instance& inst : s.instances) {
        const TriangleMesh& m = s.meshes[inst.mesh];
        for (size_t t = 0; t < m.triangle_count(); ++t)
            add_triangle_checked(by_hand, inst.transform.point(m.vertex(t, 0)), inst.transform.point(m.vertex(t, 1)),
                                 inst.transform.point(m.vertex(t, 2)), -1);
    }
    EXPECT_EQ(world_triangles(flat), world_triangles(by_hand));
}

// Normals go through the inverse transpose: under a non-uniform scale, a shear or a mirror the
// flattened corner normals stay perpendicular to the flattened triangle (M n would not), unit
// length; an instance of a mesh without normals gets zeros beside one with them.
TEST(SceneFile, FlattenTurnsNormalsWithTheSurface) {
    InstancedScene s;
    TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 1, 0, 0, 0, 1}});
    const Vec3 n = unit_or_zero(cross(m.vertex(0, 1) - m.vertex(0, 0), m.vertex(0, 2) - m.vertex(0, 0)));
    append_corner_normals(m, true, n, n * 3.0f, n);
    s.meshes.push_back(m);
    s.meshes.push_back(test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}}));
    Transform stretch, shear, mirror;
    stretch.m[0] = 2.0f;  // x doubled
    stretch.m[3] = 5.0f;  // and moved
    shear.m[1] = 0.7f;    // x += 0.7 y
    shear.m[10] = 0.25f;  // z quartered
    mirror.m[5] = -1.0f;  // y mirrored
    for (const Transform& t : {stretch, shear, mirror}) s.instances.push_back({t, 0, 0});
    s.instances.push_back({Transform{}, 1, 0});
    const TriangleMesh flat = flatten(s);
    ASSERT_EQ(flat.triangle_count(), 4u);
    ASSERT_EQ(flat.normals.size(), 12u);
    for (size_t t = 0; t < 3; ++t) {
        SCOPED_TRACE(t);
        const Vec3 ng =
            unit_or_zero(cross(flat.vertex(t, 1) - flat.vertex(t, 0), flat.vertex(t, 2) - flat.vertex(t, 0)));
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(length(flat.normals[3 * t + k]), 1.0f, 1e-6f);
            EXPECT_NEAR(std::fabs(dot(flat.normals[3 * t + k], ng)), 1.0f, 1e-6f);
        }
    }
    // The stretch by hand: M^-T n = (n.x / 2, n.y, n.z), normalised; M n would be (2 n.x, n.y, n.z).
    expect_near(flat.normals[0], unit_or_zero({n.x / 2.0f, n.y, n.z}));
    for (int k = 9; k < 12; ++k) expect_near(flat.normals[size_t(k)], {0.0f, 0.0f, 0.0f}, 0.0f);
    // A turn about z by 90 degrees turns a normal with it.
    Transform turn;
    turn.m[0] = 0.0f, turn.m[1] = -1.0f, turn.m[4] = 1.0f, turn.m[5] = 0.0f;
    expect_near(turn.normal({1.0f, 0.0f, 0.0f}), {0.0f, 1.0f, 0.0f});
    expect_near(turn.normal({0.0f, 0.0f, 0.0f}), {0.0f, 0.0f, 0.0f}, 0.0f);
}

TEST(SceneFile, UnitOrZeroNormalisesAcrossFloatRange) {
    // Float when the squared length is in float's normal range, double outside it: tiny and huge
    // normals (a file's unnormalised ones, a turned instance's) still become unit vectors.
    expect_near(unit_or_zero({3.0f, 0.0f, 4.0f}), {0.6f, 0.0f, 0.8f});
    expect_near(unit_or_zero({3e-20f, 0.0f, 4e-20f}), {0.6f, 0.0f, 0.8f});  // squared: 2.5e-39, below float's
    expect_near(unit_or_zero({0.0f, -3e20f, 4e20f}), {0.0f, -0.6f, 0.8f});  // squared: 2.5e41, above float's
    expect_near(unit_or_zero({1e-40f, 0.0f, 0.0f}), {1.0f, 0.0f, 0.0f});    // a denormal component
    expect_near(unit_or_zero({0.0f, 0.0f, 0.0f}), {0.0f, 0.0f, 0.0f}, 0.0f);
    expect_near(unit_or_zero({INFINITY, 0.0f, 0.0f}), {0.0f, 0.0f, 0.0f}, 0.0f);
    expect_near(unit_or_zero({NAN, 1.0f, 0.0f}), {0.0f, 0.0f, 0.0f}, 0.0f);
}

// Vertex normals from glTF (NORMAL) and PLY (nx ny nz), in world space for meshes placed once;
// meshes of the same file without them get zeros.
TEST(SceneFile, ReadsVertexNormalsOfGltfAndPly) {
    const InstancedScene s = load_assimp(test::data_dir() + "/instances.gltf");
    size_t floor = 0;
    for (const TriangleMesh& m : s.meshes) {
        ASSERT_EQ(m.normals.size(), 3 * m.triangle_count());
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const bool is_floor = m.material_ids[t] == int32_t(&material_named(s, "gold") - s.materials.data());
            floor += is_floor;
            for (int k = 0; k < 3; ++k)
                expect_near(m.normals[3 * t + size_t(k)], is_floor ? Vec3{0, 1, 0} : Vec3{0, 0, 0}, 0.0f);
        }
    }
    EXPECT_EQ(floor, 2u);
    TempFile ply("normals.ply",
                 "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "property float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
                 "property list uchar int vertex_indices\nend_header\n0 0 0 0 0 2\n1 0 0 0 0.6 0.8\n0 1 0 0 0 1\n"
                 "3 0 1 2\n");
    const TriangleMesh m = flatten(load_assimp(ply.path()));
    ASSERT_EQ(m.normals.size(), 3u);
    expect_near(m.normals[0], {0, 0, 1});
    expect_near(m.normals[1], {0, 0.6f, 0.8f});
    expect_near(m.normals[2], {0, 0, 1});
}

TEST(SceneFile, FlattenOffsetsMaterialsAndDropsWhatATransformDegenerates) {
    InstancedScene s;
    TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}});
    m.material_ids = {1};
    m.texcoords = {0, 0, 1, 0, 0, 1};
    s.meshes.push_back(m);
    s.materials.resize(4);
    s.instances.push_back({Transform{}, 0, 0});
    s.instances.push_back({Transform{}, 0, 2});
    Transform squash;  // z and y to 0: the triangle loses its area
    squash.m[5] = 0.0f;
    s.instances.push_back({squash, 0, 1});
    const TriangleMesh flat = flatten(s);
    ASSERT_EQ(flat.triangle_count(), 2u);
    EXPECT_EQ(flat.material_ids, (std::vector<int32_t>{1, 3}));
    EXPECT_EQ(flat.texcoords.size(), 12u);
    EXPECT_EQ(flat.dropped.zero_area, 1u);
    // -1 stays -1 whatever the offset.
    s.meshes[0].material_ids = {-1};
    EXPECT_EQ(flatten(s).material_ids, (std::vector<int32_t>{-1, -1}));
}

TEST(SceneFile, TransformAlgebra) {
    Transform a = rotation_about_y_90();
    a.m[3] = 1.0f;
    a.m[7] = -2.0f;
    a.m[0] = 0.0f;
    Transform b;
    for (int i = 0; i < 12; ++i) b.m[i] = float(i % 5) * 0.25f + (i % 4 == i / 4 ? 1.0f : 0.0f);
    EXPECT_NEAR(rotation_about_y_90().determinant(), 1.0, 1e-12);
    EXPECT_NEAR(Transform{}.determinant(), 1.0, 0.0);
    const Vec3 p{0.3f, -1.2f, 2.5f};
    expect_near((a * b).point(p), a.point(b.point(p)), 1e-4f);
    expect_near(b.inverse().point(b.point(p)), p, 1e-4f);
    expect_near(a.inverse().point(a.point(p)), p, 1e-4f);
    expect_near((b * b.inverse()).point(p), p, 1e-4f);
    expect_near(rotation_about_y_90().vector({1, 0, 0}), {0, 0, -1});
    Transform singular;
    singular.m[0] = 0.0f;
    EXPECT_EQ(singular.determinant(), 0.0);
}

TEST(SceneFile, GeneratedInstancesAreSeededRotatedAndOverlapping) {
    const TriangleMesh base = make_procedural(ProceduralKind::kStructured, 500, 2);
    const InstancedScene s = make_instances(base, 50, 7);
    ASSERT_EQ(s.instances.size(), 50u);
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_TRUE(s.is_instanced());
    EXPECT_EQ(s.triangle_count(), 50u * base.triangle_count());
    double min_scale = 10, max_scale = 0;
    bool turned = false;
    for (const Instance& inst : s.instances) {
        // A rotation times a scale: M^T M = s^2 I.
        const Transform& t = inst.transform;
        const Vec3 x = t.vector({1, 0, 0}), y = t.vector({0, 1, 0}), z = t.vector({0, 0, 1});
        const double sc = length(x);
        EXPECT_NEAR(length(y), sc, 1e-4 * sc);
        EXPECT_NEAR(length(z), sc, 1e-4 * sc);
        EXPECT_NEAR(dot(x, y), 0.0, 1e-4 * sc * sc);
        EXPECT_NEAR(dot(y, z), 0.0, 1e-4 * sc * sc);
        EXPECT_GT(t.determinant(), 0.0) << "a rotation, not a reflection";
        min_scale = std::min(min_scale, sc);
        max_scale = std::max(max_scale, sc);
        turned = turned || std::fabs(x.x / sc - 1.0f) > 0.1f;
    }
    EXPECT_GE(min_scale, 0.5 - 1e-4);
    EXPECT_LE(max_scale, 1.5 + 1e-4);
    EXPECT_GT(max_scale - min_scale, 0.5) << "scales spread over [0.5, 1.5]";
    EXPECT_TRUE(turned);
    // Neighbours overlap: some pair of instance boxes intersects.
    std::vector<AABB> boxes;
    for (const Instance& inst : s.instances) {
        AABB b = AABB::empty();
        for (const Vec3& v : base.vertices) b.extend(inst.transform.point(v));
        boxes.push_back(b);
    }
    size_t overlapping = 0;
    for (size_t i = 0; i < boxes.size(); ++i)
        for (size_t j = i + 1; j < boxes.size(); ++j) overlapping += boxes[i].overlaps(boxes[j]);
    EXPECT_GT(overlapping, 10u);
    // Seeded: the same seed gives the same scene, another seed another one.
    EXPECT_EQ(scene_hash(flatten(make_instances(base, 50, 7))), scene_hash(flatten(s)));
    EXPECT_NE(scene_hash(flatten(make_instances(base, 50, 8))), scene_hash(flatten(s)));
}

TEST(SceneFile, BadFilesGetOneLineNamingTheFile) {
    TempFile unknown("scene.xyz", "nothing\n");
    expect_error(unknown.path(), "unknown scene format '.xyz'");
    TempFile no_ext("scene", "ply\n");
    expect_error(no_ext.path(), "no file extension");
    expect_error("/nonexistent/bvhlab/scene.gltf", "does not exist");
    const std::string dir =
        std::filesystem::temp_directory_path() / ("bvhlab_test_dir_" + std::to_string(getpid()) + ".glb");
    std::filesystem::create_directories(dir);
    expect_error(dir, "directory");
    std::filesystem::remove(dir);

    // A glTF that requires an extension bvhlab does not implement.
    std::string gltf = test::read_file_bytes(test::data_dir() + "/instances.gltf");
    const std::string needs = gltf.substr(0, gltf.find('{') + 1) + "\"extensionsRequired\": [\"EXT_made_up\"]," +
                              gltf.substr(gltf.find('{') + 1);
    TempFile required("required.gltf", needs);
    expect_error(required.path(), "requires the glTF extension EXT_made_up");

    // An extension used but not required: read, with a warning naming it.
    std::string uses = gltf;
    const std::string list = "\"extensionsUsed\": [";
    ASSERT_NE(uses.find(list), std::string::npos);
    uses.insert(uses.find(list) + list.size(), "\"EXT_made_up\", ");
    TempFile used("used.gltf", uses);
    std::vector<std::string> warnings;
    EXPECT_EQ(load_assimp(used.path(), &warnings).triangle_count(), 40u);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("EXT_made_up"), std::string::npos) << warnings[0];

    // A truncated GLB, a damaged glTF.
    const std::string glb = test::read_file_bytes(test::data_dir() + "/instances.glb");
    TempFile truncated("truncated.glb", glb.substr(0, glb.size() / 2));
    expect_error(truncated.path(), "is a damaged GLB file: its header claims");
    TempFile damaged("damaged.gltf", gltf.substr(0, gltf.size() / 3));
    expect_error(damaged.path(), "Assimp cannot read it");

    // PLY: no faces; every face degenerate; an index out of range; NaN coordinates dropped.
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\n";
    TempFile points("points.ply", head +
                                      "element face 0\nproperty list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 0\n0 1 0\n");
    expect_error(points.path(), "no triangles");
    TempFile flat("flat.ply", head +
                                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                  "0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n");
    expect_error(flat.path(), "no usable triangles");
    TempFile range("range.ply", head +
                                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    EXPECT_THROW(load_assimp(range.path()), Error);
    TempFile nan("nan.ply",
                 "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                 "0 0 0\n1 0 0\n0 1 0\nnan 0 1\n3 0 1 2\n3 0 1 3\n");
    const InstancedScene with_nan = load_assimp(nan.path());
    EXPECT_EQ(with_nan.triangle_count(), 1u);
    EXPECT_EQ(with_nan.dropped.non_finite, 1u);

    // A glTF material outside the renderer's domain.
    std::string bright = gltf;
    const size_t at = bright.find("0.8,", bright.find("red-plastic"));
    ASSERT_NE(at, std::string::npos);
    bright.replace(at, 4, "2.5,");
    TempFile too_bright("bright.gltf", bright);
    expect_error(too_bright.path(), "material 'red-plastic': Kd 2.5");
}

// glTF's normalTexture is the material's tangent-space normal map, its scale the multiplier.
TEST(SceneFile, GltfNormalTextureIsTheNormalMap) {
    nlohmann::json doc = nlohmann::json::parse(test::read_file_bytes(test::data_dir() + "/instances.gltf"));
    doc["images"] = {{{"uri", "maps/bumps.png"}}};
    doc["textures"] = {{{"source", 0}}};
    doc["materials"][0]["normalTexture"] = {{"index", 0}, {"scale", 0.5}};
    doc["materials"][1]["normalTexture"] = {{"index", 0}};
    TempFile file("normal_texture.gltf", doc.dump());  // the buffer is a data: URI
    const InstancedScene s = load_assimp(file.path());
    auto named = [&](const std::string& name) {  // Assimp orders the materials its own way
        for (const Material& m : s.materials)
            if (m.name == name) return m;
        ADD_FAILURE() << "no material " << name;
        return Material{};
    };
    EXPECT_EQ(named("red-plastic").normal_texture, "maps/bumps.png");
    EXPECT_FLOAT_EQ(named("red-plastic").bump_multiplier, 0.5f);
    EXPECT_EQ(named("red-plastic").bump_texture, "");
    EXPECT_EQ(named("gold").normal_texture, "maps/bumps.png");
    EXPECT_FLOAT_EQ(named("gold").bump_multiplier, 1.0f);
    EXPECT_EQ(named("glass").normal_texture, "");
}

TEST(SceneFile, LoadSceneFileDispatchesOnTheExtension) {
    EXPECT_TRUE(is_obj_path("a/b/Scene.OBJ"));
    EXPECT_FALSE(is_obj_path("a/b.obj/scene.glb"));
    EXPECT_FALSE(is_obj_path("obj"));
    const SceneFileLoad obj = load_scene_file(test::data_dir() + "/cornell_box.obj", "", "test");
    EXPECT_EQ(obj.scene.triangle_count(), 32u);
    EXPECT_FALSE(obj.dependencies.empty());
    EXPECT_EQ(obj.scene_hash, scene_hash(flatten(obj.scene)));
    EXPECT_EQ(obj.scene.materials.size(), load_obj(test::data_dir() + "/cornell_box.obj").materials.size());
    EXPECT_FALSE(obj.scene.materials.empty()) << "the OBJ's materials become the scene's";
    const SceneFileLoad glb = load_scene_file(test::data_dir() + "/instances.glb", "", "test");
    EXPECT_EQ(glb.scene.instances.size(), 4u);
    EXPECT_EQ(glb.scene_hash, "");
}

}  // namespace bvhlab::scene
