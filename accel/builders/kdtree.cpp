// SPDX-License-Identifier: MIT
// O(N log N) SAH kd-tree build (Wald & Havran 2006). Each node keeps, per axis, its events sorted
// by (position, type); one sweep per axis finds the best plane. Triangles are then classified as
// left, right or both by their clipped bounds; only the straddling ones are clipped, once to the
// node's voxel and then split by the plane into both children's bounds ("perfect splits"); inside
// a fragment (below) the two clipped parts are kept, and a child splits its part again instead of
// clipping the triangle anew. Events whose bound the clip left in place are kept, already sorted,
// with the others' when filtered; only the moved bounds get new events, sorted and merged in.
// Nodes of up to small_node_size triangles are built on the stack without events: their planes are
// counted directly, eight candidates at a time (same plane, less work). An empty-space cut (57-62%
// of the interior nodes on the scans and furball with Wald & Havran's constants) gives its
// parent's arrays whole to the non-empty child, which reuses the parent's sweep counts and only
// re-prices the planes. Events refer to node-local triangle slots, so concurrent subtrees never
// share state; below a size threshold a subtree is built by one thread into its own fragment of
// the final node array.
// The split search (kd/plane_search), the events (kd/events) and the final layout (kd/flatten)
// are in accel/builders/kd/; this file is the recursion.
#include "accel/builders/kdtree.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>

#include "accel/builders/kd/events.h"
#include "accel/builders/kd/flatten.h"
#include "accel/builders/kd/plane_search.h"
#include "accel/builders/top_down.h"
#include "accel/core/check.h"
#include "accel/core/clip.h"
#include "accel/core/progress.h"

namespace bvhlab::accel::kd {
namespace {

/// The most vertices of a clipped polygon that a fragment keeps (a triangle clipped to a box
/// has at most 9; more, from rounding, and the child clips the triangle anew).
constexpr uint32_t kMaxKeptPolygon = 15;
/// A slot's kept-polygon entry when its triangle is still to be clipped (see SmallWork::poly).
constexpr uint32_t kNoPolygon = ~0u;
/// Meshes from this many triangles on set up the root with parallel tasks.
constexpr size_t kParallelMin = 4096;
/// Nodes from this many triangles on split their three axes' events as parallel tasks.
constexpr size_t kParallelSplit = size_t(1) << 16;
/// Nodes from this many triangles on prefetch the split's route entries, this many events
/// ahead (the table, 12 bytes a slot, outgrows the L2 cache).
constexpr size_t kPrefetchRoutes = size_t(1) << 14;
constexpr size_t kRouteAhead = 32;

/// A node's work: its voxel, and per triangle slot the global id and the bounds of the
/// triangle clipped to the voxel; per axis, the events of those bounds, sorted.
struct Work {
    AABB voxel;
    std::vector<uint32_t> tris;
    std::vector<AABB> boxes;
    std::vector<Event> events[3];
    /// Inside a fragment, per slot: the triangle's clipped part as SmallWork::poly holds it.
    /// Empty above the fragments (no part kept).
    std::vector<uint32_t> poly;

