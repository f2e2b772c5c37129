// SPDX-License-Identifier: MIT
// map_Kd textures: the bilinear lookup, path resolution (backslashes), missing files, and a
// textured quad rendered under the white sky, whose pixels must show the texture's colours.
// Normal and height maps: the frame of the texture coordinates, the bent normals against closed
// forms, and a mapped quad whose normal buffer and shading under the sky are the analytic ones.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "accel/core/check.h"
#include "renderer/core/normal_map.h"
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

/// A folder with a 2 x 2 quad facing +z, u = (x + 1) / 2, v = (y + 1) / 2, whose two triangles'
/// materials have Kd 0.5 and `map_Kd` names `texture` (as written in the MTL), or, when
/// `texture` holds a space, the line `texture` itself ("norm maps/n.pfm").
struct TexturedQuad {
    fs::path dir;
    explicit TexturedQuad(const std::string& texture, bool with_texcoords = true) {
        dir = fs::temp_directory_path() / ("bvhlab_texture_" + std::to_string(getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir / "maps");
        const std::string line = texture.find(' ') == std::string::npos ? "map_Kd " + texture : texture;
        std::ofstream(dir / "quad.mtl") << "newmtl a\nKd 0.5 0.5 0.5\n"
                                        << line << "\nnewmtl b\nKd 0.5 0.5 0.5\n"
                                        << line << "\n";
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

float distance(Vec3 a, Vec3 b) { return length(a - b); }

TEST(NormalMap, TextureCoordinatesGiveTheTangentFrame) {
    // u along +x over 2 units, v along +y over 4 units.
    const float uv[6] = {0, 0, 1, 0, 0, 1};
    Vec3 dpdu, dpdv;
    ASSERT_TRUE(uv_derivatives({0, 0, 0}, {2, 0, 0}, {0, 4, 0}, uv, dpdu, dpdv));
    EXPECT_LT(distance(dpdu, {2, 0, 0}), 1e-6f);
    EXPECT_LT(distance(dpdv, {0, 4, 0}), 1e-6f);
    // Rotated a quarter turn: u runs along +y, v along -x.
    const float turned[6] = {0.5f, 0.5f, 1.0f, 0.5f, 0.5f, 0.0f};
    ASSERT_TRUE(uv_derivatives({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, turned, dpdu, dpdv));
    EXPECT_LT(distance(dpdu, {0, 2, 0}), 1e-6f);
    EXPECT_LT(distance(dpdv, {-2, 0, 0}), 1e-6f);
    // Collinear or repeated texture coordinates, and NaN ones: no frame.
    const float line[6] = {0, 0, 1, 1, 2, 2}, nan[6] = {0, 0, 1, 0, NAN, 1};
    EXPECT_FALSE(uv_derivatives({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, line, dpdu, dpdv));
    EXPECT_FALSE(uv_derivatives({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, nan, dpdu, dpdv));
}

TEST(NormalMap, TangentSpaceTexelsTurnWithTheFrame) {
    const Vec3 n{0, 0, 1};
    const Vec3 t = normalize(Vec3{0.5f, -0.3f, 0.8f});
    const Vec3 texel = (t + splat(1.0f)) * 0.5f;
    // Tangent +x, bitangent +y: the texel's vector as it is.
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, 2, 0}, texel, 1.0f), t), 1e-6f);
    // Tangent +y, bitangent -x (a quarter turn of the texture coordinates).
    EXPECT_LT(distance(tangent_space_normal(n, {0, 2, 0}, {-2, 0, 0}, texel, 1.0f), {-t.y, t.x, t.z}), 1e-6f);
    // Mirrored v (the bitangent follows dpdv, not n x tangent): y changes sign.
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, -2, 0}, texel, 1.0f), {t.x, -t.y, t.z}), 1e-6f);
    // A tangent with a part along n: that part is taken out.
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 5}, {0, 2, 0}, texel, 1.0f), t), 1e-6f);
    // -bm scales the tangent-plane part; 0 gives n.
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, 2, 0}, texel, 0.5f),
                       normalize(Vec3{0.5f * t.x, 0.5f * t.y, t.z})),
              1e-6f);
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, 2, 0}, texel, 0.0f), n), 1e-6f);
    // The flat texel (0.5, 0.5, 1) is n; one pointing below the surface, or a tangent along n, gives n.
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, 1.0f}, 1.0f), n), 1e-6f);
    EXPECT_LT(distance(tangent_space_normal(n, {2, 0, 0}, {0, 2, 0}, {1.0f, 0.5f, 0.2f}, 1.0f), n), 1e-6f);
    EXPECT_LT(distance(tangent_space_normal(n, {0, 0, 3}, {0, 2, 0}, texel, 1.0f), n), 1e-6f);
}

