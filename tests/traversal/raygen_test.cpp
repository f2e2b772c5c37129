// SPDX-License-Identifier: MIT
// Ray generators: determinism, tile order, sample grid, secondary ray geometry.
#include "traversal/rays/raygen.h"

#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "accel/core/check.h"
#include "scene/io/obj_loader.h"
#include "tests/support/test_support.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"

namespace bvhlab::trav {
namespace {

Camera cornell_camera() {
    Camera c;
    c.eye = {278, 273, -800};
    c.target = {278, 273, 0};
    c.fov_y_deg = 39.3f;
    return c;
}

bool same_bytes(const std::vector<Ray>& a, const std::vector<Ray>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)) == 0;
}

}  // namespace

TEST(PrimaryRays, TilesArePermutationOfRowMajor) {
    PrimaryConfig row{37, 23, 4, 0}, tiled{37, 23, 4, 8};
    std::vector<Ray> a = generate_primary(cornell_camera(), row);
    std::vector<Ray> b = generate_primary(cornell_camera(), tiled);
    ASSERT_EQ(a.size(), 37u * 23u * 4u);
    ASSERT_EQ(a.size(), b.size());
    auto key = [](const Ray& r) { return std::make_tuple(r.dir.x, r.dir.y, r.dir.z); };
    std::multiset<std::tuple<float, float, float>> sa, sb;
    for (const Ray& r : a) sa.insert(key(r));
    for (const Ray& r : b) sb.insert(key(r));
    EXPECT_EQ(sa, sb);
    // The first 8x8 tile's first row of pixels comes first; pixel (8, 0) starts the second tile.
    EXPECT_EQ(std::memcmp(&b[0], &a[0], sizeof(Ray) * 4 * 8), 0);
    EXPECT_EQ(std::memcmp(&b[4 * 8], &a[4 * 37], sizeof(Ray) * 4), 0);
    EXPECT_EQ(std::memcmp(&b[4 * 64], &a[4 * 8], sizeof(Ray) * 4), 0);
}

TEST(PrimaryRays, CentreRayLooksAtTargetAndSamplesAreDistinct) {
    std::vector<Ray> r = generate_primary(cornell_camera(), {3, 3, 1, 0});
    EXPECT_NEAR(r[4].dir.x, 0.0f, 1e-6f);
    EXPECT_NEAR(r[4].dir.y, 0.0f, 1e-6f);
    EXPECT_NEAR(r[4].dir.z, 1.0f, 1e-6f);
    EXPECT_GT(r[0].dir.y, 0.0f);  // row 0 is the top of the image
    // Column 0 is the camera's left, right = forward x up: +x when looking down +z with +y up,
    // which puts the Cornell box's red wall (x = 556) on the left as in the classic image.
    EXPECT_GT(r[0].dir.x, 0.0f);
    std::vector<Ray> s = generate_primary(cornell_camera(), {1, 1, 16, 0});
    std::set<std::pair<float, float>> uniq;
    for (const Ray& x : s) uniq.insert({x.dir.x, x.dir.y});
    EXPECT_EQ(uniq.size(), 16u);
}

TEST(PrimaryRays, RejectsBadArguments) {
    EXPECT_THROW(generate_primary(cornell_camera(), {4, 4, 3, 0}), Error);  // not a square
    EXPECT_THROW(generate_primary(cornell_camera(), {0, 4, 1, 0}), Error);
    Camera bad = cornell_camera();
    bad.target = bad.eye;
    EXPECT_THROW(generate_primary(bad, {4, 4, 1, 0}), Error);
    bad = cornell_camera();
    bad.up = {0, 0, 1};  // parallel to the view direction
    EXPECT_THROW(generate_primary(bad, {4, 4, 1, 0}), Error);
}

