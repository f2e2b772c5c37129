// SPDX-License-Identifier: MIT
// Ray and hit files: round trip and every kind of bad file.
#include "traversal/rays/ray_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "tests/support/test_support.h"

namespace bvhlab::trav {
namespace {

/// Reads `path` as a ray file (or, with `hits`, a hit file) and expects an error containing `what`.
void expect_error(const std::string& path, const std::string& what, bool hits = false) {
    try {
        if (hits)
            read_hit_file(path);
        else
            read_ray_file(path);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
}

RaySet sample_set() {
    RaySet s;
    s.query = Query::kAny;
    s.rays = {{{1, 2, 3}, 0.5f, {0, 0, -1}, INFINITY}, {{-1, 0, 7.25f}, 0.0f, {1e-30f, 1, 0}, 2.0f}};
    return s;
}

}  // namespace

TEST(RayFile, RoundTripIsByteExact) {
    test::TempFile f("rays.bin");
    RaySet a = sample_set();
    a.writer = "0123456789ab-dirty";
    write_ray_file(f.path(), a);
    const std::string bytes = test::read_file_bytes(f.path());
    ASSERT_EQ(bytes.size(), 48u + 2 * 32u + 8u);
    EXPECT_EQ(bytes.substr(0, 8), "BVHLRAYS");
    uint32_t version, flags;
    uint64_t count;
    std::memcpy(&version, bytes.data() + 8, 4);
    std::memcpy(&flags, bytes.data() + 12, 4);
    std::memcpy(&count, bytes.data() + 16, 8);
    EXPECT_EQ(version, 2u);
    EXPECT_EQ(flags, 1u);  // any-hit
    EXPECT_EQ(count, 2u);
    EXPECT_EQ(bytes.substr(24, 19), std::string("0123456789ab-dirty\0", 19));
    RaySet b = read_ray_file(f.path());
    EXPECT_EQ(b.query, Query::kAny);
    EXPECT_EQ(b.writer, a.writer);
    EXPECT_EQ(b.version, 2u);
    ASSERT_EQ(b.rays.size(), 2u);
    EXPECT_EQ(std::memcmp(a.rays.data(), b.rays.data(), 64), 0);
    a.writer.clear();  // an unnamed writer is stored as "unknown"
    write_ray_file(f.path(), a);
    EXPECT_EQ(read_ray_file(f.path()).writer, "unknown");
    a.writer = "ab\x1b[31m\xff\x7f";  // escape bytes never reach a terminal or JSON
    write_ray_file(f.path(), a);
    EXPECT_EQ(read_ray_file(f.path()).writer, "ab?[31m??");
}

TEST(RayFile, Version1FilesAreStillRead) {
    // The 24-byte header of version 1, then the records; no writer, no checksum.
    test::TempFile f("v1.rays");
    const RaySet a = sample_set();
    std::string bytes("BVHLRAYS\1\0\0\0\1\0\0\0", 16);
    const uint64_t count = a.rays.size();
    bytes.append(reinterpret_cast<const char*>(&count), 8);
    bytes.append(reinterpret_cast<const char*>(a.rays.data()), a.rays.size() * sizeof(Ray));
    std::ofstream(f.path(), std::ios::binary) << bytes;
    const RaySet b = read_ray_file(f.path());
    EXPECT_EQ(b.version, 1u);
    EXPECT_EQ(b.writer, "");
    EXPECT_EQ(b.query, Query::kAny);
    ASSERT_EQ(b.rays.size(), 2u);
    EXPECT_EQ(std::memcmp(a.rays.data(), b.rays.data(), 64), 0);
    std::ofstream(f.path(), std::ios::binary) << bytes << "x";
    expect_error(f.path(), "trailing");
}

TEST(RayFile, DamageIsNoticedByTheChecksum) {
    // A flipped bit anywhere (writer, a record, the checksum itself) that leaves the header
    // readable is "damaged", never a silent change of a ray.
    test::TempFile f("damaged.rays");
    RaySet a = sample_set();
    a.writer = "abc";
    write_ray_file(f.path(), a);
    const std::string good = test::read_file_bytes(f.path());
    for (size_t pos : {size_t(30), size_t(48), size_t(48 + 37), good.size() - 3}) {
        SCOPED_TRACE(pos);
        std::string bad = good;
        bad[pos] = char(bad[pos] ^ 0x10);
        std::ofstream(f.path(), std::ios::binary) << bad;
        expect_error(f.path(), "is damaged: its checksum does not match");
    }
    HitSet h{{{5, 1.5f, 0.25f, 0.5f}}, Query::kClosest, "abc"};
    write_hit_file(f.path(), h);
    std::string bad = test::read_file_bytes(f.path());
    bad[48 + 4] = char(bad[48 + 4] ^ 1);  // the hit's t
    std::ofstream(f.path(), std::ios::binary) << bad;
    try {
        read_hit_file(f.path());
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
    }
}

TEST(RayFile, EmptySetRoundTrips) {
    test::TempFile f("empty_rays.bin");
    write_ray_file(f.path(), RaySet{});
    EXPECT_TRUE(read_ray_file(f.path()).rays.empty());
}

TEST(RayFile, BadFiles) {
    test::TempFile f("bad_rays.bin");
    write_ray_file(f.path(), sample_set());
    const std::string good = test::read_file_bytes(f.path());
    auto write = [&](const std::string& bytes) { std::ofstream(f.path(), std::ios::binary) << bytes; };

    expect_error("/nonexistent/rays.bin", "cannot open");
    write(good.substr(0, 10));
    expect_error(f.path(), "truncated");
    write(good.substr(0, good.size() - 1));
    expect_error(f.path(), "truncated");
    write(good + "x");
    expect_error(f.path(), "trailing");
    std::string bad = good;
    bad[0] = 'X';
    write(bad);
    expect_error(f.path(), "magic");
    bad = good;
    bad[8] = 3;  // version 3
    write(bad);
    expect_error(f.path(), "version 3");
    bad = good;
    bad[12] = 4;  // unknown flag bit
    write(bad);
    expect_error(f.path(), "unknown flag");
    // A hit file is not a ray file.
    write_hit_file(f.path(), HitSet{{Hit::miss()}, Query::kClosest});
    expect_error(f.path(), "magic");
}

TEST(HitFile, RoundTrip) {
    test::TempFile f("hits.bin");
    HitSet a{{{5, 1.5f, 0.25f, 0.5f}, Hit::miss()}, Query::kClosest};
    write_hit_file(f.path(), a);
    EXPECT_EQ(test::read_file_bytes(f.path()).substr(0, 8), "BVHLHITS");
    HitSet b = read_hit_file(f.path());
    ASSERT_EQ(b.hits.size(), 2u);
    EXPECT_EQ(b.hits[0].tri, 5);
    EXPECT_EQ(b.hits[0].v, 0.5f);
    EXPECT_EQ(b.hits[1].tri, -1);
    EXPECT_THROW(read_ray_file(f.path()), Error);
}

/// A hit file of `version` (2 or 3) with these record bytes, header and checksum as the writer
/// makes them: files that write_hit_file no longer writes, or would refuse to.
void write_raw_hit_file(const std::string& path, uint32_t version, uint64_t count, const std::string& records) {
    std::string bytes("BVHLHITS", 8);
    bytes.append(reinterpret_cast<const char*>(&version), 4);
    bytes.append(4, '\0');  // flags: closest hit
    bytes.append(reinterpret_cast<const char*>(&count), 8);
    bytes.append("old-writer");
    bytes.append(kFileWriterBytes - 10, '\0');
    const uint64_t sum = accel::fnv1a_words(records.data(), records.size(), accel::fnv1a_words(bytes.data(), 48));
    bytes += records;
    bytes.append(reinterpret_cast<const char*>(&sum), 8);
    std::ofstream(path, std::ios::binary) << bytes;
}

// Version 3 hit files say each hit's instance and the triangle of its mesh beside the
// scene-wide id; check_hit_ids holds all three against the scene's numbering. Version 2 files
// (16-byte records, no instances) are still read.
TEST(HitFile, Version3CarriesInstancesAndVersion2IsStillRead) {
    test::TempFile f("instanced.hits");
    const InstanceFirstIds first = {0, 10, 10, 25};  // instance 1 places an empty mesh
    const HitSet a{{{12, 1.0f, 0.1f, 0.2f}, {3, 2.0f, 0.3f, 0.4f}, Hit::miss(), {10, 3.0f, 0.5f, 0.0f}},
                   Query::kClosest};
    write_hit_file(f.path(), a, first);
    EXPECT_EQ(test::read_file_bytes(f.path()).size(), 48u + 4 * 24 + 8);
    const HitSet b = read_hit_file(f.path());
    EXPECT_EQ(b.version, 3u);
    ASSERT_EQ(b.instances.size(), 4u);
    const std::vector<std::pair<int, int>> want = {{2, 2}, {0, 3}, {-1, -1}, {2, 0}};
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(b.hits[i].tri, a.hits[i].tri);
        EXPECT_EQ(b.instances[i].instance, want[i].first) << i;
        EXPECT_EQ(b.instances[i].tri, want[i].second) << i;
    }
    EXPECT_NO_THROW(check_hit_ids(b, first, f.path()));
    try {
        check_hit_ids(b, {0, 25}, f.path());  // the same ids in a scene of one mesh
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("hit 0 names triangle 12 as instance 2's triangle 2, but in this scene it "
                                             "is instance 0's triangle 12"),
                  std::string::npos)
            << e.what();
    }
    // Without a numbering: one instance, 0.
    write_hit_file(f.path(), a);
    EXPECT_EQ(read_hit_file(f.path()).instances[0].instance, 0);
    EXPECT_EQ(read_hit_file(f.path()).instances[0].tri, 12);
    EXPECT_THROW(write_hit_file(f.path(), a, {0, 12}), Error);  // id 12 is outside 12 triangles
    // A miss that names an instance, and a hit that names none, are refused.
    const Hit miss = Hit::miss(), hit{4, 1.0f, 0.0f, 0.0f};
    const int32_t where_miss[2] = {0, 0}, where_hit[2] = {-1, 4};
    std::string rec(reinterpret_cast<const char*>(&miss), 16);
    rec.append(reinterpret_cast<const char*>(where_miss), 8);
    write_raw_hit_file(f.path(), 3, 1, rec);
    expect_error(f.path(), "hit 0 has instance 0 and triangle 0 for a miss", /*hits=*/true);
    rec.assign(reinterpret_cast<const char*>(&hit), 16);
    rec.append(reinterpret_cast<const char*>(where_hit), 8);
    write_raw_hit_file(f.path(), 3, 1, rec);
    expect_error(f.path(), "negative for a hit", /*hits=*/true);
    // Version 2: the 16-byte records alone.
    rec.assign(reinterpret_cast<const char*>(&hit), 16);
    rec.append(reinterpret_cast<const char*>(&miss), 16);
    write_raw_hit_file(f.path(), 2, 2, rec);
    const HitSet old = read_hit_file(f.path());
    EXPECT_EQ(old.version, 2u);
    EXPECT_EQ(old.writer, "old-writer");
    ASSERT_EQ(old.hits.size(), 2u);
    EXPECT_EQ(old.hits[0].tri, 4);
    EXPECT_EQ(old.hits[1].tri, -1);
    EXPECT_TRUE(old.instances.empty());
    EXPECT_NO_THROW(check_hit_ids(old, first, f.path()));
    write_raw_hit_file(f.path(), 4, 0, "");
    expect_error(f.path(), "version 4; this build reads versions 1 to 3", /*hits=*/true);
}