    uint32_t polygon(size_t s) const { return poly.empty() ? kNoPolygon : poly[s]; }
    void clear() {
        tris.clear();
        boxes.clear();
        poly.clear();
        for (auto& e : events) e.clear();
    }
};

/// A small node's copy of a (small) Work node, padded.
SmallWork small_of(const Work& w) {
    SmallWork sw;
    sw.voxel = w.voxel;
    for (size_t s = 0; s < w.tris.size(); ++s) sw.add(w.tris[s], w.boxes[s], w.polygon(s));
    sw.pad();
    return sw;
}

/// The clipped polygons of the fragment a thread is building (a stack: a node's children's
/// polygons are dropped when its subtree is done). Unfilled storage, so that making room
/// costs nothing.
class PolygonArena {
public:
    /// Room for k more vertices after the used ones (earlier pointers into the arena may move).
    PolygonVertex* room(size_t k) {
        if (size_ + k > cap_) {
            const size_t cap = std::max(2 * cap_, size_ + k + 1024);
            std::unique_ptr<PolygonVertex[]> v(new PolygonVertex[cap]);
            std::copy(v_.get(), v_.get() + size_, v.get());
            v_ = std::move(v);
            cap_ = cap;
        }
        return v_.get() + size_;
    }
    const PolygonVertex* at(size_t i) const { return v_.get() + i; }
    size_t size() const { return size_; }
    void resize(size_t n) { size_ = n; }  // within room() only

private:
    std::unique_ptr<PolygonVertex[]> v_;
    size_t size_ = 0, cap_ = 0;
};

/// Runs f(0) .. f(count - 1), as parallel tasks only when `parallel` (worth it for large
/// inputs: on the 32-triangle Cornell box, TBB's task start-up had been a quarter of the
/// whole build). Isolated: a thread waiting for these tasks runs none but them. Otherwise
/// it could steal another node's task, whose split() reuses this thread's scratch (the
/// `side` array, the sweeps) while the waiting split still needs it. Two threads seldom
/// stole; on a 16-core host furball's tree came out with 24x the triangle tests per ray.
template <typename F>
void run_tasks(int count, bool parallel, const F& f) {
    if (parallel)
        tbb::this_task_arena::isolate([&] { tbb::parallel_for(0, count, f); });
    else
        for (int i = 0; i < count; ++i) f(i);
}

/// Where split() sends a parent slot's events: its slot in each child, and per axis the event
/// types that each child keeps (bit 1 << type for the left child, 8 << type for the right).
/// A one-sided triangle's child keeps all of them; a straddler's child keeps those whose
/// bound the clipping left where it was.
struct Route {
    uint32_t slot[2];
    uint8_t keep[3];
};

/// Per-thread reusable storage: free Work objects (their vectors keep their capacity) and the
/// temporaries of find_plane() and split(). A node's vectors are taken from here and given
/// back once the node is split, so after warm-up the build allocates almost nothing per node.
struct ThreadState {
    std::vector<std::unique_ptr<Work>> free_work;
    Sweep sweeps[3];  ///< find_plane's records, per axis
    std::vector<uint8_t> side;
    std::vector<Route> route;
    std::vector<uint32_t> origin[2];
    std::vector<Event> filtered[3], fresh[2][3];
    PolygonArena polygons;  ///< the clipped parts kept inside a fragment
};

class Recursion {
public:
    Recursion(const KdTreeBuilder::Config& c, const scene::TriangleMesh& mesh, int max_depth)
        : c_(c),
          max_depth_(max_depth),
          small_(c.small_node_size),
          corners_(mesh.triangle_count()),
          parallel_(corners_.size() >= kParallelMin) {
        const auto copy = [&](size_t t) {
            for (int i = 0; i < 3; ++i) corners_[t].v[i] = mesh.vertex(t, i);
        };
        if (parallel_)
            tbb::parallel_for(size_t(0), corners_.size(), copy);
        else
            for (size_t t = 0; t < corners_.size(); ++t) copy(t);
    }

    /// A free Work with room for n triangles: the pooled one with the least capacity that
    /// holds n, else the largest, grown to n. Reusing capacity matters because fresh pages are
    /// costly: on furball page faults took a quarter of the build.
    std::unique_ptr<Work> acquire(size_t n = 0) {
        auto& pool = state_.local().free_work;
        if (pool.empty()) return std::make_unique<Work>();
        size_t pick = 0;
        for (size_t i = 1; i < pool.size(); ++i) {
            const size_t have = pool[i]->tris.capacity(), best = pool[pick]->tris.capacity();
            if (best < n ? have > best : have >= n && have < best) pick = i;
        }
        std::unique_ptr<Work> w = std::move(pool[pick]);
        pool[pick] = std::move(pool.back());
        pool.pop_back();
        w->clear();
        w->tris.reserve(n);
        w->boxes.reserve(n);
        return w;
    }
    void release(std::unique_ptr<Work> w) { state_.local().free_work.push_back(std::move(w)); }

