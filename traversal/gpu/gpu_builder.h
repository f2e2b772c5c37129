// SPDX-License-Identifier: MIT
// BVH builders that run on the GPU, in plain C++ (the kernels are in gpu_builder.cu):
//  - lbvh: Morton codes (30 or 60 bits), CUB's radix sort, Karras's (2012) parallel hierarchy
//    and bottom-up box fitting;
//  - hploc: H-PLOC (Benthin, Meister, Barczak, Mehalwal, Tsakok, Kensler, HPG 2024): Apetrei's
//    bottom-up LBVH in which each warp, at every node with more than 16 clusters below it,
//    merges them by PLOC's nearest-neighbour rule (Meister & Bittner 2018) within a search
//    radius, down to 16 (to 1 at the root).
// Both end the same way on the device: each node's SAH cost decides, bottom-up, where leaves of
// up to max_leaf triangles replace subtrees, and the BVH2 layout is written top down, a level
// per launch (slots depth first, left child next to its parent) with Woop triangles in leaf order. The result
// stays on the device for the kernels; a host copy is downloaded for the CPU tracers, the
// figures and structure files.
#pragma once

#include <cstddef>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/layouts/bvh2_node.h"
#include "scene/mesh.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::trav {

/// Device time of each stage (CUDA events), in milliseconds.
struct GpuBuildTimes {
    double upload_ms = 0.0;     ///< the mesh to the device (not part of the build time)
    double bounds_ms = 0.0;     ///< triangle boxes and the centres' bounds (CUB reduce)
    double morton_ms = 0.0;     ///< Morton codes
    double sort_ms = 0.0;       ///< CUB radix sort of the codes with the triangle ids
    double hierarchy_ms = 0.0;  ///< LBVH hierarchy and box fitting, or H-PLOC's clustering
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
    size_t peak_bytes = 0;    ///< the most device memory the build held (buffers and CUB's scratch)
    accel::RawHierarchy raw;  ///< the hierarchy before leaves were chosen, when asked for
};

/// Builds `mesh` (at least one triangle) with GPU builder `kind` and the options' leaf sizes,
/// costs, Morton bits and H-PLOC search radius. `keep_raw` also downloads the hierarchy before
/// the leaves are chosen (the LBVH's is comparable bit for bit with accel::lbvh_reference).
/// Throws bvhlab::Error without a GPU, for a CPU builder, or for a mesh past the BVH2 layout's
/// 2^25 triangle references.
GpuBuild build_on_gpu(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                      bool keep_raw = false);

/// The build repeated: `warmup` untimed builds, then `runs` timed ones (each the whole device
/// pipeline from the uploaded mesh, as build_on_gpu times it); the times of the timed runs.
std::vector<GpuBuildTimes> time_gpu_builds(const scene::TriangleMesh& mesh, accel::BuilderKind kind,
                                           const accel::BuilderOptions& options, int runs, int warmup = 1);

namespace detail {
/// The pipeline behind build_on_gpu, its arguments checked (gpu_builder.cu; runtime_stub.cpp
/// without CUDA).
GpuBuild gpu_build(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                   bool keep_raw);
}  // namespace detail

}  // namespace bvhlab::trav
