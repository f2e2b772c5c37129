// SPDX-License-Identifier: MIT
// OBJ loading: good files, every kind of bad file (written by the test), dropped triangles.
#include "scene/io/obj_loader.h"

#include <gtest/gtest.h>

#include <filesystem>

#include <cmath>

#include "accel/core/check.h"
#include "tests/support/test_support.h"

namespace bvhlab {
namespace {

using test::TempFile;

/// Loads `text` as an OBJ and expects an Error whose message contains `what`.
void expect_load_error(const std::string& name, const std::string& text, const std::string& what) {
    TempFile f(name, text);
    try {
        scene::load_obj(f.path());
        FAIL() << "no error for " << name;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "error must be one line: " << msg;
    }
}

const char* kTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

}  // namespace

TEST(ObjLoader, MissingFileAndDirectory) {
    EXPECT_THROW(scene::load_obj("/nonexistent/bvhlab/scene.obj"), Error);
    try {
        scene::load_obj("/tmp");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("directory"), std::string::npos);
    }
}

TEST(ObjLoader, MalformedLines) {
    expect_load_error("bad_v.obj", std::string("v 0 0 0\nv 1 0 abc\nv 0 1 0\nf 1 2 3\n"), "line 2");
    expect_load_error("short_v.obj", std::string("v 0 0\nf 1 1 1\n"), "needs 3 numbers");
    expect_load_error("bad_f.obj", std::string(kTri) + "f 1 2 x\n", "bad vertex reference");
    expect_load_error("zero_f.obj", std::string(kTri) + "f 0 1 2\n", "line 4");
    expect_load_error("two_f.obj", std::string(kTri) + "f 1 2\n", "at least 3 vertices");
    // 23 digits: beyond int, refused (the in-place reader once overflowed a long on it).
    expect_load_error("long_ref.obj", std::string(kTri) + "f 1/1 11111111111111111111111 2\n", "bad vertex reference");
    expect_load_error("long_ref2.obj", std::string(kTri) + "f 1 2 3/99999999999\n", "bad vertex reference");
}

TEST(ObjLoader, FaceIndexOutOfRange) {
    expect_load_error("range.obj", std::string(kTri) + "f 1 2 9\n", "out of range");
    expect_load_error("neg_range.obj", std::string(kTri) + "f -1 -2 -4\n", "out of range");
}

TEST(ObjLoader, EmptyAndAllDropped) {
    expect_load_error("empty.obj", "", "no usable triangles");
    expect_load_error("comments.obj", "# nothing\n\n", "no usable triangles");
    expect_load_error("degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", "all 1 were dropped");
}

TEST(ObjLoader, DropsNonFiniteAndZeroAreaTriangles) {
    TempFile f("drops.obj", std::string(kTri) +
                                "v nan 0 0\nv 1 1 1\nv 2 2 2\nv inf 0 1\n"
                                "f 1 2 3\nf 4 2 3\nf 1 5 6\nf 7 2 3\nf 1 2 3\n");
    scene::TriangleMesh m = scene::load_obj(f.path());
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(m.dropped.non_finite, 2u);
    EXPECT_EQ(m.dropped.zero_area, 1u);
}

TEST(ObjLoader, TriangulatesPolygonsAndNegativeIndices) {
    TempFile f("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -4 -3 -2\n");
    scene::TriangleMesh m = scene::load_obj(f.path());
    ASSERT_EQ(m.triangle_count(), 3u);
    EXPECT_NEAR(m.surface_area(), 1.5, 1e-6);
}

