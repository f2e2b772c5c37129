// SPDX-License-Identifier: MIT
// OBJ loading: one read of the file, a strict syntax scan (tinyobjloader reads `v 1 0 abc`
// as a zero and only warns about out-of-range indices), then tinyobjloader's parser.
#include "scene/io/obj_loader.h"

#include <tiny_obj_loader.h>

#include <sys/stat.h>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <future>
#include <map>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "accel/core/check.h"
#include "scene/io/atomic_file.h"

namespace bvhlab::scene {
namespace {

std::string read_file(const std::string& path) {
    struct stat st {};
    if (stat(path.c_str(), &st) != 0) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    // A pipe's size is unknown until it is read through; bvhlab reads scenes from files.
    if (!S_ISREG(st.st_mode)) {
        const std::string why = not_regular_reason(st.st_mode);
        throw Error("cannot read '" + path + "': " + why +
                    (S_ISDIR(st.st_mode) ? "" : "; save it to a file and give its path"));
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    std::string data(size_t(st.st_size), '\0');
    if (!in.read(data.data(), std::streamsize(data.size()))) throw Error("cannot read '" + path + "': read failed");
    return data;
}

/// Whether [b, e) is a number as a whole, as strtod reads it; its value in `value`.
/// The common forms go through std::from_chars without a copy (the scan of furball spent most
/// of its time copying tokens into strings for strtod); the rest (a leading '+', inf, nan)
/// through strtod. Hexadecimal is refused: strtod reads `0x10` as 16, but tinyobjloader reads
/// 0, so the scan would pass a value the parser then gets wrong.
bool is_number(const char* b, const char* e, double& value) {
    if (b == e) return false;
    const auto [ptr, ec] = std::from_chars(b, e, value);
    if (ec == std::errc() && ptr == e) return true;
    const char* digits = b + (*b == '+' || *b == '-');
    if (e - digits >= 2 && digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X')) return false;
    std::string tok(b, e);
    char* end = nullptr;
    value = std::strtod(tok.c_str(), &end);
    return end == tok.c_str() + tok.size();
}

/// One face-vertex token by strtol on a copy: v, v/vt, v//vn or v/vt/vn with non-zero integers;
/// ref gets the v, vt and vn references (0 where absent).
bool parse_face_token_slow(const char* b, const char* e, long (&ref)[3]);

/// [-]digits with at most 10 digits at p, or false (p unmoved).
bool fast_int(const char*& p, const char* e, long& v) {
    const char* s = p;
    const bool neg = p < e && *p == '-';
    if (neg) ++p;
    long x = 0;
    int digits = 0;
    for (; p < e && *p >= '0' && *p <= '9'; ++p) {
        if (++digits > 10) {  // stop before the product can overflow (found by the OBJ fuzz target)
            p = s;
            return false;
        }
        x = x * 10 + (*p - '0');
    }
    if (digits == 0) {
        p = s;
        return false;
    }
    v = neg ? -x : x;
    return true;
}

/// One face-vertex token: v, v/vt, v//vn or v/vt/vn with non-zero integers; ref gets the v,
/// vt and vn references (0 where absent). Plain decimal tokens are read in place; anything
/// else goes to parse_face_token_slow, which decides, so both paths accept the same tokens
/// with the same values.
bool parse_face_token(const char* b, const char* e, long (&ref)[3]) {
    constexpr long kMaxRef = 2147483647L;
    const char* p = b;
    auto ok = [](long x) { return x != 0 && x <= kMaxRef && x >= -kMaxRef; };
    ref[1] = ref[2] = 0;
    if (fast_int(p, e, ref[0]) && ok(ref[0])) {
        bool fine = true;
        for (int part = 0; part < 2 && fine && p < e && *p == '/'; ++part) {
            ++p;
            if (part == 0 && p < e && *p == '/') continue;  // v//vn
            fine = fast_int(p, e, ref[1 + part]) && ok(ref[1 + part]);
        }
        if (fine && p == e) return true;
    }
    return parse_face_token_slow(b, e, ref);
}

bool parse_face_token_slow(const char* b, const char* e, long (&ref)[3]) {
    std::string tok(b, e);
    const char* p = tok.c_str();
    char* end = nullptr;
    // References beyond int (what tinyobjloader stores) are bad references, never negated:
    // -LONG_MIN overflowed here before (found by the OBJ fuzz target).
    constexpr long kMaxRef = 2147483647L;
    ref[1] = ref[2] = 0;
    errno = 0;
    ref[0] = std::strtol(p, &end, 10);
    if (end == p || ref[0] == 0 || errno == ERANGE || ref[0] > kMaxRef || ref[0] < -kMaxRef) return false;
    for (int part = 0; part < 2 && *end == '/'; ++part) {
        p = end + 1;
        if (*p == '/' && part == 0) {  // v//vn
            end = const_cast<char*>(p);
            continue;
        }
        errno = 0;
        const long x = std::strtol(p, &end, 10);
        if (end == p || x == 0 || errno == ERANGE || x > kMaxRef || x < -kMaxRef) return false;
        ref[1 + part] = x;
    }
    return *end == '\0';
}

/// The next blank-separated token of [p, e) as [s, p), or false at the end of the line or a
/// comment ('#' runs to the end of the line). Every pass over OBJ lines tokenises with this.
bool next_token(const char*& p, const char* e, const char*& s) {
    while (p < e && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    if (p >= e || *p == '#') return false;
    s = p;
    while (p < e && *p != ' ' && *p != '\t' && *p != '\r' && *p != '#') ++p;
    return true;
}

/// Faces with more vertex references than this are triangulated by bvhlab as a fan, in place,
/// before tinyobjloader sees them: its ear clipping is quadratic or worse in the references (a
/// face of 50k took 22 s, of 2M minutes). Smaller polygons keep tinyobjloader's ear clipping,
/// which handles concave ones; 64^2 steps per face bound its cost.
constexpr size_t kEarClipMaxRefs = 64;

/// Byte ranges [begin, end) of the face lines (their references) that find_huge_faces found
/// with more than kEarClipMaxRefs references.
using LineRanges = std::vector<std::pair<size_t, size_t>>;

/// Throws on the first malformed v/vt/vn/f line or face index out of range. Returns the
/// (0-based) indices of vertices with a NaN or infinite coordinate: tinyobjloader reads those
/// as 0, which would silently move the vertex instead of dropping its triangles. The material
/// files named by `mtllib` go to `mtllibs`. Runs beside tinyobjloader's parse (load_obj), on the
/// text as written.
std::vector<size_t> scan_obj(const std::string& path, const std::string& text, std::vector<std::string>& mtllibs) {
    std::vector<size_t> non_finite;
    size_t line_no = 0, pos = 0;
    // Per kind of reference (v, vt, vn): the count so far, the largest positive reference and
    // its line. Negative references count back from the lines read so far.
    size_t count[3] = {0, 0, 0};
    long max_index[3] = {0, 0, 0};
    size_t max_line[3] = {0, 0, 0};
    static constexpr const char* kRefName[3] = {"face index", "texture coordinate index", "normal index"};
    static constexpr const char* kRefOf[3] = {"vertices", "texture coordinates", "normals"};
    auto fail = [&](size_t ln, const std::string& what) {
        throw Error("'" + path + "' line " + std::to_string(ln) + ": " + what);
    };
    while (pos < text.size()) {
        size_t eol = text.find('\n', pos);
        if (eol == std::string::npos) eol = text.size();
        ++line_no;
        const char* b = text.data() + pos;
        const char* e = text.data() + eol;
        pos = eol + 1;
        // Tokenise on blanks; comments run to the end of the line.
        const char* toks[32][2];
        int nt = 0;
        for (const char* p = b; nt < 32 && next_token(p, e, toks[nt][0]); ++nt) toks[nt][1] = p;
        if (nt == 0) continue;
        const std::string_view key(toks[0][0], size_t(toks[0][1] - toks[0][0]));
        if (key == "v" || key == "vn" || key == "vt") {
            const int need = key == "vt" ? 1 : 3;
            if (nt - 1 < need)
                fail(line_no, "malformed '" + std::string(key) + "' line: needs " + std::to_string(need) + " numbers");
            bool finite = true;
            for (int i = 1; i < nt; ++i) {
                double value = 0.0;
                if (!is_number(toks[i][0], toks[i][1], value))
                    fail(line_no, "malformed '" + std::string(key) + "' line: '" + std::string(toks[i][0], toks[i][1]) +
                                      "' is not a number");
                if (i <= 3 && !std::isfinite(value)) finite = false;
            }
            if (key == "v" && !finite) non_finite.push_back(count[0]);
            ++count[key == "v" ? 0 : key == "vt" ? 1 : 2];
        } else if (key == "mtllib") {
            for (int i = 1; i < nt; ++i) mtllibs.emplace_back(toks[i][0], toks[i][1]);
        } else if (key == "f") {
            if (nt < 4) fail(line_no, "malformed 'f' line: a face needs at least 3 vertices");
            // Every reference, however many (toks holds only the first 31).
            const char* s = nullptr;
            for (const char* p = toks[1][0]; next_token(p, e, s);) {
                long ref[3];
                if (!parse_face_token(s, p, ref))
                    fail(line_no, "malformed 'f' line: bad vertex reference '" + std::string(s, p) + "'");
                for (int r = 0; r < 3; ++r) {
                    if (ref[r] < 0 && size_t(-ref[r]) > count[r])
                        fail(line_no, std::string(kRefName[r]) + " " + std::to_string(ref[r]) + " out of range (" +
                                          std::to_string(count[r]) + " " + kRefOf[r] + " before this line)");
                    if (ref[r] > max_index[r]) {
                        max_index[r] = ref[r];
                        max_line[r] = line_no;
                    }
                }
            }
        }
    }
    for (int r = 0; r < 3; ++r)
        if (size_t(max_index[r]) > count[r])
            fail(max_line[r], std::string(kRefName[r]) + " " + std::to_string(max_index[r]) +
                                  " out of range (the file has " + std::to_string(count[r]) + " " + kRefOf[r] + ")");
    return non_finite;
}

/// The faces of `text` with more than kEarClipMaxRefs references, as the byte ranges of their
/// references. Only lines longer than 2 * kEarClipMaxRefs bytes can hold that many, so the pass
/// is a memchr over the text (~20 ms for furball's 149 MB).
LineRanges find_huge_faces(const std::string& text) {
    LineRanges out;
    const char* const begin = text.data();
    const char* const end = begin + text.size();
    for (const char* b = begin; b < end;) {
        const char* e = static_cast<const char*>(std::memchr(b, '\n', size_t(end - b)));
        if (!e) e = end;
        if (size_t(e - b) > 2 * kEarClipMaxRefs) {
            const char* p = b;
            while (p < e && (*p == ' ' || *p == '\t')) ++p;
            if (e - p > 2 && p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
                const char* first = p + 1;
                while (first < e && (*first == ' ' || *first == '\t')) ++first;
                size_t refs = 0;
                const char* s = nullptr;
                for (const char* q = first; next_token(q, e, s);) ++refs;
                if (refs > kEarClipMaxRefs) out.push_back({size_t(first - begin), size_t(e - begin)});
            }
        }
        b = e + 1;
    }
    return out;
}

/// `text` with each face of `huge` (ranges from find_huge_faces) replaced by its fan, one "f" line per
/// triangle: references r0 r1 ... become "f r0 r1 r2", "f r0 r2 r3", ... in place, so the
/// triangles keep the face's position, material and group. Linear in the references.
std::string fan_huge_faces(const std::string& text, const LineRanges& huge) {
    std::string out;
    out.reserve(text.size() + text.size() / 2);
    size_t copied = 0;
    for (const auto& [b, e] : huge) {
        out.append(text, copied, b - copied);  // up to and including "f "
        std::vector<std::string_view> refs;
        const char* s = nullptr;
        for (const char* p = text.data() + b; next_token(p, text.data() + e, s);) refs.emplace_back(s, size_t(p - s));
        for (size_t i = 1; i + 1 < refs.size(); ++i) {
            if (i > 1) out += "\nf ";
            out.append(refs[0]).append(" ").append(refs[i]).append(" ").append(refs[i + 1]);
        }
        copied = e;
    }
    out.append(text, copied, std::string::npos);
    return out;
}

/// The `mtllib` file `name` of an OBJ in `base_dir`: a relative name from the OBJ's folder, an
/// absolute one as it is. (tinyobjloader's MaterialFileReader prepends the folder to both, and
/// splits the folder at every ':' as a search path.)
std::string mtl_path(const std::string& base_dir, const std::string& name) {
    return !name.empty() && name[0] == '/' ? name : base_dir + name;
}

/// Reads `mtllib` files by mtl_path(); one that is missing or not a regular file is a warning
/// (the renderer decides what a missing material file means), as with tinyobjloader's reader.
class MtlReader : public tinyobj::MaterialReader {
public:
    explicit MtlReader(std::string base_dir) : base_dir_(std::move(base_dir)) {}
    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* names, std::string* warn, std::string* err) override {
        const std::string path = mtl_path(base_dir_, name);
        const std::string problem = regular_file_problem(path);
        std::ifstream in;
        if (problem.empty()) in.open(path);
        if (!problem.empty() || !in) {
            if (warn)
                *warn += "material file '" + path + "' " + (problem.empty() ? "cannot be opened" : problem) + "\n";
            return false;
        }
        std::stringstream text;
        text << in.rdbuf();
        scan_mtl(path, text.str());
        tinyobj::LoadMtl(names, materials, &text, warn, err);
        return true;
    }

    /// Throws on a numeric MTL value that is not a finite number: tinyobjloader reads `Kd nan`
    /// or `Ns 0x10` as 0 (and a map's `-bm nan` as 1), which would silently change the material.
    static void scan_mtl(const std::string& path, const std::string& text) {
        size_t line_no = 0;
        for (size_t pos = 0; pos < text.size();) {
            size_t eol = text.find('\n', pos);
            if (eol == std::string::npos) eol = text.size();
            ++line_no;
            const char* p = text.data() + pos;
            const char* const e = text.data() + eol;
            pos = eol + 1;
            const char* s = nullptr;
            if (!next_token(p, e, s)) continue;
            const std::string_view key(s, size_t(p - s));
            const char* const values = p;
            if (key == "bump" || key == "map_Bump" || key == "map_bump" || key == "norm") {
                // A map's -bm multiplier (tinyobjloader reads `-bm nan` as 1).
                while (next_token(p, e, s))
                    if (std::string_view(s, size_t(p - s)) == "-bm") {
                        double v = 0.0;
                        if (!next_token(p, e, s) || !is_number(s, p, v) || !std::isfinite(v))
                            throw Error("material file '" + path + "' line " + std::to_string(line_no) + ": " +
                                        std::string(key) + " -bm value '" + std::string(s, p) +
                                        "' is not a finite number");
                    }
                continue;
            }
            if (key != "Ka" && key != "Kd" && key != "Ks" && key != "Ke" && key != "Kt" && key != "Tf" && key != "Ns" &&
                key != "Ni" && key != "d" && key != "Tr")
                continue;
            if ((key == "Kd" || key == "Ka" || key == "Ks" || key == "Tf") && next_token(p, e, s) &&
                std::string_view(s, size_t(p - s)) == "spectral")
                continue;  // Kd spectral file.rfl: not numbers
            for (p = values; next_token(p, e, s);) {
                double v = 0.0;
                if (!is_number(s, p, v) || !std::isfinite(v))
                    throw Error("material file '" + path + "' line " + std::to_string(line_no) + ": " +
                                std::string(key) + " value '" + std::string(s, p) + "' is not a finite number");
            }
        }
    }

private:
    std::string base_dir_;
};

}  // namespace

TriangleMesh load_obj(const std::string& path, std::vector<std::string>* warnings, std::vector<std::string>* mtl_files,
                      const LoadProgress& progress) {
    const std::string text = read_file(path);
    const LineRanges huge_faces = find_huge_faces(text);
    const std::string fanned = huge_faces.empty() ? std::string() : fan_huge_faces(text, huge_faces);
    const std::string& parse_text = huge_faces.empty() ? text : fanned;
    // The strict scan runs on a second thread while tinyobjloader parses (on furball: 0.6-0.9 s
    // of scan hidden behind a 2.1 s parse); its errors come first, with the file's line numbers.
    std::vector<std::string> mtllibs;
    auto scan = std::async(std::launch::async, [&] { return scan_obj(path, text, mtllibs); });
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    const size_t slash = path.find_last_of('/');
    const std::string base_dir = slash == std::string::npos ? "./" : path.substr(0, slash + 1);
    MtlReader mtl_reader(base_dir);
    // tinyobjloader reads the text in place (an istringstream copied all of it: 0.14 s on
    // furball), 8 MiB at a time, so that each refill can report progress.
    struct TextBuf : std::streambuf {
        TextBuf(const std::string& t, const LoadProgress& p) : text(t), report(p) {}
        int_type underflow() override {
            const size_t done = egptr() ? size_t(egptr() - text.data()) : 0;
            if (report) report(done, text.size());
            if (done >= text.size()) return traits_type::eof();
            char* b = const_cast<char*>(text.data()) + done;  // a get area only: never written
            setg(b, b, b + std::min(kStep, text.size() - done));
            return traits_type::to_int_type(*b);
        }
        const size_t kStep = size_t(8) << 20;
        const std::string& text;
        const LoadProgress& report;
    } buf(parse_text, progress);
    std::istream stream(&buf);
    const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, &mtl_reader,
                                     /*triangulate=*/true, /*default_vcols_fallback=*/false);
    const std::vector<size_t> non_finite = scan.get();  // the scan's error, if any, first
    if (mtl_files)
        for (const std::string& m : mtllibs) mtl_files->push_back(mtl_path(base_dir, m));
    if (!ok || !err.empty()) {
        while (!err.empty() && (err.back() == '\n' || err.back() == '.')) err.pop_back();
        for (char& ch : err)
            if (ch == '\n') ch = ' ';
        throw Error("cannot parse '" + path + "': " + (err.empty() ? "tinyobjloader failed" : err));
    }
    if (warnings && !warn.empty()) {
        std::istringstream ws(warn);
        for (std::string line; std::getline(ws, line);)
            if (!line.empty()) warnings->push_back(line);
    }
    TriangleMesh mesh;
    for (const auto& m : materials) {
        Material mat;
        mat.name = m.name;
        mat.diffuse = {m.diffuse[0], m.diffuse[1], m.diffuse[2]};
        mat.emission = {m.emission[0], m.emission[1], m.emission[2]};
        mat.specular = {m.specular[0], m.specular[1], m.specular[2]};
        mat.ambient = {m.ambient[0], m.ambient[1], m.ambient[2]};
        mat.shininess = m.shininess;
        mat.ior = m.ior;
        mat.dissolve = m.dissolve;
        mat.illum = m.illum;
        mat.diffuse_texture = m.diffuse_texname;
        mat.normal_texture = m.normal_texname;
        mat.bump_texture = m.bump_texname;
        // One multiplier: bump's -bm, else norm's (tinyobjloader parses -bm for both).
        mat.bump_multiplier = !m.bump_texname.empty() ? m.bump_texopt.bump_multiplier : m.normal_texopt.bump_multiplier;
        mesh.materials.push_back(mat);
    }
    const size_t nv = attrib.vertices.size() / 3;
    mesh.vertices.resize(nv);
    if (nv) std::memcpy(mesh.vertices.data(), attrib.vertices.data(), nv * sizeof(Vec3));  // (null when empty)
    for (Vec3& v : mesh.vertices) v = flush_denormals(v);
    for (size_t v : non_finite)
        if (v < nv) mesh.vertices[v] = {NAN, NAN, NAN};
    const size_t nt = attrib.texcoords.size() / 2;
    const size_t nn = attrib.normals.size() / 3;
    // Normals per corner only when some face refers to one (a file may list vn lines it never uses).
    bool normals = false;
    for (const auto& shape : shapes)
        for (const tinyobj::index_t& ref : shape.mesh.indices) normals = normals || ref.normal_index >= 0;
    for (const auto& shape : shapes) {
        size_t offset = 0;
        for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const size_t fv = shape.mesh.num_face_vertices[f];
            if (fv != 3) {  // triangulation could not handle this polygon
                offset += fv;
                ++mesh.dropped.zero_area;
                continue;
            }
            uint32_t idx[3];
            float uv[6] = {};
            Vec3 n[3] = {};
            bool has_n = true;
            for (int k = 0; k < 3; ++k) {
                const tinyobj::index_t& ref = shape.mesh.indices[offset + k];
                const int vi = ref.vertex_index;
                if (vi < 0 || size_t(vi) >= nv) throw Error("'" + path + "': face index out of range");
                idx[k] = uint32_t(vi);
                if (ref.texcoord_index >= 0) {
                    if (size_t(ref.texcoord_index) >= nt)
                        throw Error("'" + path + "': texture coordinate index out of range");
                    uv[2 * k] = attrib.texcoords[2 * size_t(ref.texcoord_index)];
                    uv[2 * k + 1] = attrib.texcoords[2 * size_t(ref.texcoord_index) + 1];
                }
                if (ref.normal_index >= 0) {
                    if (size_t(ref.normal_index) >= nn) throw Error("'" + path + "': normal index out of range");
                    const float* a = &attrib.normals[3 * size_t(ref.normal_index)];
                    n[k] = {a[0], a[1], a[2]};
                } else {
                    has_n = false;
                }
            }
            offset += 3;
            const TriangleCheck check =
                check_triangle(mesh.vertices[idx[0]], mesh.vertices[idx[1]], mesh.vertices[idx[2]]);
            if (!count_drop(check, mesh.dropped)) continue;
            mesh.indices.insert(mesh.indices.end(), idx, idx + 3);
            if (nt) mesh.texcoords.insert(mesh.texcoords.end(), uv, uv + 6);
            if (normals) append_corner_normals(mesh, has_n, n[0], n[1], n[2]);
            const int mat = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
            mesh.material_ids.push_back(mat >= 0 && size_t(mat) < materials.size() ? mat : -1);
        }
    }
    if (mesh.triangle_count() == 0) {
        throw Error("'" + path + "' has no usable triangles" +
                    (mesh.dropped.total()
                         ? " (all " + std::to_string(mesh.dropped.total()) + " were dropped as non-finite or zero-area)"
                         : ""));
    }
    return mesh;
}

void write_obj(const TriangleMesh& mesh, const std::string& path) {
    write_file_atomically(path, [&](std::FILE* f) {
        // %.9g round-trips every float exactly.
        for (const Vec3& v : mesh.vertices) std::fprintf(f, "v %.9g %.9g %.9g\n", v.x, v.y, v.z);
        int32_t current = -1;
        for (size_t t = 0; t < mesh.triangle_count(); ++t) {
            const int32_t m = mesh.material_ids.empty() ? -1 : mesh.material_ids[t];
            if (m != current && m >= 0 && size_t(m) < mesh.materials.size()) {
                std::fprintf(f, "usemtl %s\n", mesh.materials[size_t(m)].name.c_str());
                current = m;
            }
            std::fprintf(f, "f %u %u %u\n", mesh.indices[3 * t] + 1, mesh.indices[3 * t + 1] + 1,
                         mesh.indices[3 * t + 2] + 1);
        }
    });
}

}  // namespace bvhlab::scene
