// SPDX-License-Identifier: MIT
// The kd-tree builder's final layout: a first walk places everything, then the fragments are
// copied in parallel.
#include "accel/builders/kd/flatten.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <string>
#include <utility>

#include "accel/core/check.h"

namespace bvhlab::accel::kd {

KdTree flatten(const TopNode& root, const AABB& bounds) {
    struct Placed {
        const Fragment* frag;
        uint32_t at, base, prim_base;  // its root's index; where its other nodes and ids go
    };
    std::vector<Placed> frags;
    std::vector<std::pair<uint32_t, KdNode>> interior;
    uint64_t nodes = 1, prims = 0;  // checked against KdNode's 30-bit children below
    std::vector<std::pair<const TopNode*, uint32_t>> stack{{&root, 0}};
    while (!stack.empty()) {
        auto [n, d] = stack.back();
        stack.pop_back();
        if (!n->child[0]) {
            frags.push_back({&n->frag, d, uint32_t(nodes), uint32_t(prims)});
            nodes += n->frag.nodes.size() - 1;
            prims += n->frag.prims.size();
            continue;
        }
        interior.push_back({d, KdNode::interior(n->axis, n->split, uint32_t(nodes))});
        stack.push_back({n->child[1].get(), uint32_t(nodes + 1)});
        stack.push_back({n->child[0].get(), uint32_t(nodes)});
        nodes += 2;
    }
    BVHLAB_CHECK(nodes <= KdNode::kMaxIndex && prims <= UINT32_MAX,
                 "kd-tree too large (" + std::to_string(nodes) + " nodes, " + std::to_string(prims) +
                     " references; the limits are 2^30 and 2^32): lower max_depth");
    KdTree t;
    t.bounds = bounds;
    // Sizing the node array writes nothing (KdNode's default constructor), so its fresh pages
    // are first touched by the parallel copy below. On this VM a fresh page costs several
    // microseconds: furball's nodes (600 MB before they were 8 bytes) took 0.7-1.9 s when one
    // thread zero-filled them.
    t.nodes.resize(nodes);
    for (const auto& [d, x] : interior) t.nodes[d] = x;
    const auto copy_nodes = [&](size_t i) {
        // Fragment node j > 0 goes to base + j - 1; its root goes to at.
        const Placed& p = frags[i];
        const auto place = [&](KdNode x) {
            return x.is_leaf() ? KdNode::leaf(x.first() + p.prim_base, x.count())
                               : KdNode::interior(x.axis(), x.split(), p.base + x.child() - 1);
        };
        t.nodes[p.at] = place(p.frag->nodes[0]);
        for (size_t j = 1; j < p.frag->nodes.size(); ++j) t.nodes[p.base + j - 1] = place(p.frag->nodes[j]);
    };
    const auto copy_prims = [&](size_t i) {
        const Placed& p = frags[i];
        std::copy(p.frag->prims.begin(), p.frag->prims.end(), t.prim_indices.begin() + p.prim_base);
    };
    if (frags.size() == 1) {  // a small mesh: no tasks
        t.prim_indices.resize(prims);
        copy_nodes(0);
        copy_prims(0);
        return t;
    }
    tbb::parallel_invoke([&] { t.prim_indices.resize(prims); },
                         [&] { tbb::parallel_for(size_t(0), frags.size(), copy_nodes); });
    tbb::parallel_for(size_t(0), frags.size(), copy_prims);
    return t;
}

}  // namespace bvhlab::accel::kd