TEST(Protocol, SecondaryRaysAreSeededAndGeometricallySound) {
    scene::TriangleMesh mesh = scene::load_obj(test::data_dir() + "/cornell_box.obj");
    EmbreeOracle oracle(mesh);
    ProtocolConfig cfg;
    cfg.camera = cornell_camera();
    cfg.primary = {64, 48, 1, 0};
    RayProtocol p1(mesh, oracle, cfg), p2(mesh, oracle, cfg);
    for (RayType t : {RayType::kPrimary, RayType::kAo, RayType::kDiffuse, RayType::kShadow})
        EXPECT_TRUE(same_bytes(p1.make(t).rays, p2.make(t).rays)) << ray_type_name(t);
    cfg.seed = 2;
    RayProtocol p3(mesh, oracle, cfg);
    EXPECT_FALSE(same_bytes(p1.make(RayType::kAo).rays, p3.make(RayType::kAo).rays));

    RaySet ao = p1.make(RayType::kAo);
    EXPECT_EQ(ao.query, Query::kAny);
    EXPECT_EQ(ao.rays.size() % 8, 0u);
    const float diag = mesh.diagonal();
    for (const Ray& r : ao.rays) {
        EXPECT_NEAR(r.tmax, 0.05f * diag, 1e-3f);
        EXPECT_NEAR(length(r.dir), 1.0f, 1e-4f);
    }
    RaySet diffuse = p1.make(RayType::kDiffuse);
    EXPECT_EQ(diffuse.query, Query::kClosest);
    EXPECT_EQ(diffuse.rays.size() * 2, ao.rays.size());  // 4 vs 8 per hit
    EXPECT_TRUE(std::isinf(diffuse.rays[0].tmax));
    RaySet shadow = p1.make(RayType::kShadow);
    const Vec3 light{278.0f, 273.0f + 0.25f * diag, -800.0f};
    for (const Ray& r : shadow.rays) {
        const Vec3 end = r.org + r.dir * r.tmax;
        EXPECT_NEAR(length(end - light), 0.0f, 1e-2f);
    }
}

TEST(Protocol, SecondaryOriginsLeaveTheSurfaceOnTheRaySide) {
    scene::TriangleMesh mesh = scene::load_obj(test::data_dir() + "/cornell_box.obj");
    EmbreeOracle oracle(mesh);
    std::vector<Ray> prim = generate_primary(cornell_camera(), {32, 24, 1, 0});
    std::vector<Hit> hits;
    oracle.trace(prim, Query::kClosest, hits);
    SecondaryConfig sc;
    sc.per_hit = 4;
    sc.offset = 1e-4f * mesh.diagonal();
    std::vector<Ray> ao = generate_ao(mesh, prim, hits, sc);
    size_t k = 0;
    for (size_t i = 0; i < prim.size(); ++i) {
        if (!hits[i].is_hit()) continue;
        Vec3 p, n;
        hit_frame(mesh, prim[i], hits[i], p, n);
        EXPECT_LT(dot(n, prim[i].dir), 0.0f);  // normal faces the camera side
        for (uint32_t s = 0; s < sc.per_hit; ++s, ++k) {
            EXPECT_GT(dot(ao[k].dir, n), 0.0f);  // into the hemisphere
            EXPECT_NEAR(dot(ao[k].org - p, n), sc.offset, 1e-3f);
        }
    }
    EXPECT_EQ(k, ao.size());
}

}  // namespace bvhlab::trav

