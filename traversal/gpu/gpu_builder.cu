// SPDX-License-Identifier: MIT
// The GPU builders (gpu_builder.h). One stream, everything allocated before the first event, so
// that the events time the device pipeline alone. Compiled without FMA contraction
// (traversal/CMakeLists.txt): the Woop maps then equal the host's bit for bit.
#include "traversal/gpu/gpu_builder.h"

#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
#include <cub/block/block_reduce.cuh>
#include <cub/block/block_scan.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <cuda/atomic>

#include <algorithm>
#include <optional>
#include <string>

#include "accel/core/morton.h"
#include "accel/core/reinsertion_search.h"
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

/// A kernel started by launch() runs its blocks as the kernel before it finishes (programmatic
/// dependent launch, sm_90): it waits here, before it touches memory, for that kernel's end and
/// its writes. A no-op in a kernel launched otherwise.
__device__ __forceinline__ void wait_for_previous() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}

/// Launches kernel k (which calls wait_for_previous first) so that the device starts it while
/// the kernel before it in the stream ends, not after a launch's latency.
template <typename... Params, typename... Args>
void launch(void (*k)(Params...), unsigned grid, unsigned block, Args... args) {
    cudaLaunchAttribute attr{};
    attr.id = cudaLaunchAttributeProgrammaticStreamSerialization;
    attr.val.programmaticStreamSerializationAllowed = 1;
    cudaLaunchConfig_t config{};
    config.gridDim = dim3(grid);
    config.blockDim = dim3(block);
    config.attrs = &attr;
    config.numAttrs = 1;
    BVHLAB_CUDA_CHECK(cudaLaunchKernelEx(&config, k, Params(args)...));
}

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

__device__ void store_meta(NodeMeta* at, const NodeMeta& m) {
    *reinterpret_cast<uint4*>(at) = make_uint4(m.count, m.interior, __float_as_uint(m.cost), m.height);
}

/// The meta of an interior node over children with metas ma and mb (left, right) and box `box`:
/// decides by SAH whether its subtree becomes one leaf.
__device__ NodeMeta node_meta(const NodeMeta& ma, const NodeMeta& mb, const AABB& box, const LeafRule& rule) {
    NodeMeta m;
    m.count = ma.count + mb.count;
    const float area = box.half_area();
    const float inner = rule.ct * area + ma.cost + mb.cost;
    const float as_leaf = rule.ci * float(m.count) * area;
    const bool leaf = m.count <= rule.min_leaf || (m.count <= rule.max_leaf && as_leaf <= inner);
    m.cost = leaf ? as_leaf : inner;
    m.interior = leaf ? 0 : 1 + ma.interior + mb.interior;
    m.height = leaf ? 0 : 1 + max(ma.height, mb.height);
    return m;
}

/// Writes interior node `id` over children a and b (complete) with box `box` (node_meta).
__device__ NodeMeta make_node(uint32_t id, uint32_t a, uint32_t b, const NodeMeta& ma, const NodeMeta& mb,
                              const AABB& box, AABB* boxes, uint2* children, NodeMeta* meta, const LeafRule& rule) {
    const NodeMeta m = node_meta(ma, mb, box, rule);
    boxes[id] = box;
    children[id] = make_uint2(a, b);
    store_meta(meta + id, m);
    return m;
}

__device__ void make_node(uint32_t id, uint32_t a, uint32_t b, const AABB& box, AABB* boxes, uint2* children,
                          NodeMeta* meta, const LeafRule& rule) {
    make_node(id, a, b, load_meta(meta + a), load_meta(meta + b), box, boxes, children, meta, rule);
}

// Float minimum and maximum as atomics on the floats' bits: a non-negative float orders as its
// int, a negative one reversed as its unsigned (-0 is made +0 first).
__device__ void atomic_min(float* at, float v) {
    v += 0.0f;
    if (v >= 0.0f)
        atomicMin(reinterpret_cast<int*>(at), __float_as_int(v));
    else
        atomicMax(reinterpret_cast<unsigned*>(at), __float_as_uint(v));
}

__device__ void atomic_max(float* at, float v) {
    v += 0.0f;
    if (v >= 0.0f)
        atomicMax(reinterpret_cast<int*>(at), __float_as_int(v));
    else
        atomicMin(reinterpret_cast<unsigned*>(at), __float_as_uint(v));
}

/// *at grown to hold `b`, by atomics on each corner.
__device__ void atomic_merge(AABB* at, const AABB& b) {
    atomic_min(&at->lo.x, b.lo.x);
    atomic_min(&at->lo.y, b.lo.y);
    atomic_min(&at->lo.z, b.lo.z);
    atomic_max(&at->hi.x, b.hi.x);
    atomic_max(&at->hi.y, b.hi.y);
    atomic_max(&at->hi.z, b.hi.z);
}

__global__ void set_empty(AABB* box) { *box = AABB::empty(); }

/// boxes[t] = box_of(t) for every primitive t, and the bounds of their centres added to *bounds
/// (set empty before): each thread takes primitives a grid apart, a block's bounds are reduced
/// in shared memory and added with one atomic per side and axis. With `centres`, each centre is
/// written too (binned SAH reads them more often than the boxes).
template <typename BoxOf>
__global__ void __launch_bounds__(kBlock) prim_boxes(uint32_t n, BoxOf box_of, AABB* __restrict__ boxes,
                                                     AABB* __restrict__ bounds, Vec3* __restrict__ centres) {
    AABB c = AABB::empty();
    for (uint32_t t = blockIdx.x * blockDim.x + threadIdx.x; t < n; t += gridDim.x * blockDim.x) {
        const AABB b = box_of(t);
        boxes[t] = b;
        c.extend(b.center());
        if (centres) centres[t] = b.center();
    }
    using Reduce = cub::BlockReduce<AABB, kBlock>;
    __shared__ typename Reduce::TempStorage scratch;
    c = Reduce(scratch).Reduce(c, BoxUnion{});
    if (threadIdx.x == 0 && !c.is_empty()) atomic_merge(bounds, c);
}

/// A triangle's box.
struct TriangleBox {
    const Vec3* verts;
    const uint32_t* idx;
    __device__ AABB operator()(uint32_t t) const {
        AABB b = AABB::empty();
        for (int k = 0; k < 3; ++k) b.extend(verts[idx[3 * t + k]]);
        return b;
    }
};

/// Instance t's world box (its BLAS's frontier boxes' corners under its transform), and its
/// record with the inverse transform (in double, as scene::Transform::inverse). A singular or
/// non-finite transform or box marks `bad` with the lowest such instance.
struct InstanceBox {
    detail::TlasInput in;
    __device__ AABB operator()(uint32_t t) const;
};

__device__ AABB InstanceBox::operator()(uint32_t t) const {
    const float* m = in.object_to_world[t].m;
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    const double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    AABB w = AABB::empty();
    const uint32_t blas = in.blas[t];
    for (uint32_t k = in.frontier_first[blas]; k < in.frontier_first[blas + 1]; ++k) {
        const AABB fb = in.frontier[k];
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3 p{(corner & 1) ? fb.hi.x : fb.lo.x, (corner & 2) ? fb.hi.y : fb.lo.y,
                         (corner & 4) ? fb.hi.z : fb.lo.z};
            w.extend(Vec3{m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                          m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]});
        }
    }
    const bool finite = isfinite(w.lo.x) && isfinite(w.lo.y) && isfinite(w.lo.z) && isfinite(w.hi.x) &&
                        isfinite(w.hi.y) && isfinite(w.hi.z);
    accel::InstanceRecord& rec = in.records[t];
    rec.blas = blas;
    rec.first_id = in.first_id[t];
    rec.reserved[0] = rec.reserved[1] = 0;
    if (!(isfinite(det) && det != 0.0) || !finite) {
        atomicMin(in.bad, t);
        w = AABB::of_point({0, 0, 0});
    } else {
        const double r[9] = {(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det,
                             (f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det,
                             (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det};
        float* inv = rec.world_to_object;
        for (int row = 0; row < 3; ++row) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) {
                inv[4 * row + k] = float(r[3 * row + k]);
                s -= r[3 * row + k] * m[4 * k + 3];
            }
            inv[4 * row + 3] = float(s);
        }
    }
    return w;
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

/// A leaf's meta: one triangle, its SAH cost.
__device__ NodeMeta leaf_meta(const AABB& box, const LeafRule& rule) { return {1, 0, rule.ci * box.half_area(), 0}; }

/// Writes leaf s of the hierarchy, triangle sorted_ids[s]; returns its box, its meta in m.
__device__ AABB make_leaf(uint32_t s, const uint32_t* __restrict__ sorted_ids, const AABB* __restrict__ tri_boxes,
                          AABB* boxes, NodeMeta* meta, const LeafRule& rule, NodeMeta& m) {
    const AABB box = tri_boxes[sorted_ids[s]];
    m = leaf_meta(box, rule);
    boxes[s] = box;
    store_meta(meta + s, m);
    return box;
}

/// Leaf s of the hierarchy is the s-th triangle in key order.
__global__ void make_leaves(uint32_t n, const uint32_t* __restrict__ sorted_ids, const AABB* __restrict__ tri_boxes,
                            AABB* __restrict__ boxes, NodeMeta* __restrict__ meta, uint32_t* __restrict__ clusters,
                            LeafRule rule) {
    const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= n) return;
    NodeMeta m;
    make_leaf(s, sorted_ids, tri_boxes, boxes, meta, rule, m);
    if (clusters) clusters[s] = s;
}

// --- LBVH: the radix tree of the sorted keys, bottom-up with its boxes (accel::morton).

/// Thread s makes leaf s (the s-th triangle in key order) and climbs: each node joins its
/// parent (morton::radix_parent) and leaves its outer key there; the first of two siblings to
/// arrive stops, the second reads the other's key, boxes the parent and goes on. A node's box
/// and meta stay in registers on the way up, so each step loads only the sibling's.
template <typename Key>
__global__ void lbvh_climb(uint32_t n, const Key* __restrict__ keys, const uint32_t* __restrict__ sorted_ids,
                           const AABB* __restrict__ tri_boxes, AABB* boxes, NodeMeta* meta, uint2* children,
                           uint32_t* __restrict__ parent, uint32_t* __restrict__ outer, uint32_t* __restrict__ root,
                           LeafRule rule) {
    const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= n) return;
    NodeMeta m;
    AABB box = make_leaf(s, sorted_ids, tri_boxes, boxes, meta, rule, m);
    uint32_t node = s, left = s, right = s;
    while (left != 0 || right != n - 1) {
        const accel::morton::RadixParent p = accel::morton::radix_parent(keys, n, left, right);
        const uint32_t up = n + p.split;
        parent[node] = up;
        reinterpret_cast<uint32_t*>(children + up)[p.left_child ? 0 : 1] = node;
        // Releases this thread's node and link to the sibling's thread; acquires the sibling's.
        cuda::atomic_ref<uint32_t, cuda::thread_scope_device> slot(outer[p.split]);
        const uint32_t other = slot.exchange(p.left_child ? left : right, cuda::memory_order_acq_rel);
        if (other == kInvalid) return;
        (p.left_child ? right : left) = other;
        const uint32_t sibling = __ldcg(reinterpret_cast<const uint32_t*>(children + up) + (p.left_child ? 1 : 0));
        const AABB sb = load_box(boxes + sibling);
        const NodeMeta sm = load_meta(meta + sibling);
        box = merge(box, sb);
        m = p.left_child ? make_node(up, node, sibling, m, sm, box, boxes, children, meta, rule)
                         : make_node(up, sibling, node, sm, m, box, boxes, children, meta, rule);
        node = up;
    }
    *root = node;
}

/// Climbs that read every node's box and meta from memory (an earlier kernel or the sibling's
/// thread wrote them).
struct WrittenLeaves {
    static constexpr bool kMade = false;
    __device__ AABB operator()(uint32_t, NodeMeta&) const { return AABB::empty(); }
};

/// leaves_and_climb's leaves: every leaf has a thread, and a leaf's box and meta are made again
/// from the triangle's box by whichever thread needs them.
struct MadeLeaves {
    static constexpr bool kMade = true;
    const uint32_t* sorted_ids;
    const AABB* tri_boxes;
    LeafRule rule;
    __device__ AABB operator()(uint32_t s, NodeMeta& m) const {
        const AABB box = tri_boxes[sorted_ids[s]];
        m = leaf_meta(box, rule);
        return box;
    }
};

/// From node `node` upwards, its box and meta (written already) in `box` and `m`: the second of
/// two siblings to arrive at their parent boxes it and goes on, the first stops. The node's box
/// and meta stay in registers, so each step loads only the sibling's; one acquire-release add on
/// the parent's counter hands them from the sibling's thread to this one. The links and parents
/// do not change, so they are read before the add. With MadeLeaves a parent with a leaf child
/// takes no add and no wait: its other child's thread makes the leaf again and goes on (of two
/// leaves, the left one's thread), and a leaf beside an interior node stops.
template <typename Leaves = WrittenLeaves>
__device__ void climb(uint32_t node, AABB box, NodeMeta m, uint32_t n, const uint32_t* __restrict__ parent,
                      const uint2* children, AABB* boxes, NodeMeta* meta, uint32_t* __restrict__ visits,
                      const LeafRule& rule, const Leaves& leaves = {}) {
    for (uint32_t p = parent[node]; p != kInvalid;) {
        const uint2 c = children[p];
        const uint32_t up = parent[p];
        const bool first = c.x == node;
        const uint32_t sibling = first ? c.y : c.x;
        AABB sb;
        NodeMeta sm;
        if (Leaves::kMade && sibling < n) {
            if (node < n && !first) return;
            sb = leaves(sibling, sm);
        } else if (Leaves::kMade && node < n) {
            return;
        } else {
            cuda::atomic_ref<uint32_t, cuda::thread_scope_device> count(visits[p - n]);
            if (count.fetch_add(1u, cuda::memory_order_acq_rel) == 0) return;
            sb = load_box(boxes + sibling);
            sm = load_meta(meta + sibling);
        }
        box = merge(box, sb);
        m = first ? node_meta(m, sm, box, rule) : node_meta(sm, m, box, rule);
        boxes[p] = box;
        store_meta(meta + p, m);
        node = p;
        p = up;
    }
}

/// From node x, whose box and meta an earlier kernel wrote, upwards (climb).
__device__ void climb_from(uint32_t x, uint32_t n, const uint32_t* __restrict__ parent, uint2* children, AABB* boxes,
                           NodeMeta* meta, uint32_t* __restrict__ visits, const LeafRule& rule) {
    climb(x, boxes[x], meta[x], n, parent, children, boxes, meta, visits, rule);
}

/// From each leaf upwards (climb).
__global__ void fit_boxes(uint32_t n, const uint32_t* __restrict__ parent, uint2* children, AABB* boxes, NodeMeta* meta,
                          uint32_t* __restrict__ visits, LeafRule rule) {
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k < n) climb_from(k, n, parent, children, boxes, meta, visits, rule);
}

/// Thread s makes leaf s (triangle sorted_ids[s]) and climbs a hierarchy whose links and parents
/// are made.
__global__ void leaves_and_climb(uint32_t n, const uint32_t* __restrict__ sorted_ids,
                                 const AABB* __restrict__ tri_boxes, const uint32_t* __restrict__ parent,
                                 uint2* children, AABB* boxes, NodeMeta* meta, uint32_t* __restrict__ visits,
                                 LeafRule rule) {
    wait_for_previous();
    const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= n) return;
    NodeMeta m;
    const AABB box = make_leaf(s, sorted_ids, tri_boxes, boxes, meta, rule, m);
    climb(s, box, m, n, parent, children, boxes, meta, visits, rule, MadeLeaves{sorted_ids, tri_boxes, rule});
}

// --- PLOC (Meister & Bittner 2018): rounds over the whole cluster list, as
// accel::ploc_reference makes them (bit for bit: the same areas, ties and node numbers).

