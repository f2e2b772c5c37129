// SPDX-License-Identifier: MIT
// Assimp input: nodes to instances, aiMaterials to the renderer's parameters, the first camera.
#include "scene/io/scene_file.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/GltfMaterial.h>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tbb/parallel_for.h>
#include <assimp/Importer.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "accel/core/check.h"
#include "scene/domain.h"
#include "scene/io/atomic_file.h"

namespace bvhlab::scene {

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

/// Assimp's file system, recording every file the importer opens (a glTF's buffers, an
/// OBJ-like format's material files): the scene cache's dependencies.
class RecordingIO : public Assimp::DefaultIOSystem {
public:
    std::vector<std::string> opened;
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        Assimp::IOStream* s = DefaultIOSystem::Open(file, mode);
        if (s) opened.emplace_back(file);
        return s;
    }
};

[[noreturn]] void fail(const std::string& path, const std::string& why) { throw Error("'" + path + "': " + why); }

/// The first line of an Assimp error, without trailing blanks.
std::string first_line(std::string s) {
    s = s.substr(0, s.find('\n'));
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    return s.empty() ? "Assimp could not read it" : s;
}

/// The JSON of a .gltf, or the JSON chunk of a .glb (null when the container is damaged: Assimp
/// then says why).
nlohmann::json gltf_json(const std::string& path, bool binary) {
    std::ifstream in(path, std::ios::binary);
    if (!binary) return nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    uint32_t header[5] = {};
    if (!in.read(reinterpret_cast<char*>(header), sizeof header)) return nullptr;
    if (header[0] != 0x46546C67u || header[4] != 0x4E4F534Au) return nullptr;  // "glTF", "JSON"
    // Assimp allocates and clears what the header claims before it finds the file too short
    // (1.95 GB for a 3 KB file found by fuzzing), so a header that claims more is refused here.
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    const uint64_t claimed = std::max<uint64_t>(header[2], uint64_t(header[3]) + 20);
    if (!ec && claimed > size)
        fail(path, "is a damaged GLB file: its header claims " + std::to_string(claimed) + " bytes and the file has " +
                       std::to_string(size));
    std::string text(header[3], '\0');
    if (!in.read(text.data(), std::streamsize(text.size()))) return nullptr;
    return nlohmann::json::parse(text, nullptr, false);
}

/// Refuses a glTF that requires an extension bvhlab does not implement; warns about used ones.
/// A PLY header as the format defines it: "ply" on the first line, text lines, and an
/// "end_header" line within the first MiB. Assimp's PLY reader loops forever on a header whose
/// end_header line is broken by a NUL byte, so the header is checked before Assimp sees it.
/// A line of a PLY header after "ply": one of the header's keywords; and for an "element NAME
/// COUNT" line, a count that the file's size cannot hold (each
/// entry takes at least a byte) is refused, since Assimp's PLY reader loops over the count
/// before it finds the file short (fuzz finding: a count of 8.3e40 in a 300-byte file).
void check_ply_header_line(const std::string& path, const std::string& line) {
    std::istringstream ss(line);
    std::string word, name, count;
    ss >> word >> name >> count;
    // The header's grammar: anything else makes Assimp's reader misread what follows (fuzz
    // finding: a stray line made it allocate 15 GB).
    static const char* const kWords[] = {"format", "comment", "obj_info", "element", "property"};
    if (!word.empty() && std::none_of(std::begin(kWords), std::end(kWords), [&](const char* w) { return word == w; }))
        fail(path, "has a PLY header line that is not format, comment, obj_info, element or property: '" +
                       line.substr(0, 40) + (line.size() > 40 ? "..." : "") + "'");
    if (word != "element") return;
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    const bool digits =
        !count.empty() && std::all_of(count.begin(), count.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits)
        fail(path, "has a PLY element '" + name + "' whose count '" + count.substr(0, 24) + "' is not a number");
    if (!ec && (count.size() > 19 || std::stoull(count) > size))
        fail(path, "has a PLY element '" + name + "' of " + (count.size() > 24 ? count.substr(0, 24) + "..." : count) +
                       " entries, more than the file's " + std::to_string(size) + " bytes can hold");
}