TEST(ObjLoader, LargePolygonsAreFannedInPlaceAndFullyChecked) {
    // A convex 1000-gon (more than the 64 references ear clipping is given): 998 triangles of
    // its fan, in place between a triangle before it and one after, with the polygon's area.
    const int n = 1000;
    std::string text = std::string(kTri) + "f 1 2 3\n";
    for (int i = 0; i < n; ++i)
        text += "v " + std::to_string(std::cos(2 * M_PI * i / n)) + " " + std::to_string(std::sin(2 * M_PI * i / n)) +
                " 5\n";
    text += "f";
    for (int i = 0; i < n; ++i) text += " " + std::to_string(4 + i) + (i % 2 ? "//" + std::to_string(1 + i % 3) : "");
    text += "  # a comment\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1 3 2\n";
    TempFile f("ngon.obj", text);
    scene::TriangleMesh m = scene::load_obj(f.path());
    ASSERT_EQ(m.triangle_count(), 1u + (n - 2) + 1u);
    const double ngon = 0.5 * n * std::sin(2 * M_PI / n);
    EXPECT_NEAR(m.surface_area(), 0.5 + ngon + 0.5, 1e-3);
    EXPECT_EQ(m.vertex(0, 0).z, 0.0f);  // the triangle before
    EXPECT_EQ(m.vertex(1, 0).z, 5.0f);  // the fan: r0, r1, r2
    EXPECT_EQ(m.vertex(1, 0).x, 1.0f);
    EXPECT_EQ(m.vertex(n - 2, 0).x, 1.0f);  // every fan triangle starts at r0
    EXPECT_EQ(m.vertex(n - 1, 1).z, 0.0f);  // the triangle after
    // References beyond the 31st are checked too, with the line number.
    std::string bad = std::string(kTri) + "f";
    for (int i = 0; i < 40; ++i) bad += i == 35 ? " 1x" : " " + std::to_string(1 + i % 3);
    expect_load_error("bad_far_ref.obj", bad + "\n", "line 4: malformed 'f' line: bad vertex reference '1x'");
    std::string far = std::string(kTri) + "f";
    for (int i = 0; i < 100; ++i) far += " " + std::to_string(i == 80 ? 99 : 1 + i % 3);
    expect_load_error("far_range.obj", far + "\n", "face index 99 out of range");
}

TEST(ObjLoader, ProgressReportsBytesUpToTheWholeFile) {
    // A 20 MB OBJ: progress in 8 MiB steps, never backwards, ending at the file's size.
    std::string text = kTri;
    while (text.size() < (size_t(20) << 20)) text += "v 0.123456 0.654321 0.5\n# padding padding padding\nf 1 2 3\n";
    TempFile f("progress.obj", text);
    std::vector<std::pair<size_t, size_t>> calls;
    scene::load_obj(f.path(), nullptr, nullptr, [&](size_t done, size_t total) { calls.push_back({done, total}); });
    ASSERT_GE(calls.size(), 3u);
    for (size_t i = 1; i < calls.size(); ++i) EXPECT_GE(calls[i].first, calls[i - 1].first);
    EXPECT_EQ(calls.back().first, text.size());
    EXPECT_EQ(calls.back().second, text.size());
}

TEST(ObjLoader, CornellBoxKeepsMaterialsAndEmission) {
    scene::TriangleMesh m = scene::load_obj(test::data_dir() + "/cornell_box.obj");
    EXPECT_EQ(m.triangle_count(), 32u);
    EXPECT_EQ(m.dropped.total(), 0u);
    int light = -1;
    for (size_t i = 0; i < m.materials.size(); ++i)
        if (m.materials[i].name == "light") light = int(i);
    ASSERT_GE(light, 0);
    EXPECT_GT(m.materials[size_t(light)].emission.x, 1.0f);
    int light_tris = 0;
    for (int32_t id : m.material_ids) light_tris += id == light;
    EXPECT_EQ(light_tris, 2);
}

