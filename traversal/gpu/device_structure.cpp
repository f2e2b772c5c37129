// SPDX-License-Identifier: MIT
#include "traversal/gpu/device_structure.h"

#include "accel/core/check.h"

namespace bvhlab::trav {

DeviceStructure::DeviceStructure(const Structure& s) : layout_(s.layout), depth_(s.depth()) {
    std::string why;
    if (!gpu_available(&why)) throw Error(why);
    if (s.layout == Layout::kBvh2) {
        bvh_nodes_.upload(s.bvh2.nodes);
        bvh_tris_.upload(s.bvh2.tris);
        bvh_ids_.upload(s.bvh2.tri_ids);
    } else if (s.layout == Layout::kCwbvh) {
        cw_nodes_.upload(s.cwbvh.nodes);
        bvh_tris_.upload(s.cwbvh.tris);
        cw_vtris_.upload(s.cwbvh.vtris);
        bvh_ids_.upload(s.cwbvh.tri_ids);
    } else {
        kd_nodes_.upload(s.kd.tree.nodes);
        kd_prims_.upload(s.kd.tree.prim_indices);
        kd_tris_.upload(s.kd.tris);
        kd_bounds_ = s.kd.tree.bounds;
    }
}

}  // namespace bvhlab::trav
