// SPDX-License-Identifier: MIT
// Structure cache: a BuildTree saved with the hash of the triangles it was built over and
// the builder config, so nothing is rebuilt and a stale file is caught. Format in README.md.
#pragma once

#include <cstdint>
#include <string>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/build_tree.h"
#include "accel/layouts/kd_node.h"

namespace bvhlab::accel {

constexpr uint32_t kTreeFileVersion = 2;  // 2: kd-tree nodes are 8 bytes (were 16)

/// What a cached tree was built from.
struct TreeFileMeta {
    BuilderKind builder = BuilderKind::kBinned;  ///< BVH files
    BuilderOptions options;                      ///< BVH files
    bool kdtree = false;                         ///< true: the file holds a kd-tree
    KdTreeBuilder::Config kd;                    ///< kd-tree files
    uint64_t triangles = 0;
    std::string scene_hash;  ///< scene_hash() of the mesh, 16 hex digits
};

struct TreeFile {
    TreeFileMeta meta;
    BuildTree tree;  ///< BVH files
    KdTree kd;       ///< kd-tree files; kd.bounds is not stored (it is the mesh's bounds)
};

/// Writes `tree` and its provenance. Throws bvhlab::Error on I/O failure.
void write_tree_file(const std::string& path, const BuildTree& tree, const TreeFileMeta& meta);

/// Writes a kd-tree (meta.kdtree must be true).
void write_kd_file(const std::string& path, const KdTree& tree, const TreeFileMeta& meta);

/// Reads a tree file (BVH or kd-tree). Throws bvhlab::Error naming the problem on a missing file, wrong magic,
/// unknown version, truncation, trailing bytes, or a checksum mismatch (corruption).
/// Checks only the file itself: staleness against a scene is the caller's check.
TreeFile read_tree_file(const std::string& path);

/// "" when `meta` matches the scene and the options given; otherwise why the cache is stale.
std::string stale_reason(const TreeFileMeta& meta, uint64_t triangles, const std::string& scene_hash);

/// One-line description of a builder config, e.g. "sbvh bins=32 leaf=1..8 depth<64 ...".
std::string describe_config(BuilderKind kind, const BuilderOptions& o);
std::string describe_config(const TreeFileMeta& meta);

}  // namespace bvhlab::accel
