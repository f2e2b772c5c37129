// SPDX-License-Identifier: MIT
// Ray and hit files: a 48-byte header (magic, version, flags, count, writer), packed records and
// a checksum (version 2); version 1 files (24-byte header, no writer or checksum) are read too.
#include "traversal/rays/ray_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "accel/core/check.h"
#include "accel/core/checksum.h"
#include "scene/domain.h"
#include "scene/io/atomic_file.h"

// Records are written as the in-memory structs, which is the little-endian file layout only on
// little-endian hosts (x86-64, AArch64 Linux).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "ray files need a little-endian host");

namespace bvhlab::trav {
namespace {

constexpr uint32_t kFlagAnyHit = 1u;

/// Version 1's header; version 2 follows it with the writer, and ends with the checksum.
struct Header {
    char magic[8];
    uint32_t version;
    uint32_t flags;
    uint64_t count;
};
static_assert(sizeof(Header) == 24, "file header is 24 bytes");

struct HeaderV2 {
    Header base;
    char writer[kFileWriterBytes];
};
static_assert(sizeof(HeaderV2) == 48, "version 2 header is 48 bytes");

using File = std::unique_ptr<FILE, int (*)(FILE*)>;

File open(const std::string& path, const char* mode) {
    if (std::filesystem::is_directory(path)) throw Error("'" + path + "' is a folder, not a file");
    FILE* f = std::fopen(path.c_str(), mode);
    if (!f) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    return File(f, &std::fclose);
}

/// The checksum of a version 2 file: its header, then its records.
template <typename T>
uint64_t content_checksum(const HeaderV2& h, const std::vector<T>& records) {
    return accel::fnv1a_words(records.data(), records.size() * sizeof(T), accel::fnv1a_words(&h, sizeof h));
}

template <typename T>
void write_records(const std::string& path, const char* magic, uint32_t version, Query query,
                   const std::vector<T>& records, const std::string& writer) {
    HeaderV2 h{};
    std::memcpy(h.base.magic, magic, 8);
    h.base.version = version;
    h.base.flags = query == Query::kAny ? kFlagAnyHit : 0u;
    h.base.count = records.size();
    const std::string w = writer.empty() ? "unknown" : writer.substr(0, kFileWriterBytes);
    std::memcpy(h.writer, w.data(), w.size());
    const uint64_t sum = content_checksum(h, records);
    scene::write_file_atomically(path, [&](std::FILE* f) {
        std::fwrite(&h, sizeof h, 1, f);
        if (!records.empty()) std::fwrite(records.data(), sizeof(T), records.size(), f);
        std::fwrite(&sum, sizeof sum, 1, f);
    });
}

/// A hit of a version 3 file.
struct HitRecord3 {
    Hit hit;
    HitInstance where;
};
static_assert(sizeof(HitRecord3) == 24, "version 3 hit records are 24 bytes");

/// The version field of a file whose header can be read, else 0 (read_records then says why).
uint32_t peek_version(const std::string& path) {
    if (std::filesystem::is_directory(path)) return 0;
    File f(std::fopen(path.c_str(), "rb"), &std::fclose);
    Header h{};
    if (!f || std::fread(&h, sizeof h, 1, f.get()) != 1) return 0;
    return h.version;
}

/// Reads the records of a ray or hit file and sets `set`'s query, writer and version. Files of
/// version 1 and of `version` are read; `readable` names every version the caller reads.
template <typename T, typename Set>
std::vector<T> read_records(const std::string& path, const char* magic, uint32_t version, const char* what, Set& set,
                            const char* readable) {
    File f = open(path, "rb");
    HeaderV2 h{};
    if (std::fread(&h.base, sizeof h.base, 1, f.get()) != 1)
        throw Error("'" + path + "' is truncated: shorter than the 24-byte " + std::string(what) + " header");
    if (std::memcmp(h.base.magic, magic, 8) != 0)
        throw Error("'" + path + "' is not a " + what + " (magic is not " + std::string(magic, 8) + ")");
    const bool v1 = h.base.version == 1;
    if (h.base.version != version && !v1)
        throw Error("'" + path + "' has " + what + " version " + std::to_string(h.base.version) +
                    "; this build reads versions " + readable);
    if (h.base.flags & ~kFlagAnyHit)
        throw Error("'" + path + "' sets unknown flag bits 0x" + std::to_string(h.base.flags & ~kFlagAnyHit));
    set.query = (h.base.flags & kFlagAnyHit) ? Query::kAny : Query::kClosest;
    set.version = h.base.version;
    const size_t header = v1 ? sizeof(Header) : sizeof(HeaderV2), trailer = v1 ? 0 : sizeof(uint64_t);
    if (!v1 && std::fread(h.writer, sizeof h.writer, 1, f.get()) != 1)
        throw Error("'" + path + "' is truncated: shorter than the 48-byte " + std::string(what) + " header");
    set.writer = v1 ? std::string() : std::string(h.writer, strnlen(h.writer, sizeof h.writer));
    // The writer is text for people and JSON: a byte outside printable ASCII (an escape
    // sequence, 0xFF) is shown as '?', never passed to a terminal or a JSON encoder.
    for (char& c : set.writer)
        if (c < 0x20 || c > 0x7e) c = '?';
    std::fseek(f.get(), 0, SEEK_END);
    const long size = std::ftell(f.get());
    if (size < 0) throw Error("cannot read '" + path + "': " + std::strerror(errno));
    // The count is checked against the file's size before anything is allocated, by division
    // (a count near 2^64 wrapped the product, and the message with it).
    const unsigned long long body = (unsigned long long)size >= header + trailer ? size - header - trailer : 0;
    if (h.base.count > body / sizeof(T) || h.base.count * sizeof(T) != body)
        throw Error("'" + path + "' is truncated or has trailing bytes: header says " + std::to_string(h.base.count) +
                    " records of " + std::to_string(sizeof(T)) + " bytes, the file has room for " +
                    std::to_string(body / sizeof(T)) + " (" + std::to_string(size) + " bytes)");
    std::fseek(f.get(), long(header), SEEK_SET);
    std::vector<T> out(h.base.count);
    uint64_t stored = 0;
    if ((h.base.count && std::fread(out.data(), sizeof(T), out.size(), f.get()) != out.size()) ||
        (!v1 && std::fread(&stored, sizeof stored, 1, f.get()) != 1))
        throw Error("cannot read '" + path + "': " + std::strerror(errno));
    if (!v1 && content_checksum(h, out) != stored)
        throw Error("'" + path + "' is damaged: its checksum does not match its contents (" + what + ", " +
                    std::to_string(h.base.count) + " records)");
    return out;
}

}  // namespace

void write_ray_file(const std::string& path, const RaySet& set) {
    write_records(path, "BVHLRAYS", kRayFileVersion, set.query, set.rays, set.writer);
}

std::string invalid_ray(const Ray& r) {
    auto finite3 = [](Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    auto str = [](Vec3 v) {
        char b[96];
        std::snprintf(b, sizeof b, "(%g, %g, %g)", v.x, v.y, v.z);
        return std::string(b);
    };
    if (!finite3(r.org)) return "a non-finite origin " + str(r.org);
    if (!finite3(r.dir)) return "a non-finite direction " + str(r.dir);
    if (r.dir.x == 0.0f && r.dir.y == 0.0f && r.dir.z == 0.0f) return "a zero direction";
    if (std::string p = scene::vec_problem("an origin", r.org); !p.empty()) return p;
    if (std::string p = scene::vec_problem("a direction", r.dir); !p.empty()) return p;
    if (!std::isfinite(r.tmin) || r.tmin < 0.0f) return "tmin " + std::to_string(r.tmin) + " (must be finite and >= 0)";
    if (std::isnan(r.tmax) || r.tmax < r.tmin)
        return "tmax " + std::to_string(r.tmax) + " below tmin " + std::to_string(r.tmin) + " or NaN";
    return "";
}

RaySet read_ray_file(const std::string& path) {
    RaySet s;
    s.rays = read_records<Ray>(path, "BVHLRAYS", kRayFileVersion, "bvhlab ray file", s, "1 and 2");
    for (size_t i = 0; i < s.rays.size(); ++i) {
        const std::string why = invalid_ray(s.rays[i]);
        if (!why.empty()) throw Error("ray file '" + path + "': ray " + std::to_string(i) + " has " + why);
    }
    return s;
}

HitInstance split_hit_id(const InstanceFirstIds& first, uint64_t id) {
    BVHLAB_CHECK(first.size() >= 2 && id < first.back(), "split_hit_id: an id outside the instances' range");
    // The last instance whose first id is <= id (instances of empty meshes share a first id).
    const auto it = std::upper_bound(first.begin(), first.end() - 1, id) - 1;
    return {int32_t(it - first.begin()), int32_t(id - *it)};
}

void write_hit_file(const std::string& path, const HitSet& set, const InstanceFirstIds& first) {
    std::vector<HitRecord3> records(set.hits.size());
    for (size_t i = 0; i < set.hits.size(); ++i) {
        const Hit& h = set.hits[i];
        HitInstance w{-1, -1};
        if (h.is_hit() && first.empty()) {
            w = {0, h.tri};
        } else if (h.is_hit()) {
            if (first.size() < 2 || uint64_t(h.tri) >= first.back())
                throw Error("hit file '" + path + "': hit " + std::to_string(i) + " names triangle " +
                            std::to_string(h.tri) + ", outside the scene's " +
                            std::to_string(first.empty() ? 0 : first.back()) + " triangles");
            w = split_hit_id(first, uint64_t(h.tri));
        }
        records[i] = {h, w};
    }
    write_records(path, "BVHLHITS", kHitFileVersion, set.query, records, set.writer);
}

HitSet read_hit_file(const std::string& path) {
    HitSet s;
    if (peek_version(path) == 3) {
        const std::vector<HitRecord3> records =
            read_records<HitRecord3>(path, "BVHLHITS", 3, "bvhlab hit file", s, "1 to 3");
        s.hits.resize(records.size());
        s.instances.resize(records.size());
        for (size_t i = 0; i < records.size(); ++i) {
            s.hits[i] = records[i].hit;
            s.instances[i] = records[i].where;
        }
    } else {
        s.hits = read_records<Hit>(path, "BVHLHITS", 2, "bvhlab hit file", s, "1 to 3");
    }
    for (size_t i = 0; i < s.hits.size(); ++i) {
        const Hit& h = s.hits[i];
        if (h.tri < -1)
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " has triangle id " +
                        std::to_string(h.tri));
        if (h.tri >= 0 && !(std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v)))
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " has a non-finite t, u or v");
        if (!s.instances.empty()) {
            const HitInstance w = s.instances[i];
            if (h.tri < 0 ? (w.instance != -1 || w.tri != -1) : (w.instance < 0 || w.tri < 0))
                throw Error("hit file '" + path + "': hit " + std::to_string(i) + " has instance " +
                            std::to_string(w.instance) + " and triangle " + std::to_string(w.tri) +
                            (h.tri < 0 ? " for a miss (must be -1 and -1)" : " (negative for a hit)"));
        }
    }
    return s;
}

void check_hit_ids(const HitSet& set, const InstanceFirstIds& first, const std::string& path) {
    BVHLAB_CHECK(first.size() >= 2, "check_hit_ids needs the instances' first ids and the total");
    const uint64_t triangle_count = first.back();
    for (size_t i = 0; i < set.hits.size(); ++i) {
        const Hit& h = set.hits[i];
        if (h.tri < 0) continue;
        if (uint64_t(h.tri) >= triangle_count)
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " names triangle " +
                        std::to_string(h.tri) + ", but the scene has " + std::to_string(triangle_count) +
                        " triangles (hits of another scene?)");
        if (set.instances.empty()) continue;
        const HitInstance want = split_hit_id(first, uint64_t(h.tri)), got = set.instances[i];
        if (got.instance != want.instance || got.tri != want.tri)
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " names triangle " +
                        std::to_string(h.tri) + " as instance " + std::to_string(got.instance) + "'s triangle " +
                        std::to_string(got.tri) + ", but in this scene it is instance " +
                        std::to_string(want.instance) + "'s triangle " + std::to_string(want.tri) +
                        " (hits of another scene?)");
    }
}

}  // namespace bvhlab::trav
