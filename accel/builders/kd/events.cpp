// SPDX-License-Identifier: MIT
// Generation, sorting and merging of the kd-tree builder's events.
#include "accel/builders/kd/events.h"

#include <algorithm>
#include <memory>
#include <utility>

namespace bvhlab::accel::kd {
namespace {

/// sort_by_pos() for large m: a stable LSD radix sort, three digits of 11, 11 and 10 bits, all
/// counted in one pass, moved a -> t -> a -> t.
void radix_sort_by_pos(Event* a, Event* t, size_t m) {
    static constexpr int kShift[3] = {0, 11, 22};
    std::unique_ptr<uint32_t[]> count(new uint32_t[3 * 2048]());
    const auto digit = [](const Event& e, int d) { return (e.pos_key() >> kShift[d]) & 2047u; };
    for (size_t i = 0; i < m; ++i)
        for (int d = 0; d < 3; ++d) ++count[d * 2048 + digit(a[i], d)];
    for (int d = 0; d < 3; ++d) {
        uint32_t* c = &count[d * 2048];
        uint32_t sum = 0;
        for (int b = 0; b < 2048; ++b) sum += std::exchange(c[b], sum);
    }
    Event* from = a;
    Event* to = t;
    for (int d = 0; d < 3; ++d) {
        uint32_t* c = &count[d * 2048];
        for (size_t i = 0; i < m; ++i) to[c[digit(from[i], d)]++] = from[i];
        std::swap(from, to);
    }
}

}  // namespace

/// Usually b (the straddlers' new events) is much shorter: then each of its events finds its
/// place in a by a galloping search and the runs of a between them are block copies.
/// Otherwise a conditional move instead of a branch per event (the new events fall anywhere
/// among the others).
void merge_events(const Event* a, size_t na, const Event* b, size_t nb, Event* out) {
    size_t i = 0, j = 0;
    if (nb * 16 < na) {
        for (; j < nb; ++j) {
            // The end of the run of a below b[j]: gallop, then bisect the last step.
            const uint64_t y = b[j].key;
            size_t step = 1, lo = i, hi = i;
            while (hi < na && a[hi].key < y) {
                lo = hi + 1;
                hi = i + step;
                step *= 2;
            }
            const Event* end = std::lower_bound(a + lo, a + std::min(hi, na), b[j]);
            out = std::copy(a + i, end, out);
            i = size_t(end - a);
            *out++ = b[j];
        }
        std::copy(a + i, a + na, out);
        return;
    }
    while (i < na && j < nb) {
        const uint64_t x = a[i].key, y = b[j].key;
        const bool take_b = y < x;
        out->key = take_b ? y : x;
        ++out;
        j += take_b;
        i += !take_b;
    }
    out = std::copy(a + i, a + na, out);
    std::copy(b + j, b + nb, out);
}

Event* write_events(const AABB* b, uint32_t first, uint32_t last, int k, Event* out) {
    for (uint32_t s = first; s < last; ++s)
        if (b[s].lo[k] != b[s].hi[k]) *out++ = Event::make(b[s].hi[k], kEnd, s);
    for (uint32_t s = first; s < last; ++s)
        if (b[s].lo[k] == b[s].hi[k]) *out++ = Event::make(b[s].lo[k], kPlanar, s);
    for (uint32_t s = first; s < last; ++s)
        if (b[s].lo[k] != b[s].hi[k]) *out++ = Event::make(b[s].lo[k], kStart, s);
    return out;
}

/// A comparison sort when m is small (the radix sort's counters, 24 KB, cost more than
/// sorting a few hundred events).
void sort_by_pos(Event* a, Event* t, size_t m) {
    if (m >= 512) return radix_sort_by_pos(a, t, m);
    std::copy(a, a + m, t);
    std::sort(t, t + m);  // keys are unique and ordered as the radix sort's stable output
}

}  // namespace bvhlab::accel::kd
