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
#include "scene/io/scene_file.h"
#include "scene/scene.h"
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
              "illum 7\nmap_Kd tex\\red.png\nnorm tex/n.png\nbump -bm 0.25 tex/h.png\n");
        write(obj,
              "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 2\nv nan 0 0\nvt 0.25 0.5\nvt 1 0\n"
              "vn 0 0.6 0.8\nusemtl red\nf 1/1/1 2/2/1 3/1/1\nf 2 4 3\nf 1 5 6\nf 1 2 2\n");
    }
    ~Fixture() { fs::remove_all(dir); }
    static void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
    SceneLoad load() const { return load_obj_cached(obj.string(), cache.string(), "test-writer"); }
    std::string entry() const {
        for (const auto& e : fs::directory_iterator(cache)) return e.path().string();
        return "";
    }
};

void expect_same_normals(const TriangleMesh& a, const TriangleMesh& b) {
    ASSERT_EQ(a.normals.size(), b.normals.size());
    EXPECT_EQ(0, std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3)));
}

void expect_same(const SceneLoad& a, const SceneLoad& b) {
    EXPECT_EQ(a.scene_hash, b.scene_hash);
    ASSERT_EQ(a.mesh.vertices.size(), b.mesh.vertices.size());
    // NaN vertices (of dropped triangles) compare by bytes.
    EXPECT_EQ(0, std::memcmp(a.mesh.vertices.data(), b.mesh.vertices.data(), a.mesh.vertices.size() * sizeof(Vec3)));
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    EXPECT_EQ(a.mesh.material_ids, b.mesh.material_ids);
    EXPECT_EQ(a.mesh.texcoords, b.mesh.texcoords);
    expect_same_normals(a.mesh, b.mesh);
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
        EXPECT_EQ(x.normal_texture, y.normal_texture);
        EXPECT_EQ(x.bump_texture, y.bump_texture);
        EXPECT_EQ(x.bump_multiplier, y.bump_multiplier);
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
    ASSERT_EQ(second.mesh.normals.size(), 6u);  // the first face's vn, zeros for the second's
    EXPECT_NEAR(second.mesh.normals[1].y, 0.6f, 1e-6f);
    EXPECT_EQ(second.mesh.normals[5].z, 0.0f);
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

namespace bvhlab::scene {

namespace {

/// data/instances.gltf with its buffer moved into buffer.bin beside it, in a fresh folder.
struct GltfFixture {
    fs::path dir, gltf, bin, cache;
    GltfFixture() {
        dir = fs::temp_directory_path() / ("bvhlab_scene_cache_gltf_" + std::to_string(getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
        gltf = dir / "scene.gltf";
        bin = dir / "buffer.bin";
        cache = dir / "cache";
        std::string text = test::read_file_bytes(test::data_dir() + "/instances.gltf");
        const std::string prefix = "data:application/octet-stream;base64,";
        const size_t at = text.find(prefix), end = text.find('"', at);
        std::ofstream(bin, std::ios::binary)
            << base64_decode(text.substr(at + prefix.size(), end - at - prefix.size()));
        text.replace(at, end - at, "buffer.bin");
        std::ofstream(gltf, std::ios::binary) << text;
    }
    ~GltfFixture() { fs::remove_all(dir); }
    SceneFileLoad load() const { return load_scene_file(gltf.string(), cache.string(), "test-writer"); }
    static std::string base64_decode(const std::string& in) {
        std::string out;
        uint32_t val = 0;  // the last 24 bits read
        int bits = -8;
        for (unsigned char c : in) {
            const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
            const char* p = std::strchr(table, c);
            if (!p || c == 0) break;
            val = ((val << 6) | uint32_t(p - table)) & 0xffffffu;
            bits += 6;
            if (bits >= 0) {
                out.push_back(char((val >> bits) & 0xff));
                bits -= 8;
            }
        }
        return out;
    }
};

void expect_same_scene(const InstancedScene& a, const InstancedScene& b) {
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    for (size_t m = 0; m < a.meshes.size(); ++m) {
        EXPECT_EQ(a.meshes[m].indices, b.meshes[m].indices);
        EXPECT_EQ(a.meshes[m].material_ids, b.meshes[m].material_ids);
        EXPECT_EQ(a.meshes[m].texcoords, b.meshes[m].texcoords);
        expect_same_normals(a.meshes[m], b.meshes[m]);
        EXPECT_EQ(scene_hash(a.meshes[m]), scene_hash(b.meshes[m]));
    }
    ASSERT_EQ(a.instances.size(), b.instances.size());
    for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_TRUE(a.instances[i].transform == b.instances[i].transform);
        EXPECT_EQ(a.instances[i].mesh, b.instances[i].mesh);
    }
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (size_t i = 0; i < a.materials.size(); ++i) {
        EXPECT_EQ(a.materials[i].name, b.materials[i].name);
        EXPECT_EQ(a.materials[i].illum, b.materials[i].illum);
        EXPECT_EQ(a.materials[i].dissolve, b.materials[i].dissolve);
        EXPECT_EQ(a.materials[i].emission.y, b.materials[i].emission.y);
    }
    ASSERT_EQ(a.camera.has_value(), b.camera.has_value());
    if (a.camera) {
        EXPECT_EQ(a.camera->eye.z, b.camera->eye.z);
        EXPECT_EQ(a.camera->fov_y_deg, b.camera->fov_y_deg);
    }
}

}  // namespace

// A glTF's converted scene (meshes, instances, materials, camera) is cached; its external buffer
// is a dependency: changing it is a miss, and the entry is written again.
TEST(SceneCache, CachesConvertedGltfScenesAndWatchesTheirBuffers) {
    GltfFixture f;
    const SceneFileLoad first = f.load();
    EXPECT_FALSE(first.from_cache);
    EXPECT_EQ(first.cache_warning, "");
    ASSERT_EQ(first.dependencies.size(), 1u) << "the buffer Assimp opened";
    EXPECT_EQ(fs::path(first.dependencies[0]).filename(), "buffer.bin");
    EXPECT_TRUE(first.scene.is_instanced());
    const SceneFileLoad second = f.load();
    EXPECT_TRUE(second.from_cache);
    expect_same_scene(first.scene, second.scene);
    expect_same_scene(first.scene, load_assimp(f.gltf.string()));
    EXPECT_EQ(second.dependencies, first.dependencies);
    // A changed buffer (the first cube vertex moved) is a miss, with the new geometry.
    std::string bytes = test::read_file_bytes(f.bin.string());
    const float moved = 0.25f;
    std::memcpy(bytes.data(), &moved, sizeof moved);
    std::ofstream(f.bin, std::ios::binary) << bytes;
    const SceneFileLoad third = f.load();
    EXPECT_FALSE(third.from_cache);
    EXPECT_NE(scene_hash(flatten(third.scene)), scene_hash(flatten(first.scene)));
    EXPECT_TRUE(f.load().from_cache);
    // A PLY: one mesh, no dependencies, its hash kept with the entry.
    const std::string ply = (f.dir / "cube.ply").string();
    fs::copy_file(test::data_dir() + "/cube_binary.ply", ply);
    const SceneFileLoad p1 = load_scene_file(ply, f.cache.string(), "w"),
                        p2 = load_scene_file(ply, f.cache.string(), "w");
    EXPECT_FALSE(p1.from_cache);
    EXPECT_TRUE(p2.from_cache);
    EXPECT_EQ(p1.scene_hash, scene_hash(flatten(p1.scene)));
    EXPECT_EQ(p2.scene_hash, p1.scene_hash);
    EXPECT_TRUE(p2.dependencies.empty());
}

}  // namespace bvhlab::scene
