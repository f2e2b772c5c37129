// SPDX-License-Identifier: MIT
// Scene cache entries: a fixed header, the dependencies (each material file's or, for other
// formats, each file the importer opened beside the scene, by content hash), the scene (its
// materials, meshes, instances and camera), and a checksum of everything before it.
// Little-endian.
#include "scene/io/scene_cache.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/io/atomic_file.h"
#include "scene/io/obj_loader.h"
#include "scene/scene.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "scene cache files need a little-endian host");

namespace bvhlab::scene {
namespace fs = std::filesystem;
namespace {

constexpr char kMagic[9] = "BVHLSCNE";
constexpr const char* kExtension = ".bvhscene";

/// The fixed part of an entry.
struct Header {
    char magic[8];
    uint32_t version;         // kSceneCacheVersion
    uint32_t loader_version;  // the loader's version (kObjLoaderVersion, kAssimpLoaderVersion)
    uint64_t obj_hash;        // hash_file of the scene file
    uint64_t scene_hash;      // scene_hash of the mesh of a single-mesh scene, as a number (0 otherwise)
    uint64_t vertices, triangles, materials;  // vertices and triangles stored, over every mesh
    uint64_t dropped_non_finite, dropped_zero_area;
    uint32_t dependencies;  // material files
    uint32_t warnings;
    char writer[24];
};
static_assert(sizeof(Header) == 104, "scene cache header is 104 bytes");
static_assert(sizeof(Instance) == 56 && sizeof(SceneCamera) == 40, "instances and cameras are stored as they are");

/// Why an entry cannot be used: turned into a warning, never an error.
struct Unusable {
    std::string why;
};

class Out {
public:
    template <typename T>
    void pod(const T& v) {
        bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    void str(const std::string& s) {
        pod(uint32_t(s.size()));
        bytes_.append(s);
    }
    template <typename T>
    void array(const std::vector<T>& v) {
        if (!v.empty()) bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    std::string& bytes() { return bytes_; }

private:
    std::string bytes_;
};

class In {
public:
    In(const char* p, size_t n) : p_(p), n_(n) {}
    template <typename T>
    T pod() {
        T v;
        take(&v, sizeof v);
        return v;
    }
    std::string str() {
        const auto len = pod<uint32_t>();
        if (len > n_ - at_) throw Unusable{"a string runs past the end"};
        std::string s(p_ + at_, len);
        at_ += len;
        return s;
    }
    /// `count` records of T, checked against what is left before anything is allocated.
    template <typename T>
    void array(std::vector<T>& v, uint64_t count, const char* what) {
        if (count > (n_ - at_) / sizeof(T)) throw Unusable{std::string("its ") + what + " count runs past the end"};
        v.resize(count);
        take(v.data(), count * sizeof(T));
    }
    bool at_end() const { return at_ == n_; }

private:
    void take(void* dst, size_t bytes) {
        if (bytes > n_ - at_) throw Unusable{"it is truncated"};
        if (bytes) std::memcpy(dst, p_ + at_, bytes);
        at_ += bytes;
    }
    const char* p_;
    size_t n_, at_ = 0;
};

struct Dependency {
    std::string path;
    bool exists;
    uint64_t hash;
};

/// The entry of `file` in `dir`: its stem, and a hash of its absolute path and the loader version.
std::string entry_path(const std::string& dir, const std::string& file, uint32_t loader_version) {
    std::error_code ec;
    fs::path abs = fs::weakly_canonical(fs::absolute(file), ec);
    if (ec) abs = fs::absolute(file);
    const std::string key = abs.string() + '\0' + std::to_string(loader_version);
    return (fs::path(dir) /
            (abs.stem().string() + "-" + accel::hash_hex(accel::fnv1a(key.data(), key.size())) + kExtension))
        .string();
}

std::string read_whole(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw Unusable{std::string("it cannot be opened: ") + std::strerror(errno)};
    const auto size = static_cast<std::streamoff>(in.tellg());
    std::string data(size_t(size), '\0');
    in.seekg(0);
    if (!in.read(data.data(), size)) throw Unusable{"it cannot be read"};
    return data;
}

/// The parts of an entry, checked whole: the checksum, then every count and index.
struct Entry {
    Header h{};
    std::string source;
    std::vector<Dependency> deps;
    std::vector<std::string> warnings;
    InstancedScene scene;
};

Entry parse_entry(const std::string& data) {
    if (data.size() < sizeof(Header) + 8) throw Unusable{"it is shorter than its header"};
    Entry e;
    std::memcpy(&e.h, data.data(), sizeof e.h);
    if (std::memcmp(e.h.magic, kMagic, 8) != 0) throw Unusable{"it is not a bvhlab scene cache file"};
    if (e.h.version != kSceneCacheVersion)
        throw Unusable{"it has format version " + std::to_string(e.h.version) + ", this build writes " +
                       std::to_string(kSceneCacheVersion)};
    uint64_t stored;
    std::memcpy(&stored, data.data() + data.size() - 8, 8);
    if (accel::fnv1a_words(data.data(), data.size() - 8) != stored) throw Unusable{"it is damaged (checksum mismatch)"};
    In in(data.data() + sizeof(Header), data.size() - sizeof(Header) - 8);
    e.source = in.str();
    for (uint32_t i = 0; i < e.h.dependencies; ++i) {
        Dependency d;
        d.path = in.str();
        d.exists = in.pod<uint8_t>() != 0;
        d.hash = in.pod<uint64_t>();
        e.deps.push_back(std::move(d));
    }
    for (uint32_t i = 0; i < e.h.warnings; ++i) e.warnings.push_back(in.str());
    if (e.h.materials > (1u << 20)) throw Unusable{"its material count is implausible"};
    for (uint64_t i = 0; i < e.h.materials; ++i) {
        Material m;
        m.name = in.str();
        m.diffuse = in.pod<Vec3>();
        m.emission = in.pod<Vec3>();
        m.specular = in.pod<Vec3>();
        m.ambient = in.pod<Vec3>();
        m.shininess = in.pod<float>();
        m.ior = in.pod<float>();
        m.dissolve = in.pod<float>();
        m.illum = in.pod<int32_t>();
        m.diffuse_texture = in.str();
        m.normal_texture = in.str();
        m.bump_texture = in.str();
        m.bump_multiplier = in.pod<float>();
        e.scene.materials.push_back(std::move(m));
    }
    const auto meshes = in.pod<uint32_t>();
    uint64_t vertices = 0, triangles = 0;
    for (uint32_t k = 0; k < meshes; ++k) {
        TriangleMesh& mesh = e.scene.meshes.emplace_back();
        const auto nv = in.pod<uint64_t>(), nt = in.pod<uint64_t>();
        if (nt > (uint64_t(1) << 40)) throw Unusable{"its triangle count is implausible"};
        in.array(mesh.vertices, nv, "vertex");
        in.array(mesh.indices, 3 * nt, "index");
        in.array(mesh.material_ids, nt, "material id");
        const auto has_texcoords = in.pod<uint8_t>();
        if (has_texcoords > 1) throw Unusable{"its texture-coordinate flag is neither 0 nor 1"};
        if (has_texcoords) in.array(mesh.texcoords, 6 * nt, "texture coordinate");
        const auto has_normals = in.pod<uint8_t>();
        if (has_normals > 1) throw Unusable{"its normal flag is neither 0 nor 1"};
        if (has_normals) in.array(mesh.normals, 3 * nt, "normal");
        for (uint32_t i : mesh.indices)
            if (i >= mesh.vertices.size()) throw Unusable{"an index is out of range"};
        for (int32_t m : mesh.material_ids)
            if (m < -1 || (m >= 0 && uint64_t(m) >= e.h.materials)) throw Unusable{"a material id is out of range"};
        vertices += nv;
        triangles += nt;
    }
    if (vertices != e.h.vertices || triangles != e.h.triangles)
        throw Unusable{"its meshes do not hold the vertices and triangles its header counts"};
    in.array(e.scene.instances, in.pod<uint64_t>(), "instance");
    for (const Instance& inst : e.scene.instances)
        if (inst.mesh >= meshes || inst.material_offset != 0) throw Unusable{"an instance is out of range"};
    const auto has_camera = in.pod<uint8_t>();
    if (has_camera > 1) throw Unusable{"its camera flag is neither 0 nor 1"};
    if (has_camera) e.scene.camera = in.pod<SceneCamera>();
    if (!in.at_end()) throw Unusable{"it has trailing bytes"};
    e.scene.dropped = {e.h.dropped_non_finite, e.h.dropped_zero_area};
    return e;
}

/// Whether every dependency still has the bytes it had (or is still missing).
/// A material file's hash, or exists = false when it is missing or not a regular file (the
/// loader reads neither, and reports both as missing).
uint64_t dependency_hash(const std::string& path, bool* exists) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        *exists = false;
        return 0;
    }
    return hash_file(path, exists);
}

bool dependencies_unchanged(const std::vector<Dependency>& deps) {
    for (const Dependency& d : deps) {
        bool exists = false;
        const uint64_t h = dependency_hash(d.path, &exists);
        if (exists != d.exists || (exists && h != d.hash)) return false;
    }
    return true;
}

void write_entry(const std::string& path, const std::string& file, uint64_t file_hash, uint32_t loader_version,
                 const std::vector<Dependency>& deps, const CachedScene& load, const std::string& writer) {
    const InstancedScene& scene = load.scene;
    Out out;
    Header h{};
    std::memcpy(h.magic, kMagic, 8);
    h.version = kSceneCacheVersion;
    h.loader_version = loader_version;
    h.obj_hash = file_hash;
    h.scene_hash = load.scene_hash.empty() ? 0 : accel::hash_from_hex(load.scene_hash);
    for (const TriangleMesh& m : scene.meshes) {
        h.vertices += m.vertices.size();
        h.triangles += m.triangle_count();
    }
    h.materials = scene.materials.size();
    h.dropped_non_finite = scene.dropped.non_finite;
    h.dropped_zero_area = scene.dropped.zero_area;
    h.dependencies = uint32_t(deps.size());
    h.warnings = uint32_t(load.warnings.size());
    std::memcpy(h.writer, writer.data(), std::min(writer.size(), sizeof h.writer));
    out.pod(h);
    out.str(fs::absolute(file).string());
    for (const Dependency& d : deps) {
        out.str(d.path);
        out.pod(uint8_t(d.exists));
        out.pod(d.hash);
    }
    for (const std::string& w : load.warnings) out.str(w);
    for (const Material& m : scene.materials) {
        out.str(m.name);
        out.pod(m.diffuse);
        out.pod(m.emission);
        out.pod(m.specular);
        out.pod(m.ambient);
        out.pod(m.shininess);
        out.pod(m.ior);
        out.pod(m.dissolve);
        out.pod(m.illum);
        out.str(m.diffuse_texture);
        out.str(m.normal_texture);
        out.str(m.bump_texture);
        out.pod(m.bump_multiplier);
    }
    out.pod(uint32_t(scene.meshes.size()));
    for (const TriangleMesh& m : scene.meshes) {
        out.pod(uint64_t(m.vertices.size()));
        out.pod(uint64_t(m.triangle_count()));
        out.array(m.vertices);
        out.array(m.indices);
        out.array(m.material_ids);
        out.pod(uint8_t(!m.texcoords.empty()));
        out.array(m.texcoords);
        out.pod(uint8_t(!m.normals.empty()));
        out.array(m.normals);
    }
    out.pod(uint64_t(scene.instances.size()));
    out.array(scene.instances);
    out.pod(uint8_t(scene.camera.has_value()));
    if (scene.camera) out.pod(*scene.camera);
    const uint64_t sum = accel::fnv1a_words(out.bytes().data(), out.bytes().size());
    out.pod(sum);
    std::error_code ec;
    fs::create_directories(fs::path(path).parent_path(), ec);
    write_file_atomically(path, [&](std::FILE* f) { std::fwrite(out.bytes().data(), 1, out.bytes().size(), f); });
}

}  // namespace

std::string default_scene_cache_dir() {
    auto env = [](const char* name) -> std::string {
        const char* v = std::getenv(name);
        return v && *v ? v : "";
    };
    if (const std::string d = env("BVHLAB_CACHE_DIR"); !d.empty()) return d;
    if (const std::string d = env("XDG_CACHE_HOME"); !d.empty()) return d + "/bvhlab";
    if (const std::string d = env("HOME"); !d.empty()) return d + "/.cache/bvhlab";
    return "";
}

uint64_t hash_file(const std::string& path, bool* exists) {
    if (exists) *exists = true;
    // Checked before opening: opening a FIFO would wait for a writer.
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        if (errno == ENOENT && exists) {
            *exists = false;
            return 0;
        }
        throw Error("cannot open '" + path + "': " + std::strerror(errno));
    }
    if (!S_ISREG(st.st_mode))
        throw Error("cannot read '" + path + "': " + not_regular_reason(st.st_mode) +
                    (S_ISDIR(st.st_mode) ? "" : "; save it to a file and give its path"));
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {  // replaced in between
        ::close(fd);
        throw Error("cannot read '" + path + "': it is not a regular file");
    }
    const size_t size = size_t(st.st_size);
    if (size == 0) {
        ::close(fd);
        return accel::fnv1a_words(nullptr, 0);
    }
    void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    ::close(fd);
    if (map == MAP_FAILED) throw Error("cannot read '" + path + "': " + std::strerror(errno));
    constexpr size_t kChunk = size_t(4) << 20;
    const size_t chunks = (size + kChunk - 1) / kChunk;
    std::vector<uint64_t> part(chunks);
    const auto* base = static_cast<const char*>(map);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        const size_t b = c * kChunk;
        part[c] = accel::fnv1a_words(base + b, std::min(kChunk, size - b));
    });
    ::munmap(map, size);
    uint64_t h = accel::fnv1a_words(&size, sizeof size);
    return accel::fnv1a_words(part.data(), part.size() * sizeof(uint64_t), h);
}

