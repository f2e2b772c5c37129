// SPDX-License-Identifier: MIT
#include "traversal/oracle/embree_oracle.h"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "accel/core/check.h"

namespace bvhlab::trav {

struct EmbreeOracle::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<RTCScene> mesh_scenes;  // an instanced scene's meshes, each its own Embree scene
    std::vector<uint32_t> first_ids;    // an instanced scene: scene-wide id of each instance's triangle 0
    std::string error;                  // first error Embree reported through the callback

    /// Our hit of Embree's (instance, primitive): the scene-wide id (TwoLevelBvh's numbering).
    Hit hit(unsigned inst, unsigned prim, float t, float u, float v) const {
        const uint32_t base = first_ids.empty() ? 0u : first_ids[inst];
        return {int32_t(base + prim), t, u, v};
    }
    /// A new scene in robust mode: watertight triangle tests, no precision-for-speed shortcuts.
    RTCScene new_scene() const {
        RTCScene s = rtcNewScene(device);
        rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
        return s;
    }
    /// Attaches `mesh` to `scene` as one triangle geometry (triangle ids = primIDs).
    void attach(RTCScene scene, const scene::TriangleMesh& mesh) const {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const size_t nv = mesh.vertices.size(), nt = mesh.triangle_count();
        // Embree reads vertex buffers with 16-byte loads, so pad the last vertex.
        auto* v = static_cast<float*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv + 1));
        auto* idx = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
        if (v && idx) {
            std::memcpy(v, mesh.vertices.data(), nv * sizeof(Vec3));
            std::memcpy(idx, mesh.indices.data(), nt * 3 * sizeof(unsigned));
            rtcCommitGeometry(geom);
            rtcAttachGeometry(scene, geom);
        }
        rtcReleaseGeometry(geom);
    }
};

namespace {

void on_error(void* user, RTCError code, const char* str) {
    auto* impl = static_cast<EmbreeOracle::Impl*>(user);
    if (impl->error.empty()) impl->error = "Embree error " + std::to_string(int(code)) + ": " + (str ? str : "");
}

RTCRay to_rtc(const Ray& r) {
    RTCRay x;
    x.org_x = r.org.x;
    x.org_y = r.org.y;
    x.org_z = r.org.z;
    x.tnear = r.tmin;
    x.dir_x = r.dir.x;
    x.dir_y = r.dir.y;
    x.dir_z = r.dir.z;
    x.time = 0.0f;
    x.tfar = r.tmax;
    x.mask = ~0u;
    x.id = 0;
    x.flags = 0;
    return x;
}

}  // namespace

EmbreeOracle::EmbreeOracle(const scene::TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
    impl_->device = rtcNewDevice(nullptr);
    BVHLAB_CHECK(impl_->device != nullptr, "rtcNewDevice failed");
    rtcSetDeviceErrorFunction(impl_->device, on_error, impl_.get());
    impl_->scene = impl_->new_scene();
    impl_->attach(impl_->scene, mesh);
    rtcCommitScene(impl_->scene);
    if (!impl_->error.empty()) throw Error(impl_->error);
}

EmbreeOracle::EmbreeOracle(const scene::InstancedScene& placed) : impl_(std::make_unique<Impl>()) {
    impl_->device = rtcNewDevice(nullptr);
    BVHLAB_CHECK(impl_->device != nullptr, "rtcNewDevice failed");
    rtcSetDeviceErrorFunction(impl_->device, on_error, impl_.get());
    impl_->mesh_scenes.assign(placed.meshes.size(), nullptr);
    for (const scene::Instance& inst : placed.instances) {
        BVHLAB_CHECK(inst.mesh < placed.meshes.size(), "an instance of a mesh the scene does not have");
        RTCScene& ms = impl_->mesh_scenes[inst.mesh];
        if (ms) continue;
        ms = impl_->new_scene();
        impl_->attach(ms, placed.meshes[inst.mesh]);
        rtcCommitScene(ms);
    }
    // Embree's own instances: geometry i of the top scene is instance i, so Embree's instID is
    // the instance index.
    impl_->scene = impl_->new_scene();
    uint64_t first = 0;
    for (size_t i = 0; i < placed.instances.size(); ++i) {
        const scene::Instance& inst = placed.instances[i];
        BVHLAB_CHECK(first <= 0x7fffffffull, "more than 2^31 - 1 triangles in an instanced scene");
        impl_->first_ids.push_back(uint32_t(first));
        first += placed.meshes[inst.mesh].triangle_count();
        RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, impl_->mesh_scenes[inst.mesh]);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, inst.transform.m);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(impl_->scene, g, unsigned(i));
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(impl_->scene);
    if (!impl_->error.empty()) throw Error(impl_->error);
}

