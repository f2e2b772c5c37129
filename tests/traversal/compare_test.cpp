// SPDX-License-Identifier: MIT
// The tie rules of compare_hits on hand-built cases: each tie kind, and real mismatches
// that must not be excused.
#include "traversal/oracle/compare.h"

#include <gtest/gtest.h>

#include <string>

#include "accel/core/check.h"
#include "tests/support/test_support.h"
#include "traversal/reference/ref_intersect.h"

namespace bvhlab::trav {
namespace {

CompareReport one(const scene::TriangleMesh& m, const Ray& r, Query q, Hit ours, Hit oracle, Hit lookup = Hit::miss()) {
    return compare_hits(m, {r}, q, {ours}, {oracle}, [lookup](const Ray&) { return lookup; });
}

// Two triangles sharing the edge x = 1 (a unit square split in two), in the z = 0 plane.
scene::TriangleMesh square() { return test::mesh_of({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {1, 0, 0, 2, 0, 0, 1, 1, 0}}); }

}  // namespace

TEST(CompareHits, AgreementAndTSlack) {
    scene::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, {0, 1.0f, 0.3f, 0.2f}, {0, 1.0000001f, 0.3f, 0.2f});
    EXPECT_EQ(rep.agree, 1u);
    rep = one(m, r, Query::kClosest, {0, 1.0f, 0.3f, 0.2f}, {0, 1.5f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);  // same triangle, very different t
}

TEST(CompareHits, AnyHitNeedsAClosestHitLookupAndClosestHitDoesNot) {
    // An any-hit set is judged against the closest hit (a hit the oracle did not report must
    // still lie on its triangle, before the closest one): without a lookup it is refused by
    // name, where a closest-hit comparison needs none.
    scene::TriangleMesh m = square();
    const Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    const Hit h{0, 1.0f, 0.3f, 0.2f};
    try {
        compare_hits(m, {r}, Query::kAny, {h}, {h}, {});
        ADD_FAILURE() << "an any-hit comparison without a lookup was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("any-hit comparison needs a closest-hit lookup"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(compare_hits(m, {r}, Query::kClosest, {h}, {h}, {}).agree, 1u);
}

TEST(CompareHits, SharedEdgeTie) {
    scene::TriangleMesh m = square();
    Ray r{{1.0f, 0.5f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, {0, 1.0f, 0.5f, 0.5f}, {1, 1.0f, 0.0f, 0.5f});
    EXPECT_EQ(rep.ties, 1u);
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kSharedEdgeOrVertex)], 1u);
}

TEST(CompareHits, NearEdgeMissIsTieButInteriorMissIsNot) {
    scene::TriangleMesh m = square();
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
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 0.05f, 0, 0, 0.05f, 0.0016f, 0}});
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
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 4, 0, 0, 0, 4, 0}, {0, 0, -1, 4, 0, -1, 0, 1, 1}});
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
    scene::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, 1.0f};  // tmax exactly at the surface
    CompareReport rep = one(m, r, Query::kAny, Hit::miss(), {0, 0, 0, 0}, {0, 1.0f, 0.3f, 0.2f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kIntervalEnd)], 1u);
    Ray in{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, 5.0f};
    rep = one(m, in, Query::kAny, Hit::miss(), {0, 0, 0, 0}, {0, 1.0f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);
    rep = one(m, in, Query::kAny, {0, 1.0f, 0.3f, 0.2f}, {0, 0, 0, 0});
    EXPECT_EQ(rep.agree, 1u);  // any-hit: Embree's record is only "occluded"
    // ... but the hit claimed must still be real: triangle 1 does not cover (0.5, 0.2).
    rep = one(m, in, Query::kAny, {1, 1.0f, 0.1f, 0.1f}, {0, 0, 0, 0});
    EXPECT_EQ(rep.mismatches_by_kind[size_t(MismatchKind::kOffTriangle)], 1u);
}

TEST(CompareHits, HitAtTminZeroIsTie) {
    // An origin lying on a triangle's plane (a secondary ray leaving through a crossing
    // triangle): one side sees t = 2e-8, the other rounds t below tmin = 0.
    scene::TriangleMesh m = square();
    Ray r{{0.5f, 0.2f, 2e-8f}, 0.0f, {0, 0, -1}, INFINITY};
    CompareReport rep = one(m, r, Query::kClosest, Hit::miss(), {0, 2e-8f, 0.3f, 0.2f});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kIntervalEnd)], 1u);
    Ray away{{0.5f, 0.2f, 0.5f}, 0.0f, {0, 0, -1}, INFINITY};
    rep = one(m, away, Query::kClosest, Hit::miss(), {0, 0.5f, 0.3f, 0.2f});
    EXPECT_EQ(rep.mismatches, 1u);
}

}  // namespace bvhlab::trav

