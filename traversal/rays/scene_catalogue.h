// SPDX-License-Identifier: MIT
// Scene catalogues: the scenes.json files of $BVHLAB_SCENES and data/, which name scenes and
// give their files, triangle counts, cameras and AO lengths.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "traversal/rays/raygen.h"

namespace bvhlab::trav {

struct CatalogueEntry {
    std::string name;
    std::string file;              ///< path of the OBJ: the catalogue's folder joined with its "file"
    uint64_t triangles = 0;        ///< 0 when the entry does not say
    std::optional<Camera> camera;  ///< absent when the entry has none
    float ao_length = 0.0f;        ///< 0 when the entry does not say
};

/// The entries of DIR/scenes.json, by name. Empty when there is no such file; throws
/// bvhlab::Error naming the file when it exists but is malformed.
std::vector<CatalogueEntry> read_catalogue(const std::string& dir);

}  // namespace bvhlab::trav
