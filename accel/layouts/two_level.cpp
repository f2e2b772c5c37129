// SPDX-License-Identifier: MIT
// Two-level BVH construction: a BLAS per placed mesh, then a TLAS over the instances.
#include "accel/layouts/two_level.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "accel/builders/binned_sah.h"
#include "accel/core/check.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"

namespace bvhlab::accel {

namespace {

/// The boxes of a binary tree's nodes `levels` below the root (fewer where leaves end sooner):
/// their transformed corners bound an instance far tighter than the root box's when it is turned.
std::vector<AABB> frontier_boxes(const BuildTree& tree, int levels) {
    if (tree.nodes[0].is_leaf()) return {tree.nodes[0].bounds};
    std::vector<AABB> out;
    std::vector<std::pair<uint32_t, int>> todo{{0u, 0}};
    while (!todo.empty()) {
        const auto [node, level] = todo.back();
        todo.pop_back();
        const uint32_t first = tree.nodes[node].first_index;
        for (uint32_t c = first; c < first + 2; ++c) {
            if (!tree.nodes[c].is_leaf() && level + 1 < levels)
                todo.push_back({c, level + 1});
            else
                out.push_back(tree.nodes[c].bounds);
        }
    }
    return out;
}

/// The world box of `boxes` (object space) under `t`: their transformed corners' box.
AABB world_box(const std::vector<AABB>& boxes, const scene::Transform& t) {
    AABB w = AABB::empty();
    for (const AABB& b : boxes)
        for (int k = 0; k < 8; ++k)
            w.extend(t.point({(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z}));
    return w;
}

}  // namespace

std::vector<AABB> frontier_boxes(const Bvh2& bvh, int levels) {
    BVHLAB_CHECK(!bvh.nodes.empty(), "the frontier of an empty BVH");
    const Bvh2Node& root = bvh.nodes[0];
    if (root.child[0] < 0 && root.child[1] == root.child[0]) return {root.child_box(0)};  // a root leaf
    std::vector<AABB> out;
    std::vector<std::pair<uint32_t, int>> todo{{0u, 0}};
    while (!todo.empty()) {
        const auto [node, level] = todo.back();
        todo.pop_back();
        const Bvh2Node& n = bvh.nodes[node];
        for (int k = 0; k < 2; ++k) {
            if (n.child[k] >= 0 && level + 1 < levels)
                todo.push_back({uint32_t(n.child[k]), level + 1});
            else
                out.push_back(n.child_box(k));
        }
    }
    return out;
}

uint32_t TwoLevelBvh::blas_depth() const {
    uint32_t d = 0;
    for (const Bvh2& b : blas) d = std::max(d, b.depth);
    for (const Cwbvh& b : cw_blas) d = std::max(d, b.depth);
    return d;
}

size_t TwoLevelBvh::bytes() const {
    size_t n = tlas.bytes() + instances.size() * sizeof(InstanceRecord);
    for (const Bvh2& b : blas) n += b.bytes();
    for (const Cwbvh& b : cw_blas) n += b.bytes();
    return n + cw_tlas.bytes();
}

uint32_t TwoLevelBvh::instance_of_id(uint32_t id) const {
    BVHLAB_CHECK(id < world_triangles, "a triangle id beyond the scene's");
    const auto it = std::upper_bound(instances.begin(), instances.end(), id,
                                     [](uint32_t v, const InstanceRecord& r) { return v < r.first_id; });
    return uint32_t(it - instances.begin()) - 1;
}

TwoLevelBvh build_two_level(const scene::InstancedScene& scene, const MeshBuilder& build, const BlasLayout& layout) {
    if (scene.instances.empty()) throw Error("a two-level BVH needs at least one instance");
    const uint64_t world = scene.triangle_count();
    if (world > 0x7fffffffull)
        throw Error("the scene places " + std::to_string(world) +
                    " triangles; two-level hits number them with 31 bits (at most 2^31 - 1)");
    TwoLevelBvh out;
    out.world_triangles = world;
    std::vector<bool> placed(scene.meshes.size(), false);
    for (const scene::Instance& inst : scene.instances) {
        BVHLAB_CHECK(inst.mesh < scene.meshes.size(), "an instance of a mesh the scene does not have");
        placed[inst.mesh] = true;
    }
    if (layout.wide)
        out.cw_blas.resize(scene.meshes.size());
    else
        out.blas.resize(scene.meshes.size());
    std::vector<std::vector<AABB>> boxes(scene.meshes.size());
    tbb::parallel_for(size_t(0), scene.meshes.size(), [&](size_t m) {
        if (!placed[m]) return;
        const scene::TriangleMesh& mesh = scene.meshes[m];
        const BuildTree tree = build(mesh);
        boxes[m] = frontier_boxes(tree, kFrontierLevels);
        if (!layout.wide) {
            out.blas[m] = convert_to_bvh2(tree, mesh);
            return;
        }
        const WideTree wide = collapse_to_wide(tree, mesh, layout.collapse);
        const std::string err = validate_wide(wide, mesh.triangle_count(), tree.prim_indices);
        BVHLAB_CHECK(err.empty(), "the collapse produced an invalid wide BLAS: " + err);
        out.cw_blas[m] = convert_to_cwbvh(wide, mesh, layout.tris);
    });

    const std::vector<uint64_t> first = scene::instance_first_ids(scene);
    std::vector<PrimRef> refs(scene.instances.size());
    out.instances.resize(scene.instances.size());
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const scene::Instance& inst = scene.instances[i];
        const double det = inst.transform.determinant();
        if (!(std::isfinite(det) && det != 0.0))
            throw Error("instance " + std::to_string(i) + " has a singular or non-finite transform");
        InstanceRecord& r = out.instances[i];
        std::memcpy(r.world_to_object, inst.transform.inverse().m, sizeof r.world_to_object);
        r.blas = inst.mesh;
        r.first_id = uint32_t(first[i]);
        r.reserved[0] = r.reserved[1] = 0;
        refs[i] = {world_box(boxes[inst.mesh], inst.transform), uint32_t(i)};
    }
    // One instance per leaf: testing an instance costs a whole BLAS traversal, far more than the
    // triangle a leaf entry usually stands for.
    BinnedSahBuilder::Config cfg;
    cfg.min_leaf_size = 1;
    cfg.max_leaf_size = 1;
    const BuildTree tlas = BinnedSahBuilder(cfg).build(std::move(refs));
    out.tlas = convert_bvh2_nodes(tlas);
    if (layout.wide) {
        // Leaves of one instance need no splitting, so the collapse never reads a mesh.
        const WideTree wide = collapse_to_wide(tlas, scene::TriangleMesh{}, CollapseMethod::kSahOptimal);
        const std::string err = validate_wide(wide, scene.instances.size(), tlas.prim_indices);
        BVHLAB_CHECK(err.empty(), "the collapse produced an invalid wide TLAS: " + err);
        out.cw_tlas = convert_cwbvh_nodes(wide);
    }
    // The traversal enters a TLAS leaf's first instance only.
    for (const Bvh2Node& n : out.tlas.nodes)
        for (int32_t ref : n.child)
            BVHLAB_CHECK(ref >= 0 || Bvh2Node::leaf_count(ref) == 1, "a TLAS leaf of more than one instance");
    return out;
}

}  // namespace bvhlab::accel