// The MTL parameters the renderer maps: Ks, Ka, Ns, Ni, d, illum and map_Kd as written.
TEST(ObjLoader, KeepsTheRenderersMaterialParameters) {
    test::TempFile mtl("params.mtl",
                       "newmtl m\nKd 0.5 0.5 0.5\nKs 0.25 0.5 0.75\nKa 20 20 20\nNs 250\nNi 1.33\nd 0.5\nillum 7\n"
                       "map_Kd textures\\wood.png\n");
    test::TempFile obj("params.obj", "mtllib " + std::filesystem::path(mtl.path()).filename().string() +
                                         "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
    const scene::TriangleMesh m = scene::load_obj(obj.path());
    ASSERT_EQ(m.materials.size(), 1u);
    const scene::Material& x = m.materials[0];
    EXPECT_EQ(x.specular.z, 0.75f);
    EXPECT_EQ(x.ambient.x, 20.0f);
    EXPECT_EQ(x.shininess, 250.0f);
    EXPECT_EQ(x.ior, 1.33f);
    EXPECT_EQ(x.dissolve, 0.5f);
    EXPECT_EQ(x.illum, 7);
    EXPECT_EQ(x.diffuse_texture, "textures\\wood.png");
}

// An absolute mtllib path is read as it is (it had the OBJ's folder put in front); a relative
// one from the OBJ's folder; a missing one is a warning naming the resolved path.
TEST(ObjLoader, AbsoluteAndRelativeMaterialFiles) {
    test::TempFile mtl("absolute.mtl", "newmtl red\nKd 1 0 0\n");
    const std::string abs = std::filesystem::absolute(mtl.path()).string();
    test::TempFile obj("absolute.obj", "mtllib " + abs + "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    std::vector<std::string> warnings, files;
    const scene::TriangleMesh m = scene::load_obj(obj.path(), &warnings, &files);
    ASSERT_EQ(m.materials.size(), 1u);
    EXPECT_EQ(m.materials[0].diffuse.x, 1.0f);
    EXPECT_EQ(m.material_ids[0], 0);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(files[0], abs);
    EXPECT_TRUE(warnings.empty());
    test::TempFile gone("gone_mtl.obj", "mtllib no-such.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    warnings.clear();
    files.clear();
    scene::load_obj(gone.path(), &warnings, &files);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(files[0], std::filesystem::path(gone.path()).parent_path().string() + "/no-such.mtl");
    ASSERT_FALSE(warnings.empty());
    EXPECT_NE(warnings[0].find("no-such.mtl' does not exist"), std::string::npos) << warnings[0];
}

// vt and vn references are checked like v ones: negative beyond what was read so far, positive
// beyond the file's count.
TEST(ObjLoader, TextureAndNormalReferencesOutOfRange) {
    expect_load_error("negvt.obj", std::string(kTri) + "vt 0 0\nf 1/-2 2/1 3/1\n",
                      "line 5: texture coordinate index -2 out of range");
    expect_load_error("bigvt.obj", std::string(kTri) + "vt 0 0\nf 1/1 2/2 3/1\n",
                      "line 5: texture coordinate index 2 out of range (the file has 1 texture coordinates)");
    expect_load_error("negvn.obj", std::string(kTri) + "vn 0 0 1\nf 1//1 2//-2 3//1\n",
                      "line 5: normal index -2 out of range");
    expect_load_error("bigvn.obj", std::string(kTri) + "vn 0 0 1\nf 1/1/1 2/1/3 3/1/1\nvt 0 0\n",
                      "normal index 3 out of range (the file has 1 normals)");
    // A later vt makes a forward reference valid, as in any OBJ reader.
    TempFile later("latervt.obj", std::string(kTri) + "f 1/1 2/1 3/1\nvt 0.5 0.5\n");
    EXPECT_EQ(scene::load_obj(later.path()).triangle_count(), 1u);
}

/// The three components of each vector, for comparisons.
std::vector<float> components(const std::vector<Vec3>& v) {
    std::vector<float> out;
    for (const Vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
    return out;
}

// Shading normals per corner, made unit vectors; a face without vn, or with a zero vn at any
// corner, gets zeros at all three (the renderer shades it by its geometric normal); a file whose
// faces refer to no vn has none at all.
TEST(ObjLoader, KeepsUnitNormalsPerCorner) {
    test::TempFile obj("vn.obj",
                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 2\nvn 0 3 4\nvn 0 0 0\n"
                       "f 1//1 2//2 3//1\nf 2 4 3\nf 2//1 4//3 3//2\nf 1/1/1 2/1/-2 3/1/1\nvt 0 0\n");
    const scene::TriangleMesh m = scene::load_obj(obj.path());
    ASSERT_EQ(m.triangle_count(), 4u);
    const std::vector<float> want = {0, 0, 1, 0, 0.6f, 0.8f, 0, 0, 1, 0, 0, 0, 0, 0,    0,    0, 0, 0,
                                     0, 0, 0, 0, 0,    0,    0, 0, 0, 0, 0, 1, 0, 0.6f, 0.8f, 0, 0, 1};
    EXPECT_EQ(components(m.normals), want);
    test::TempFile unused("unused_vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\n");
    EXPECT_TRUE(scene::load_obj(unused.path()).normals.empty());
}

// Texture coordinates per corner, as the faces reference them; a face without vt gets zeros,
// a file without vt none at all, and a vt reference past the end is an error.
TEST(ObjLoader, KeepsTextureCoordinatesPerCorner) {
    test::TempFile obj("uv.obj",
                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\n"
                       "f 1/1 2/2 3/3\nf 2 4 3\nf 2/3 4/2 3/-3\n");
    const scene::TriangleMesh m = scene::load_obj(obj.path());
    ASSERT_EQ(m.triangle_count(), 3u);
    const std::vector<float> want = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0,    0,    0,
                                     0,    0,    0,    0.5f, 0.6f, 0.3f, 0.4f, 0.1f, 0.2f};
    EXPECT_EQ(m.texcoords, want);
    test::TempFile plain("no_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_TRUE(scene::load_obj(plain.path()).texcoords.empty());
    test::TempFile bad("bad_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/5 3/1\n");
    EXPECT_THROW(scene::load_obj(bad.path()), Error);
}

// write_obj with materials: every triangle is written, a usemtl line only where the material
// changes, and the triangles load back in order (without an MTL file, as material -1).
TEST(ObjLoader, WriteKeepsEveryTriangleAcrossMaterialChanges) {
    scene::TriangleMesh a = test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0},
                                           {0, 0, 1, 1, 0, 1, 0, 1, 1},
                                           {0, 0, 2, 1, 0, 2, 0, 1, 2},
                                           {0, 0, 3, 1, 0, 3, 0, 1, 3}});
    a.materials.resize(2);
    a.materials[0].name = "red";
    a.materials[1].name = "blue";
    a.material_ids = {0, 0, 1, 0};
    TempFile f("materials_roundtrip.obj");
    scene::write_obj(a, f.path());
    const std::string text = test::read_file_bytes(f.path());
    size_t usemtl = 0;
    for (size_t at = text.find("usemtl"); at != std::string::npos; at = text.find("usemtl", at + 1)) ++usemtl;
    EXPECT_EQ(usemtl, 3u) << text;
    EXPECT_LT(text.find("usemtl red"), text.find("usemtl blue"));
    const scene::TriangleMesh b = scene::load_obj(f.path());
    ASSERT_EQ(b.triangle_count(), 4u);
    EXPECT_EQ(scene::scene_hash(a), scene::scene_hash(b));
}

TEST(ObjLoader, WriteThenLoadIsExact) {
    scene::TriangleMesh a = test::mesh_of({{0.1f, 0.2f, 0.3f, 1.0f / 3.0f, 0, 0, 0, 1e-7f, 5}});
    TempFile f("roundtrip.obj");
    scene::write_obj(a, f.path());
    scene::TriangleMesh b = scene::load_obj(f.path());
    EXPECT_EQ(scene::scene_hash(a), scene::scene_hash(b));
}

}  // namespace bvhlab

