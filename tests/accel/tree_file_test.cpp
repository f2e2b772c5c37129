// SPDX-License-Identifier: MIT
// Structure cache files: round trip, staleness, and every kind of damaged file.
#include "accel/io/tree_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/io/procedural.h"
#include "tests/support/test_support.h"

namespace bvhlab::accel {
namespace {

void expect_read_error(const std::string& path, const std::string& what) {
    try {
        read_tree_file(path);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
}

struct Fixture {
    scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kStructured, 2000, 3);
    TreeFileMeta meta;
    BuildTree tree;
    Fixture() {
        meta.builder = BuilderKind::kSbvh;
        meta.options.sbvh_budget = 1.5f;
        meta.options.config.max_leaf_size = 4;
        meta.triangles = mesh.triangle_count();
        meta.scene_hash = scene::scene_hash(mesh);
        tree = run_builder(meta.builder, mesh, meta.options).tree;
    }
};

}  // namespace

TEST(TreeFile, RoundTripKeepsTreeAndProvenance) {
    Fixture fx;
    test::TempFile f("cache.tree");
    write_tree_file(f.path(), fx.tree, fx.meta);
    TreeFile r = read_tree_file(f.path());
    EXPECT_EQ(r.tree.prim_indices, fx.tree.prim_indices);
    ASSERT_EQ(r.tree.nodes.size(), fx.tree.nodes.size());
    EXPECT_EQ(std::memcmp(r.tree.nodes.data(), fx.tree.nodes.data(), fx.tree.nodes.size() * sizeof(BuildNode)), 0);
    EXPECT_EQ(r.meta.builder, BuilderKind::kSbvh);
    EXPECT_EQ(r.meta.scene_hash, fx.meta.scene_hash);
    EXPECT_EQ(describe_config(r.meta.builder, r.meta.options), describe_config(fx.meta.builder, fx.meta.options));
    EXPECT_EQ(stale_reason(r.meta, fx.mesh.triangle_count(), scene::scene_hash(fx.mesh)), "");
}

TEST(TreeFile, StaleWhenTrianglesDiffer) {
    Fixture fx;
    scene::TriangleMesh other =
        scene::make_procedural(scene::ProceduralKind::kStructured, 2000, 4);  // same count, other seed
    EXPECT_NE(stale_reason(fx.meta, other.triangle_count(), scene::scene_hash(other)), "");
    EXPECT_NE(stale_reason(fx.meta, 1999, fx.meta.scene_hash), "");
}

TEST(TreeFile, DamagedFiles) {
    Fixture fx;
    test::TempFile f("damaged.tree");
    write_tree_file(f.path(), fx.tree, fx.meta);
    const std::string good = test::read_file_bytes(f.path());
    auto write = [&](const std::string& b) { std::ofstream(f.path(), std::ios::binary) << b; };
    expect_read_error("/nonexistent/x.tree", "cannot open");
    write(good.substr(0, 40));
    expect_read_error(f.path(), "truncated");
    write(good.substr(0, good.size() - 9));
    expect_read_error(f.path(), "truncated");
    write(good + "junk");
    expect_read_error(f.path(), "trailing");
    std::string bad = good;
    bad[3] = 'X';
    write(bad);
    expect_read_error(f.path(), "magic");
    bad = good;
    bad[8] = 9;
    write(bad);
    expect_read_error(f.path(), "version 9");
    // Forged counts near 2^64 (node_count at byte 64, index_count at 72): refused by what the
    // file can hold, with the counts as written, before any allocation.
    for (size_t at : {size_t(64), size_t(72)}) {
        bad = good;
        const uint64_t huge = (1ull << 63) + 5;
        std::memcpy(&bad[at], &huge, 8);
        write(bad);
        expect_read_error(f.path(), "claims");
        expect_read_error(f.path(), std::to_string(huge));
    }
    // Header values out of range, with the checksum made right again: refused by name.
    // (Ct is at byte 48, max_depth at 44.)
    const auto with_checksum = [](std::string b) {
        const uint64_t sum = fnv1a(b.data(), b.size() - 8);
        std::memcpy(&b[b.size() - 8], &sum, 8);
        return b;
    };
    bad = good;
    const float nan = std::nanf("");
    std::memcpy(&bad[48], &nan, 4);
    write(with_checksum(bad));
    expect_read_error(f.path(), "header value out of range: ct nan");
    bad = good;
    const uint32_t zero = 0;
    std::memcpy(&bad[44], &zero, 4);
    write(with_checksum(bad));
    expect_read_error(f.path(), "header value out of range: max_depth 0 is not in [1, 64]");
    write(with_checksum(good));
    EXPECT_NO_THROW(read_tree_file(f.path()));
    for (size_t pos : {size_t(100), good.size() / 2, good.size() - 20}) {
        bad = good;
        bad[pos] = char(bad[pos] ^ 0x40);
        write(bad);
        expect_read_error(f.path(), "corrupt");
    }
}

TEST(TreeFile, KdTreeRoundTripAndCorruption) {
    scene::TriangleMesh m = scene::make_procedural(scene::ProceduralKind::kSoup, 3000, 8);
    KdTreeBuilder::Config c;
    c.empty_bonus = 0.3f;
    KdTree kd = KdTreeBuilder(c).build(m);
    TreeFileMeta meta;
    meta.kdtree = true;
    meta.kd = c;
    meta.triangles = m.triangle_count();
    meta.scene_hash = scene::scene_hash(m);
    test::TempFile f("kd.tree");
    write_kd_file(f.path(), kd, meta);
    TreeFile r = read_tree_file(f.path());
    ASSERT_TRUE(r.meta.kdtree);
    EXPECT_EQ(r.meta.kd.empty_bonus, 0.3f);
    EXPECT_EQ(describe_config(r.meta), describe_config(meta));
    EXPECT_EQ(r.kd.prim_indices, kd.prim_indices);
    ASSERT_EQ(r.kd.nodes.size(), kd.nodes.size());
    EXPECT_EQ(std::memcmp(r.kd.nodes.data(), kd.nodes.data(), kd.nodes.size() * sizeof(KdNode)), 0);
    std::string bad = test::read_file_bytes(f.path());
    bad[bad.size() / 2] = char(bad[bad.size() / 2] ^ 1);
    std::ofstream(f.path(), std::ios::binary) << bad;
    expect_read_error(f.path(), "corrupt");
}

}  // namespace bvhlab::accel
