// SPDX-License-Identifier: MIT
// Probe: where a GPU builder's trees lose their trace speed, top or bottom. Hybrid hierarchies
// of one scene, each with the GPU builders' leaf choice (accel::tree_from_hierarchy), beside the
// binned SAH build; the CPU tracer's node visits and triangle tests per ray (framing camera,
// primary and diffuse rays), as experiments/probes/ploc_quality.cpp reports them.
//  - binned>K + B: the binned SAH tree's nodes of more than K triangles (the same splits as the
//    full binned build), each node of at most K below them rebuilt by B (lbvh, ploc r8, or the
//    LBVH with Morton codes of the whole scene: lbvhg);
//  - A>K + B: hierarchy A (lbvh or ploc r8) down to its subtrees of at most K triangles,
//    each rebuilt by B (the binned SAH build, ploc r8, or binned SAH down to 512 and ploc r8 below);
//  - chunkK / chunkuK / lbvhcK + binned: clusters of at most K triangles that the top cannot cut
//    (K after one another in the Morton order, or the LBVH's largest subtrees of at most K),
//    binned SAH over the clusters (weighted by their triangle counts; chunku: unweighted), the
//    binned SAH build inside each: what binning clusters in place of triangles would give;
//  - ploccK / ploccpK + B: PLOC r8's largest subtrees of at most K triangles as the clusters (PLOC
//    set), binned SAH or PLOC inside each; plocaA / plocauA + binned: PLOC's subtrees of at most 16
//    whose every merge was nearly free (its area at most A% of the larger child's; plocau
//    unweighted); warpaA + binned: gpu-binned's clusters at alpha A% (accel::triangle_clusters;
//    UNWEIGHTED set: every cluster weighs 1, as gpu-binned bins them).
// Usage: hybrid_quality SCENE.obj|soup [K ...]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/core/binning.h"
#include "probe_trees.h"

using namespace bvhlab;

static probe::RaySets g_rays;

static void report(const std::string& name, const accel::BuildTree& t, const scene::TriangleMesh& m,
                   const accel::BuildConfig& c) {
    probe::print_tree(name, 22, t, m, c, g_rays);
}

/// A hierarchy under construction: leaves hold a triangle, interior nodes two children.
struct Gen {
    struct Node {
        int32_t left = -1, right = -1;
        uint32_t tri = 0;
    };
    std::vector<Node> nodes;

    uint32_t leaf(uint32_t tri) {
        nodes.push_back({-1, -1, tri});
        return uint32_t(nodes.size() - 1);
    }
    uint32_t inner(uint32_t a, uint32_t b) {
        nodes.push_back({int32_t(a), int32_t(b), 0});
        return uint32_t(nodes.size() - 1);
    }
    /// Grafts hierarchy h over local triangle ids, ids[k] being local triangle k's id.
    uint32_t graft(const accel::RawHierarchy& h, const std::vector<uint32_t>& ids) {
        const uint32_t n = uint32_t(h.sorted_ids.size());
        std::function<uint32_t(uint32_t)> go = [&](uint32_t x) -> uint32_t {
            if (x < n) return leaf(ids[h.sorted_ids[x]]);
            const uint32_t a = go(h.left[x - n]);
            const uint32_t b = go(h.right[x - n]);
            return inner(a, b);
        };
        return go(h.root);
    }
    /// Grafts BuildTree t over local triangle ids (ids[k]: local triangle k's id; empty: t's ids
    /// are the mesh's), each leaf's ids (left to right) becoming leaf_of(them).
    template <typename LeafOf>
    uint32_t graft(const accel::BuildTree& t, const std::vector<uint32_t>& ids, LeafOf&& leaf_of) {
        std::function<uint32_t(uint32_t)> go = [&](uint32_t x) -> uint32_t {
            const accel::BuildNode& d = t.nodes[x];
            if (d.is_leaf()) {
                std::vector<uint32_t> l;
                for (uint32_t i = 0; i < d.prim_count; ++i) {
                    const uint32_t k = t.prim_indices[d.first_index + i];
                    l.push_back(ids.empty() ? k : ids[k]);
                }
                return leaf_of(l);
            }
            const uint32_t a = go(d.first_index);
            const uint32_t b = go(d.first_index + 1);
            return inner(a, b);
        };
        return go(0);
    }
    /// A chain over ids (for leaves that could not be split).
    uint32_t chain(const std::vector<uint32_t>& ids) {
        uint32_t r = leaf(ids[0]);
        for (size_t i = 1; i < ids.size(); ++i) r = inner(r, leaf(ids[i]));
        return r;
    }
    /// The RawHierarchy: leaves numbered left to right, boxes fitted.
    accel::RawHierarchy raw(uint32_t root, const scene::TriangleMesh& m) const {
        accel::RawHierarchy h;
        uint32_t n = 0;
        for (const auto& x : nodes) n += x.left < 0 ? 1 : 0;
        h.sorted_ids.reserve(n);
        h.left.resize(n - 1);
        h.right.resize(n - 1);
        h.boxes.resize(2 * size_t(n) - 1);
        uint32_t next_inner = 0;
        std::function<uint32_t(uint32_t)> go = [&](uint32_t x) -> uint32_t {
            const Node& d = nodes[x];
            if (d.left < 0) {
                const uint32_t id = uint32_t(h.sorted_ids.size());
                h.sorted_ids.push_back(d.tri);
                AABB b = AABB::empty();
                for (int v = 0; v < 3; ++v) b.extend(m.vertices[m.indices[3 * size_t(d.tri) + v]]);
                h.boxes[id] = b;
                return id;
            }
            const uint32_t me = next_inner++;
            const uint32_t a = go(uint32_t(d.left));
            const uint32_t b = go(uint32_t(d.right));
            h.left[me] = a;
            h.right[me] = b;
            h.boxes[n + me] = merge(h.boxes[a], h.boxes[b]);
            return n + me;
        };
        h.root = go(root);
        return h;
    }
};