namespace bvhlab::scene {

TEST(ObjLoader, DenormalCoordinatesBecomeZero) {
    // Embree's threads read denormals as 0 (DAZ); a mesh holds none, so every thread and
    // library sees the same triangle.
    test::TempFile f("denormal.obj", "v 1e-45 0 0\nv 1 -3e-39 0\nv 0 1 1.2e-38\nf 1 2 3\n");
    const TriangleMesh m = load_obj(f.path());
    ASSERT_EQ(m.triangle_count(), 1u);
    EXPECT_EQ(m.vertex(0, 0).x, 0.0f);
    EXPECT_FALSE(std::signbit(m.vertex(0, 1).y));
    EXPECT_EQ(m.vertex(0, 1).y, 0.0f);
    EXPECT_EQ(m.vertex(0, 2).z, 1.2e-38f);  // FLT_MIN and above stay
    TriangleMesh g;
    ASSERT_TRUE(add_triangle_checked(g, {0, 0, 1e-40f}, {1, 0, 0}, {0, 1, -1e-41f}, -1));
    EXPECT_EQ(g.vertex(0, 0).z, 0.0f);
    EXPECT_EQ(g.vertex(0, 2).z, 0.0f);
    EXPECT_EQ(flush_denormals({1e-30f, -2e-45f, 5.0f}).y, 0.0f);
    EXPECT_EQ(flush_denormals({1e-30f, -2e-45f, 5.0f}).x, 1e-30f);
    EXPECT_TRUE(std::signbit(flush_denormals({-0.0f, 0.0f, 0.0f}).x));  // -0 is not a denormal
}

}  // namespace bvhlab::scene
