// SPDX-License-Identifier: MIT
// Helpers shared by the tests: paths, temporary files, scenes and hit comparison.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "scene/mesh.h"

namespace bvhlab::test {

/// The project's data/ folder: $BVHLAB_DATA (for installed test binaries), else the source tree's.
inline std::string data_dir() {
    const char* env = std::getenv("BVHLAB_DATA");
    return env && *env ? env : BVHLAB_TEST_DATA_DIR;
}

/// $BVHLAB_SCENES or "" when unset.
inline std::string scenes_dir() {
    const char* s = std::getenv("BVHLAB_SCENES");
    return s ? s : "";
}

/// A file under the test's temporary folder that is removed when this object dies.
class TempFile {
public:
    explicit TempFile(const std::string& name, const std::string& contents = "") {
        const char* tmp = std::getenv("TMPDIR");
        path_ = std::string(tmp && *tmp ? tmp : "/tmp") + "/bvhlab_test_" + std::to_string(getpid()) + "_" + name;
        if (!contents.empty() || name.find(".obj") != std::string::npos) {
            std::ofstream(path_, std::ios::binary) << contents;
        }
    }
    ~TempFile() { std::remove(path_.c_str()); }
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

/// The whole content of a file, as bytes.
inline std::string read_file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

/// One triangle per entry of `tris` (9 floats each), no materials.
inline scene::TriangleMesh mesh_of(std::initializer_list<std::array<float, 9>> tris) {
    scene::TriangleMesh m;
    for (const auto& t : tris)
        scene::add_triangle_checked(m, {t[0], t[1], t[2]}, {t[3], t[4], t[5]}, {t[6], t[7], t[8]}, -1);
    return m;
}

}  // namespace bvhlab::test