void check_ply_header(const std::string& path) {
    constexpr size_t kMaxHeader = 1 << 20;
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot be opened");
    std::string head(kMaxHeader, '\0');
    in.read(head.data(), std::streamsize(head.size()));
    head.resize(size_t(in.gcount()));
    if (head.rfind("ply\n", 0) != 0 && head.rfind("ply\r\n", 0) != 0)
        fail(path, "is not a PLY file (its first line is not 'ply')");
    size_t line = 0;
    for (size_t i = 0; i < head.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(head[i]);
        if (c == '\n') {
            std::string text = head.substr(line, i - line);
            while (!text.empty() && (text.back() == '\r' || text.back() == ' ' || text.back() == '\t')) text.pop_back();
            if (text == "end_header") return;
            if (line > 0) check_ply_header_line(path, text);
            line = i + 1;
        } else if ((c < 0x20 || c > 0x7e) && c != '\r' && c != '\t') {
            fail(path, "has a byte that is not text (" + std::to_string(int(c)) + ") in its PLY header, at offset " +
                           std::to_string(i));
        }
    }
    fail(path, "has no end_header line ending its PLY header" +
                   std::string(head.size() == kMaxHeader ? " in its first MiB" : ""));
}

/// Whether the file begins with PLY's magic line ("ply" and a line end).
bool starts_as_ply(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char head[5] = {};
    in.read(head, sizeof head);
    const std::string h(head, size_t(in.gcount()));
    return h.rfind("ply\n", 0) == 0 || h.rfind("ply\r\n", 0) == 0;
}

void check_gltf_extensions(const std::string& path, bool binary, std::vector<std::string>* warnings) {
    const nlohmann::json doc = gltf_json(path, binary);
    if (!doc.is_object()) return;  // Assimp reports the damage
    const auto& ok = supported_gltf_extensions();
    const auto names = [&](const char* key) {
        std::vector<std::string> out;
        auto it = doc.find(key);
        if (it != doc.end() && it->is_array())
            for (const auto& e : *it)
                if (e.is_string()) out.push_back(e.get<std::string>());
        return out;
    };
    const std::vector<std::string> required = names("extensionsRequired");
    for (const std::string& e : required)
        if (std::find(ok.begin(), ok.end(), e) == ok.end()) {
            std::string list;
            for (const std::string& s : ok) list += (list.empty() ? "" : ", ") + s;
            fail(path,
                 "requires the glTF extension " + e + ", which bvhlab does not implement (it implements " + list + ")");
        }
    if (warnings)
        for (const std::string& e : names("extensionsUsed"))
            if (std::find(ok.begin(), ok.end(), e) == ok.end())
                warnings->push_back("'" + path + "' uses the glTF extension " + e + ", which bvhlab ignores");
}

Transform to_transform(const aiMatrix4x4& a) {
    Transform t;
    const float rows[12] = {a.a1, a.a2, a.a3, a.a4, a.b1, a.b2, a.b3, a.b4, a.c1, a.c2, a.c3, a.c4};
    std::memcpy(t.m, rows, sizeof rows);
    return t;
}

Vec3 color(const aiMaterial& m, const char* key, unsigned type, unsigned index, Vec3 fallback) {
    aiColor4D c;
    if (m.Get(key, type, index, c) != aiReturn_SUCCESS) return fallback;
    return {c.r, c.g, c.b};
}

float number(const aiMaterial& m, const char* key, unsigned type, unsigned index, float fallback) {
    float v = 0.0f;
    return m.Get(key, type, index, v) == aiReturn_SUCCESS ? v : fallback;
}

