// SPDX-License-Identifier: MIT
#include "accel/builders/lbvh_reference.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>

#include "accel/builders/binned_sah.h"
#include "accel/core/check.h"
#include "accel/core/morton.h"
#include "accel/core/reinsertion_search.h"

namespace bvhlab::accel {

namespace {

/// The radix tree bottom-up, as the GPU climbs it (morton::radix_parent): from each leaf in
/// turn, the first of two siblings to arrive at their parent leaves its outer key there and
/// stops; the second boxes the parent (when h has boxes) and goes on (the GPU's atomic
/// exchanges, in one thread).
void emit_hierarchy(RawHierarchy& h) {
    const uint32_t n = uint32_t(h.keys.size());
    h.left.resize(n - 1);
    h.right.resize(n - 1);
    std::vector<uint32_t> outer(n - 1, ~0u);
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t node = k, left = k, right = k;
        for (;;) {
            if (left == 0 && right == n - 1) {
                h.root = node;
                break;
            }
            const morton::RadixParent p = morton::radix_parent(h.keys.data(), n, left, right);
            (p.left_child ? h.left : h.right)[p.split] = node;
            uint32_t& o = outer[p.split];
            if (o == ~0u) {
                o = p.left_child ? left : right;
                break;
            }
            (p.left_child ? right : left) = o;
            node = n + p.split;
            if (!h.boxes.empty()) h.boxes[node] = merge(h.boxes[h.left[p.split]], h.boxes[h.right[p.split]]);
        }
    }
}

/// The leaves in Morton order: keys, sorted ids and the leaves' boxes (boxes sized for 2n - 1
/// nodes). The first step of every GPU builder. The order compares the codes without their
/// `ignored` low bits (the keys keep them).
RawHierarchy morton_order(const scene::TriangleMesh& mesh, int morton_bits, int ignored = 0) {
    if (morton_bits != 30 && morton_bits != 60)
        throw Error("morton_bits " + std::to_string(morton_bits) + " is neither 30 nor 60");
    const size_t n = mesh.triangle_count();
    if (n == 0) throw Error("the mesh has no triangles to build a structure over");
    RawHierarchy h;
    h.boxes.resize(2 * n - 1);
    std::vector<AABB> tri(n);
    AABB centres = AABB::empty();
    for (size_t t = 0; t < n; ++t) {
        tri[t] = mesh.triangle_bounds(t);
        centres.extend(tri[t].center());
    }
    const uint32_t cells = morton::cells_per_axis(morton_bits);
    const Vec3 scale{morton::axis_scale(centres.lo.x, centres.hi.x, cells),
                     morton::axis_scale(centres.lo.y, centres.hi.y, cells),
                     morton::axis_scale(centres.lo.z, centres.hi.z, cells)};
    std::vector<uint64_t> codes(n);
    for (size_t t = 0; t < n; ++t)
        codes[t] = morton_bits == 60 ? morton::code60(tri[t].center(), centres.lo, scale)
                                     : morton::code30(tri[t].center(), centres.lo, scale);
    h.sorted_ids.resize(n);
    std::iota(h.sorted_ids.begin(), h.sorted_ids.end(), 0u);
    // The GPU's radix sort is stable: equal keys keep the order of their triangle ids.
    std::stable_sort(h.sorted_ids.begin(), h.sorted_ids.end(),
                     [&](uint32_t a, uint32_t b) { return codes[a] >> ignored < codes[b] >> ignored; });
    h.keys.resize(n);
    for (size_t k = 0; k < n; ++k) {
        h.keys[k] = codes[h.sorted_ids[k]];
        h.boxes[k] = tri[h.sorted_ids[k]];
    }
    return h;
}

/// What the leaf choice keeps of a node (as the GPU's NodeMeta): its triangles, whether its
/// subtree becomes one leaf, its SAH cost and its height in the layout (0 for a leaf).
struct NodeFit {
    uint32_t count = 1;
    bool leaf = true;
    float cost = 0.0f;
    uint32_t height = 0;
};

NodeFit leaf_fit(const AABB& box, const BuildConfig& config) {
    return {1, true, config.intersection_cost * box.half_area(), 0};
}

/// A node's fit from its children's, in the GPU's float operations (make_node): a leaf when it
/// holds at most min_leaf triangles, or at most max_leaf and costs no more as one.
NodeFit node_fit(const NodeFit& a, const NodeFit& b, float area, const BuildConfig& config) {
    NodeFit m;
    m.count = a.count + b.count;
    const float inner = config.traversal_cost * area + a.cost + b.cost;
    const float as_leaf = config.intersection_cost * float(m.count) * area;
    m.leaf = m.count <= config.min_leaf_size || (m.count <= config.max_leaf_size && as_leaf <= inner);
    m.cost = m.leaf ? as_leaf : inner;
    m.height = m.leaf ? 0 : 1 + std::max(a.height, b.height);
    return m;
}

/// n, the hierarchy's leaves; throws unless it has n - 1 nodes and 2n - 1 boxes.
uint32_t check_hierarchy(const RawHierarchy& h) {
    const uint32_t n = uint32_t(h.sorted_ids.size());
    BVHLAB_CHECK(n > 0 && h.boxes.size() == 2 * size_t(n) - 1 && h.left.size() + 1 == n && h.right.size() + 1 == n,
                 "a hierarchy of n leaves has n - 1 nodes");
    return n;
}

/// Visits the nodes of the subtree of `root` children first (a depth-first walk; nodes below n
/// are leaves, children(x) gives an interior node's two); `enter(x)` false stops the walk at x,
/// which is visited as it is.
template <typename Children, typename Enter, typename Visit>
void post_order(uint32_t root, uint32_t n, Children&& children, Enter&& enter, Visit&& visit) {
    std::vector<std::pair<uint32_t, bool>> stack{{root, false}};
    while (!stack.empty()) {
        const auto [x, expanded] = stack.back();
        stack.pop_back();
        if (x < n || expanded || !enter(x)) {
            visit(x);
        } else {
            const std::pair<uint32_t, uint32_t> c = children(x);
            stack.push_back({x, true});
            stack.push_back({c.second, false});
            stack.push_back({c.first, false});
        }
    }
}

/// Every node's fit, bottom-up from the hierarchy's boxes.
std::vector<NodeFit> fit_hierarchy(const RawHierarchy& h, const BuildConfig& config) {
    const uint32_t n = uint32_t(h.sorted_ids.size());
    std::vector<NodeFit> fit(h.boxes.size());
    post_order(
        h.root, n, [&](uint32_t x) { return std::make_pair(h.left[x - n], h.right[x - n]); },
        [](uint32_t) { return true; },
        [&](uint32_t x) {
            fit[x] = x < n ? leaf_fit(h.boxes[x], config)
                           : node_fit(fit[h.left[x - n]], fit[h.right[x - n]], h.boxes[x].half_area(), config);
        });
    return fit;
}

}  // namespace

