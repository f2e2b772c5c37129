// SPDX-License-Identifier: MIT
// map_Kd textures: the bilinear lookup, path resolution (backslashes), missing files, and a
// textured quad rendered under the white sky, whose pixels must show the texture's colours.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "accel/core/check.h"
#include "renderer/image.h"
#include "renderer/wavefront.h"
#include "scene/io/obj_loader.h"
#include "traversal/oracle/embree_oracle.h"

namespace bvhlab::render {
namespace {

namespace fs = std::filesystem;

TEST(Texture, BilinearLookupWrapsAndFlipsV) {
    // 2 x 2: top row red, green; bottom row blue, white.
    const std::vector<Vec3> texels = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    const TextureInfo t{0, 2, 2, 0};
    auto near = [](Vec3 a, Vec3 b) { return std::fabs(a.x - b.x) + std::fabs(a.y - b.y) + std::fabs(a.z - b.z); };
    // Texel centres: u = 0.25 / 0.75, v = 0.75 (top row) / 0.25 (bottom row).
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.25f, 0.75f), {1, 0, 0}), 1e-6f);
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.75f, 0.75f), {0, 1, 0}), 1e-6f);
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.25f, 0.25f), {0, 0, 1}), 1e-6f);
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.75f, 0.25f), {1, 1, 1}), 1e-6f);
    // Half way between red and green; the same a period away, and at negative coordinates.
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.5f, 0.75f), {0.5f, 0.5f, 0}), 1e-6f);
    EXPECT_LT(near(sample_texture(texels.data(), t, 2.5f, -1.25f), {0.5f, 0.5f, 0}), 1e-6f);
    // u = 0 lies between the last column and the first (repeat wrapping).
    EXPECT_LT(near(sample_texture(texels.data(), t, 0.0f, 0.75f), {0.5f, 0.5f, 0}), 1e-6f);
    // A NaN coordinate reads as 0, not as a NaN colour.
    const Vec3 c = sample_texture(texels.data(), t, NAN, 0.75f);
    EXPECT_TRUE(std::isfinite(c.x + c.y + c.z));
    float u, v;
    const float uv[6] = {0, 0, 1, 0, 0, 1};
    triangle_texcoords(uv, 0, 0.25f, 0.5f, u, v);
    EXPECT_FLOAT_EQ(u, 0.25f);
    EXPECT_FLOAT_EQ(v, 0.5f);
}

TEST(Texture, PathsWithBackslashesResolve) {
    EXPECT_EQ(resolve_texture_path("/data/scene", "tex\\wood.png"), "/data/scene/tex/wood.png");
    EXPECT_EQ(resolve_texture_path("/data/scene", "./tex/../img\\a.exr"), "/data/scene/img/a.exr");
    EXPECT_EQ(resolve_texture_path("/data/scene", "/abs/t.pfm"), "/abs/t.pfm");
    EXPECT_EQ(resolve_texture_path("", "t.pfm"), "t.pfm");
}