    /// Splits in parallel while nodes are large, then hands each subtree to one thread.
    std::unique_ptr<TopNode> build_top(std::unique_ptr<Work> w, int depth) {
        auto node = std::make_unique<TopNode>();
        if (w->tris.size() < c_.task_threshold) {
            // Reserve what the fragments built so far needed per triangle (plus a quarter),
            // so that a fragment's arrays rarely grow: growing copies them into fresh pages,
            // and on furball page faults were a third of the build.
            const double n = double(w->tris.size());
            const double seen = double(frag_tris_.load(std::memory_order_relaxed));
            const double per_tri_nodes = seen > 0 ? double(frag_nodes_.load(std::memory_order_relaxed)) / seen : 8.0;
            const double per_tri_refs = seen > 0 ? double(frag_refs_.load(std::memory_order_relaxed)) / seen : 4.0;
            Fragment& f = node->frag;
            f.nodes.reserve(size_t(1.25 * per_tri_nodes * n) + 1);
            f.prims.reserve(size_t(1.25 * per_tri_refs * n));
            f.nodes.resize(1);
            build_fragment(std::move(w), depth, f, 0);
            frag_tris_ += uint64_t(n);
            frag_nodes_ += f.nodes.size();
            frag_refs_ += f.prims.size();
            return node;
        }
        const Plane p = depth < max_depth_ ? choose_plane(*w) : Plane{};
        if (!(p.cost < c_.intersection_cost * float(w->tris.size()))) {
            node->frag.nodes.push_back(KdNode::leaf(0, uint32_t(w->tris.size())));
            node->frag.prims = w->tris;
            if (c_.progress) c_.progress->add(w->tris.size());
            release(std::move(w));
            return node;
        }
        Children ch = split(std::move(w), p);
        node->axis = uint32_t(p.axis);
        node->split = p.pos;
        tbb::parallel_invoke([&] { node->child[0] = build_top(std::move(ch.left), depth + 1); },
                             [&] { node->child[1] = build_top(std::move(ch.right), depth + 1); });
        return node;
    }

    /// The root's work: every triangle with its bounds, the scene box, and the sorted events.
    /// Bounds and box come from one parallel pass. Each axis's events are generated and
    /// sorted in two halves of the triangles, six tasks instead of three (on two threads, the
    /// third axis had run alone), and the halves are merged.
    std::unique_ptr<Work> root() {
        std::unique_ptr<Work> w = acquire();
        const size_t n = corners_.size();
        w->tris.resize(n);
        w->boxes.resize(n);
        // Per half of the triangles, the bounds that are flat on each axis (one event each).
        const size_t half = n / 2;
        std::atomic<size_t> flat[2][3] = {};
        const auto bound = [&](const tbb::blocked_range<size_t>& r, AABB voxel) {
            size_t flats[2][3] = {};
            for (size_t t = r.begin(); t != r.end(); ++t) {
                AABB b = AABB::empty();
                for (int i = 0; i < 3; ++i) b.extend(corners_[t].v[i]);
                w->tris[t] = uint32_t(t);
                w->boxes[t] = b;
                voxel.extend(b);
                for (int k = 0; k < 3; ++k) flats[t >= half][k] += b.lo[k] == b.hi[k];
            }
            for (int h = 0; h < 2; ++h)
                for (int k = 0; k < 3; ++k) flat[h][k] += flats[h][k];
            return voxel;
        };
        const tbb::blocked_range<size_t> all(0, n);
        w->voxel = parallel_ ? tbb::parallel_reduce(all, AABB::empty(), bound,
                                                    [](AABB a, const AABB& b) {
                                                        a.extend(b);
                                                        return a;
                                                    })
                             : bound(all, AABB::empty());
        std::vector<Event> scratch[3];
        const size_t lo[2] = {0, half}, hi[2] = {half, n};
        size_t second_half[3];         // per axis, where the second half's events start
        for (int k = 0; k < 3; ++k) {  // no fill: Event's default constructor writes nothing
            second_half[k] = 2 * half - flat[0][k];
            w->events[k].resize(second_half[k] + 2 * (n - half) - flat[1][k]);
            scratch[k].resize(w->events[k].size());
        }
        run_tasks(6, parallel_, [&](int task) {
            const int k = task / 2, h = task % 2;
            const size_t first = h == 0 ? 0 : second_half[k];
            Event* const a = w->events[k].data() + first;
            const Event* e = write_events(w->boxes.data(), uint32_t(lo[h]), uint32_t(hi[h]), k, a);
            sort_by_pos(a, scratch[k].data() + first, size_t(e - a));
        });
        run_tasks(3, parallel_, [&](int k) {
            const Event* sorted = scratch[k].data();
            const size_t m = second_half[k];
            merge_events(sorted, m, sorted + m, scratch[k].size() - m, w->events[k].data());
        });
        return w;
    }

private:
    /// Builds the subtree of `w` into `f`, its root at f.nodes[at]. `counted`: w has the same
    /// bounds and events as the node whose find_plane() ran last on this thread (it is the
    /// child of an empty-space cut), so that sweep's counts still hold.
    void build_fragment(std::unique_ptr<Work> w, int depth, Fragment& f, uint32_t at, bool counted = false) {
        const auto n = uint32_t(w->tris.size());
        if (n <= small_) {
            const SmallWork sw = small_of(*w);
            release(std::move(w));
            build_small(sw, depth, f, at, state_.local().polygons);
            return;
        }
        const Plane p = depth < max_depth_ ? find_plane(*w, counted ? Records::kKept : Records::kKeep) : Plane{};
        if (!(p.cost < c_.intersection_cost * float(n))) {
            f.nodes[at] = KdNode::leaf(uint32_t(f.prims.size()), n);
            f.prims.insert(f.prims.end(), w->tris.begin(), w->tris.end());
            if (c_.progress) c_.progress->add(n);
            release(std::move(w));
            return;
        }
        PolygonArena& polygons = state_.local().polygons;
        const size_t mark = polygons.size();
        Children ch = split(std::move(w), p, c_.reuse_clipped_polygons ? &polygons : nullptr);
        const auto k = uint32_t(f.nodes.size());
        f.nodes.resize(k + 2);
        f.nodes[at] = KdNode::interior(uint32_t(p.axis), p.pos, k);
        // An empty child is a leaf at once, so the other child's find_plane() is the next.
        build_fragment(std::move(ch.left), depth + 1, f, k, ch.empty_cut);
        build_fragment(std::move(ch.right), depth + 1, f, k + 1, ch.empty_cut);
        polygons.resize(mark);
    }

