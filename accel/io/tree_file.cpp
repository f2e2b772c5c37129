// SPDX-License-Identifier: MIT
// Tree files: fixed little-endian header, the builder config, nodes, primitive indices and a
// trailing FNV-1a checksum of everything before it.
#include "accel/io/tree_file.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/io/atomic_file.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "tree files need a little-endian host");

namespace bvhlab::accel {
namespace {

/// Fixed header, 88 bytes.
struct Header {
    char magic[8];        // "BVHLTREE"
    uint32_t version;     // kTreeFileVersion
    uint32_t builder;     // BuilderKind, or kKdTreeCode
    uint64_t triangles;   // triangle count of the scene
    uint64_t scene_hash;  // scene_hash() as a number
    uint32_t num_bins, min_leaf, max_leaf, max_depth;
    float traversal_cost, intersection_cost, sbvh_alpha, sbvh_budget;
    uint64_t node_count;    // BuildNode records (32 bytes each) that follow
    uint64_t index_count;   // uint32 primitive indices that follow the nodes
    uint32_t spatial_bins;  // SBVH spatial bins
    uint32_t reinsertion;   // BVH files: reinsertion passes run after the build (was reserved, 0)
    // The GPU builders (lbvh, ploc, hploc, gpu-binned) have no bin option: num_bins holds their Morton bits,
    // spatial_bins H-PLOC's search radius and sbvh_alpha gpu-binned's cluster alpha.
};
static_assert(sizeof(Header) == 88, "tree file header is 88 bytes");

constexpr uint32_t kKdTreeCode = 3;  // builder field of kd-tree files

/// Header, node records, indices, checksum; shared by BVH and kd-tree files.
template <typename Node>
void write_file(const std::string& path, Header h, const std::vector<Node>& nodes,
                const std::vector<uint32_t>& indices) {
    std::memcpy(h.magic, "BVHLTREE", 8);
    h.version = kTreeFileVersion;
    h.node_count = nodes.size();
    h.index_count = indices.size();
    uint64_t sum = fnv1a(&h, sizeof h);
    sum = fnv1a(nodes.data(), nodes.size() * sizeof(Node), sum);
    sum = fnv1a(indices.data(), indices.size() * sizeof(uint32_t), sum);
    scene::write_file_atomically(path, [&](std::FILE* f) {
        std::fwrite(&h, sizeof h, 1, f);
        if (!nodes.empty()) std::fwrite(nodes.data(), sizeof(Node), nodes.size(), f);
        if (!indices.empty()) std::fwrite(indices.data(), sizeof(uint32_t), indices.size(), f);
        std::fwrite(&sum, sizeof sum, 1, f);
    });
}

Header provenance(const TreeFileMeta& meta) {
    Header h{};
    h.triangles = meta.triangles;
    h.scene_hash = hash_from_hex(meta.scene_hash);
    return h;
}

}  // namespace

std::string describe_config(BuilderKind kind, const BuilderOptions& o) {
    std::ostringstream s;
    s << builder_name(kind) << " leaf=" << o.config.min_leaf_size << ".." << o.config.max_leaf_size
      << " max_depth=" << o.config.max_depth << " Ct=" << o.config.traversal_cost
      << " Ci=" << o.config.intersection_cost;
    if (runs_on_gpu(kind)) {
        if (uses_morton(kind)) s << " morton=" << o.morton_bits;
        if (kind == BuilderKind::kGpuBinned) s << " bins=32";
        if (uses_radius(kind)) s << " radius=" << o.ploc_radius;
        if (uses_clusters(kind) && o.cluster_alpha > 0.0f) s << " clusters=" << o.cluster_alpha;  // older records: off
        if (const int r = reinsertion_passes(kind, o); r > 0) s << " reinsert=" << r;  // older records have none
        return s.str();
    }
    if (kind != BuilderKind::kSweep) s << " bins=" << o.num_bins;
    if (kind == BuilderKind::kSbvh)
        s << " alpha=" << o.sbvh_alpha << " budget=" << o.sbvh_budget << " spatial_bins=" << o.sbvh_spatial_bins;
    s << " reinsert=" << reinsertion_passes(kind, o);
    return s.str();
}

void write_tree_file(const std::string& path, const BuildTree& tree, const TreeFileMeta& meta) {
    Header h = provenance(meta);
    h.builder = uint32_t(meta.builder);
    const BuildConfig& c = meta.options.config;
    h.num_bins = uint32_t(meta.options.num_bins);
    h.min_leaf = c.min_leaf_size;
    h.max_leaf = c.max_leaf_size;
    h.max_depth = c.max_depth;
    h.traversal_cost = c.traversal_cost;
    h.intersection_cost = c.intersection_cost;
    h.sbvh_alpha = meta.options.sbvh_alpha;
    h.sbvh_budget = meta.options.sbvh_budget;
    h.spatial_bins = uint32_t(meta.options.sbvh_spatial_bins);
    h.reinsertion = uint32_t(reinsertion_passes(meta.builder, meta.options));
    if (runs_on_gpu(meta.builder)) {
        h.num_bins = uint32_t(meta.options.morton_bits);
        h.spatial_bins = uint32_t(meta.options.ploc_radius);
        h.sbvh_alpha = meta.options.cluster_alpha;
    }
    write_file(path, h, tree.nodes, tree.prim_indices);
}

void write_kd_file(const std::string& path, const KdTree& tree, const TreeFileMeta& meta) {
    BVHLAB_CHECK(meta.kdtree, "write_kd_file needs kd-tree metadata");
    Header h = provenance(meta);
    h.builder = kKdTreeCode;
    // kd-tree files reuse the cost fields for the kd constants and alpha's for the bonus.
    h.traversal_cost = meta.kd.traversal_cost;
    h.intersection_cost = meta.kd.intersection_cost;
    h.sbvh_alpha = meta.kd.empty_bonus;
    h.max_depth = uint32_t(meta.kd.max_depth);
    write_file(path, h, tree.nodes, tree.prim_indices);
}

TreeFile read_tree_file(const std::string& path) {
    if (std::filesystem::is_directory(path)) throw Error("'" + path + "' is a folder, not a structure file");
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw Error("cannot open structure file '" + path + "': " + std::strerror(errno));
    const auto size = uint64_t(in.tellg());
    in.seekg(0);
    Header h{};
    if (size < sizeof h || !in.read(reinterpret_cast<char*>(&h), sizeof h))
        throw Error("structure file '" + path + "' is truncated: shorter than its 88-byte header");
    if (std::memcmp(h.magic, "BVHLTREE", 8) != 0)
        throw Error("'" + path + "' is not a bvhlab structure file (magic is not BVHLTREE)");
    if (h.version != kTreeFileVersion)
        throw Error("structure file '" + path + "' has version " + std::to_string(h.version) +
                    "; this build reads version " + std::to_string(kTreeFileVersion));
    const uint32_t b = h.builder;
    if (b != uint32_t(BuilderKind::kBinned) && b != uint32_t(BuilderKind::kSweep) &&
        b != uint32_t(BuilderKind::kSbvh) && b != uint32_t(BuilderKind::kLbvh) && b != uint32_t(BuilderKind::kPloc) &&
        b != uint32_t(BuilderKind::kHploc) && b != uint32_t(BuilderKind::kGpuBinned) && b != kKdTreeCode)
        throw Error("structure file '" + path + "' names an unknown builder (" + std::to_string(h.builder) + ")");
    const bool kd = h.builder == kKdTreeCode;
    const uint64_t node_bytes = kd ? sizeof(KdNode) : sizeof(BuildNode);
    // The counts are checked by division before any product, so that a forged count near 2^64
    // cannot wrap the expected size (or the message), and before anything is allocated.
    const uint64_t body = size >= sizeof h + 8 ? size - sizeof h - 8 : 0;
    if (h.node_count > body / node_bytes || h.index_count > (body - h.node_count * node_bytes) / 4)
        throw Error("structure file '" + path + "' is truncated or damaged: its header claims " +
                    std::to_string(h.node_count) + " nodes and " + std::to_string(h.index_count) +
                    " indices, more than its " + std::to_string(size) + " bytes hold");
    const uint64_t expect = sizeof h + h.node_count * node_bytes + h.index_count * 4 + 8;
    if (size != expect)
        throw Error("structure file '" + path + "' is truncated or has trailing bytes: expected " +
                    std::to_string(expect) + " bytes, found " + std::to_string(size));
    TreeFile f;
    void* nodes = nullptr;
    std::vector<uint32_t>& indices = kd ? f.kd.prim_indices : f.tree.prim_indices;
    if (kd) {
        f.kd.nodes.resize(h.node_count);
        nodes = f.kd.nodes.data();
    } else {
        f.tree.nodes.resize(h.node_count);
        nodes = f.tree.nodes.data();
    }
    indices.resize(h.index_count);
    uint64_t stored = 0;
    in.read(static_cast<char*>(nodes), std::streamsize(h.node_count * node_bytes));
    in.read(reinterpret_cast<char*>(indices.data()), std::streamsize(h.index_count * 4));
    in.read(reinterpret_cast<char*>(&stored), sizeof stored);
    if (!in) throw Error("cannot read structure file '" + path + "'");
    uint64_t sum = fnv1a(&h, sizeof h);
    sum = fnv1a(nodes, h.node_count * node_bytes, sum);
    sum = fnv1a(indices.data(), indices.size() * 4, sum);
    if (sum != stored) throw Error("structure file '" + path + "' is corrupt: checksum mismatch");
    if (kd) {
        f.meta.kdtree = true;
        f.meta.kd.traversal_cost = h.traversal_cost;
        f.meta.kd.intersection_cost = h.intersection_cost;
        f.meta.kd.empty_bonus = h.sbvh_alpha;
        f.meta.kd.max_depth = int(h.max_depth);
    }
    f.meta.builder = BuilderKind(h.builder);
    f.meta.triangles = h.triangles;
    f.meta.scene_hash = hash_hex(h.scene_hash);
    BuilderOptions& o = f.meta.options;
    o.num_bins = int(h.num_bins);
    o.config.min_leaf_size = h.min_leaf;
    o.config.max_leaf_size = h.max_leaf;
    o.config.max_depth = h.max_depth;
    o.config.traversal_cost = h.traversal_cost;
    o.config.intersection_cost = h.intersection_cost;
    o.sbvh_alpha = h.sbvh_alpha;
    o.sbvh_budget = h.sbvh_budget;
    o.sbvh_spatial_bins = int(h.spatial_bins);
    o.reinsertion_passes = int(h.reinsertion);
    if (!kd && runs_on_gpu(f.meta.builder)) {
        o.morton_bits = int(h.num_bins);
        o.ploc_radius = int(h.spatial_bins);
        // gpu-binned's cluster alpha, in SBVH alpha's field: files written before it hold SBVH's
        // default there (below 1: off), as the other GPU builders' do.
        o.cluster_alpha = uses_clusters(f.meta.builder) && h.sbvh_alpha >= 1.0f ? h.sbvh_alpha : 0.0f;
        o.sbvh_alpha = BuilderOptions{}.sbvh_alpha;
        o.num_bins = BuilderOptions{}.num_bins;
        o.sbvh_spatial_bins = BuilderOptions{}.sbvh_spatial_bins;
    }
    // The header's configuration is shown and reused as it is (a NaN Ct printed "SAH nan", a
    // max depth of 0 "depth 9 of 0"): the ranges a build accepts.
    if (const std::string bad = kd ? kd_config_problem(f.meta.kd) : options_problem(o); !bad.empty())
        throw Error("structure file '" + path + "' has a header value out of range: " + bad);
    return f;
}

std::string describe_config(const TreeFileMeta& meta) {
    if (!meta.kdtree) return describe_config(meta.builder, meta.options);
    std::ostringstream s;
    s << "kdtree Ct=" << meta.kd.traversal_cost << " Ci=" << meta.kd.intersection_cost
      << " empty_bonus=" << meta.kd.empty_bonus << " max_depth=" << meta.kd.max_depth;
    return s.str();
}

std::string stale_reason(const TreeFileMeta& meta, uint64_t triangles, const std::string& scene_hash) {
    if (meta.triangles != triangles || meta.scene_hash != scene_hash)
        return "it was built over other triangles (" + std::to_string(meta.triangles) + " triangles, hash " +
               meta.scene_hash + "; this scene has " + std::to_string(triangles) + ", hash " + scene_hash + ")";
    return {};
}

}  // namespace bvhlab::accel
