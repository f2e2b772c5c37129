// SPDX-License-Identifier: MIT
// The binary scene cache: a hit gives the mesh a parse gives; a changed OBJ or material file, or
// another loader version, is never served; a damaged or foreign entry is rebuilt with a warning.
#include "scene/io/scene_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/io/obj_loader.h"
#include "tests/support/test_support.h"

namespace bvhlab::scene {
namespace {
namespace fs = std::filesystem;

/// A fresh folder with an OBJ that names a material file, and a cache folder beside it.
struct Fixture {
    fs::path dir, obj, mtl, cache;
    Fixture() {
        dir = fs::temp_directory_path() / ("bvhlab_scene_cache_" + std::to_string(getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
        obj = dir / "scene.obj";
        mtl = dir / "scene.mtl";
        cache = dir / "cache";
        write(mtl,
              "newmtl red\nKd 0.9 0.1 0.1\nKe 1 2 3\nKs 0.5 0.4 0.3\nKa 0.1 0.2 0.3\nNs 250\nNi 1.33\nd 0.75\n"
              "illum 7\nmap_Kd tex\\red.png\n");
        write(obj,
              "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 2\nv nan 0 0\nvt 0.25 0.5\nvt 1 0\n"
              "usemtl red\nf 1/1 2/2 3/1\nf 2 4 3\nf 1 5 6\nf 1 2 2\n");
    }
    ~Fixture() { fs::remove_all(dir); }
    static void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
    SceneLoad load() const { return load_obj_cached(obj.string(), cache.string(), "test-writer"); }
    std::string entry() const {
        for (const auto& e : fs::directory_iterator(cache)) return e.path().string();
        return "";
    }
};

void expect_same(const SceneLoad& a, const SceneLoad& b) {
    EXPECT_EQ(a.scene_hash, b.scene_hash);
    ASSERT_EQ(a.mesh.vertices.size(), b.mesh.vertices.size());
    // NaN vertices (of dropped triangles) compare by bytes.
    EXPECT_EQ(0, std::memcmp(a.mesh.vertices.data(), b.mesh.vertices.data(), a.mesh.vertices.size() * sizeof(Vec3)));
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    EXPECT_EQ(a.mesh.material_ids, b.mesh.material_ids);
    EXPECT_EQ(a.mesh.texcoords, b.mesh.texcoords);
    ASSERT_EQ(a.mesh.materials.size(), b.mesh.materials.size());
    for (size_t i = 0; i < a.mesh.materials.size(); ++i) {
        EXPECT_EQ(a.mesh.materials[i].name, b.mesh.materials[i].name);
        const Material &x = a.mesh.materials[i], &y = b.mesh.materials[i];
        EXPECT_EQ(x.emission.z, y.emission.z);
        EXPECT_EQ(x.diffuse.x, y.diffuse.x);
        EXPECT_EQ(x.specular.y, y.specular.y);
        EXPECT_EQ(x.ambient.z, y.ambient.z);
        EXPECT_EQ(x.shininess, y.shininess);
        EXPECT_EQ(x.ior, y.ior);
        EXPECT_EQ(x.dissolve, y.dissolve);
        EXPECT_EQ(x.illum, y.illum);
        EXPECT_EQ(x.diffuse_texture, y.diffuse_texture);
    }
    EXPECT_EQ(a.mesh.dropped.non_finite, b.mesh.dropped.non_finite);
    EXPECT_EQ(a.mesh.dropped.zero_area, b.mesh.dropped.zero_area);
    EXPECT_EQ(a.warnings, b.warnings);
}

}  // namespace

// The material files the OBJ names, and the missing ones, on a parse and on a cache hit.
TEST(SceneCache, ReportsMissingMaterialFiles) {
    Fixture f;
    Fixture::write(f.obj, "mtllib scene.mtl\nmtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for (int run = 0; run < 2; ++run) {
        const SceneLoad l = f.load();
        EXPECT_EQ(l.from_cache, run == 1);
        ASSERT_EQ(l.material_files.size(), 2u);
        ASSERT_EQ(l.missing_material_files.size(), 1u);
        EXPECT_NE(l.missing_material_files[0].find("gone.mtl"), std::string::npos);
    }
    const SceneLoad off = load_obj_cached(f.obj.string(), "", "test-writer");
    EXPECT_EQ(off.missing_material_files.size(), 1u);
}

TEST(SceneCache, AHitGivesWhatTheParseGave) {
    Fixture fx;
    const SceneLoad first = fx.load();
    EXPECT_FALSE(first.from_cache);
    EXPECT_EQ(first.cache_warning, "");
    ASSERT_TRUE(fs::exists(first.cache_file));
    const SceneLoad second = fx.load();
    EXPECT_TRUE(second.from_cache);
    EXPECT_EQ(second.cache_file, first.cache_file);
    expect_same(first, second);
    EXPECT_EQ(second.mesh.triangle_count(), 2u);
    EXPECT_EQ(second.mesh.dropped.total(), 2u);
    EXPECT_EQ(second.mesh.materials.at(0).emission.z, 3.0f);
    expect_same(second, load_obj_cached(fx.obj.string(), "", ""));  // the cache off: a plain parse
    const auto entries = list_scene_cache(fx.cache.string());
    ASSERT_EQ(entries.size(), 1u);
    EXPECT_EQ(entries[0].problem, "");
    EXPECT_EQ(entries[0].triangles, 2u);
    EXPECT_EQ(entries[0].writer, "test-writer");
}

TEST(SceneCache, AChangedObjOrMaterialFileIsNeverServed) {
    Fixture fx;
    fx.load();
    ASSERT_TRUE(fx.load().from_cache);
    // The same size, one vertex moved: a new mesh.
    std::string text = test::read_file_bytes(fx.obj.string());
    text.replace(text.find("v 1 1 0"), 7, "v 1 3 0");
    Fixture::write(fx.obj, text);
    SceneLoad l = fx.load();
    EXPECT_FALSE(l.from_cache);
    EXPECT_EQ(l.mesh.vertices[3].y, 3.0f);
    EXPECT_TRUE(fx.load().from_cache);
    // The material file changed, removed, then back.
    Fixture::write(fx.mtl, "newmtl red\nKd 0.9 0.1 0.1\nKe 1 2 4\n");
    l = fx.load();
    EXPECT_FALSE(l.from_cache);
    EXPECT_EQ(l.mesh.materials.at(0).emission.z, 4.0f);
    fs::remove(fx.mtl);
    l = fx.load();
    EXPECT_FALSE(l.from_cache);
    EXPECT_TRUE(l.mesh.materials.empty());
    EXPECT_TRUE(fx.load().from_cache);  // still missing: served, with the loader's warning again
    Fixture::write(fx.mtl, "newmtl red\nKe 0 0 5\n");
    l = fx.load();
    EXPECT_FALSE(l.from_cache);
    EXPECT_EQ(l.mesh.materials.at(0).emission.z, 5.0f);
}

TEST(SceneCache, AnotherLoaderVersionIsNotServed) {
    Fixture fx;
    const SceneLoad first = fx.load();
    // The entry as another loader version would have written it (checksum made again).
    std::string bytes = test::read_file_bytes(first.cache_file);
    const uint32_t other = kObjLoaderVersion + 1;
    std::memcpy(&bytes[12], &other, 4);
    const uint64_t sum = accel::fnv1a_words(bytes.data(), bytes.size() - 8);
    std::memcpy(&bytes[bytes.size() - 8], &sum, 8);
    Fixture::write(first.cache_file, bytes);
    const SceneLoad l = fx.load();
    EXPECT_FALSE(l.from_cache);
    EXPECT_EQ(l.cache_warning, "");
    EXPECT_TRUE(fx.load().from_cache);
}

TEST(SceneCache, ADamagedOrForeignEntryIsRebuiltWithAWarning) {
    Fixture fx;
    const SceneLoad first = fx.load();
    const std::string good = test::read_file_bytes(first.cache_file);
    const std::vector<std::pair<std::string, std::string>> damage = {
        {good.substr(0, 50), "shorter than its header"},
        {good.substr(0, good.size() - 5), "damaged"},
        {std::string(good).replace(good.size() / 2, 1, 1, char(good[good.size() / 2] ^ 4)), "damaged"},
        {"NOTACACHE" + std::string(200, 'x'), "not a bvhlab scene cache file"},
    };
    for (const auto& [bytes, why] : damage) {
        SCOPED_TRACE(why);
        Fixture::write(first.cache_file, bytes);
        const auto listed = list_scene_cache(fx.cache.string());
        ASSERT_EQ(listed.size(), 1u);
        EXPECT_NE(listed[0].problem.find(why), std::string::npos) << listed[0].problem;
        const SceneLoad l = fx.load();
        EXPECT_FALSE(l.from_cache);
        EXPECT_NE(l.cache_warning.find("ignored and rebuilt: "), std::string::npos) << l.cache_warning;
        EXPECT_NE(l.cache_warning.find(why), std::string::npos) << l.cache_warning;
        expect_same(first, l);
        EXPECT_TRUE(fx.load().from_cache);  // written again
    }
}

TEST(SceneCache, AnUnwritableFolderIsAWarningAndClearRemovesOnlyEntries) {
    Fixture fx;
    Fixture::write(fx.dir / "blocker", "a file where the cache folder should be");
    const SceneLoad l = load_obj_cached(fx.obj.string(), (fx.dir / "blocker" / "cache").string(), "w");
    EXPECT_FALSE(l.from_cache);
    EXPECT_NE(l.cache_warning.find("scene cache not written"), std::string::npos) << l.cache_warning;
    EXPECT_EQ(l.mesh.triangle_count(), 2u);
    fx.load();
    Fixture::write(fx.cache / "notes.txt", "not the cache's");
    Fixture::write(fx.cache / ".x.bvhscene.tmp-abc123", "a killed writer's temporary");
    uint64_t bytes = 0;
    EXPECT_EQ(clear_scene_cache(fx.cache.string(), &bytes), 2u);
    EXPECT_GT(bytes, 0u);
    EXPECT_TRUE(fs::exists(fx.cache / "notes.txt"));
    EXPECT_TRUE(list_scene_cache(fx.cache.string()).empty());
    EXPECT_FALSE(fx.load().from_cache);
}

TEST(SceneCache, ObjErrorsAreStillErrors) {
    Fixture fx;
    Fixture::write(fx.obj, "v 0 0 0\nv 1 0 abc\nv 0 1 0\nf 1 2 3\n");
    EXPECT_THROW(fx.load(), Error);
    EXPECT_THROW(load_obj_cached((fx.dir / "missing.obj").string(), fx.cache.string(), ""), Error);
}

TEST(SceneCache, FileHashSeesEveryByte) {
    Fixture fx;
    const fs::path big = fx.dir / "big.bin";
    std::string bytes(9u << 20, 'a');  // three 4 MiB chunks, the last partial
    Fixture::write(big, bytes);
    const uint64_t h = hash_file(big.string());
    for (size_t pos : {size_t(0), size_t(4u << 20), bytes.size() - 1}) {
        std::string b = bytes;
        b[pos] = 'b';
        Fixture::write(big, b);
        EXPECT_NE(hash_file(big.string()), h) << pos;
    }
    Fixture::write(big, bytes + "a");  // a longer file of the same bytes
    EXPECT_NE(hash_file(big.string()), h);
    bool exists = true;
    EXPECT_EQ(hash_file((fx.dir / "none").string(), &exists), 0u);
    EXPECT_FALSE(exists);
}

}  // namespace bvhlab::scene
