// SPDX-License-Identifier: MIT
#include "traversal/rays/scene_catalogue.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "accel/core/check.h"
#include "scene/domain.h"

namespace bvhlab::trav {
namespace {

/// Reads one scene's fields, naming the file, the scene and the field in every error.
struct FieldReader {
    const std::string& path;
    std::string scene;

    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw Error("'" + path + "': scene '" + scene + "': field '" + field + "' " + what);
    }
    std::string text(const nlohmann::json& e, const char* field) const {
        if (!e.contains(field)) fail(field, "is missing");
        if (!e[field].is_string()) fail(field, "must be a string, not " + std::string(e[field].type_name()));
        return e[field].get<std::string>();
    }
    float number(const nlohmann::json& j, const std::string& field, double lo, double hi) const {
        if (!j.is_number()) fail(field, "must be a number, not " + std::string(j.type_name()));
        const double v = j.get<double>();
        if (!(v >= lo && v <= hi))
            fail(field,
                 "is " + j.dump() + ", outside [" + nlohmann::json(lo).dump() + ", " + nlohmann::json(hi).dump() + "]");
        return float(v);
    }
    glm::vec3 vec3(const nlohmann::json& j, const std::string& field) const {
        if (!j.is_array() || j.size() != 3) fail(field, "must be an array of 3 numbers, not " + j.dump());
        constexpr double m = scene::kMaxCoordinate;  // the numeric domain
        return {number(j[0], field, -m, m), number(j[1], field, -m, m), number(j[2], field, -m, m)};
    }
};

}  // namespace

std::vector<CatalogueEntry> read_catalogue(const std::string& dir) {
    const std::string path = dir + "/scenes.json";
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return {};
    if (!std::filesystem::is_regular_file(path, ec)) throw Error("'" + path + "' is not a regular file");
    std::ifstream in(path);
    if (!in) throw Error("cannot open '" + path + "'");
    std::vector<CatalogueEntry> out;
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw Error("cannot parse '" + path + "': " + e.what());
    }
    if (!j.is_object() || !j.contains("scenes")) return {};
    if (!j["scenes"].is_object()) throw Error("'" + path + "': \"scenes\" must be an object of named scenes");
    for (const auto& [name, e] : j["scenes"].items()) {
        const FieldReader r{path, name};
        if (!e.is_object()) throw Error("'" + path + "': scene '" + name + "' must be an object");
        CatalogueEntry c;
        c.name = name;
        const std::string rel = r.text(e, "file");
        // Scene files live in the catalogue's folder: no absolute paths, no way out by "..".
        const std::filesystem::path norm = std::filesystem::path(rel).lexically_normal();
        if (norm.is_absolute() || norm.empty() || *norm.begin() == "..")
            throw Error("'" + path + "': scene '" + name + "' names a file outside its folder: '" + rel + "'");
        c.file = dir + "/" + rel;
        if (e.contains("triangles")) {
            if (!e["triangles"].is_number_unsigned()) r.fail("triangles", "must be a non-negative integer");
            c.triangles = e["triangles"].get<uint64_t>();
        }
        if (e.contains("camera")) {
            const auto& cam = e["camera"];
            if (!cam.is_object()) r.fail("camera", "must be an object with eye, target, up and fov_y_deg");
            for (const char* k : {"eye", "target", "up", "fov_y_deg"})
                if (!cam.contains(k)) r.fail(std::string("camera.") + k, "is missing");
            c.camera =
                Camera{r.vec3(cam["eye"], "camera.eye"), r.vec3(cam["target"], "camera.target"),
                       r.vec3(cam["up"], "camera.up"), r.number(cam["fov_y_deg"], "camera.fov_y_deg", 1e-3, 179.0)};
        }
        if (e.contains("ao_length")) c.ao_length = r.number(e["ao_length"], "ao_length", 1e-30, 1e30);
        out.push_back(std::move(c));
    }
    return out;
}

}  // namespace bvhlab::trav