    Plane choose_plane(const Work& w) const {
        if (w.tris.size() > small_) return find_plane(w, Records::kShared);
        return find_plane_small(small_of(w), c_, avx2_);
    }

    /// The bounds of straddling triangle t clipped to each side of plane p in `voxel`.
    std::pair<AABB, AABB> split_straddler(uint32_t t, const AABB& voxel, const Plane& p) const {
        const Corners& c = corners_[t];
        return split_clipped_triangle(c.v[0], c.v[1], c.v[2], voxel, p.axis, p.pos);
    }
    /// split_straddler() for a straddler whose clipped part is `kept` (a PolygonArena entry as
    /// SmallWork::poly holds it; kNoPolygon: the triangle clipped to `voxel`). Its two parts
    /// go to `polygons`, and their entries to part[0] and part[1] (kNoPolygon where a part
    /// is not kept; with reuse_clipped_polygons off, none is, and this is split_straddler()).
    std::pair<AABB, AABB> split_part(uint32_t t, uint32_t kept, const AABB& voxel, const Plane& p,
                                     PolygonArena& polygons, uint32_t (&part)[2]) const {
        if (!c_.reuse_clipped_polygons) {
            part[0] = part[1] = kNoPolygon;
            return split_straddler(t, voxel, p);
        }
        // Each part gets room for twice the polygon's vertices.
        PolygonVertex* out = polygons.room(4 * kMaxKeptPolygon);
        PolygonVertex clipped[12];
        const PolygonVertex* in = clipped;
        int m = 0;
        if (kept == kNoPolygon) {
            const Corners& c = corners_[t];
            m = clip_triangle_polygon(c.v[0], c.v[1], c.v[2], voxel, clipped);
        } else {
            in = polygons.at(kept >> 4);
            m = int(kept & 15);
        }
        int count[2];
        const auto boxes = split_polygon(in, m, voxel, p.axis, p.pos, out, &count[0], out + 2 * m, &count[1]);
        const size_t first[2] = {polygons.size(), polygons.size() + 2 * size_t(m)};
        polygons.resize(first[1] + size_t(count[1]));
        for (int i = 0; i < 2; ++i) {
            const bool keep = count[i] <= int(kMaxKeptPolygon) && first[i] < (size_t(1) << 28);
            part[i] = keep ? uint32_t(first[i]) << 4 | uint32_t(count[i]) : kNoPolygon;
        }
        return boxes;
    }