RawHierarchy lbvh_reference(const scene::TriangleMesh& mesh, int morton_bits) {
    RawHierarchy h = morton_order(mesh, morton_bits);
    if (h.keys.size() > 1) emit_hierarchy(h);  // else the root is leaf 0
    return h;
}

RawHierarchy radix_tree(const std::vector<uint64_t>& keys) {
    if (keys.size() < 2 || !std::is_sorted(keys.begin(), keys.end()))
        throw Error("a radix tree needs at least two sorted keys");
    RawHierarchy h;
    h.keys = keys;
    emit_hierarchy(h);
    return h;
}

RawHierarchy ploc_reference(const scene::TriangleMesh& mesh, int morton_bits, int radius) {
    if (radius < 1 || radius > 16) throw Error("PLOC's radius " + std::to_string(radius) + " is outside [1, 16]");
    RawHierarchy h = morton_order(mesh, morton_bits);
    const uint32_t n = uint32_t(h.keys.size());
    h.left.reserve(n - 1);
    h.right.reserve(n - 1);
    std::vector<uint32_t> clusters(n), next, nn;
    std::iota(clusters.begin(), clusters.end(), 0u);
    uint32_t node = n;
    while (clusters.size() > 1) {
        const size_t m = clusters.size(), r = size_t(radius);
        nn.assign(m, 0);
        for (size_t i = 0; i < m; ++i) {
            float best = std::numeric_limits<float>::infinity();
            const AABB& b = h.boxes[clusters[i]];
            for (size_t j = i > r ? i - r : 0; j <= std::min(i + r, m - 1); ++j) {
                if (j == i) continue;
                const float a = merge(b, h.boxes[clusters[j]]).half_area();
                if (a < best) {  // on equal areas the lower place
                    best = a;
                    nn[i] = uint32_t(j);
                }
            }
        }
        next.clear();
        for (size_t i = 0; i < m; ++i) {
            const size_t j = nn[i];
            if (nn[j] != i) {
                next.push_back(clusters[i]);
            } else if (i < j) {
                h.left.push_back(clusters[i]);
                h.right.push_back(clusters[j]);
                h.boxes[node] = merge(h.boxes[clusters[i]], h.boxes[clusters[j]]);
                next.push_back(node++);
            }
        }
        clusters.swap(next);
    }
    h.root = clusters[0];
    return h;
}