static scene::TriangleMesh sub_mesh(const scene::TriangleMesh& m, const std::vector<uint32_t>& ids) {
    scene::TriangleMesh s;
    s.vertices.reserve(3 * ids.size());
    for (uint32_t t : ids) {
        for (int v = 0; v < 3; ++v) {
            s.indices.push_back(uint32_t(s.vertices.size()));
            s.vertices.push_back(m.vertices[m.indices[3 * size_t(t) + v]]);
        }
        s.material_ids.push_back(-1);
    }
    return s;
}

using Bottom = std::function<uint32_t(Gen&, const std::vector<uint32_t>&)>;

static Bottom bottom_of(const std::string& b, const scene::TriangleMesh& m, const std::vector<uint64_t>& global_keys) {
    if (b == "binned") {
        return [&m](Gen& g, const std::vector<uint32_t>& ids) -> uint32_t {
            if (ids.size() == 1) return g.leaf(ids[0]);
            accel::BuilderOptions o;
            o.config.max_leaf_size = 1;
            const scene::TriangleMesh s = sub_mesh(m, ids);
            const accel::BuildTree t = accel::run_builder(accel::BuilderKind::kBinned, s, o).tree;
            return g.graft(t, ids, [&g](const std::vector<uint32_t>& l) { return g.chain(l); });
        };
    }
    if (b == "lbvhg") {
        // The LBVH over the ids' global Morton codes (what one sort of the whole scene gives).
        return [&global_keys](Gen& g, const std::vector<uint32_t>& ids) -> uint32_t {
            if (ids.size() == 1) return g.leaf(ids[0]);
            std::vector<std::pair<uint64_t, uint32_t>> k;
            for (uint32_t t : ids) k.push_back({global_keys[t], t});
            std::sort(k.begin(), k.end());
            std::vector<uint64_t> keys;
            for (size_t i = 0; i < k.size(); ++i) keys.push_back((k[i].first << 20) | i);  // distinct
            accel::RawHierarchy h = accel::radix_tree(keys);
            std::vector<uint32_t> sorted(k.size());
            for (size_t i = 0; i < k.size(); ++i) {
                h.sorted_ids.push_back(uint32_t(i));
                sorted[i] = k[i].second;
            }
            return g.graft(h, sorted);
        };
    }
    if (b == "binned512+ploc") {
        // Binned SAH down to nodes of at most 512 triangles, PLOC r8 below them.
        return [&m](Gen& g, const std::vector<uint32_t>& ids) -> uint32_t {
            if (ids.size() <= 512) {
                if (ids.size() == 1) return g.leaf(ids[0]);
                return g.graft(accel::ploc_reference(sub_mesh(m, ids), 30, 8), ids);
            }
            accel::BuilderOptions o;
            o.config.min_leaf_size = o.config.max_leaf_size = 512;
            const accel::BuildTree t = accel::run_builder(accel::BuilderKind::kBinned, sub_mesh(m, ids), o).tree;
            return g.graft(t, ids, [&](const std::vector<uint32_t>& l) {
                if (l.size() == 1) return g.leaf(l[0]);
                return g.graft(accel::ploc_reference(sub_mesh(m, l), 30, 8), l);
            });
        };
    }
    const bool ploc = b == "ploc";
    return [&m, ploc](Gen& g, const std::vector<uint32_t>& ids) -> uint32_t {
        if (ids.size() == 1) return g.leaf(ids[0]);
        const scene::TriangleMesh s = sub_mesh(m, ids);
        return g.graft(ploc ? accel::ploc_reference(s, 30, 8) : accel::lbvh_reference(s, 30), ids);
    };
}