TEST(RayFile, InvalidRaysAreRefusedWithTheirIndex) {
    // Each of these once reached Embree (which aborts on a NaN direction) or the kernels.
    const float nan = std::nanf("");
    const std::vector<std::pair<Ray, std::string>> bad = {
        {{{0, 0, 0}, 0.0f, {nan, 0, 1}, INFINITY}, "non-finite direction"},
        {{{INFINITY, 0, 0}, nan, {0, 0, 1}, INFINITY}, "non-finite origin"},
        {{{0, 0, 0}, 0.0f, {0, 0, 0}, INFINITY}, "zero direction"},
        {{{0, 0, 0}, nan, {0, 0, 1}, INFINITY}, "tmin"},
        {{{0, 0, 0}, -1.0f, {0, 0, 1}, INFINITY}, "tmin"},
        {{{0, 0, 0}, INFINITY, {0, 0, 1}, INFINITY}, "tmin"},
        {{{0, 0, 0}, 2.0f, {0, 0, 1}, 1.0f}, "tmax"},
        {{{0, 0, 0}, 0.0f, {0, 0, 1}, nan}, "tmax"},
    };
    test::TempFile f("bad_rays.bin");
    for (const auto& [ray, why] : bad) {
        SCOPED_TRACE(why);
        EXPECT_NE(invalid_ray(ray), "");
        RaySet set = sample_set();
        set.rays.push_back(ray);
        write_ray_file(f.path(), set);
        expect_error(f.path(), "ray 2 has");
        expect_error(f.path(), why);
    }
    for (const Ray& r : sample_set().rays) EXPECT_EQ(invalid_ray(r), "");  // tmax = +inf and tiny components are fine
}