/// A texture's path as the file writes it; "" for none. Embedded textures ("*N") are not read.
std::string texture(const aiMaterial& m, aiTextureType type, const std::string& path, const std::string& name,
                    std::vector<std::string>* warnings) {
    aiString s;
    if (m.GetTexture(type, 0, &s) != aiReturn_SUCCESS || s.length == 0) return "";
    if (s.C_Str()[0] == '*') {
        const bool colour = type == aiTextureType_BASE_COLOR || type == aiTextureType_DIFFUSE;
        if (warnings)
            warnings->push_back("'" + path + "': material '" + name + "' has an embedded " +
                                (colour ? "base-colour texture" : "normal or height map") +
                                ", which bvhlab does not read (it renders " +
                                (colour ? "with the base colour)" : "without it)"));
        return "";
    }
    return s.C_Str();
}

/// glTF's metallic-roughness material as MTL parameters (README, "Scene formats"):
/// transmission > 0 -> glass (d = 1 - transmission, Ni = ior); metallic >= 0.5 -> conductor
/// (illum 3, Ks = base colour); otherwise plastic (illum 2, Kd = base colour, Ks 0.04, Ni = ior).
/// Roughness r gives the GGX alpha r^2, i.e. Ns = 2 / r^4 - 2 (capped at 1e6).
Material gltf_material(const aiMaterial& am, const std::string& path, std::vector<std::string>* warnings) {
    Material m;
    m.name = am.GetName().C_Str();
    const Vec3 base = color(am, AI_MATKEY_BASE_COLOR, {1, 1, 1});
    const float metallic = number(am, AI_MATKEY_METALLIC_FACTOR, 1.0f);
    const float roughness = number(am, AI_MATKEY_ROUGHNESS_FACTOR, 1.0f);
    const float transmission = number(am, AI_MATKEY_TRANSMISSION_FACTOR, 0.0f);
    const float ior = number(am, AI_MATKEY_REFRACTI, 1.5f);
    const float strength = number(am, AI_MATKEY_EMISSIVE_INTENSITY, 1.0f);
    const float r4 = roughness * roughness * roughness * roughness;
    m.shininess = r4 > 2.0f / 1e6f ? std::max(0.0f, 2.0f / r4 - 2.0f) : 1e6f;
    m.emission = color(am, AI_MATKEY_COLOR_EMISSIVE, {0, 0, 0}) * strength;
    m.ior = ior;
    m.diffuse = base;
    m.specular = {0.04f, 0.04f, 0.04f};
    if (transmission > 0.0f) {
        m.dissolve = std::max(0.0f, 1.0f - transmission);
        m.illum = 4;
    } else if (metallic >= 0.5f) {
        m.specular = base;
        m.illum = 3;
    } else {
        m.illum = 2;
    }
    m.diffuse_texture = texture(am, aiTextureType_BASE_COLOR, path, m.name, warnings);
    if (m.diffuse_texture.empty()) m.diffuse_texture = texture(am, aiTextureType_DIFFUSE, path, m.name, warnings);
    m.normal_texture = texture(am, aiTextureType_NORMALS, path, m.name, warnings);
    m.bump_multiplier = number(am, AI_MATKEY_GLTF_TEXTURE_SCALE(aiTextureType_NORMALS, 0), 1.0f);
    return m;
}

