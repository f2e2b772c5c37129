// SPDX-License-Identifier: MIT
// The kd-tree builder's split search, kLanes candidates at a time through GCC/Clang vector
// types, each search in a portable copy and (x86-64) an AVX2 copy.
#include "accel/builders/kd/plane_search.h"

#include <algorithm>
#include <cstring>

namespace bvhlab::accel::kd {
namespace {

/// Eight floats or ints (GCC/Clang vector types): one AVX2 register, or two SSE or NEON ones.
/// They must never cross a call that is not inlined: the AVX2 copies pass them in one register
/// and the portable code in memory, so every function that takes or returns one is
/// always_inline. (to_float and the cost evaluation were once only `inline`: at -O0 they were
/// real calls, and a sanitizer build read their arguments from a garbage address.) They never
/// appear in a header.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
using FV = float __attribute__((vector_size(4 * kLanes)));
using IV = int32_t __attribute__((vector_size(4 * kLanes)));
__attribute__((always_inline)) inline FV to_float(const IV& x) { return __builtin_convertvector(x, FV); }
/// The smallest lane (inlined into the AVX2 copies as into the portable ones).
__attribute__((always_inline)) inline float hmin(const FV& x) {
    float m = x[0];
    for (uint32_t i = 1; i < kLanes; ++i) m = std::min(m, x[i]);
    return m;
}
/// x86-64 builds carry a second copy of each search compiled for AVX2, used when the CPU has
/// it (the portable copy runs each vector as two SSE halves).
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define BVHLAB_KD_AVX2 1
#else
#define BVHLAB_KD_AVX2 0
#endif

/// The cost of kLanes planes at once (F positions, I counts left and right).
template <typename F, typename I>
__attribute__((always_inline)) inline F evaluate(const AxisCost& c, const F& pos, const I& nl, const I& nr) {
    const F pl = c.face + c.side * (pos - c.lo), pr = c.face + c.side * (c.hi - pos);
    const F cost = c.ct + c.ci * (pl * to_float(nl) + pr * to_float(nr));
    return ((nl == 0) | (nr == 0)) ? cost * c.bonus : cost;
}

/// price_positions() on one axis, kLanes positions at a time. At a position: left of the
/// plane, every bound that starts before it and every flat bound up to it; right, every bound
/// that ends after it (so the starts at it go right). A flat bound at the position counts left
/// for the left-first cost, right for the right-first one; without flat bounds on the axis
/// (kFlat false) the two are the same. Ties go to the lower position, then left first, as in a
/// scalar loop that keeps only strictly cheaper planes.
template <bool kFlat>
__attribute__((always_inline)) inline Plane price_body(const Sweep& s, uint32_t n, int k, const AxisCost& cost) {
    // Loads kLanes records from entry i (an out parameter: a vector return value would change
    // the ABI between the two copies).
    const auto load = [](IV& v, const std::vector<uint32_t>& a, size_t i) { std::memcpy(&v, a.data() + i, sizeof v); };
    IV lane;
    for (uint32_t i = 0; i < kLanes; ++i) lane[i] = int32_t(i);
    const FV inf = FV{} + INFINITY;
    // Per lane: the cheapest cost seen and its candidate's order, 2 g (+ 1 right first).
    FV best = inf;
    IV best_at = IV{};
    const auto groups = int32_t(s.groups);
    for (int32_t g = 0; g < groups; g += int32_t(kLanes)) {
        IV key, planars_to, starts_before, ends_to;
        load(key, s.key, size_t(g) + 1);
        load(planars_to, s.planars, size_t(g) + 1);
        load(starts_before, s.starts, size_t(g));
        load(ends_to, s.ends, size_t(g) + 1);
        const IV left = starts_before + planars_to;
        const IV right = int32_t(n) - ends_to - planars_to;
        // from_sort_key, kLanes at a time (keys with the top bit set are negative here)
        const IV bits = key < 0 ? (key & 0x7fffffff) : ~key;
        FV pos;
        std::memcpy(&pos, &bits, sizeof pos);
        const IV order = 2 * (g + lane);
        const IV inside = (g + lane < groups) & (pos > cost.lo) & (pos < cost.hi);
        const FV c = inside ? evaluate(cost, pos, left, right) : inf;
        IV cheaper = c < best;
        best = cheaper ? c : best;
        best_at = cheaper ? order : best_at;
        if (kFlat) {
            IV planars_before;
            load(planars_before, s.planars, size_t(g));
            const IV planars = planars_to - planars_before;
            const FV r = inside & (planars != 0) ? evaluate(cost, pos, left - planars, right + planars) : inf;
            cheaper = r < best;
            best = cheaper ? r : best;
            best_at = cheaper ? order + 1 : best_at;
        }
    }
    const float m = hmin(best);
    if (!(m < INFINITY)) return Plane{};
    int32_t at = INT32_MAX;
    for (uint32_t i = 0; i < kLanes; ++i)
        if (best[i] == m) at = std::min(at, best_at[i]);
    return {m, k, from_sort_key(s.key[size_t(at / 2) + 1]), at % 2 == 0};
}

template <bool kFlat>
Plane price(const Sweep& s, uint32_t n, int k, const AxisCost& cost) {
    return price_body<kFlat>(s, n, k, cost);
}
#if BVHLAB_KD_AVX2
template <bool kFlat>
__attribute__((target("avx2"))) Plane price_avx2(const Sweep& s, uint32_t n, int k, const AxisCost& cost) {
    return price_body<kFlat>(s, n, k, cost);
}
#endif

/// The cheapest plane on axis k of a small node, in versions by node size: kMax is the most
/// vectors per candidate list, so that loops unroll and vectors stay in registers. Without
/// flat (planar) bounds on this axis, which is the common case, both sides of a plane cost the
/// same and half the work is skipped.
template <bool kFlat, uint32_t kMax>
__attribute__((always_inline)) inline Plane small_axis_body(const SmallWork& w, int k, const AxisCost& cost) {
    const uint32_t n = w.n, vecs = kMax == 1 ? 1 : (n + kLanes - 1) / kLanes;
    const FV inf = FV{} + INFINITY;
    // Candidates: the lower bounds (list 0) and the upper bounds (list 1).
    FV pos[2][kMax];
    IV below[2][kMax], above[2][kMax], planar[2][kMax];
    for (uint32_t v = 0; v < vecs; ++v) {
        std::memcpy(&pos[0][v], &w.lo[k][kLanes * v], sizeof(FV));
        std::memcpy(&pos[1][v], &w.hi[k][kLanes * v], sizeof(FV));
        for (int l = 0; l < 2; ++l) below[l][v] = above[l][v] = planar[l][v] = IV{};
    }
    for (uint32_t s = 0; s < n; ++s) {
        const float lo = w.lo[k][s], hi = w.hi[k][s];
        const IV flat = IV{} - int32_t(lo == hi);  // all ones when flat
        for (int l = 0; l < 2; ++l)
            for (uint32_t v = 0; v < vecs; ++v) {  // comparisons give -1 for true
                below[l][v] -= lo < pos[l][v];
                above[l][v] -= hi > pos[l][v];
                if (kFlat) planar[l][v] -= flat & (lo == pos[l][v]);
            }
    }
    FV left[2][kMax], right[2][kMax];
    for (int l = 0; l < 2; ++l)
        for (uint32_t v = 0; v < vecs; ++v) {
            const FV x = pos[l][v];
            const IV b = below[l][v], a = above[l][v];
            const IV inside = (x > cost.lo) & (x < cost.hi);
            left[l][v] = inside ? evaluate(cost, x, b + planar[l][v], a) : inf;
            if (kFlat) right[l][v] = inside ? evaluate(cost, x, b, a + planar[l][v]) : inf;
        }
    // The cheapest cost, the lowest position at that cost, and left before right, with vector
    // minima instead of a branch per candidate (they mispredicted).
    FV low = inf;
    for (int l = 0; l < 2; ++l)
        for (uint32_t v = 0; v < vecs; ++v) {
            low = low < left[l][v] ? low : left[l][v];
            if (kFlat) low = low < right[l][v] ? low : right[l][v];
        }
    const float m = hmin(low);
    if (!(m < cost.below)) return Plane{};
    FV at = inf;
    for (int l = 0; l < 2; ++l)
        for (uint32_t v = 0; v < vecs; ++v) {
            IV hit = left[l][v] == m;
            if (kFlat) hit |= right[l][v] == m;
            const FV x = hit ? pos[l][v] : inf;
            at = at < x ? at : x;
        }
    const float x = hmin(at);
    bool planar_left = true;
    if (kFlat) {
        IV on_left = IV{};
        for (int l = 0; l < 2; ++l)
            for (uint32_t v = 0; v < vecs; ++v) on_left |= (left[l][v] == m) & (pos[l][v] == x);
        int32_t any = 0;
        for (uint32_t i = 0; i < kLanes; ++i) any |= on_left[i];
        planar_left = any != 0;
    }
    return {m, k, x, planar_left};
}

/// Nodes of up to kLanes triangles (most searches: four in five on furball at Wald &
/// Havran's constants) get a version with one vector per list, nodes of up to 2 and 4 kLanes
/// ones with two and four.
template <bool kFlat>
__attribute__((always_inline)) inline Plane small_axis_sized(const SmallWork& w, int k, const AxisCost& cost) {
    constexpr uint32_t kVecs = kMaxSmallNode / kLanes;
    if (w.n <= kLanes) return small_axis_body<kFlat, 1>(w, k, cost);
    if (w.n <= 2 * kLanes) return small_axis_body<kFlat, 2>(w, k, cost);
    if (w.n <= 4 * kLanes) return small_axis_body<kFlat, 4>(w, k, cost);
    return small_axis_body<kFlat, kVecs>(w, k, cost);
}

template <bool kFlat>
Plane small_axis(const SmallWork& w, int k, const AxisCost& cost) {
    return small_axis_sized<kFlat>(w, k, cost);
}
#if BVHLAB_KD_AVX2
template <bool kFlat>
__attribute__((target("avx2"))) Plane small_axis_avx2(const SmallWork& w, int k, const AxisCost& cost) {
    return small_axis_sized<kFlat>(w, k, cost);
}
#endif

}  // namespace

AxisCost axis_cost(const AABB& voxel, int k, float inv_area, const KdTreeBuilder::Config& c) {
    const Vec3 ext = voxel.hi - voxel.lo;
    const float a = ext[(k + 1) % 3], b = ext[(k + 2) % 3];
    return {voxel.lo[k],      voxel.hi[k],         2.0f * a * b * inv_area, 2.0f * (a + b) * inv_area,
            c.traversal_cost, c.intersection_cost, 1.0f - c.empty_bonus};
}

bool use_avx2(bool wanted) {
#if BVHLAB_KD_AVX2
    return wanted && __builtin_cpu_supports("avx2");
#else
    (void)wanted;
    return false;
#endif
}

void count_positions(const std::vector<Event>& e, Sweep& s) {
    const size_t m = e.size();
    if (s.key.size() < m + 1 + kLanes) {  // never shrunk, so never filled again
        for (auto* a : {&s.key, &s.starts, &s.planars, &s.ends}) a->resize(m + 1 + kLanes);
        s.starts[0] = s.planars[0] = s.ends[0] = 0;
    }
    uint32_t *key = s.key.data() + 1, *starts = s.starts.data() + 1;
    uint32_t *planars = s.planars.data() + 1, *ends = s.ends.data() + 1;
    // Running counts only, with no reset per position: each event's record is overwritten
    // until the position's last event, which keeps it.
    uint32_t counts[3] = {0, 0, 0};  // by type: ends, planars, starts
    size_t groups = 0;
    for (size_t i = 0; i < m; ++i) {
        const uint32_t k = e[i].pos_key();
        ++counts[e[i].type()];
        key[groups] = k;
        starts[groups] = counts[kStart];
        planars[groups] = counts[kPlanar];
        ends[groups] = counts[kEnd];
        groups += uint32_t(i + 1 == m || e[i + 1].pos_key() != k);
    }
    s.groups = groups;
}

Plane price_positions(const Sweep& s, uint32_t n, int k, const AxisCost& cost, bool avx2) {
    const bool flat = s.planars[s.groups] != 0;
#if BVHLAB_KD_AVX2
    if (avx2) return flat ? price_avx2<true>(s, n, k, cost) : price_avx2<false>(s, n, k, cost);
#else
    (void)avx2;
#endif
    return flat ? price<true>(s, n, k, cost) : price<false>(s, n, k, cost);
}

Plane find_plane_small(const SmallWork& w, const KdTreeBuilder::Config& c, bool avx2) {
    Plane best;
    const float area = w.voxel.area();
    if (!(area > 0.0f) || w.n == 0) return best;
    const float inv_area = 1.0f / area;
    const float leaf = c.intersection_cost * float(w.n);
    for (int k = 0; k < 3; ++k) {
        const bool flat = w.flat >> k & 1;
        AxisCost cost = axis_cost(w.voxel, k, inv_area, c);
        cost.below = std::min(best.cost, leaf);
        Plane p;
#if BVHLAB_KD_AVX2
        if (avx2)
            p = flat ? small_axis_avx2<true>(w, k, cost) : small_axis_avx2<false>(w, k, cost);
        else
#else
        (void)avx2;
#endif
            p = flat ? small_axis<true>(w, k, cost) : small_axis<false>(w, k, cost);
        if (p.cost < best.cost) best = p;  // an earlier axis wins ties
    }
    return best;
}

}  // namespace bvhlab::accel::kd