namespace {

/// A cluster of the reference clustering: its box, its triangle ids in order, and its merges as
/// (first, split, end) places in that order.
struct RefCluster {
    AABB box;
    std::vector<uint32_t> tris;
    std::vector<std::array<uint32_t, 3>> merges;
};

std::vector<RefCluster> make_clusters(const scene::TriangleMesh& mesh, float alpha) {
    if (!(alpha >= 1.0f)) {
        std::ostringstream s;
        s << "cluster alpha " << alpha << " is not at least 1";
        throw Error(s.str());
    }
    const RawHierarchy order = morton_order(mesh, 30, kClusterOrderIgnoredBits);
    const std::vector<uint32_t>& sorted = order.sorted_ids;
    constexpr size_t kChunk = 32;
    std::vector<RefCluster> out;
    for (size_t b = 0; b < sorted.size(); b += kChunk) {
        std::vector<RefCluster> c;
        for (size_t i = b; i < std::min(sorted.size(), b + kChunk); ++i) c.push_back({order.boxes[i], {sorted[i]}, {}});
        for (;;) {
            const size_t k = c.size();
            std::vector<size_t> nn(k, k);
            std::vector<float> best(k, std::numeric_limits<float>::infinity());
            for (size_t i = 0; i < k; ++i) {
                uint32_t least = kNoClusterPair;  // keys carry places in the chunk, ordered as the list is
                for (size_t j = 0; j < k; ++j) {
                    if (j == i || c[i].tris.size() + c[j].tris.size() > kMaxClusterTriangles) continue;
                    const uint32_t key = cluster_pair_key(merge(c[i].box, c[j].box).half_area(), uint32_t(j));
                    if (key < least) least = key, nn[i] = j;
                }
                if (least != kNoClusterPair) best[i] = cluster_key_area(least);
            }
            std::vector<char> gone(k, 0);
            bool merged = false;
            for (size_t i = 0; i < k; ++i) {
                const size_t j = nn[i];
                if (j == k || j < i || nn[j] != i) continue;
                if (!(best[i] <= alpha * std::max(c[i].box.half_area(), c[j].box.half_area()))) continue;
                const uint32_t wi = uint32_t(c[i].tris.size()), wj = uint32_t(c[j].tris.size());
                for (const auto& m : c[j].merges) c[i].merges.push_back({m[0] + wi, m[1] + wi, m[2] + wi});
                c[i].merges.push_back({0, wi, wi + wj});
                c[i].tris.insert(c[i].tris.end(), c[j].tris.begin(), c[j].tris.end());
                c[i].box = merge(c[i].box, c[j].box);
                gone[j] = 1;
                merged = true;
            }
            if (!merged) break;
            std::vector<RefCluster> kept;
            for (size_t i = 0; i < k; ++i)
                if (!gone[i]) kept.push_back(std::move(c[i]));
            c.swap(kept);
        }
        for (RefCluster& x : c) out.push_back(std::move(x));
    }
    return out;
}

}  // namespace

std::vector<std::vector<uint32_t>> triangle_clusters(const scene::TriangleMesh& mesh, float alpha) {
    std::vector<std::vector<uint32_t>> out;
    for (RefCluster& c : make_clusters(mesh, alpha)) out.push_back(std::move(c.tris));
    return out;
}