/// Any other format's material: the classic diffuse, specular, emissive, shininess, opacity.
Material classic_material(const aiMaterial& am, const std::string& path, std::vector<std::string>* warnings) {
    Material m;
    m.name = am.GetName().C_Str();
    m.diffuse = color(am, AI_MATKEY_COLOR_DIFFUSE, m.diffuse);
    m.specular = color(am, AI_MATKEY_COLOR_SPECULAR, {0, 0, 0});
    m.emission = color(am, AI_MATKEY_COLOR_EMISSIVE, {0, 0, 0});
    m.shininess = number(am, AI_MATKEY_SHININESS, 1.0f);
    m.dissolve = number(am, AI_MATKEY_OPACITY, 1.0f);
    m.ior = number(am, AI_MATKEY_REFRACTI, 1.0f);
    m.illum = (m.specular.x > 0 || m.specular.y > 0 || m.specular.z > 0) ? 2 : 0;
    m.diffuse_texture = texture(am, aiTextureType_DIFFUSE, path, m.name, warnings);
    m.normal_texture = texture(am, aiTextureType_NORMALS, path, m.name, warnings);
    m.bump_texture = texture(am, aiTextureType_HEIGHT, path, m.name, warnings);
    return m;
}

/// The world transform of a node: its parents' transforms, outermost first.
aiMatrix4x4 world_matrix(const aiNode* node) {
    aiMatrix4x4 t;
    for (; node; node = node->mParent) t = node->mTransformation * t;
    return t;
}

struct Placement {
    std::vector<unsigned> meshes;  // the node's aiMesh list
    Transform transform;
};

void collect(const aiNode* node, const aiMatrix4x4& parent, std::vector<Placement>& out) {
    const aiMatrix4x4 world = parent * node->mTransformation;
    if (node->mNumMeshes > 0)
        out.push_back({std::vector<unsigned>(node->mMeshes, node->mMeshes + node->mNumMeshes), to_transform(world)});
    for (unsigned i = 0; i < node->mNumChildren; ++i) collect(node->mChildren[i], world, out);
}

/// A parallel loop over [0, n) in blocks of `grain`.
template <class F>
void parallel_range(size_t n, size_t grain, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) f(i);
    });
}

