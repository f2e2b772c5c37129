// SPDX-License-Identifier: MIT
// The host side of a render: the mesh's materials mapped to BSDFs, the light table, the sky
// rule and the camera, in the flat arrays both integrators read.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "renderer/core/stages.h"
#include "renderer/core/texture.h"
#include "renderer/image.h"
#include "scene/mesh.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::render {

/// The sky, as the user asked for it.
struct SkyOption {
    bool given = false;  ///< false: the default rule (white 1 without emitters, black with)
    Vec3 radiance{0.0f, 0.0f, 0.0f};
    std::string env_file;  ///< a lat-long environment map instead (read_image); "" for none
    float env_scale = 1.0f;
};

/// How map_Kd textures are found.
struct TextureOptions {
    std::string base_dir;                          ///< the folder relative texture paths start from (the OBJ's)
    bool warn_missing = false;                     ///< a missing file: a warning and the material's Kd, not an error
    std::vector<std::string>* warnings = nullptr;  ///< one line per missing file, when warn_missing
};

/// A texture path as an MTL file writes it, as a path on this machine: backslashes (Windows
/// exports) become slashes, and a relative path starts at base_dir.
std::string resolve_texture_path(const std::string& base_dir, const std::string& name);

class RenderScene {
public:
    /// Maps the materials, loads their map_Kd textures and their normal or height maps (norm,
    /// else map_Bump: a grey image is a height map, any other a tangent-space normal map) through
    /// read_image, each file once, and builds the light table. Throws bvhlab::Error for an empty
    /// mesh, a texture that cannot be read or has a non-finite texel (a negative one in a colour
    /// texture, one outside [0, 1] in a normal map), and a missing one unless warn_missing.
    RenderScene(const scene::TriangleMesh& mesh, const SkyOption& sky, const TextureOptions& textures = {});

    /// Views into this object's arrays (host memory); valid while it lives.
    SceneView view() const;

    const scene::TriangleMesh& mesh() const { return mesh_; }
    const std::vector<RenderMaterial>& materials() const { return materials_; }
    const std::vector<uint32_t>& light_tris() const { return light_tris_; }
    const std::vector<AliasEntry>& alias_table() const { return alias_; }
    const std::vector<float>& pick_pdf() const { return pick_pdf_; }
    const std::vector<int32_t>& material_ids() const { return material_ids_; }
    const std::vector<Vec3>& texels() const { return texels_; }
    const std::vector<TextureInfo>& textures() const { return textures_; }
    /// The mesh's texture coordinates when some material has a texture, else empty.
    const std::vector<float>& texcoords() const { return textured_ ? mesh_.texcoords : no_texcoords_; }
    Vec3 sky() const { return sky_; }
    float sky_pick() const { return sky_pick_; }
    float offset() const { return offset_; }
    /// The environment map (empty image when none) and its sampling tables.
    const Image& env() const { return env_; }
    const std::vector<float>& env_row_cdf() const { return env_row_cdf_; }
    const std::vector<float>& env_col_cdf() const { return env_col_cdf_; }
    const std::vector<float>& env_row_pdf() const { return env_row_pdf_; }
    const std::vector<float>& env_col_pdf() const { return env_col_pdf_; }
    /// One line on how the scene is lit, for the summary ("12 emissive triangles, black sky").
    const std::string& lighting() const { return lighting_; }

private:
    void build_env_tables();
    void load_textures(const TextureOptions& opts);
    struct LoadedTexture {
        int32_t index;  ///< -1 for a missing file that the options allow
        bool height;    ///< a map_Bump height map, stored as its slopes (height_slopes)
    };
    /// The texture `name` as material m writes it for `role` ("map_Kd", "norm" or "map_Bump"),
    /// loading it unless `loaded` has it.
    LoadedTexture load_texture(const TextureOptions& opts, const scene::Material& m, const std::string& name,
                               const char* role, std::map<std::string, LoadedTexture>& loaded);

    const scene::TriangleMesh& mesh_;
    std::vector<RenderMaterial> materials_;  // [0] default
    std::vector<int32_t> material_ids_;
    std::vector<Vec3> texels_;
    std::vector<TextureInfo> textures_;
    bool textured_ = false;  // some material has a texture and the mesh has texture coordinates
    std::vector<float> no_texcoords_;
    std::vector<uint32_t> light_tris_;
    std::vector<AliasEntry> alias_;
    std::vector<float> pick_pdf_;
    Vec3 sky_{0.0f, 0.0f, 0.0f};
    float sky_pick_ = 0.0f;
    float offset_ = 0.0f;
    std::string lighting_;
    Image env_;
    std::vector<float> env_row_cdf_, env_col_cdf_, env_row_pdf_, env_col_pdf_;
};

/// Vose's alias table for non-negative `weights` with a positive sum.
std::vector<AliasEntry> build_alias_table(const std::vector<double>& weights);

/// Camera settings beyond the pinhole of the ray protocol.
struct LensOptions {
    float aperture_radius = 0.0f;  ///< 0: pinhole
    float focus_distance = 0.0f;   ///< 0: the distance from the eye to the target
    Vec3 eye_end{0.0f, 0.0f, 0.0f};
    bool moving = false;  ///< eye_end is where the eye is at shutter time 1
    float shutter_open = 0.0f, shutter_close = 1.0f;
    bool pixel_centres = false;  ///< no sub-pixel jitter (what the first-hit cache needs)
};

/// CameraData for `cam` (the catalogue's or the framing camera) and an image size. Throws
/// bvhlab::Error for a degenerate camera or a zero size.
CameraData make_camera(const trav::Camera& cam, uint32_t width, uint32_t height, const LensOptions& lens);

}  // namespace bvhlab::render
