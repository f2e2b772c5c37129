// SPDX-License-Identifier: MIT
// Ray and hit files: a 24-byte header (magic, version, flags, count) and packed records.
#include "traversal/rays/ray_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "accel/core/check.h"

// Records are written as the in-memory structs, which is the little-endian file layout only on
// little-endian hosts (x86-64, AArch64 Linux).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "ray files need a little-endian host");

namespace bvhlab::trav {
namespace {

constexpr uint32_t kFlagAnyHit = 1u;

struct Header {
    char magic[8];
    uint32_t version;
    uint32_t flags;
    uint64_t count;
};
static_assert(sizeof(Header) == 24, "file header is 24 bytes");

using File = std::unique_ptr<FILE, int (*)(FILE*)>;

File open(const std::string& path, const char* mode) {
    FILE* f = std::fopen(path.c_str(), mode);
    if (!f) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    return File(f, &std::fclose);
}

template <typename T>
void write_records(const std::string& path, const char* magic, uint32_t version, Query query,
                   const std::vector<T>& records) {
    File f = open(path, "wb");
    Header h{};
    std::memcpy(h.magic, magic, 8);
    h.version = version;
    h.flags = query == Query::kAny ? kFlagAnyHit : 0u;
    h.count = records.size();
    bool ok = std::fwrite(&h, sizeof h, 1, f.get()) == 1 &&
              (records.empty() || std::fwrite(records.data(), sizeof(T), records.size(), f.get()) == records.size());
    ok = (std::fclose(f.release()) == 0) && ok;
    if (!ok) throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

template <typename T>
std::vector<T> read_records(const std::string& path, const char* magic, uint32_t version,
                            const char* what, Query& query) {
    File f = open(path, "rb");
    Header h{};
    if (std::fread(&h, sizeof h, 1, f.get()) != 1)
        throw Error("'" + path + "' is truncated: shorter than the 24-byte " + what + " header");
    if (std::memcmp(h.magic, magic, 8) != 0)
        throw Error("'" + path + "' is not a " + what + " (magic is not " + std::string(magic, 8) + ")");
    if (h.version != version)
        throw Error("'" + path + "' has " + what + " version " + std::to_string(h.version) +
                    "; this build reads version " + std::to_string(version));
    if (h.flags & ~kFlagAnyHit)
        throw Error("'" + path + "' sets unknown flag bits 0x" + std::to_string(h.flags & ~kFlagAnyHit));
    query = (h.flags & kFlagAnyHit) ? Query::kAny : Query::kClosest;
    std::fseek(f.get(), 0, SEEK_END);
    const long size = std::ftell(f.get());
    const unsigned long long expect = sizeof(Header) + h.count * sizeof(T);
    if (size < 0 || h.count > (1ull << 40) || (unsigned long long)size != expect)
        throw Error("'" + path + "' is truncated or has trailing bytes: header says " +
                    std::to_string(h.count) + " records (" + std::to_string(expect) +
                    " bytes), file has " + std::to_string(size) + " bytes");
    std::fseek(f.get(), sizeof(Header), SEEK_SET);
    std::vector<T> out(h.count);
    if (h.count && std::fread(out.data(), sizeof(T), out.size(), f.get()) != out.size())
        throw Error("cannot read '" + path + "': " + std::strerror(errno));
    return out;
}

}  // namespace

void write_ray_file(const std::string& path, const RaySet& set) {
    write_records(path, "BVHLRAYS", kRayFileVersion, set.query, set.rays);
}

RaySet read_ray_file(const std::string& path) {
    RaySet s;
    s.rays = read_records<Ray>(path, "BVHLRAYS", kRayFileVersion, "bvhlab ray file", s.query);
    return s;
}

void write_hit_file(const std::string& path, const HitSet& set) {
    write_records(path, "BVHLHITS", kHitFileVersion, set.query, set.hits);
}

HitSet read_hit_file(const std::string& path) {
    HitSet s;
    s.hits = read_records<Hit>(path, "BVHLHITS", kHitFileVersion, "bvhlab hit file", s.query);
    return s;
}

}  // namespace bvhlab::trav
