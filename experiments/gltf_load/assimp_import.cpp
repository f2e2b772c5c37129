// SPDX-License-Identifier: MIT
// Assimp's own import of a scene file, with the post-processing bvhlab asks for: the baseline of
// the glTF load-time measurement (experiments/NOTES.md, session 22). Prints the best of 5 in ms.
//   g++ -O2 -std=c++17 assimp_import.cpp -lassimp -o assimp_import && ./assimp_import FILE
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <chrono>
#include <cstdio>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    double best = 1e30;
    unsigned tris = 0;
    for (int run = 0; run < 5; ++run) {
        const auto t0 = std::chrono::steady_clock::now();
        Assimp::Importer importer;
        const aiScene* s =
            importer.ReadFile(argv[1], aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!s) return 1;
        tris = 0;
        for (unsigned i = 0; i < s->mNumMeshes; ++i) tris += s->mMeshes[i]->mNumFaces;
        if (ms < best) best = ms;
    }
    std::printf("{\"assimp_import_ms\": %.1f, \"faces\": %u}\n", best, tris);
}
