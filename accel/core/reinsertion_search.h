// SPDX-License-Identifier: MIT
// The search of the GPU's parallel reinsertion (after Meister & Bittner 2018), written once for
// the device (traversal/gpu/gpu_builder.cu) and for its CPU reference
// (accel::parallel_reinsertion_reference), which the GPU's passes equal bit for bit.
#pragma once

#include <cstdint>

#include "accel/core/aabb.h"
#include "accel/core/hd.h"

namespace bvhlab::accel {

constexpr uint32_t kReinsertNone = 0xffffffffu;  ///< no node
/// The search's reach: ancestors up to this many levels above the node's parent, and this many
/// nodes visited in all (experiments/NOTES.md: against an unbounded search, the same trace speed
/// within the noise and 10% less time on furball; 8 levels lose 2-3% of it).
constexpr uint32_t kReinsertLevels = 16;
constexpr int kReinsertSteps = 64;
constexpr int kReinsertStack = 48;  ///< deeper than any search goes (24 changes nothing measured)

/// A node's part in a pass.
enum ReinsertRole : uint8_t {
    kInsideLeaf = 0,  ///< below a leaf: stays with it
    kFixed = 1,       ///< the root and its children: stay
    kInterior = 2,
    kLeaf = 3,  ///< a leaf of the tree: the refit starts here
};

/// What the role needs of a node's leaf choice.
struct ReinsertMeta {
    uint32_t count;  ///< triangles below
    bool leaf;       ///< its subtree becomes one leaf
};

/// Node x's role. A node lies inside a leaf when an ancestor chose to be one (only ancestors of
/// at most max_leaf triangles can); leaves of the tree keep kLeaf even beside the root.
/// parent_of(y) gives y's parent (kReinsertNone for the root), meta_of(y) its ReinsertMeta.
template <typename ParentOf, typename MetaOf>
BVHLAB_HD ReinsertRole reinsertion_role(uint32_t x, uint32_t max_leaf, ParentOf&& parent_of, MetaOf&& meta_of) {
    const uint32_t p = parent_of(x);
    for (uint32_t q = p; q != kReinsertNone; q = parent_of(q)) {
        const ReinsertMeta m = meta_of(q);
        if (m.count > max_leaf) break;
        if (m.leaf) return kInsideLeaf;
    }
    if (meta_of(x).leaf) return kLeaf;
    return p == kReinsertNone || parent_of(p) == kReinsertNone ? kFixed : kInterior;
}

/// What the search reads of a node, in one 32-byte sector: its box and children (kReinsertNone
/// for a leaf of the tree, whose triangles stay together).
struct alignas(32) SearchNode {
    float lo_x, lo_y, lo_z;
    uint32_t left;
    float hi_x, hi_y, hi_z;
    uint32_t right;

    BVHLAB_HD AABB box() const { return {{lo_x, lo_y, lo_z}, {hi_x, hi_y, hi_z}}; }
    BVHLAB_HD bool leaf() const { return left == kReinsertNone; }
};
static_assert(sizeof(SearchNode) == 32, "one sector per node");

/// A node's best move: beside `to` (kReinsertNone: none saves area), saving `gain` of interior
/// area, below `top`, the lowest common ancestor of the node and `to`.
struct ReinsertMove {
    float gain = 0.0f;
    uint32_t to = kReinsertNone, top = kReinsertNone;
};

/// The best place for `node` (a node of the tree whose parent `p` is not the root).
/// node_at(x) gives node x's SearchNode, parent_of(x) its parent (kReinsertNone for the root).
/// Cutting the node out frees its parent p (its area saved) and shrinks p's ancestors below
/// `top`; putting it beside X adds A(X u node) and grows X's ancestors below `top`. X runs over
/// the subtree of the sibling of each node on the path to the root (depth-first branch and
/// bound: a subtree whose growth already costs what the best saves is skipped; leaves are not
/// entered), and over the ancestors themselves; p and the root are not candidates. One loop
/// over both the subtrees' nodes and the levels up, not a loop over the levels with one over
/// each subtree inside: on the GPU a lane whose subtree is done goes on to the next level while
/// the others are still in theirs, so a warp's lanes stay busy.
template <typename NodeAt, typename ParentOf>
BVHLAB_HD ReinsertMove reinsertion_search(uint32_t node, uint32_t p, NodeAt&& node_at, ParentOf&& parent_of) {
    ReinsertMove best;
    const AABB nb = node_at(node).box();
    const float an = nb.half_area();
    const SearchNode pn = node_at(p);
    float budget = pn.box().half_area();  // what the move saves before X's cost
    const uint32_t s = pn.left == node ? pn.right : pn.left;
    AABB shrunk = node_at(s).box();  // the current ancestor without the node
    float stack_budget[kReinsertStack];
    uint32_t stack_node[kReinsertStack];
    int steps = kReinsertSteps;  // shared by every subtree of the search
    int sp = 0;
    stack_budget[sp] = budget;
    stack_node[sp++] = s;
    uint32_t under = p;  // the common ancestor of the node and the subtree being explored
    uint32_t below = p, level = 0;
    bool up_pending = false;  // `under` is an ancestor whose own candidacy comes after its subtree
    SearchNode un{};
    uint32_t other = kReinsertNone;
    for (;;) {
        if (sp && steps > 0) {
            --sp;
            --steps;
            const float b = stack_budget[sp];
            const uint32_t x = stack_node[sp];
            if (b - an <= best.gain) continue;
            const SearchNode xn = node_at(x);
            const AABB xb = xn.box();
            const float r = b - merge(xb, nb).half_area();
            if (r > best.gain) best = {r, x, under};
            if (xn.leaf()) continue;                   // a leaf's triangles stay together
            const float below_x = r + xb.half_area();  // X's own growth is paid by its children
            if (below_x - an <= best.gain || sp + 2 > kReinsertStack) continue;
            stack_budget[sp] = below_x;
            stack_node[sp++] = xn.right;
            stack_budget[sp] = below_x;
            stack_node[sp++] = xn.left;
            continue;
        }
        if (up_pending) {  // `under` keeps its box below here: the node stays below it
            const uint32_t up = under;
            shrunk = merge(shrunk, node_at(other).box());
            const float up_area = un.box().half_area();
            budget += up_area - shrunk.half_area();  // `up` shrinks from here on
            if (parent_of(up) != kReinsertNone) {    // X = up: a new node over it has its old box
                const float r = budget - up_area;
                if (r > best.gain) best = {r, up, up};
            }
            below = up;
            ++level;
            up_pending = false;
        }
        if (level >= kReinsertLevels) break;
        const uint32_t up = parent_of(below);
        if (up == kReinsertNone) break;
        un = node_at(up);
        other = un.left == below ? un.right : un.left;
        sp = 0;
        stack_budget[sp] = budget;
        stack_node[sp++] = other;
        under = up;
        up_pending = true;
    }
    return best;
}

}  // namespace bvhlab::accel
