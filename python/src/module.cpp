// SPDX-License-Identifier: MIT
// The Python module `bvhlab` (pybind11): scenes from files or numpy arrays, the library's
// structure factory, ray sets and ray/hit files as numpy structured arrays, tracing on the CPU
// or a GPU kernel with the GIL released, verification against Embree, and the path tracer.
// Errors are bvhlab.Error with the CLI's one-line messages. Documented in docs/python.md.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "accel/core/check.h"
#include "renderer/denoise.h"
#include "renderer/gpu/gpu_render.h"
#include "renderer/render_scene.h"
#include "renderer/wavefront.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "scene/io/scene_file.h"
#include "scene/scene.h"
#include "traversal/factory.h"
#include "traversal/gpu/gpu_builder.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/oracle/compare.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/ray_file.h"
#include "traversal/rays/raygen.h"

namespace bvhlab {
const char* git_commit();  // generated at build time
}

namespace py = pybind11;
using namespace bvhlab;

namespace {

/// A scene: the mesh, its hash, and an Embree oracle built on first use.
struct Scene {
    scene::TriangleMesh mesh;
    std::string hash;
    std::string source;
    std::vector<std::string> warnings;
    std::vector<int64_t> kept;  ///< for a scene from arrays with drop_degenerate: the input index of each triangle
    std::unique_ptr<trav::EmbreeOracle> oracle_;

