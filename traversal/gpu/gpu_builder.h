// SPDX-License-Identifier: MIT
// BVH builders that run on the GPU, in plain C++ (the kernels are in gpu_builder.cu):
//  - lbvh: Morton codes (30 or 60 bits), CUB's radix sort, and the keys' radix tree (Karras
//    2012) built bottom-up with its boxes in one kernel (Apetrei 2014; accel/core/morton.h);
//  - ploc: PLOC (Meister & Bittner 2018) over the sorted leaves: rounds in which each cluster
//    finds its nearest neighbour within a search radius (a block's clusters in shared memory),
//    mutual pairs merge, and CUB's scan compacts the list, until one cluster is left; the same
//    hierarchy as accel::ploc_reference, bit for bit;
//  - hploc: H-PLOC (Benthin, Meister, Barczak, Mehalwal, Tsakok, Kensler, HPG 2024): Apetrei's
//    bottom-up LBVH in which each warp, at every node with more than 16 clusters below it,
//    merges them by PLOC's nearest-neighbour rule (Meister & Bittner 2018) within a search
//    radius, down to 16 (to 1 at the root);
//  - gpu-binned: the binned SAH (Wald 2007) as accel::BinnedSahBuilder splits, top down: nodes of
//    more than 512 triangles level by level (chunks binned by blocks, a warp's sweep per node, a
//    stable partition through CUB's scan), a warp per subtree of up to 512 in shared memory, and
//    a thread per node of up to 16 for the exact sweep; with leaves of one triangle its tree is
//    BinnedSahBuilder's, node for node.
// Any of the four may then run passes of parallel reinsertion (Meister & Bittner 2018; BuilderOptions::
// reinsertion_passes, 0 by default): each pass every leaf and interior node of the tree searches,
// up to 16 levels above it and 64 nodes in all, for the sibling that saves the most interior
// area; moves that change the same nodes' links are resolved by priority (the larger gain wins),
// a move whose X lies below another move's node is dropped (no subtree is carried into itself),
// the rest are made at once, and boxes and leaf choices are fitted again. Passes that leave the
// tree as deep as max_depth are undone.
// All four end the same way on the device: each node's SAH cost decides, bottom-up, where leaves of
// up to max_leaf triangles replace subtrees, and the BVH2 layout is written flat: every node's
// place from one scan over all nodes' flags (nodes in the order of their ids, the LBVH's leaves
// in Morton order, gpu-binned's in its final order), then the Woop triangles in leaf order. The result
// stays on the device for the kernels; a host copy is downloaded for the CPU tracers, the
// figures and structure files.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/layouts/bvh2_node.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/device_structure.h"

