// SPDX-License-Identifier: MIT
// The property test over the adversarial scenes (tests/support/adversarial.h): every structure
// (binned, sweep, SBVH with and without reinsertion, kd-trees at several constants, depth
// limits and build paths, the CWBVH of each BVH) through every CPU tracer (the kd-tree with
// its full stack and short stacks of 1, 2 and 8) on the four ray types agrees with Embree:
// zero real mismatches under the strict oracle. Also: the generator makes what it promises.
#include <gtest/gtest.h>

#include <functional>
#include <set>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/passes/collapse_wide.h"
#include "tests/support/adversarial.h"
#include "tests/support/agreement.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/cpu/kd_trace.h"
#include "traversal/oracle/compare.h"
#include "traversal/rays/protocol.h"

namespace bvhlab::trav {
namespace {

using Tracer = std::function<void(const RaySet&, std::vector<Hit>&)>;

/// A scene's four ray sets with Embree's answers, made once and checked against every tracer.
struct CheckedScene {
    const test::AdversarialScene& scene;
    EmbreeOracle oracle;
    std::vector<std::pair<RayType, RaySet>> sets;
    std::vector<std::vector<Hit>> reference;

    explicit CheckedScene(const test::AdversarialScene& s) : scene(s), oracle(s.mesh) {
        ProtocolConfig cfg;
        cfg.camera = s.camera;
        cfg.primary = {64, 48, 1, 0};
        cfg.ao_length = s.ao_length;
        RayProtocol proto(s.mesh, oracle, cfg);
        for (RayType t : {RayType::kPrimary, RayType::kAo, RayType::kDiffuse, RayType::kShadow}) {
            sets.emplace_back(t, proto.make(t));
            reference.emplace_back();
            oracle.trace(sets.back().second.rays, sets.back().second.query, reference.back());
        }
    }

    /// Zero real mismatches on every ray type; ties at most the scene's max_tie_fraction.
    void expect_agreement(const std::string& what, const Tracer& trace) const {
        SCOPED_TRACE(what);
        for (size_t i = 0; i < sets.size(); ++i) {
            const RaySet& set = sets[i].second;
            SCOPED_TRACE(ray_type_name(sets[i].first));
            std::vector<Hit> ours;
            trace(set, ours);
            const CompareReport rep =
                test::expect_no_real_mismatch(scene.mesh, oracle, set.rays, set.query, ours, reference[i]);
            // Coincident ties are proven (the rooms overlap coplanar triangles on purpose); the
            // ties that excuse float error are capped.
            EXPECT_LE(double(rep.ties - rep.ties_by_kind[size_t(TieKind::kCoincident)]),
                      double(set.rays.size()) * scene.max_tie_fraction + 5.0);
        }
    }
};

const std::vector<test::AdversarialScene>& scenes() {
    static const std::vector<test::AdversarialScene> s = test::adversarial_scenes();
    return s;
}

}  // namespace

TEST(Adversarial, GeneratorMakesWhatItPromises) {
    for (const auto& s : scenes()) {
        SCOPED_TRACE(s.name);
        const scene::TriangleMesh& m = s.mesh;
        ASSERT_GT(m.triangle_count(), 600u);
        size_t near_flat = 0, axis_aligned = 0;
        float lo = INFINITY, hi = -INFINITY;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const Vec3 a = m.vertex(t, 0), b = m.vertex(t, 1), c = m.vertex(t, 2);
            bool flat = false;  // in some axis, exactly or to 4 ulps
            for (int k = 0; k < 3; ++k) {
                const float mn = std::min({a[k], b[k], c[k]}), mx = std::max({a[k], b[k], c[k]});
                lo = std::min(lo, mn);
                hi = std::max(hi, mx);
                float up = mn;
                for (int u = 0; u < 4; ++u) up = std::nextafter(up, INFINITY);
                // Flat to 1-4 ulps in one axis: the kd-tree's thin cells.
                if (mn < mx && up >= mx) ++near_flat;
                flat = flat || up >= mx;
            }
            axis_aligned += flat;
        }
        EXPECT_GT(near_flat, 20u);
        EXPECT_GT(axis_aligned, m.triangle_count() / 2);  // mostly axis-aligned faces
        // Offset scenes lie far from the origin.
        if (s.name.find("offset") != std::string::npos) {
            EXPECT_GT(lo, 9000.0f);
        } else {
            EXPECT_LT(lo, 0.0f);  // the huge ground plane
        }
        EXPECT_GT(hi - lo, 900.0f);
    }
    // Seeded: the same config gives the same mesh, another seed another one.
    const auto a = test::make_adversarial_scene({7, 0.0, 8, false}),
               b = test::make_adversarial_scene({7, 0.0, 8, false});
    const auto c = test::make_adversarial_scene({8, 0.0, 8, false});
    EXPECT_EQ(scene::scene_hash(a.mesh), scene::scene_hash(b.mesh));
    EXPECT_NE(scene::scene_hash(a.mesh), scene::scene_hash(c.mesh));
}