TEST(NormalMap, HeightGradientsBendTheNormalAsTheDisplacedSurface) {
    const Vec3 n{0, 0, 1};
    // z = h(u, v) over the plane x = 2u, y = 4v: the surface z = hu x / 2 + hv y / 4, whose
    // normal is (-hu / 2, -hv / 4, 1).
    const float hu = 0.6f, hv = -1.2f;
    EXPECT_LT(distance(height_normal(n, {2, 0, 0}, {0, 4, 0}, hu, hv), normalize(Vec3{-hu / 2, -hv / 4, 1})), 1e-6f);
    // Mirrored v: dpdv along -y, so the same hv tilts the other way.
    EXPECT_LT(distance(height_normal(n, {2, 0, 0}, {0, -4, 0}, hu, hv), normalize(Vec3{-hu / 2, hv / 4, 1})), 1e-6f);
    // With n the other way round the heights rise along -z: the surface z = -h, whose normal on
    // n's side is (-hu / 2, -hv / 4, -1).
    EXPECT_LT(distance(height_normal(n * -1.0f, {2, 0, 0}, {0, 4, 0}, hu, hv), normalize(Vec3{-hu / 2, -hv / 4, -1})),
              1e-6f);
    EXPECT_LT(distance(height_normal(n, {2, 0, 0}, {4, 0, 0}, hu, hv), n), 1e-6f);  // parallel: n
    EXPECT_LT(distance(height_normal(n, {2, 0, 0}, {0, 4, 0}, 0.0f, 0.0f), n), 1e-6f);
    // Central differences of a linear ramp of heights are exact between the edge texels.
    Image ramp(64, 2);
    for (uint32_t y = 0; y < 2; ++y)
        for (uint32_t x = 0; x < 64; ++x) ramp.at(x, y) = splat((float(x) + 0.5f) / 64.0f);
    std::vector<Vec3> slopes(ramp.pixels.size());
    height_slopes(ramp.pixels.data(), 64, 2, slopes.data());
    const TextureInfo info{0, 64, 2, 0};
    for (float u : {0.1f, 0.37f, 0.5f, 0.9f}) {
        float du, dv;
        height_derivatives(slopes.data(), info, u, 0.3f, 0.25f, du, dv);
        EXPECT_NEAR(du, 0.25f, 1e-4f) << "u " << u;
        EXPECT_NEAR(dv, 0.0f, 1e-6f) << "u " << u;
    }
}