namespace bvhlab::trav {

/// Device time of each stage (CUDA events), in milliseconds.
struct GpuBuildTimes {
    double upload_ms = 0.0;     ///< the mesh to the device (not part of the build time)
    double bounds_ms = 0.0;     ///< triangle boxes and the centres' bounds (CUB reduce)
    double morton_ms = 0.0;     ///< Morton codes
    double sort_ms = 0.0;       ///< CUB radix sort of the codes with the triangle ids
    double hierarchy_ms = 0.0;  ///< LBVH hierarchy and box fitting, or (H-)PLOC's clustering
    double optimize_ms = 0.0;   ///< reinsertion passes (0 without them)
    double convert_ms = 0.0;    ///< leaves chosen by SAH, BVH2 nodes and Woop triangles written
    double total_ms = 0.0;      ///< bounds to convert: the build time
};

/// A BVH built on the GPU, in the BVH2 layout, resident on the device.
struct GpuBuild {
    DeviceBuffer<accel::Bvh2Node> nodes;
    DeviceBuffer<accel::WoopTriangle> tris;
    DeviceBuffer<uint32_t> tri_ids;
    accel::Bvh2 host;  ///< the same structure downloaded (with its depth)
    GpuBuildTimes times;
    size_t peak_bytes = 0;            ///< the most device memory the build held (buffers and CUB's scratch)
    size_t node_count = 0;            ///< layout nodes written (the first node_count of `nodes`)
    accel::RawHierarchy raw;          ///< the hierarchy before leaves were chosen, when asked for
    int reinsertion_passes = 0;       ///< passes of parallel reinsertion run
    bool reinsertion_undone = false;  ///< they made the tree deeper than max_depth and were undone
    size_t clusters = 0;              ///< gpu-binned with a cluster alpha: the clusters it binned
};

/// Builds `mesh` (at least one triangle) with GPU builder `kind` and the options' leaf sizes,
/// costs, Morton bits, (H-)PLOC search radius and gpu-binned's cluster alpha (whose hierarchy equals
/// accel::clustered_binned_reference's). `keep_raw` also downloads the hierarchy before
/// the leaves are chosen, after any reinsertion passes (the LBVH's and PLOC's are comparable bit
/// for bit with accel::lbvh_reference and accel::ploc_reference, passes with
/// accel::parallel_reinsertion_reference; gpu-binned's has no keys and its sorted_ids are its
/// final order).
/// Throws bvhlab::Error without a GPU, for a CPU builder, for leaves larger than the BVH2
/// layout's 16 triangles, or for a mesh past its 2^27 triangle references.
GpuBuild build_on_gpu(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                      bool keep_raw = false);

/// The build repeated: `warmup` untimed builds, then `runs` timed ones (each the whole device
/// pipeline from the uploaded mesh, as build_on_gpu times it); the times of the timed runs.
std::vector<GpuBuildTimes> time_gpu_builds(const scene::TriangleMesh& mesh, accel::BuilderKind kind,
                                           const accel::BuilderOptions& options, int runs, int warmup = 1);

/// The TLAS of a two-level BVH2 structure rebuilt on the GPU, once per frame, from the instances'
/// transforms; the BLAS stay as built. Each instance's world box is the box of its BLAS's frontier
/// boxes' transformed corners (the nodes four levels below the root, as accel::build_two_level
/// bounds instances), the instance records are written anew (inverse transforms in double, as the
/// host inverts them), and a GPU builder makes the TLAS over the boxes with one instance per leaf
/// (the traversal enters a leaf's first instance only). Nothing returns to the host but the
/// layout's height and an error flag.
class GpuTlasBuilder {
public:
    /// Uploads structure `s` (layout two-level) and what every rebuild reads. Throws
    /// bvhlab::Error for another layout, or without a GPU.
    explicit GpuTlasBuilder(const Structure& s);

    /// Rebuilds the TLAS for `object_to_world` (one transform per instance, in the structure's
    /// order) with GPU builder `kind` and its options (the leaf sizes are set to one instance).
    /// Returns the device time of each stage (upload_ms: the transforms). Throws bvhlab::Error for
    /// a wrong count, a CPU builder, or a singular or non-finite transform or world box (the
    /// structure then keeps its last TLAS and instance records).
    GpuBuildTimes rebuild(const std::vector<scene::Transform>& object_to_world, accel::BuilderKind kind,
                          const accel::BuilderOptions& options = {});

