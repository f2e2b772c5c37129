// SPDX-License-Identifier: MIT
#include "traversal/rays/scene_catalogue.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "accel/core/check.h"

namespace bvhlab::trav {
namespace {

glm::vec3 vec3_of(const nlohmann::json& j) {
    return {j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>()};
}

}  // namespace

std::vector<CatalogueEntry> read_catalogue(const std::string& dir) {
    const std::string path = dir + "/scenes.json";
    std::ifstream in(path);
    if (!in) return {};
    std::vector<CatalogueEntry> out;
    try {
        const nlohmann::json j = nlohmann::json::parse(in);
        if (!j.contains("scenes")) return {};
        for (const auto& [name, e] : j.at("scenes").items()) {
            CatalogueEntry c;
            c.name = name;
            const std::string rel = e.at("file").get<std::string>();
            // Scene files live in the catalogue's folder: no absolute paths, no way out by "..".
            const std::filesystem::path norm = std::filesystem::path(rel).lexically_normal();
            if (norm.is_absolute() || norm.empty() || *norm.begin() == "..")
                throw Error("'" + path + "': scene '" + name + "' names a file outside its folder: '" + rel + "'");
            c.file = dir + "/" + rel;
            if (e.contains("triangles")) c.triangles = e["triangles"].get<uint64_t>();
            if (e.contains("camera")) {
                const auto& cam = e["camera"];
                c.camera = Camera{vec3_of(cam.at("eye")), vec3_of(cam.at("target")), vec3_of(cam.at("up")),
                                  cam.at("fov_y_deg").get<float>()};
            }
            if (e.contains("ao_length")) c.ao_length = e["ao_length"].get<float>();
            out.push_back(std::move(c));
        }
    } catch (const nlohmann::json::exception& e) {
        throw Error("cannot parse '" + path + "': " + e.what());
    }
    return out;
}

}  // namespace bvhlab::trav