TEST(NormalMap, HeightDerivativesAreCentralDifferencesOfTheLookup) {
    // The slope texture's lookup against its definition, on a small random texture (so that the
    // block around most points wraps), at coordinates inside, outside and on texel edges.
    const uint32_t w = 5, h = 3;
    std::vector<Vec3> texels(w * h), slopes(w * h);
    uint32_t state = 12345;
    auto rnd = [&] { return float((state = state * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
    for (Vec3& c : texels) c = {rnd(), rnd(), rnd()};
    height_slopes(texels.data(), w, h, slopes.data());
    const TextureInfo t{0, w, h, 0};
    const float du = 1.0f / float(w), dv = 1.0f / float(h);
    for (int k = 0; k < 200; ++k) {
        const float u = k < 4 ? float(k) / float(w) : 6.0f * rnd() - 3.0f, v = k < 4 ? 0.5f : 6.0f * rnd() - 3.0f;
        float hu, hv;
        height_derivatives(slopes.data(), t, u, v, 0.7f, hu, hv);
        const float want_u =
            0.7f * (map_height(texels.data(), t, u + du, v) - map_height(texels.data(), t, u - du, v)) / (2.0f * du);
        const float want_v =
            0.7f * (map_height(texels.data(), t, u, v + dv) - map_height(texels.data(), t, u, v - dv)) / (2.0f * dv);
        EXPECT_NEAR(hu, want_u, 2e-4f * (1.0f + std::fabs(want_u))) << "u " << u << " v " << v;
        EXPECT_NEAR(hv, want_v, 2e-4f * (1.0f + std::fabs(want_v))) << "u " << u << " v " << v;
    }
    // wrap_index: in range as it is, any other integer into [0, n).
    EXPECT_EQ(wrap_index(3, 5), 3);
    EXPECT_EQ(wrap_index(-1, 5), 4);
    EXPECT_EQ(wrap_index(-11, 5), 4);
    EXPECT_EQ(wrap_index(5, 5), 0);
    EXPECT_EQ(wrap_index(17, 5), 2);
    EXPECT_EQ(wrap_index(-3, 1), 0);
}

/// A constant texel `c` as a 4 x 4 PFM.
void write_constant(const fs::path& path, Vec3 c) {
    Image img(4, 4);
    for (Vec3& p : img.pixels) p = c;
    write_image(img, path.string());
}

/// The quad's renders: every pixel's normal buffer equals `normal`, and its radiance is a
/// Lambertian Kd 0.5 plane's with that shading normal under the white sky, clipped at the
/// plane: 0.5 (1 + cos theta) / 2 (the isotropic sky on a tilted plane).
void expect_bent_quad(const RenderResult& r, Vec3 normal, const std::vector<uint32_t>& columns) {
    const float want = 0.5f * (1.0f + normal.z) / 2.0f;
    for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x : columns) {
            EXPECT_LT(distance(r.normal.at(x, y), normal), 1e-4f) << "normal of pixel " << x << "," << y;
            const float sd = std::sqrt(r.variance_of_mean.at(x, y).x);
            EXPECT_NEAR(r.mean.at(x, y).x, want, 5.0f * sd + 2e-3f) << "pixel " << x << "," << y;
        }
}

TEST(NormalMap, ATangentSpaceMapBendsTheQuadsNormalAndShading) {
    const Vec3 t = normalize(Vec3{0.5f, -0.3f, 0.6f});
    for (const char* line : {"norm maps/n.pfm", "map_Bump maps/n.pfm", "bump -bm 1 maps/n.pfm"}) {
        SCOPED_TRACE(line);
        TexturedQuad q(line);
        write_constant(q.dir / "maps" / "n.pfm", (t + splat(1.0f)) * 0.5f);
        const scene::TriangleMesh mesh = q.mesh();
        ASSERT_EQ(mesh.materials.size(), 2u);
        const RenderScene scene(mesh, {}, {q.dir.string(), false, nullptr});
        ASSERT_EQ(scene.textures().size(), 1u);  // two materials, one file: loaded once
        EXPECT_EQ(scene.materials()[1].normal_kind, NormalMapKind::kTangentSpace);
        expect_bent_quad(render_quad(scene, 64), t, {0, 1, 2, 3, 4, 5, 6, 7});
    }
    // -bm 0.5 halves the tangent-plane part.
    TexturedQuad q("norm -bm 0.5 maps/n.pfm");
    write_constant(q.dir / "maps" / "n.pfm", (t + splat(1.0f)) * 0.5f);
    const scene::TriangleMesh mesh = q.mesh();
    EXPECT_FLOAT_EQ(mesh.materials[0].bump_multiplier, 0.5f);
    const RenderScene scene(mesh, {}, {q.dir.string(), false, nullptr});
    expect_bent_quad(render_quad(scene, 64), normalize(Vec3{0.5f * t.x, 0.5f * t.y, t.z}), {0, 3, 7});
}

TEST(NormalMap, AGreyBumpMapIsAHeightMap) {
    // Heights rising with u over 64 texels: h = u, so -bm 0.8 on the quad (x = 2u - 1) is the
    // surface z = 0.8 (x + 1) / 2, of normal (-0.4, 0, 1). Columns 1-6 lie clear of the
    // repeat's jump at u = 0.
    TexturedQuad q("map_Bump -bm 0.8 maps/h.pfm");
    Image ramp(64, 4);
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 64; ++x) ramp.at(x, y) = splat((float(x) + 0.5f) / 64.0f);
    write_image(ramp, (q.dir / "maps" / "h.pfm").string());
    const scene::TriangleMesh mesh = q.mesh();
    EXPECT_EQ(mesh.materials[0].bump_texture, "maps/h.pfm");
    EXPECT_FLOAT_EQ(mesh.materials[0].bump_multiplier, 0.8f);
    const RenderScene scene(mesh, {}, {q.dir.string(), false, nullptr});
    ASSERT_EQ(scene.textures().size(), 1u);  // two materials, one file: loaded (and made slopes) once
    EXPECT_EQ(scene.materials()[1].normal_kind, NormalMapKind::kHeight);
    EXPECT_EQ(scene.materials()[2].normal_kind, NormalMapKind::kHeight);
    EXPECT_FLOAT_EQ(scene.materials()[1].bump_scale, 0.8f);
    expect_bent_quad(render_quad(scene, 64), normalize(Vec3{-0.4f, 0.0f, 1.0f}), {1, 2, 3, 4, 5, 6});
}

TEST(NormalMap, BadMapsAreErrorsAndMissingOnesWarnings) {
    {
        TexturedQuad q("norm maps/n.pfm");
        write_constant(q.dir / "maps" / "n.pfm", {0.5f, 0.5f, 1.5f});
        const scene::TriangleMesh mesh = q.mesh();
        try {
            RenderScene scene(mesh, {}, {q.dir.string(), false, nullptr});
            FAIL() << "a normal map above 1 must be an error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("(norm of material 'a') has a texel above 1"), std::string::npos)
                << e.what();
        }
    }
    {
        TexturedQuad q("map_Bump maps/h.pfm");
        write_constant(q.dir / "maps" / "h.pfm", splat(NAN));
        const scene::TriangleMesh mesh = q.mesh();
        EXPECT_THROW(RenderScene(mesh, {}, {q.dir.string(), false, nullptr}), Error);
    }
    TexturedQuad q("norm maps/gone.pfm");
    const scene::TriangleMesh mesh = q.mesh();
    EXPECT_THROW(RenderScene(mesh, {}, {q.dir.string(), false, nullptr}), Error);
    std::vector<std::string> warnings;
    const RenderScene scene(mesh, {}, {q.dir.string(), true, &warnings});
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("renders without its norm"), std::string::npos) << warnings[0];
    EXPECT_EQ(scene.materials()[1].normal_kind, NormalMapKind::kNone);
    expect_bent_quad(render_quad(scene, 16), {0, 0, 1}, {2, 5});
}

}  // namespace
}  // namespace bvhlab::render
