// SPDX-License-Identifier: MIT
// The kd-tree builder's events (Wald & Havran 2006): per axis, the positions where triangles'
// clipped bounds start, end or lie flat, as 64-bit keys that sort by (position, type, slot);
// their generation, sorting and merging. Internal to the builder (not installed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "accel/core/aabb.h"

namespace bvhlab::accel::kd {

enum : uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };
constexpr uint32_t kSlotBits = 30;
constexpr uint32_t kSlotMask = (1u << kSlotBits) - 1;

/// A float's bits mapped so that unsigned order is float order, and back.
inline uint32_t sort_key(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float from_sort_key(uint32_t u) {
    u = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

/// One event on one axis, as one 64-bit key: the plane position's sort key above the event
/// type (end < planar < start) above a node-local triangle slot. Each axis has its own sorted
/// list; key order is position, then type, then slot, and comparing two events is a single
/// integer comparison (merges run without branches). Positions carry +0 for -0 (x + 0 is +0
/// for x = -0), so that equal positions have equal keys.
struct Event {
    uint64_t key;

    /// Unwritten, so that sizing an event array costs no fill: every array is written whole
    /// before it is read.
    Event() {}
    explicit Event(uint64_t k) : key(k) {}
    static Event make(float pos, uint32_t type, uint32_t slot) {
        return Event(uint64_t(sort_key(pos + 0.0f)) << 32 | type << kSlotBits | slot);
    }
    uint32_t pos_key() const { return uint32_t(key >> 32); }
    uint32_t type() const { return uint32_t(key) >> kSlotBits; }
    uint32_t slot() const { return uint32_t(key) & kSlotMask; }
    Event with_slot(uint32_t s) const { return Event((key & ~uint64_t(kSlotMask)) | s); }
    bool operator<(const Event& o) const { return key < o.key; }
};

/// Merges two sorted event lists into out, which may also be a's array nb places before a
/// (then every write lands below the events of a still to be read).
void merge_events(const Event* a, size_t na, const Event* b, size_t nb, Event* out);

/// Writes the events on axis k of bounds b[first, last), each with its index as its slot, to
/// out in key order but for position: the ends, the planars, then the starts, each by slot.
/// Returns the end of what was written (at most 2 (last - first) events).
Event* write_events(const AABB* b, uint32_t first, uint32_t last, int k, Event* out);

/// Sorts a[0, m) by position into t (a is scratch). Events generated in key order but for
/// their positions (write_events) leave sorted by key.
void sort_by_pos(Event* a, Event* t, size_t m);

}  // namespace bvhlab::accel::kd
