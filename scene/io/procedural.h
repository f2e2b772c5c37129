// SPDX-License-Identifier: MIT
// Seeded procedural scenes with an exact triangle count, for tests and build benchmarks.
#pragma once

#include <cstdint>
#include <string>

#include "scene/mesh.h"

namespace bvhlab::scene {

enum class ProceduralKind {
    kSoup,        ///< random triangles in the unit cube, edge length ~ 2 / cbrt(n)
    kStructured,  ///< a wavy height field in [0,1]^2 with boxes standing on it
};

/// Parses "soup" or "structured"; throws bvhlab::Error otherwise.
ProceduralKind parse_procedural_kind(const std::string& name);

/// Exactly `triangles` triangles (>= 1), the same for the same (kind, triangles, seed).
TriangleMesh make_procedural(ProceduralKind kind, uint64_t triangles, uint64_t seed);

}  // namespace bvhlab::scene