    /// Starts loading triangle t's corners (a node's triangles lie anywhere in memory: on the
    /// 1M soup, waiting for them was a third of the split).
    void prefetch(uint32_t t) const {
        const char* p = reinterpret_cast<const char*>(&corners_[t]);
        __builtin_prefetch(p);
        __builtin_prefetch(p + sizeof(Corners) - 1);
    }

    /// build_fragment for a node of at most small_ triangles: the same planes, clipping and
    /// slot order as split(), with everything on the stack. A straddler's two clipped parts are
    /// kept in `polygons` for the children, which split them again instead of clipping the
    /// triangle to their voxel anew (same bounds to rounding: double-precision vertices,
    /// rounded to float).
    void build_small(const SmallWork& w, int depth, Fragment& f, uint32_t at, PolygonArena& polygons) {
        const Plane p = depth < max_depth_ ? find_plane_small(w, c_, avx2_) : Plane{};
        if (!(p.cost < c_.intersection_cost * float(w.n))) {
            f.nodes[at] = KdNode::leaf(uint32_t(f.prims.size()), w.n);
            f.prims.insert(f.prims.end(), w.tris, w.tris + w.n);
            if (c_.progress) c_.progress->add(w.n);
            return;
        }
        SmallWork child[2];
        const int axis = p.axis;
        child[0].voxel = child[1].voxel = w.voxel;
        child[0].voxel.hi[axis] = p.pos;
        child[1].voxel.lo[axis] = p.pos;
        uint8_t side[kMaxSmallNode];
        for (uint32_t s = 0; s < w.n; ++s) {
            side[s] = classify(w.lo[axis][s], w.hi[axis][s], p);
            if (side[s] == kBoth) {
                prefetch(w.tris[s]);
                continue;
            }
            child[side[s] - 1].add(w, s);
        }
        const size_t mark = polygons.size();
        for (uint32_t s = 0; s < w.n; ++s) {
            if (side[s] != kBoth) continue;
            const uint32_t t = w.tris[s];
            uint32_t part[2];
            const auto boxes = split_part(t, w.poly[s], w.voxel, p, polygons, part);
            if (!boxes.first.is_empty()) child[0].add(t, boxes.first, part[0]);
            if (!boxes.second.is_empty()) child[1].add(t, boxes.second, part[1]);
        }
        child[0].pad();
        child[1].pad();
        const auto k = uint32_t(f.nodes.size());
        f.nodes.resize(k + 2);
        f.nodes[at] = KdNode::interior(uint32_t(axis), p.pos, k);
        build_small(child[0], depth + 1, f, k, polygons);
        build_small(child[1], depth + 1, f, k + 1, polygons);
        polygons.resize(mark);
    }

    /// Where find_plane() keeps its per-position records.
    enum class Records {
        kShared,  ///< one buffer serves all three axes (the large nodes above the fragments)
        kKeep,    ///< each axis keeps its records, for a child of an empty-space cut
        kKept,    ///< the kept records of the last call on this thread hold (same events):
                  ///< only the second pass runs
    };

    /// One sweep per axis over the sorted events finds the cheapest plane, in two passes.
    /// The first counts, without branches, and writes one record per distinct position (on
    /// scanned meshes about a third of the events: vertices are shared); the second evaluates
    /// the SAH at the records inside the voxel.
    Plane find_plane(const Work& w, Records records) const {
        Plane best;
        const float area = w.voxel.area();
        if (!(area > 0.0f) || w.tris.empty()) return best;
        const float inv_area = 1.0f / area;
        const auto n = uint32_t(w.tris.size());
        ThreadState& ts = state_.local();
        for (int k = 0; k < 3; ++k) {
            Sweep& sweep = ts.sweeps[records == Records::kShared ? 0 : k];
            if (records != Records::kKept) count_positions(w.events[k], sweep);
            const Plane p = price_positions(sweep, n, k, axis_cost(w.voxel, k, inv_area, c_), avx2_);
            if (p.cost < best.cost) best = p;  // an earlier axis wins ties
        }
        return best;
    }

