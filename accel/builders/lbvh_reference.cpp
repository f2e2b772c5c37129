// SPDX-License-Identifier: MIT
#include "accel/builders/lbvh_reference.h"

#include <algorithm>
#include <numeric>

#include "accel/core/check.h"
#include "accel/core/morton.h"

namespace bvhlab::accel {

namespace {

template <typename Key>
void emit_hierarchy(RawHierarchy& h, const std::vector<Key>& keys) {
    const int64_t n = int64_t(keys.size());
    h.left.resize(size_t(n - 1));
    h.right.resize(size_t(n - 1));
    std::vector<uint32_t> parent(size_t(2 * n - 1), ~0u);
    for (int64_t i = 0; i + 1 < n; ++i) {
        morton::karras_children(keys.data(), n, i, h.left[size_t(i)], h.right[size_t(i)]);
        parent[h.left[size_t(i)]] = uint32_t(n + i);
        parent[h.right[size_t(i)]] = uint32_t(n + i);
    }
    // Boxes bottom-up as the GPU fits them: from each leaf upwards, a node is boxed by the
    // second of its children to arrive (the GPU's atomic counters, in one thread).
    std::vector<uint8_t> visits(size_t(n - 1), 0);
    for (int64_t k = 0; k < n; ++k) {
        uint32_t p = parent[size_t(k)];
        while (p != ~0u) {
            const size_t i = size_t(p - n);
            if (++visits[i] < 2) break;
            h.boxes[p] = merge(h.boxes[h.left[i]], h.boxes[h.right[i]]);
            p = parent[p];
        }
    }
    h.root = uint32_t(n);
}

}  // namespace

RawHierarchy lbvh_reference(const scene::TriangleMesh& mesh, int morton_bits) {
    if (morton_bits != 30 && morton_bits != 60)
        throw Error("morton_bits " + std::to_string(morton_bits) + " is neither 30 nor 60");
    const size_t n = mesh.triangle_count();
    if (n == 0) throw Error("the mesh has no triangles to build a structure over");
    RawHierarchy h;
    h.boxes.resize(2 * n - 1);
    std::vector<AABB> tri(n);
    AABB centres = AABB::empty();
    for (size_t t = 0; t < n; ++t) {
        tri[t] = mesh.triangle_bounds(t);
        centres.extend(tri[t].center());
    }
    const uint32_t cells = morton::cells_per_axis(morton_bits);
    const Vec3 scale{morton::axis_scale(centres.lo.x, centres.hi.x, cells),
                     morton::axis_scale(centres.lo.y, centres.hi.y, cells),
                     morton::axis_scale(centres.lo.z, centres.hi.z, cells)};
    std::vector<uint64_t> codes(n);
    for (size_t t = 0; t < n; ++t)
        codes[t] = morton_bits == 60 ? morton::code60(tri[t].center(), centres.lo, scale)
                                     : morton::code30(tri[t].center(), centres.lo, scale);
    h.sorted_ids.resize(n);
    std::iota(h.sorted_ids.begin(), h.sorted_ids.end(), 0u);
    // The GPU's radix sort is stable: equal keys keep the order of their triangle ids.
    std::stable_sort(h.sorted_ids.begin(), h.sorted_ids.end(),
                     [&](uint32_t a, uint32_t b) { return codes[a] < codes[b]; });
    h.keys.resize(n);
    for (size_t k = 0; k < n; ++k) {
        h.keys[k] = codes[h.sorted_ids[k]];
        h.boxes[k] = tri[h.sorted_ids[k]];
    }
    if (n == 1) return h;  // the root is leaf 0
    if (morton_bits == 60) {
        emit_hierarchy(h, h.keys);
    } else {
        std::vector<uint32_t> k32(h.keys.begin(), h.keys.end());
        emit_hierarchy(h, k32);
    }
    return h;
}

}  // namespace bvhlab::accel
