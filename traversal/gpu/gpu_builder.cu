// SPDX-License-Identifier: MIT
// The GPU builders (gpu_builder.h). One stream, everything allocated before the first event, so
// that the events time the device pipeline alone. Compiled without FMA contraction
// (traversal/CMakeLists.txt): the Woop maps then equal the host's bit for bit.
#include "traversal/gpu/gpu_builder.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cuda/atomic>

#include <algorithm>
#include <string>

#include "accel/core/morton.h"
#include "traversal/cuda_check.h"

namespace bvhlab::trav {

using accel::Bvh2Node;

using accel::WoopTriangle;

namespace {

constexpr uint32_t kInvalid = 0xffffffffu;
constexpr uint32_t kWarp = 32;
/// H-PLOC merges a node's clusters down to this many, so that two children fill one warp.
constexpr uint32_t kHplocThreshold = kWarp / 2;
constexpr int kBlock = 256;

/// Subtrees of at most this many interior layout nodes are written by one thread, start to end;
/// larger ones node by node, a level per launch.
constexpr uint32_t kSubtreeInterior = 2;

/// What the leaf choice and the layout need of a node: the triangles below it, the BVH2 interior
/// nodes its subtree becomes (0: it becomes a leaf), its SAH cost (times its own half area), and
/// the height of its subtree in the layout (interior nodes on its longest path).
struct alignas(16) NodeMeta {
    uint32_t count;
    uint32_t interior;
    float cost;
    uint32_t height;

    __host__ __device__ bool leaf() const { return interior == 0; }
};

struct LeafRule {
    float ct, ci;
    uint32_t min_leaf, max_leaf;
};

struct BoxUnion {
    __device__ AABB operator()(const AABB& a, const AABB& b) const { return merge(a, b); }
};

unsigned grid_for(size_t n) { return unsigned((n + kBlock - 1) / kBlock); }

// Loads through L2 (not L1, which is not coherent): data that another block wrote before an
// atomic that this thread has seen.
__device__ AABB load_box(const AABB* b) {
    const float* f = reinterpret_cast<const float*>(b);
    return {{__ldcg(f), __ldcg(f + 1), __ldcg(f + 2)}, {__ldcg(f + 3), __ldcg(f + 4), __ldcg(f + 5)}};
}

__device__ NodeMeta load_meta(const NodeMeta* m) {
    const uint4 v = __ldcg(reinterpret_cast<const uint4*>(m));
    return {v.x, v.y, __uint_as_float(v.z), v.w};
}

/// Writes interior node `id` over children a and b (complete) with box `box`, and decides by
/// SAH whether its subtree becomes one leaf.
__device__ void make_node(uint32_t id, uint32_t a, uint32_t b, const AABB& box, AABB* boxes, uint2* children,
                          NodeMeta* meta, const LeafRule& rule) {
    const NodeMeta ma = load_meta(meta + a), mb = load_meta(meta + b);
    NodeMeta m;
    m.count = ma.count + mb.count;
    const float area = box.half_area();
    const float inner = rule.ct * area + ma.cost + mb.cost;
    const float as_leaf = rule.ci * float(m.count) * area;
    const bool leaf = m.count <= rule.min_leaf || (m.count <= rule.max_leaf && as_leaf <= inner);
    m.cost = leaf ? as_leaf : inner;
    m.interior = leaf ? 0 : 1 + ma.interior + mb.interior;
    m.height = leaf ? 0 : 1 + max(ma.height, mb.height);
    boxes[id] = box;
    children[id] = make_uint2(a, b);
    *reinterpret_cast<uint4*>(meta + id) = make_uint4(m.count, m.interior, __float_as_uint(m.cost), m.height);
}

__global__ void triangle_boxes(uint32_t n, const Vec3* __restrict__ verts, const uint32_t* __restrict__ idx,
                               AABB* __restrict__ boxes, AABB* __restrict__ centres) {
    const uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= n) return;
    AABB b = AABB::empty();
    for (int k = 0; k < 3; ++k) b.extend(verts[idx[3 * t + k]]);
    boxes[t] = b;
    centres[t] = AABB::of_point(b.center());
}

template <typename Key>
__global__ void morton_codes(uint32_t n, int bits, const AABB* __restrict__ boxes, const AABB* __restrict__ bounds,
                             Key* __restrict__ keys, uint32_t* __restrict__ ids) {
    const uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= n) return;
    const AABB c = *bounds;
    const uint32_t cells = accel::morton::cells_per_axis(bits);
    const Vec3 scale{accel::morton::axis_scale(c.lo.x, c.hi.x, cells), accel::morton::axis_scale(c.lo.y, c.hi.y, cells),
                     accel::morton::axis_scale(c.lo.z, c.hi.z, cells)};
    const Vec3 p = boxes[t].center();
    if constexpr (sizeof(Key) == 8)
        keys[t] = accel::morton::code60(p, c.lo, scale);
    else
        keys[t] = accel::morton::code30(p, c.lo, scale);
    ids[t] = t;
}