/// PLOC's nearest neighbour of cluster i of m within `radius` places: the smallest merged box's
/// half area, on equal areas the lower place (so the globally closest pair is always mutual).
/// box(j) gives cluster j's box.
template <typename BoxOf>
__device__ uint32_t ploc_nearest(uint32_t i, uint32_t m, int radius, BoxOf&& box) {
    const AABB b = box(i);
    const uint32_t lo = i > uint32_t(radius) ? i - uint32_t(radius) : 0;
    const uint32_t hi = min(i + uint32_t(radius), m - 1);
    float best = __int_as_float(0x7f800000);  // +inf
    uint32_t best_j = i;
    for (uint32_t j = lo; j <= hi; ++j) {
        if (j == i) continue;
        const float a = merge(b, box(j)).half_area();
        if (a < best) {
            best = a;
            best_j = j;
        }
    }
    return best_j;
}

/// The nearest neighbour of each of the m clusters (ploc_nearest). The block's clusters and the
/// radius to each side are read once into shared memory.
constexpr int kPlocMaxRadius = 16;
__global__ void __launch_bounds__(kBlock) ploc_neighbours(uint32_t m, int radius, const uint32_t* __restrict__ clusters,
                                                          const AABB* __restrict__ boxes, uint32_t* __restrict__ nn) {
    __shared__ AABB tile[kBlock + 2 * kPlocMaxRadius];
    const int64_t first = int64_t(blockIdx.x) * kBlock - radius;
    for (int k = threadIdx.x; k < kBlock + 2 * radius; k += kBlock) {
        const int64_t at = first + k;
        if (at >= 0 && at < int64_t(m)) tile[k] = boxes[clusters[at]];
    }
    __syncthreads();
    const uint32_t i = blockIdx.x * kBlock + threadIdx.x;
    if (i >= m) return;
    nn[i] = ploc_nearest(i, m, radius, [&](uint32_t j) { return tile[int64_t(j) - first]; });
}

/// Per cluster, packed for one scan: the low word 1 if it stays in the list (not merged, or the
/// lower of a mutual pair, which makes the node), the high word 1 if it makes a node.
__global__ void ploc_flags(uint32_t m, const uint32_t* __restrict__ nn, unsigned long long* __restrict__ flags) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= m) return;
    const uint32_t j = nn[i];
    const bool mutual = nn[j] == i;
    const unsigned long long makes = mutual && i < j, stays = !mutual || i < j;
    flags[i] = makes << 32 | stays;
}

/// Makes the round's nodes (numbered from `base` by the scan of the makers) and compacts the
/// list into `out`; the last thread stores the next round's base and list length in
/// `words[1]` and `words[3]`.
__global__ void ploc_merge_round(uint32_t m, uint32_t base, const uint32_t* __restrict__ clusters,
                                 const uint32_t* __restrict__ nn, const unsigned long long* __restrict__ flags,
                                 const unsigned long long* __restrict__ scan, uint32_t* __restrict__ out, AABB* boxes,
                                 uint2* children, NodeMeta* meta, uint32_t* words, LeafRule rule) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= m) return;
    const unsigned long long f = flags[i], before = scan[i];
    if (f & 0xffffffffull) {
        uint32_t id = clusters[i];
        if (f >> 32) {
            const uint32_t other = clusters[nn[i]];
            const uint32_t node = base + uint32_t(before >> 32);
            make_node(node, id, other, merge(boxes[id], boxes[other]), boxes, children, meta, rule);
            id = node;
        }
        out[uint32_t(before)] = id;
    }
    if (i == m - 1) {
        const unsigned long long total = before + f;
        words[3] = uint32_t(total);
        words[1] = base + uint32_t(total >> 32);
    }
}

