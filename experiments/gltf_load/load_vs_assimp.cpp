// SPDX-License-Identifier: MIT
// bvhlab's glTF load (scene::load_assimp: Assimp's import and the conversion) against Assimp's
// own import with the same post-processing, interleaved in one process so that both see the
// same allocator and page-cache state. Prints one JSON line: best and median of each over the
// rounds (experiments/NOTES.md, sessions 22 and 23).
//   g++ -O2 -std=c++17 -I. experiments/gltf_load/load_vs_assimp.cpp build/scene/libbvhlab_scene.a \
//       build/accel/libbvhlab_accel.a -lassimp -ltbb -ltinyobjloader -o load_vs_assimp
//   ./load_vs_assimp FILE [ROUNDS]
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "scene/io/scene_file.h"

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const int rounds = argc > 2 ? std::atoi(argv[2]) : 9;
    std::vector<double> assimp, bvhlab;
    size_t triangles = 0;
    for (int r = 0; r < rounds; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        {
            Assimp::Importer importer;
            const aiScene* s = importer.ReadFile(
                argv[1], aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure);
            if (!s) return 1;
        }
        assimp.push_back(ms_since(t0));
        t0 = std::chrono::steady_clock::now();
        {
            const bvhlab::scene::InstancedScene s = bvhlab::scene::load_assimp(argv[1]);
            triangles = s.triangle_count();
        }
        bvhlab.push_back(ms_since(t0));
    }
    std::printf(
        "{\"file\": \"%s\", \"triangles\": %zu, \"rounds\": %d, \"assimp_best_ms\": %.1f, \"assimp_median_ms\": %.1f, "
        "\"load_best_ms\": %.1f, \"load_median_ms\": %.1f, \"ratio_median\": %.2f}\n",
        argv[1], triangles, rounds, *std::min_element(assimp.begin(), assimp.end()), median(assimp),
        *std::min_element(bvhlab.begin(), bvhlab.end()), median(bvhlab), median(bvhlab) / median(assimp));
}