/// Leaf s of the hierarchy is the s-th triangle in key order.
__global__ void make_leaves(uint32_t n, const uint32_t* __restrict__ sorted_ids, const AABB* __restrict__ tri_boxes,
                            AABB* __restrict__ boxes, NodeMeta* __restrict__ meta, uint32_t* __restrict__ clusters,
                            LeafRule rule) {
    const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= n) return;
    const AABB b = tri_boxes[sorted_ids[s]];
    boxes[s] = b;
    meta[s] = {1, 0, rule.ci * b.half_area(), 0};
    if (clusters) clusters[s] = s;
}

// --- LBVH: Karras's hierarchy, then boxes bottom-up.

template <typename Key>
__global__ void karras_hierarchy(uint32_t n, const Key* __restrict__ keys, uint2* __restrict__ children,
                                 uint32_t* __restrict__ parent) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i + 1 >= n) return;
    uint32_t l, r;
    accel::morton::karras_children(keys, int64_t(n), int64_t(i), l, r);
    children[n + i] = make_uint2(l, r);
    parent[l] = n + i;
    parent[r] = n + i;
}

/// From each leaf upwards; the second child to arrive at a node boxes it and goes on.
__global__ void fit_boxes(uint32_t n, const uint32_t* __restrict__ parent, uint2* children, AABB* boxes, NodeMeta* meta,
                          uint32_t* __restrict__ visits, LeafRule rule) {
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= n) return;
    uint32_t p = parent[k];
    while (p != kInvalid) {
        __threadfence();  // this thread's node before the counter
        if (atomicAdd(&visits[p - n], 1u) == 0) return;
        __threadfence();
        const uint2 c = children[p];
        make_node(p, c.x, c.y, merge(load_box(boxes + c.x), load_box(boxes + c.y)), boxes, children, meta, rule);
        p = parent[p];
    }
}

// --- H-PLOC (Benthin et al. 2024, Algorithm 1).

struct WarpScratch {
    uint32_t ids[kWarp];
    uint32_t nn[kWarp];
    AABB boxes[kWarp];
    uint32_t base;  // the first node id of a round's new nodes
};

