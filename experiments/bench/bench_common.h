// SPDX-License-Identifier: MIT
// Scenes and provenance shared by the benchmark programs: procedural scenes always, plus the
// scenes of $BVHLAB_SCENES/scenes.json when it is set.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "scene/mesh.h"
#include "traversal/rays/raygen.h"
#include "traversal/rays/scene_catalogue.h"

namespace bvhlab {
const char* git_commit();
const char* build_type();
}  // namespace bvhlab

namespace bvhlab::bench {

struct BenchScene {
    std::string name;
    std::function<scene::TriangleMesh()> load;  ///< loads on first use only
    trav::Camera camera;
    bool has_camera = false;
    float ao_length = 0.0f;
    std::string file;  ///< the OBJ of a catalogue scene ("" for procedural ones)
};

/// soup-1M and structured-1M, then every catalogue scene of $BVHLAB_SCENES.
inline std::vector<BenchScene> bench_scenes(bool with_procedural = true) {
    std::vector<BenchScene> out;
    if (with_procedural) {
        out.push_back(
            {"soup-1M", [] { return scene::make_procedural(scene::ProceduralKind::kSoup, 1000000, 1); }, {}, false, 0});
        out.push_back({"structured-1M",
                       [] { return scene::make_procedural(scene::ProceduralKind::kStructured, 1000000, 1); },
                       {},
                       false,
                       0});
    }
    const char* dir = std::getenv("BVHLAB_SCENES");
    if (!dir || !*dir) return out;
    for (const trav::CatalogueEntry& e : trav::read_catalogue(dir)) {
        BenchScene s;
        s.name = e.name;
        s.load = [file = e.file] { return scene::load_obj(file); };
        s.file = e.file;
        s.has_camera = e.camera.has_value();
        if (e.camera) s.camera = *e.camera;
        s.ao_length = e.ao_length;
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
