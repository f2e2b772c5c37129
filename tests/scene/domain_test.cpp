// SPDX-License-Identifier: MIT
// The numeric domain (scene/domain.h): meshes, vectors and materials just inside pass, just
// outside are named.
#include "scene/domain.h"

#include <gtest/gtest.h>

#include <cmath>

#include "scene/mesh.h"
#include "tests/support/test_support.h"

namespace bvhlab::scene {
namespace {

TEST(NumericDomain, MeshCoordinatesAndSize) {
    const float m = kMaxCoordinate;
    EXPECT_EQ(domain_problem(test::mesh_of({{0, 0, 0, m, 0, 0, 0, m, 0}})), "");
    EXPECT_EQ(domain_problem(test::mesh_of({{-m, -m, -m, m, 0, 0, 0, m, 0}})), "");
    const std::string far =
        domain_problem(test::mesh_of({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 0, 2 * m, 0, 0, 0, 1, 0}}));
    EXPECT_NE(far.find("vertex 5 (2e+10, 0, 0) is outside [-1e+10, 1e+10]"), std::string::npos) << far;
    const float d = kMinSceneDiagonal;
    EXPECT_EQ(domain_problem(test::mesh_of({{0, 0, 0, d, 0, 0, 0, d, 0}})), "");
    const std::string tiny = domain_problem(test::mesh_of({{0, 0, 0, d / 4, 0, 0, 0, d / 4, 0}}));
    EXPECT_NE(tiny.find("bounding-box diagonal"), std::string::npos) << tiny;
}

TEST(NumericDomain, Vectors) {
    EXPECT_EQ(vec_problem("v", {kMaxCoordinate, -kMaxCoordinate, 0}), "");
    EXPECT_NE(vec_problem("v", {0, std::nextafter(kMaxCoordinate, INFINITY), 0}), "");
    EXPECT_NE(vec_problem("v", {NAN, 0, 0}), "");
    EXPECT_NE(vec_problem("an origin", {3e18f, 0, 0}).find("an origin (3e+18, 0, 0)"), std::string::npos);
}

TEST(NumericDomain, Materials) {
    Material ok;
    ok.diffuse = {1, 0, 0};
    ok.emission = {kMaxRadiance, 0, 0};
    ok.ior = 0.0f;  // up to 1: the renderer's default 1.5
    EXPECT_EQ(material_problem(ok), "");
    const auto problem = [](auto set) {
        Material m;
        set(m);
        return material_problem(m);
    };
    EXPECT_NE(problem([](Material& m) {
                  m.diffuse = {-1, 0, 0};
              }).find("Kd -1 0 0 is not in [0, 1]"),
              std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.specular = {1.5f, 0, 0}; }).find("Ks"), std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.emission = {2 * kMaxRadiance, 0, 0}; }).find("Ke"), std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.ambient = {NAN, 0, 0}; }).find("Ka"), std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.ior = -1; }).find("Ni -1 is not in [0, 100]"), std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.dissolve = 2; }).find("d 2"), std::string::npos);
    EXPECT_NE(problem([](Material& m) { m.shininess = -1; }).find("Ns"), std::string::npos);
}

}  // namespace
}  // namespace bvhlab::scene