/// PLOC within the warp: the clusters in lanes [0, count) (node id and box) are merged, each
/// round every cluster pairing with its nearest neighbour within `radius` lanes (the smallest
/// merged box; ties by the pair's lanes, so that the closest pair is always mutual), until at
/// most `target` remain, compacted to the low lanes. Returns the count. The lanes see each
/// other's clusters through the warp's shared scratch.
__device__ __forceinline__ uint32_t ploc_merge(uint32_t& id, AABB& box, uint32_t count, uint32_t target, int radius,
                                               WarpScratch& scratch, uint32_t* node_counter, AABB* boxes,
                                               uint2* children, NodeMeta* meta, const LeafRule& rule) {
    const uint32_t lane = threadIdx.x % kWarp;
    const uint32_t below = (1u << lane) - 1;
    while (count > target) {
        scratch.ids[lane] = id;
        scratch.boxes[lane] = box;
        __syncwarp();
        uint64_t best = ~0ull;
        if (lane < count) {
            const uint32_t lo = lane > uint32_t(radius) ? lane - uint32_t(radius) : 0;
            const uint32_t hi = min(lane + uint32_t(radius), count - 1);
            for (uint32_t j = lo; j <= hi; ++j) {
                if (j == lane) continue;
                const float a = merge(box, scratch.boxes[j]).half_area();
                const uint64_t pair = lane < j ? (lane << 5 | j) : (j << 5 | lane);
                const uint64_t key = uint64_t(__float_as_uint(a)) << 32 | pair;
                if (key < best) best = key;
            }
        }
        const uint32_t pl = uint32_t(best >> 5) & 31, ph = uint32_t(best) & 31;
        const uint32_t nn = lane < count ? (pl == lane ? ph : pl) : lane;
        scratch.nn[lane] = nn;
        __syncwarp();
        const bool mutual = lane < count && scratch.nn[nn] == lane;
        const bool creator = mutual && lane < nn;
        const uint32_t creators = __ballot_sync(~0u, creator);
        const uint32_t kept = __ballot_sync(~0u, lane < count && !(mutual && lane > nn));
        // One atomic per round for the warp's new nodes (every round has at least one).
        if (lane == 0) scratch.base = atomicAdd(node_counter, uint32_t(__popc(creators)));
        __syncwarp();
        if (creator) {
            const uint32_t node = scratch.base + __popc(creators & below);
            box = merge(box, scratch.boxes[nn]);
            make_node(node, id, scratch.ids[nn], box, boxes, children, meta, rule);
            id = node;
        }
        __syncwarp();
        if (kept >> lane & 1) {
            const uint32_t at = __popc(kept & below);
            scratch.ids[at] = id;
            scratch.boxes[at] = box;
        }
        __syncwarp();
        count = __popc(kept);
        if (lane < count) {
            id = scratch.ids[lane];
            box = scratch.boxes[lane];
        }
        __syncwarp();
    }
    return count;
}

template <typename Key>
__global__ void __launch_bounds__(kBlock)
    hploc(uint32_t n, const Key* __restrict__ keys, int32_t* parent_ids, uint32_t* clusters, AABB* boxes,
          uint2* children, NodeMeta* meta, uint32_t* node_counter, uint32_t* root, int radius, LeafRule rule) {
    __shared__ WarpScratch scratch[kBlock / kWarp];
    WarpScratch& mine = scratch[threadIdx.x / kWarp];
    const uint32_t lane = threadIdx.x % kWarp;
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    uint32_t left = i, right = i, split = 0;
    bool active = i < n;
    while (__ballot_sync(~0u, active)) {
        if (active) {
            int32_t previous;
            // Join the neighbour whose boundary keys differ less (Apetrei 2014); the first of
            // two siblings to arrive stops, the second takes the parent.
            if (left == 0 || (right != n - 1 && accel::morton::apetrei_delta(keys, right) <
                                                    accel::morton::apetrei_delta(keys, left - 1))) {
                split = right + 1;
                __threadfence();
                previous = atomicExch(&parent_ids[right], int32_t(left));
                if (previous != -1) right = uint32_t(previous);
            } else {
                split = left;
                __threadfence();
                previous = atomicExch(&parent_ids[left - 1], int32_t(right));
                if (previous != -1) left = uint32_t(previous);
            }
            __threadfence();
            if (previous == -1) active = false;
        }
        __syncwarp();  // reconverge before the warp's collectives
        const uint32_t size = right - left + 1;
        const bool final_node = active && size == n;
        uint32_t wave = __ballot_sync(~0u, active && (size > kHplocThreshold || final_node));
        while (wave) {
            const int src = __ffs(wave) - 1;
            wave &= wave - 1;
            const uint32_t l = __shfl_sync(~0u, left, src), r = __shfl_sync(~0u, right, src);
            const uint32_t s = __shfl_sync(~0u, split, src);
            const bool last = __shfl_sync(~0u, final_node, src);
            // Each child's clusters sit at the start of its range (an unmerged child: all of its
            // leaves; a merged one: at most 16, then kInvalid).
            const uint32_t left_span = min(s - l, kHplocThreshold), right_span = min(r + 1 - s, kHplocThreshold);
            const uint32_t a = lane < left_span ? __ldcg(&clusters[l + lane]) : kInvalid;
            const uint32_t nl = __popc(__ballot_sync(~0u, a != kInvalid));
            const uint32_t b = lane < right_span ? __ldcg(&clusters[s + lane]) : kInvalid;
            const uint32_t nr = __popc(__ballot_sync(~0u, b != kInvalid));
            const uint32_t b_shifted = __shfl_sync(~0u, b, int(lane - nl) & 31);
            uint32_t id = lane < nl ? a : (lane < nl + nr ? b_shifted : kInvalid);
            AABB box = id != kInvalid ? load_box(boxes + id) : AABB::empty();
            const uint32_t count = ploc_merge(id, box, nl + nr, last ? 1 : kHplocThreshold, radius, mine, node_counter,
                                              boxes, children, meta, rule);
            const uint32_t store_span = min(r - l + 1, kHplocThreshold);
            if (lane < store_span) clusters[l + lane] = lane < count ? id : kInvalid;
            if (last && lane == 0) *root = id;
            __syncwarp();
            __threadfence();
        }
        if (size == n) active = false;  // the root is done
    }
}