EmbreeOracle::~EmbreeOracle() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    for (RTCScene ms : impl_->mesh_scenes)
        if (ms) rtcReleaseScene(ms);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

Hit EmbreeOracle::intersect(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray = to_rtc(ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return Hit::miss();
    return impl_->hit(rh.hit.instID[0], rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
}

bool EmbreeOracle::occluded(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r = to_rtc(ray);
    rtcOccluded1(impl_->scene, &ctx, &r);
    // Embree marks an occluded ray by setting tfar to -inf.
    return r.tfar == -INFINITY;
}

void EmbreeOracle::trace(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits) const {
    hits.resize(rays.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            if (query == Query::kClosest) {
                hits[i] = intersect(rays[i]);
            } else {
                hits[i] = occluded(rays[i]) ? Hit{0, 0.0f, 0.0f, 0.0f} : Hit::miss();
            }
        }
    });
}

void EmbreeOracle::trace16(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits) const {
    hits.resize(rays.size());
    const size_t packets = (rays.size() + 15) / 16;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, packets, 64), [&](const auto& r) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        alignas(64) RTCRayHit16 rh;
        alignas(64) int valid[16];
        for (size_t p = r.begin(); p < r.end(); ++p) {
            const size_t base = p * 16;
            for (size_t k = 0; k < 16; ++k) {
                const size_t i = base + k;
                valid[k] = i < rays.size() ? -1 : 0;
                const Ray& x = rays[i < rays.size() ? i : base];
                rh.ray.org_x[k] = x.org.x;
                rh.ray.org_y[k] = x.org.y;
                rh.ray.org_z[k] = x.org.z;
                rh.ray.tnear[k] = x.tmin;
                rh.ray.dir_x[k] = x.dir.x;
                rh.ray.dir_y[k] = x.dir.y;
                rh.ray.dir_z[k] = x.dir.z;
                rh.ray.time[k] = 0.0f;
                rh.ray.tfar[k] = x.tmax;
                rh.ray.mask[k] = ~0u;
                rh.ray.id[k] = unsigned(k);
                rh.ray.flags[k] = 0;
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (query == Query::kClosest) {
                rtcIntersect16(valid, impl_->scene, &ctx, &rh);
            } else {
                rtcOccluded16(valid, impl_->scene, &ctx, &rh.ray);
            }
            for (size_t k = 0; k < 16 && base + k < rays.size(); ++k) {
                Hit& h = hits[base + k];
                if (query == Query::kClosest) {
                    h = rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID
                            ? Hit::miss()
                            : impl_->hit(rh.hit.instID[0][k], rh.hit.primID[k], rh.ray.tfar[k], rh.hit.u[k],
                                         rh.hit.v[k]);
                } else {
                    h = rh.ray.tfar[k] == -INFINITY ? Hit{0, 0.0f, 0.0f, 0.0f} : Hit::miss();
                }
            }
        }
    });
}

namespace {

class EmbreeTracer final : public Tracer {
public:
    EmbreeTracer(const EmbreeOracle& oracle, bool packets16) : oracle_(oracle), packets16_(packets16) {}
    std::string name() const override { return packets16_ ? "embree-rtcIntersect16" : "embree-rtcIntersect1"; }
    std::string device() const override { return "embree"; }
    void set_rays(const std::vector<Ray>& rays, Query query) override {
        rays_ = rays;
        query_ = query;
    }
    double run() override {
        const auto t0 = std::chrono::steady_clock::now();
        if (packets16_)
            oracle_.trace16(rays_, query_, hits_);
        else
            oracle_.trace(rays_, query_, hits_);
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
    void hits(std::vector<Hit>& out) const override { out = hits_; }

private:
    const EmbreeOracle& oracle_;
    bool packets16_;
    std::vector<Ray> rays_;
    Query query_ = Query::kClosest;
    std::vector<Hit> hits_;
};

}  // namespace

std::unique_ptr<Tracer> make_embree_tracer(const EmbreeOracle& oracle, bool packets16) {
    return std::make_unique<EmbreeTracer>(oracle, packets16);
}

}  // namespace bvhlab::trav