CachedScene load_cached(const std::string& path, uint32_t loader_version, const std::string& cache_dir,
                        const std::string& writer, const SceneParser& parser) {
    CachedScene r;
    auto note_dependencies = [&r](const std::vector<std::string>& files) {
        r.dependencies = files;
        std::error_code ec;
        for (const std::string& f : files)
            if (!fs::is_regular_file(f, ec)) r.missing_dependencies.push_back(f);
    };
    // The file parsed (no cache, an entry that is not a regular file, a miss); its dependencies.
    auto parse = [&]() {
        std::vector<std::string> files;
        r.scene = parser(&r.warnings, &files);
        const bool one_mesh = r.scene.instances.size() == 1 && r.scene.instances[0].transform.is_identity();
        r.scene_hash = one_mesh ? scene_hash(r.scene.meshes[r.scene.instances[0].mesh]) : "";
        note_dependencies(files);
        return files;
    };
    if (cache_dir.empty()) {
        parse();
        return r;
    }
    bool exists = false;
    const uint64_t file_hash = hash_file(path, &exists);
    if (!exists) throw Error("cannot open '" + path + "': " + std::strerror(ENOENT));
    r.cache_file = entry_path(cache_dir, path, loader_version);
    std::error_code ec;
    const fs::file_status entry = fs::symlink_status(r.cache_file, ec);
    if (fs::exists(entry) && !fs::is_regular_file(entry)) {
        // Never read (a FIFO would hang) and never replaced: the cache's files are its own.
        parse();
        r.cache_warning = "scene cache entry '" + r.cache_file + "' is not a regular file: ignored, and not written";
        return r;
    }
    if (fs::exists(entry)) {
        try {
            Entry e = parse_entry(read_whole(r.cache_file));
            if (e.h.loader_version == loader_version && e.h.obj_hash == file_hash && dependencies_unchanged(e.deps)) {
                r.scene = std::move(e.scene);
                r.warnings = std::move(e.warnings);
                r.scene_hash = e.h.scene_hash ? accel::hash_hex(e.h.scene_hash) : "";
                r.from_cache = true;
                std::vector<std::string> files;
                for (const Dependency& d : e.deps) files.push_back(d.path);
                note_dependencies(files);
                return r;
            }
        } catch (const Unusable& u) {
            r.cache_warning = "scene cache entry '" + r.cache_file + "' ignored and rebuilt: " + u.why;
        }
    }
    const std::vector<std::string> files = parse();
    std::vector<Dependency> deps;
    for (const std::string& m : files) {
        Dependency d{m, false, 0};
        d.hash = dependency_hash(m, &d.exists);
        deps.push_back(std::move(d));
    }
    try {
        write_entry(r.cache_file, path, file_hash, loader_version, deps, r, writer);
    } catch (const Error& e) {
        r.cache_warning = std::string("scene cache not written: ") + e.what();
    }
    return r;
}

