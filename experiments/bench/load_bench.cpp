// SPDX-License-Identifier: MIT
// Issue 21's scene-path figures, in one run on one machine: tinyobjloader's parse alone (its own
// file read, triangulation on), bvhlab's cold load (strict scan, parse, cleanup and scene hash,
// cache off) and a load served by the scene cache. On soup-1M (written once as OBJ to a temporary
// folder) and every OBJ of $BVHLAB_SCENES/scenes.json.
#include <benchmark/benchmark.h>
#include <tiny_obj_loader.h>
#include <unistd.h>

#include <filesystem>

#include "experiments/bench/bench_common.h"
#include "scene/io/scene_cache.h"

namespace {
namespace fs = std::filesystem;

void tinyobj_parse(benchmark::State& state, const std::string& path) {
    for (auto _ : state) {
        tinyobj::attrib_t attrib;
        std::vector<tinyobj::shape_t> shapes;
        std::vector<tinyobj::material_t> materials;
        std::string warn, err;
        const std::string dir = fs::path(path).parent_path().string() + "/";
        if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, path.c_str(), dir.c_str(), true))
            state.SkipWithError(err.c_str());
        benchmark::DoNotOptimize(attrib.vertices.data());
    }
}

void bvhlab_load(benchmark::State& state, const std::string& path, const std::string& cache) {
    if (!cache.empty()) bvhlab::scene::load_obj_cached(path, cache, "load_bench");  // the entry
    for (auto _ : state) {
        const bvhlab::scene::SceneLoad l = bvhlab::scene::load_obj_cached(path, cache, "load_bench");
        if (!cache.empty() && !l.from_cache) state.SkipWithError("the cache did not serve the load");
        state.counters["triangles"] = double(l.mesh.triangle_count());
    }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    benchmark::AddCustomContext("git_commit", bvhlab::git_commit());
    benchmark::AddCustomContext("bvhlab_build_type", bvhlab::build_type());
    const fs::path tmp = fs::temp_directory_path() / ("bvhlab_load_bench_" + std::to_string(getpid()));
    fs::create_directories(tmp);
    std::vector<std::pair<std::string, std::string>> scenes;
    const std::string soup = (tmp / "soup-1M.obj").string();
    bvhlab::scene::write_obj(bvhlab::scene::make_procedural(bvhlab::scene::ProceduralKind::kSoup, 1000000, 1), soup);
    scenes.push_back({"soup-1M", soup});
    for (const auto& scene : bvhlab::bench::bench_scenes(/*with_procedural=*/false))
        scenes.push_back({scene.name, scene.file});
    const std::string cache = (tmp / "cache").string();
    for (const auto& [name, file] : scenes) {
        benchmark::RegisterBenchmark(("tinyobj_parse/" + name).c_str(), tinyobj_parse, file)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("load_cold/" + name).c_str(), bvhlab_load, file, std::string())
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("load_cached/" + name).c_str(), bvhlab_load, file, cache)
            ->Unit(benchmark::kMillisecond);
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    fs::remove_all(tmp);
    return 0;
}
