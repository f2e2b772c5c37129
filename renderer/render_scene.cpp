// SPDX-License-Identifier: MIT
#include "renderer/render_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>

#include "accel/core/check.h"
#include "renderer/core/normal_map.h"
#include "scene/domain.h"
#include "scene/io/atomic_file.h"

namespace bvhlab::render {

RenderMaterial default_material() {
    RenderMaterial m{};
    m.type = BsdfType::kLambert;
    m.base = scene::Material{}.diffuse;
    m.alpha = 1.0f;
    m.ior = 1.5f;
    m.texture = -1;
    m.normal_map = -1;
    m.normal_kind = NormalMapKind::kNone;
    m.bump_scale = 1.0f;
    return m;
}

float roughness_from_shininess(float ns) {
    return std::clamp(std::sqrt(2.0f / (std::max(ns, 0.0f) + 2.0f)), 0.001f, 1.0f);
}

RenderMaterial map_material(const scene::Material& in, int32_t texture) {
    RenderMaterial m = default_material();
    m.base = in.diffuse;
    m.specular = in.specular;
    m.emission = in.emission;
    // Ka above 1 is no reflectance; files such as tinyobjloader's Cornell box use it for the
    // light's emission. Read that way only when Ke is black.
    if (max3(in.emission) <= 0.0f && max3(in.ambient) > 1.0f) m.emission = in.ambient;
    m.alpha = roughness_from_shininess(in.shininess);
    m.ior = in.ior > 1.0f ? in.ior : 1.5f;
    m.texture = texture;
    const bool black_ks = max3(in.specular) <= 0.0f;
    if (in.dissolve < 1.0f || in.illum == 4 || in.illum == 6 || in.illum == 7 || in.illum == 9) {
        m.type = BsdfType::kGlass;
    } else if (in.illum == 3 || in.illum == 5) {
        m.type = in.shininess >= 1000.0f ? BsdfType::kMirror : BsdfType::kConductor;
        if (black_ks) m.specular = in.diffuse;
    } else if (in.illum == 2 && !black_ks) {
        m.type = BsdfType::kPlastic;
    } else {
        m.type = BsdfType::kLambert;
    }
    return m;
}

std::vector<AliasEntry> build_alias_table(const std::vector<double>& weights) {
    const size_t n = weights.size();
    BVHLAB_CHECK(n > 0 && n < (size_t(1) << 32), "an alias table needs 1 to 2^32 - 1 entries");
    const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
    BVHLAB_CHECK(total > 0.0 && std::isfinite(total), "an alias table needs a positive, finite total weight");
    std::vector<AliasEntry> table(n);
    std::vector<double> scaled(n);
    std::vector<uint32_t> small, large;
    for (size_t i = 0; i < n; ++i) {
        scaled[i] = weights[i] * double(n) / total;
        (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
    }
    while (!small.empty() && !large.empty()) {
        const uint32_t s = small.back(), l = large.back();
        small.pop_back();
        table[s] = {float(scaled[s]), l};
        scaled[l] -= 1.0 - scaled[s];
        if (scaled[l] < 1.0) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // What is left is 1 up to rounding.
    for (uint32_t i : large) table[i] = {1.0f, i};
    for (uint32_t i : small) table[i] = {1.0f, i};
    return table;
}

std::string resolve_texture_path(const std::string& base_dir, const std::string& name) {
    std::string p = name;
    std::replace(p.begin(), p.end(), '\\', '/');
    const std::filesystem::path path(p);
    if (path.is_absolute() || base_dir.empty()) return path.lexically_normal().string();
    return (std::filesystem::path(base_dir) / path).lexically_normal().string();
}

namespace {

/// The problem with a texture's texels for its role, or "": colours must be finite and not
/// negative, normal maps in [0, 1] (they hold (n + 1) / 2), heights finite.
std::string texel_problem(const Image& img, const char* role) {
    const bool normals = std::string(role) == "norm";
    const bool heights = std::string(role) == "map_Bump";
    for (const Vec3& p : img.pixels) {
        if (!std::isfinite(p.x + p.y + p.z)) return "has a NaN or infinite texel";
        if (heights) continue;
        if (p.x < 0.0f || p.y < 0.0f || p.z < 0.0f) return "has a negative texel";
        if (normals && (p.x > 1.0f || p.y > 1.0f || p.z > 1.0f))
            return "has a texel above 1, which a normal map (texels (n + 1) / 2) cannot hold";
    }
    return "";
}

/// Whether every texel of [p, p + n) is grey (equal channels): a map_Bump image is then a height
/// map, else a tangent-space normal map.
bool grey(const Vec3* p, size_t n) {
    for (size_t i = 0; i < n; ++i)
        if (p[i].x != p[i].y || p[i].y != p[i].z) return false;
    return true;
}

}  // namespace

RenderScene::LoadedTexture RenderScene::load_texture(const TextureOptions& opts, const scene::Material& m,
                                                     const std::string& name, const char* role,
                                                     std::map<std::string, LoadedTexture>& loaded) {
    const std::string r = role;
    const std::string path = resolve_texture_path(opts.base_dir, name);
    const std::string key = r + ":" + path;  // one file in two roles is loaded once for each
    const std::string what = "texture " + path + " (" + r + " of material '" + m.name + "')";
    auto it = loaded.find(key);
    if (it == loaded.end()) {
        LoadedTexture t{-1, false};
        const std::string problem = scene::regular_file_problem(path);
        if (problem.empty()) {
            Image img = read_image(path, r == "map_Kd" ? ImageValues::kColour : ImageValues::kData);
            // A map_Bump image is a height map (grey) or a normal map, checked for what it is.
            t.height = r == "map_Bump" && grey(img.pixels.data(), img.pixels.size());
            const char* check = r == "map_Bump" && !t.height ? "norm" : role;
            if (const std::string p = texel_problem(img, check); !p.empty()) throw Error(what + " " + p);
            if (t.height) {  // rendering reads the heights' slopes (renderer/core/normal_map.h)
                std::vector<Vec3> slopes(img.pixels.size());
                height_slopes(img.pixels.data(), img.width, img.height, slopes.data());
                img.pixels = std::move(slopes);
            }
            BVHLAB_CHECK(texels_.size() + img.pixels.size() < (size_t(1) << 32),
                         "the textures hold 2^32 texels or more");
            t.index = int32_t(textures_.size());
            textures_.push_back({uint32_t(texels_.size()), img.width, img.height, 0});
            texels_.insert(texels_.end(), img.pixels.begin(), img.pixels.end());
        } else if (problem != scene::kDoesNotExist) {  // a folder or a device: an error either way
            throw Error(what + ": " + problem);
        } else if (!opts.warn_missing) {
            throw Error(what + " does not exist (--missing-textures warn renders without it)");
        } else if (opts.warnings) {
            opts.warnings->push_back("texture " + path + " does not exist: material '" + m.name +
                                     "' renders without its " + r);
        }
        it = loaded.emplace(key, t).first;
    }
    return it->second;
}

void RenderScene::load_textures(const TextureOptions& opts) {
    std::map<std::string, LoadedTexture> loaded;  // role and resolved path -> texture (index -1: missing)
    bool maps = false;
    for (size_t i = 0; i < mesh_.materials.size(); ++i) {
        const scene::Material& m = mesh_.materials[i];
        RenderMaterial& r = materials_[i + 1];
        if (!m.diffuse_texture.empty()) r.texture = load_texture(opts, m, m.diffuse_texture, "map_Kd", loaded).index;
        // norm before map_Bump: one map per material.
        const bool norm = !m.normal_texture.empty();
        if (!norm && m.bump_texture.empty()) continue;
        const LoadedTexture t =
            load_texture(opts, m, norm ? m.normal_texture : m.bump_texture, norm ? "norm" : "map_Bump", loaded);
        if (t.index < 0) continue;
        r.normal_map = t.index;
        r.normal_kind = t.height ? NormalMapKind::kHeight : NormalMapKind::kTangentSpace;
        r.bump_scale = m.bump_multiplier;
        maps = true;
    }
    if (textures_.empty()) return;
    if (mesh_.texcoords.size() == 6 * mesh_.triangle_count())
        textured_ = true;
    else if (opts.warnings)
        opts.warnings->push_back(
            std::string("the scene has ") + (maps ? "textures or normal maps" : "map_Kd textures") +
            " but no texture coordinates (vt): they render with Kd" + (maps ? " and without normal maps" : ""));
}

RenderScene::RenderScene(const scene::TriangleMesh& mesh, const SkyOption& sky, const TextureOptions& textures)
    : mesh_(mesh) {
    BVHLAB_CHECK(mesh.triangle_count() > 0, "cannot render a scene with no triangles");
    BVHLAB_CHECK(mesh.normals.empty() || mesh.normals.size() == 3 * mesh.triangle_count(),
                 "a mesh's shading normals must be 3 per triangle, or none");
    materials_.push_back(default_material());
    for (const scene::Material& m : mesh.materials) {
        if (const std::string p = scene::material_problem(m); !p.empty())
            throw Error("material '" + m.name + "': " + p);
        materials_.push_back(map_material(m, -1));
    }
    material_ids_ = mesh.material_ids;
    if (material_ids_.size() != mesh.triangle_count()) material_ids_.assign(mesh.triangle_count(), -1);
    load_textures(textures);
    std::vector<double> power;
    pick_pdf_.assign(mesh.triangle_count(), 0.0f);
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const RenderMaterial& m = materials_[size_t(material_ids_[t] + 1)];
        if (max3(m.emission) <= 0.0f) continue;
        const Vec3 a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
        const double area = 0.5 * double(length(cross(b - a, c - a)));
        if (!(area > 0.0)) continue;
        light_tris_.push_back(uint32_t(t));
        power.push_back(area * double(luminance(m.emission)));
    }
    if (!light_tris_.empty()) {
        alias_ = build_alias_table(power);
        const double total = std::accumulate(power.begin(), power.end(), 0.0);
        for (size_t i = 0; i < light_tris_.size(); ++i) pick_pdf_[light_tris_[i]] = float(power[i] / total);
    }
    const size_t n = light_tris_.size();
    if (!sky.env_file.empty()) {
        BVHLAB_CHECK(std::isfinite(sky.env_scale) && sky.env_scale >= 0.0f, "--env-scale must be a finite number >= 0");
        env_ = read_image(sky.env_file);
        for (Vec3& p : env_.pixels) {
            if (!std::isfinite(p.x + p.y + p.z) || p.x < 0.0f || p.y < 0.0f || p.z < 0.0f)
                throw Error("environment map " + sky.env_file + " has a negative, NaN or infinite pixel");
            p = p * sky.env_scale;
            if (!(std::max(p.x, std::max(p.y, p.z)) <= scene::kMaxRadiance)) {
                char b[128];
                std::snprintf(b, sizeof b, " times --env-scale %g has a texel of radiance %g, above %g",
                              double(sky.env_scale), double(std::max(p.x, std::max(p.y, p.z))),
                              double(scene::kMaxRadiance));
                throw Error("environment map " + sky.env_file + b + ", the numeric domain bvhlab supports");
            }
        }
        build_env_tables();
        lighting_ = std::to_string(n) + " emissive triangles, environment map " + sky.env_file + " (" +
                    std::to_string(env_.width) + "x" + std::to_string(env_.height) + ", scale " +
                    std::to_string(sky.env_scale) + ")";
        if (env_row_cdf_.empty()) {  // black everywhere: nothing to sample
            env_ = Image();
            lighting_ += ", black";
        }
    } else if (sky.given) {
        sky_ = sky.radiance;
        lighting_ = std::to_string(n) + " emissive triangles, sky (" + std::to_string(sky_.x) + ", " +
                    std::to_string(sky_.y) + ", " + std::to_string(sky_.z) + ") as given";
    } else if (n == 0) {
        sky_ = splat(1.0f);
        lighting_ = "no emitters and no sky given: lit by a white sky of radiance 1";
    } else {
        lighting_ = std::to_string(n) + " emissive triangles, black sky (none given)";
    }
    const bool sky_on = max3(sky_) > 0.0f || env_.width > 0;
    sky_pick_ = !sky_on ? 0.0f : (n == 0 ? 1.0f : 0.5f);
    offset_ = 1e-5f * std::max(mesh.diagonal(), 1e-6f);
}

void RenderScene::build_env_tables() {
    const uint32_t w = env_.width, h = env_.height;
    std::vector<double> row(h, 0.0), weight(size_t(w) * h);
    for (uint32_t y = 0; y < h; ++y) {
        const double st = std::sin(kPi * (double(y) + 0.5) / double(h));
        for (uint32_t x = 0; x < w; ++x) {
            const double v = double(luminance(env_.at(x, y))) * st;
            weight[size_t(y) * w + x] = v;
            row[y] += v;
        }
    }
    const double total = std::accumulate(row.begin(), row.end(), 0.0);
    if (!(total > 0.0)) return;
    env_row_cdf_.assign(h + 1, 0.0f);
    env_row_pdf_.assign(h, 0.0f);
    env_col_cdf_.assign(size_t(h) * (w + 1), 0.0f);
    env_col_pdf_.assign(size_t(h) * w, 0.0f);
    double acc = 0.0;
    for (uint32_t y = 0; y < h; ++y) {
        acc += row[y];
        env_row_cdf_[y + 1] = float(acc / total);
        env_row_pdf_[y] = float(row[y] / total * h);
        float* cdf = &env_col_cdf_[size_t(y) * (w + 1)];
        double c = 0.0;
        for (uint32_t x = 0; x < w; ++x) {
            // A row without light is never picked; it gets a uniform table all the same.
            const double p = row[y] > 0.0 ? weight[size_t(y) * w + x] / row[y] : 1.0 / w;
            c += p;
            cdf[x + 1] = float(c);
            env_col_pdf_[size_t(y) * w + x] = float(p * w);
        }
        cdf[w] = 1.0f;
    }
    env_row_cdf_[h] = 1.0f;
}

SceneView RenderScene::view() const {
    SceneView v;
    v.vertices = mesh_.vertices.data();
    v.indices = mesh_.indices.data();
    v.material_ids = material_ids_.data();
    v.normals = mesh_.normals.empty() ? nullptr : mesh_.normals.data();
    v.materials = materials_.data();
    v.lights.tris = light_tris_.data();
    v.lights.table = alias_.data();
    v.lights.pick_pdf = pick_pdf_.data();
    v.lights.count = uint32_t(light_tris_.size());
    v.lights.sky = sky_;
    v.lights.sky_pick = sky_pick_;
    if (env_.width > 0) {
        v.lights.env = {env_.pixels.data(),  env_row_cdf_.data(), env_col_cdf_.data(), env_row_pdf_.data(),
                        env_col_pdf_.data(), env_.width,          env_.height};
    }
    v.textures = {texels_.data(), textures_.data(), textured_ ? mesh_.texcoords.data() : nullptr};
    v.offset = offset_;
    return v;
}

CameraData make_camera(const trav::Camera& cam, uint32_t width, uint32_t height, const LensOptions& lens) {
    BVHLAB_CHECK(width > 0 && height > 0, "the image size must be at least 1 x 1");
    const Vec3 eye{cam.eye.x, cam.eye.y, cam.eye.z}, target{cam.target.x, cam.target.y, cam.target.z},
        up{cam.up.x, cam.up.y, cam.up.z};
    const Vec3 view = target - eye;
    const float dist = length(view);
    const Vec3 right_raw = cross(view, up);
    BVHLAB_CHECK(dist > 0.0f && std::isfinite(dist) && length(right_raw) > 0.0f,
                 "degenerate camera: eye and target coincide or up is parallel to the view");
    const bool wide = cam.projection != trav::Projection::kPerspective;
    BVHLAB_CHECK(wide || (cam.fov_y_deg > 0.0f && cam.fov_y_deg < 180.0f),
                 "the field of view must be in (0, 180) degrees");
    BVHLAB_CHECK(
        cam.projection != trav::Projection::kFisheye || (cam.fisheye_fov_deg > 0.0f && cam.fisheye_fov_deg <= 360.0f),
        "the fish-eye's field of view must be in (0, 360] degrees");
    BVHLAB_CHECK(!wide || (lens.aperture_radius == 0.0f && lens.focus_distance == 0.0f),
                 "a fish-eye or panorama camera has no lens: no aperture or focus distance");
    BVHLAB_CHECK(lens.aperture_radius >= 0.0f && lens.focus_distance >= 0.0f,
                 "aperture and focus distance must not be negative");
    BVHLAB_CHECK(lens.shutter_open >= 0.0f && lens.shutter_open <= lens.shutter_close && lens.shutter_close <= 1.0f,
                 "the shutter interval must satisfy 0 <= open <= close <= 1");
    CameraData c;
    c.back = normalize(view * -1.0f);
    c.right = normalize(right_raw);
    c.up = cross(c.back, c.right);
    c.eye0 = eye;
    c.eye1 = lens.moving ? lens.eye_end : eye;
    c.tan_half_fov_y = std::tan(0.5f * cam.fov_y_deg * kPi / 180.0f);
    c.aspect = float(width) / float(height);
    c.lens_radius = lens.aperture_radius;
    c.focus_distance = lens.focus_distance > 0.0f ? lens.focus_distance : dist;
    c.shutter_open = lens.shutter_open;
    c.shutter_close = lens.shutter_close;
    c.width = width;
    c.height = height;
    c.pixel_centres = lens.pixel_centres ? 1u : 0u;
    c.projection = cam.projection;
    c.half_fov = 0.5f * cam.fisheye_fov_deg * kPi / 180.0f;
    return c;
}

}  // namespace bvhlab::render