RawHierarchy clustered_binned_reference(const scene::TriangleMesh& mesh, float alpha) {
    const std::vector<RefCluster> cl = make_clusters(mesh, alpha);
    const uint32_t n = uint32_t(mesh.triangle_count());
    RawHierarchy h;
    h.boxes.resize(2 * size_t(n) - 1);
    h.left.resize(n - 1);
    h.right.resize(n - 1);
    if (n == 1) {
        h.sorted_ids = {0};
        h.boxes[0] = mesh.triangle_bounds(0);
        return h;
    }
    std::vector<PrimRef> refs(cl.size());
    for (size_t k = 0; k < cl.size(); ++k) refs[k] = {cl[k].box, uint32_t(k)};
    BinnedSahBuilder::Config config;
    config.min_leaf_size = config.max_leaf_size = 1;
    const BuildTree top = BinnedSahBuilder(config).build(std::move(refs));
    // Node n + m - 1 for a split at place m; each node's box from its children's.
    const auto link = [&](uint32_t m, uint32_t a, uint32_t b) {
        const uint32_t id = n + m - 1;
        h.left[m - 1] = a;
        h.right[m - 1] = b;
        h.boxes[id] = merge(h.boxes[a], h.boxes[b]);
        return id;
    };
    // A cluster's range [a, b) of its places, starting at place `at`: its leaves and merges.
    std::function<uint32_t(const RefCluster&, uint32_t, uint32_t, uint32_t)> inside =
        [&](const RefCluster& c, uint32_t at, uint32_t a, uint32_t b) -> uint32_t {
        if (b - a == 1) return at + a;
        for (const auto& m : c.merges)
            if (m[0] == a && m[2] == b) return link(at + m[1], inside(c, at, a, m[1]), inside(c, at, m[1], b));
        throw Error("clustered_binned_reference: a cluster's merges do not cover it");
    };
    uint32_t place = 0;
    std::function<uint32_t(uint32_t)> walk = [&](uint32_t x) -> uint32_t {
        const BuildNode& node = top.nodes[x];
        if (node.is_leaf()) {
            const RefCluster& c = cl[top.prim_indices[node.first_index]];
            const uint32_t at = place;
            for (uint32_t t : c.tris) {
                h.sorted_ids.push_back(t);
                h.boxes[place++] = mesh.triangle_bounds(t);
            }
            return inside(c, at, 0, uint32_t(c.tris.size()));
        }
        const uint32_t a = walk(node.first_index);
        const uint32_t m = place;
        const uint32_t b = walk(node.first_index + 1);
        return link(m, a, b);
    };
    h.root = walk(0);
    return h;
}

BuildTree tree_from_hierarchy(const RawHierarchy& h, const BuildConfig& config) {
    const uint32_t n = check_hierarchy(h);
    const std::vector<NodeFit> fit = fit_hierarchy(h, config);
    // Top-down: a node's children at two adjacent slots; a leaf's triangles left to right.
    BuildTree tree;
    tree.nodes.push_back({h.boxes[h.root], 0, 0});
    std::vector<std::pair<uint32_t, uint32_t>> todo{{h.root, 0}};  // hierarchy node, slot
    std::vector<uint32_t> below;
    while (!todo.empty()) {
        const auto [x, slot] = todo.back();
        todo.pop_back();
        if (fit[x].leaf) {
            tree.nodes[slot].first_index = uint32_t(tree.prim_indices.size());
            tree.nodes[slot].prim_count = fit[x].count;
            below.assign(1, x);
            while (!below.empty()) {
                const uint32_t y = below.back();
                below.pop_back();
                if (y < n) {
                    tree.prim_indices.push_back(h.sorted_ids[y]);
                } else {
                    below.push_back(h.right[y - n]);
                    below.push_back(h.left[y - n]);
                }
            }
            continue;
        }
        const uint32_t first = uint32_t(tree.nodes.size());
        tree.nodes[slot].first_index = first;
        const uint32_t a = h.left[x - n], b = h.right[x - n];
        tree.nodes.push_back({h.boxes[a], 0, 0});
        tree.nodes.push_back({h.boxes[b], 0, 0});
        todo.push_back({b, first + 1});
        todo.push_back({a, first});
    }
    return tree;
}