/// Appends the triangles of `meshes` to `out`, through `t`, dropping bad ones. In parallel: the
/// vertices and normals, then each face's check, then (after a sequential count of where each
/// kept face goes, in file order) the faces' indices, materials, texture coordinates and normals.
void append(const aiScene& scene, const std::vector<unsigned>& meshes, const Transform& t, bool texcoords, bool normals,
            bool materials, TriangleMesh& out) {
    constexpr uint8_t kNotTriangle = 255;
    for (unsigned id : meshes) {
        const aiMesh& am = *scene.mMeshes[id];
        if (!(am.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const auto base = uint32_t(out.vertices.size());
        const size_t nv = am.mNumVertices, nf = am.mNumFaces;
        out.vertices.resize(base + nv);
        Vec3* pos = out.vertices.data() + base;
        parallel_range(nv, 16384, [&](size_t v) {
            const aiVector3D& p = am.mVertices[v];
            pos[v] = flush_denormals(t.point({p.x, p.y, p.z}));
        });
        // World-space unit normals per vertex, once (not per corner).
        std::vector<Vec3> vn;
        if (normals && am.mNormals) {
            const Transform normal_map = t.normal_map();
            vn.resize(nv);
            parallel_range(nv, 16384, [&](size_t v) {
                const aiVector3D& n = am.mNormals[v];
                vn[v] = unit_or_zero(normal_map.vector({n.x, n.y, n.z}));
            });
        }
        std::vector<uint8_t> check(nf);
        parallel_range(nf, 16384, [&](size_t f) {
            const aiFace& face = am.mFaces[f];
            const unsigned* i = face.mIndices;
            check[f] = face.mNumIndices != 3 ? kNotTriangle : uint8_t(check_triangle(pos[i[0]], pos[i[1]], pos[i[2]]));
        });
        std::vector<uint32_t> at(nf);
        const size_t first = out.material_ids.size();
        size_t kept = 0;
        for (size_t f = 0; f < nf; ++f) {
            at[f] = uint32_t(kept);
            if (check[f] != kNotTriangle && count_drop(TriangleCheck(check[f]), out.dropped)) ++kept;
        }
        out.indices.resize(3 * (first + kept));
        out.material_ids.resize(first + kept);
        if (texcoords) out.texcoords.resize(6 * (first + kept));
        if (normals) out.normals.resize(3 * (first + kept));
        const aiVector3D* uv = am.mTextureCoords[0];
        parallel_range(nf, 16384, [&](size_t f) {
            if (check[f] != uint8_t(TriangleCheck::kOk)) return;
            const unsigned* i = am.mFaces[f].mIndices;
            const size_t j = first + at[f];
            for (int k = 0; k < 3; ++k) out.indices[3 * j + k] = base + i[k];
            out.material_ids[j] = materials ? int32_t(am.mMaterialIndex) : -1;
            if (texcoords)
                for (int k = 0; k < 3; ++k) {
                    out.texcoords[6 * j + 2 * k] = uv ? uv[i[k]].x : 0.0f;
                    out.texcoords[6 * j + 2 * k + 1] = uv ? uv[i[k]].y : 0.0f;
                }
            if (normals)
                corner_normals(!vn.empty(), vn.empty() ? Vec3{} : vn[i[0]], vn.empty() ? Vec3{} : vn[i[1]],
                               vn.empty() ? Vec3{} : vn[i[2]], /*unit=*/true, &out.normals[3 * j]);
        });
    }
}

}  // namespace

bool is_obj_path(const std::string& path) { return lower_extension(path) == ".obj"; }

const std::vector<std::string>& supported_gltf_extensions() {
    static const std::vector<std::string> names{"KHR_materials_emissive_strength", "KHR_materials_ior",
                                                "KHR_materials_transmission"};
    return names;
}

SceneFileLoad load_scene_file(const std::string& path, const std::string& cache_dir, const std::string& writer,
                              const LoadProgress& progress) {
    if (is_obj_path(path))
        return load_cached(path, kObjLoaderVersion, cache_dir, writer,
                           [&](std::vector<std::string>* warnings, std::vector<std::string>* files) {
                               return single_instance(load_obj(path, warnings, files, progress));
                           });
    return load_cached(path, kAssimpLoaderVersion, cache_dir, writer,
                       [&](std::vector<std::string>* warnings, std::vector<std::string>* files) {
                           return load_assimp(path, warnings, files);
                       });
}

InstancedScene load_assimp(const std::string& path, std::vector<std::string>* warnings,
                           std::vector<std::string>* dependencies) {
    if (const std::string p = regular_file_problem(path); !p.empty()) fail(path, p);
    const std::string ext = lower_extension(path);
    Assimp::Importer importer;
    if (ext.empty() || !importer.IsExtensionSupported(ext))
        fail(path, (ext.empty() ? std::string("no file extension") : "unknown scene format '" + ext + "'") +
                       " (bvhlab reads .obj, and through Assimp .gltf, .glb, .ply, .fbx, .dae, .3ds, .stl and the "
                       "other formats `assimp listext` lists)");
    const bool gltf = ext == ".gltf" || ext == ".glb";
    if (gltf) check_gltf_extensions(path, ext == ".glb", warnings);
    // Assimp picks a reader by the file's first bytes when the extension's reader declines it, so
    // a file of any extension that starts as a PLY file is checked as one (fuzz finding: a .gltf
    // holding a damaged PLY header looped in Assimp's PLY reader).
    if (ext == ".ply" || starts_as_ply(path)) check_ply_header(path);

    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    auto* io = new RecordingIO;  // the importer owns it
    importer.SetIOHandler(io);
    // Read and validated first; each mesh's empty faces are then removed and its primitive types
    // taken from its faces before Assimp triangulates: its PLY reader keeps faces of no vertices
    // and declares polygons a damaged file may not have, and the triangulation then asserts
    // (aborts) and the sorting by type reads out of bounds (fuzz findings).
    const aiScene* as = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    if (as) {
        for (unsigned m = 0; m < as->mNumMeshes; ++m) {
            aiMesh& mesh = *as->mMeshes[m];
            unsigned types = 0, kept = 0;
            for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
                aiFace& face = mesh.mFaces[f];
                const unsigned k = face.mNumIndices;
                if (k == 0) continue;
                types |= k == 1   ? aiPrimitiveType_POINT
                         : k == 2 ? aiPrimitiveType_LINE
                         : k == 3 ? aiPrimitiveType_TRIANGLE
                                  : aiPrimitiveType_POLYGON;
                // Moved down by swapping (the array still owns and frees every face's indices).
                std::swap(mesh.mFaces[kept].mIndices, face.mIndices);
                std::swap(mesh.mFaces[kept].mNumIndices, face.mNumIndices);
                ++kept;
            }
            mesh.mNumFaces = kept;
            mesh.mPrimitiveTypes = types ? types : unsigned(aiPrimitiveType_POINT);  // no faces: removed as points
        }
        as = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_SortByPType);
    }
    if (dependencies) {
        std::error_code ec;
        const fs::path self = fs::weakly_canonical(fs::absolute(path), ec);
        for (const std::string& f : io->opened) {
            const fs::path p = fs::weakly_canonical(fs::absolute(f), ec);
            if (p != self && std::find(dependencies->begin(), dependencies->end(), p.string()) == dependencies->end())
                dependencies->push_back(p.string());
        }
    }
    if (!as) {
        const std::string why = first_line(importer.GetErrorString());
        // Assimp says this when a file's only primitives are points or lines.
        if (why.find("No meshes") != std::string::npos || why.find("no meshes") != std::string::npos ||
            why.find("contains no faces") != std::string::npos)
            fail(path, "has no triangles (Assimp: " + why + ")");
        fail(path, "Assimp cannot read it: " + why);
    }
    if (as->mFlags & AI_SCENE_FLAGS_INCOMPLETE) fail(path, "has no triangles (Assimp read no meshes from it)");

    InstancedScene s;
    // PLY and STL carry no materials: Assimp's made-up one would turn them into white plastic.
    const bool materials = ext != ".ply" && ext != ".stl";
    for (unsigned i = 0; materials && i < as->mNumMaterials; ++i) {
        Material m = gltf ? gltf_material(*as->mMaterials[i], path, warnings)
                          : classic_material(*as->mMaterials[i], path, warnings);
        if (const std::string p = material_problem(m); !p.empty()) fail(path, "material '" + m.name + "': " + p);
        s.materials.push_back(std::move(m));
    }

    std::vector<Placement> placements;
    if (as->mRootNode) collect(as->mRootNode, aiMatrix4x4(), placements);
    bool texcoords = false;
    bool normals = false;
    for (unsigned i = 0; i < as->mNumMeshes; ++i) {
        texcoords = texcoords || as->mMeshes[i]->mTextureCoords[0];
        normals = normals || as->mMeshes[i]->mNormals;
    }

    std::map<std::vector<unsigned>, uint32_t> uses;
    for (auto it = placements.begin(); it != placements.end();) {
        if (it->transform.determinant() == 0.0 || !std::isfinite(it->transform.determinant())) {
            if (warnings)
                warnings->push_back("'" + path + "': a node with a singular or non-finite transform is left out");
            it = placements.erase(it);
        } else {
            ++uses[it->meshes];
            ++it;
        }
    }
    // Meshes placed once go into world space, merged into one mesh placed once (first).
    TriangleMesh world;
    size_t world_vertices = 0, world_faces = 0;  // reserved at once: a 1M-triangle glTF grew by doubling
    for (const Placement& p : placements)
        if (uses[p.meshes] == 1)
            for (unsigned id : p.meshes) {
                world_vertices += as->mMeshes[id]->mNumVertices;
                world_faces += as->mMeshes[id]->mNumFaces;
            }
    world.vertices.reserve(world_vertices);
    world.indices.reserve(3 * world_faces);
    world.material_ids.reserve(world_faces);
    if (texcoords) world.texcoords.reserve(6 * world_faces);
    if (normals) world.normals.reserve(3 * world_faces);
    std::map<std::vector<unsigned>, uint32_t> shared;  // node mesh list -> index into s.meshes
    for (const Placement& p : placements) {
        if (uses[p.meshes] == 1) {
            append(*as, p.meshes, p.transform, texcoords, normals, materials, world);
            continue;
        }
        auto [it, added] = shared.emplace(p.meshes, uint32_t(s.meshes.size() + 1));  // +1: world is first
        if (added) {
            s.meshes.emplace_back();
            append(*as, p.meshes, Transform{}, texcoords, normals, materials, s.meshes.back());
        }
        s.instances.push_back({p.transform, it->second, 0});
    }
    const auto add_drops = [&s](const TriangleMesh& m) {
        s.dropped.non_finite += m.dropped.non_finite;
        s.dropped.zero_area += m.dropped.zero_area;
    };
    add_drops(world);
    for (const TriangleMesh& m : s.meshes) add_drops(m);
    if (world.triangle_count() > 0) {
        s.meshes.insert(s.meshes.begin(), std::move(world));
        s.instances.insert(s.instances.begin(), Instance{});
    } else {  // nothing placed once: no world mesh
        for (Instance& inst : s.instances) --inst.mesh;
    }
    if (s.triangle_count() == 0)
        fail(path, s.dropped.total() > 0 ? "has no usable triangles (all " + std::to_string(s.dropped.total()) +
                                               " are degenerate or non-finite)"
                                         : "has no triangles");
    // Shared meshes whose every triangle was dropped place nothing.
    s.instances.erase(std::remove_if(s.instances.begin(), s.instances.end(),
                                     [&s](const Instance& i) { return s.meshes[i.mesh].triangle_count() == 0; }),
                      s.instances.end());

    if (as->mNumCameras > 0) {
        const aiCamera& cam = *as->mCameras[0];
        const aiNode* node = as->mRootNode ? as->mRootNode->FindNode(cam.mName) : nullptr;
        const Transform t = to_transform(node ? world_matrix(node) : aiMatrix4x4());
        // glTF cameras sit at their node's origin looking down -z with +y up (Assimp's glTF
        // reader also copies the node's translation into mPosition, which would count it twice);
        // other readers give the camera in its node's space, as aiCamera documents.
        const Vec3 eye = gltf ? Vec3{0, 0, 0} : Vec3{cam.mPosition.x, cam.mPosition.y, cam.mPosition.z};
        const Vec3 look = gltf ? Vec3{0, 0, -1} : Vec3{cam.mLookAt.x, cam.mLookAt.y, cam.mLookAt.z};
        const Vec3 up = gltf ? Vec3{0, 1, 0} : Vec3{cam.mUp.x, cam.mUp.y, cam.mUp.z};
        SceneCamera c;
        c.eye = t.point(eye);
        c.target = t.point(eye + look);
        c.up = t.vector(up);
        // Assimp's glTF reader stores yfov * aspect as mHorizontalFOV; other readers give half
        // the horizontal angle, as aiCamera documents.
        const float aspect = cam.mAspect > 0.0f ? cam.mAspect : 1.0f;
        const double fov_y =
            gltf ? cam.mHorizontalFOV / aspect : 2.0 * std::atan(std::tan(cam.mHorizontalFOV) / aspect);
        c.fov_y_deg = float(fov_y * 180.0 / M_PI);
        if (c.fov_y_deg > 0.0f && c.fov_y_deg < 180.0f && length(c.target - c.eye) > 0.0f)
            s.camera = c;
        else if (warnings)
            warnings->push_back("'" + path +
                                "': its camera is unusable (field of view or direction), so it is ignored");
    }
    return s;
}

}  // namespace bvhlab::scene
