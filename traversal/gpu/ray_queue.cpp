// SPDX-License-Identifier: MIT
#include "traversal/gpu/ray_queue.h"

#include <string>

#include "accel/core/check.h"

namespace bvhlab::trav {

void RayQueue::reserve(size_t capacity) {
    if (count_.empty()) {
        count_.resize(1);
        set_count(0);
    }
    if (capacity <= rays_.size()) return;
    if (capacity > UINT32_MAX) throw Error("a ray queue holds at most 2^32 - 1 rays, not " + std::to_string(capacity));
    rays_.resize(capacity);
    hits_.resize(capacity);
    set_count(0);
}

void RayQueue::upload(const std::vector<Ray>& rays) {
    reserve(rays.size());
    if (!rays.empty()) detail::copy_to_device(rays_.data(), rays.data(), rays.size() * sizeof(Ray));
    set_count(uint32_t(rays.size()));
}

void RayQueue::set_count(uint32_t count) {
    BVHLAB_CHECK(count <= rays_.size(), "ray queue count beyond its capacity");
    detail::copy_to_device(count_.data(), &count, sizeof count);
}

}  // namespace bvhlab::trav