// --- The BVH2 layout, top down, one level per launch.

struct Mesh {
    const Vec3* verts;
    const uint32_t* idx;
};

/// The triangle ids of leaf subtree `node` to tri_ids[first, ...), left to right (their Woop maps
/// come after, from a flat kernel: the maps' double-precision math stays out of the tree walks).
__device__ void emit_leaf(uint32_t node, uint32_t first, uint32_t n, const uint2* children, const uint32_t* sorted_ids,
                          uint32_t* tri_ids) {
    uint32_t stack[Bvh2Node::kMaxLeafCount];
    int sp = 0;
    stack[sp++] = node;
    while (sp) {
        const uint32_t x = stack[--sp];
        if (x < n) {
            tri_ids[first++] = sorted_ids[x];
        } else {
            const uint2 c = children[x];
            stack[sp++] = c.y;
            stack[sp++] = c.x;
        }
    }
}

/// The Woop map of every triangle in leaf order.
__global__ void woop_maps(uint32_t n, const uint32_t* __restrict__ tri_ids, const Vec3* __restrict__ verts,
                          const uint32_t* __restrict__ idx, WoopTriangle* __restrict__ tris) {
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= n) return;
    const uint32_t t = tri_ids[k];
    WoopTriangle w;
    accel::woop_map(verts[idx[3 * t]], verts[idx[3 * t + 1]], verts[idx[3 * t + 2]], w);
    tris[k] = w;
}

struct Layout {
    Bvh2Node* nodes;
    WoopTriangle* tris;
    uint32_t* tri_ids;
};

struct LayoutInput {
    uint32_t n;
    const uint2* children;
    const AABB* boxes;
    const NodeMeta* meta;
    const uint32_t* sorted_ids;
    Mesh mesh;
};

/// Writes layout node `slot` for hierarchy node `node` (interior, not a leaf): its children's
/// boxes and references, their leaves' triangles. The left child's subtree takes the slots
/// after `slot`, the right one's those after the left's. Calls next(child, first, slot) for
/// each interior child.
template <typename Next>
__device__ void write_node(const LayoutInput& in, const Layout& out, uint32_t node, uint32_t first, uint32_t slot,
                           Next&& next) {
    const uint2 c = in.children[node];
    const NodeMeta m[2] = {in.meta[c.x], in.meta[c.y]};
    const uint32_t child[2] = {c.x, c.y};
    const uint32_t firsts[2] = {first, first + m[0].count};
    const uint32_t slots[2] = {slot + 1, slot + 1 + m[0].interior};
    Bvh2Node o{};
    for (int k = 0; k < 2; ++k) {
        o.set_child_box(k, in.boxes[child[k]]);
        o.child[k] = m[k].leaf() ? Bvh2Node::leaf_ref(firsts[k], m[k].count) : int32_t(slots[k]);
    }
    out.nodes[slot] = o;
    for (int k = 0; k < 2; ++k) {
        if (m[k].leaf())
            emit_leaf(child[k], firsts[k], in.n, in.children, in.sorted_ids, out.tri_ids);
        else
            next(child[k], firsts[k], slots[k]);
    }
}