/// Walks hierarchy h down to its largest subtrees that `whole(node, its triangle count)` keeps
/// whole: each becomes at(its triangles' ids, left to right), and every node above them
/// join(left's result, right's).
template <typename At, typename Join>
static uint32_t cut_hierarchy_if(const accel::RawHierarchy& h, const std::function<bool(uint32_t, uint32_t)>& whole,
                                 At&& at, Join&& join) {
    const uint32_t n = uint32_t(h.sorted_ids.size());
    std::vector<uint32_t> count(h.boxes.size(), 1);
    std::function<uint32_t(uint32_t)> cnt = [&](uint32_t x) -> uint32_t {
        if (x < n) return 1;
        return count[x] = cnt(h.left[x - n]) + cnt(h.right[x - n]);
    };
    cnt(h.root);
    std::function<void(uint32_t, std::vector<uint32_t>&)> collect = [&](uint32_t x, std::vector<uint32_t>& l) {
        if (x < n) {
            l.push_back(h.sorted_ids[x]);
            return;
        }
        collect(h.left[x - n], l);
        collect(h.right[x - n], l);
    };
    std::function<uint32_t(uint32_t)> go = [&](uint32_t x) -> uint32_t {
        if (x < n || whole(x, count[x])) {
            std::vector<uint32_t> l;
            collect(x, l);
            return at(l);
        }
        const uint32_t p = go(h.left[x - n]);
        const uint32_t q = go(h.right[x - n]);
        return join(p, q);
    };
    return go(h.root);
}

/// cut_hierarchy_if at the largest subtrees of at most k triangles.
template <typename At, typename Join>
static uint32_t cut_hierarchy(const accel::RawHierarchy& h, uint32_t k, At&& at, Join&& join) {
    return cut_hierarchy_if(
        h, [k](uint32_t, uint32_t count) { return count <= k; }, at, join);
}

/// A cluster of triangles that the top of a hierarchy cannot cut: its box, how many triangles it
/// holds, and their ids.
struct Cluster {
    AABB box;
    uint32_t weight = 0;
    std::vector<uint32_t> ids;
};

