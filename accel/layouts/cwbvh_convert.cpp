// SPDX-License-Identifier: MIT
#include "accel/layouts/cwbvh_convert.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <string>

#include "accel/core/check.h"

namespace bvhlab::accel {
namespace {

/// The largest scale exponent: the traversal scales 2^e by 2^15 and by a reciprocal of up to
/// 2^80 (safe_reciprocal), which must stay below FLT_MAX.
constexpr int kMaxExponent = 31;
constexpr int kMinExponent = -126;

/// Slot of each child (Ylitie et al., section 3.2): the child furthest in octant direction s
/// from the node's centre takes slot s, assigned greedily over all (child, slot) pairs.
std::array<int, kWideArity> assign_slots(const WideNode& n) {
    const Vec3 centre = n.bounds.center();
    struct Pair {
        float score;
        int child, slot;
    };
    std::vector<Pair> pairs;
    for (uint32_t c = 0; c < n.child_count; ++c) {
        const Vec3 d = n.child[c].box.center() - centre;
        for (int s = 0; s < int(kWideArity); ++s) {
            const float score = (s & 1 ? d.x : -d.x) + (s & 2 ? d.y : -d.y) + (s & 4 ? d.z : -d.z);
            pairs.push_back({score, int(c), s});
        }
    }
    std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.score > b.score; });
    std::array<int, kWideArity> child_of_slot;
    child_of_slot.fill(-1);
    std::array<bool, kWideArity> placed{};
    for (const Pair& p : pairs) {
        if (placed[size_t(p.child)] || child_of_slot[size_t(p.slot)] >= 0) continue;
        placed[size_t(p.child)] = true;
        child_of_slot[size_t(p.slot)] = p.child;
    }
    return child_of_slot;
}

/// Smallest e with 255 * 2^e >= extent (doubles; exact for float inputs).
int scale_exponent(double extent) {
    if (!(extent > 0.0)) return kMinExponent;
    int e = int(std::ceil(std::log2(extent / 255.0)));
    while (255.0 * std::ldexp(1.0, e) < extent) ++e;
    while (e > kMinExponent && 255.0 * std::ldexp(1.0, e - 1) >= extent) --e;
    return std::max(e, kMinExponent);
}

void quantise(const WideNode& n, const std::array<int, kWideArity>& child_of_slot, CwbvhNode& out) {
    for (int k = 0; k < 3; ++k) {
        const double p = n.bounds.lo[k];
        const int e = scale_exponent(double(n.bounds.hi[k]) - p);
        if (e > kMaxExponent)
            throw Error("a node of the scene spans " + std::to_string(double(n.bounds.hi[k]) - p) +
                        " units on one axis: too large for the CWBVH's quantised boxes");
        out.p[k] = n.bounds.lo[k];
        out.e[k] = uint8_t(e + 127);
        const double s = std::ldexp(1.0, e);
        for (int slot = 0; slot < int(kWideArity); ++slot) {
            const int c = child_of_slot[size_t(slot)];
            if (c < 0) {
                out.qlo[k][slot] = 255;  // an empty box: no ray enters it
                out.qhi[k][slot] = 0;
                continue;
            }
            const AABB& b = n.child[c].box;
            double lo = std::floor((double(b.lo[k]) - p) / s), hi = std::ceil((double(b.hi[k]) - p) / s);
            lo = std::clamp(lo, 0.0, 255.0);
            hi = std::clamp(hi, 0.0, 255.0);
            while (lo > 0.0 && p + lo * s > double(b.lo[k])) lo -= 1.0;
            while (hi < 255.0 && p + hi * s < double(b.hi[k])) hi += 1.0;
            out.qlo[k][slot] = uint8_t(lo);
            out.qhi[k][slot] = uint8_t(hi);
        }
    }
}

}  // namespace

AABB decode_child_box(const CwbvhNode& node, uint32_t slot, double* lo, double* hi) {
    AABB b;
    for (int k = 0; k < 3; ++k) {
        const double s = std::ldexp(1.0, int(node.e[k]) - 127);
        const double l = double(node.p[k]) + node.qlo[k][slot] * s, h = double(node.p[k]) + node.qhi[k][slot] * s;
        if (lo) lo[k] = l;
        if (hi) hi[k] = h;
        b.lo[k] = float(l);
        b.hi[k] = float(h);
    }
    return b;
}

Cwbvh convert_cwbvh_nodes(const WideTree& w, std::vector<std::array<AABB, kWideArity>>* slot_boxes) {
    BVHLAB_CHECK(!w.nodes.empty(), "cannot convert an empty WideTree");
    Cwbvh out;
    out.depth = w.depth;
    out.nodes.reserve(w.nodes.size());
    out.tri_ids.reserve(w.prim_indices.size());
    // Breadth-first, so that each node's interior children are contiguous (child_base).
    std::deque<std::pair<uint32_t, uint32_t>> queue{{0u, 0u}};  // (wide node, output node)
    out.nodes.emplace_back();
    while (!queue.empty()) {
        const auto [wi, oi] = queue.front();
        queue.pop_front();
        const WideNode& n = w.nodes[wi];
        const auto child_of_slot = assign_slots(n);
        CwbvhNode node{};
        quantise(n, child_of_slot, node);
        node.child_base = uint32_t(out.nodes.size());
        node.tri_base = uint32_t(out.tri_ids.size());
        for (uint32_t slot = 0; slot < kWideArity; ++slot) {
            const int c = child_of_slot[slot];
            if (c < 0) continue;
            const WideChild& ch = n.child[c];
            if (ch.is_leaf()) {
                const uint32_t offset = uint32_t(out.tri_ids.size()) - node.tri_base;
                node.meta[slot] = CwbvhNode::leaf_meta(offset, ch.count);
                for (uint32_t k = 0; k < ch.count; ++k) out.tri_ids.push_back(w.prim_indices[ch.index + k]);
            } else {
                node.meta[slot] = CwbvhNode::interior_meta(slot);
                node.imask = uint8_t(node.imask | (1u << slot));
                queue.push_back({ch.index, uint32_t(out.nodes.size())});
                out.nodes.emplace_back();
            }
        }
        out.nodes[oi] = node;
        if (slot_boxes) {
            if (slot_boxes->size() <= oi) slot_boxes->resize(out.nodes.size());
            for (uint32_t slot = 0; slot < kWideArity; ++slot)
                (*slot_boxes)[oi][slot] = child_of_slot[slot] < 0 ? AABB::empty() : n.child[child_of_slot[slot]].box;
        }
    }
    return out;
}

Cwbvh convert_to_cwbvh(const WideTree& w, const scene::TriangleMesh& mesh, CwTris tri_format,
                       std::vector<std::array<AABB, kWideArity>>* slot_boxes) {
    Cwbvh out = convert_cwbvh_nodes(w, slot_boxes);
    out.tri_format = tri_format;
    if (tri_format == CwTris::kWoop)
        out.tris.resize(out.tri_ids.size());
    else
        out.vtris.resize(out.tri_ids.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.tri_ids.size(), 4096), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            const uint32_t t = out.tri_ids[i];
            const Vec3 a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
            if (tri_format == CwTris::kWoop)
                out.tris[i] = make_woop_triangle(a, b, c);
            else
                out.vtris[i] = make_vertex_triangle(a, b, c);
        }
    });
    return out;
}

}  // namespace bvhlab::accel