SceneLoad load_obj_cached(const std::string& obj_path, const std::string& cache_dir, const std::string& writer,
                          const LoadProgress& progress) {
    CachedScene c = load_cached(obj_path, kObjLoaderVersion, cache_dir, writer,
                                [&](std::vector<std::string>* warnings, std::vector<std::string>* files) {
                                    return single_instance(load_obj(obj_path, warnings, files, progress));
                                });
    SceneLoad r;
    r.mesh = single_mesh(std::move(c.scene), /*allow_flatten=*/true, "'" + obj_path + "'");
    r.warnings = std::move(c.warnings);
    r.material_files = std::move(c.dependencies);
    r.missing_material_files = std::move(c.missing_dependencies);
    r.scene_hash = std::move(c.scene_hash);
    r.from_cache = c.from_cache;
    r.cache_file = std::move(c.cache_file);
    r.cache_warning = std::move(c.cache_warning);
    return r;
}

std::vector<SceneCacheEntry> list_scene_cache(const std::string& dir) {
    std::vector<SceneCacheEntry> out;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return out;
    for (const auto& de : fs::directory_iterator(dir, ec)) {
        if (de.path().extension() != kExtension || de.path().filename().string()[0] == '.') continue;
        SceneCacheEntry s;
        s.file = de.path().string();
        if (!de.is_regular_file(ec) || de.is_symlink(ec)) {
            s.problem = "not a regular file";
            out.push_back(std::move(s));
            continue;
        }
        s.bytes = de.file_size(ec);
        try {
            const Entry e = parse_entry(read_whole(s.file));
            s.source = e.source;
            s.triangles = e.h.triangles;
            s.writer = std::string(e.h.writer, strnlen(e.h.writer, sizeof e.h.writer));
        } catch (const Unusable& u) {
            s.problem = u.why;
        }
        out.push_back(std::move(s));
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.file < b.file; });
    return out;
}

size_t clear_scene_cache(const std::string& dir, uint64_t* bytes) {
    size_t n = 0;
    uint64_t total = 0;
    std::error_code ec;
    if (fs::is_directory(dir, ec)) {
        for (const auto& de : fs::directory_iterator(dir, ec)) {
            const std::string name = de.path().filename().string();
            const bool entry = de.path().extension() == kExtension && name[0] != '.';
            const bool temporary = name[0] == '.' && name.find(kExtension + std::string(".tmp-")) != std::string::npos;
            if ((!entry && !temporary) || !de.is_regular_file(ec) || de.is_symlink(ec))
                continue;  // never anything but the cache's own files
            const uint64_t size = de.file_size(ec);
            if (fs::remove(de.path(), ec)) {
                ++n;
                total += size;
            }
        }
    }
    if (bytes) *bytes = total;
    return n;
}

}  // namespace bvhlab::scene
