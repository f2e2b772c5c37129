// SPDX-License-Identifier: MIT
// Structural validation of a BuildTree; tests and debug builds call it after every builder.
#pragma once

#include <string>

#include "accel/core/build_tree.h"
#include "accel/layouts/kd_node.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

struct ValidateOptions {
    /// Spatial-split trees reference a triangle at least once and bound only its clipped
    /// part; object-split trees reference each exactly once and bound it whole.
    bool allow_duplicates = false;
};

/// Checks: every node reachable exactly once, children inside their parent's bounds, leaf
/// sizes within config, depth below max_depth, leaf bounds containing their triangles, and
/// every triangle referenced (exactly once unless duplicates are allowed). Returns an empty
/// string when valid, otherwise the first problem found.
std::string validate(const BuildTree& tree, const scene::TriangleMesh& mesh, const BuildConfig& config,
                     const ValidateOptions& options = {});

/// Structural check of a kd-tree, e.g. one read from a file: every node reached exactly once
/// from the root, splits inside their cells, leaf ranges and triangle ids in range. Returns ""
/// when valid, otherwise the first problem found.
std::string validate_kd(const KdTree& tree, size_t triangles);

}  // namespace bvhlab::accel
