// SPDX-License-Identifier: MIT
#include "accel/core/clip.h"

#include "accel/core/round.h"

#include <algorithm>
#include <cmath>

namespace bvhlab::accel {
namespace {

using P3 = PolygonVertex;

/// Whether edge pq, whose ends lie at signed distances dp and dq from a plane, crosses it.
bool crosses(double dp, double dq) { return (dp < 0 && dq > 0) || (dp > 0 && dq < 0); }

/// The point where edge pq crosses the plane x[axis] = plane (dp, dq as for crosses()).
P3 crossing(const P3& p, const P3& q, double dp, double dq, int axis, double plane) {
    const double t = dp / (dp - dq);
    P3 r;
    for (int k = 0; k < 3; ++k) r.v[k] = p.v[k] + t * (q.v[k] - p.v[k]);
    r.v[axis] = plane;  // exact on the plane, so clipped bounds never leak past it
    return r;
}

/// Keeps the part of `in` (n vertices) on the side sign*(x[axis] - plane) <= 0.
int clip_plane(const P3* in, int n, P3* out, int axis, double plane, double sign) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const P3& p = in[i];
        const P3& q = in[i + 1 == n ? 0 : i + 1];
        double dp = sign * (p.v[axis] - plane), dq = sign * (q.v[axis] - plane);
        if (dp <= 0) out[m++] = p;
        if (crosses(dp, dq)) out[m++] = crossing(p, q, dp, dq, axis, plane);
    }
    return m;
}

/// Clips triangle abc to `box` into buf; returns the vertex count and sets *out to the buffer
/// holding the polygon. A triangle clipped by 6 planes has at most 9 vertices.
int clip_to_box(Vec3 a, Vec3 b, Vec3 c, const AABB& box, P3 (&buf)[2][12], const P3** out) {
    const Vec3 tri[3] = {a, b, c};
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) buf[0][i].v[k] = tri[i][k];
    // A plane that the whole triangle lies inside of cannot cut any clipped part either, so
    // it is skipped (most planes, for a triangle that straddles just one split).
    const Vec3 tlo = vmin(a, vmin(b, c)), thi = vmax(a, vmax(b, c));
    int n = 3, cur = 0;
    for (int axis = 0; axis < 3 && n > 0; ++axis) {
        if (tlo[axis] < box.lo[axis]) {
            n = clip_plane(buf[cur], n, buf[cur ^ 1], axis, box.lo[axis], -1.0);
            cur ^= 1;
            if (n == 0) break;
        }
        if (thi[axis] > box.hi[axis]) {
            n = clip_plane(buf[cur], n, buf[cur ^ 1], axis, box.hi[axis], 1.0);
            cur ^= 1;
        }
    }
    *out = buf[cur];
    return n;
}

/// Grows b by the float box of polygon vertex p, rounded outwards (round_outwards).
inline void extend_outwards(AABB& b, const P3& p) {
    for (int k = 0; k < 3; ++k) {
        float lo, hi;
        round_outwards(p.v[k], lo, hi);
        b.lo[k] = std::min(b.lo[k], lo);
        b.hi[k] = std::max(b.hi[k], hi);
    }
}

}  // namespace

ClipResult clip_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box) {
    P3 buf[2][12];
    const P3* poly = nullptr;
    const int n = clip_to_box(a, b, c, box, buf, &poly);
    ClipResult r;
    if (n < 3) {
        for (int i = 0; i < n; ++i) extend_outwards(r.bounds, poly[i]);
        return r;
    }
    // Area of a planar polygon: half the norm of the summed fan cross products.
    const P3* p = poly;
    double s[3] = {0, 0, 0};
    for (int i = 1; i + 1 < n; ++i) {
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[i].v[k] - p[0].v[k];
            e2[k] = p[i + 1].v[k] - p[0].v[k];
        }
        s[0] += e1[1] * e2[2] - e1[2] * e2[1];
        s[1] += e1[2] * e2[0] - e1[0] * e2[2];
        s[2] += e1[0] * e2[1] - e1[1] * e2[0];
    }
    r.area = 0.5 * std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int i = 0; i < n; ++i) extend_outwards(r.bounds, p[i]);
    // Rounding outwards may step outside the box by an ulp, where no part of the triangle is.
    r.bounds = intersect(r.bounds, box);
    return r;
}

namespace {

/// One pass over the polygon p[0, n)'s edges: each vertex bounds the side(s) it is on, and each
/// edge that crosses the plane adds its crossing, exactly on the plane, to both. With kParts,
/// the two parts' vertices are written too, in order.
template <bool kParts>
std::pair<AABB, AABB> split_pass(const P3* poly, int n, const AABB& box, int axis, float pos, P3* below, int* n_below,
                                 P3* above, int* n_above) {
    AABB side[2] = {AABB::empty(), AABB::empty()};
    int m[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
        const P3& p = poly[i];
        const P3& q = poly[i + 1 == n ? 0 : i + 1];
        const double dp = p.v[axis] - double(pos), dq = q.v[axis] - double(pos);
        if (dp <= 0) {
            extend_outwards(side[0], p);
            if (kParts) below[m[0]++] = p;
        }
        if (dp >= 0) {
            extend_outwards(side[1], p);
            if (kParts) above[m[1]++] = p;
        }
        if (crosses(dp, dq)) {
            const P3 r = crossing(p, q, dp, dq, axis, pos);
            extend_outwards(side[0], r);
            extend_outwards(side[1], r);
            if (kParts) below[m[0]++] = above[m[1]++] = r;
        }
    }
    if (kParts) *n_below = m[0], *n_above = m[1];
    // Rounding outwards may step outside a side's box by an ulp; clamp back in.
    AABB cell[2] = {box, box};
    cell[0].hi[axis] = pos;
    cell[1].lo[axis] = pos;
    return {intersect(side[0], cell[0]), intersect(side[1], cell[1])};
}

}  // namespace

std::pair<AABB, AABB> split_clipped_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box, int axis, float pos) {
    P3 buf[2][12];
    const P3* poly = nullptr;
    const int n = clip_to_box(a, b, c, box, buf, &poly);
    return split_pass<false>(poly, n, box, axis, pos, nullptr, nullptr, nullptr, nullptr);
}

int clip_triangle_polygon(Vec3 a, Vec3 b, Vec3 c, const AABB& box, PolygonVertex* out) {
    P3 buf[2][12];
    const P3* poly = nullptr;
    const int n = clip_to_box(a, b, c, box, buf, &poly);
    std::copy(poly, poly + n, out);
    return n;
}

std::pair<AABB, AABB> split_polygon(const PolygonVertex* p, int n, const AABB& box, int axis, float pos,
                                    PolygonVertex* below, int* n_below, PolygonVertex* above, int* n_above) {
    return split_pass<true>(p, n, box, axis, pos, below, n_below, above, n_above);
}

}  // namespace bvhlab::accel