namespace bvhlab::trav {
namespace {

void expect_dir(Vec3 got, Vec3 want, const char* what) {
    EXPECT_NEAR(got.x, want.x, 1e-6f) << what;
    EXPECT_NEAR(got.y, want.y, 1e-6f) << what;
    EXPECT_NEAR(got.z, want.z, 1e-6f) << what;
}

float angle_between(Vec3 a, Vec3 b) { return std::acos(std::fmin(1.0f, dot(a, b) / (length(a) * length(b)))); }

}  // namespace

// Camera space: x right, y up, the view along -z. The closed forms at chosen image points.
TEST(Projection, PanoramaIsEquirectangular) {
    const auto at = [](float u, float v) { return wide_direction(Projection::kPanorama, u, v, 2.0f, 0.0f); };
    expect_dir(at(0.5f, 0.5f), {0, 0, -1}, "centre: ahead");
    expect_dir(at(0.75f, 0.5f), {1, 0, 0}, "three quarters across: right");
    expect_dir(at(0.25f, 0.5f), {-1, 0, 0}, "a quarter across: left");
    expect_dir(at(0.0f, 0.5f), {0, 0, 1}, "the left edge: behind");
    expect_dir(at(0.5f, 0.0f), {0, 1, 0}, "the top: up");
    expect_dir(at(0.5f, 1.0f), {0, -1, 0}, "the bottom: down");
    const float s = std::sqrt(0.5f);
    expect_dir(at(0.375f, 0.25f), {-0.5f, s, -0.5f}, "45 degrees left, 45 up");
}

TEST(Projection, FisheyeIsEquidistant) {
    const float half = 0.5f * 3.14159265f;  // 180 degrees across the inscribed circle
    const auto at = [&](float u, float v, float aspect) {
        return wide_direction(Projection::kFisheye, u, v, aspect, half);
    };
    expect_dir(at(0.5f, 0.5f, 1.0f), {0, 0, -1}, "centre: ahead");
    expect_dir(at(0.5f, 0.0f, 1.0f), {0, 1, 0}, "top of the circle: 90 degrees up");
    expect_dir(at(1.0f, 0.5f, 1.0f), {1, 0, 0}, "right of the circle: 90 degrees right");
    expect_dir(at(1.0f, 0.5f, 2.0f), {0, 0, 1}, "a 2:1 image's right edge: 180 degrees, behind");
    // Equidistant: the angle from the axis is the distance from the centre times half the
    // field of view, whatever the direction; and the direction has unit length.
    for (float u : {0.1f, 0.3f, 0.62f, 0.9f})
        for (float v : {0.05f, 0.4f, 0.77f}) {
            const float aspect = 1.5f, x = (2 * u - 1) * aspect, y = 1 - 2 * v;
            const Vec3 d = at(u, v, aspect);
            EXPECT_NEAR(length(d), 1.0f, 1e-6f);
            EXPECT_NEAR(angle_between(d, {0, 0, -1}), std::sqrt(x * x + y * y) * half, 2e-4f) << u << " " << v;
            EXPECT_NEAR(std::atan2(d.y, d.x), std::atan2(y, x), 2e-4f) << u << " " << v;
        }
}

TEST(PrimaryRays, PanoramaAndFisheyeRaysFollowTheProjection) {
    Camera c;
    c.eye = {1, 2, 3};
    c.target = {1, 2, 2};  // looking along -z, up +y: camera space is world space
    c.projection = Projection::kPanorama;
    const std::vector<Ray> pano = generate_primary(c, {4, 2, 1, 0});
    const float s = std::sqrt(0.5f);
    expect_dir(pano[1].dir, {-0.5f, s, -0.5f}, "pixel (1, 0): 45 degrees left, 45 up");
    expect_dir(pano[6].dir, {0.5f, -s, -0.5f}, "pixel (2, 1): 45 degrees right, 45 down");
    EXPECT_EQ(pano[6].org.x, 1.0f);
    c.projection = Projection::kFisheye;
    c.fisheye_fov_deg = 180.0f;
    const std::vector<Ray> fish = generate_primary(c, {3, 3, 1, 0});
    expect_dir(fish[4].dir, {0, 0, -1}, "centre pixel: ahead");
    const float edge = 2.0f / 3.0f * 0.5f * 3.14159265f;  // pixel (2, 1): r = 2/3
    expect_dir(fish[5].dir, {std::sin(edge), 0, -std::cos(edge)}, "pixel (2, 1)");
    c.fisheye_fov_deg = 0.0f;
    EXPECT_THROW(generate_primary(c, {3, 3, 1, 0}), Error);
}

}  // namespace bvhlab::trav

namespace bvhlab::trav {

// Every primary hit gets its shadow ray, the first one too: with a narrow view every pixel
// sees the back wall, and each shadow ray runs from its hit to the light.
TEST(Protocol, EveryHitHasItsShadowRayFromTheFirstOn) {
    scene::TriangleMesh mesh = scene::load_obj(test::data_dir() + "/cornell_box.obj");
    EmbreeOracle oracle(mesh);
    ProtocolConfig cfg;
    cfg.camera = cornell_camera();
    cfg.camera.fov_y_deg = 10.0f;
    cfg.primary = {8, 6, 1, 0};
    RayProtocol p(mesh, oracle, cfg);
    const RaySet shadow = p.make(RayType::kShadow);
    ASSERT_EQ(shadow.rays.size(), 48u) << "every pixel of the narrow view hits";
    const float diag = mesh.diagonal();
    const Vec3 light{278.0f, 273.0f + 0.25f * diag, -800.0f};
    for (size_t i = 0; i < shadow.rays.size(); ++i) {
        const Ray& r = shadow.rays[i];
        EXPECT_NEAR(length(r.dir), 1.0f, 1e-4f) << i;
        EXPECT_NEAR(length(r.org + r.dir * r.tmax - light), 0.0f, 1e-2f) << i;
    }
}

}  // namespace bvhlab::trav
