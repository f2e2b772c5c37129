// SPDX-License-Identifier: MIT
// The GPU builders' hierarchies on the CPU, step by step as the GPU makes them: the references
// that the GPU's LBVH and PLOC are compared with bit for bit, and the leaf choice that turns any
// such hierarchy into a BuildTree. Not builders of their own: one thread, single-triangle leaves.
//  - LBVH: Morton codes, a stable sort, the keys' radix tree (Karras 2012) bottom-up with its
//    boxes (Apetrei 2014).
//  - PLOC (Meister & Bittner, "Parallel Locally-Ordered Clustering for Bounding Volume
//    Hierarchy Construction", TVCG 2018): from the sorted leaves, rounds in which every cluster
//    finds its nearest neighbour within `radius` places (the smallest merged box; on equal
//    areas the lower place), mutual pairs merge into a node at the lower place of the two,
//    and the list is compacted, until one cluster is left.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/build_tree.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// A binary hierarchy with one triangle per leaf, as the GPU builders emit it before their leaves
/// are collapsed. Node ids: leaf k (0 <= k < n) holds triangle sorted_ids[k]; interior nodes
/// are n .. 2n - 2 (an LBVH's interior node n + i splits its keys between i and i + 1, so its
/// root is n + the place of the root's split).
struct RawHierarchy {
    uint32_t root = 0;
    std::vector<uint64_t> keys;         ///< the Morton codes in sorted order
    std::vector<uint32_t> sorted_ids;   ///< triangle ids in key order (ties by id)
    std::vector<uint32_t> left, right;  ///< children of interior node n + i at [i]
    std::vector<AABB> boxes;            ///< every node's box, by node id

    size_t interior_count() const { return left.size(); }
};

/// The LBVH of `mesh` with `morton_bits` (30 or 60) bit codes of the triangle boxes' centres in
/// the centres' bounding box. Throws bvhlab::Error for an empty mesh or other bit counts.
RawHierarchy lbvh_reference(const scene::TriangleMesh& mesh, int morton_bits);

/// The LBVH's hierarchy over sorted keys alone (at least two): left, right and root, no boxes,
/// sorted ids or leaves. Throws bvhlab::Error for fewer keys or keys out of order.
RawHierarchy radix_tree(const std::vector<uint64_t>& keys);

/// PLOC's hierarchy of `mesh` over the same sorted leaves, with search radius `radius` (1 to 16).
/// Interior nodes are numbered from n in the order they are made: round by round, and within a
/// round by the place of the pair's lower cluster. Throws bvhlab::Error as lbvh_reference does,
/// and for a radius outside [1, 16].
RawHierarchy ploc_reference(const scene::TriangleMesh& mesh, int morton_bits, int radius);

/// gpu-binned's clusters (BuilderOptions::cluster_alpha = alpha, at least 1): the triangles in
/// Morton order (the top 24 bits of 30-bit codes: kClusterOrderIgnoredBits) in chunks of 32; in each chunk, rounds in
/// which every cluster finds the cluster whose union with it has the least half area (to 2^-18 relative, on equal areas
/// the lower place: cluster_pair_key) among those it may join (at most kMaxClusterTriangles together), and each mutual
/// pair whose union's half area (that key's) is at most alpha times the larger one's merges, the lower place keeping
/// the cluster with its own triangles first; until a round merges nothing. The clusters in order of chunk and place,
/// each as its triangle ids. Throws bvhlab::Error for an empty mesh or an alpha below 1.
std::vector<std::vector<uint32_t>> triangle_clusters(const scene::TriangleMesh& mesh, float alpha);

constexpr uint32_t kMaxClusterTriangles = 16;

/// The clustering's order ignores the 30-bit codes' low 6 bits (8 bits per axis are left; equal
/// codes keep the order of triangle ids): a cheaper sort, and no measurable change in the trees.
constexpr int kClusterOrderIgnoredBits = 6;

/// No pair: the two clusters may not merge, or their union's area is not finite.
constexpr uint32_t kNoClusterPair = 0xffffffffu;

/// A union of two clusters as the clustering compares them: its half area's float with the low 5
/// bits cleared (to 2^-18 relative) and the other cluster's place in its chunk (0-31) there, so
/// one unsigned minimum finds the least area and, on equal ones, the lower place.
BVHLAB_HD inline uint32_t cluster_pair_key(float half_area, uint32_t place) {
    if (!(half_area >= 0.0f && half_area < 3.402823466e38f)) return kNoClusterPair;
    uint32_t u;
    std::memcpy(&u, &half_area, sizeof u);
    return (u & ~31u) | (place & 31u);
}

/// The half area a key keeps (cluster_pair_key; not kNoClusterPair).
BVHLAB_HD inline float cluster_key_area(uint32_t key) {
    const uint32_t u = key & ~31u;
    float a;
    std::memcpy(&a, &u, sizeof a);
    return a;
}

/// gpu-binned's hierarchy with clusters, as traversal/gpu/gpu_builder.cu makes it, bit for bit:
/// binned SAH over the clusters' boxes (BinnedSahBuilder's splits, down to single clusters), each
/// cluster's merges below it (the lower place's cluster on the left). Interior node n + m - 1
/// splits the final order at place m; sorted_ids is that order, keys are empty. Throws as
/// triangle_clusters does.
RawHierarchy clustered_binned_reference(const scene::TriangleMesh& mesh, float alpha);

/// The BuildTree of a hierarchy with the GPU builders' leaf choice: bottom-up, a node's subtree
/// becomes one leaf when it holds at most min_leaf triangles, or at most max_leaf and its SAH
/// cost as a leaf (Ci x count x half area) is no more than as a node (Ct x half area + the
/// children's costs). Children are adjacent as every BuildTree has them; a leaf lists its
/// triangles left to right.
BuildTree tree_from_hierarchy(const RawHierarchy& h, const BuildConfig& config);

/// `passes` passes of the GPU builders' parallel reinsertion (after Meister & Bittner 2018) over
/// h, in place, as traversal/gpu/gpu_builder.cu makes them, bit for bit. Each pass, the nodes of
/// the tree (its leaves, as tree_from_hierarchy's leaf choice makes them, and the interior nodes
/// above them, but the root and its children) search for their best move
/// (accel::reinsertion_search, against the boxes as the pass began); a move that changes the
/// same links as another goes ahead only if its gain is the larger (on equal gains the lower
/// node); a move whose X lies below another moving node on X's path to the common ancestor is
/// dropped; the rest move at once, and boxes and leaf choices are fitted again from the tree's
/// leaves up. Passes that leave the tree at least max_depth deep and deeper than it was are
/// undone (the hierarchy as it was, boxes fitted again from its leaves): returns whether they
/// stand. Fewer than 3 leaves: nothing moves. Throws bvhlab::Error as tree_from_hierarchy does.
bool parallel_reinsertion_reference(RawHierarchy& h, const BuildConfig& config, int passes);

}  // namespace bvhlab::accel