/// PLOC's last rounds in one block: from at most kPlocTail clusters down to the root, the same
/// rounds as ploc_neighbours, ploc_flags and ploc_merge_round (the same node numbers), with the
/// list in shared memory and no round trips to the host.
constexpr uint32_t kPlocTail = 1024;
__global__ void __launch_bounds__(kPlocTail)
    ploc_tail(uint32_t m, uint32_t base, int radius, const uint32_t* __restrict__ list, AABB* boxes, uint2* children,
              NodeMeta* meta, uint32_t* root, LeafRule rule) {
    using Scan = cub::BlockScan<uint32_t, kPlocTail>;
    __shared__ typename Scan::TempStorage scan_storage;
    __shared__ uint32_t ids[kPlocTail], nn[kPlocTail];
    __shared__ AABB bx[kPlocTail];
    __shared__ uint32_t totals;
    const uint32_t i = threadIdx.x;
    if (i < m) {
        ids[i] = list[i];
        bx[i] = boxes[ids[i]];
    }
    __syncthreads();
    while (m > 1) {
        if (i < m) nn[i] = ploc_nearest(i, m, radius, [&](uint32_t j) { return bx[j]; });
        __syncthreads();
        const uint32_t j = i < m ? nn[i] : i;
        const bool mutual = i < m && nn[j] == i;
        const uint32_t makes = mutual && i < j, stays = i < m && (!mutual || i < j);
        uint32_t before, total;
        Scan(scan_storage).ExclusiveSum(makes << 16 | stays, before, total);  // both at most 1024
        uint32_t id = i < m ? ids[i] : 0;
        AABB box = i < m ? bx[i] : AABB::empty();
        if (makes) {
            const uint32_t node = base + (before >> 16);
            box = merge(box, bx[j]);
            make_node(node, id, ids[j], box, boxes, children, meta, rule);
            id = node;
        }
        if (i == 0) totals = total;
        __syncthreads();  // every cluster read before the list is rewritten
        if (stays) {
            ids[before & 0xffff] = id;
            bx[before & 0xffff] = box;
        }
        __syncthreads();
        m = totals & 0xffff;
        base += totals >> 16;
    }
    if (i == 0) *root = ids[0];
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
            // Join the neighbour whose boundary keys differ less (Apetrei 2014); the first of
            // two siblings to arrive stops, the second takes the parent.
            int32_t previous;
            if (accel::morton::radix_parent(keys, n, left, right).left_child) {
                split = right + 1;  // the parent's right child's first key
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

// --- Parallel reinsertion (Meister & Bittner 2018) between the hierarchy and the layout. Each
// pass, every node of the tree (its leaves, as the SAH chose them, and the interior nodes above
// them) searches for the node X whose sibling it should become: the most interior area saved,
// as accel::ReinsertionOptimizer counts it, with the boxes as they are. Moves that change the
// same nodes' links are resolved by priority (the larger gain wins), the winners move at once,
// and boxes and leaf choices are fitted again bottom-up from the tree's leaves.

using accel::SearchNode;
static_assert(accel::kReinsertNone == kInvalid, "one word for no node");

using accel::kFixed;
using accel::kInsideLeaf;
using accel::kInterior;
using accel::kLeaf;
using Role = accel::ReinsertRole;

__device__ SearchNode load_search_node(const SearchNode* n) {
    const uint4 a = __ldg(reinterpret_cast<const uint4*>(n)), b = __ldg(reinterpret_cast<const uint4*>(n) + 1);
    return {__uint_as_float(a.x), __uint_as_float(a.y), __uint_as_float(a.z), a.w,
            __uint_as_float(b.x), __uint_as_float(b.y), __uint_as_float(b.z), b.w};
}

/// Each node's role, and for the nodes of the tree (not inside a leaf) the search's copy.
__global__ void reinsert_roles(uint32_t total, uint32_t max_leaf, const uint32_t* __restrict__ parent,
                               const uint2* __restrict__ children, const AABB* __restrict__ boxes,
                               const NodeMeta* __restrict__ meta, uint8_t* __restrict__ role,
                               SearchNode* __restrict__ search) {
    const uint32_t x = blockIdx.x * blockDim.x + threadIdx.x;
    if (x >= total) return;
    const Role r = accel::reinsertion_role(
        x, max_leaf, [&](uint32_t y) { return parent[y]; },
        [&](uint32_t y) {
            const NodeMeta m = meta[y];
            return accel::ReinsertMeta{m.count, m.leaf()};
        });
    role[x] = r;
    if (r == kInsideLeaf) return;
    const AABB b = boxes[x];
    const uint2 c = r == kLeaf ? make_uint2(kInvalid, kInvalid) : children[x];
    search[x] = {b.lo.x, b.lo.y, b.lo.z, c.x, b.hi.x, b.hi.y, b.hi.z, c.y};
}

__device__ uint32_t other_child(const uint2& c, uint32_t x) { return c.x == x ? c.y : c.x; }

/// The nodes a pass can move (interior nodes and leaves of the tree, not the root): the pass's
/// kernels run over their list, not over every node, most of which lie inside leaves.
struct Movable {
    const uint8_t* role;
    __device__ bool operator()(uint32_t x) const { return role[x] >= kInterior; }
};

/// Calls f(x) for every node x on a pass's list (grid-stride: its length is on the device).
template <typename F>
__device__ void for_each_listed(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count, F&& f) {
    const uint32_t m = *count;
    for (uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < m; k += gridDim.x * blockDim.x) f(list[k]);
}

/// The best move of node `node` (accel::reinsertion_search) to gain, to and top; none for the
/// root, its children and the nodes inside leaves.
__device__ void reinsert_search_node(uint32_t node, const uint8_t* __restrict__ role,
                                     const uint32_t* __restrict__ parent, const SearchNode* __restrict__ search,
                                     float* __restrict__ gain, uint32_t* __restrict__ to, uint32_t* __restrict__ top) {
    accel::ReinsertMove best;
    const Role r = Role(role[node]);
    const uint32_t p = parent[node];
    // The root and its children stay (kFixed), and so do leaves among them (p or its parent is
    // the root).
    if ((r == kInterior || r == kLeaf) && p != kInvalid && parent[p] != kInvalid) {
        best = accel::reinsertion_search(
            node, p, [&](uint32_t x) { return load_search_node(search + x); }, [&](uint32_t x) { return parent[x]; });
    }
    gain[node] = best.gain;
    to[node] = best.to;
    top[node] = best.top;
}

__global__ void reinsert_search(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count,
                                const uint8_t* __restrict__ role, const uint32_t* __restrict__ parent,
                                const SearchNode* __restrict__ search, float* __restrict__ gain,
                                uint32_t* __restrict__ to, uint32_t* __restrict__ top) {
    for_each_listed(list, count,
                    [&](uint32_t node) { reinsert_search_node(node, role, parent, search, gain, to, top); });
}

/// Calls f on every node whose links candidate `node`'s move to X = `to` changes: the node, its
/// parent, sibling and grandparent, X and X's parent.
template <typename F>
__device__ void each_touched(uint32_t node, uint32_t to, const uint32_t* parent, const uint2* children, F&& f) {
    const uint32_t p = parent[node];
    f(node);
    f(p);
    f(other_child(children[p], node));
    f(parent[p]);
    f(to);
    f(parent[to]);
}

__device__ unsigned long long reinsert_priority(float gain, uint32_t i) {
    return static_cast<unsigned long long>(__float_as_uint(gain)) << 32 | (0xffffffffu - i);
}

__global__ void reinsert_lock(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count,
                              const float* __restrict__ gain, const uint32_t* __restrict__ to,
                              const uint32_t* __restrict__ parent, const uint2* __restrict__ children,
                              unsigned long long* locks) {
    for_each_listed(list, count, [&](uint32_t i) {
        if (to[i] == kInvalid) return;
        const unsigned long long key = reinsert_priority(gain[i], i);
        each_touched(i, to[i], parent, children, [&](uint32_t y) { atomicMax(locks + y, key); });
    });
}

/// A move that holds every node it touches goes ahead and marks its node as moving; the others
/// are dropped (to = kInvalid).
__global__ void reinsert_claim(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count,
                               const float* __restrict__ gain, uint32_t* __restrict__ to,
                               const uint32_t* __restrict__ parent, const uint2* __restrict__ children,
                               const unsigned long long* __restrict__ locks, uint8_t* __restrict__ moving) {
    for_each_listed(list, count, [&](uint32_t i) {
        if (to[i] == kInvalid) return;
        const unsigned long long key = reinsert_priority(gain[i], i);
        bool mine = true;
        each_touched(i, to[i], parent, children, [&](uint32_t y) { mine &= locks[y] == key; });
        if (mine)
            moving[i] = 1;
        else
            to[i] = kInvalid;
    });
}

/// Drops a claimed move whose X lies below another claimed move's node (on X's path up to `top`,
/// the common ancestor): that node could carry X into this move's own subtree, a cycle.
__global__ void reinsert_uncross(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count,
                                 uint32_t* __restrict__ to, const uint32_t* __restrict__ top,
                                 const uint32_t* __restrict__ parent, const uint8_t* __restrict__ moving) {
    for_each_listed(list, count, [&](uint32_t i) {
        if (to[i] == kInvalid) return;
        for (uint32_t y = to[i]; y != top[i];) {
            y = parent[y];
            if (moving[y]) {
                to[i] = kInvalid;
                return;
            }
        }
    });
}

__device__ void replace_child(uint2* children, uint32_t at, uint32_t old_child, uint32_t new_child) {
    uint2 c = children[at];
    if (c.x == old_child)
        c.x = new_child;
    else
        c.y = new_child;
    children[at] = c;
}

/// The claimed moves: the node's parent p leaves (its sibling takes its place) and comes back
/// over X and the node, in X's place. Moves that were claimed touch disjoint nodes.
__global__ void reinsert_apply(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count,
                               const uint32_t* __restrict__ to, uint32_t* parent, uint2* children) {
    for_each_listed(list, count, [&](uint32_t node) {
        if (to[node] == kInvalid) return;
        const uint32_t x = to[node];
        const uint32_t p = parent[node], g = parent[p];
        const uint32_t s = other_child(children[p], node);
        replace_child(children, g, p, s);
        parent[s] = g;
        const uint32_t q = parent[x];
        replace_child(children, q, x, p);
        children[p] = make_uint2(x, node);
        parent[x] = p;
        parent[p] = q;
    });
}

/// Copies the root's meta (the root's id in *root) to *out.
__global__ void root_meta(const uint32_t* root, const NodeMeta* meta, NodeMeta* out) { *out = meta[*root]; }

/// Zeroes the root's triangle count before a refit, which counts them again only if every leaf
/// reaches the root.
__global__ void clear_root_count(const uint32_t* root, NodeMeta* meta) {
    if (!meta[*root].leaf()) meta[*root].count = 0;  // a root leaf: nothing moves
}

/// fit_boxes from the tree's leaves (their subtrees are as they were) after a pass.
__global__ void refit_from_leaves(const uint32_t* __restrict__ list, const uint32_t* __restrict__ count, uint32_t n,
                                  const uint8_t* __restrict__ role, const uint32_t* __restrict__ parent,
                                  uint2* children, AABB* boxes, NodeMeta* meta, uint32_t* __restrict__ visits,
                                  LeafRule rule) {
    for_each_listed(list, count, [&](uint32_t x) {
        if (role[x] == kLeaf) climb_from(x, n, parent, children, boxes, meta, visits, rule);
    });
}

// --- The BVH2 layout, flat: one scan over every node places them all.

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

/// The Woop map of every triangle in leaf order (gathered: writing each map to its place from the
/// mesh's order was slower, experiments/NOTES.md).
__global__ void woop_maps(uint32_t n, const uint32_t* __restrict__ tri_ids, const Vec3* __restrict__ verts,
                          const uint32_t* __restrict__ idx, WoopTriangle* __restrict__ tris,
                          uint32_t* __restrict__ copy_ids = nullptr) {
    wait_for_previous();
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= n) return;
    const uint32_t t = tri_ids[k];
    if (copy_ids) copy_ids[k] = t;  // the layout's ids, when they are the sorted ones
    WoopTriangle w;
    accel::woop_map(verts[idx[3 * t]], verts[idx[3 * t + 1]], verts[idx[3 * t + 2]], w);
    tris[k] = w;
}

// --- Binned SAH, top down (Wald 2007), split as BinnedSahBuilder splits: 32 centroid bins per
// axis, the same bin mapping, sweep and ties, and an exact sweep over sorted centroids at <= 16
// triangles (its sweep_threshold). Nodes split down to single triangles; the leaves are then
// chosen bottom-up by SAH, like the other GPU builders'. Interior node n + m - 1 splits its range
// of the order at m (a range's split is unique), so a subtree is a range of final_ids, as the
// LBVH's are of the sorted keys.
// Large tasks (more than kSahWarpTask triangles) are split level by level, every kernel over all
// of a level's tasks: their triangles binned in chunks (a block each, bins in shared memory, then
// added to the task's bins, the chunk's counts per bin kept), one warp of the task's last chunk to
// finish sweeps, and the chunks partition stably (each chunk's lefts from those counts, each
// chunk after its task's earlier chunks' lefts) into the other order buffer. Each level's grids
// are bounded from the level before; the host reads the counts while the device runs the next
// level. Then one warp per small task builds its subtree in shared memory down to tiny tasks (at
// most kSahSweep triangles), which one thread each sweeps exactly. The tiers' costs on furball:
// experiments/NOTES.md, session 33.

constexpr int kSahBins = 32;  ///< a warp sweeps one axis, a lane per bin
static_assert(kSahBins == int(kWarp), "one lane per bin");
constexpr uint32_t kSahWarpTask = 512;                  ///< tasks of at most this many: one warp
constexpr uint32_t kSahPerThread = 8;                   ///< a large task's triangles per thread
constexpr uint32_t kSahChunk = kSahPerThread * kBlock;  ///< and per block
constexpr uint32_t kSahSweep = 16;                      ///< exact sweep at or below (BinnedSahBuilder's)
constexpr int kSahWarps = 4;                            ///< warps per block of the small tasks
constexpr int kSahStack = 12;                           ///< > log2(kSahWarpTask): the smaller child first
/// Tasks of at most this many chunks: the scatter sums the lefts of a chunk's predecessors from
/// their bin counts; larger ones' lefts come from sah_lefts (a launch a level, as long as a task
/// is this large).
constexpr uint32_t kSahSumChunks = 64;

struct SahTask {
    uint32_t b, e;  ///< positions in the order buffers
    uint32_t slot;  ///< parent << 1 | side, or kInvalid for the root
    uint32_t buf;   ///< the order buffer holding the range
    AABB cb;        ///< its centroids' bounds (added to by the parent's partition)
};

struct SahSplit {
    int axis;  ///< -1: every centroid equal, split at the range's middle
    int bin;   ///< bins <= bin go left
    uint32_t m;
    uint32_t pad;
    AABB* child_cb[2];  ///< the children's tasks' centroid bounds; null for a one-triangle child
};

struct alignas(16) SahBin {  // 16-byte aligned: sah_start clears it in two vector stores
    float lo[3], hi[3];
    uint32_t count, pad;

    __device__ static SahBin empty() { return {{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}, 0, 0}; }
};

struct SahOrder {
    uint32_t* buf[2];
};

/// BinMapping on the device: the same float operations, so the same bins.
struct SahMap {
    Vec3 origin, scale;
    __device__ explicit SahMap(const AABB& cb) : origin(cb.lo) {
        const Vec3 e = cb.extent();
        const float k = float(kSahBins) * (1.0f - 1e-6f);
        scale = {e.x > 0.0f ? k / e.x : 0.0f, e.y > 0.0f ? k / e.y : 0.0f, e.z > 0.0f ? k / e.z : 0.0f};
    }
    __device__ int bin(float c, int axis) const {
        return min(max(int((c - origin[axis]) * scale[axis]), 0), kSahBins - 1);
    }
};

__device__ void set_link(uint2* children, uint32_t* root, uint32_t slot, uint32_t node) {
    if (slot == kInvalid)
        *root = node;
    else
        reinterpret_cast<uint32_t*>(children + (slot >> 1))[slot & 1] = node;
}

__device__ AABB shfl_box(const AABB& b, int src) {
    return {{__shfl_sync(~0u, b.lo.x, src), __shfl_sync(~0u, b.lo.y, src), __shfl_sync(~0u, b.lo.z, src)},
            {__shfl_sync(~0u, b.hi.x, src), __shfl_sync(~0u, b.hi.y, src), __shfl_sync(~0u, b.hi.z, src)}};
}

__device__ AABB shfl_up_box(const AABB& b, unsigned d) {
    return {{__shfl_up_sync(~0u, b.lo.x, d), __shfl_up_sync(~0u, b.lo.y, d), __shfl_up_sync(~0u, b.lo.z, d)},
            {__shfl_up_sync(~0u, b.hi.x, d), __shfl_up_sync(~0u, b.hi.y, d), __shfl_up_sync(~0u, b.hi.z, d)}};
}

__device__ AABB shfl_down_box(const AABB& b, unsigned d) {
    return {{__shfl_down_sync(~0u, b.lo.x, d), __shfl_down_sync(~0u, b.lo.y, d), __shfl_down_sync(~0u, b.lo.z, d)},
            {__shfl_down_sync(~0u, b.hi.x, d), __shfl_down_sync(~0u, b.hi.y, d), __shfl_down_sync(~0u, b.hi.z, d)}};
}

/// The box over every lane's box.
__device__ AABB warp_union(AABB b) {
    for (int d = 16; d > 0; d >>= 1) b = merge(b, shfl_box(b, int((threadIdx.x & 31) ^ d)));
    return b;
}

/// The warp's lowest weight and, among equal ones, the lowest lane's (every lane gets both).
__device__ void warp_argmin(float& w, int& at) {
    for (int d = 16; d > 0; d >>= 1) {
        const float ow = __shfl_xor_sync(~0u, w, d);
        const int oa = __shfl_xor_sync(~0u, at, d);
        if (ow < w || (ow == w && oa < at)) {
            w = ow;
            at = oa;
        }
    }
}

/// The best split over three axes' bins (lane i holds bin i of each; bin_of(axis, box, count)
/// reads the lane's), as best_bin_split finds it: between bins i and i + 1 of a splittable axis,
/// both sides non-empty, by A_L N_L + A_R N_R; on equal weights the first axis, then the lowest i.
/// kTogether axes' scans run side by side (3: their shuffles are independent; 1: an axis at a
/// time, fewer registers). Every lane gets the winner; axis -1 when nothing separates the
/// triangles.
struct WarpSplit {
    int axis;
    int bin;
    uint32_t left;  ///< triangles in bins <= bin
};

template <int kTogether, typename BinOf>
__device__ WarpSplit sweep_bins_warp(BinOf bin_of, const bool (&splittable)[3]) {
    static_assert(3 % kTogether == 0, "the axes in equal groups");
    const unsigned lane = threadIdx.x & 31;
    float w = __int_as_float(0x7f800000);
    int at = 3 * 32;  // axis * 32 + bin
    uint32_t left = 0;
    for (int a0 = 0; a0 < 3; a0 += kTogether) {
        AABB l[kTogether], r[kTogether];
        uint32_t nl[kTogether], nr[kTogether];
        for (int j = 0; j < kTogether; ++j) {
            bin_of(a0 + j, l[j], nl[j]);
            r[j] = l[j];
            nr[j] = nl[j];
        }
        for (unsigned d = 1; d < 32; d <<= 1) {
            for (int j = 0; j < kTogether; ++j) {
                const AABB ol = shfl_up_box(l[j], d), orr = shfl_down_box(r[j], d);
                const uint32_t cl = __shfl_up_sync(~0u, nl[j], d), cr = __shfl_down_sync(~0u, nr[j], d);
                if (lane >= d) {
                    l[j] = merge(l[j], ol);
                    nl[j] += cl;
                }
                if (lane + d < 32) {
                    r[j] = merge(r[j], orr);
                    nr[j] += cr;
                }
            }
        }
        for (int j = 0; j < kTogether; ++j) {
            const int a = a0 + j;
            const AABB right = shfl_down_box(r[j], 1);  // bins lane + 1 and up
            const uint32_t n_right = __shfl_down_sync(~0u, nr[j], 1);
            if (!splittable[a] || lane == 31 || nl[j] == 0 || n_right == 0) continue;
            const float wa = l[j].half_area() * float(nl[j]) + right.half_area() * float(n_right);
            if (wa < w) {  // strict: the first axis on ties
                w = wa;
                at = a * 32 + int(lane);
                left = nl[j];
            }
        }
    }
    warp_argmin(w, at);
    if (!(w < __int_as_float(0x7f800000))) return {-1, -1, 0};
    return {at / 32, at % 32, __shfl_sync(~0u, left, at % 32)};
}

/// The root task (or, for a small mesh, the first small task), and the first bin_count bins
/// empty (those of the most large tasks a level can have), written as 16-byte halves.
__global__ void sah_start(uint32_t n, const AABB* __restrict__ bounds, SahTask* large, SahTask* small,
                          uint32_t* __restrict__ first, uint32_t* __restrict__ chunk_task, uint32_t* __restrict__ words,
                          SahBin* bins, uint32_t bin_count) {
    wait_for_previous();
    static_assert(sizeof(SahBin) == 2 * sizeof(uint4), "a bin is two 16-byte halves");
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const SahBin e = SahBin::empty();
    const uint4 half[2] = {reinterpret_cast<const uint4*>(&e)[0], reinterpret_cast<const uint4*>(&e)[1]};
    uint4* out = reinterpret_cast<uint4*>(bins);
    for (uint32_t k = i; k < 2 * bin_count; k += gridDim.x * blockDim.x) out[k] = half[k & 1];
    if (n > kSahWarpTask)  // the root's chunks
        for (uint32_t k = i; k < (n + kSahChunk - 1) / kSahChunk; k += gridDim.x * blockDim.x) chunk_task[k] = 0;
    if (i != 0) return;
    const SahTask root{0, n, kInvalid, 0, *bounds};
    if (n > kSahWarpTask) {
        large[0] = root;
        first[0] = 0;
        first[1] = (n + kSahChunk - 1) / kSahChunk;
        words[4] = 1;
    } else {
        small[0] = root;
        words[1] = 1;
    }
}

/// Chunk k of a level's large tasks (by default the block's own): its task (chunk_task, written
/// with first by sah_chunks) and range.
struct SahChunk {
    uint32_t task, b, e;
    __device__ SahChunk(const SahTask* tasks, const uint32_t* first, const uint32_t* chunk_task,
                        uint32_t k = blockIdx.x) {
        task = chunk_task[k];
        const SahTask& t = tasks[task];
        b = t.b + (k - first[task]) * kSahChunk;
        e = min(b + kSahChunk, t.e);
    }
};

/// A float's bits as an unsigned that orders as the float does (-0 made +0 first), so that
/// integer minima and maxima (atomics, warp reductions) are the floats' own.
__device__ uint32_t ordered_bits(float v) {
    const uint32_t u = __float_as_uint(v + 0.0f);
    return u & 0x80000000u ? ~u : u | 0x80000000u;
}

__device__ float from_ordered_bits(uint32_t u) { return __uint_as_float(u & 0x80000000u ? u & 0x7fffffffu : ~u); }

/// Appends a child task (two or more triangles) to `list`; returns its centroid bounds to add to.
__device__ AABB* sah_push(SahTask* list, uint32_t* count, uint32_t b, uint32_t e, uint32_t slot, uint32_t buf) {
    const uint32_t k = atomicAdd(count, 1u);
    list[k] = {b, e, slot, buf, AABB::empty()};
    return &list[k].cb;
}

/// Where a large task's split goes: the level's bins, splits and done counters, the lists (and
/// counters) of the next level's large tasks and of the small tasks, and the hierarchy's links.
struct SahSplitOut {
    SahBin* bins;
    SahSplit* splits;
    uint32_t* done;  ///< per task: its chunks binned (the last to finish splits it, and zeroes this)
    SahTask* next;
    uint32_t* next_count;
    SahTask* small;
    uint32_t* small_count;
    uint32_t n;
    uint2* children;
    uint32_t* root;
};

/// One warp: task `task`'s best split over its bins, which every chunk's block has added to (read
/// from L2; the bins made empty again for the next level), the node linked to its parent, the
/// children queued (large, small) or linked (leaves).
__device__ void sah_split_task(const SahTask* __restrict__ tasks, uint32_t task, const SahSplitOut& o) {
    const uint32_t lane = threadIdx.x & 31;
    const SahTask t = tasks[task];
    const SahMap map(t.cb);
    AABB box[3];
    uint32_t num[3];
    bool splittable[3];
    for (int a = 0; a < 3; ++a) {
        SahBin* g = o.bins + (size_t(task) * 3 + a) * kSahBins + lane;
        box[a] = {{__ldcg(&g->lo[0]), __ldcg(&g->lo[1]), __ldcg(&g->lo[2])},
                  {__ldcg(&g->hi[0]), __ldcg(&g->hi[1]), __ldcg(&g->hi[2])}};
        num[a] = __ldcg(&g->count);
        *g = SahBin::empty();
        splittable[a] = map.scale[a] > 0.0f;
    }
    const WarpSplit best = sweep_bins_warp<3>(
        [&](int a, AABB& bx, uint32_t& c) {
            bx = box[a];
            c = num[a];
        },
        splittable);
    const int axis = best.axis, bin = best.bin;
    const uint32_t left = best.left;
    if (lane != 0) return;
    const uint32_t m = axis >= 0 ? t.b + left : t.b + (t.e - t.b) / 2;
    const uint32_t id = o.n + m - 1;
    set_link(o.children, o.root, t.slot, id);
    SahSplit s{axis, bin, m, 0, {nullptr, nullptr}};
    const uint32_t range[3] = {t.b, m, t.e};
    for (int side = 0; side < 2; ++side) {
        const uint32_t b = range[side], e = range[side + 1], slot = id << 1 | uint32_t(side);
        if (e - b == 1)
            set_link(o.children, o.root, slot, b);
        else if (e - b > kSahWarpTask)
            s.child_cb[side] = sah_push(o.next, o.next_count, b, e, slot, 1 - t.buf);
        else
            s.child_cb[side] = sah_push(o.small, o.small_count, b, e, slot, 1 - t.buf);
    }
    o.splits[task] = s;
}

/// Bins each chunk's triangles in shared memory, a set of bins per warp (fewer threads meet on an
/// address), runs of neighbours in one bin merged first, then adds them to its task's bins and
/// keeps the chunk's counts per bin (its lefts, once the split is known). The last of a task's
/// chunks to finish splits the task.
constexpr int kBinSets = kBlock / int(kWarp);

__global__ void __launch_bounds__(kBlock)
    sah_bin(const SahTask* __restrict__ tasks, const uint32_t* __restrict__ task_count,
            const uint32_t* __restrict__ first, const uint32_t* __restrict__ chunk_task, SahOrder order,
            const AABB* __restrict__ tri_boxes, uint32_t* __restrict__ chunk_counts, SahSplitOut out) {
    wait_for_previous();
    SahBin* bins = out.bins;
    const uint32_t count = *task_count;
    if (blockIdx.x >= first[count]) return;  // a grid for the most chunks the level can have
    __shared__ uint32_t lo[kBinSets][3 * kSahBins][3], hi[kBinSets][3 * kSahBins][3];
    __shared__ uint32_t num[kBinSets][3 * kSahBins];
    for (uint32_t k = threadIdx.x; k < kBinSets * 3 * kSahBins; k += blockDim.x) {
        for (int j = 0; j < 3; ++j) {
            lo[0][k][j] = ~0u;  // the sets are contiguous: k runs over all of them
            hi[0][k][j] = 0u;
        }
        num[0][k] = 0;
    }
    const SahChunk c(tasks, first, chunk_task);
    const SahTask& t = tasks[c.task];
    const SahMap map(t.cb);
    const uint32_t* in = order.buf[t.buf];
    const uint32_t set = threadIdx.x / kWarp;
    __syncthreads();
    // Each thread takes kSahPerThread neighbours in the order, which often share a bin (the
    // order keeps the mesh's own within a node): a run in one bin is merged in registers and added
    // once.
    struct Run {
        int bin;
        uint32_t count;
        uint32_t c[6];
    };
    Run run[3];
    auto flush = [&](const Run& x, int a) {
        if (!x.count) return;
        const int k = a * kSahBins + x.bin;
        for (int j = 0; j < 3; ++j) {
            atomicMin(&lo[set][k][j], x.c[j]);
            atomicMax(&hi[set][k][j], x.c[3 + j]);
        }
        atomicAdd(&num[set][k], x.count);
    };
    for (int a = 0; a < 3; ++a) run[a].count = 0;
    // The thread's triangles' boxes loaded first, all at once: one load latency, not one a triangle.
    const uint32_t i0 = c.b + threadIdx.x * kSahPerThread;
    uint32_t id[kSahPerThread];
    AABB boxes[kSahPerThread];
#pragma unroll
    for (uint32_t j = 0; j < kSahPerThread; ++j) id[j] = i0 + j < c.e ? in[i0 + j] : kInvalid;
#pragma unroll
    for (uint32_t j = 0; j < kSahPerThread; ++j)
        if (id[j] != kInvalid) boxes[j] = tri_boxes[id[j]];
#pragma unroll
    for (uint32_t j = 0; j < kSahPerThread; ++j) {
        if (id[j] == kInvalid) break;
        const AABB& box = boxes[j];
        const Vec3 ct = box.center();
        const uint32_t corner[6] = {ordered_bits(box.lo.x), ordered_bits(box.lo.y), ordered_bits(box.lo.z),
                                    ordered_bits(box.hi.x), ordered_bits(box.hi.y), ordered_bits(box.hi.z)};
        for (int a = 0; a < 3; ++a) {
            const int bin = map.bin(ct[a], a);
            Run& x = run[a];
            if (x.count && x.bin == bin) {
                for (int q = 0; q < 3; ++q) {
                    x.c[q] = min(x.c[q], corner[q]);
                    x.c[3 + q] = max(x.c[3 + q], corner[3 + q]);
                }
                ++x.count;
            } else {
                flush(x, a);
                x.bin = bin;
                x.count = 1;
                for (int q = 0; q < 6; ++q) x.c[q] = corner[q];
            }
        }
    }
    for (int a = 0; a < 3; ++a) flush(run[a], a);
    __syncthreads();
    for (uint32_t k = threadIdx.x; k < 3 * kSahBins; k += blockDim.x) {
        uint32_t l[3] = {~0u, ~0u, ~0u}, h[3] = {0u, 0u, 0u}, total = 0;
        for (int w = 0; w < kBinSets; ++w) {
            for (int j = 0; j < 3; ++j) {
                l[j] = min(l[j], lo[w][k][j]);
                h[j] = max(h[j], hi[w][k][j]);
            }
            total += num[w][k];
        }
        chunk_counts[size_t(blockIdx.x) * 3 * kSahBins + k] = total;
        if (!total) continue;
        SahBin* g = bins + size_t(c.task) * 3 * kSahBins + k;
        for (int j = 0; j < 3; ++j) {
            atomic_min(&g->lo[j], from_ordered_bits(l[j]));
            atomic_max(&g->hi[j], from_ordered_bits(h[j]));
        }
        atomicAdd(&g->count, total);
    }
    // The task's last chunk to finish splits it: each block's bin atomics made visible before its
    // count of the task's chunks goes up.
    __shared__ bool last;
    __threadfence();
    __syncthreads();
    if (threadIdx.x == 0) {
        const uint32_t chunks = first[c.task + 1] - first[c.task];
        last = atomicAdd(&out.done[c.task], 1u) == chunks - 1;
        if (last) out.done[c.task] = 0;  // for the next level's task c.task
    }
    __syncthreads();
    if (last && threadIdx.x < kWarp) {
        __threadfence();
        sah_split_task(tasks, c.task, out);
    }
}

/// Each chunk's count of triangles going left, from its counts per bin (one warp per chunk), for
/// the tasks of more than kSahSumChunks chunks.
__global__ void __launch_bounds__(kBlock)
    sah_lefts(const SahTask* __restrict__ tasks, const uint32_t* __restrict__ task_count,
              const uint32_t* __restrict__ first, const uint32_t* __restrict__ chunk_task,
              const SahSplit* __restrict__ splits, const uint32_t* __restrict__ chunk_counts,
              uint32_t* __restrict__ lefts) {
    wait_for_previous();
    const uint32_t chunk = (blockIdx.x * blockDim.x + threadIdx.x) / kWarp, lane = threadIdx.x & 31;
    const uint32_t count = *task_count;
    if (chunk >= first[count]) return;  // whole warps
    const SahChunk c(tasks, first, chunk_task, chunk);
    if (first[c.task + 1] - first[c.task] <= kSahSumChunks) return;
    const SahSplit s = splits[c.task];
    if (s.axis < 0) {  // by place
        if (lane == 0) lefts[chunk] = s.m > c.b ? min(s.m, c.e) - c.b : 0;
        return;
    }
    uint32_t k = lane <= uint32_t(s.bin) ? chunk_counts[(size_t(chunk) * 3 + s.axis) * kSahBins + lane] : 0;
    k = __reduce_add_sync(~0u, k);
    if (lane == 0) lefts[chunk] = k;
}

/// The stable partition of each chunk into the other order buffer (left side from the task's
/// first position, after the lefts of the task's chunks before it, which the block sums; right
/// side from m), the children's centroid bounds added to, and one-triangle children's triangles
/// written to final_ids. The block reads its chunk in kSahPerThread coalesced rounds; each
/// triangle's place among the lefts comes from the warps' ballots, counted per round and warp.
__global__ void __launch_bounds__(kBlock)
    sah_scatter(const SahTask* __restrict__ tasks, const uint32_t* __restrict__ task_count,
                const uint32_t* __restrict__ first, const uint32_t* __restrict__ chunk_task,
                const SahSplit* __restrict__ splits, SahOrder order, const Vec3* __restrict__ centres,
                const uint32_t* __restrict__ chunk_counts, const uint32_t* __restrict__ lefts,
                uint32_t* __restrict__ final_ids) {
    wait_for_previous();
    const uint32_t count = *task_count;
    if (blockIdx.x >= first[count]) return;  // a grid for the most chunks the level can have
    constexpr uint32_t kWarps = kBlock / kWarp;
    __shared__ uint32_t before[kSahPerThread][kWarps];  // lefts counted before each round and warp
    __shared__ uint32_t side_box[2][6];                 // the children's centroid bounds, ordered bits
    __shared__ uint32_t task_lefts[kWarps];             // per warp: lefts of the task's chunks before this one
    const SahChunk c(tasks, first, chunk_task);
    const SahTask& t = tasks[c.task];
    const SahSplit s = splits[c.task];
    const SahMap map(t.cb);
    const uint32_t* in = order.buf[t.buf];
    uint32_t* out = order.buf[1 - t.buf];
    const uint32_t lane = threadIdx.x & 31, warp = threadIdx.x / kWarp;
    const unsigned lt = (1u << lane) - 1;
    if (threadIdx.x < 12) side_box[threadIdx.x / 6][threadIdx.x % 6] = threadIdx.x % 6 < 3 ? ~0u : 0u;
    // Every round's ids, then their centres, loaded before the ballots: one load latency each.
    uint32_t ids[kSahPerThread];
    Vec3 centre[kSahPerThread];
    unsigned ballots[kSahPerThread];
#pragma unroll
    for (uint32_t r = 0; r < kSahPerThread; ++r) {
        const uint32_t i = c.b + r * kBlock + threadIdx.x;
        ids[r] = i < c.e ? in[i] : kInvalid;
    }
#pragma unroll
    for (uint32_t r = 0; r < kSahPerThread; ++r)
        if (ids[r] != kInvalid) centre[r] = centres[ids[r]];
#pragma unroll
    for (uint32_t r = 0; r < kSahPerThread; ++r) {
        const uint32_t i = c.b + r * kBlock + threadIdx.x;
        bool l = false;
        if (i < c.e) l = s.axis < 0 ? i < s.m : map.bin(centre[r][s.axis], s.axis) <= s.bin;
        ballots[r] = __ballot_sync(~0u, l);
        if (lane == 0) before[r][warp] = __popc(ballots[r]);
    }
    // The lefts of the task's chunks before this one: by place, the split's distance from the
    // task's start; else from sah_lefts, or for a task of at most kSahSumChunks chunks from their
    // counts of the bins <= s.bin (sah_bin's), a warp per chunk and a lane per bin.
    uint32_t part = 0;
    if (s.axis < 0) {
        part = threadIdx.x == 0 ? min(s.m, c.b) - t.b : 0;
    } else if (first[c.task + 1] - first[c.task] > kSahSumChunks) {
        for (uint32_t k = first[c.task] + threadIdx.x; k < blockIdx.x; k += kBlock) part += lefts[k];
    } else if (lane <= uint32_t(s.bin)) {
        const uint32_t* counts = chunk_counts + size_t(s.axis) * kSahBins + lane;
        for (uint32_t k = first[c.task] + warp; k < blockIdx.x; k += kWarps) part += counts[size_t(k) * 3 * kSahBins];
    }
    part = __reduce_add_sync(~0u, part);
    if (lane == 0) task_lefts[warp] = part;
    __syncthreads();
    if (threadIdx.x == 0) {  // exclusive scan over rounds, then warps
        uint32_t sum = 0;
        for (uint32_t w = 0; w < kWarps; ++w) sum += task_lefts[w];
        for (uint32_t r = 0; r < kSahPerThread; ++r)
            for (uint32_t w = 0; w < kWarps; ++w) {
                const uint32_t k = before[r][w];
                before[r][w] = sum;
                sum += k;
            }
    }
    __syncthreads();
    AABB side[2] = {AABB::empty(), AABB::empty()};
    for (uint32_t r = 0; r < kSahPerThread; ++r) {
        const uint32_t i = c.b + r * kBlock + threadIdx.x;
        if (i >= c.e) break;
        const bool is_left = (ballots[r] >> lane) & 1;
        const uint32_t l = before[r][warp] + __popc(ballots[r] & lt);  // lefts before i in its task
        const uint32_t at = is_left ? t.b + l : s.m + (i - t.b - l);
        out[at] = ids[r];
        if (!s.child_cb[is_left ? 0 : 1]) final_ids[at] = ids[r];
        const Vec3 c = centre[r];
        if (is_left)
            side[0].extend(c);
        else
            side[1].extend(c);
    }
    for (int j = 0; j < 2; ++j) {
        const uint32_t v[6] = {ordered_bits(side[j].lo.x), ordered_bits(side[j].lo.y), ordered_bits(side[j].lo.z),
                               ordered_bits(side[j].hi.x), ordered_bits(side[j].hi.y), ordered_bits(side[j].hi.z)};
        for (int q = 0; q < 6; ++q) {
            const uint32_t x = q < 3 ? __reduce_min_sync(~0u, v[q]) : __reduce_max_sync(~0u, v[q]);
            if (lane == 0) (q < 3 ? atomicMin(&side_box[j][q], x) : atomicMax(&side_box[j][q], x));
        }
    }
    __syncthreads();
    if (threadIdx.x < 2 && s.child_cb[threadIdx.x]) {
        const uint32_t* q = side_box[threadIdx.x];
        if (q[0] != ~0u)  // not empty
            atomic_merge(s.child_cb[threadIdx.x],
                         {{from_ordered_bits(q[0]), from_ordered_bits(q[1]), from_ordered_bits(q[2])},
                          {from_ordered_bits(q[3]), from_ordered_bits(q[4]), from_ordered_bits(q[5])}});
    }
}

/// The next level's chunks: each large task's first chunk (first[count] = the chunk count) and
/// each chunk's task, and for the host (mapped memory) the tasks, chunks and most chunks of one
/// task. One block.
__global__ void __launch_bounds__(1024)
    sah_chunks(const SahTask* __restrict__ tasks, const uint32_t* __restrict__ task_count, uint32_t* __restrict__ first,
               uint32_t* __restrict__ chunk_task, uint32_t* __restrict__ done_count, uint32_t* host) {
    wait_for_previous();
    using Scan = cub::BlockScan<uint32_t, 1024>;
    __shared__ typename Scan::TempStorage scratch;
    __shared__ uint32_t largest;
    if (threadIdx.x == 0) largest = 0;
    const uint32_t count = *task_count;
    uint32_t base = 0;
    for (uint32_t k0 = 0; k0 < count; k0 += 1024) {
        const uint32_t k = k0 + threadIdx.x;
        const uint32_t chunks = k < count ? (tasks[k].e - tasks[k].b + kSahChunk - 1) / kSahChunk : 0;
        uint32_t before, sum;
        Scan(scratch).ExclusiveSum(chunks, before, sum);
        if (k < count) {
            first[k] = base + before;
            for (uint32_t j = 0; j < chunks; ++j) chunk_task[base + before + j] = k;
        }
        if (chunks) atomicMax(&largest, chunks);
        base += sum;
        __syncthreads();
    }
    if (threadIdx.x == 0) {
        first[count] = base;
        *done_count = 0;  // this level's task counter: the next level's tasks' pushes start from 0
        host[0] = count;
        host[1] = base;
        host[2] = largest;
        __threadfence_system();
    }
}

/// One warp per small task: its subtree down to tiny tasks (at most kSahSweep triangles, left to
/// sah_tiny), the triangle ids in shared memory. Each node is split by 32 bins per axis, then the
/// smaller child goes on and the larger waits on a stack (so it stays short).
__global__ void __launch_bounds__(kSahWarps* kWarp)
    sah_small(const SahTask* __restrict__ tasks, uint32_t* words, SahOrder order, const AABB* __restrict__ tri_boxes,
              const Vec3* __restrict__ centres, uint32_t n, uint2* children, uint32_t* root,
              uint32_t* __restrict__ final_ids, uint3* __restrict__ tiny) {
    wait_for_previous();
    __shared__ uint32_t ids_of[kSahWarps][kSahWarpTask], tmp_of[kSahWarps][kSahWarpTask];
    __shared__ uint32_t lo_of[kSahWarps][3 * kSahBins][3], hi_of[kSahWarps][3 * kSahBins][3];  // ordered bits
    __shared__ uint32_t num_of[kSahWarps][3 * kSahBins];
    const uint32_t w = threadIdx.x / kWarp, lane = threadIdx.x & 31;
    uint32_t* ids = ids_of[w];
    uint32_t* tmp = tmp_of[w];
    uint32_t(*lo)[3] = lo_of[w];
    uint32_t(*hi)[3] = hi_of[w];
    uint32_t* num = num_of[w];
    const uint32_t count = words[1];
    const unsigned lt = (1u << lane) - 1;
    for (uint32_t task = blockIdx.x * kSahWarps + w; task < count; task += gridDim.x * kSahWarps) {
        const SahTask t = tasks[task];
        const uint32_t* in = order.buf[t.buf];
        for (uint32_t i = lane; i < t.e - t.b; i += kWarp) ids[i] = in[t.b + i];
        __syncwarp();
        uint3 stack[kSahStack];
        int sp = 0;
        uint32_t b = 0, e = t.e - t.b, slot = t.slot;
        for (;;) {
            const uint32_t size = e - b;
            if (size <= kSahSweep) {  // a tiny task for sah_tiny, its ids in final_ids
                for (uint32_t i = b + lane; i < e; i += kWarp) final_ids[t.b + i] = ids[i];
                if (lane == 0) {
                    if (size == 1)
                        set_link(children, root, slot, t.b + b);
                    else
                        tiny[atomicAdd(words + 3, 1u)] = make_uint3(t.b + b, t.b + e, slot);
                }
                if (sp == 0) break;
                const uint3 top = stack[--sp];
                b = top.x;
                e = top.y;
                slot = top.z;
                continue;
            }
            uint32_t m;  // the left child's size
            {
                // 32 bins per axis over the centroids' bounds, in shared memory.
                AABB cb = AABB::empty();
                for (uint32_t i = b + lane; i < e; i += kWarp) cb.extend(centres[ids[i]]);
                cb = warp_union(cb);
                const SahMap map(cb);
                for (uint32_t k = lane; k < 3 * kSahBins; k += kWarp) {
                    for (int j = 0; j < 3; ++j) {
                        lo[k][j] = ordered_bits(FLT_MAX);  // empty: read back as AABB::empty()
                        hi[k][j] = ordered_bits(-FLT_MAX);
                    }
                    num[k] = 0;
                }
                __syncwarp();
                for (uint32_t i = b + lane; i < e; i += kWarp) {
                    const AABB box = tri_boxes[ids[i]];
                    const Vec3 ct = box.center();
                    for (int a = 0; a < 3; ++a) {
                        const int k = a * kSahBins + map.bin(ct[a], a);
                        atomicMin(&lo[k][0], ordered_bits(box.lo.x));
                        atomicMin(&lo[k][1], ordered_bits(box.lo.y));
                        atomicMin(&lo[k][2], ordered_bits(box.lo.z));
                        atomicMax(&hi[k][0], ordered_bits(box.hi.x));
                        atomicMax(&hi[k][1], ordered_bits(box.hi.y));
                        atomicMax(&hi[k][2], ordered_bits(box.hi.z));
                        atomicAdd(&num[k], 1u);
                    }
                }
                __syncwarp();
                const bool splittable[3] = {map.scale[0] > 0.0f, map.scale[1] > 0.0f, map.scale[2] > 0.0f};
                const WarpSplit best = sweep_bins_warp<1>(
                    [&](int a, AABB& bx, uint32_t& c) {
                        const int k = a * kSahBins + int(lane);
                        bx = {{from_ordered_bits(lo[k][0]), from_ordered_bits(lo[k][1]), from_ordered_bits(lo[k][2])},
                              {from_ordered_bits(hi[k][0]), from_ordered_bits(hi[k][1]), from_ordered_bits(hi[k][2])}};
                        c = num[k];
                    },
                    splittable);
                const int axis = best.axis, bin = best.bin;
                m = axis >= 0 ? best.left : size / 2;
                __syncwarp();
                if (axis >= 0) {  // stable partition through tmp
                    uint32_t nl = 0, nr = 0;
                    for (uint32_t i0 = b; i0 < e; i0 += kWarp) {
                        const uint32_t i = i0 + lane;
                        const bool live = i < e;
                        const uint32_t id = live ? ids[i] : 0;
                        const bool l = live && map.bin(centres[id][axis], axis) <= bin;
                        const unsigned bl = __ballot_sync(~0u, l), br = __ballot_sync(~0u, live && !l);
                        if (l) tmp[b + nl + __popc(bl & lt)] = id;
                        if (live && !l) tmp[b + m + nr + __popc(br & lt)] = id;
                        nl += __popc(bl);
                        nr += __popc(br);
                    }
                    __syncwarp();
                    for (uint32_t i = b + lane; i < e; i += kWarp) ids[i] = tmp[i];
                    __syncwarp();
                }
            }
            const uint32_t id = n + t.b + b + m - 1;
            if (lane == 0) set_link(children, root, slot, id);
            // The smaller child next, the larger on the stack.
            const uint3 l{b, b + m, id << 1}, r{b + m, e, id << 1 | 1u};
            const bool left_first = m <= size - m;
            stack[sp++] = left_first ? r : l;
            const uint3 go = left_first ? l : r;
            b = go.x;
            e = go.y;
            slot = go.z;
        }
        __syncwarp();
    }
}

/// sah_small's grid: as many blocks as the device holds at once (each warp takes tasks in turn, so
/// the kernel lasts as long as its longest warp).
unsigned small_grid() {
    int blocks = 0;
    BVHLAB_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&blocks, sah_small, kSahWarps * kWarp, 0));
    return unsigned(std::max(blocks, 1) * gpu_sm_count());
}