    /// The event types (bits 1 << type) on axis k of a straddler's bounds `parent` that its
    /// clipped bounds `child` in one child share: a bound the clip did not move keeps its
    /// event, already in sorted place.
    static uint32_t kept_events(const AABB& parent, const AABB& child, int k) {
        if (parent.lo[k] == parent.hi[k])
            return child.lo[k] == parent.lo[k] && child.hi[k] == parent.hi[k] ? 1u << kPlanar : 0u;
        if (child.lo[k] == child.hi[k]) return 0;
        return uint32_t(child.lo[k] == parent.lo[k]) << kStart | uint32_t(child.hi[k] == parent.hi[k]) << kEnd;
    }

    struct Children {
        std::unique_ptr<Work> left, right;
        bool empty_cut;  ///< one child is empty and the other is w, with a smaller voxel
    };

    /// Splits w's triangles, bounds and events between two children. Inside a fragment,
    /// `polygons` keeps the straddlers' clipped parts for the children (see split_part()).
    Children split(std::unique_ptr<Work> wp, const Plane& p, PolygonArena* polygons = nullptr) {
        ThreadState& ts = state_.local();
        const Work& w = *wp;
        const size_t n = w.tris.size();
        const int axis = p.axis;
        std::vector<uint8_t>& side = ts.side;
        side.resize(n);
        size_t sides[3] = {0, 0, 0};  // straddling, left only, right only
        for (size_t s = 0; s < n; ++s) {
            side[s] = classify(w.boxes[s].lo[axis], w.boxes[s].hi[axis], p);
            ++sides[side[s]];
        }
        AABB cell[2] = {w.voxel, w.voxel};
        cell[0].hi[axis] = p.pos;
        cell[1].lo[axis] = p.pos;
        if (sides[kLeftOnly] == n || sides[kRightOnly] == n) {
            // An empty-space cut: every slot keeps its number, bounds and events.
            const int full = sides[kLeftOnly] == n ? 0 : 1;
            std::unique_ptr<Work> c[2];
            c[full] = std::move(wp);
            c[full]->voxel = cell[full];
            c[!full] = acquire();
            c[!full]->voxel = cell[!full];
            return {std::move(c[0]), std::move(c[1]), true};
        }
        std::unique_ptr<Work> lp = acquire(sides[kLeftOnly] + sides[kBoth]);
        std::unique_ptr<Work> rp = acquire(sides[kRightOnly] + sides[kBoth]);
        Work &left = *lp, &right = *rp;
        left.voxel = cell[0];
        right.voxel = cell[1];
        // One-sided triangles keep their bounds and events; their slots are renumbered in
        // order.
        std::vector<Route>& route = ts.route;
        route.resize(n);
        for (size_t s = 0; s < n; ++s) {
            Route& r = route[s];
            if (side[s] == kBoth) {
                r = {{0, 0}, {0, 0, 0}};
                continue;
            }
            const int i = side[s] - 1;
            Work& to = i == 0 ? left : right;
            const auto keep = uint8_t(i == 0 ? 7 : 7 << 3);
            r = {{uint32_t(to.tris.size()), uint32_t(to.tris.size())}, {keep, keep, keep}};
            to.tris.push_back(w.tris[s]);
            to.boxes.push_back(w.boxes[s]);
            if (polygons) to.poly.push_back(w.polygon(s));
        }
        // Straddling triangles: clipped to each child's voxel, appended after the one-sided
        // ones (so that slot order, and with it the order of kept events, is preserved).
        const uint32_t one_sided[2] = {uint32_t(left.tris.size()), uint32_t(right.tris.size())};
        Work* child[2] = {&left, &right};
        for (auto& o : ts.origin) o.clear();
        // The corners of the straddler 8 ahead are fetched while this one is clipped.
        const auto next_straddler = [&](size_t s) {
            while (s < n && side[s] != kBoth) ++s;
            return s;
        };
        size_t ahead = next_straddler(0);
        for (int i = 0; i < 8 && ahead < n; ++i, ahead = next_straddler(ahead + 1)) prefetch(w.tris[ahead]);
        for (size_t s = next_straddler(0); s < n; s = next_straddler(s + 1)) {
            if (ahead < n) {
                prefetch(w.tris[ahead]);
                ahead = next_straddler(ahead + 1);
            }
            const uint32_t t = w.tris[s];
            uint32_t part[2];
            const auto boxes =
                polygons ? split_part(t, w.polygon(s), w.voxel, p, *polygons, part) : split_straddler(t, w.voxel, p);
            for (int i = 0; i < 2; ++i) {
                const AABB& box = i == 0 ? boxes.first : boxes.second;
                if (box.is_empty()) continue;
                if (polygons) child[i]->poly.push_back(part[i]);
                Route& r = route[s];
                r.slot[i] = uint32_t(child[i]->tris.size());
                for (int k = 0; k < 3; ++k) r.keep[k] |= uint8_t(kept_events(w.boxes[s], box, k) << (3 * i));
                child[i]->tris.push_back(t);
                child[i]->boxes.push_back(box);
                ts.origin[i].push_back(uint32_t(s));
            }
        }
        // Events only for children above the small-node size (their parent has events too).
        // Per axis: the kept events stay sorted when filtered (slots are renumbered in order);
        // the straddlers' new events (about half of theirs: a clip moves one bound on the
        // split axis and often none on the others) are sorted and merged in.
        const bool events[2] = {left.tris.size() > small_, right.tris.size() > small_};
        if (!events[0] && !events[1]) {
            release(std::move(wp));
            return {std::move(lp), std::move(rp), false};
        }
        // Per axis (three tasks for a large node: at the root, the other thread had idled):
        // the new events, then the kept ones, then the merge.
        const auto axis_events = [&](int k) {
            for (int i = 0; i < 2; ++i) {
                if (!events[i]) continue;
                const std::vector<AABB>& boxes = child[i]->boxes;
                std::vector<Event>& fresh = ts.fresh[i][k];
                fresh.clear();
                for (size_t j = 0; j < ts.origin[i].size(); ++j) {
                    const auto slot = uint32_t(one_sided[i] + j);
                    const AABB& b = boxes[slot];
                    const uint32_t kept = route[ts.origin[i][j]].keep[k] >> (3 * i);
                    if (b.lo[k] == b.hi[k]) {
                        if (!(kept & 1u << kPlanar)) fresh.push_back(Event::make(b.lo[k], kPlanar, slot));
                        continue;
                    }
                    if (!(kept & 1u << kStart)) fresh.push_back(Event::make(b.lo[k], kStart, slot));
                    if (!(kept & 1u << kEnd)) fresh.push_back(Event::make(b.hi[k], kEnd, slot));
                }
                std::sort(fresh.begin(), fresh.end());
            }
            const std::vector<Event>& in = w.events[k];
            // The kept events are filtered straight into each child's array, behind room for
            // its new events, which are then merged in place (the output never overtakes the
            // unread kept events). A child without events gets a scratch array.
            Event* kept_at[2];
            for (int i = 0; i < 2; ++i) {
                std::vector<Event>& dst = events[i] ? child[i]->events[k] : ts.filtered[k];
                const size_t room = events[i] ? ts.fresh[i][k].size() : 0;
                dst.resize(room + in.size());  // no fill: Event's constructor writes nothing
                kept_at[i] = dst.data() + room;
            }
            // Both outputs are written every time and the counters decide what is kept, so
            // the loop has no branch and no store-to-load chain through a pointer table.
            Event* const fl = kept_at[0];
            Event* const fr = kept_at[1];
            size_t il = 0, ir = 0;
            // A large node's route table is larger than the cache and the events reach it in
            // position order, i.e. at random: its entries are fetched kRouteAhead events early.
            const size_t m = in.size();
            const size_t ahead = n >= kPrefetchRoutes ? kRouteAhead : 0;
            for (size_t j = 0; j < m; ++j) {
                const Event& e = in[j];
                if (ahead != 0 && j + ahead < m) __builtin_prefetch(&route[in[j + ahead].slot()]);
                const Route& r = route[e.slot()];
                const uint32_t keep = r.keep[k] >> e.type();
                fl[il] = e.with_slot(r.slot[0]);
                fr[ir] = e.with_slot(r.slot[1]);
                il += keep & 1;
                ir += keep >> 3 & 1;
            }
            const size_t kept[2] = {il, ir};
            for (int i = 0; i < 2; ++i) {
                if (!events[i]) continue;
                const std::vector<Event>& fresh = ts.fresh[i][k];
                std::vector<Event>& dst = child[i]->events[k];
                merge_events(kept_at[i], kept[i], fresh.data(), fresh.size(), dst.data());
                dst.resize(fresh.size() + kept[i]);
            }
        };
        run_tasks(3, n >= kParallelSplit, axis_events);
        release(std::move(wp));
        return {std::move(lp), std::move(rp), false};
    }

