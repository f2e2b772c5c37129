// SPDX-License-Identifier: MIT
// The scenes, ray sets and figures of the pinned-work test (tests/traversal/pinned_work_test.cpp)
// and of the GPU counters' check against it.
#pragma once

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "scene/io/procedural.h"
#include "tests/support/adversarial.h"
#include "tests/support/edge_rays.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::test {

/// Relative tolerance of every pinned figure.
constexpr double kPinnedTolerance = 0.02;

/// tests/traversal/pinned_work.json in the source tree, or $BVHLAB_PINNED_WORK.
inline std::string pinned_work_path() {
    const char* env = std::getenv("BVHLAB_PINNED_WORK");
    return env && *env ? env : std::string(BVHLAB_TEST_SOURCE_DIR) + "/traversal/pinned_work.json";
}

struct PinnedScene {
    std::string name;
    scene::TriangleMesh mesh;
    trav::Camera camera;
};

/// Three seeded scenes: an adversarial room, a structured height field with boxes, the lattice.
inline std::vector<PinnedScene> pinned_scenes() {
    std::vector<PinnedScene> s;
    AdversarialScene room = make_adversarial_scene({7, 0.0, 8, false});
    s.push_back({"room-seed7", std::move(room.mesh), room.camera});
    scene::TriangleMesh field = scene::make_procedural(scene::ProceduralKind::kStructured, 4000, 5);
    const trav::Camera field_camera = trav::framing_camera(field);
    s.push_back({"structured-4000", std::move(field), field_camera});
    scene::TriangleMesh lattice = make_lattice_scene(1);
    const trav::Camera lattice_camera = trav::framing_camera(lattice);
    s.push_back({"lattice-1", std::move(lattice), lattice_camera});
    return s;
}

/// The protocol's primary (64 x 48) and diffuse rays of a pinned scene, seed 1.
struct PinnedRays {
    std::vector<std::pair<std::string, trav::RaySet>> sets;
    explicit PinnedRays(const PinnedScene& scene) {
        const trav::EmbreeOracle oracle(scene.mesh);
        trav::ProtocolConfig cfg;
        cfg.camera = scene.camera;
        cfg.primary = {64, 48, 1, 0};
        trav::RayProtocol proto(scene.mesh, oracle, cfg);
        sets.emplace_back("primary", proto.make(trav::RayType::kPrimary));
        sets.emplace_back("diffuse", proto.make(trav::RayType::kDiffuse));
    }
};

/// Mean and 99th percentile of nodes, leaves and triangle tests per ray.
inline nlohmann::json summarise_work(const std::vector<trav::TraversalCounters>& c) {
    nlohmann::json j;
    auto add = [&](const char* name, auto field) {
        std::vector<double> v;
        for (const auto& x : c) v.push_back(double(field(x)));
        std::sort(v.begin(), v.end());
        double sum = 0;
        for (double x : v) sum += x;
        j[std::string(name) + "_mean"] = v.empty() ? 0.0 : sum / double(v.size());
        j[std::string(name) + "_p99"] = v.empty() ? 0.0 : v[size_t(0.99 * double(v.size() - 1))];
    };
    add("nodes", [](const trav::TraversalCounters& x) { return x.nodes; });
    add("leaves", [](const trav::TraversalCounters& x) { return x.leaves; });
    add("tri_tests", [](const trav::TraversalCounters& x) { return x.tri_tests; });
    return j;
}

/// One line per figure of `pinned` that `now` moved by more than `tol` (relative).
inline std::vector<std::string> compare_pinned(const nlohmann::json& pinned, const nlohmann::json& now, double tol) {
    std::vector<std::string> moved;
    auto check = [&](const std::string& what, double was, double is) {
        if (std::fabs(is - was) > tol * std::fabs(was))
            moved.push_back(what + ": pinned " + std::to_string(was) + ", now " + std::to_string(is) + " (" +
                            std::to_string(was != 0 ? 100.0 * (is - was) / was : INFINITY) + "%)");
    };
    for (const auto& [key, figures] : pinned.at("work").items()) {
        if (!now.at("work").contains(key)) continue;
        for (const auto& [name, value] : figures.items())
            check(key + " " + name, value.get<double>(), now.at("work").at(key).value(name, NAN));
    }
    for (const auto& [key, value] : pinned.at("sah").items())
        if (now.at("sah").contains(key)) check(key + " sah", value.get<double>(), now.at("sah").at(key).get<double>());
    return moved;
}

}  // namespace bvhlab::test
