// SPDX-License-Identifier: MIT
// Rays on the edges and planes of a structure, for the CPU and GPU tests. A lattice scene puts
// everything on the integer planes of [0, 32]^3 (cubes, zero-thickness quads, long triangles
// with integer vertices that spatial splits cut, vertices exactly on planes), so kd and SBVH
// split planes fall on faces, vertices and flat triangles. The rays come from the structure's
// own boxes (BVH2 child boxes, CWBVH decoded child boxes, kd cells): rays along box faces
// (a zero direction component, both signs of zero), along box edges (two zero components),
// through and from box corners, starting on a face, with tmin = tmax, and crossing and
// grazing flat boxes.
#pragma once

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "accel/layouts/cwbvh_convert.h"
#include "scene/mesh.h"
#include "traversal/device/ray.h"
#include "traversal/structure.h"

namespace bvhlab::test {

/// Cubes, flat quads and long triangles on the integer planes of [0, 32]^3, seeded.
inline scene::TriangleMesh make_lattice_scene(uint32_t seed) {
    std::mt19937 rng(seed);
    auto ri = [&](int lo, int hi) { return float(std::uniform_int_distribution<int>(lo, hi)(rng)); };
    scene::TriangleMesh m;
    auto tri = [&](Vec3 a, Vec3 b, Vec3 c) { scene::add_triangle_checked(m, a, b, c, -1); };
    auto quad = [&](Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
        tri(a, b, c);
        tri(a, c, d);
    };
    // The root box is exactly [0, 32]^3, so root-level spatial bins fall on integers too.
    tri({0, 0, 0}, {32, 32, 32}, {32, 0, 0});
    for (int i = 0; i < 40; ++i) {  // boxes of 1-2 units: faces on integer planes
        const Vec3 lo{ri(0, 29), ri(0, 29), ri(0, 29)};
        const Vec3 hi = lo + Vec3{ri(1, 2), ri(1, 2), ri(1, 2)};
        quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z});
        quad({lo.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z});
        quad({lo.x, lo.y, lo.z}, {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, lo.y, lo.z});
        quad({lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
        quad({lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z});
        quad({hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, hi.y, lo.z});
    }
    for (int i = 0; i < 30; ++i) {  // zero-thickness quads on integer planes, some on cube faces
        const int k = int(ri(0, 2));
        const float at = ri(0, 32), a0 = ri(0, 28), b0 = ri(0, 28), a1 = a0 + ri(1, 4), b1 = b0 + ri(1, 4);
        auto p = [&](float a, float b) {
            Vec3 v;
            v[k] = at;
            v[(k + 1) % 3] = a;
            v[(k + 2) % 3] = b;
            return v;
        };
        quad(p(a0, b0), p(a1, b0), p(a1, b1), p(a0, b1));
    }
    for (int i = 0; i < 30; ++i)  // long triangles with integer vertices, cut by spatial splits
        tri({ri(0, 32), ri(0, 32), ri(0, 32)}, {ri(0, 32), ri(0, 32), ri(0, 32)}, {ri(0, 32), ri(0, 32), ri(0, 32)});
    for (int i = 0; i < 30; ++i) {  // one vertex on a lattice point, the others off the planes
        const Vec3 a{ri(1, 31), ri(1, 31), ri(1, 31)};
        tri(a, a + Vec3{ri(-2, 2) + 0.5f, ri(-2, 2) + 0.25f, 0.75f}, a + Vec3{0.5f, ri(-2, 2) + 0.75f, -1.25f});
    }
    return m;
}

/// The boxes a traversal of `s` tests: BVH2 child boxes, CWBVH child boxes as decoded, or
/// kd-tree cells (interior and leaf).
inline std::vector<AABB> structure_boxes(const trav::Structure& s) {
    std::vector<AABB> boxes;
    const auto bvh2_boxes = [&boxes](const accel::Bvh2& bvh) {
        for (const accel::Bvh2Node& n : bvh.nodes)
            for (int slot = 0; slot < 2; ++slot)
                if (!n.child_box(slot).is_empty()) boxes.push_back(n.child_box(slot));  // a root leaf's 2nd is empty
    };
    const auto cwbvh_boxes = [&boxes](const accel::Cwbvh& cw) {
        for (const accel::CwbvhNode& n : cw.nodes)
            for (uint32_t slot = 0; slot < 8; ++slot)
                if (n.meta[slot] != 0) boxes.push_back(accel::decode_child_box(n, slot));
    };
    if (s.layout == trav::Layout::kBvh2) {
        bvh2_boxes(s.bvh2);
    } else if (trav::is_two_level(s.layout)) {
        // The TLAS's world boxes and each BLAS's (object space: the world's under identity).
        bvh2_boxes(s.two_level.tlas);
        for (const accel::Bvh2& b : s.two_level.blas) bvh2_boxes(b);
        for (const accel::Cwbvh& b : s.two_level.cw_blas) cwbvh_boxes(b);
        if (!s.two_level.cw_tlas.nodes.empty()) cwbvh_boxes(s.two_level.cw_tlas);
    } else if (s.layout == trav::Layout::kCwbvh) {
        cwbvh_boxes(s.cwbvh);
    } else {
        std::vector<std::pair<uint32_t, AABB>> todo{{0u, s.kd.tree.bounds}};
        while (!todo.empty()) {
            const auto [i, box] = todo.back();
            todo.pop_back();
            boxes.push_back(box);
            const accel::KdNode& n = s.kd.tree.nodes[i];
            if (n.is_leaf()) continue;
            AABB below = box, above = box;
            below.hi[int(n.axis())] = n.split();
            above.lo[int(n.axis())] = n.split();
            todo.push_back({n.child(), below});
            todo.push_back({n.child() + 1, above});
        }
    }
    return boxes;
}

/// Up to `max_boxes` of `boxes` (a seeded sample), and for each: rays along a face, along an
/// edge, through a corner, from a corner, from a face, with tmin = tmax, and across and along
/// the box when it is flat. `scene` is the scene's box (origins start outside it).
inline std::vector<trav::Ray> edge_rays(const std::vector<AABB>& boxes, const AABB& scene, uint32_t seed,
                                        size_t max_boxes) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    auto coin = [&] { return unit(rng) < 0.5f; };
    auto zero = [&] { return coin() ? 0.0f : -0.0f; };
    const Vec3 ext = scene.hi - scene.lo;
    const float far = 2.0f * (std::max({ext.x, ext.y, ext.z}) + 1.0f);
    std::vector<size_t> order(boxes.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::shuffle(order.begin(), order.end(), rng);
    order.resize(std::min(order.size(), max_boxes));
    std::vector<trav::Ray> rays;
    auto add = [&](Vec3 o, Vec3 d, float tmin = 0.0f, float tmax = INFINITY) { rays.push_back({o, tmin, d, tmax}); };
    auto random_dir = [&] {
        Vec3 d{unit(rng) * 2 - 1, unit(rng) * 2 - 1, unit(rng) * 2 - 1};
        return length(d) > 0.1f ? d : Vec3{0.3f, -1.0f, 0.2f};
    };
    for (size_t bi : order) {
        const AABB& b = boxes[bi];
        auto within = [&](int k) {  // a coordinate across the box, 10% past each side
            const float w = b.hi[k] - b.lo[k];
            return b.lo[k] - 0.1f * w + 1.2f * w * unit(rng);
        };
        auto face_point = [&](int k, bool hi_side) {
            Vec3 p;
            p[k] = hi_side ? b.hi[k] : b.lo[k];
            p[(k + 1) % 3] = within((k + 1) % 3);
            p[(k + 2) % 3] = within((k + 2) % 3);
            return p;
        };
        // Along a face: in its plane, from outside the scene.
        {
            const int k = int(rng() % 3);
            Vec3 p = face_point(k, coin()), d;
            const float a = 6.2831853f * unit(rng);
            d[k] = zero();
            d[(k + 1) % 3] = std::cos(a);
            d[(k + 2) % 3] = std::sin(a);
            Vec3 o = p - d * far;
            o[k] = p[k];  // exactly in the plane
            add(o, d);
        }
        // Along an edge: two coordinates on the box's planes, the third axis the direction.
        {
            const int j = int(rng() % 3), k1 = (j + 1) % 3, k2 = (j + 2) % 3;
            Vec3 o, d;
            o[k1] = coin() ? b.hi[k1] : b.lo[k1];
            o[k2] = coin() ? b.hi[k2] : b.lo[k2];
            const bool up = coin();
            o[j] = up ? scene.lo[j] - 1.0f : scene.hi[j] + 1.0f;
            d[j] = up ? 1.0f : -1.0f;
            d[k1] = zero();
            d[k2] = zero();
            add(o, d);
        }
        const Vec3 corner{coin() ? b.hi.x : b.lo.x, coin() ? b.hi.y : b.lo.y, coin() ? b.hi.z : b.lo.z};
        // Through a corner (d reaches it at t = 1, up to rounding), and the same ray cut to
        // tmin = tmax = 1.
        {
            const Vec3 o = corner + random_dir() * (1.0f + far * 0.25f * unit(rng));
            add(o, corner - o);
            add(o, corner - o, 1.0f, 1.0f);
        }
        add(corner, random_dir());  // from a corner
        {                           // from a face, inwards or outwards
            const int k = int(rng() % 3);
            const Vec3 p = face_point(k, coin());
            Vec3 d = random_dir();
            if (std::fabs(d[k]) < 0.05f) d[k] = 0.3f;
            add(p, d);
        }
        // Flat boxes (a leaf of flat triangles, a kd cell between equal planes): across the
        // plane inside the box, and along it.
        for (int k = 0; k < 3; ++k) {
            if (b.lo[k] != b.hi[k]) continue;
            const Vec3 p = face_point(k, false);
            Vec3 d{0.2f * (unit(rng) - 0.5f), 0.2f * (unit(rng) - 0.5f), 0.2f * (unit(rng) - 0.5f)};
            const float side = coin() ? 1.0f : -1.0f;
            d[k] = -side;
            add(p - d * (1.0f + 2.0f * unit(rng)), d);
            Vec3 along = random_dir();
            along[k] = zero();
            if (length(along) < 0.1f) along[(k + 1) % 3] = 1.0f;
            Vec3 o = p - along * far;
            o[k] = p[k];
            add(o, along);
        }
    }
    return rays;
}

}  // namespace bvhlab::test