/// The tiny tasks' sort keys (the largest first; past the last task, last) and their numbers.
__global__ void tiny_keys(uint32_t total, const uint3* __restrict__ tiny, const uint32_t* __restrict__ words,
                          uint8_t* __restrict__ keys, uint32_t* __restrict__ index) {
    wait_for_previous();
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= total) return;
    keys[k] = k < words[3] ? uint8_t(kSahSweep - (tiny[k].y - tiny[k].x)) : uint8_t(kSahSweep);
    index[k] = k;
}

/// One thread per tiny task (2 to kSahSweep triangles, its ids in final_ids): its whole subtree by
/// BinnedSahBuilder's exact sweep: per axis the triangles in order of centroid, each plane
/// between unequal centroids weighed by A_L N_L + A_R N_R, the lowest weight (the first axis, the
/// first plane on ties) taken. The task's triangles are ranked once per axis, the orders packed
/// four bits a place (place to triangle, triangle to place); a node is a mask of its triangles,
/// and per axis a mask of their places, whose set bits the sweeps walk. Boxes and the forward
/// sweep's areas stay in shared memory (a column per thread, so a warp's accesses fall in
/// distinct banks); everything else in registers.
constexpr int kTinyBlock = 64;
static_assert(kSahSweep <= 16, "an order's places are four bits, a node a 16-bit mask");

