// SPDX-License-Identifier: MIT
// Float RGB images and their files: PFM always (our own writer and reader, for builds without
// OpenImageIO), EXR, PNG and the rest through OpenImageIO, chosen by the file's extension.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/vec3.h"

namespace bvhlab::render {

struct Image {
    uint32_t width = 0, height = 0;
    std::vector<Vec3> pixels;  ///< row-major, top row first

    Image() = default;
    Image(uint32_t w, uint32_t h) : width(w), height(h), pixels(size_t(w) * h, Vec3{0.0f, 0.0f, 0.0f}) {}
    Vec3& at(uint32_t x, uint32_t y) { return pixels[size_t(y) * width + x]; }
    const Vec3& at(uint32_t x, uint32_t y) const { return pixels[size_t(y) * width + x]; }
};

/// True when this build can write `path`'s format (PFM always; others need OpenImageIO).
bool can_write_image(const std::string& path, std::string* why = nullptr);

/// Writes `img` atomically. .pfm: linear float; .exr/.hdr: linear float through OpenImageIO;
/// .png/.jpg/.tif and the rest: clamped, sRGB-encoded 8 bits through OpenImageIO. Throws
/// bvhlab::Error naming the file for an unknown extension, a build without OpenImageIO or an
/// I/O failure.
void write_image(const Image& img, const std::string& path);

/// Writes every image or none: each goes to a temporary first, and only when all are written
/// are they renamed to their names (a full disk on the third leaves none of them, and no
/// temporary).
void write_images(const std::vector<std::pair<const Image*, std::string>>& images);

/// Reads a PFM file (colour "PF" or grey "Pf", either byte order). Throws bvhlab::Error.
Image read_pfm(const std::string& path);

/// What an image's values are: colours (8-bit and other sRGB-tagged files are linearised) or
/// data such as normal and height maps (values as stored, scaled to [0, 1] for integer formats).
enum class ImageValues { kColour, kData };

/// Reads an image as RGB: PFM always, anything else through OpenImageIO (colours linearised as
/// `values` says; one channel is grey; alpha is dropped). Throws bvhlab::Error naming the file
/// when it is missing, unreadable, or needs OpenImageIO that this build lacks.
Image read_image(const std::string& path, ImageValues values = ImageValues::kColour);

/// Linear to sRGB-encoded, for 8-bit output.
float srgb_encode(float linear);

/// The image as 8-bit sRGB, RGB interleaved, rows top first (what PNG output holds).
std::vector<uint8_t> srgb_bytes(const Image& img);

}  // namespace bvhlab::render
