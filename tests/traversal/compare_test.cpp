// SPDX-License-Identifier: MIT
// The tie rules of compare_hits on hand-built cases: each tie kind, and real mismatches
// that must not be excused.
#include "traversal/oracle/compare.h"

#include <gtest/gtest.h>

#include "tests/support/test_support.h"

namespace bvhlab::trav {
namespace {

CompareReport one(const accel::TriangleMesh& m, const Ray& r, Query q, Hit ours, Hit oracle, Hit lookup = Hit::miss()) {
    return compare_hits(m, {r}, q, {ours}, {oracle}, [lookup](const Ray&) { return lookup; });
}

// Two triangles sharing the edge x = 1 (a unit square split in two), in the z = 0 plane.
accel::TriangleMesh square() { return test::mesh_of({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {1, 0, 0, 2, 0, 0, 1, 1, 0}}); }

}  // namespace

TEST(CompareHits, AgreementAndTSlack) {
    accel::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, {0, 1.0f, 0.3f, 0.2f}, {0, 1.0000001f, 0.3f, 0.2f});
    EXPECT_EQ(rep.agree, 1u);
    rep = one(m, r, Query::kClosest, {0, 1.0f, 0.3f, 0.2f}, {0, 1.5f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);  // same triangle, very different t
}

TEST(CompareHits, SharedEdgeTie) {
    accel::TriangleMesh m = square();
    Ray r{{1.0f, 0.5f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, {0, 1.0f, 0.5f, 0.5f}, {1, 1.0f, 0.0f, 0.5f});
    EXPECT_EQ(rep.ties, 1u);
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kSharedEdgeOrVertex)], 1u);
}

TEST(CompareHits, NearEdgeMissIsTieButInteriorMissIsNot) {
    accel::TriangleMesh m = square();
    Ray r{{0.99999f, 0.5f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, Hit::miss(), {0, 1.0f, 0.49999f, 0.5f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kNearEdge)], 1u);
    Ray c{{0.6f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    rep = one(m, c, Query::kClosest, Hit::miss(), {0, 1.0f, 0.4f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);
    // A spurious interior hit of ours is caught the same way.
    rep = one(m, c, Query::kClosest, {0, 1.0f, 0.4f, 0.2f}, Hit::miss());
    EXPECT_EQ(rep.mismatches, 1u);
}

TEST(CompareHits, EdgeWindowScalesWithSliverConditioning) {
    // A sliver 0.05 long and 0.0016 wide, seen from 3.8 away (furball's proportions): a float
    // kernel's barycentrics are off by ~1e-4 here, so a hit just outside the short edge in
    // double precision is a tie, one clearly outside is not.
    accel::TriangleMesh m = test::mesh_of({{0, 0, 0, 0.05f, 0, 0, 0.05f, 0.0016f, 0}});
    auto ray_at = [](float x, float y) { return Ray{{x, y, 3.8f}, 0.0f, {0, 0, -1}, INFINITY}; };
    // x = 0.05 + 2e-6 is outside the edge x = 0.05 by a barycentric of ~4e-5 of the long side.
    CompareReport rep = one(m, ray_at(0.050002f, 0.0008f), Query::kClosest, {0, 3.8f, 0.5f, 0.5f}, Hit::miss());
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kNearEdge)], 1u);
    rep = one(m, ray_at(0.0505f, 0.0008f), Query::kClosest, {0, 3.8f, 0.5f, 0.5f}, Hit::miss());
    EXPECT_EQ(rep.mismatches, 1u);
}

TEST(CompareHits, CoincidentTrianglesNeedADoublePrecisionProof) {
    // Two triangles crossing along the line y = 0.5 in the z = 0 plane's neighbourhood: the
    // first lies in z = 0, the second is tilted through z = 0 at y = 0.5.
    accel::TriangleMesh m = test::mesh_of({{0, 0, 0, 4, 0, 0, 0, 4, 0}, {0, 0, -1, 4, 0, -1, 0, 1, 1}});
    Ray r{{0.5f, 0.5f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, {0, 1.0f, 0.125f, 0.125f}, {1, 1.0f, 0.125f, 0.5f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kCoincident)], 1u);
    EXPECT_EQ(rep.mismatches, 0u);
    // Same claimed t, but the ray does not reach triangle 1 there (it passes at y = 3.5,
    // where triangle 1 is far above z = 0): a real mismatch.
    Ray far{{0.2f, 3.5f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    rep = one(m, far, Query::kClosest, {0, 1.0f, 0.05f, 0.875f}, {1, 1.0f, 0.3f, 0.3f});
    EXPECT_EQ(rep.mismatches, 1u);
}

TEST(CompareHits, AnyHitUsesLookupAndIntervalEnd) {
    accel::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, 1.0f};  // tmax exactly at the surface
    CompareReport rep = one(m, r, Query::kAny, Hit::miss(), {0, 0, 0, 0}, {0, 1.0f, 0.3f, 0.2f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kIntervalEnd)], 1u);
    Ray in{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, 5.0f};
    rep = one(m, in, Query::kAny, Hit::miss(), {0, 0, 0, 0}, {0, 1.0f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);
    rep = one(m, in, Query::kAny, {1, 3.0f, 0.1f, 0.1f}, {0, 0, 0, 0});
    EXPECT_EQ(rep.agree, 1u);  // any-hit: which triangle does not matter
}

TEST(CompareHits, HitAtTminZeroIsTie) {
    // An origin lying on a triangle's plane (a secondary ray leaving through a crossing
    // triangle): one side sees t = 2e-8, the other rounds t below tmin = 0.
    accel::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 2e-8f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, Hit::miss(), {0, 2e-8f, 0.3f, 0.2f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kIntervalEnd)], 1u);
    Ray away{{0.5f, 0.2f, 0.5f}, 0.0f, {0, 0, -1}, INFINITY};
    rep = one(m, away, Query::kClosest, Hit::miss(), {0, 0.5f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);
}

}  // namespace bvhlab::trav