__device__ __forceinline__ uint32_t nibble(uint64_t packed, uint32_t j) { return uint32_t(packed >> (4 * j)) & 15u; }

__global__ void __launch_bounds__(kTinyBlock)
    sah_tiny(const uint3* __restrict__ tiny, const uint32_t* __restrict__ by_size, const uint32_t* __restrict__ words,
             const AABB* __restrict__ tri_boxes, uint32_t n, uint2* children, uint32_t* root,
             uint32_t* __restrict__ final_ids) {
    wait_for_previous();
    __shared__ float corner[6][kSahSweep][kTinyBlock];
    __shared__ float left_area[kSahSweep][kTinyBlock];
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= words[3]) return;
    const unsigned me = threadIdx.x;
    const uint3 t = tiny[by_size[k]];
    const uint32_t count = t.y - t.x;
    auto box_of = [&](uint32_t x) {
        return AABB{{corner[0][x][me], corner[1][x][me], corner[2][x][me]},
                    {corner[3][x][me], corner[4][x][me], corner[5][x][me]}};
    };
    auto centre = [&](uint32_t x, int a) { return (corner[a][x][me] + corner[3 + a][x][me]) * 0.5f; };
    uint32_t ids[kSahSweep];
    BVHLAB_UNROLL
    for (uint32_t i = 0; i < kSahSweep; ++i) {
        ids[i] = 0;
        if (i < count) {
            ids[i] = final_ids[t.x + i];
            const AABB bx = tri_boxes[ids[i]];
            corner[0][i][me] = bx.lo.x;
            corner[1][i][me] = bx.lo.y;
            corner[2][i][me] = bx.lo.z;
            corner[3][i][me] = bx.hi.x;
            corner[4][i][me] = bx.hi.y;
            corner[5][i][me] = bx.hi.z;
        }
    }
    // The task's triangles in order of centroid, per axis: triangle i goes to place rank(i).
    // Equal centroids may come in any order: no plane falls between them, so a node's planes,
    // weights and sides are the same whatever their order (the CPU sorts by (centroid, id); its
    // leaves of several triangles may list them in another order, its tree is the same).
    uint64_t order[3], place[3];  // place -> triangle, triangle -> place
    BVHLAB_UNROLL
    for (int a = 0; a < 3; ++a) {
        float c[kSahSweep];
        BVHLAB_UNROLL
        for (uint32_t i = 0; i < kSahSweep; ++i) c[i] = i < count ? centre(i, a) : 0.0f;
        uint64_t o = 0, p = 0;
        BVHLAB_UNROLL
        for (uint32_t i = 0; i < kSahSweep; ++i) {
            if (i >= count) break;
            uint32_t r = 0;
            BVHLAB_UNROLL
            for (uint32_t j = 0; j < kSahSweep; ++j)
                r += j < count && (c[j] < c[i] || (c[j] == c[i] && j < i)) ? 1u : 0u;
            o |= uint64_t(i) << (4 * r);
            p |= uint64_t(r) << (4 * i);
        }
        order[a] = o;
        place[a] = p;
    }
    // The best plane of axis a for a node whose places in this axis's order are `places` (size
    // of them): its weight (+inf for none) and the triangles left of it. Forward: each member's
    // left area; backward: the right box, and each plane's weight (<= keeps the first plane of
    // equal weights).
    auto sweep = [&](int a, uint32_t places, uint32_t size, uint32_t& m_out) {
        const uint64_t o = order[a];
        AABB acc = AABB::empty();
        uint32_t q = 0;
        float first = 0.0f, last = 0.0f;
        for (uint32_t p = places; p; p &= p - 1) {
            const uint32_t x = nibble(o, __ffs(p) - 1);
            acc.extend(box_of(x));
            left_area[q][me] = acc.half_area();
            last = centre(x, a);
            if (q == 0) first = last;
            ++q;
        }
        float w = __int_as_float(0x7f800000);
        if (!(last - first > 0.0f)) return w;  // flat: no plane
        acc = AABB::empty();
        float next = 0.0f;  // the centroid of the member after this one
        q = size;
        for (uint32_t p = places; p;) {
            const uint32_t j = 31 - __clz(p);
            p &= ~(1u << j);
            const uint32_t x = nibble(o, j);
            const float c = centre(x, a);
            --q;  // members left of the plane above this one: q + 1
            if (q + 1 < size && c != next) {
                const float wi = left_area[q][me] * float(q + 1) + acc.half_area() * float(size - q - 1);
                if (wi <= w) {
                    w = wi;
                    m_out = q + 1;
                }
            }
            acc.extend(box_of(x));
            next = c;
        }
        return w;
    };
    // The stack of nodes waiting (mask | first position << 16, slot), in registers: the smaller
    // child goes first, so at most log2(kSahSweep) wait.
    uint32_t wait_node[4], wait_slot[4];
    int waiting = 0;
    uint32_t node = (1u << count) - 1, slot = t.z;
    for (;;) {
        const uint32_t mask = node & 0xffffu, b = node >> 16, size = __popc(mask);
        if (size == 1) {
            const uint32_t x = __ffs(mask) - 1;
            uint32_t id = 0;
            BVHLAB_UNROLL
            for (uint32_t i = 0; i < kSahSweep; ++i) id = i == x ? ids[i] : id;
            set_link(children, root, slot, t.x + b);
            final_ids[t.x + b] = id;
            if (waiting == 0) break;
            node = wait_node[0];
            slot = wait_slot[0];
            BVHLAB_UNROLL
            for (int s = 0; s < 3; ++s) {
                wait_node[s] = wait_node[s + 1];
                wait_slot[s] = wait_slot[s + 1];
            }
            --waiting;
            continue;
        }
        uint32_t places[3] = {0, 0, 0};
        for (uint32_t p = mask; p; p &= p - 1) {
            const uint32_t x = __ffs(p) - 1;
            BVHLAB_UNROLL
            for (int a = 0; a < 3; ++a) places[a] |= 1u << nibble(place[a], x);
        }
        float best = __int_as_float(0x7f800000);
        int best_axis = -1;
        uint32_t m = size / 2;
        BVHLAB_UNROLL
        for (int a = 0; a < 3; ++a) {
            uint32_t ma = 0;
            const float w = sweep(a, places[a], size, ma);
            if (w < best) {
                best = w;
                best_axis = a;
                m = ma;
            }
        }
        // The first m of the node's triangles in the chosen order (by place: in task order).
        uint32_t left = 0;
        if (best_axis >= 0) {
            const uint64_t o = best_axis == 0 ? order[0] : best_axis == 1 ? order[1] : order[2];
            uint32_t p = best_axis == 0 ? places[0] : best_axis == 1 ? places[1] : places[2];
            for (uint32_t q = 0; q < m; ++q, p &= p - 1) left |= 1u << nibble(o, __ffs(p) - 1);
        } else {
            uint32_t p = mask;
            for (uint32_t q = 0; q < m; ++q, p &= p - 1) left |= 1u << (__ffs(p) - 1);
        }
        const uint32_t id = n + t.x + b + m - 1;
        set_link(children, root, slot, id);
        const uint32_t l = left | b << 16, r = (mask & ~left) | (b + m) << 16;
        const bool left_first = m <= size - m;
        BVHLAB_UNROLL
        for (int s = 3; s > 0; --s) {
            wait_node[s] = wait_node[s - 1];
            wait_slot[s] = wait_slot[s - 1];
        }
        wait_node[0] = left_first ? r : l;
        wait_slot[0] = left_first ? id << 1 | 1u : id << 1;
        ++waiting;
        node = left_first ? l : r;
        slot = left_first ? id << 1 : id << 1 | 1u;
    }
}

struct Layout {
    Bvh2Node* nodes;
    WoopTriangle* tris;
    uint32_t* tri_ids;
};

// --- Clusters for binned SAH (BuilderOptions::cluster_alpha; accel::clustered_binned_reference): the Morton order in
// chunks of a warp; in each, rounds in which every cluster finds the cluster whose union with it has the least area
// (accel::cluster_pair_key: to 2^-18 relative, ties to the lower lane) among those it may join (at most kClusterCap
// triangles together), and mutual pairs merge when the merge is nearly free (the union's half area at most alpha times
// the larger one's), until a round merges nothing. Binned SAH then runs over the clusters, and each cluster's merges
// become the nodes below it. Node ids stay n + m - 1 (every subtree a range of the final order): a merge's split is
// at its right cluster's first triangle.

constexpr uint32_t kClusterCap = accel::kMaxClusterTriangles;
constexpr uint32_t kMergeRef = 0x80000000u;  ///< a cluster reference to an interior node (by its right-first triangle)

struct ClusterOut {
    uint32_t* count;    ///< per chunk: its clusters
    uint32_t* mask;     ///< per chunk: the lanes that head a cluster
    uint32_t* members;  ///< per sorted place: the chunk's triangles (sorted places), a cluster's together
    uint32_t* tris;     ///< the same members' triangle ids
    uint4* info;        ///< per head slot: first member's index in members, triangle count, root reference
    AABB* box;          ///< per head slot: the cluster's box
    uint2* record;      ///< per sorted place s: the merge whose right cluster starts with s (kInvalid: none)
};