TEST(RayFile, AHugeCountIsRefusedWithoutWrapping) {
    test::TempFile f("huge_count.rays");
    std::string bytes("BVHLRAYS\1\0\0\0\0\0\0\0", 16);
    const uint64_t count = (1ull << 59);  // times 32 bytes wraps to 0 in 64 bits
    bytes.append(reinterpret_cast<const char*>(&count), 8);
    std::ofstream(f.path(), std::ios::binary) << bytes;
    expect_error(f.path(), "header says 576460752303423488 records of 32 bytes, the file has room for 0");
}

TEST(HitFile, InvalidHitsAndForeignIdsAreRefused) {
    test::TempFile f("bad_hits.bin");
    write_hit_file(f.path(), {{{5, 1.0f, 0.1f, 0.1f}, {-7, 1.0f, 0.1f, 0.1f}}, Query::kClosest});
    EXPECT_THROW(read_hit_file(f.path()), Error);  // id below -1
    write_hit_file(f.path(), {{{5, std::nanf(""), 0.1f, 0.1f}}, Query::kClosest});
    EXPECT_THROW(read_hit_file(f.path()), Error);  // NaN t on a hit
    const HitSet ok{{{5, 1.0f, 0.1f, 0.1f}, Hit::miss()}, Query::kClosest};
    EXPECT_NO_THROW(check_hit_ids(ok, {0, 6}, f.path()));
    try {
        check_hit_ids(ok, {0, 5}, f.path());  // the hits of a larger scene
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("hit 0 names triangle 5"), std::string::npos) << e.what();
    }
}

}  // namespace bvhlab::trav
