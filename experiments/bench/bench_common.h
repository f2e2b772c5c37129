// SPDX-License-Identifier: MIT
// Scenes and provenance shared by the benchmark programs: procedural scenes always, plus the
// scenes of $BVHLAB_SCENES/scenes.json when it is set.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "accel/core/mesh.h"
#include "accel/io/obj_loader.h"
#include "accel/io/procedural.h"
#include "traversal/rays/raygen.h"

namespace bvhlab {
const char* git_commit();
const char* build_type();
}  // namespace bvhlab

namespace bvhlab::bench {

struct BenchScene {
    std::string name;
    std::function<accel::TriangleMesh()> load;  ///< loads on first use only
    trav::Camera camera;
    bool has_camera = false;
    float ao_length = 0.0f;
};

/// soup-1M and structured-1M, then every catalogue scene of $BVHLAB_SCENES.
inline std::vector<BenchScene> bench_scenes(bool with_procedural = true) {
    std::vector<BenchScene> out;
    if (with_procedural) {
        out.push_back({"soup-1M", [] { return accel::make_procedural(accel::ProceduralKind::kSoup, 1000000, 1); }, {}, false, 0});
        out.push_back({"structured-1M", [] { return accel::make_procedural(accel::ProceduralKind::kStructured, 1000000, 1); }, {}, false, 0});
    }
    const char* dir = std::getenv("BVHLAB_SCENES");
    if (!dir || !*dir) return out;
    std::ifstream in(std::string(dir) + "/scenes.json");
    if (!in) return out;
    nlohmann::json cat = nlohmann::json::parse(in)["scenes"];
    for (const auto& [name, e] : cat.items()) {
        BenchScene s;
        s.name = name;
        const std::string file = std::string(dir) + "/" + e["file"].get<std::string>();
        s.load = [file] { return accel::load_obj(file); };
        const auto& c = e["camera"];
        s.camera.eye = {c["eye"][0], c["eye"][1], c["eye"][2]};
        s.camera.target = {c["target"][0], c["target"][1], c["target"][2]};
        s.camera.up = {c["up"][0], c["up"][1], c["up"][2]};
        s.camera.fov_y_deg = c["fov_y_deg"];
        s.has_camera = true;
        s.ao_length = e["ao_length"];
        out.push_back(s);
    }
    return out;
}

/// The main() of every benchmark program: records commit and build type in the JSON
/// context, lets `register_scene` register its benchmarks for each scene, runs them.
inline int bench_main(int argc, char** argv, const std::function<void(const BenchScene&)>& register_scene) {
    benchmark::Initialize(&argc, argv);
    benchmark::AddCustomContext("git_commit", git_commit());
    benchmark::AddCustomContext("bvhlab_build_type", build_type());
    benchmark::AddCustomContext("device", "cpu");
    for (const auto& scene : bench_scenes()) register_scene(scene);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

}  // namespace bvhlab::bench
