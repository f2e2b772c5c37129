// SPDX-License-Identifier: MIT
#include "traversal/gpu/gpu_builder.h"

#include <algorithm>
#include <string>

#include "accel/core/check.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/two_level.h"
#include "scene/domain.h"

namespace bvhlab::trav {

GpuBuild build_on_gpu(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                      bool keep_raw) {
    const std::string name = accel::builder_name(kind);
    if (!accel::runs_on_gpu(kind)) throw Error("builder '" + name + "' runs on the CPU, not the GPU");
    std::string why;
    if (!gpu_available(&why)) throw Error("builder '" + name + "' runs on the GPU, and there is none: " + why);
    if (const std::string p = accel::options_problem(options); !p.empty()) throw Error(p);
    const size_t n = mesh.triangle_count();
    if (n == 0) throw Error("the mesh has no triangles to build a structure over");
    if (const std::string p = accel::bvh2_leaf_problem(options.config); !p.empty()) throw Error(p);
    if (n - 1 > accel::Bvh2Node::kMaxLeafFirst)
        throw Error("the BVH2 layout holds at most " + std::to_string(accel::Bvh2Node::kMaxLeafFirst + 1) +
                    " triangle references; the mesh has " + std::to_string(n));
    return detail::gpu_build(mesh, kind, options, keep_raw);
}

std::vector<GpuBuildTimes> time_gpu_builds(const scene::TriangleMesh& mesh, accel::BuilderKind kind,
                                           const accel::BuilderOptions& options, int runs, int warmup) {
    if (runs < 1 || warmup < 0) throw Error("time_gpu_builds needs runs >= 1 and warmup >= 0");
    std::vector<GpuBuildTimes> out;
    for (int k = 0; k < warmup + runs; ++k) {
        const GpuBuildTimes t = build_on_gpu(mesh, kind, options).times;
        if (k >= warmup) out.push_back(t);
    }
    return out;
}

GpuTlasBuilder::GpuTlasBuilder(const Structure& s) {
    if (s.layout != Layout::kTwoLevel)
        throw Error("a TLAS is rebuilt on the GPU for two-level BVH2 structures only, not " + s.name);
    std::string why;
    if (!gpu_available(&why)) throw Error("a TLAS rebuild runs on the GPU, and there is none: " + why);
    const accel::TwoLevelBvh& t = s.two_level;
    instances_ = t.instances.size();
    std::vector<uint32_t> blas_of(instances_), first_id(instances_), first{0};
    std::vector<AABB> frontier;
    for (size_t i = 0; i < instances_; ++i) {
        blas_of[i] = t.instances[i].blas;
        first_id[i] = t.instances[i].first_id;
    }
    for (const accel::Bvh2& b : t.blas) {
        if (!b.nodes.empty()) {
            const std::vector<AABB> f = accel::frontier_boxes(b);
            frontier.insert(frontier.end(), f.begin(), f.end());
        }
        first.push_back(uint32_t(frontier.size()));
    }
    blas_of_.upload(blas_of);
    first_id_.upload(first_id);
    frontier_first_.upload(first);
    frontier_.upload(frontier);
    device_ = std::make_shared<DeviceStructure>(s);
    tlas_nodes_ = t.tlas.nodes.size();
    tlas_depth_ = t.tlas.depth;
}

GpuBuildTimes GpuTlasBuilder::rebuild(const std::vector<scene::Transform>& object_to_world, accel::BuilderKind kind,
                                      const accel::BuilderOptions& options) {
    if (object_to_world.size() != instances_)
        throw Error("a TLAS rebuild needs one transform per instance: " + std::to_string(object_to_world.size()) +
                    " for " + std::to_string(instances_));
    if (!accel::runs_on_gpu(kind))
        throw Error("builder '" + std::string(accel::builder_name(kind)) + "' runs on the CPU, not the GPU");
    accel::BuilderOptions o = options;
    o.config.min_leaf_size = o.config.max_leaf_size = 1;  // one instance per leaf
    if (const std::string p = accel::options_problem(o); !p.empty()) throw Error(p);
    DeviceTimer upload;
    upload.start();
    DeviceBuffer<scene::Transform> transforms(object_to_world);
    const double upload_ms = upload.stop();
    // New records in a buffer of their own: the structure keeps its last TLAS and records if a
    // transform is bad.
    DeviceBuffer<accel::InstanceRecord> records(instances_);
    DeviceBuffer<uint32_t> bad(1);
    detail::fill_device_bytes(bad.data(), 0xff, bad.bytes());
    const detail::TlasInput in{transforms.data(), blas_of_.data(), first_id_.data(), frontier_first_.data(),
                               frontier_.data(),  records.data(),  bad.data()};
    GpuBuild g = detail::gpu_build_tlas(uint32_t(instances_), in, kind, o);
    uint32_t first_bad = 0;
    detail::copy_to_host(&first_bad, bad.data(), sizeof first_bad);
    if (first_bad != ~0u)
        throw Error("instance " + std::to_string(first_bad) +
                    " has a singular or non-finite transform, or a non-finite world box");
    tlas_nodes_ = g.node_count;
    tlas_depth_ = g.host.depth;
    device_->replace_tlas(std::move(g.nodes), std::move(g.tri_ids), std::move(records), tlas_depth_);
    g.times.upload_ms = upload_ms;
    return g.times;
}

accel::Bvh2 GpuTlasBuilder::download_tlas() const {
    accel::Bvh2 t;
    const Bvh2View v = device_->bvh2();  // a two-level structure's TLAS
    t.nodes.resize(tlas_nodes_);
    t.tri_ids.resize(instances_);
    detail::copy_to_host(t.nodes.data(), v.nodes, tlas_nodes_ * sizeof(accel::Bvh2Node));
    detail::copy_to_host(t.tri_ids.data(), v.tri_ids, instances_ * sizeof(uint32_t));
    t.depth = tlas_depth_;
    return t;
}

std::vector<accel::InstanceRecord> GpuTlasBuilder::download_instances() const {
    std::vector<accel::InstanceRecord> r(instances_);
    detail::copy_to_host(r.data(), device_->two_level().instances, instances_ * sizeof(accel::InstanceRecord));
    return r;
}

GpuRefitter::GpuRefitter(const Structure& s, const scene::TriangleMesh& mesh) {
    if (s.layout != Layout::kBvh2) throw Error("a refit on the GPU needs a single-level BVH2 structure, not " + s.name);
    std::string why;
    if (!gpu_available(&why)) throw Error("a refit runs on the GPU, and there is none: " + why);
    const accel::Bvh2& b = s.bvh2;
    for (uint32_t id : b.tri_ids)
        if (id >= mesh.triangle_count())
            throw Error("the structure names triangle " + std::to_string(id) + " and the mesh has " +
                        std::to_string(mesh.triangle_count()));
    std::vector<uint32_t> parents(b.nodes.size(), ~0u), leaves;
    for (size_t n = 0; n < b.nodes.size(); ++n) {
        const accel::Bvh2Node& node = b.nodes[n];
        for (int k = 0; k < 2; ++k) {
            if (node.child[k] >= 0)
                parents[size_t(node.child[k])] = uint32_t(n) << 1 | uint32_t(k);
            else if (k == 0 || node.child[1] != node.child[0])  // a root leaf's second slot repeats the first
                leaves.push_back(uint32_t(n) << 1 | uint32_t(k));
        }
    }
    vertex_count_ = mesh.vertices.size();
    node_count_ = b.nodes.size();
    tri_count_ = b.tri_ids.size();
    depth_ = b.depth;
    indices_.upload(mesh.indices);
    parents_.upload(parents);
    leaves_.upload(leaves);
    visits_.resize(node_count_);
    device_ = std::make_shared<DeviceStructure>(s);
}

GpuBuildTimes GpuRefitter::refit(const std::vector<Vec3>& vertices) {
    if (vertices.size() != vertex_count_)
        throw Error("a refit needs the mesh's " + std::to_string(vertex_count_) + " vertices, not " +
                    std::to_string(vertices.size()));
    for (size_t v = 0; v < vertices.size(); ++v)
        if (const std::string p = scene::vec_problem(("refit: vertex " + std::to_string(v)).c_str(), vertices[v]);
            !p.empty())
            throw Error(p);
    GpuBuildTimes t;
    DeviceTimer upload;
    upload.start();
    DeviceBuffer<Vec3> verts(vertices);
    t.upload_ms = upload.stop();
    detail::fill_device_bytes(visits_.data(), 0, visits_.bytes());
    const Bvh2View v = device_->bvh2();
    const detail::RefitInput in{verts.data(),
                                indices_.data(),
                                v.tri_ids,
                                parents_.data(),
                                leaves_.data(),
                                uint32_t(leaves_.size()),
                                uint32_t(tri_count_),
                                visits_.data(),
                                device_->bvh2_nodes_for_refit(),
                                device_->bvh2_tris_for_refit()};
    t.total_ms = detail::gpu_refit(in);
    t.hierarchy_ms = t.total_ms;
    return t;
}

accel::Bvh2 GpuRefitter::download() const {
    accel::Bvh2 b;
    const Bvh2View v = device_->bvh2();
    b.nodes.resize(node_count_);
    b.tris.resize(tri_count_);
    b.tri_ids.resize(tri_count_);
    detail::copy_to_host(b.nodes.data(), v.nodes, node_count_ * sizeof(accel::Bvh2Node));
    detail::copy_to_host(b.tris.data(), v.tris, tri_count_ * sizeof(accel::WoopTriangle));
    detail::copy_to_host(b.tri_ids.data(), v.tri_ids, tri_count_ * sizeof(uint32_t));
    b.depth = depth_;
    return b;
}

}  // namespace bvhlab::trav
