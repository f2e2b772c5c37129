// SPDX-License-Identifier: MIT
#include "scene/io/procedural.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "accel/core/check.h"
#include "accel/core/random.h"

namespace bvhlab::scene {
namespace {

float unit(uint64_t seed, uint64_t i, uint64_t k) { return unit_float(splitmix64(seed ^ splitmix64(i * 16 + k))); }

/// Soup: each triangle is a random centre plus three random offsets. Generated triangles
/// are non-degenerate with probability ~1; any that is not is regenerated with another stream.
TriangleMesh soup(uint64_t n, uint64_t seed) {
    TriangleMesh m;
    m.vertices.resize(3 * n);
    m.indices.resize(3 * n);
    m.material_ids.assign(n, -1);
    const float size = 2.0f / std::cbrt(float(n));
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, 8192), [&](const auto& r) {
        for (uint64_t i = r.begin(); i < r.end(); ++i) {
            for (uint64_t attempt = 0;; ++attempt) {
                const uint64_t s = seed + attempt * 0x632be59bd9b4e019ull;
                Vec3 c{unit(s, i, 0), unit(s, i, 1), unit(s, i, 2)};
                Vec3 v[3];
                for (int k = 0; k < 3; ++k)
                    v[k] = c + Vec3{unit(s, i, 3 + 3 * k) - 0.5f, unit(s, i, 4 + 3 * k) - 0.5f,
                                    unit(s, i, 5 + 3 * k) - 0.5f} *
                                   size;
                if (check_triangle(v[0], v[1], v[2]) != TriangleCheck::kOk) continue;
                for (int k = 0; k < 3; ++k) {
                    m.vertices[3 * i + k] = flush_denormals(v[k]);
                    m.indices[3 * i + k] = uint32_t(3 * i + k);
                }
                break;
            }
        }
    });
    return m;
}

void add_quad(TriangleMesh& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint64_t& budget) {
    if (budget > 0 && add_triangle_checked(m, a, b, c, -1)) --budget;
    if (budget > 0 && add_triangle_checked(m, a, c, d, -1)) --budget;
}

/// Structured: about 90% of the budget in a height field, the rest in axis-aligned boxes
/// (12 triangles each) on it; both use exact coordinates, so shared edges are watertight.
TriangleMesh structured(uint64_t n, uint64_t seed) {
    TriangleMesh m;
    uint64_t budget = n;
    const uint64_t boxes = n >= 120 ? n / 10 / 12 : 0;
    uint64_t field = n - boxes * 12;
    const auto w = uint64_t(std::ceil(std::sqrt(double((field + 1) / 2))));
    auto height = [&](uint64_t x, uint64_t y) {
        const float fx = float(x) / float(w), fy = float(y) / float(w);
        return 0.05f * std::sin(12.0f * fx + 3.0f * unit(seed, 0, 0)) * std::cos(9.0f * fy);
    };
    auto p = [&](uint64_t x, uint64_t y) { return Vec3{float(x) / float(w), height(x, y), float(y) / float(w)}; };
    uint64_t field_budget = field;
    for (uint64_t y = 0; y < w && field_budget > 0; ++y)
        for (uint64_t x = 0; x < w && field_budget > 0; ++x)
            add_quad(m, p(x, y), p(x, y + 1), p(x + 1, y + 1), p(x + 1, y), field_budget);
    budget = boxes * 12 + field_budget;
    for (uint64_t b = 0; b < boxes; ++b) {
        const float cx = unit(seed, b, 1), cz = unit(seed, b, 2);
        const float s = 0.004f + 0.02f * unit(seed, b, 3), h = 0.01f + 0.1f * unit(seed, b, 4);
        const Vec3 lo{cx - s, -0.06f, cz - s}, hi{cx + s, 0.06f + h, cz + s};
        Vec3 c[8];
        for (int k = 0; k < 8; ++k) c[k] = {(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
        add_quad(m, c[0], c[1], c[3], c[2], budget);
        add_quad(m, c[4], c[6], c[7], c[5], budget);
        add_quad(m, c[0], c[4], c[5], c[1], budget);
        add_quad(m, c[2], c[3], c[7], c[6], budget);
        add_quad(m, c[0], c[2], c[6], c[4], budget);
        add_quad(m, c[1], c[5], c[7], c[3], budget);
    }
    // Pad with small floating triangles if rounding left any of the budget.
    for (uint64_t i = 0; budget > 0; ++i) {
        const Vec3 c{unit(seed, i, 5), 0.3f, unit(seed, i, 6)};
        if (add_triangle_checked(m, c, c + Vec3{0.01f, 0, 0}, c + Vec3{0, 0, 0.01f}, -1)) --budget;
    }
    return m;
}

}  // namespace

ProceduralKind parse_procedural_kind(const std::string& name) {
    if (name == "soup") return ProceduralKind::kSoup;
    if (name == "structured") return ProceduralKind::kStructured;
    throw Error("unknown procedural scene kind '" + name + "' (expected soup or structured)");
}

TriangleMesh make_procedural(ProceduralKind kind, uint64_t triangles, uint64_t seed) {
    BVHLAB_CHECK(triangles >= 1, "a procedural scene needs at least one triangle");
    BVHLAB_CHECK(triangles <= (1ull << 30), "procedural scenes are limited to 2^30 triangles");
    return kind == ProceduralKind::kSoup ? soup(triangles, seed) : structured(triangles, seed);
}

}  // namespace bvhlab::scene