/// A folder with a 2 x 2 quad facing +z, u = (x + 1) / 2, v = (y + 1) / 2, whose material
/// `map_Kd` names `texture` (as written in the MTL) and has Kd 0.5.
struct TexturedQuad {
    fs::path dir;
    explicit TexturedQuad(const std::string& texture, bool with_texcoords = true) {
        dir = fs::temp_directory_path() / ("bvhlab_texture_" + std::to_string(getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir / "maps");
        std::ofstream(dir / "quad.mtl") << "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd " << texture
                                        << "\nnewmtl b\nKd 0.5 0.5 0.5\nmap_Kd " << texture << "\n";
        std::ofstream obj(dir / "quad.obj");
        obj << "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n";
        if (with_texcoords)
            obj << "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 1/1 3/3 4/4\n";
        else
            obj << "usemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\n";
    }
    ~TexturedQuad() { fs::remove_all(dir); }
    scene::TriangleMesh mesh() const { return scene::load_obj((dir / "quad.obj").string()); }
};

/// 4 x 1 texels: red, red, green, green (so u in [1/8, 3/8] is pure red, [5/8, 7/8] pure green).
void write_stripes(const fs::path& path) {
    Image img(4, 1);
    img.pixels = {{0.8f, 0.1f, 0.1f}, {0.8f, 0.1f, 0.1f}, {0.1f, 0.8f, 0.1f}, {0.1f, 0.8f, 0.1f}};
    write_image(img, path.string());
}

/// The quad framed exactly (its edges on the image's) under the white sky: a Lambertian plane
/// that sees only sky returns its albedo, so pixel columns show the texture.
RenderResult render_quad(const RenderScene& scene, uint32_t spp) {
    trav::Camera cam;
    cam.eye = {0.0f, 0.0f, 3.0f};
    cam.target = {0.0f, 0.0f, 0.0f};
    cam.fov_y_deg = float(2.0 * std::atan(1.0 / 3.0) * 180.0 / M_PI);
    trav::EmbreeOracle oracle(scene.mesh());
    auto tracer = trav::make_embree_tracer(oracle, false);
    RenderSettings rs;
    rs.spp = spp;
    rs.max_depth = 2;
    rs.aovs = true;
    return render_host(scene, make_camera(cam, 8, 8, {}), rs, *tracer, *tracer);
}

TEST(Texture, TexturedQuadShowsTheTextureUnderTheSky) {
    TexturedQuad q("maps\\stripes.pfm");  // written the Windows way
    write_stripes(q.dir / "maps" / "stripes.pfm");
    const scene::TriangleMesh mesh = q.mesh();
    std::vector<std::string> warnings;
    TextureOptions opts{q.dir.string(), false, &warnings};
    const RenderScene scene(mesh, {}, opts);
    ASSERT_EQ(scene.textures().size(), 1u);  // two materials, one file: loaded once
    EXPECT_EQ(scene.materials()[1].texture, 0);
    EXPECT_EQ(scene.materials()[2].texture, 0);
    EXPECT_TRUE(warnings.empty());
    const RenderResult r = render_quad(scene, 64);
    for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x : {1u, 2u, 5u, 6u}) {
            const Vec3 want = x < 4 ? Vec3{0.8f, 0.1f, 0.1f} : Vec3{0.1f, 0.8f, 0.1f};
            const Vec3 got = r.mean.at(x, y), a = r.albedo.at(x, y);
            for (int c = 0; c < 3; ++c) {
                const float sd = std::sqrt(r.variance_of_mean.at(x, y)[c]);
                EXPECT_NEAR(got[c], want[c], 5.0f * sd + 1e-3f) << "pixel " << x << "," << y << " channel " << c;
                EXPECT_NEAR(a[c], want[c], 1e-5f) << "albedo of pixel " << x << "," << y;
            }
        }
}

TEST(Texture, MissingTextureIsAnErrorOrAWarningWithKd) {
    TexturedQuad q("maps\\absent.png");
    const scene::TriangleMesh mesh = q.mesh();
    try {
        RenderScene scene(mesh, {}, {q.dir.string(), false, nullptr});
        FAIL() << "a missing texture must be an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find((q.dir / "maps" / "absent.png").string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
    std::vector<std::string> warnings;
    const RenderScene scene(mesh, {}, {q.dir.string(), true, &warnings});
    EXPECT_EQ(warnings.size(), 1u);  // one per file, though two materials name it
    EXPECT_EQ(scene.materials()[1].texture, -1);
    const RenderResult r = render_quad(scene, 16);
    EXPECT_NEAR(r.albedo.at(3, 3).x, 0.5f, 1e-5f);  // Kd
}

TEST(Texture, UnreadableTextureIsAnErrorAndNoTexcoordsAWarning) {
    {
        TexturedQuad q("maps/broken.pfm");
        std::ofstream(q.dir / "maps" / "broken.pfm") << "PF\n2 2\n-1\nshort";
        const scene::TriangleMesh mesh = q.mesh();
        EXPECT_THROW(RenderScene(mesh, {}, {q.dir.string(), true, nullptr}), Error);
    }
    TexturedQuad q("maps/stripes.pfm", /*with_texcoords=*/false);
    write_stripes(q.dir / "maps" / "stripes.pfm");
    const scene::TriangleMesh mesh = q.mesh();
    std::vector<std::string> warnings;
    const RenderScene scene(mesh, {}, {q.dir.string(), false, &warnings});
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("no texture coordinates"), std::string::npos);
    EXPECT_TRUE(scene.texcoords().empty());
    EXPECT_NEAR(render_quad(scene, 4).albedo.at(1, 1).x, 0.5f, 1e-5f);
}

}  // namespace
}  // namespace bvhlab::render