    /// A triangle's corners side by side: one or two cache lines, where the mesh's index
    /// and vertex arrays cost two to four.
    struct Corners {
        Vec3 v[3];
    };

    const KdTreeBuilder::Config& c_;
    const int max_depth_;
    const uint32_t small_;  // nodes of at most this many triangles keep no events
    const bool avx2_ = use_avx2(c_.use_avx2);
    std::vector<Corners> corners_;
    const bool parallel_;  // whether the root's setup runs as parallel tasks
    mutable tbb::enumerable_thread_specific<ThreadState> state_;
    std::atomic<uint64_t> frag_tris_{0}, frag_nodes_{0}, frag_refs_{0};  // for reserving fragments
};

}  // namespace
}  // namespace bvhlab::accel::kd

namespace bvhlab::accel {

std::string kd_config_problem(const KdTreeBuilder::Config& c) {
    for (const std::string& p : {range_problem("kd_ct", c.traversal_cost, 0.001f, 1e6f),
                                 range_problem("kd_ci", c.intersection_cost, 0.001f, 1e6f),
                                 range_problem("kd_bonus", c.empty_bonus, 0.0f, 0.99f),
                                 range_problem("kd_max_depth", c.max_depth, -1, int(kMaxTreeDepth))})
        if (!p.empty()) return p;
    return "";
}

int KdTreeBuilder::max_depth_for(size_t n) const {
    if (config_.max_depth >= 0) return std::min(config_.max_depth, int(kMaxTreeDepth));
    return std::min(int(kMaxTreeDepth), int(8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1)))));
}

