// SPDX-License-Identifier: MIT
// Helpers of the GPU tests: the skip when no device is usable, and a structure of any layout.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "scene/scene.h"
#include "traversal/factory.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::trav {

/// Empty when a GPU is usable, else why not. (GTEST_SKIP must be in the test body itself.)
inline std::string no_gpu_reason() {
    std::string why;
    return gpu_available(&why) ? std::string() : why;
}

/// Whether this build has the GPU kernels (nvcc at configure time), device or not.
inline bool built_with_cuda() {
    std::string why;
    gpu_available(&why);
    return why.find("without CUDA") == std::string::npos;
}

#define BVHLAB_SKIP_WITHOUT_GPU() \
    if (const std::string why = ::bvhlab::trav::no_gpu_reason(); !why.empty()) GTEST_SKIP() << "no GPU: " << why

/// A structure of `layout` from the library's factory (no EPO: the tests do not read it). For
/// the two-level layouts, the mesh placed once (identity): triangle ids are the mesh's.
inline Structure make_structure(const scene::TriangleMesh& mesh, Layout layout, accel::BuilderKind builder,
                                accel::CwTris tris = accel::CwTris::kWoop) {
    StructureSpec spec;
    spec.builder = layout == Layout::kKd ? "kdtree" : accel::builder_name(builder);
    spec.layout = layout == Layout::kCwbvh || layout == Layout::kTwoLevelCwbvh ? "cwbvh" : "bvh2";
    spec.cw_tris = tris == accel::CwTris::kVertices ? "vertices" : "woop";
    spec.epo = false;
    if (is_two_level(layout)) return build_structure(scene::single_instance(mesh), spec).structure;
    return build_structure(mesh, spec).structure;
}

/// Whether `layout`'s triangles come in both CWBVH formats (Woop and vertices).
inline bool has_cw_tris(Layout layout) { return layout == Layout::kCwbvh || layout == Layout::kTwoLevelCwbvh; }

}  // namespace bvhlab::trav