/// Binned SAH over clusters (the library's 32-bin mapping and sweep; at 16 or fewer an exact
/// sweep, each cluster its own bin in centre order), each cluster weighted by its triangle count
/// (or 1: `weighted` false), each cluster's own subtree made by `bottom`. What a GPU builder that
/// bins clusters in place of triangles would make.
static uint32_t binned_clusters(Gen& g, const std::vector<uint32_t>& items, const std::vector<Cluster>& cl,
                                bool weighted, const Bottom& bottom) {
    const size_t n = items.size();
    if (n == 1) return bottom(g, cl[items[0]].ids);
    const auto bin_of = [&](uint32_t i) { return accel::Bin{cl[i].box, weighted ? cl[i].weight : 1u}; };
    AABB cb = AABB::empty();
    for (uint32_t i : items) cb.extend(cl[i].box.center());
    const accel::BinMapping map(cb, 32);
    float best = std::numeric_limits<float>::infinity();
    std::vector<uint32_t> left, right;
    for (int a = 0; a < 3; ++a) {
        if (!map.splittable(a)) continue;
        std::vector<uint32_t> order = items;
        std::vector<accel::Bin> bins;
        if (n <= 16) {
            std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
                const float cx = cl[x].box.center()[a], cy = cl[y].box.center()[a];
                return cx < cy || (cx == cy && x < y);
            });
            for (uint32_t i : order) bins.push_back(bin_of(i));
        } else {
            bins.assign(size_t(map.num_bins), accel::Bin::empty());
            for (uint32_t i : items) {
                accel::Bin& b = bins[size_t(map.bin(cl[i].box.center()[a], a))];
                b.bounds.extend(cl[i].box);
                b.count += bin_of(i).count;
            }
        }
        const accel::BinSweep sw = accel::sweep_bins(bins.data(), int(bins.size()));
        if (!(sw.weight < best)) continue;
        best = sw.weight;
        left.clear();
        right.clear();
        for (size_t k = 0; k < n; ++k) {
            const uint32_t i = order[k];
            const int at = n <= 16 ? int(k) : map.bin(cl[i].box.center()[a], a);
            (at <= sw.bin ? left : right).push_back(i);
        }
    }
    if (left.empty() || right.empty()) {  // every centre in one place: halves of the list
        left.assign(items.begin(), items.begin() + long(n / 2));
        right.assign(items.begin() + long(n / 2), items.end());
    }
    const uint32_t p = binned_clusters(g, left, cl, weighted, bottom);
    const uint32_t q = binned_clusters(g, right, cl, weighted, bottom);
    return g.inner(p, q);
}

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const scene::TriangleMesh mesh = probe::load_mesh(argv[1]);
    g_rays = probe::framing_rays(mesh);
    std::vector<uint32_t> ks;
    for (int i = 2; i < argc; ++i) ks.push_back(uint32_t(std::atoi(argv[i])));
    if (ks.empty()) ks = {64, 512, 4096, 32768};
    const char* only = std::getenv("ONLY");  // a substring of the variants to run
    const auto want = [&](const std::string& name) { return !only || name.find(only) != std::string::npos; };
    const uint32_t n = uint32_t(mesh.triangle_count());
    accel::BuildConfig c;
    accel::BuilderOptions full;
    if (want("binned")) report("binned", accel::run_builder(accel::BuilderKind::kBinned, mesh, full).tree, mesh, c);
    const accel::RawHierarchy lbvh = accel::lbvh_reference(mesh, 30);
    std::vector<uint64_t> global_keys(n);
    for (uint32_t i = 0; i < n; ++i) global_keys[lbvh.sorted_ids[i]] = lbvh.keys[i];
    if (want("lbvh")) report("lbvh", accel::tree_from_hierarchy(lbvh, c), mesh, c);
    const bool with_ploc = std::getenv("PLOC") != nullptr;
    accel::RawHierarchy ploc;
    if (with_ploc) {
        ploc = accel::ploc_reference(mesh, 30, 8);
        report("ploc r8", accel::tree_from_hierarchy(ploc, c), mesh, c);
    }
    for (uint32_t k : ks) {
        // The binned tree cut at k: nodes of more than k triangles split as in the full build.
        accel::BuilderOptions top;
        top.config.min_leaf_size = k;
        top.config.max_leaf_size = k;
        const accel::BuildTree t = accel::run_builder(accel::BuilderKind::kBinned, mesh, top).tree;
        for (const std::string b : {"lbvh", "lbvhg", "ploc"}) {
            const std::string name = "binned>" + std::to_string(k) + " + " + b;
            if (!want(name)) continue;
            const Bottom bottom = bottom_of(b, mesh, global_keys);
            Gen g;
            const uint32_t root = g.graft(t, {}, [&](const std::vector<uint32_t>& l) { return bottom(g, l); });
            report(name, accel::tree_from_hierarchy(g.raw(root, mesh), c), mesh, c);
        }
        // Hierarchy A down to its subtrees of at most k triangles, each rebuilt by binned SAH.
        for (const std::string a : {"lbvh", "ploc"})
            for (const std::string bn : {"binned", "ploc", "binned512+ploc"}) {
                const std::string name = a + ">" + std::to_string(k) + " + " + bn;
                if (!want(name) || (a == "ploc" && !with_ploc) || a == bn) continue;
                const accel::RawHierarchy& h = a == "lbvh" ? lbvh : ploc;
                const Bottom bottom = bottom_of(bn, mesh, global_keys);
                Gen g;
                const uint32_t root = cut_hierarchy(
                    h, k, [&](const std::vector<uint32_t>& l) { return bottom(g, l); },
                    [&](uint32_t p, uint32_t q) { return g.inner(p, q); });
                report(name, accel::tree_from_hierarchy(g.raw(root, mesh), c), mesh, c);
            }
    }
    // Clusters of k triangles that the top cannot cut, binned SAH over them, binned inside each:
    //  - chunk: k triangles after one another in the scene's Morton order (weighted by count);
    //  - chunku: the same, every cluster weighing 1;
    //  - lbvhc: the LBVH's largest subtrees of at most k triangles;
    //  - plocc: PLOC r8's largest subtrees of at most k triangles (PLOC set), each cluster's own
    //    subtree made by binned SAH or by PLOC again (what H-PLOC stopped at k would hand over).
    for (uint32_t k : ks)
        for (const std::string kind : {"chunk", "chunku", "lbvhc", "plocc", "ploccp", "ploca", "plocau", "warpa"}) {
            const std::string name = kind + std::to_string(k) + (kind == "ploccp" ? " + ploc" : " + binned");
            if (!want(name) || (k > 256 && kind.rfind("ploca", 0) != 0 && kind != "warpa") ||
                (kind.rfind("ploc", 0) == 0 && !with_ploc))
                continue;
            std::vector<Cluster> cl;
            const auto add = [&](const std::vector<uint32_t>& ids) {
                Cluster x;
                x.box = AABB::empty();
                for (uint32_t t : ids)
                    for (int v = 0; v < 3; ++v) x.box.extend(mesh.vertices[mesh.indices[3 * size_t(t) + v]]);
                x.weight = uint32_t(ids.size());
                x.ids = ids;
                cl.push_back(std::move(x));
            };
            if (kind == "warpa") {  // k: alpha in percent; gpu-binned's clusters (chunks of 32, at most 16)
                for (const auto& ids : accel::triangle_clusters(mesh, float(k) / 100.0f)) add(ids);
            } else if (kind == "chunk" || kind == "chunku") {
                for (uint32_t b = 0; b < n; b += k) {
                    std::vector<uint32_t> ids;
                    for (uint32_t i = b; i < std::min(n, b + k); ++i) ids.push_back(lbvh.sorted_ids[i]);
                    add(ids);
                }
            } else {
                // ploca: k is a percentage; a cluster is a subtree of at most 16 triangles whose
                // every merge was nearly free (the parent's area at most k% of its larger child's).
                std::vector<char> cheap;
                if (kind.rfind("ploca", 0) == 0) {
                    cheap.assign(ploc.boxes.size(), 1);
                    std::function<bool(uint32_t)> mark = [&](uint32_t x) -> bool {
                        if (x < n) return true;
                        const uint32_t l = ploc.left[x - n], r = ploc.right[x - n];
                        const bool a = mark(l), b = mark(r);
                        const float most = std::max(ploc.boxes[l].half_area(), ploc.boxes[r].half_area());
                        return cheap[x] = a && b && ploc.boxes[x].half_area() <= most * float(k) / 100.0f;
                    };
                    mark(ploc.root);
                }
                cut_hierarchy_if(
                    kind == "lbvhc" ? lbvh : ploc,
                    [&](uint32_t x, uint32_t count) {
                        return kind.rfind("ploca", 0) == 0 ? count <= 16 && cheap[x] : count <= k;
                    },
                    [&](const std::vector<uint32_t>& l) {
                        add(l);
                        return 0u;
                    },
                    [](uint32_t, uint32_t) { return 0u; });
            }
            std::vector<uint32_t> items(cl.size());
            for (uint32_t i = 0; i < items.size(); ++i) items[i] = i;
            const Bottom bottom = bottom_of(kind == "ploccp" ? "ploc" : "binned", mesh, global_keys);
            Gen g;
            const uint32_t root = binned_clusters(
                g, items, cl, kind != "chunku" && kind != "plocau" && !std::getenv("UNWEIGHTED"), bottom);
            std::printf("# %s: %zu clusters\n", name.c_str(), cl.size());
            report(name, accel::tree_from_hierarchy(g.raw(root, mesh), c), mesh, c);
        }
}