__global__ void __launch_bounds__(kBlock)
    cluster_chunks(uint32_t n, const uint32_t* __restrict__ sorted_ids, const AABB* __restrict__ tri_boxes, float alpha,
                   ClusterOut out) {
    wait_for_previous();
    // A cluster's triangles as a list through next_ from the lane that holds it (its first) to
    // its tail; at the end, the chunk's triangles in cluster order.
    __shared__ uint8_t next_[kBlock / kWarp][kWarp], order_[kBlock / kWarp][kWarp];
    // The lanes' boxes, the count in lo's w (kDead for a lane whose cluster merged away or that
    // holds none); rewritten by the lanes whose cluster grew or went.
    __shared__ float4 lo4[kBlock / kWarp][kWarp], hi4[kBlock / kWarp][kWarp];
    // The pairs' keys (accel::cluster_pair_key: the union's half area and the other's lane;
    // kNoClusterPair where the two may not merge, the same lane, a dead one, over the cap): lane l
    // reads its row at key_[j][l], so each round's search is one unsigned minimum over 32 words and
    // touches no box, and a merge recomputes only the merged clusters' pairs. Row length 33: both
    // key_[j][l] and key_[l][j] over the lanes l fall on 32 banks.
    __shared__ uint32_t key_[kBlock / kWarp][kWarp * (kWarp + 1)];
    const uint32_t lane = threadIdx.x % kWarp, w = threadIdx.x / kWarp;
    const uint32_t chunk = blockIdx.x * (kBlock / kWarp) + w;
    const uint32_t base = chunk * kWarp;
    if (base >= n) return;  // whole warps leave together
    const uint32_t s = base + lane;
    bool alive = s < n;
    AABB box = alive ? tri_boxes[sorted_ids[s]] : AABB::empty();
    uint32_t count = alive ? 1 : 0;
    uint32_t ref = s, tail = lane;
    uint32_t* key = key_[w];
    constexpr uint32_t kDead = 4 * kClusterCap;  // over the cap with any cluster
    const auto put_box = [&] {
        lo4[w][lane] = make_float4(box.lo.x, box.lo.y, box.lo.z, __uint_as_float(alive ? count : kDead));
        hi4[w][lane] = make_float4(box.hi.x, box.hi.y, box.hi.z, 0.0f);
    };
    // This lane's pair with lane j: the keys for this lane's search (place j) and for j's (place
    // lane), kNoClusterPair twice if they may not merge (the same lane, or over the cap, which a
    // dead lane always is). The union's half area as AABB::half_area's (never empty here, so
    // without its test), for every lane: no branch.
    const auto put_pair = [&](uint32_t j) {
        const float4 a = lo4[w][j], b = hi4[w][j];
        const float ex = fmaxf(box.hi.x, b.x) - fminf(box.lo.x, a.x);
        const float ey = fmaxf(box.hi.y, b.y) - fminf(box.lo.y, a.y);
        const float ez = fmaxf(box.hi.z, b.z) - fminf(box.lo.z, a.z);
        const float area = ex * ey + ey * ez + ez * ex;
        const bool may = j != lane && (alive ? count : kDead) + __float_as_uint(a.w) <= kClusterCap;
        key[j * (kWarp + 1) + lane] = may ? accel::cluster_pair_key(area, j) : accel::kNoClusterPair;
        key[lane * (kWarp + 1) + j] = may ? accel::cluster_pair_key(area, lane) : accel::kNoClusterPair;
    };
    put_box();
    __syncwarp();
    key[lane * (kWarp + 1) + lane] = accel::kNoClusterPair;
    for (uint32_t d = 1; d <= kWarp / 2; ++d) put_pair((lane + d) % kWarp);  // each pair once (d = 16 twice)
    __syncwarp();
    for (;;) {
        uint32_t least = accel::kNoClusterPair;
        for (uint32_t j = 0; j < kWarp; ++j) least = min(least, key[j * (kWarp + 1) + lane]);
        const uint32_t nn = least == accel::kNoClusterPair || !alive ? kWarp : least & (kWarp - 1);
        const float best = accel::cluster_key_area(least);
        const uint32_t nn_of_nn = __shfl_sync(~0u, nn, int(nn % kWarp));
        const float4 oa = lo4[w][nn % kWarp], ob = hi4[w][nn % kWarp];
        const AABB other{{oa.x, oa.y, oa.z}, {ob.x, ob.y, ob.z}};
        const uint32_t other_count = __float_as_uint(oa.w);
        const bool mutual = nn < kWarp && nn_of_nn == lane;
        const bool cheap = mutual && best <= alpha * fmaxf(box.half_area(), other.half_area());
        const bool take = cheap && lane < nn;  // the lower lane keeps the cluster
        const bool taken = __shfl_sync(~0u, take ? 1u : 0u, int(nn % kWarp)) != 0 && cheap && nn < lane;
        const uint32_t grew = __ballot_sync(~0u, take);
        if (!grew) break;
        const uint32_t other_ref = __shfl_sync(~0u, ref, int(nn % kWarp));
        const uint32_t other_tail = __shfl_sync(~0u, tail, int(nn % kWarp));
        __syncwarp();  // every lane has read the boxes before the grown ones are rewritten
        if (take) {
            const uint32_t right_first = base + nn;  // a lane's cluster starts with its own triangle
            out.record[right_first] = make_uint2(ref, other_ref);
            next_[w][tail] = uint8_t(nn);
            tail = other_tail;
            box = merge(box, other);
            count += other_count;
            ref = kMergeRef | right_first;
            put_box();
        }
        if (taken) {
            alive = false;
            count = 0;
            box = AABB::empty();
            put_box();
        }
        const uint32_t gone = __ballot_sync(~0u, taken);
        __syncwarp();
        for (uint32_t rest = grew; rest; rest &= rest - 1)  // the grown clusters' pairs anew
            put_pair(uint32_t(__ffs(int(rest))) - 1);
        for (uint32_t rest = gone; rest; rest &= rest - 1) {  // and no pair with the merged-away ones
            const uint32_t i = uint32_t(__ffs(int(rest))) - 1;
            key[i * (kWarp + 1) + lane] = accel::kNoClusterPair;
            key[lane * (kWarp + 1) + i] = accel::kNoClusterPair;
        }
        __syncwarp();
    }
    const uint32_t heads = __ballot_sync(~0u, alive);
    // Each head's first member place: the counts of the heads before it.
    uint32_t first = count;
    for (uint32_t d = 1; d < kWarp; d <<= 1) {
        const uint32_t v = __shfl_up_sync(~0u, first, d);
        if (lane >= d) first += v;
    }
    first -= count;
    for (uint32_t k = 0, at = lane; k < count; ++k, at = next_[w][at]) order_[w][first + k] = uint8_t(at);
    __syncwarp();
    if (s < n) {
        const uint32_t m = base + order_[w][lane];
        out.members[s] = m;
        out.tris[s] = sorted_ids[m];
    }
    if (alive) {
        out.info[s] = make_uint4(base + first, count, ref, 0);
        out.box[s] = box;
    }
    if (lane == 0) {
        out.count[chunk] = __popc(heads);
        out.mask[chunk] = heads;
    }
}

/// Cluster k (k-th head in chunk order; chunk_end: the clusters up to each chunk's end) at its
/// place: its box, centre and info, and the centres' bounds (a block's reduced, then atomics: a
/// few blocks a SM, each slot a grid apart, so few atomics meet on the bounds).
__global__ void __launch_bounds__(kBlock)
    cluster_compact(uint32_t n, const uint32_t* __restrict__ chunk_end, ClusterOut in, AABB* __restrict__ boxes,
                    Vec3* __restrict__ centres, uint4* __restrict__ info, AABB* __restrict__ bounds) {
    wait_for_previous();
    AABB cb = AABB::empty();
    for (uint32_t s = blockIdx.x * blockDim.x + threadIdx.x; s < n; s += gridDim.x * blockDim.x) {
        const uint32_t chunk = s / kWarp, lane = s % kWarp, heads = in.mask[chunk];
        if (heads >> lane & 1u) {
            const uint32_t k = chunk_end[chunk] - __popc(heads) + __popc(heads & ((1u << lane) - 1u));
            const AABB b = in.box[s];
            boxes[k] = b;
            centres[k] = b.center();
            info[k] = in.info[s];
            cb.extend(b.center());
        }
    }
    using Reduce = cub::BlockReduce<AABB, kBlock>;
    __shared__ typename Reduce::TempStorage tmp;
    const AABB total = Reduce(tmp).Reduce(cb, BoxUnion{});
    if (threadIdx.x == 0 && !total.is_empty()) atomic_merge(bounds, total);
}

/// The triangle count of cluster k (an iterator over binned SAH's order of clusters feeds the scan).
struct ClusterWeight {
    const uint4* info;
    __device__ uint32_t operator()(uint32_t k) const { return info[k].y; }
};

/// The cluster at place p of binned SAH's order puts its triangles at places offset[p] on: the
/// final order (triangle ids) and each sorted place's final place.
__global__ void cluster_expand(uint32_t c, const uint32_t* __restrict__ order, const uint4* __restrict__ info,
                               const uint32_t* __restrict__ offset, const uint32_t* __restrict__ members,
                               const uint32_t* __restrict__ tris, uint32_t* __restrict__ final_ids,
                               uint32_t* __restrict__ place) {
    wait_for_previous();
    const uint32_t p = blockIdx.x * blockDim.x + threadIdx.x;
    if (p >= c) return;
    const uint4 x = info[order[p]];
    for (uint32_t k = 0; k < x.y; ++k) {
        const uint32_t m = members[x.x + k];
        final_ids[offset[p] + k] = tris[x.x + k];
        place[m] = offset[p] + k;
    }
}

__device__ uint32_t cluster_node(uint32_t ref, uint32_t n, const uint32_t* place) {
    return ref & kMergeRef ? n + place[ref & ~kMergeRef] - 1 : place[ref];
}

/// Each merge inside a cluster as its node: id n + (its right cluster's first place) - 1.
__global__ void cluster_nodes(uint32_t n, const uint2* __restrict__ record, const uint32_t* __restrict__ place,
                              uint2* __restrict__ children) {
    wait_for_previous();
    const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= n) return;
    const uint2 r = record[s];
    if (r.x == kInvalid) return;
    children[n + place[s] - 1] = make_uint2(cluster_node(r.x, n, place), cluster_node(r.y, n, place));
}

/// Binned SAH's nodes over the c clusters (node c + j splits its order at place j + 1) as nodes of
/// the whole tree; a cluster in place of a leaf by its root. The root last (thread c - 1).
__global__ void cluster_top(uint32_t c, uint32_t n, const uint2* __restrict__ top,
                            const uint32_t* __restrict__ top_root, const uint32_t* __restrict__ order,
                            const uint4* __restrict__ info, const uint32_t* __restrict__ offset,
                            const uint32_t* __restrict__ place, uint2* __restrict__ children,
                            uint32_t* __restrict__ root) {
    wait_for_previous();
    const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= c) return;
    auto node_of = [&](uint32_t x) {
        return x < c ? cluster_node(info[order[x]].z, n, place) : n + offset[x - c + 1] - 1;
    };
    if (j == c - 1) {
        *root = node_of(*top_root);
        return;
    }
    const uint2 t = top[c + j];
    children[n + offset[j + 1] - 1] = make_uint2(node_of(t.x), node_of(t.y));
}

struct LayoutInput {
    uint32_t n;
    const uint2* children;
    const AABB* boxes;
    const NodeMeta* meta;
    const uint32_t* sorted_ids;
};

/// Every node's parent from the children (PLOC and H-PLOC record none while they merge).
__global__ void parents_of(uint32_t n, const uint2* __restrict__ children, uint32_t* __restrict__ parent) {
    wait_for_previous();
    const uint32_t x = n + blockIdx.x * blockDim.x + threadIdx.x;
    if (x >= 2 * n - 1) return;
    const uint2 c = children[x];
    parent[c.x] = x;
    parent[c.y] = x;
}

/// The layout orders nodes by id, with the root first: PLOC and H-PLOC number nodes as they
/// make them, so the root is the last and the order is reversed; the LBVH's root (*root) trades
/// places with its first interior node (n).
struct LayoutOrder {
    uint32_t total;  // 2n - 1 hierarchy nodes
    bool reverse;
    bool id_ranges;  // subtrees are ranges of the sorted triangles (the LBVH's, unless reinsertion moved them)
    const uint32_t* root;
    __device__ uint32_t operator()(uint32_t x) const {
        if (reverse) return total - 1 - x;
        const uint32_t first = (total + 1) / 2, r = __ldg(root);
        if (r < first) return x;  // a root leaf (one triangle) is already first
        return x == r ? first : x == first ? r : x;
    }
};

/// Per hierarchy node, in layout order: 1 << 32 for a layout node (interior, not collapsed into
/// a leaf), its triangle count for a layout leaf, 0 for a node inside a leaf. A node is inside a
/// leaf when an ancestor chose to be one, and only ancestors of at most max_leaf triangles can.
__global__ void layout_flags(LayoutOrder order, uint32_t max_leaf, const uint32_t* __restrict__ parent,
                             const NodeMeta* __restrict__ meta, unsigned long long* __restrict__ flags) {
    wait_for_previous();
    const uint32_t x = blockIdx.x * blockDim.x + threadIdx.x;
    if (x >= order.total) return;
    const NodeMeta m = meta[x];
    bool live = true;
    for (uint32_t y = x;;) {
        const uint32_t p = parent[y];
        if (p == kInvalid) break;
        const NodeMeta pm = meta[p];
        if (pm.count > max_leaf) break;
        if (pm.leaf()) {
            live = false;
            break;
        }
        y = p;
    }
    flags[order(x)] = !live ? 0ull : m.leaf() ? m.count : 1ull << 32;
}

/// The layout from the flags' exclusive scan: a layout node's slot is the number of layout
/// nodes before it, a leaf's first triangle the triangles of the leaves before it. A root that
/// is a leaf is node 0 with both slots naming it (the second behind an empty box).
__global__ void layout_write(LayoutOrder order, LayoutInput in, const uint32_t* __restrict__ parent, Layout out,
                             const unsigned long long* __restrict__ flags,
                             const unsigned long long* __restrict__ scan) {
    wait_for_previous();
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= order.total) return;
    const unsigned long long f = flags[k];
    if (!f) return;
    const uint32_t x = order(k);  // the order is its own inverse
    const unsigned long long at = scan[k];
    // A leaf's first triangle: the LBVH's subtrees are ranges of the sorted triangles, so its
    // leftmost leaf (tri_ids are then the sorted ids, in Morton order); else the scan's count.
    auto first_of = [&](uint32_t node, unsigned long long scanned) {
        if (!order.id_ranges) return uint32_t(scanned);
        while (node >= in.n) node = in.children[node].x;
        return node;
    };
    if (f >> 32) {
        const uint2 c = in.children[x];
        const uint32_t child[2] = {c.x, c.y};
        Bvh2Node o{};
        for (int j = 0; j < 2; ++j) {
            const NodeMeta cm = in.meta[child[j]];
            const unsigned long long cs = scan[order(child[j])];
            o.set_child_box(j, in.boxes[child[j]]);
            o.child[j] = cm.leaf() ? Bvh2Node::leaf_ref(first_of(child[j], cs), cm.count) : int32_t(cs >> 32);
        }
        out.nodes[at >> 32] = o;
        return;
    }
    // With id ranges the leaves' triangles, left to right, are the sorted order itself: tri_ids is
    // sorted_ids, copied whole after the layout.
    if (!order.id_ranges) emit_leaf(x, first_of(x, at), in.n, in.children, in.sorted_ids, out.tri_ids);
    if (parent[x] == kInvalid) {
        Bvh2Node o{};
        o.set_child_box(0, in.boxes[x]);
        o.set_child_box(1, AABB::empty());
        o.child[0] = o.child[1] = Bvh2Node::leaf_ref(0, in.meta[x].count);
        out.nodes[0] = o;
    }
}

// --- Refit of a BVH2 layout (GpuRefitter).

__device__ AABB load_child_box(const Bvh2Node* n, int slot) {
    const float* xy = slot == 0 ? &n->c0_lo_x : &n->c1_lo_x;
    const float* z = slot == 0 ? &n->c0_lo_z : &n->c1_lo_z;
    return {{__ldcg(xy), __ldcg(xy + 2), __ldcg(z)}, {__ldcg(xy + 1), __ldcg(xy + 3), __ldcg(z + 1)}};
}

/// From each leaf (a node's slot) upwards: the leaf's box from its triangles, then each node's
/// box in its parent's slot, written by the second of its two children to finish.
__global__ void refit_leaves(detail::RefitInput in) {
    const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= in.leaf_count) return;
    uint32_t node = in.leaves[k] >> 1;
    int slot = int(in.leaves[k] & 1);
    const int32_t ref = in.nodes[node].child[slot];
    const uint32_t first = Bvh2Node::leaf_first(ref), count = Bvh2Node::leaf_count(ref);
    AABB box = AABB::empty();
    for (uint32_t t = first; t < first + count; ++t) {
        const uint32_t tri = in.tri_ids[t];
        for (int v = 0; v < 3; ++v) box.extend(in.verts[in.idx[3 * tri + v]]);
    }
    in.nodes[node].set_child_box(slot, box);
    if (in.nodes[node].child[0] == in.nodes[node].child[1]) return;  // a root leaf: one slot
    for (;;) {
        __threadfence();  // this thread's box before the counter
        if (atomicAdd(&in.visits[node], 1u) == 0) return;
        __threadfence();
        const AABB b = merge(load_child_box(in.nodes + node, 0), load_child_box(in.nodes + node, 1));
        const uint32_t p = in.parents[node];
        if (p == kInvalid) return;
        node = p >> 1;
        slot = int(p & 1);
        in.nodes[node].set_child_box(slot, b);
    }
}

__global__ void set_word(uint32_t* p, uint32_t v) { *p = v; }

__global__ void iota(uint32_t n, uint32_t* __restrict__ out) {
    wait_for_previous();
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) out[i] = i;
}

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

