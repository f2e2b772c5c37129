// SPDX-License-Identifier: MIT
// Helpers of the GPU tests: the skip when no device is usable, and a structure of any layout.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/passes/collapse_wide.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/structure.h"

namespace bvhlab::trav {

/// Empty when a GPU is usable, else why not. (GTEST_SKIP must be in the test body itself.)
inline std::string no_gpu_reason() {
    std::string why;
    return gpu_available(&why) ? std::string() : why;
}

#define BVHLAB_SKIP_WITHOUT_GPU() \
    if (const std::string why = ::bvhlab::trav::no_gpu_reason(); !why.empty()) GTEST_SKIP() << "no GPU: " << why

inline Structure make_structure(const accel::TriangleMesh& mesh, Layout layout, accel::BuilderKind builder,
                                accel::CwTris tris = accel::CwTris::kWoop) {
    Structure s;
    s.layout = layout;
    if (layout == Layout::kBvh2) {
        s.name = std::string("bvh2/") + accel::builder_name(builder);
        s.bvh2 = accel::convert_to_bvh2(accel::run_builder(builder, mesh, {}).tree, mesh);
    } else if (layout == Layout::kCwbvh) {
        s.name =
            std::string(tris == accel::CwTris::kVertices ? "cwbvh-vertices/" : "cwbvh/") + accel::builder_name(builder);
        const accel::BuildTree tree = accel::run_builder(builder, mesh, {}).tree;
        s.cwbvh = accel::convert_to_cwbvh(accel::collapse_to_wide(tree, mesh, accel::CollapseMethod::kSahOptimal), mesh,
                                          tris);
    } else {
        s.name = "kdtree";
        s.kd = accel::convert_to_kd_layout(accel::KdTreeBuilder().build(mesh), mesh);
    }
    return s;
}

}  // namespace bvhlab::trav