/// Writes the whole subtree below `node` (at most kSubtreeInterior interior nodes) in this
/// thread, depth first.
__device__ void write_subtree(const LayoutInput& in, const Layout& out, uint32_t node, uint32_t first, uint32_t slot) {
    uint4 stack[kSubtreeInterior];
    int sp = 0;
    stack[sp++] = make_uint4(node, first, slot, 0);
    while (sp) {
        const uint4 t = stack[--sp];
        write_node(in, out, t.x, t.y, t.z,
                   [&](uint32_t c, uint32_t f, uint32_t sl) { stack[sp++] = make_uint4(c, f, sl, 0); });
    }
}

/// After the hierarchy: the root and the layout's height, for the host to launch one level each;
/// a root that is a leaf is written at once (both slots name it, the second behind an empty
/// box), otherwise the root is the first level's one entry.
__global__ void seed_layout(LayoutInput in, uint32_t* words, Layout out, uint4* level0, uint32_t* counts) {
    const uint32_t root = words[0];
    const NodeMeta rm = in.meta[root];
    words[2] = max(rm.height, 1u);
    if (!rm.leaf()) {
        level0[0] = make_uint4(root, 0, 0, 0);
        counts[0] = 1;
        return;
    }
    Bvh2Node o{};
    o.set_child_box(0, in.boxes[root]);
    o.set_child_box(1, AABB::empty());
    o.child[0] = o.child[1] = Bvh2Node::leaf_ref(0, rm.count);
    out.nodes[0] = o;
    emit_leaf(root, 0, in.n, in.children, in.sorted_ids, out.tri_ids);
}

/// One level of the layout, top down: each entry (node, first triangle, layout slot) is
/// written whole by its thread when its subtree is small, else its node is written and its
/// interior children become the next level's entries. Slots are depth first (a node's left
/// child in the next slot), whatever order the entries come in.
__global__ void __launch_bounds__(kBlock)
    write_level(LayoutInput in, Layout out, const uint4* __restrict__ level, uint4* __restrict__ next,
                const uint32_t* counts, uint32_t* next_count) {
    const uint32_t count = counts[0];
    for (uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < count; k += gridDim.x * blockDim.x) {
        const uint4 t = level[k];
        if (in.meta[t.x].interior <= kSubtreeInterior) {
            write_subtree(in, out, t.x, t.y, t.z);
        } else {
            write_node(in, out, t.x, t.y, t.z, [&](uint32_t c, uint32_t f, uint32_t sl) {
                next[atomicAdd(next_count, 1u)] = make_uint4(c, f, sl, 0);
            });
        }
    }
}

__global__ void set_word(uint32_t* p, uint32_t v) { *p = v; }

class Events {
public:
    explicit Events(int n) : e_(size_t(n)) {
        for (cudaEvent_t& e : e_) BVHLAB_CUDA_CHECK(cudaEventCreate(&e));
    }
    ~Events() {
        for (cudaEvent_t e : e_) BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(e));
    }
    void record(int k) { BVHLAB_CUDA_CHECK(cudaEventRecord(e_[size_t(k)])); }
    /// Waits for event k; a kernel's fault surfaces here.
    void sync(int k) { BVHLAB_CUDA_CHECK(cudaEventSynchronize(e_[size_t(k)])); }
    double ms(int a, int b) const {
        float t = 0.0f;
        BVHLAB_CUDA_CHECK(cudaEventElapsedTime(&t, e_[size_t(a)], e_[size_t(b)]));
        return t;
    }

private:
    std::vector<cudaEvent_t> e_;
};

template <typename T>
void download(std::vector<T>& h, const T* d, size_t count) {
    h.resize(count);
    if (count) detail::copy_to_host(h.data(), d, count * sizeof(T));
}