/// Binned SAH's level counts, which the device writes into mapped pinned memory (two slots: the
/// host reads one level's while the device writes the next's). mark(k) records, after the work
/// enqueued so far, that slot k is written; wait(k) waits for that alone. Nothing is copied in the
/// stream.
class Readback {
public:
    static constexpr size_t kWords = 4;
    Readback() {
        BVHLAB_CUDA_CHECK(cudaHostAlloc(&h_, 2 * kWords * sizeof(uint32_t), cudaHostAllocMapped));
        BVHLAB_CUDA_CHECK(cudaHostGetDevicePointer(reinterpret_cast<void**>(&d_), h_, 0));
        for (cudaEvent_t& e : e_) BVHLAB_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
    }
    ~Readback() {
        for (cudaEvent_t e : e_) BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(e));
        BVHLAB_CUDA_CHECK_LOG(cudaFreeHost(h_));
    }
    Readback(const Readback&) = delete;
    Readback& operator=(const Readback&) = delete;
    /// Slot k as the device writes it.
    uint32_t* slot(int k) const { return d_ + k * kWords; }
    void mark(int k) { BVHLAB_CUDA_CHECK(cudaEventRecord(e_[k])); }
    const uint32_t* wait(int k) {
        BVHLAB_CUDA_CHECK(cudaEventSynchronize(e_[k]));
        return h_ + k * kWords;
    }

private:
    uint32_t* h_ = nullptr;
    uint32_t* d_ = nullptr;
    cudaEvent_t e_[2] = {};
};

template <typename T>
void download(std::vector<T>& h, const T* d, size_t count) {
    h.resize(count);
    if (count) detail::copy_to_host(h.data(), d, count * sizeof(T));
}

/// What the pipeline builds over: a mesh's triangles (their Woop maps written, a host copy
/// downloaded), or instances' world boxes (a TLAS: no triangles, nothing downloaded).
struct Prims {
    uint32_t n;
    const scene::TriangleMesh* mesh;
    const detail::TlasInput* tlas;
};