    const trav::EmbreeOracle& oracle() {
        if (!oracle_) oracle_ = std::make_unique<trav::EmbreeOracle>(mesh);
        return *oracle_;
    }
};

/// A structure, holding its scene alive (the hit ids are the scene's triangle ids).
struct Structure {
    std::shared_ptr<Scene> scene;
    trav::AccelStructure s;
};

/// A BVH2 structure on the GPU whose boxes and triangles follow the scene's vertices as they
/// move (trav::GpuRefitter); holds the structure alive.
struct Refit {
    std::shared_ptr<Structure> st;
    std::unique_ptr<trav::GpuRefitter> gpu;
};

/// The numpy dtype of trav::Ray (32 bytes) and trav::Hit (16 bytes): the file records' bytes.
py::dtype ray_dtype() {
    py::list names, formats, offsets;
    names.append("org"), formats.append(py::dtype("(3,)<f4")), offsets.append(0);
    names.append("tmin"), formats.append(py::dtype("<f4")), offsets.append(12);
    names.append("dir"), formats.append(py::dtype("(3,)<f4")), offsets.append(16);
    names.append("tmax"), formats.append(py::dtype("<f4")), offsets.append(28);
    return py::dtype(names, formats, offsets, sizeof(trav::Ray));
}

py::dtype hit_dtype() {
    py::list names, formats, offsets;
    names.append("tri"), formats.append(py::dtype("<i4")), offsets.append(0);
    names.append("t"), formats.append(py::dtype("<f4")), offsets.append(4);
    names.append("u"), formats.append(py::dtype("<f4")), offsets.append(8);
    names.append("v"), formats.append(py::dtype("<f4")), offsets.append(12);
    return py::dtype(names, formats, offsets, sizeof(trav::Hit));
}

/// A numpy array owning a moved-in vector (no copy): the capsule frees it.
template <typename T>
py::array to_numpy(std::vector<T>&& v, const py::dtype& dt) {
    auto* heap = new std::vector<T>(std::move(v));
    py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    return py::array(dt, {py::ssize_t(heap->size())}, {py::ssize_t(sizeof(T))}, heap->data(), owner);
}

/// The records of a numpy array of `dt` records (or raw bytes of the same size), checked.
template <typename T>
const T* records(const py::array& a, const py::dtype& dt, const char* what, size_t* n) {
    if (a.ndim() != 1)
        throw Error(std::string(what) + " must be a 1-D array of records, not " + std::to_string(a.ndim()) + "-D");
    if (a.itemsize() != py::ssize_t(sizeof(T)) || !(a.dtype().equal(dt) || a.dtype().kind() == 'V'))
        throw Error(std::string(what) + " must have bvhlab's dtype (bvhlab." + (sizeof(T) == 32 ? "RAY" : "HIT") +
                    "_DTYPE, " + std::to_string(sizeof(T)) + "-byte records)");
    if (!(a.flags() & py::array::c_style)) throw Error(std::string(what) + " must be C-contiguous");
    *n = size_t(a.shape(0));
    return static_cast<const T*>(a.data());
}

std::vector<trav::Ray> ray_vector(const py::array& rays) {
    size_t n = 0;
    const trav::Ray* p = records<trav::Ray>(rays, ray_dtype(), "rays", &n);
    std::vector<trav::Ray> v(p, p + n);
    for (size_t i = 0; i < n; ++i)
        if (const std::string why = trav::invalid_ray(v[i]); !why.empty())
            throw Error("ray " + std::to_string(i) + " is invalid: " + why);
    return v;
}

trav::Query parse_query(const std::string& q) {
    if (q == "closest") return trav::Query::kClosest;
    if (q == "any") return trav::Query::kAny;
    throw Error("query '" + q + "' is not one of closest, any");
}

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// An (N, 3) float array as vertices, denormals as 0 (as every loader reads them).
std::vector<Vec3> vertex_vector(const FloatArray& vertices) {
    if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw Error("vertices must be an (N, 3) array of floats");
    std::vector<Vec3> out(size_t(vertices.shape(0)));
    const float* v = vertices.data();
    for (size_t i = 0; i < out.size(); ++i) out[i] = scene::flush_denormals(Vec3{v[3 * i], v[3 * i + 1], v[3 * i + 2]});
    return out;
}

std::shared_ptr<Scene> scene_from_arrays(FloatArray vertices,
                                         py::array_t<int64_t, py::array::c_style | py::array::forcecast> indices,
                                         bool drop_degenerate) {
    auto s = std::make_shared<Scene>();
    // The caller's vertices and indices as they are (denormals as 0, as every loader does), so
    // that a triangle's id is its row, unless drop_degenerate removes some (Scene.kept).
    s->mesh.vertices = vertex_vector(vertices);
    if (indices.ndim() != 2 || indices.shape(1) != 3) throw Error("indices must be an (M, 3) array of integers");
    const size_t nv = s->mesh.vertices.size(), nt = size_t(indices.shape(0));
    const int64_t* ix = indices.data();
    for (size_t t = 0; t < nt; ++t) {
        for (int c = 0; c < 3; ++c)
            if (ix[3 * t + c] < 0 || size_t(ix[3 * t + c]) >= nv)
                throw Error("triangle " + std::to_string(t) + " names vertex " + std::to_string(ix[3 * t + c]) +
                            ", but there are " + std::to_string(nv) + " vertices");
        const auto& V = s->mesh.vertices;
        const scene::TriangleCheck check =
            scene::check_triangle(V[size_t(ix[3 * t])], V[size_t(ix[3 * t + 1])], V[size_t(ix[3 * t + 2])]);
        if (check != scene::TriangleCheck::kOk && !drop_degenerate)
            throw Error("triangle " + std::to_string(t) + " has " +
                        (check == scene::TriangleCheck::kNonFinite ? "a non-finite vertex" : "zero area") +
                        " (pass drop_degenerate=True to drop such triangles; Scene.kept maps the ids)");
        if (!scene::count_drop(check, s->mesh.dropped)) continue;
        for (int c = 0; c < 3; ++c) s->mesh.indices.push_back(uint32_t(ix[3 * t + c]));
        s->mesh.material_ids.push_back(-1);
        s->kept.push_back(int64_t(t));
    }
    if (s->mesh.triangle_count() == 0) throw Error("the scene has no usable triangles");
    s->hash = scene::scene_hash(s->mesh);
    s->source = "arrays";
    return s;
}

std::shared_ptr<Scene> load_scene(const std::string& path, bool flatten) {
    auto s = std::make_shared<Scene>();
    scene::SceneFileLoad load = scene::load_scene_file(path, "", "python");
    s->warnings = std::move(load.warnings);
    s->mesh = scene::single_mesh(std::move(load.scene), flatten, "'" + path + "'");
    if (s->mesh.triangle_count() == 0) throw Error("'" + path + "' has no usable triangles");
    s->hash = scene::scene_hash(s->mesh);
    s->source = path;
    return s;
}

std::shared_ptr<Scene> generate_scene(const std::string& kind, uint64_t triangles, uint64_t seed) {
    scene::ProceduralKind k;
    if (kind == "soup")
        k = scene::ProceduralKind::kSoup;
    else if (kind == "structured")
        k = scene::ProceduralKind::kStructured;
    else
        throw Error("generated scene kind '" + kind + "' is not one of soup, structured");
    if (triangles == 0 || triangles > 100000000ull) throw Error("triangles must be in [1, 100000000]");
    auto s = std::make_shared<Scene>();
    s->mesh = scene::make_procedural(k, triangles, seed);
    s->hash = scene::scene_hash(s->mesh);
    s->source = "gen:" + kind + ":" + std::to_string(triangles) + ":" + std::to_string(seed);
    return s;
}

/// The spec of build()'s keyword options; unknown ones are refused by name.
trav::StructureSpec make_spec(const std::string& builder, const std::string& layout, const py::kwargs& kw) {
    trav::StructureSpec spec;
    spec.builder = builder;
    spec.layout = layout;
    for (auto item : kw) {
        const std::string k = py::str(item.first);
        const py::handle v = item.second;
        if (k == "bins")
            spec.options.num_bins = v.cast<int>();
        else if (k == "max_leaf")
            spec.options.config.max_leaf_size = v.cast<uint32_t>();
        else if (k == "min_leaf")
            spec.options.config.min_leaf_size = v.cast<uint32_t>();
        else if (k == "alpha")
            spec.options.sbvh_alpha = v.cast<float>();
        else if (k == "budget")
            spec.options.sbvh_budget = v.cast<float>();
        else if (k == "spatial_bins")
            spec.options.sbvh_spatial_bins = v.cast<int>();
        else if (k == "reinsertion_passes")
            spec.options.reinsertion_passes = v.cast<int>();
        else if (k == "collapse")
            spec.collapse = v.cast<std::string>();
        else if (k == "cw_tris")
            spec.cw_tris = v.cast<std::string>();
        else if (k == "kd_stack")
            spec.kd_stack = v.cast<int>();
        else if (k == "kd_ct")
            spec.kd.traversal_cost = v.cast<float>();
        else if (k == "kd_ci")
            spec.kd.intersection_cost = v.cast<float>();
        else if (k == "kd_bonus")
            spec.kd.empty_bonus = v.cast<float>();
        else if (k == "kd_max_depth")
            spec.kd.max_depth = v.cast<int>();
        else if (k == "epo")
            spec.epo = v.cast<bool>();
        else if (k == "build_device")
            spec.build_device = v.cast<std::string>();
        else if (k == "morton_bits")
            spec.options.morton_bits = v.cast<int>();
        else if (k == "radius")
            spec.options.ploc_radius = v.cast<int>();
        else if (k == "clusters")
            spec.options.cluster_alpha = v.cast<float>();
        else
            throw Error("build() has no option '" + k +
                        "' (bins, max_leaf, min_leaf, alpha, budget, spatial_bins, reinsertion_passes, collapse, "
                        "cw_tris, kd_stack, kd_ct, kd_ci, kd_bonus, kd_max_depth, epo, build_device, morton_bits, "
                        "radius, clusters)");
    }
    return spec;
}

py::object to_py(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

/// The tracer trace() asks for.
std::unique_ptr<trav::Tracer> make_tracer(Structure& st, const std::string& device, const std::string& kernel,
                                          int block_size) {
    if (device == "cpu" || device == "embree") {
        if (!kernel.empty()) throw Error("kernel '" + kernel + "' chooses a GPU kernel; it needs device='gpu'");
        // embree: Embree 3 traces the structure's scene (the reference; the structure is not used).
        return device == "cpu" ? st.s.cpu_tracer() : trav::make_embree_tracer(st.scene->oracle(), false);
    }
    if (device != "gpu") throw Error("device '" + device + "' is not one of cpu, gpu, embree");
    std::string why;
    if (!trav::gpu_available(&why)) throw Error("device='gpu': " + why);
    const trav::KernelInfo& k = kernel.empty() ? st.s.default_kernel() : trav::find_kernel(kernel);
    trav::GpuTraceOptions o = st.s.gpu_options(k);
    o.block_size = block_size;
    return st.s.gpu_tracer(k.name, o);
}

/// trace(): the rays (checked) set once, `runs` timed runs, the hits; the GIL released meanwhile.
py::tuple timed_trace(trav::Tracer& tracer, const py::array& rays, const std::string& query, int runs) {
    const trav::Query q = parse_query(query);
    std::vector<trav::Ray> rv = ray_vector(rays);
    std::vector<trav::Hit> hits;
    std::vector<double> ms;
    {
        py::gil_scoped_release release;
        tracer.set_rays(rv, q);
        for (int i = 0; i < runs; ++i) ms.push_back(tracer.run());
        tracer.hits(hits);
    }
    py::dict info;
    info["kernel"] = tracer.name();
    info["device"] = tracer.device();
    info["ms"] = ms;
    info["block_size"] = tracer.block_size();
    info["timing"] = tracer.device() == "gpu" ? "kernel only (CUDA events)" : "wall clock of the parallel trace";
    return py::make_tuple(to_numpy(std::move(hits), hit_dtype()), info);
}

py::dict report_dict(const trav::CompareReport& rep, const trav::CompareConfig& cc) {
    py::dict d = to_py(trav::report_json(rep, cc));
    py::list first;
    for (const auto& m : rep.first_mismatches) {
        py::dict x;
        x["ray"] = m.ray;
        x["ours_tri"] = m.ours.tri;
        x["ours_t"] = m.ours.t;
        x["oracle_tri"] = m.oracle.tri;
        x["oracle_t"] = m.oracle.t;
        x["reason"] = m.reason;
        first.append(x);
    }
    d["first_mismatches"] = first;
    return d;
}

trav::Camera camera_of(const Scene& s, const py::object& eye, const py::object& target, const py::object& up,
                       float fov) {
    trav::Camera c = trav::framing_camera(s.mesh);
    auto vec = [](const py::object& o, const char* what) {
        const auto v = o.cast<std::vector<float>>();
        if (v.size() != 3) throw Error(std::string(what) + " must have 3 numbers");
        for (float x : v)
            if (!std::isfinite(x)) throw Error(std::string(what) + " must be finite");
        return glm::vec3(v[0], v[1], v[2]);
    };
    if (!eye.is_none()) c.eye = vec(eye, "eye");
    if (!target.is_none()) c.target = vec(target, "target");
    if (!up.is_none()) c.up = vec(up, "up");
    if (fov != 0.0f) {
        if (!(fov > 0.0f && fov < 180.0f)) throw Error("fov " + std::to_string(fov) + " is not in (0, 180)");
        c.fov_y_deg = fov;
    }
    return c;
}

}  // namespace

PYBIND11_MODULE(_bvhlab, m) {
    m.doc() = "bvhlab: acceleration structures for ray tracing, built, traced on CPU and GPU, checked against Embree";
    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
    m.attr("RAY_DTYPE") = ray_dtype();
    m.attr("HIT_DTYPE") = hit_dtype();
    m.attr("__commit__") = git_commit();

    py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A triangle mesh (ids dense from 0) and its hash")
        .def(py::init(&scene_from_arrays), py::arg("vertices"), py::arg("indices"), py::arg("drop_degenerate") = false,
             "A scene from an (N, 3) float array of vertices and an (M, 3) integer array of triangles")
        .def_property_readonly("triangle_count", [](const Scene& s) { return s.mesh.triangle_count(); })
        .def_property_readonly("hash", [](const Scene& s) { return s.hash; })
        .def_property_readonly("source", [](const Scene& s) { return s.source; })
        .def_property_readonly("warnings", [](const Scene& s) { return s.warnings; })
        .def_property_readonly("kept",
                               [](const Scene& s) {
                                   std::vector<int64_t> k = s.kept;
                                   return to_numpy(std::move(k), py::dtype::of<int64_t>());
                               })
        .def_property_readonly("bounds",
                               [](const Scene& s) {
                                   const AABB b = s.mesh.bounds();
                                   return py::make_tuple(py::make_tuple(b.lo.x, b.lo.y, b.lo.z),
                                                         py::make_tuple(b.hi.x, b.hi.y, b.hi.z));
                               })
        .def_property_readonly("vertices",
                               [](const Scene& s) {
                                   py::array_t<float> a({py::ssize_t(s.mesh.vertices.size()), py::ssize_t(3)});
                                   std::memcpy(a.mutable_data(), s.mesh.vertices.data(), s.mesh.vertices.size() * 12);
                                   return a;
                               })
        .def_property_readonly("indices",
                               [](const Scene& s) {
                                   py::array_t<uint32_t> a({py::ssize_t(s.mesh.triangle_count()), py::ssize_t(3)});
                                   std::memcpy(a.mutable_data(), s.mesh.indices.data(), s.mesh.indices.size() * 4);
                                   return a;
                               })
        .def("__repr__", [](const Scene& s) {
            return "<bvhlab.Scene " + s.source + ": " + std::to_string(s.mesh.triangle_count()) + " triangles, hash " +
                   s.hash + ">";
        });

    m.def("load", &load_scene, py::arg("path"), py::arg("flatten") = false,
          "Loads a scene file: OBJ (materials and texture coordinates too), glTF, PLY and the other formats Assimp "
          "reads. A scene that places a mesh more than once needs flatten=True, which makes it one mesh");
    m.def("generate", &generate_scene, py::arg("kind") = "structured", py::arg("triangles") = 10000,
          py::arg("seed") = 1, "A generated scene: soup (random triangles) or structured (a height field with boxes)");

    py::class_<Structure, std::shared_ptr<Structure>>(m, "Structure", "A built acceleration structure")
        .def_property_readonly("name", [](const Structure& s) { return s.s.structure.name; })
        .def_property_readonly("layout",
                               [](const Structure& s) { return std::string(trav::layout_name(s.s.structure.layout)); })
        .def_property_readonly("stats", [](const Structure& s) { return to_py(s.s.figures); })
        .def_property_readonly("bytes", [](const Structure& s) { return s.s.structure.bytes(); })
        .def_property_readonly("depth", [](const Structure& s) { return s.s.structure.depth(); })
        .def_property_readonly("scene", [](const Structure& s) { return s.scene; })
        .def_property_readonly("default_kernel",
                               [](const Structure& s) { return std::string(s.s.default_kernel().name); })
        .def(
            "save", [](const Structure& s, const std::string& path) { s.s.save(path, s.scene->hash); }, py::arg("path"),
            "Writes the tree to a structure file (bvhlab build --out's format)")
        .def("__repr__", [](const Structure& s) {
            return "<bvhlab.Structure " + s.s.structure.name + ", " + std::to_string(s.s.structure.bytes()) + " bytes>";
        });

    m.def(
        "build",
        [](std::shared_ptr<Scene> scene, const std::string& builder, const std::string& layout, py::kwargs kw) {
            const trav::StructureSpec spec = make_spec(builder, layout, kw);
            auto st = std::make_shared<Structure>();
            st->scene = scene;
            {
                py::gil_scoped_release release;
                st->s = trav::build_structure(scene->mesh, spec);
            }
            return st;
        },
        py::arg("scene"), py::arg("builder") = "binned", py::arg("layout") = "bvh2",
        "Builds a structure: builder binned|sweep|sbvh|kdtree on the CPU or lbvh|ploc|hploc|gpu-binned on the GPU, "
        "layout "
        "bvh2|cwbvh, options as keywords "
        "(bins, max_leaf, min_leaf, alpha, budget, spatial_bins, reinsertion_passes, collapse, cw_tris, kd_stack, "
        "build_device, morton_bits, radius, clusters, "
        "kd_ct, kd_ci, kd_bonus, kd_max_depth, epo)");
    m.def(
        "load_structure",
        [](const std::string& path, std::shared_ptr<Scene> scene, const std::string& layout, int kd_stack) {
            trav::StructureSpec spec;
            spec.layout = layout;
            spec.kd_stack = kd_stack;
            spec.check();
            auto st = std::make_shared<Structure>();
            st->scene = scene;
            st->s = trav::load_structure(scene->mesh, scene->hash, path, spec);
            return st;
        },
        py::arg("path"), py::arg("scene"), py::arg("layout") = "bvh2", py::arg("kd_stack") = 64,
        "Loads a structure file written for `scene` (a stale file is refused)");

    m.def(
        "rays",
        [](std::shared_ptr<Scene> scene, const std::string& kind, uint32_t width, uint32_t height, uint32_t spp,
           uint32_t ao_rays, uint32_t diffuse_rays, uint64_t seed, const py::object& eye, const py::object& target,
           const py::object& up, float fov) {
            trav::ProtocolConfig cfg;
            cfg.camera = camera_of(*scene, eye, target, up, fov);
            cfg.primary.width = width;
            cfg.primary.height = height;
            cfg.primary.samples = spp;
            cfg.ao_rays = ao_rays;
            cfg.diffuse_rays = diffuse_rays;
            cfg.seed = seed;
            const trav::RayType type = trav::parse_ray_type(kind);
            const trav::EmbreeOracle& oracle = scene->oracle();
            trav::RaySet set;
            {
                py::gil_scoped_release release;
                trav::RayProtocol proto(scene->mesh, oracle, cfg);
                set = proto.make(type);
            }
            return py::make_tuple(to_numpy(std::move(set.rays), ray_dtype()),
                                  set.query == trav::Query::kAny ? "any" : "closest");
        },
        py::arg("scene"), py::arg("kind") = "primary", py::arg("width") = 1024, py::arg("height") = 768,
        py::arg("spp") = 1, py::arg("ao_rays") = 8, py::arg("diffuse_rays") = 4, py::arg("seed") = 1,
        py::arg("eye") = py::none(), py::arg("target") = py::none(), py::arg("up") = py::none(), py::arg("fov") = 0.0f,
        "The ray protocol's rays: kind primary|ao|diffuse|shadow; returns (rays, query). Secondary rays start at "
        "Embree's primary hits, so they do not depend on any structure");

    m.def(
        "read_rays",
        [](const std::string& path) {
            trav::RaySet set = trav::read_ray_file(path);
            return py::make_tuple(to_numpy(std::move(set.rays), ray_dtype()),
                                  set.query == trav::Query::kAny ? "any" : "closest");
        },
        py::arg("path"), "Reads a ray file: (rays, query)");
    m.def(
        "write_rays",
        [](const std::string& path, const py::array& rays, const std::string& query) {
            trav::RaySet set;
            set.rays = ray_vector(rays);
            set.query = parse_query(query);
            set.writer = std::string("python ") + git_commit();
            trav::write_ray_file(path, set);
        },
        py::arg("path"), py::arg("rays"), py::arg("query") = "closest", "Writes a ray file (checksummed, atomic)");
    m.def(
        "read_hits",
        [](const std::string& path) {
            trav::HitSet set = trav::read_hit_file(path);
            return py::make_tuple(to_numpy(std::move(set.hits), hit_dtype()),
                                  set.query == trav::Query::kAny ? "any" : "closest");
        },
        py::arg("path"), "Reads a hit file: (hits, query)");
    m.def(
        "write_hits",
        [](const std::string& path, const py::array& hits, const std::string& query) {
            size_t n = 0;
            const trav::Hit* p = records<trav::Hit>(hits, hit_dtype(), "hits", &n);
            trav::HitSet set;
            set.hits.assign(p, p + n);
            set.query = parse_query(query);
            set.writer = std::string("python ") + git_commit();
            trav::write_hit_file(path, set);
        },
        py::arg("path"), py::arg("hits"), py::arg("query") = "closest", "Writes a hit file (checksummed, atomic)");

    m.def(
        "trace",
        [](std::shared_ptr<Structure> st, const py::array& rays, const std::string& query, const std::string& device,
           const std::string& kernel, int block_size, int runs) {
            if (runs < 1 || runs > 1000) throw Error("runs " + std::to_string(runs) + " is not in [1, 1000]");
            if (block_size != 0 && (block_size < 32 || block_size > 1024))
                throw Error("block_size " + std::to_string(block_size) + " is not in [32, 1024]");
            return timed_trace(*make_tracer(*st, device, kernel, block_size), rays, query, runs);
        },
        py::arg("structure"), py::arg("rays"), py::arg("query") = "closest", py::arg("device") = "cpu",
        py::arg("kernel") = "", py::arg("block_size") = 0, py::arg("runs") = 1,
        "Traces rays (a RAY_DTYPE array) with bvhlab's CPU traversal of the structure (device='cpu'), a GPU kernel "
        "(device='gpu'; default kernel: the registry's for the layout) or Embree 3 (device='embree', the reference); "
        "returns (hits, info) with info['ms'] the time of each run. The GIL is released while tracing");

    m.def(
        "verify",
        [](std::shared_ptr<Scene> scene, const py::array& rays, const py::array& hits, const std::string& query,
           float edge_eps, float t_tol) {
            const trav::Query q = parse_query(query);
            std::vector<trav::Ray> rv = ray_vector(rays);
            size_t n = 0;
            const trav::Hit* hp = records<trav::Hit>(hits, hit_dtype(), "hits", &n);
            if (n != rv.size()) throw Error(std::to_string(n) + " hits for " + std::to_string(rv.size()) + " rays");
            std::vector<trav::Hit> ours(hp, hp + n), ref;
            for (size_t i = 0; i < n; ++i)
                if (ours[i].tri >= 0 && size_t(ours[i].tri) >= scene->mesh.triangle_count())
                    throw Error("hit " + std::to_string(i) + " names triangle " + std::to_string(ours[i].tri) +
                                ", but the scene has " + std::to_string(scene->mesh.triangle_count()));
            trav::CompareConfig cc;
            cc.edge_eps = edge_eps;
            cc.t_rel_tol = t_tol;
            if (!(edge_eps >= 0.0f && edge_eps <= 0.1f)) throw Error("edge_eps is not in [0, 0.1]");
            if (!(t_tol >= 0.0f && t_tol <= 0.1f)) throw Error("t_tol is not in [0, 0.1]");
            const trav::EmbreeOracle& oracle = scene->oracle();
            trav::CompareReport rep;
            {
                py::gil_scoped_release release;
                oracle.trace(rv, q, ref);
                rep = trav::compare_hits(
                    scene->mesh, rv, q, ours, ref, [&](const trav::Ray& r) { return oracle.intersect(r); }, cc);
            }
            return report_dict(rep, cc);
        },
        py::arg("scene"), py::arg("rays"), py::arg("hits"), py::arg("query") = "closest",
        py::arg("edge_eps") = trav::CompareConfig{}.edge_eps, py::arg("t_tol") = trav::CompareConfig{}.t_rel_tol,
        "Checks every hit against Embree; returns a report dict (rays, agree, ties by kind, mismatches by kind)");

    m.def(
        "render",
        [](std::shared_ptr<Structure> st, uint32_t width, uint32_t height, uint32_t spp, uint32_t max_depth,
           uint32_t seed, const std::string& device, const std::string& kernel, const py::object& eye,
           const py::object& target, const py::object& up, float fov, const py::object& sky, bool denoise,
           const std::string& oidn) -> py::object {
            render::SkyOption so;
            if (!sky.is_none()) {
                const auto v = sky.cast<std::vector<float>>();
                if (v.size() != 3) throw Error("sky must have 3 numbers");
                for (float x : v)
                    if (!(x >= 0.0f && x <= 1e6f)) throw Error("sky radiance must be finite and in [0, 1e6]");
                so.given = true;
                so.radiance = Vec3{v[0], v[1], v[2]};
            }
            const render::RenderScene rscene(st->scene->mesh, so);
            const render::CameraData cd =
                render::make_camera(camera_of(*st->scene, eye, target, up, fov), width, height, {});
            render::RenderSettings rs;
            rs.spp = spp;
            rs.max_depth = max_depth;
            rs.seed = seed;
            rs.aovs = denoise;  // the denoiser takes the albedo and normal
            render::check_settings(rs, cd);
            render::DenoiseOptions dopts;
            dopts.library = oidn;
            if (denoise) {
                std::string why;
                if (render::find_oidn(dopts, &why).empty()) throw Error("denoise: " + why);
            }
            std::unique_ptr<trav::Tracer> tracer = make_tracer(*st, device, kernel, 0);
            render::RenderResult res;
            {
                py::gil_scoped_release release;
                if (device == "gpu") {
                    const trav::KernelInfo& k = trav::find_kernel(tracer->name());
                    res = render::render_gpu(rscene, cd, rs, *st->s.device(), k, st->s.gpu_options(k));
                } else {
                    res = render::render_host(rscene, cd, rs, *tracer, *tracer);
                }
            }
            static_assert(sizeof(Vec3) == 3 * sizeof(float), "an image row is packed floats");
            const auto to_array = [](const render::Image& im) {
                py::array_t<float> a({py::ssize_t(im.height), py::ssize_t(im.width), py::ssize_t(3)});
                std::memcpy(a.mutable_data(), im.pixels.data(), im.pixels.size() * sizeof(Vec3));
                return a;
            };
            if (!denoise) return to_array(res.mean);
            render::DenoiseResult d;
            {
                py::gil_scoped_release release;
                d = render::denoise(res.mean, res.albedo, res.normal, dopts);
            }
            return py::make_tuple(to_array(res.mean), to_array(d.image));
        },
        py::arg("structure"), py::arg("width") = 320, py::arg("height") = 240, py::arg("spp") = 16,
        py::arg("max_depth") = 8, py::arg("seed") = 1, py::arg("device") = "cpu", py::arg("kernel") = "",
        py::arg("eye") = py::none(), py::arg("target") = py::none(), py::arg("up") = py::none(), py::arg("fov") = 0.0f,
        py::arg("sky") = py::none(), py::arg("denoise") = false, py::arg("oidn") = "",
        "Path-traces the structure's scene (device='cpu': bvhlab's CPU traversal, 'gpu': the GPU path tracer, "
        "'embree': the reference integrator, Embree tracing every ray) with its OBJ materials, lit by its emissive "
        "triangles and the sky (RGB "
        "radiance; default: white without emitters, black with them); returns "
        "a float32 (height, width, 3) image of linear radiance. denoise=True also runs Intel Open Image Denoise "
        "(the pyoidn wheel's library, or oidn= a library path) with the albedo and normal, and returns (image, "
        "denoised)");

    py::class_<Refit>(m, "Refitter",
                      "A BVH2 structure on the GPU refitted to moved vertices (same triangles): refit() then trace()")
        .def(py::init([](std::shared_ptr<Structure> st) {
                 auto r = std::make_unique<Refit>();
                 r->gpu = std::make_unique<trav::GpuRefitter>(st->s.structure, st->scene->mesh);
                 r->st = std::move(st);
                 return r;
             }),
             py::arg("structure"), "Uploads a structure of the bvh2 layout and its scene's triangles (a GPU is needed)")
        .def(
            "refit",
            [](Refit& r, const FloatArray& vertices) {
                const std::vector<Vec3> v = vertex_vector(vertices);
                if (v.size() != r.st->scene->mesh.vertices.size())
                    throw Error(std::to_string(v.size()) + " vertices for a scene of " +
                                std::to_string(r.st->scene->mesh.vertices.size()));
                trav::GpuBuildTimes t;
                {
                    py::gil_scoped_release release;
                    t = r.gpu->refit(v);
                }
                py::dict d;
                d["ms"] = t.total_ms;
                d["upload_ms"] = t.upload_ms;
                d["timing"] = "device time of the refit (CUDA events); upload_ms: the vertices";
                return d;
            },
            py::arg("vertices"),
            "Refits to (N, 3) vertices, as many as the scene has; a vertex outside bvhlab's numeric domain raises "
            "bvhlab.Error and leaves the structure as it was. Returns {'ms', 'upload_ms', 'timing'}")
        .def(
            "trace",
            [](Refit& r, const py::array& rays, const std::string& query, const std::string& kernel, int runs) {
                if (runs < 1 || runs > 1000) throw Error("runs " + std::to_string(runs) + " is not in [1, 1000]");
                const trav::KernelInfo& k = kernel.empty() ? r.st->s.default_kernel() : trav::find_kernel(kernel);
                return timed_trace(*trav::make_gpu_tracer(r.gpu->device(), k, r.st->s.gpu_options(k)), rays, query,
                                   runs);
            },
            py::arg("rays"), py::arg("query") = "closest", py::arg("kernel") = "", py::arg("runs") = 1,
            "Traces rays through the refitted structure with a GPU kernel of the bvh2 layout (default: the "
            "registry's); returns (hits, info) as trace() does");

    m.def(
        "kernels",
        []() {
            py::list out;
            for (const trav::KernelInfo& k : trav::registered_kernels()) {
                py::dict d;
                d["name"] = k.name;
                d["layout"] = trav::layout_name(k.layout);
                d["description"] = k.description;
                d["default"] = k.is_default;
                d["short_stack"] = k.short_stack;
                d["default_block"] = k.default_block;
                out.append(d);
            }
            return out;
        },
        "The registered GPU kernels (empty in a build without CUDA)");
    m.def(
        "gpu_available",
        []() {
            std::string why;
            const bool ok = trav::gpu_available(&why);
            return py::make_tuple(ok, why);
        },
        "(True, '') when a CUDA device is usable, else (False, why)");
}