template <typename Key>
GpuBuild build(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
               bool keep_raw) {
    const uint32_t n = uint32_t(mesh.triangle_count());
    const int bits = options.morton_bits;
    const bool lbvh = kind == accel::BuilderKind::kLbvh;
    const LeafRule rule{options.config.traversal_cost, options.config.intersection_cost, options.config.min_leaf_size,
                        options.config.max_leaf_size};
    const size_t base = gpu_memory_use().current;
    GpuBuild g;
    Events ev(8);
    ev.record(0);
    DeviceBuffer<Vec3> verts(mesh.vertices);
    DeviceBuffer<uint32_t> idx(mesh.indices);
    ev.record(1);

    // Everything the pipeline needs, before its first event.
    const size_t nodes = 2 * size_t(n) - 1, inner = std::max<size_t>(n - 1, 1);
    DeviceBuffer<AABB> tri_boxes(n), centres(n), bounds(1), boxes(nodes);
    DeviceBuffer<Key> keys(n), keys_alt(n);
    DeviceBuffer<uint32_t> ids(n), ids_alt(n);
    DeviceBuffer<uint2> children(nodes);
    DeviceBuffer<NodeMeta> meta(nodes);
    DeviceBuffer<uint32_t> parent(lbvh ? nodes : 0), visits(lbvh ? inner : 0), clusters(lbvh ? 0 : n);
    DeviceBuffer<int32_t> parent_ids(lbvh ? 0 : inner);
    DeviceBuffer<uint32_t> words(3);  // root, H-PLOC's node counter, the layout's height
    DeviceBuffer<Bvh2Node> out_nodes(inner);
    DeviceBuffer<uint4> levels(2 * inner);  // the layout's entries of two levels
    DeviceBuffer<uint32_t> level_counts(accel::kMaxTreeDepth + 1);
    g.tris.resize(n);
    g.tri_ids.resize(n);
    size_t reduce_bytes = 0, sort_bytes = 0;
    cub::DoubleBuffer<Key> dk(keys.data(), keys_alt.data());
    cub::DoubleBuffer<uint32_t> dv(ids.data(), ids_alt.data());
    BVHLAB_CUDA_CHECK(cub::DeviceReduce::Reduce(nullptr, reduce_bytes, centres.data(), bounds.data(), int(n),
                                                BoxUnion{}, AABB::empty()));
    BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, sort_bytes, dk, dv, int(n), 0, bits));
    DeviceBuffer<uint8_t> scratch(std::max(reduce_bytes, sort_bytes));
    g.peak_bytes = gpu_memory_use().current - base;
    uint32_t* root = words.data();
    uint32_t* node_counter = words.data() + 1;
    if (lbvh) {
        detail::fill_device_bytes(parent.data(), 0xff, parent.bytes());
        detail::fill_device_bytes(visits.data(), 0, visits.bytes());
    } else {
        detail::fill_device_bytes(parent_ids.data(), 0xff, parent_ids.bytes());
    }
    detail::fill_device_bytes(words.data(), 0, words.bytes());
    detail::fill_device_bytes(level_counts.data(), 0, level_counts.bytes());

    ev.record(2);
    triangle_boxes<<<grid_for(n), kBlock>>>(n, verts.data(), idx.data(), tri_boxes.data(), centres.data());
    BVHLAB_CHECK_LAUNCH();
    BVHLAB_CUDA_CHECK(cub::DeviceReduce::Reduce(scratch.data(), reduce_bytes, centres.data(), bounds.data(), int(n),
                                                BoxUnion{}, AABB::empty()));
    ev.record(3);
    morton_codes<Key><<<grid_for(n), kBlock>>>(n, bits, tri_boxes.data(), bounds.data(), keys.data(), ids.data());
    BVHLAB_CHECK_LAUNCH();
    ev.record(4);
    BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(scratch.data(), sort_bytes, dk, dv, int(n), 0, bits));
    ev.record(5);
    const Key* sorted_keys = dk.Current();
    const uint32_t* sorted_ids = dv.Current();
    make_leaves<<<grid_for(n), kBlock>>>(n, sorted_ids, tri_boxes.data(), boxes.data(), meta.data(),
                                         lbvh ? nullptr : clusters.data(), rule);
    BVHLAB_CHECK_LAUNCH();
    if (n == 1) {
        // The root is leaf 0 (words are zero).
    } else if (lbvh) {
        set_word<<<1, 1>>>(root, n);
        karras_hierarchy<Key><<<grid_for(n - 1), kBlock>>>(n, sorted_keys, children.data(), parent.data());
        BVHLAB_CHECK_LAUNCH();
        fit_boxes<<<grid_for(n), kBlock>>>(n, parent.data(), children.data(), boxes.data(), meta.data(), visits.data(),
                                           rule);
        BVHLAB_CHECK_LAUNCH();
    } else {
        set_word<<<1, 1>>>(node_counter, n);
        hploc<Key><<<grid_for(n), kBlock>>>(n, sorted_keys, parent_ids.data(), clusters.data(), boxes.data(),
                                            children.data(), meta.data(), node_counter, root, options.ploc_radius,
                                            rule);
        BVHLAB_CHECK_LAUNCH();
    }
    ev.record(6);
    // The layout, one level per launch: the host reads the layout's height (one small copy, the
    // pipeline's only round trip) and launches that many levels.
    const unsigned level_grid = std::min<unsigned>(unsigned(gpu_sm_count()) * 8, grid_for(inner));
    const Layout out{out_nodes.data(), g.tris.data(), g.tri_ids.data()};
    const LayoutInput in{n, children.data(), boxes.data(), meta.data(), sorted_ids, Mesh{verts.data(), idx.data()}};
    seed_layout<<<1, 1>>>(in, words.data(), out, levels.data(), level_counts.data());
    BVHLAB_CHECK_LAUNCH();
    uint32_t height = 0;
    detail::copy_to_host(&height, words.data() + 2, sizeof height);
    if (height > accel::kMaxTreeDepth)
        throw Error("builder '" + std::string(accel::builder_name(kind)) + "' made a tree " + std::to_string(height) +
                    " levels deep; the traversal stacks hold " + std::to_string(accel::kMaxTreeDepth));
    for (uint32_t level = 0; level < height; ++level) {
        const uint4* cur = levels.data() + (level % 2) * inner;
        uint4* nxt = levels.data() + ((level + 1) % 2) * inner;
        write_level<<<level_grid, kBlock>>>(in, out, cur, nxt, level_counts.data() + level,
                                            level_counts.data() + level + 1);
    }
    BVHLAB_CHECK_LAUNCH();
    woop_maps<<<grid_for(n), kBlock>>>(n, g.tri_ids.data(), verts.data(), idx.data(), g.tris.data());
    BVHLAB_CHECK_LAUNCH();
    ev.record(7);
    ev.sync(7);

    GpuBuildTimes& t = g.times;
    t.upload_ms = ev.ms(0, 1);
    t.bounds_ms = ev.ms(2, 3);
    t.morton_ms = ev.ms(3, 4);
    t.sort_ms = ev.ms(4, 5);
    t.hierarchy_ms = ev.ms(5, 6);
    t.convert_ms = ev.ms(6, 7);
    t.total_ms = ev.ms(2, 7);

    // The host copy, and the nodes moved to a buffer of their exact size.
    uint32_t w[3];  // root, node counter, height
    detail::copy_to_host(w, words.data(), sizeof w);
    NodeMeta root_meta;
    detail::copy_to_host(&root_meta, meta.data() + w[0], sizeof root_meta);
    const size_t node_count = root_meta.leaf() ? 1 : root_meta.interior;
    g.host.depth = height;
    download(g.host.nodes, out_nodes.data(), node_count);
    g.nodes.upload(g.host.nodes);
    download(g.host.tris, g.tris.data(), n);
    download(g.host.tri_ids, g.tri_ids.data(), n);
    if (keep_raw) {
        accel::RawHierarchy& raw = g.raw;
        raw.root = w[0];
        std::vector<Key> k;
        download(k, sorted_keys, n);
        raw.keys.assign(k.begin(), k.end());
        download(raw.sorted_ids, sorted_ids, n);
        std::vector<uint2> c;
        download(c, children.data(), nodes);
        for (size_t i = n; i < nodes; ++i) {
            raw.left.push_back(c[i].x);
            raw.right.push_back(c[i].y);
        }
        download(raw.boxes, boxes.data(), nodes);
    }
    return g;
}

}  // namespace

namespace detail {

GpuBuild gpu_build(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                   bool keep_raw) {
    return options.morton_bits == 60 ? build<uint64_t>(mesh, kind, options, keep_raw)
                                     : build<uint32_t>(mesh, kind, options, keep_raw);
}

}  // namespace detail

}  // namespace bvhlab::trav
