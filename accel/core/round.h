// SPDX-License-Identifier: MIT
// Rounding a double-precision coordinate to float outwards, for bounds that must contain it.
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>

namespace bvhlab::accel {

/// The next float below (dir < 0) or above (dir > 0) a finite f.
inline float float_step(float f, int dir) {
    if (f == 0.0f)
        return dir < 0 ? -std::numeric_limits<float>::denorm_min() : std::numeric_limits<float>::denorm_min();
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    u = (f > 0.0f) == (dir > 0) ? u + 1 : u - 1;  // away from zero: +1; towards it: -1
    std::memcpy(&f, &u, sizeof f);
    return f;
}

/// The floats [lo, hi] around x: x itself when it is a float (a triangle corner, or a crossing
/// on its clip plane), else the floats on either side of it. Rounding a computed crossing to
/// the nearest float can move it into a box by half an ulp; a split placed at that bound, or a
/// grazing ray (for which half an ulp across is a long way along), then misses the sliver of
/// triangle beyond it. (What is left is the error of the double-precision crossing itself,
/// about 1e-16 relative: far below a float kernel's own.)
inline void round_outwards(double x, float& lo, float& hi) {
    const float f = float(x);
    lo = hi = f;
    if (double(f) > x) lo = float_step(f, -1);
    if (double(f) < x) hi = float_step(f, 1);
}

}  // namespace bvhlab::accel
