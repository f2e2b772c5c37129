// SPDX-License-Identifier: MIT
// The BSDFs, samplers and the alias table against their definitions, by Monte Carlo.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "accel/core/check.h"
#include "renderer/core/bsdf.h"
#include "renderer/render_scene.h"

namespace bvhlab::render {
namespace {

RenderMaterial make(BsdfType type, float alpha = 0.3f) {
    RenderMaterial m = default_material();
    m.type = type;
    m.base = {0.5f, 0.6f, 0.7f};
    m.specular = {0.9f, 0.8f, 0.7f};
    m.alpha = alpha;
    m.ior = 1.5f;
    return m;
}

float rnd(uint32_t i, uint32_t d) { return rand01(i, 7, d, 3); }

Vec3 direction(float theta_deg, float phi_deg) {
    const float t = theta_deg * kPi / 180.0f, p = phi_deg * kPi / 180.0f;
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

class NonDeltaBsdf : public ::testing::TestWithParam<BsdfType> {};

// The density sample_bsdf reports integrates, over the sphere, to the fraction of samples it
// produced (the rest fell below the surface); estimated with uniform directions.
TEST_P(NonDeltaBsdf, DensityIntegratesToTheSampledFraction) {
    const RenderMaterial m = make(GetParam());
    for (float theta : {10.0f, 45.0f, 80.0f}) {
        const Vec3 wo = direction(theta, 30.0f);
        const int n = 400000;
        double integral = 0.0;
        int produced = 0;
        for (int i = 0; i < n; ++i) {
            const Vec3 wi = sample_uniform_sphere(rnd(i, 0), rnd(i, 1));
            float pdf;
            eval_bsdf(m, m.base, wo, wi, pdf);
            integral += pdf * 4.0 * kPi / n;
            BsdfSample s;
            produced += sample_bsdf(m, m.base, wo, rnd(i, 2), rnd(i, 3), rnd(i, 4), s);
        }
        EXPECT_NEAR(integral, double(produced) / n, 0.02) << "theta " << theta;
    }
}

// Each sample's weight is f cos / pdf evaluated at its direction, and its pdf is eval's.
TEST_P(NonDeltaBsdf, SampleWeightIsEvalOverPdf) {
    const RenderMaterial m = make(GetParam());
    const Vec3 wo = direction(40.0f, 10.0f);
    for (int i = 0; i < 2000; ++i) {
        BsdfSample s;
        if (!sample_bsdf(m, m.base, wo, rnd(i, 0), rnd(i, 1), rnd(i, 2), s)) continue;
        float pdf;
        const Vec3 f = eval_bsdf(m, m.base, wo, s.wi, pdf);
        EXPECT_FALSE(s.delta);
        EXPECT_NEAR(s.pdf, pdf, 1e-4f * pdf);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], f[c] / pdf, 1e-4f * (1.0f + s.weight[c]));
    }
}

// f(wo, wi) = f(wi, wo): eval returns f cos(wi), so divide by the cosines.
TEST_P(NonDeltaBsdf, IsReciprocal) {
    const RenderMaterial m = make(GetParam());
    for (int i = 0; i < 200; ++i) {
        const Vec3 a = sample_cosine_hemisphere(rnd(i, 0), rnd(i, 1)),
                   b = sample_cosine_hemisphere(rnd(i, 2), rnd(i, 3));
        if (a.z < 1e-3f || b.z < 1e-3f) continue;
        float p;
        const Vec3 fab = eval_bsdf(m, m.base, a, b, p) * (1.0f / b.z);
        const Vec3 fba = eval_bsdf(m, m.base, b, a, p) * (1.0f / a.z);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(fab[c], fba[c], 1e-3f * (1.0f + fab[c]));
    }
}

INSTANTIATE_TEST_SUITE_P(Lobes, NonDeltaBsdf,
                         ::testing::Values(BsdfType::kLambert, BsdfType::kConductor, BsdfType::kPlastic),
                         [](const auto& info) {
                             return info.param == BsdfType::kLambert     ? std::string("lambert")
                                    : info.param == BsdfType::kConductor ? std::string("conductor")
                                                                         : std::string("plastic");
                         });

// Directional albedo: Lambertian Kd = 1 reflects everything; a white GGX conductor loses what
// single scattering loses: about 1% at alpha 0.1, and at normal incidence exactly the reflections
// about normals steeper than 45 degrees, a fraction alpha^2 / (1 + alpha^2) of the visible ones.
TEST(Bsdf, WhiteFurnaceAlbedo) {
    auto albedo = [](const RenderMaterial& m, Vec3 wo, double* produced = nullptr) {
        double sum = 0.0;
        int ok = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i) {
            BsdfSample s;
            if (sample_bsdf(m, m.base, wo, rnd(i, 0), rnd(i, 1), rnd(i, 2), s)) {
                sum += s.weight.x;
                ++ok;
            }
        }
        if (produced) *produced = double(ok) / n;
        return sum / n;
    };
    RenderMaterial lambert = make(BsdfType::kLambert);
    lambert.base = splat(1.0f);
    EXPECT_NEAR(albedo(lambert, direction(60.0f, 0.0f)), 1.0, 1e-6);
    RenderMaterial metal = make(BsdfType::kConductor, 0.1f);
    metal.specular = splat(1.0f);
    for (float theta : {0.0f, 45.0f}) {
        const double a = albedo(metal, direction(theta, 0.0f));
        EXPECT_GT(a, 0.98) << theta;
        EXPECT_LE(a, 1.0) << theta;
    }
    for (float alpha : {0.3f, 0.8f}) {
        metal.alpha = alpha;
        double produced;
        EXPECT_LT(albedo(metal, direction(0.0f, 0.0f), &produced), produced);
        EXPECT_NEAR(produced, 1.0 / (1.0 + alpha * alpha), 0.005) << alpha;
    }
}