bool parallel_reinsertion_reference(RawHierarchy& h, const BuildConfig& config, int passes) {
    const uint32_t n = check_hierarchy(h);
    if (n < 3 || passes <= 0) return true;
    const uint32_t total = uint32_t(h.boxes.size());
    std::vector<uint32_t> left(total, kReinsertNone), right(total, kReinsertNone), parent(total, kReinsertNone);
    for (uint32_t i = 0; i + 1 < n; ++i) {
        left[n + i] = h.left[i];
        right[n + i] = h.right[i];
        parent[h.left[i]] = parent[h.right[i]] = n + i;
    }
    const std::vector<uint32_t> left0 = left, right0 = right, parent0 = parent;
    std::vector<NodeFit> fit = fit_hierarchy(h, config);
    const NodeFit before = fit[h.root];
    const auto children = [&](uint32_t x) { return std::make_pair(left[x], right[x]); };
    const auto sibling = [&](uint32_t x) { return left[parent[x]] == x ? right[parent[x]] : left[parent[x]]; };
    // Boxes and fits again below `root` from the nodes where enter(x) is false (and the leaves).
    const auto refit = [&](auto&& enter) {
        post_order(h.root, n, children, enter, [&](uint32_t x) {
            if (x < n || !enter(x)) return;
            h.boxes[x] = merge(h.boxes[left[x]], h.boxes[right[x]]);
            fit[x] = node_fit(fit[left[x]], fit[right[x]], h.boxes[x].half_area(), config);
        });
    };
    std::vector<uint8_t> role(total);
    std::vector<SearchNode> search(total);
    std::vector<ReinsertMove> move(total);
    std::vector<unsigned long long> locks(total);
    std::vector<uint8_t> moving(total);
    for (int pass = 0; pass < passes; ++pass) {
        for (uint32_t x = 0; x < total; ++x) {
            const ReinsertRole r = reinsertion_role(
                x, config.max_leaf_size, [&](uint32_t y) { return parent[y]; },
                [&](uint32_t y) {
                    return ReinsertMeta{fit[y].count, fit[y].leaf};
                });
            role[x] = r;
            const AABB& b = h.boxes[x];
            const bool open = r != kLeaf && x >= n;
            search[x] = {b.lo.x, b.lo.y, b.lo.z, open ? left[x] : kReinsertNone,
                         b.hi.x, b.hi.y, b.hi.z, open ? right[x] : kReinsertNone};
        }
        for (uint32_t x = 0; x < total; ++x) {
            const uint32_t p = parent[x];
            move[x] = {};
            if (role[x] >= kInterior && p != kReinsertNone && parent[p] != kReinsertNone) {
                move[x] = reinsertion_search(
                    x, p, [&](uint32_t y) { return search[y]; }, [&](uint32_t y) { return parent[y]; });
            }
        }
        // The six nodes whose links a move changes, its priority (gain, then the lower node).
        const auto touched = [&](uint32_t x) {
            const uint32_t p = parent[x], to = move[x].to;
            return std::array<uint32_t, 6>{x, p, sibling(x), parent[p], to, parent[to]};
        };
        const auto key = [&](uint32_t x) {
            uint32_t bits;
            std::memcpy(&bits, &move[x].gain, sizeof bits);
            return static_cast<unsigned long long>(bits) << 32 | (0xffffffffu - x);
        };
        std::fill(locks.begin(), locks.end(), 0ull);
        std::fill(moving.begin(), moving.end(), uint8_t(0));
        for (uint32_t x = 0; x < total; ++x)
            if (move[x].to != kReinsertNone)
                for (uint32_t y : touched(x)) locks[y] = std::max(locks[y], key(x));
        for (uint32_t x = 0; x < total; ++x) {
            if (move[x].to == kReinsertNone) continue;
            bool mine = true;
            for (uint32_t y : touched(x)) mine &= locks[y] == key(x);
            if (mine)
                moving[x] = 1;
            else
                move[x].to = kReinsertNone;
        }
        for (uint32_t x = 0; x < total; ++x) {  // no subtree carried into itself
            for (uint32_t y = move[x].to; move[x].to != kReinsertNone && y != move[x].top;) {
                y = parent[y];
                if (moving[y]) move[x].to = kReinsertNone;
            }
        }
        const auto replace_child = [&](uint32_t at, uint32_t old_child, uint32_t new_child) {
            (left[at] == old_child ? left[at] : right[at]) = new_child;
        };
        for (uint32_t x = 0; x < total; ++x) {
            const uint32_t to = move[x].to;
            if (to == kReinsertNone) continue;
            const uint32_t p = parent[x], g = parent[p];
            const uint32_t s = sibling(x);
            replace_child(g, p, s);
            parent[s] = g;
            const uint32_t q = parent[to];
            replace_child(q, to, p);
            left[p] = to;
            right[p] = x;
            parent[to] = p;
            parent[p] = q;
        }
        refit([&](uint32_t x) { return role[x] != kLeaf; });  // the tree's leaves keep theirs
    }
    const NodeFit after = fit[h.root];
    const bool stand =
        !(std::max(after.height, 1u) >= config.max_depth && after.height > before.height) && after.count == n;
    if (!stand) {  // the hierarchy as it was, fitted again from its leaves
        left = left0;
        right = right0;
        parent = parent0;
        refit([](uint32_t) { return true; });
    }
    for (uint32_t i = 0; i + 1 < n; ++i) {
        h.left[i] = left[n + i];
        h.right[i] = right[n + i];
    }
    return stand;
}

}  // namespace bvhlab::accel