template <typename Key>
GpuBuild build(const Prims& prims, accel::BuilderKind kind, const accel::BuilderOptions& options, bool keep_raw) {
    const uint32_t n = prims.n;
    const int bits = kind == accel::BuilderKind::kGpuBinned ? 30 : options.morton_bits;
    const bool lbvh = kind == accel::BuilderKind::kLbvh, ploc = kind == accel::BuilderKind::kPloc;
    const bool sah = kind == accel::BuilderKind::kGpuBinned;
    // Binned SAH over clusters of nearly coincident triangles (cluster_chunks).
    const float alpha = sah && prims.mesh ? options.cluster_alpha : 0.0f;  // a TLAS bins every instance
    const bool clustered = alpha > 0.0f && n > 1;
    const bool coded = !sah || clustered;  // Morton codes sorted
    const int passes = n >= 3 ? accel::reinsertion_passes(kind, options) : 0;
    const LeafRule rule{options.config.traversal_cost, options.config.intersection_cost, options.config.min_leaf_size,
                        options.config.max_leaf_size};
    const size_t base = gpu_memory_use().current;
    GpuBuild g;
    Events ev(9);
    ev.record(0);
    DeviceBuffer<Vec3> verts;
    DeviceBuffer<uint32_t> idx;
    if (prims.mesh) {
        verts.upload(prims.mesh->vertices);
        idx.upload(prims.mesh->indices);
    }
    ev.record(1);

    // Everything the pipeline needs, before its first event.
    const size_t nodes = 2 * size_t(n) - 1, inner = std::max<size_t>(n - 1, 1);
    DeviceBuffer<AABB> tri_boxes(n), bounds(1), boxes(nodes);
    DeviceBuffer<Key> keys(coded ? n : 0), keys_alt(coded ? n : 0);
    DeviceBuffer<uint32_t> ids(n), ids_alt(n);
    DeviceBuffer<Vec3> centres(sah && !clustered ? n : 0);  // binned SAH over triangles: their centroids
    DeviceBuffer<uint2> children(nodes);
    DeviceBuffer<NodeMeta> meta(nodes);
    DeviceBuffer<uint32_t> parent(nodes), visits(lbvh || sah || passes ? inner : 0), clusters(lbvh || sah ? 0 : n);
    DeviceBuffer<int32_t> parent_ids(kind == accel::BuilderKind::kHploc ? inner : 0);
    // PLOC's second cluster list, nearest neighbours, flags and their scan.
    DeviceBuffer<uint32_t> clusters_alt(ploc ? n : 0), nn(ploc ? n : 0);
    DeviceBuffer<unsigned long long> flags(ploc ? n : 0), flag_scan(ploc ? n : 0);
    DeviceBuffer<uint32_t> words(4);  // root, (H-)PLOC's node counter, (unused), PLOC's list length
    DeviceBuffer<Bvh2Node> out_nodes(inner);
    // Binned SAH: two lists of a level's large tasks, their splits, bins, first chunks and chunks
    // binned (per task), each chunk's counts per bin and lefts, the small and tiny tasks, the
    // triangles' final order, and counters: [1] the small tasks, [3] the tiny tasks, [4] and [5]
    // the large tasks of even and odd levels ([0] and [2] are not used).
    const size_t s_large = sah ? n / (kSahWarpTask + 1) + 1 : 0;
    const size_t s_chunks = sah ? n / kSahChunk + s_large + 1 : 0;
    DeviceBuffer<SahTask> s_tasks(2 * s_large), s_small(sah ? n / 2 + 1 : 0);
    DeviceBuffer<SahSplit> s_splits(s_large);
    DeviceBuffer<SahBin> s_bins(3 * kSahBins * s_large);
    DeviceBuffer<uint32_t> s_first(s_large + 1), s_chunk_task(s_chunks), s_lefts(s_chunks), s_done(s_large),
        final_ids(sah ? n : 0);
    DeviceBuffer<uint32_t> s_words(sah ? 6 : 0), s_chunk_counts(3 * kSahBins * s_chunks);
    DeviceBuffer<uint3> s_tiny(sah ? n / 2 + 1 : 0);
    // The tiny tasks in order of size (threads of a warp then walk subtrees of one size).
    DeviceBuffer<uint8_t> t_keys(s_tiny.size()), t_keys_alt(s_tiny.size());
    DeviceBuffer<uint32_t> t_index(s_tiny.size()), t_index_alt(s_tiny.size());
    cub::DoubleBuffer<uint8_t> tk(t_keys.data(), t_keys_alt.data());
    cub::DoubleBuffer<uint32_t> ti(t_index.data(), t_index_alt.data());
    DeviceBuffer<unsigned long long> layout_flags_(nodes), layout_scan(nodes);  // the layout's flags and their scan
    // Clusters: per chunk of a warp its count, head lanes and first cluster; per sorted place the
    // members, head info and box, and the merge records; the compacted clusters (boxes, centres,
    // info, centres' bounds); binned SAH's tree over them (links, root, order), the clusters'
    // triangle counts in that order and their scan, and each sorted place's final place.
    const size_t cn = clustered ? n : 0, c_chunks = clustered ? (n + kWarp - 1) / kWarp : 0;
    DeviceBuffer<uint32_t> c_count(c_chunks), c_mask(c_chunks), c_end(c_chunks), c_members(cn), c_tris(cn);
    DeviceBuffer<uint4> c_info_slot(cn), c_info(cn);
    DeviceBuffer<AABB> c_box_slot(cn), c_boxes(cn), c_bounds(clustered ? 1 : 0);
    DeviceBuffer<uint2> c_record(cn), c_top(clustered ? 2 * cn : 0);
    DeviceBuffer<Vec3> c_centres(cn);
    DeviceBuffer<uint32_t> c_order(cn), c_offset(cn), c_place(cn), c_words(clustered ? 2 : 0);
    const auto c_weights = thrust::make_transform_iterator(c_order.data(), ClusterWeight{c_info.data()});
    // Reinsertion: each node's role and move (X, gain, common ancestor), a lock and a moving flag
    // per node, the hierarchy before the passes (restored if they are undone) and the root's
    // meta before and after.
    const size_t r_nodes = passes ? nodes : 0;
    DeviceBuffer<uint8_t> r_role(r_nodes), r_moving(r_nodes);
    DeviceBuffer<SearchNode> r_search(r_nodes);
    DeviceBuffer<float> r_gain(r_nodes);
    DeviceBuffer<uint32_t> r_to(r_nodes), r_top(r_nodes), r_parent(r_nodes), r_list(r_nodes), r_count(passes ? 1 : 0);
    DeviceBuffer<unsigned long long> r_locks(r_nodes);
    DeviceBuffer<uint2> r_children(passes ? nodes - n : 0);  // the interior nodes' (passes need n >= 3)
    DeviceBuffer<NodeMeta> r_root(passes ? 2 : 0);
    g.tris.resize(prims.mesh ? n : 0);
    g.tri_ids.resize(n);
    size_t sort_bytes = 0, scan_bytes = 0, select_bytes = 0;
    cub::DoubleBuffer<Key> dk(keys.data(), keys_alt.data());
    cub::DoubleBuffer<uint32_t> dv(ids.data(), ids_alt.data());
    if (coded) BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, sort_bytes, dk, dv, int(n), 0, bits));
    BVHLAB_CUDA_CHECK(
        cub::DeviceScan::ExclusiveSum(nullptr, scan_bytes, layout_flags_.data(), layout_scan.data(), int(nodes)));
    if (sah) {
        size_t b = 0;
        BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, b, tk, ti, int(s_tiny.size()), 0, 5));
        sort_bytes = std::max(sort_bytes, b);
        if (clustered) {
            BVHLAB_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, b, c_weights, c_offset.data(), int(n)));
            scan_bytes = std::max(scan_bytes, b);
            BVHLAB_CUDA_CHECK(cub::DeviceScan::InclusiveSum(nullptr, b, c_count.data(), c_end.data(), int(c_chunks)));
            scan_bytes = std::max(scan_bytes, b);
        }
    }
    if (passes) {
        BVHLAB_CUDA_CHECK(cub::DeviceSelect::If(nullptr, select_bytes, thrust::counting_iterator<uint32_t>(0),
                                                r_list.data(), r_count.data(), int(nodes), Movable{r_role.data()}));
    }
    DeviceBuffer<uint8_t> scratch(std::max({sort_bytes, scan_bytes, select_bytes}));
    g.peak_bytes = gpu_memory_use().current - base;
    uint32_t* root = words.data();
    uint32_t* node_counter = words.data() + 1;
    detail::fill_device_bytes(parent.data(), 0xff, parent.bytes());
    if (lbvh) {  // the climb's outer keys, none yet
        detail::fill_device_bytes(visits.data(), 0xff, visits.bytes());
    }
    if (kind == accel::BuilderKind::kHploc) {
        detail::fill_device_bytes(parent_ids.data(), 0xff, parent_ids.bytes());
    }
    detail::fill_device_bytes(words.data(), 0, words.bytes());
    if (sah) detail::fill_device_bytes(s_words.data(), 0, s_words.bytes());
    if (sah) detail::fill_device_bytes(s_done.data(), 0, s_done.bytes());
    std::optional<Readback> readback;  // binned SAH's level counts
    if (sah) readback.emplace();
    if (clustered) detail::fill_device_bytes(c_record.data(), 0xff, c_record.bytes());

    // The boxes' kernel: a few blocks per SM, each primitive a grid apart (few atomics on the bounds).
    const unsigned box_grid = std::min(grid_for(n), unsigned(4 * gpu_sm_count()));
    ev.record(2);
    set_empty<<<1, 1>>>(bounds.data());
    if (prims.mesh)
        prim_boxes<<<box_grid, kBlock>>>(n, TriangleBox{verts.data(), idx.data()}, tri_boxes.data(), bounds.data(),
                                         centres.data());
    else
        prim_boxes<<<box_grid, kBlock>>>(n, InstanceBox{*prims.tlas}, tri_boxes.data(), bounds.data(), centres.data());
    BVHLAB_CHECK_LAUNCH();
    ev.record(3);
    if (coded) {
        morton_codes<Key><<<grid_for(n), kBlock>>>(n, bits, tri_boxes.data(), bounds.data(), keys.data(), ids.data());
        BVHLAB_CHECK_LAUNCH();
    }
    ev.record(4);
    if (coded) {  // the clustering's order ignores low bits (accel::kClusterOrderIgnoredBits)
        const int low = clustered ? accel::kClusterOrderIgnoredBits : 0;
        BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(scratch.data(), sort_bytes, dk, dv, int(n), low, bits));
    }
    ev.record(5);
    const Key* sorted_keys = dk.Current();
    const uint32_t* sorted_ids = sah ? final_ids.data() : dv.Current();
    if (sah && n == 1) {
        launch(iota, 1, 1, 1, final_ids.data());
        BVHLAB_CHECK_LAUNCH();
    }
    if ((!lbvh && !sah) || n == 1) {  // the LBVH's climb makes its leaves, binned SAH's come last
        make_leaves<<<grid_for(n), kBlock>>>(n, sorted_ids, tri_boxes.data(), boxes.data(), meta.data(),
                                             lbvh ? nullptr : clusters.data(), rule);
        BVHLAB_CHECK_LAUNCH();
    }
    if (n == 1) {
        // The root is leaf 0 (words are zero).
    } else if (lbvh) {
        lbvh_climb<Key><<<grid_for(n), kBlock>>>(n, sorted_keys, sorted_ids, tri_boxes.data(), boxes.data(),
                                                 meta.data(), children.data(), parent.data(), visits.data(), root,
                                                 rule);
        BVHLAB_CHECK_LAUNCH();
    } else if (sah) {
        // Binned SAH over m primitives (boxes, centres, the centres' bounds): links of nodes m + k
        // in kids, the root in *proot, the primitives' final order in fin.
        const auto binned = [&](uint32_t m, const AABB* pboxes, const Vec3* pcentres, const AABB* pbounds, uint2* kids,
                                uint32_t* proot, uint32_t* fin) {
            launch(iota, grid_for(m), kBlock, m, ids.data());
            const SahOrder order{{ids.data(), ids_alt.data()}};
            const uint32_t bin_count = uint32_t(3 * kSahBins * (m / (kSahWarpTask + 1) + 1));  // disjoint tasks
            launch(sah_start, std::min(grid_for(2 * bin_count), 1024u), kBlock, m, pbounds, s_tasks.data(),
                   s_small.data(), s_first.data(), s_chunk_task.data(), s_words.data(), s_bins.data(), bin_count);
            BVHLAB_CHECK_LAUNCH();
            // Large tasks level by level. Level k's kernels read its task count (words[4 + k % 2]) and
            // chunk count (first[tasks]) on the device; their grids are bounded from level k - 1's counts
            // (a task makes at most two large tasks, with at most one chunk more than its own). So the
            // host enqueues level k before it knows level k's counts, then reads them (written by level
            // k - 1's sah_chunks into mapped memory) while the device runs level k; a level with no
            // tasks does nothing.
            uint32_t tasks = m > kSahWarpTask ? 1 : 0, chunks = (m + kSahChunk - 1) / kSahChunk;
            size_t grid_chunks = chunks;
            // The most chunks of a task at the level enqueued next (a child has at most its parent's):
            // sah_lefts runs while a task may have more than kSahSumChunks.
            uint32_t most = chunks;
            SahTask* level = s_tasks.data();
            SahTask* next = s_tasks.data() + s_large;
            for (uint32_t k = 0; tasks; ++k) {
                const uint32_t* now = s_words.data() + 4 + k % 2;
                uint32_t* after = s_words.data() + 4 + (k + 1) % 2;
                const SahSplitOut split_out{s_bins.data(),
                                            s_splits.data(),
                                            s_done.data(),
                                            next,
                                            after,
                                            s_small.data(),
                                            s_words.data() + 1,
                                            m,
                                            kids,
                                            proot};
                launch(sah_bin, unsigned(grid_chunks), kBlock, level, now, s_first.data(), s_chunk_task.data(), order,
                       pboxes, s_chunk_counts.data(), split_out);
                if (most > kSahSumChunks)
                    launch(sah_lefts, unsigned((grid_chunks * kWarp + kBlock - 1) / kBlock), kBlock, level, now,
                           s_first.data(), s_chunk_task.data(), s_splits.data(), s_chunk_counts.data(), s_lefts.data());
                launch(sah_scatter, unsigned(grid_chunks), kBlock, level, now, s_first.data(), s_chunk_task.data(),
                       s_splits.data(), order, pcentres, s_chunk_counts.data(), s_lefts.data(), fin);
                launch(sah_chunks, 1, 1024, next, after, s_first.data(), s_chunk_task.data(),
                       s_words.data() + 4 + k % 2, readback->slot(int(k % 2)));
                BVHLAB_CHECK_LAUNCH();
                readback->mark(int(k % 2));
                if (k > 0) {  // level k's counts
                    const uint32_t* w = readback->wait(int((k - 1) % 2));
                    tasks = w[0];
                    chunks = w[1];
                    most = w[2];
                }
                grid_chunks = std::min(size_t(chunks) + tasks, s_chunks);
                std::swap(level, next);
            }
            launch(sah_small, small_grid(), kSahWarps * kWarp, s_small.data(), s_words.data(), order, pboxes, pcentres,
                   m, kids, proot, fin, s_tiny.data());
            launch(tiny_keys, grid_for(s_tiny.size()), kBlock, uint32_t(s_tiny.size()), s_tiny.data(), s_words.data(),
                   tk.Current(), ti.Current());
            BVHLAB_CHECK_LAUNCH();
            BVHLAB_CUDA_CHECK(
                cub::DeviceRadixSort::SortPairs(scratch.data(), sort_bytes, tk, ti, int(s_tiny.size()), 0, 5));
            launch(sah_tiny, unsigned((s_tiny.size() + kTinyBlock - 1) / kTinyBlock), kTinyBlock, s_tiny.data(),
                   ti.Current(), s_words.data(), pboxes, m, kids, proot, fin);
            BVHLAB_CHECK_LAUNCH();
        };
        if (!clustered) {
            binned(n, tri_boxes.data(), centres.data(), bounds.data(), children.data(), root, final_ids.data());
        } else {
            const uint32_t chunks = uint32_t(c_chunks);
            const ClusterOut co{c_count.data(),     c_mask.data(),     c_members.data(), c_tris.data(),
                                c_info_slot.data(), c_box_slot.data(), c_record.data()};
            const uint32_t* morton_ids = dv.Current();
            set_empty<<<1, 1>>>(c_bounds.data());
            launch(cluster_chunks, (chunks + kBlock / kWarp - 1) / (kBlock / kWarp), kBlock, n, morton_ids,
                   tri_boxes.data(), alpha, co);
            BVHLAB_CHECK_LAUNCH();
            BVHLAB_CUDA_CHECK(
                cub::DeviceScan::InclusiveSum(scratch.data(), scan_bytes, c_count.data(), c_end.data(), int(chunks)));
            launch(cluster_compact, box_grid, kBlock, n, c_end.data(), co, c_boxes.data(), c_centres.data(),
                   c_info.data(), c_bounds.data());
            BVHLAB_CHECK_LAUNCH();
            uint32_t c = 0;  // the clusters: the last chunk's end
            detail::copy_to_host(&c, c_end.data() + chunks - 1, sizeof c);
            uint32_t* top_root = c_words.data();
            if (c == 1) {
                launch(iota, 1, 1, 1, c_order.data());
                set_word<<<1, 1>>>(top_root, 0);
                BVHLAB_CHECK_LAUNCH();
            } else {
                binned(c, c_boxes.data(), c_centres.data(), c_bounds.data(), c_top.data(), top_root, c_order.data());
            }
            BVHLAB_CUDA_CHECK(
                cub::DeviceScan::ExclusiveSum(scratch.data(), scan_bytes, c_weights, c_offset.data(), int(c)));
            launch(cluster_expand, grid_for(c), kBlock, c, c_order.data(), c_info.data(), c_offset.data(),
                   c_members.data(), c_tris.data(), final_ids.data(), c_place.data());
            launch(cluster_nodes, grid_for(n), kBlock, n, c_record.data(), c_place.data(), children.data());
            launch(cluster_top, grid_for(c), kBlock, c, n, c_top.data(), top_root, c_order.data(), c_info.data(),
                   c_offset.data(), c_place.data(), children.data(), root);
            BVHLAB_CHECK_LAUNCH();
            g.clusters = c;
        }
        launch(parents_of, grid_for(n - 1), kBlock, n, children.data(), parent.data());
        BVHLAB_CHECK_LAUNCH();
        detail::fill_device_bytes(visits.data(), 0, visits.bytes());
        launch(leaves_and_climb, grid_for(n), kBlock, n, final_ids.data(), tri_boxes.data(), parent.data(),
               children.data(), boxes.data(), meta.data(), visits.data(), rule);
        BVHLAB_CHECK_LAUNCH();
    } else if (ploc) {
        // Rounds over the whole list until a block can finish it; the host reads each round's
        // list length (a round trip per round).
        uint32_t m = n, base = n;
        uint32_t* list = clusters.data();
        uint32_t* next = clusters_alt.data();
        while (m > kPlocTail) {
            ploc_neighbours<<<grid_for(m), kBlock>>>(m, options.ploc_radius, list, boxes.data(), nn.data());
            ploc_flags<<<grid_for(m), kBlock>>>(m, nn.data(), flags.data());
            BVHLAB_CUDA_CHECK(
                cub::DeviceScan::ExclusiveSum(scratch.data(), scan_bytes, flags.data(), flag_scan.data(), int(m)));
            ploc_merge_round<<<grid_for(m), kBlock>>>(m, base, list, nn.data(), flags.data(), flag_scan.data(), next,
                                                      boxes.data(), children.data(), meta.data(), words.data(), rule);
            BVHLAB_CHECK_LAUNCH();
            uint32_t w[3];  // node counter, height, list length
            detail::copy_to_host(w, words.data() + 1, sizeof w);
            base = w[0];
            m = w[2];
            std::swap(list, next);
        }
        ploc_tail<<<1, kPlocTail>>>(m, base, options.ploc_radius, list, boxes.data(), children.data(), meta.data(),
                                    root, rule);
        BVHLAB_CHECK_LAUNCH();
    } else {
        set_word<<<1, 1>>>(node_counter, n);
        hploc<Key><<<grid_for(n), kBlock>>>(n, sorted_keys, parent_ids.data(), clusters.data(), boxes.data(),
                                            children.data(), meta.data(), node_counter, root, options.ploc_radius,
                                            rule);
        BVHLAB_CHECK_LAUNCH();
    }
    if (!lbvh && !sah && n > 1) {  // PLOC and H-PLOC record no parents while they merge
        launch(parents_of, grid_for(n - 1), kBlock, n, children.data(), parent.data());
        BVHLAB_CHECK_LAUNCH();
    }
    ev.record(6);
    if (passes) {
        BVHLAB_CUDA_CHECK(
            cudaMemcpyAsync(r_children.data(), children.data() + n, r_children.bytes(), cudaMemcpyDeviceToDevice));
        BVHLAB_CUDA_CHECK(cudaMemcpyAsync(r_parent.data(), parent.data(), parent.bytes(), cudaMemcpyDeviceToDevice));
        root_meta<<<1, 1>>>(root, meta.data(), r_root.data());
        const uint32_t total = uint32_t(nodes);
        // The list kernels' grid: enough blocks to fill every SM, each thread taking the list's
        // nodes a grid apart.
        const unsigned list_grid = std::min(grid_for(total), unsigned(16 * gpu_sm_count()));
        for (int pass = 0; pass < passes; ++pass) {
            reinsert_roles<<<grid_for(total), kBlock>>>(total, rule.max_leaf, parent.data(), children.data(),
                                                        boxes.data(), meta.data(), r_role.data(), r_search.data());
            BVHLAB_CHECK_LAUNCH();
            BVHLAB_CUDA_CHECK(cub::DeviceSelect::If(scratch.data(), select_bytes,
                                                    thrust::counting_iterator<uint32_t>(0), r_list.data(),
                                                    r_count.data(), int(total), Movable{r_role.data()}));
            const uint32_t* list = r_list.data();
            const uint32_t* count = r_count.data();
            reinsert_search<<<list_grid, kBlock>>>(list, count, r_role.data(), parent.data(), r_search.data(),
                                                   r_gain.data(), r_to.data(), r_top.data());
            BVHLAB_CHECK_LAUNCH();
            detail::fill_device_bytes(r_locks.data(), 0, r_locks.bytes());
            detail::fill_device_bytes(r_moving.data(), 0, r_moving.bytes());
            reinsert_lock<<<list_grid, kBlock>>>(list, count, r_gain.data(), r_to.data(), parent.data(),
                                                 children.data(), r_locks.data());
            BVHLAB_CHECK_LAUNCH();
            reinsert_claim<<<list_grid, kBlock>>>(list, count, r_gain.data(), r_to.data(), parent.data(),
                                                  children.data(), r_locks.data(), r_moving.data());
            BVHLAB_CHECK_LAUNCH();
            reinsert_uncross<<<list_grid, kBlock>>>(list, count, r_to.data(), r_top.data(), parent.data(),
                                                    r_moving.data());
            BVHLAB_CHECK_LAUNCH();
            reinsert_apply<<<list_grid, kBlock>>>(list, count, r_to.data(), parent.data(), children.data());
            BVHLAB_CHECK_LAUNCH();
            clear_root_count<<<1, 1>>>(root, meta.data());
            detail::fill_device_bytes(visits.data(), 0, visits.bytes());
            refit_from_leaves<<<list_grid, kBlock>>>(list, count, n, r_role.data(), parent.data(), children.data(),
                                                     boxes.data(), meta.data(), visits.data(), rule);
            BVHLAB_CHECK_LAUNCH();
        }
        root_meta<<<1, 1>>>(root, meta.data(), r_root.data() + 1);
        BVHLAB_CHECK_LAUNCH();
        // Passes that leave the tree as deep as max_depth (deeper than it was), or not one tree
        // over every triangle (a safety net: the moves are made so that none is carried into its
        // own subtree), are undone: the hierarchy as the builder made it, fitted again.
        NodeMeta rm[2];
        detail::copy_to_host(rm, r_root.data(), sizeof rm);
        if ((std::max(rm[1].height, 1u) >= options.config.max_depth && rm[1].height > rm[0].height) ||
            rm[1].count != n) {
            BVHLAB_CUDA_CHECK(
                cudaMemcpyAsync(children.data() + n, r_children.data(), r_children.bytes(), cudaMemcpyDeviceToDevice));
            BVHLAB_CUDA_CHECK(
                cudaMemcpyAsync(parent.data(), r_parent.data(), parent.bytes(), cudaMemcpyDeviceToDevice));
            detail::fill_device_bytes(visits.data(), 0, visits.bytes());
            fit_boxes<<<grid_for(n), kBlock>>>(n, parent.data(), children.data(), boxes.data(), meta.data(),
                                               visits.data(), rule);
            BVHLAB_CHECK_LAUNCH();
            g.reinsertion_undone = true;
        }
    }
    ev.record(7);
    // The layout, flat: each node's place from a scan over every node's flag (no round trip).
    const Layout out{out_nodes.data(), g.tris.data(), g.tri_ids.data()};
    const LayoutInput in{n, children.data(), boxes.data(), meta.data(), sorted_ids};
    const LayoutOrder order{uint32_t(nodes), !lbvh && !sah, (lbvh || sah) && (!passes || g.reinsertion_undone), root};
    {
        launch(layout_flags, grid_for(nodes), kBlock, order, rule.max_leaf, parent.data(), meta.data(),
               layout_flags_.data());
        BVHLAB_CHECK_LAUNCH();
        BVHLAB_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(scratch.data(), scan_bytes, layout_flags_.data(),
                                                        layout_scan.data(), int(nodes)));
        launch(layout_write, grid_for(nodes), kBlock, order, in, parent.data(), out, layout_flags_.data(),
               layout_scan.data());
        BVHLAB_CHECK_LAUNCH();
        if (prims.mesh) {  // with id ranges, the maps read the sorted ids and copy them to tri_ids
            launch(woop_maps, grid_for(n), kBlock, n, order.id_ranges ? sorted_ids : g.tri_ids.data(), verts.data(),
                   idx.data(), g.tris.data(), order.id_ranges ? g.tri_ids.data() : nullptr);
            BVHLAB_CHECK_LAUNCH();
        } else if (order.id_ranges) {
            BVHLAB_CUDA_CHECK(
                cudaMemcpyAsync(g.tri_ids.data(), sorted_ids, size_t(n) * sizeof(uint32_t), cudaMemcpyDeviceToDevice));
        }
    }
    ev.record(8);
    ev.sync(8);

    GpuBuildTimes& t = g.times;
    t.upload_ms = ev.ms(0, 1);
    t.bounds_ms = ev.ms(2, 3);
    t.morton_ms = ev.ms(3, 4);
    t.sort_ms = ev.ms(4, 5);
    t.hierarchy_ms = ev.ms(5, 6);
    t.optimize_ms = ev.ms(6, 7);
    t.convert_ms = ev.ms(7, 8);
    t.total_ms = ev.ms(2, 8);
    g.reinsertion_passes = passes;

    // The host copy, and the nodes moved to a buffer of their exact size.
    uint32_t w[3];  // root, node counter, (unused)
    detail::copy_to_host(w, words.data(), sizeof w);
    NodeMeta root_meta;
    detail::copy_to_host(&root_meta, meta.data() + w[0], sizeof root_meta);
    const size_t node_count = root_meta.leaf() ? 1 : root_meta.interior;
    const uint32_t height = std::max(root_meta.height, 1u);  // a root leaf is one node
    if (height > accel::kMaxTreeDepth)
        throw Error("builder '" + std::string(accel::builder_name(kind)) + "' made a tree " + std::to_string(height) +
                    " levels deep; the traversal stacks hold " + std::to_string(accel::kMaxTreeDepth));
    g.node_count = node_count;
    g.host.depth = height;
    if (!prims.mesh) {  // a TLAS: the nodes stay in their buffer (room for n - 1)
        g.nodes = std::move(out_nodes);
        return g;
    }
    download(g.host.nodes, out_nodes.data(), node_count);
    g.nodes.upload(g.host.nodes);
    download(g.host.tris, g.tris.data(), n);
    download(g.host.tri_ids, g.tri_ids.data(), n);
    if (keep_raw) {
        accel::RawHierarchy& raw = g.raw;
        raw.root = w[0];
        if (!sah) {  // binned SAH sorts no keys
            std::vector<Key> k;
            download(k, sorted_keys, n);
            raw.keys.assign(k.begin(), k.end());
        }
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

double gpu_refit(const RefitInput& in) {
    Events ev(2);
    ev.record(0);
    refit_leaves<<<grid_for(in.leaf_count), kBlock>>>(in);
    BVHLAB_CHECK_LAUNCH();
    launch(woop_maps, grid_for(in.tri_count), kBlock, in.tri_count, in.tri_ids, in.verts, in.idx, in.tris,
           static_cast<uint32_t*>(nullptr));
    BVHLAB_CHECK_LAUNCH();
    ev.record(1);
    ev.sync(1);
    return ev.ms(0, 1);
}

GpuBuild gpu_build(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                   bool keep_raw) {
    const Prims p{uint32_t(mesh.triangle_count()), &mesh, nullptr};
    // gpu-binned takes no Morton bits: its clusters follow 30-bit codes (accel::triangle_clusters).
    return options.morton_bits == 60 && kind != accel::BuilderKind::kGpuBinned
               ? build<uint64_t>(p, kind, options, keep_raw)
               : build<uint32_t>(p, kind, options, keep_raw);
}

GpuBuild gpu_build_tlas(uint32_t instances, const TlasInput& in, accel::BuilderKind kind,
                        const accel::BuilderOptions& options) {
    const Prims p{instances, nullptr, &in};
    return options.morton_bits == 60 ? build<uint64_t>(p, kind, options, false)
                                     : build<uint32_t>(p, kind, options, false);
}

}  // namespace detail

}  // namespace bvhlab::trav