KdTree KdTreeBuilder::build(const scene::TriangleMesh& mesh) const {
    BVHLAB_CHECK(mesh.triangle_count() > 0, "cannot build a kd-tree over zero triangles");
    BVHLAB_CHECK(mesh.triangle_count() <= kd::kSlotMask, "too many triangles for the kd-tree builder");
    BVHLAB_CHECK(config_.traversal_cost > 0 && config_.intersection_cost > 0, "kd-tree costs must be positive");
    BVHLAB_CHECK(config_.small_node_size <= kMaxSmallNodeSize,
                 "kd-tree small_node_size must be at most " + std::to_string(kMaxSmallNodeSize));
    BVHLAB_CHECK(config_.empty_bonus >= 0 && config_.empty_bonus < 1, "the empty-space bonus must be in [0, 1)");
    AABB bounds;
    std::unique_ptr<kd::TopNode> tree;
    {
        kd::Recursion rec(config_, mesh, max_depth_for(mesh.triangle_count()));
        std::unique_ptr<kd::Work> root = rec.root();
        bounds = root->voxel;
        tree = rec.build_top(std::move(root), 0);
    }
    // The recursion's buffers (the corners, the pooled arrays of the top levels' nodes, the
    // sweep records; on furball ~0.5 GB) are freed before flatten() touches the final arrays,
    // so that the OS can hand their just-freed pages back: on this VM a page the host already
    // backs faults in ~2 us, a new one in ~10 us (experiments/NOTES.md, session 7).
    KdTree out = kd::flatten(*tree, bounds);
    destroy_iteratively(std::move(tree));
    return out;
}

}  // namespace bvhlab::accel