    /// The structure on the device with the last TLAS, for make_gpu_tracer.
    std::shared_ptr<const DeviceStructure> device() const { return device_; }
    /// The last TLAS downloaded: nodes, instance ids (tri_ids), depth; no triangles.
    accel::Bvh2 download_tlas() const;
    /// The instance records on the device, downloaded.
    std::vector<accel::InstanceRecord> download_instances() const;
    size_t instance_count() const { return instances_; }

private:
    std::shared_ptr<DeviceStructure> device_;
    size_t instances_ = 0;
    DeviceBuffer<uint32_t> blas_of_;         // each instance's BLAS
    DeviceBuffer<uint32_t> first_id_;        // each instance's first scene-wide triangle id
    DeviceBuffer<uint32_t> frontier_first_;  // each BLAS's first frontier box, and the end
    DeviceBuffer<AABB> frontier_;
    size_t tlas_nodes_ = 0;  // nodes of the last TLAS
    uint32_t tlas_depth_ = 0;
};

/// A single-level BVH2 refitted on the GPU after its mesh's vertices moved (the same triangles):
/// each leaf's box from its triangles' new vertices, each node's box bottom-up (the second child
/// to finish a node boxes it and goes on to its parent), and the Woop triangles anew; the tree's
/// shape stays, so its quality is the old tree's over the new geometry (a rebuild restores it).
/// For animated meshes, frame by frame.
class GpuRefitter {
public:
    /// Uploads structure `s` (layout bvh2) and what every refit reads: the mesh's indices, each
    /// node's parent and each leaf's slot. Throws bvhlab::Error for another layout, a mesh that
    /// is not the structure's, or without a GPU.
    GpuRefitter(const Structure& s, const scene::TriangleMesh& mesh);

    /// Refits to `vertices` (as many as the mesh has, same indices). Returns the device time
    /// (total_ms; upload_ms: the vertices). Throws bvhlab::Error for a wrong count or a vertex
    /// outside bvhlab's numeric domain (nothing is changed then).
    GpuBuildTimes refit(const std::vector<Vec3>& vertices);

    /// The structure on the device, refitted, for make_gpu_tracer.
    std::shared_ptr<const DeviceStructure> device() const { return device_; }
    /// The refitted layout downloaded (nodes, Woop triangles, ids, depth).
    accel::Bvh2 download() const;

private:
    std::shared_ptr<DeviceStructure> device_;
    size_t vertex_count_ = 0, node_count_ = 0, tri_count_ = 0;
    uint32_t depth_ = 0;
    DeviceBuffer<uint32_t> indices_;
    DeviceBuffer<uint32_t> parents_;  // each node's parent << 1 | its slot there; ~0 for the root
    DeviceBuffer<uint32_t> leaves_;   // each leaf as its node << 1 | slot
    DeviceBuffer<uint32_t> visits_;   // per node, zeroed before each refit
};

namespace detail {
/// The refit kernels (gpu_builder.cu): leaves, then nodes bottom-up, then the Woop triangles.
struct RefitInput {
    const Vec3* verts;
    const uint32_t* idx;
    const uint32_t* tri_ids;
    const uint32_t* parents;
    const uint32_t* leaves;
    uint32_t leaf_count;
    uint32_t tri_count;
    uint32_t* visits;
    accel::Bvh2Node* nodes;
    accel::WoopTriangle* tris;
};
/// Runs the refit on the device; returns its device time in milliseconds.
double gpu_refit(const RefitInput& in);

/// The pipeline behind build_on_gpu, its arguments checked (gpu_builder.cu; runtime_stub.cpp
/// without CUDA).
GpuBuild gpu_build(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                   bool keep_raw);

/// What a TLAS rebuild reads on the device.
struct TlasInput {
    const scene::Transform* object_to_world;  ///< one per instance
    const uint32_t* blas;                     ///< each instance's BLAS
    const uint32_t* first_id;                 ///< each instance's first scene-wide triangle id
    const uint32_t* frontier_first;           ///< each BLAS's first frontier box, and the end
    const AABB* frontier;                     ///< every BLAS's frontier boxes, in object space
    accel::InstanceRecord* records;           ///< written whole
    uint32_t* bad;                            ///< the lowest instance with a bad transform, or ~0
};

/// The TLAS pipeline over `instances` instances (gpu_builder.cu): the nodes and instance ids stay
/// on the device (GpuBuild::nodes, tri_ids; host.depth), no host copy.
GpuBuild gpu_build_tlas(uint32_t instances, const TlasInput& in, accel::BuilderKind kind,
                        const accel::BuilderOptions& options);
}  // namespace detail

}  // namespace bvhlab::trav
