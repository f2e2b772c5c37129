// SPDX-License-Identifier: MIT
// Ray and hit files: a 48-byte header (magic, version, flags, count, writer), packed records and
// a checksum (version 2); version 1 files (24-byte header, no writer or checksum) are read too.
#include "traversal/rays/ray_file.h"

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

/// Reads the records of a ray or hit file and sets `set`'s query, writer and version.
template <typename T, typename Set>
std::vector<T> read_records(const std::string& path, const char* magic, uint32_t version, const char* what, Set& set) {
    File f = open(path, "rb");
    HeaderV2 h{};
    if (std::fread(&h.base, sizeof h.base, 1, f.get()) != 1)
        throw Error("'" + path + "' is truncated: shorter than the 24-byte " + std::string(what) + " header");
    if (std::memcmp(h.base.magic, magic, 8) != 0)
        throw Error("'" + path + "' is not a " + what + " (magic is not " + std::string(magic, 8) + ")");
    const bool v1 = h.base.version == 1;
    if (h.base.version != version && !v1)
        throw Error("'" + path + "' has " + what + " version " + std::to_string(h.base.version) +
                    "; this build reads versions 1 and " + std::to_string(version));
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
    s.rays = read_records<Ray>(path, "BVHLRAYS", kRayFileVersion, "bvhlab ray file", s);
    for (size_t i = 0; i < s.rays.size(); ++i) {
        const std::string why = invalid_ray(s.rays[i]);
        if (!why.empty()) throw Error("ray file '" + path + "': ray " + std::to_string(i) + " has " + why);
    }
    return s;
}

void write_hit_file(const std::string& path, const HitSet& set) {
    write_records(path, "BVHLHITS", kHitFileVersion, set.query, set.hits, set.writer);
}

HitSet read_hit_file(const std::string& path) {
    HitSet s;
    s.hits = read_records<Hit>(path, "BVHLHITS", kHitFileVersion, "bvhlab hit file", s);
    for (size_t i = 0; i < s.hits.size(); ++i) {
        const Hit& h = s.hits[i];
        if (h.tri < -1)
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " has triangle id " +
                        std::to_string(h.tri));
        if (h.tri >= 0 && !(std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v)))
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " has a non-finite t, u or v");
    }
    return s;
}

void check_hit_ids(const HitSet& set, size_t triangle_count, const std::string& path) {
    for (size_t i = 0; i < set.hits.size(); ++i)
        if (set.hits[i].tri >= 0 && size_t(set.hits[i].tri) >= triangle_count)
            throw Error("hit file '" + path + "': hit " + std::to_string(i) + " names triangle " +
                        std::to_string(set.hits[i].tri) + ", but the scene has " + std::to_string(triangle_count) +
                        " triangles (hits of another scene?)");
}

}  // namespace bvhlab::trav