TEST(Bsdf, DielectricFresnel) {
    EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);         // ((n - 1) / (n + 1))^2
    EXPECT_NEAR(fresnel_dielectric(1.0f, 1.0f / 1.5f), 0.04f, 1e-6f);  // the same from inside
    // Total internal reflection beyond the critical angle asin(1 / 1.5) = 41.8 degrees.
    EXPECT_EQ(fresnel_dielectric(std::cos(45.0f * kPi / 180.0f), 1.0f / 1.5f), 1.0f);
    EXPECT_LT(fresnel_dielectric(std::cos(40.0f * kPi / 180.0f), 1.0f / 1.5f), 1.0f);
    // Grazing incidence reflects almost everything.
    EXPECT_GT(fresnel_dielectric(0.01f, 1.5f), 0.9f);
}

// Glass refracts by Snell's law and picks reflection with probability F.
TEST(Bsdf, GlassFollowsSnellAndFresnel) {
    const RenderMaterial g = make(BsdfType::kGlass);
    const Vec3 wo = direction(50.0f, 20.0f);
    const float f = fresnel_dielectric(wo.z, 1.5f);
    int reflected = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        BsdfSample s;
        ASSERT_TRUE(sample_bsdf(g, g.base, wo, rnd(i, 0), 0.5f, 0.5f, s));
        EXPECT_TRUE(s.delta);
        EXPECT_NEAR(length(s.wi), 1.0f, 1e-5f);
        if (s.wi.z > 0.0f) {
            ++reflected;
            EXPECT_NEAR(s.wi.z, wo.z, 1e-6f);
        } else {
            const float sin_o = std::sqrt(1.0f - wo.z * wo.z), sin_t = std::sqrt(1.0f - s.wi.z * s.wi.z);
            EXPECT_NEAR(sin_o, 1.5f * sin_t, 1e-5f);
            EXPECT_NEAR(s.weight.x, 1.0f / (1.5f * 1.5f), 1e-6f);  // radiance compressed entering
        }
    }
    EXPECT_NEAR(double(reflected) / n, f, 0.005);
}

TEST(Sampling, FrameIsOrthonormalForEveryNormal) {
    for (int i = 0; i < 1000; ++i) {
        const Vec3 n = sample_uniform_sphere(rnd(i, 0), rnd(i, 1));
        const Frame f = Frame::around(n);
        EXPECT_NEAR(dot(f.t, f.b), 0.0f, 1e-5f);
        EXPECT_NEAR(dot(f.t, n), 0.0f, 1e-5f);
        EXPECT_NEAR(dot(f.b, n), 0.0f, 1e-5f);
        EXPECT_NEAR(length(f.t), 1.0f, 1e-5f);
        const Vec3 v = f.to_world(f.to_local({0.3f, -0.5f, 0.8f}));
        EXPECT_NEAR(v.x, 0.3f, 1e-5f);
    }
    const Frame down = Frame::around({0.0f, 0.0f, -1.0f});
    EXPECT_NEAR(dot(down.t, down.b), 0.0f, 1e-6f);
}

