// SPDX-License-Identifier: MIT
// `bvhlab build`: build a BVH and print its quality figures.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "accel/core/check.h"
#include "accel/io/tree_file.h"
#include "scene/io/atomic_file.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/gpu_builder.h"

namespace bvhlab::cli {

void print_build_table(const Scene& s, const Built& b) {
    const auto& r = b.record;
    if (b.is_kd()) {
        std::printf("scene        %s (%zu triangles, hash %s)\n", s.name.c_str(), s.mesh.triangle_count(),
                    s.hash.c_str());
        std::printf("builder      SAH kd-tree (Wald-Havran O(N log N))  build %.1f ms, depth %llu of %d\n",
                    b.result.build_ms, (unsigned long long)r["depth"].get<uint64_t>(), r["max_depth"].get<int>());
        std::printf("nodes        %zu (%llu leaves); references %zu (%.3fx the triangles)\n", r["nodes"].get<size_t>(),
                    (unsigned long long)r["leaves"].get<uint64_t>(), r["references"].get<size_t>(),
                    r["duplication"].get<double>());
        std::printf("kd SAH       %.2f (Ct = %g, Ci = %g, empty bonus %g)\n", r["sah"].get<double>(),
                    r["sah_constants"]["traversal"].get<double>(), r["sah_constants"]["intersection"].get<double>(),
                    r["sah_constants"]["empty_bonus"].get<double>());
        std::printf("bytes        %zu (tree), %zu (kd layout + Woop triangles)\n", r["bytes"].get<size_t>(),
                    b.structure.bytes());
        return;
    }
    std::printf("scene        %s (%zu triangles, hash %s)\n", s.name.c_str(), s.mesh.triangle_count(), s.hash.c_str());
    if (trav::is_two_level(b.structure.layout)) {
        std::printf(
            "two-level    %s %s BLAS over %llu meshes (%llu triangles stored), binned TLAS over %llu instances\n",
            r["builder"].get<std::string>().c_str(),
            b.structure.layout == trav::Layout::kTwoLevelCwbvh ? "cwbvh" : "bvh2",
            (unsigned long long)r["meshes"].get<uint64_t>(), (unsigned long long)r["stored_triangles"].get<uint64_t>(),
            (unsigned long long)r["instances"].get<uint64_t>());
        std::printf("build        %.1f ms\n", b.result.build_ms);
        std::printf("nodes        %llu BLAS (depth %u), %llu TLAS (depth %u)\n",
                    (unsigned long long)r["blas_nodes"].get<uint64_t>(), r["blas_depth"].get<uint32_t>(),
                    (unsigned long long)r["tlas_nodes"].get<uint64_t>(), r["tlas_depth"].get<uint32_t>());
        std::printf("bytes        %zu (two-level layout: %.1f per world triangle)\n", b.structure.bytes(),
                    r["bytes_per_world_triangle"].get<double>());
        return;
    }
    std::printf("builder      %s  build %.1f ms\n", r["builder"].get<std::string>().c_str(), b.result.build_ms);
    if (r.contains("gpu_build")) {
        const auto& gb = r["gpu_build"];
        std::printf(
            "gpu build    %.3f ms on the device (bounds %.3f, morton %.3f, sort %.3f, hierarchy %.3f, reinsertion "
            "%.3f, layout %.3f), %.0f Mtris/s, peak %.1f MB\n",
            gb["total_ms"].get<double>(), gb["bounds_ms"].get<double>(), gb["morton_ms"].get<double>(),
            gb["sort_ms"].get<double>(), gb["hierarchy_ms"].get<double>(), gb["optimize_ms"].get<double>(),
            gb["convert_ms"].get<double>(), gb["mtris_per_s"].get<double>(),
            double(gb["peak_device_bytes"].get<size_t>()) / 1e6);
        if (gb.contains("median_ms"))
            std::printf("gpu timing   median %.3f ms of %zu runs after a warm-up: %.0f Mtris/s\n",
                        gb["median_ms"].get<double>(), gb["runs_ms"].size(), gb["median_mtris_per_s"].get<double>());
    }
    std::printf("nodes        %llu (%llu leaves), depth %u\n", (unsigned long long)b.stats.nodes,
                (unsigned long long)b.stats.leaves, b.stats.depth);
    std::printf("leaf size    mean %.2f, max %u; references %llu (%.3fx the triangles)\n", b.stats.mean_leaf_size,
                b.stats.max_leaf_size, (unsigned long long)b.stats.references,
                double(b.stats.references) / double(s.mesh.triangle_count()));
    std::printf("SAH          %.4f (Ct = Ci = 1, root-normalised)\n", b.stats.sah);
    if (b.stats.epo >= 0) std::printf("EPO          %.4f\n", b.stats.epo);
    if (!b.stats.epo_skipped.empty()) std::printf("EPO          skipped (work bound reached)\n");
    if (b.structure.layout != trav::Layout::kCwbvh) {
        std::printf("bytes        %llu (BuildTree), %zu (bvh2 layout + Woop triangles)\n",
                    (unsigned long long)b.stats.bytes, b.structure.bytes());
        return;
    }
    const auto& w = r["wide"];
    std::printf("cwbvh        %s collapse in %.1f ms: %zu nodes, %zu leaves, %.2f children per node, depth %u\n",
                w["collapse"].get<std::string>().c_str(), w["collapse_ms"].get<double>(), w["nodes"].get<size_t>(),
                w["leaves"].get<size_t>(), w["mean_children"].get<double>(), w["depth"].get<uint32_t>());
    std::printf("wide SAH     %.4f (node %g, triangle %g, root-normalised)\n", w["sah"].get<double>(),
                w["sah_costs"]["node"].get<double>(), w["sah_costs"]["prim"].get<double>());
    std::printf("bytes        %zu (cwbvh layout + %s triangles) against %zu for the bvh2 layout: %.3fx\n",
                b.structure.bytes(), w["triangles"].get<std::string>() == "vertices" ? "vertex" : "Woop",
                r["bvh2_layout_bytes"].get<size_t>(), r["bytes_vs_bvh2"].get<double>());
}

namespace {

/// The median of a non-empty list of timings.
double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

void register_build(CLI::App& app, Globals& g) {
    struct Opts {
        std::string scene, out;
        BuildOptions build;
        int runs = 0;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand(
        "build", "build a BVH (binary, or collapsed to a CWBVH) or kd-tree from a scene and print its quality figures");
    sub->add_option("scene", o->scene, kSceneHelp)->required();
    o->build.add_to(*sub);
    sub->add_flag("!--no-epo", o->build.epo, "skip EPO (slow on very large scenes)");
    sub->add_option("-o,--out", o->out, "write the tree to this structure file (load it with --structure FILE)");
    auto* runs = sub->add_option("--runs", o->runs,
                                 "GPU builders: build this many more times after a warm-up and report the median "
                                 "device time (gpu_build.median_ms) and its Mtris/s; for an instanced scene, rebuild "
                                 "its TLAS on the GPU this many times instead (gpu_tlas.median_ms)")
                     ->check(CLI::Range(1, 1000));
    sub->callback([o, &g, runs] {
        const std::vector<scene::NamedFile> outputs{{"--out", o->out}};
        std::vector<scene::NamedFile> inputs{{"the scene", o->scene}, {"--structure", o->build.structure_file()}};
        scene::refuse_clashing_files(outputs, inputs);  // before the load, and again with its files
        Scene s = load_scene(o->scene, g);
        for (auto& f : s.input_files()) inputs.push_back(std::move(f));
        scene::refuse_clashing_files(outputs, inputs);
        if (s.placed && !o->out.empty())
            throw Error("--out writes a structure file, which holds a single-level structure, and scene '" + s.name +
                        "' is built two-level (it places a mesh more than once): --flatten makes it one mesh");
        if (runs->count() &&
            (!o->build.structure_file().empty() || o->build.is_kdtree() || !accel::runs_on_gpu(o->build.kind())))
            throw Error(
                "--runs applies to a GPU builder (--builder lbvh, ploc, hploc or gpu-binned): it times the build of "
                "one mesh, or "
                "the TLAS rebuild of an instanced scene");
        if (runs->count() && s.placed && o->build.layout != "bvh2")
            throw Error(
                "--runs on an instanced scene rebuilds its TLAS on the GPU, which the two-level BVH2 layout "
                "has (not --layout " +
                o->build.layout + ")");
        Built b = build_scene(s, o->build, g);
        if (o->runs > 0 && s.placed) {
            // The TLAS rebuilt on the GPU from the instances' own transforms, as a renderer would
            // each frame: a warm-up, then the runs.
            trav::GpuTlasBuilder tlas(b.structure);
            std::vector<scene::Transform> transforms;
            for (const scene::Instance& inst : s.placed->instances) transforms.push_back(inst.transform);
            std::vector<double> ms;
            trav::GpuBuildTimes last;
            {
                Stage st(g, "rebuilding the TLAS over " + std::to_string(transforms.size()) + " instances " +
                                std::to_string(o->runs) + " times on the GPU");
                for (int k = 0; k <= o->runs; ++k) {
                    last = tlas.rebuild(transforms, b.spec.kind(), b.spec.options);
                    if (k > 0) ms.push_back(last.total_ms);
                }
            }
            nlohmann::json& gt = b.record["gpu_tlas"];
            gt["builder"] = b.spec.builder;
            gt["instances"] = transforms.size();
            gt["runs_ms"] = ms;
            gt["last"] = trav::gpu_stage_times(last);
            gt["median_ms"] = median(ms);
        } else if (o->runs > 0) {
            std::vector<double> ms;
            {
                Stage st(g, "timing " + std::to_string(o->runs) + " more builds on the GPU");
                for (const trav::GpuBuildTimes& t :
                     trav::time_gpu_builds(s.mesh, b.spec.kind(), b.spec.options, o->runs))
                    ms.push_back(t.total_ms);
            }
            nlohmann::json& gb = b.record["gpu_build"];
            gb["runs_ms"] = ms;
            gb["median_ms"] = median(ms);
            gb["median_mtris_per_s"] = double(s.mesh.triangle_count()) / (median(ms) * 1e3);
        }
        if (!o->out.empty()) {
            b.save(o->out, s.hash);
            b.record["structure_file"] = o->out;
        }
        // Device memory, where there is a GPU: the structure uploaded as a kernel reads it, and
        // the most device memory the process held for it (null without a GPU).
        // The GPU and driver those figures (and a GPU build's times) come from.
        b.record["device_structure_bytes"] = nullptr;
        b.record["device_peak_bytes"] = nullptr;
        b.record["gpu"] = nullptr;
        b.record["driver"] = nullptr;
        if (trav::gpu_available()) {
            b.record["device_structure_bytes"] = b.device()->bytes();
            b.record["device_peak_bytes"] = trav::gpu_memory_use().peak;
            b.record["gpu"] = trav::gpu_description();
            b.record["driver"] = trav::gpu_driver();
        }
        if (g.json)
            emit(b.record);
        else
            print_build_table(s, b);
    });
}

}  // namespace bvhlab::cli
