// SPDX-License-Identifier: MIT
// Progress of builds and EPO: the counter's contract (serialised, throttled, done < total until
// the end, one final report), and every CPU builder's leaves counting exactly their references.
#include "accel/core/progress.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <mutex>
#include <utility>
#include <vector>

#include "accel/builders/binned_sah.h"
#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/builders/sbvh.h"
#include "accel/builders/sweep_sah.h"
#include "accel/core/stats.h"
#include "scene/io/procedural.h"

namespace bvhlab::accel {
namespace {

/// Reports as the counter makes them, checking that no two overlap.
struct Recorder {
    std::mutex mu;
    std::vector<std::pair<uint64_t, uint64_t>> calls;
    std::atomic<int> inside{0};
    bool overlapped = false;
    ProgressFn fn() {
        return [this](uint64_t done, uint64_t total) {
            if (inside.fetch_add(1) != 0) overlapped = true;
            {
                std::lock_guard<std::mutex> lock(mu);
                calls.emplace_back(done, total);
            }
            inside.fetch_sub(1);
        };
    }
};

TEST(Progress, CounterReportsSeriallyBelowTheTotalThenOnceDone) {
    Recorder rec;
    ProgressCounter c(rec.fn(), 10000, 0.0);              // no throttle: every add may report
    tbb::parallel_for(0, 12000, [&](int) { c.add(1); });  // more than the estimate (duplicates)
    EXPECT_EQ(c.done(), 12000u);
    ASSERT_FALSE(rec.calls.empty());
    EXPECT_FALSE(rec.overlapped);
    for (const auto& [done, total] : rec.calls) {
        EXPECT_EQ(total, 10000u);
        EXPECT_LT(done, total);  // never "done" before finish()
    }
    c.finish();
    c.finish();  // once only
    ASSERT_EQ(rec.calls.back(), std::make_pair(uint64_t(10000), uint64_t(10000)));
    EXPECT_NE(rec.calls[rec.calls.size() - 2].first, 10000u);
    // Throttled: a long period lets no report through before finish().
    Recorder quiet;
    ProgressCounter slow(quiet.fn(), 100, 3600.0);
    for (int i = 0; i < 100; ++i) slow.add(1);
    EXPECT_TRUE(quiet.calls.empty());
    slow.finish();
    EXPECT_EQ(quiet.calls.size(), 1u);
    // No function: counting only.
    ProgressCounter none({}, 5);
    none.add(3);
    none.finish();
    EXPECT_EQ(none.done(), 3u);
}

TEST(Progress, EveryBuilderCountsItsReferencesInLeaves) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 3000, 7);
    const uint64_t n = mesh.triangle_count();
    {
        ProgressCounter c({}, n);
        BinnedSahBuilder::Config cfg;
        cfg.progress = &c;
        const BuildTree t = BinnedSahBuilder(cfg).build(mesh);
        EXPECT_EQ(c.done(), n);
        EXPECT_EQ(t.prim_indices.size(), n);
    }
    {
        ProgressCounter c({}, n);
        SweepSahBuilder::Config cfg;
        cfg.progress = &c;
        SweepSahBuilder(cfg).build(mesh);
        EXPECT_EQ(c.done(), n);
    }
    {
        // Spatial splits duplicate references: the leaves count every copy.
        ProgressCounter c({}, n);
        SbvhBuilder::Config cfg;
        cfg.progress = &c;
        cfg.reinsertion_passes = 0;
        const BuildTree t = SbvhBuilder(cfg).build(mesh);
        EXPECT_GT(t.prim_indices.size(), n);
        EXPECT_EQ(c.done(), t.prim_indices.size());
    }
    // The kd-tree's leaves, every reference, wherever they are made: in one thread's subtree
    // (small nodes, and with no small-node search the event path), and in the parallel top
    // levels (a task threshold of 1 keeps every node there).
    for (const auto& [small, task] : {std::pair<uint32_t, uint32_t>{64, 2048}, {0, 2048}, {64, 1}}) {
        ProgressCounter c({}, n);
        KdTreeBuilder::Config cfg;
        cfg.progress = &c;
        cfg.small_node_size = small;
        cfg.task_threshold = task;
        const KdTree t = KdTreeBuilder(cfg).build(mesh);
        EXPECT_EQ(c.done(), t.prim_indices.size()) << "small " << small << " task " << task;
        EXPECT_GT(c.done(), n);
    }
    // run_builder hands its counter to the builder: with no throttle the leaves' counts arrive
    // as they are made, rising, below the total; the last report says done.
    for (BuilderKind kind : {BuilderKind::kBinned, BuilderKind::kSweep, BuilderKind::kSbvh}) {
        Recorder rec;
        BuilderOptions o;
        o.progress = rec.fn();
        o.progress_period_s = 0.0;
        run_builder(kind, mesh, o);
        ASSERT_GE(rec.calls.size(), 3u) << builder_name(kind);
        EXPECT_EQ(rec.calls.back(), std::make_pair(n, n)) << builder_name(kind);
        for (size_t i = 0; i + 1 < rec.calls.size(); ++i) {
            EXPECT_GT(rec.calls[i].first, 0u) << builder_name(kind);
            EXPECT_LT(rec.calls[i].first, n) << builder_name(kind);
            EXPECT_EQ(rec.calls[i].second, n) << builder_name(kind);
        }
    }
}

TEST(Progress, EpoReportsItsTriangles) {
    const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 5000, 3);
    const BuildTree t = BinnedSahBuilder().build(mesh);
    Recorder rec;
    const TreeStats with = compute_stats(t, mesh, BuildConfig{}, true, 0, rec.fn());
    ASSERT_FALSE(rec.calls.empty());
    EXPECT_EQ(rec.calls.back(), std::make_pair(uint64_t(5000), uint64_t(5000)));
    EXPECT_EQ(with.epo, compute_stats(t, mesh, BuildConfig{}).epo);  // the same figure
    Recorder off;
    compute_stats(t, mesh, BuildConfig{}, false, 0, off.fn());
    EXPECT_TRUE(off.calls.empty());  // no EPO, nothing to report
}

}  // namespace
}  // namespace bvhlab::accel