TEST(Adversarial, EveryBvhAndCwbvhAgreesWithEmbree) {
    for (const auto& s : scenes()) {
        SCOPED_TRACE(s.name);
        const CheckedScene cs(s);
        for (const test::BvhVariant& v : test::bvh_variants()) {
            const accel::BuildTree tree = v.build(s.mesh);
            const std::string name = v.name();
            const accel::Bvh2 bvh = accel::convert_to_bvh2(tree, s.mesh);
            cs.expect_agreement("bvh2 " + name, [&](const RaySet& set, std::vector<Hit>& h) {
                trace_cpu(bvh, set.rays, set.query, h);
            });
            for (auto tris : {accel::CwTris::kWoop, accel::CwTris::kVertices}) {
                const accel::Cwbvh cw = accel::convert_to_cwbvh(
                    accel::collapse_to_wide(tree, s.mesh, accel::CollapseMethod::kSahOptimal), s.mesh, tris);
                cs.expect_agreement(
                    std::string("cwbvh ") + (tris == accel::CwTris::kWoop ? "woop " : "vertices ") + name,
                    [&](const RaySet& set, std::vector<Hit>& h) { trace_cpu(cw, set.rays, set.query, h); });
            }
        }
    }
}

TEST(Adversarial, EveryKdTreeAndStackAgreesWithEmbree) {
    struct Variant {
        std::string name;
        accel::KdTreeBuilder::Config config;
    };
    std::vector<Variant> variants;
    variants.push_back({"default", {}});
    accel::KdTreeBuilder::Config wh;  // Wald & Havran's constants: deeper trees, more thin cells
    wh.traversal_cost = 15.0f;
    wh.intersection_cost = 20.0f;
    wh.empty_bonus = 0.2f;
    variants.push_back({"wald-havran", wh});
    accel::KdTreeBuilder::Config cheap = wh;  // splits almost everywhere
    cheap.traversal_cost = 2.0f;
    variants.push_back({"ct2", cheap});
    accel::KdTreeBuilder::Config shallow;
    shallow.max_depth = 6;
    variants.push_back({"depth6", shallow});
    accel::KdTreeBuilder::Config fresh = wh;  // every clip from the triangle, no small-node path
    fresh.reuse_clipped_polygons = false;
    fresh.small_node_size = 0;
    fresh.task_threshold = 64;
    variants.push_back({"fresh-clips", fresh});
    for (const auto& s : scenes()) {
        SCOPED_TRACE(s.name);
        const CheckedScene cs(s);
        for (const Variant& v : variants) {
            const accel::KdLayout kd =
                accel::convert_to_kd_layout(accel::KdTreeBuilder(v.config).build(s.mesh), s.mesh);
            // Stack 1 on the Ct = 2 tree is the hardest case: room-seed1's floor planes lie
            // denormals apart, and a restart's re-descent drops the thin cells' entries (it lost
            // 2-18 rays per set until a stalled restart retried with the ring's full 8 entries).
            for (int stack : {64, 1, 2, 8}) {
                cs.expect_agreement(
                    "kdtree " + v.name + " stack " + std::to_string(stack),
                    [&](const RaySet& set, std::vector<Hit>& h) { trace_kd_cpu(kd, stack, set.rays, set.query, h); });
            }
        }
    }
}

}  // namespace bvhlab::trav
