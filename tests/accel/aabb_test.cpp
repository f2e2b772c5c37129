// SPDX-License-Identifier: MIT
// Unit tests of AABB and the centroid bin mapping.
#include <gtest/gtest.h>

#include "accel/core/aabb.h"
#include "accel/core/binning.h"

namespace bvhlab {

TEST(AABB, EmptyHasZeroAreaAndExtendsToPoint) {
    AABB b = AABB::empty();
    EXPECT_TRUE(b.is_empty());
    EXPECT_EQ(b.area(), 0.0f);
    EXPECT_EQ(b.half_area(), 0.0f);  // not the +inf of its extents' products: SAH sums stay finite
    b.extend(Vec3{1, 2, 3});
    EXPECT_FALSE(b.is_empty());
    EXPECT_EQ(b.area(), 0.0f);
    EXPECT_EQ(b.half_area(), 0.0f);
    EXPECT_EQ(b.lo.y, 2.0f);
    EXPECT_EQ(b.hi.z, 3.0f);
}

TEST(AABB, AreaOfUnitCubeAndFlatBox) {
    AABB cube{{0, 0, 0}, {1, 1, 1}};
    EXPECT_FLOAT_EQ(cube.area(), 6.0f);
    EXPECT_FLOAT_EQ(cube.half_area(), 3.0f);
    AABB flat{{0, 0, 0}, {2, 0, 3}};
    EXPECT_FLOAT_EQ(flat.area(), 12.0f);
}

TEST(AABB, ContainsOverlapsAndLargestAxis) {
    AABB a{{0, 0, 0}, {4, 2, 1}};
    EXPECT_TRUE(a.contains({{1, 1, 0}, {2, 2, 1}}));
    EXPECT_FALSE(a.contains({{1, 1, 0}, {5, 2, 1}}));
    EXPECT_TRUE(a.overlaps({{4, 2, 1}, {5, 5, 5}}));  // touching counts
    EXPECT_FALSE(a.overlaps({{4.1f, 0, 0}, {5, 1, 1}}));
    EXPECT_EQ(a.largest_axis(), 0);
    EXPECT_EQ(merge(a, AABB{{-1, 0, 0}, {0, 7, 0}}).largest_axis(), 1);
}

TEST(BinMapping, EndsLandInFirstAndLastBin) {
    AABB c{{0, 0, 0}, {1, 2, 4}};
    accel::BinMapping m(c, 16);
    for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(m.bin(c.lo[a], a), 0);
        EXPECT_EQ(m.bin(c.hi[a], a), 15);
        EXPECT_TRUE(m.splittable(a));
    }
    // Bins are equal width: the midpoint is in the middle bin boundary.
    EXPECT_EQ(m.bin(0.5f - 1e-4f, 0), 7);
    EXPECT_EQ(m.bin(0.5f + 1e-4f, 0), 8);
}

TEST(BinMapping, FlatAxisIsNotSplittableAndClamps) {
    AABB c{{0, 3, 0}, {1, 3, 1}};
    accel::BinMapping m(c, 8);
    EXPECT_FALSE(m.splittable(1));
    EXPECT_EQ(m.bin(3.0f, 1), 0);
    EXPECT_EQ(m.bin(-100.0f, 0), 0);
    EXPECT_EQ(m.bin(100.0f, 0), 7);
}

}  // namespace bvhlab
