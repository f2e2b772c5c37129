// SPDX-License-Identifier: MIT
#include "traversal/gpu/device_structure.h"

#include "accel/core/check.h"

namespace bvhlab::trav {

DeviceStructure::DeviceStructure(const Structure& s) : layout_(s.layout), depth_(s.depth()), name_(s.name) {
    std::string why;
    if (!gpu_available(&why)) throw Error(why);
    if (s.layout == Layout::kBvh2) {
        bvh_nodes_.upload(s.bvh2.nodes);
        bvh_tris_.upload(s.bvh2.tris);
        bvh_ids_.upload(s.bvh2.tri_ids);
    } else {
        kd_nodes_.upload(s.kd.tree.nodes);
        kd_prims_.upload(s.kd.tree.prim_indices);
        kd_tris_.upload(s.kd.tris);
        kd_bounds_ = s.kd.tree.bounds;
    }
}

size_t DeviceStructure::bytes() const {
    return bvh_nodes_.bytes() + bvh_tris_.bytes() + bvh_ids_.bytes() + kd_nodes_.bytes() + kd_prims_.bytes() +
           kd_tris_.bytes();
}

}  // namespace bvhlab::trav
