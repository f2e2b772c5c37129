// SPDX-License-Identifier: MIT
// The agreement check of the CPU and GPU tests: a tracer's hits against Embree's on the same
// rays under the strict oracle, with the first real mismatches printed.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "accel/builders/builder.h"
#include "traversal/oracle/compare.h"
#include "traversal/oracle/embree_oracle.h"

namespace bvhlab::test {

/// A BVH build the CPU agreement tests cover.
struct BvhVariant {
    accel::BuilderKind kind;
    int reinsertion;  ///< passes, -1 for the builder's default
    std::string name() const {
        return std::string(accel::builder_name(kind)) + (reinsertion == 0 ? " without reinsertion" : "");
    }
    accel::BuildTree build(const scene::TriangleMesh& mesh) const {
        accel::BuilderOptions opts;
        opts.reinsertion_passes = reinsertion;
        return accel::run_builder(kind, mesh, opts).tree;
    }
};

/// Binned, sweep, and SBVH without and with reinsertion.
inline std::vector<BvhVariant> bvh_variants() {
    return {{accel::BuilderKind::kBinned, -1},
            {accel::BuilderKind::kSweep, -1},
            {accel::BuilderKind::kSbvh, 0},
            {accel::BuilderKind::kSbvh, -1}};
}

/// Compares `ours` with `reference` (Embree's hits of the same rays) and expects 0 real
/// mismatches, printing the first ones with their rays. Returns the report (ties by kind).
inline trav::CompareReport expect_no_real_mismatch(const scene::TriangleMesh& mesh, const trav::EmbreeOracle& oracle,
                                                   const std::vector<trav::Ray>& rays, trav::Query query,
                                                   const std::vector<trav::Hit>& ours,
                                                   const std::vector<trav::Hit>& reference) {
    const trav::CompareReport rep =
        trav::compare_hits(mesh, rays, query, ours, reference, [&](const trav::Ray& r) { return oracle.intersect(r); });
    EXPECT_EQ(rep.mismatches, 0u);
    for (const auto& d : rep.first_mismatches) {
        const trav::Ray& r = rays[d.ray];
        ADD_FAILURE() << "ray " << d.ray << " (" << r.org.x << ", " << r.org.y << ", " << r.org.z << ") dir ("
                      << r.dir.x << ", " << r.dir.y << ", " << r.dir.z << ") [" << r.tmin << ", " << r.tmax
                      << "]: ours " << d.ours.tri << " t=" << d.ours.t << ", embree " << d.oracle.tri
                      << " t=" << d.oracle.t << ": " << d.reason;
    }
    EXPECT_EQ(rep.agree + rep.ties + rep.mismatches, rep.rays);
    return rep;
}

}  // namespace bvhlab::test