TEST(Sampling, RandomNumbersAreUniformAndDecorrelated) {
    const int n = 100000;
    double sum = 0.0, sum_xy = 0.0;
    int bins[10] = {};
    for (int i = 0; i < n; ++i) {
        const float a = rand01(uint32_t(i), 0, 0, 1), b = rand01(uint32_t(i), 0, 1, 1);
        ASSERT_GE(a, 0.0f);
        ASSERT_LT(a, 1.0f);
        sum += a;
        sum_xy += (a - 0.5) * (b - 0.5);
        ++bins[int(a * 10)];
    }
    EXPECT_NEAR(sum / n, 0.5, 0.005);
    EXPECT_NEAR(sum_xy / n, 0.0, 0.003);
    for (int b : bins) EXPECT_NEAR(b, n / 10, 500);
    EXPECT_NE(rand01(1, 2, 3, 4), rand01(1, 2, 3, 5));  // the seed matters
}

TEST(AliasTable, PicksInProportionToWeight) {
    const std::vector<double> w = {1.0, 0.0, 3.0, 0.5, 5.5};
    const std::vector<AliasEntry> t = build_alias_table(w);
    std::vector<int> count(w.size(), 0);
    const int n = 1000000;
    for (int i = 0; i < n; ++i) ++count[alias_pick(t.data(), uint32_t(t.size()), (float(i) + 0.5f) / float(n))];
    for (size_t i = 0; i < w.size(); ++i) EXPECT_NEAR(double(count[i]) / n, w[i] / 10.0, 1e-3) << i;
    EXPECT_THROW(build_alias_table({0.0, 0.0}), Error);
    EXPECT_THROW(build_alias_table({}), Error);
}

TEST(Materials, MtlMappingFollowsTheDocumentedTable) {
    scene::Material m;
    m.diffuse = {0.5f, 0.5f, 0.5f};
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kLambert);
    m.illum = 2;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kLambert);  // Ks black
    m.specular = {0.04f, 0.04f, 0.04f};
    m.shininess = 100.0f;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kPlastic);
    EXPECT_NEAR(map_material(m, -1).alpha, std::sqrt(2.0f / 102.0f), 1e-6f);
    EXPECT_NEAR(map_material(m, -1).ior, 1.5f, 0.0f);  // Ni absent (1)
    m.illum = 3;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kConductor);
    m.shininess = 1000.0f;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kMirror);
    m.specular = {0.0f, 0.0f, 0.0f};
    EXPECT_NEAR(map_material(m, -1).specular.x, 0.5f, 0.0f);  // Kd when Ks is black
    m.illum = 7;
    m.ior = 1.33f;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kGlass);
    EXPECT_NEAR(map_material(m, -1).ior, 1.33f, 0.0f);
    m.illum = 2;
    m.dissolve = 0.5f;
    EXPECT_EQ(map_material(m, -1).type, BsdfType::kGlass);
    // Ke makes a light; Ka above 1 does only when Ke is black.
    scene::Material l;
    l.ambient = {20.0f, 20.0f, 20.0f};
    EXPECT_NEAR(map_material(l, -1).emission.x, 20.0f, 0.0f);
    l.emission = {1.0f, 2.0f, 3.0f};
    EXPECT_NEAR(map_material(l, -1).emission.x, 1.0f, 0.0f);
    scene::Material ambient_only;
    ambient_only.ambient = {0.2f, 0.2f, 0.2f};
    EXPECT_EQ(max3(map_material(ambient_only, -1).emission), 0.0f);
    EXPECT_NEAR(roughness_from_shininess(0.0f), 1.0f, 0.0f);
    EXPECT_NEAR(roughness_from_shininess(1e9f), 0.001f, 0.0f);
}

}  // namespace
}  // namespace bvhlab::render