namespace bvhlab::trav {

TEST(CompareHits, EveryKindOfMadeUpHitIsARealMismatch) {
    // Two stacked unit squares: z = 0 (triangles 0, 1) and z = -1 (triangles 2, 3); a ray
    // straight down through (0.5, 0.2) meets triangle 0 at t = 1 and triangle 2 at t = 2.
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 1, 0, 0, 1, 1, 0},
                                           {1, 0, 0, 2, 0, 0, 1, 1, 0},
                                           {0, 0, -1, 1, 0, -1, 1, 1, -1},
                                           {1, 0, -1, 2, 0, -1, 1, 1, -1}});
    const Ray r{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    const Hit truth{0, 1.0f, 0.3f, 0.2f}, below{2, 2.0f, 0.3f, 0.2f};
    auto kind_of = [&](const Hit& ours, const Hit& oracle,
                       const Ray& ray = Ray{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY}) {
        const CompareReport rep = one(m, ray, Query::kClosest, ours, oracle);
        EXPECT_EQ(rep.mismatches, 1u);
        EXPECT_EQ(rep.ties, 0u);
        for (int k = 0; k < kMismatchKinds; ++k)
            if (rep.mismatches_by_kind[size_t(k)]) return MismatchKind(k);
        return MismatchKind(-1);
    };
    EXPECT_EQ(one(m, r, Query::kClosest, truth, truth).agree, 1u);                   // the real answer passes
    EXPECT_EQ(kind_of({7, 1.0f, 0.3f, 0.2f}, truth), MismatchKind::kInvalidRecord);  // no such triangle
    EXPECT_EQ(kind_of({0, NAN, 0.3f, 0.2f}, truth), MismatchKind::kInvalidRecord);
    // "Triangle 0, t = 0": the ray's origin, at tmin = 0 (once excused as an interval-end tie).
    EXPECT_EQ(kind_of({0, 0.0f, 0.0f, 0.0f}, truth), MismatchKind::kWrongT);
    EXPECT_EQ(kind_of({0, 1.5f, 0.3f, 0.2f}, truth), MismatchKind::kWrongT);
    // The right t on a neighbour sharing an edge with the right triangle (once a shared-edge
    // tie): the ray passes 0.5 away from it.
    EXPECT_EQ(kind_of({1, 1.0f, 0.0f, 0.2f}, truth), MismatchKind::kOffTriangle);
    EXPECT_EQ(kind_of({0, 1.0f, 0.9f, 0.05f}, truth), MismatchKind::kWrongUv);
    const Ray short_ray{{0.5f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, 0.5f};
    EXPECT_EQ(kind_of({0, 1.0f, 0.3f, 0.2f}, Hit::miss(), short_ray), MismatchKind::kOutsideInterval);
    // Real hits that disagree with Embree, each named.
    EXPECT_EQ(kind_of(truth, Hit::miss()), MismatchKind::kExtraHit);
    EXPECT_EQ(kind_of(Hit::miss(), truth), MismatchKind::kMissedHit);
    EXPECT_EQ(kind_of(below, truth), MismatchKind::kFartherHit);
    EXPECT_EQ(kind_of(truth, below), MismatchKind::kCloserHit);
    // The same lies in an any-hit set.
    const CompareReport any = compare_hits(m, {r, r}, Query::kAny, {{0, 0.0f, 0.0f, 0.0f}, {1, 1.0f, 0.0f, 0.2f}},
                                           {{0, 0, 0, 0}, {0, 0, 0, 0}}, [&](const Ray&) { return truth; });
    EXPECT_EQ(any.mismatches, 2u);
    EXPECT_EQ(any.mismatches_by_kind[size_t(MismatchKind::kWrongT)], 1u);
    EXPECT_EQ(any.mismatches_by_kind[size_t(MismatchKind::kOffTriangle)], 1u);
    std::string why;
    EXPECT_EQ(check_claimed_hit(m, r, truth, &why), -1) << why;
    EXPECT_EQ(check_claimed_hit(m, r, {1, 1.0f, 0.0f, 0.2f}, &why), int(MismatchKind::kOffTriangle));
    EXPECT_NE(why.find("outside triangle 1"), std::string::npos) << why;
    EXPECT_STREQ(mismatch_kind_name(MismatchKind::kFartherHit), "farther-hit");
}

}  // namespace bvhlab::trav

namespace bvhlab::trav {

TEST(CompareHits, OverlappingTrianglesSharingAVertexAreCoincidentNotASeam) {
    // Two coplanar triangles sharing vertex (0, 0, 0) and overlapping (a duplicate-like pair, as
    // in architectural models): a ray through the middle of both hits each well inside.
    scene::TriangleMesh m = test::mesh_of({{0, 0, 0, 4, 0, 0, 0, 4, 0}, {0, 0, 0, 4, 1, 0, 1, 4, 0}});
    const Ray r{{1.0f, 1.0f, 1.0f}, 0.0f, {0, 0, -1}, INFINITY};
    double t, u0, v0, u1, v1;
    ASSERT_TRUE(plane_hit_reference(r, m.vertex(0, 0), m.vertex(0, 1), m.vertex(0, 2), t, u0, v0));
    ASSERT_TRUE(plane_hit_reference(r, m.vertex(1, 0), m.vertex(1, 1), m.vertex(1, 2), t, u1, v1));
    const CompareReport rep =
        one(m, r, Query::kClosest, {0, 1.0f, float(u0), float(v0)}, {1, 1.0f, float(u1), float(v1)});
    EXPECT_EQ(rep.ties_by_kind[size_t(TieKind::kCoincident)], 1u);
    EXPECT_EQ(rep.mismatches, 0u);
}

}  // namespace bvhlab::trav
