// SPDX-License-Identifier: MIT
// GPU API of a build without CUDA: every entry point says so.
#include "accel/core/check.h"
#include "traversal/launch.h"

namespace bvhlab::trav {

struct GpuBvh2::Impl {};

static const char* kNoCuda = "this bvhlab was built without CUDA (nvcc was not found at configure time)";

bool gpu_available(std::string* why) {
    if (why) *why = kNoCuda;
    return false;
}
std::string gpu_description() { return "none"; }
std::string gpu_driver() { return "none"; }
GpuBvh2::GpuBvh2(const accel::Bvh2&) { throw Error(kNoCuda); }
GpuBvh2::~GpuBvh2() = default;
void GpuBvh2::upload_rays(const std::vector<Ray>&) { throw Error(kNoCuda); }
float GpuBvh2::trace(Query) { throw Error(kNoCuda); }
void GpuBvh2::download_hits(std::vector<Hit>&) const { throw Error(kNoCuda); }
void GpuBvh2::trace(const std::vector<Ray>&, Query, std::vector<Hit>&) { throw Error(kNoCuda); }

}  // namespace bvhlab::trav
