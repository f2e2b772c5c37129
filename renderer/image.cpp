// SPDX-License-Identifier: MIT
#include "renderer/image.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "accel/core/check.h"
#include "scene/io/atomic_file.h"

#if defined(BVHLAB_HAVE_OIIO)
#include <OpenImageIO/imageio.h>
#endif

namespace bvhlab::render {
namespace fs = std::filesystem;
namespace {

std::string extension_of(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

scene::TemporaryFile write_pfm(const Image& img, const std::string& path) {
    return scene::write_temporary(path, [&](std::FILE* f) {
        // Negative scale: little-endian. PFM stores the bottom row first.
        std::fprintf(f, "PF\n%u %u\n-1.0\n", img.width, img.height);
        for (uint32_t y = img.height; y-- > 0;)
            std::fwrite(&img.pixels[size_t(y) * img.width], sizeof(Vec3), img.width, f);
    });
}

#if defined(BVHLAB_HAVE_OIIO)
bool is_float_format(const std::string& ext) { return ext == ".exr" || ext == ".hdr"; }

/// OpenImageIO's error text as one line about `path`: its first line, with the temporary's
/// name replaced by the user's.
std::string oiio_reason(std::string why, const std::string& tmp, const std::string& path) {
    why = why.substr(0, why.find('\n'));
    for (size_t at; (at = why.find(tmp)) != std::string::npos;) why.replace(at, tmp.size(), path);
    return why.empty() ? "OpenImageIO failed" : why;
}

scene::TemporaryFile write_oiio(const Image& img, const std::string& path, const std::string& ext) {
    // OpenImageIO picks the format by the name, so the temporary keeps the extension.
    const fs::path final_path(scene::output_target(path));
    const fs::path tmp =
        final_path.parent_path() / ("." + final_path.stem().string() + ".tmp" + std::to_string(getpid()) + ext);
    auto out = OIIO::ImageOutput::create(tmp.string());
    if (!out) throw Error("cannot write " + path + ": OpenImageIO has no writer for '" + ext + "'");
    const bool fl = is_float_format(ext);
    OIIO::ImageSpec spec(int(img.width), int(img.height), 3, fl ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    std::vector<uint8_t> bytes;
    const void* data = img.pixels.data();
    if (!fl) {
        bytes = srgb_bytes(img);
        data = bytes.data();
    }
    const bool ok = out->open(tmp.string(), spec) &&
                    out->write_image(fl ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8, data) && out->close();
    if (!ok) {
        const std::string why = oiio_reason(out->geterror(), tmp.string(), path);
        std::error_code ec;
        fs::remove(tmp, ec);
        throw Error("cannot write " + path + ": " + why);
    }
    return {tmp.string(), final_path.string(), path};
}
#endif

}  // namespace

std::vector<uint8_t> srgb_bytes(const Image& img) {
    std::vector<uint8_t> bytes(img.pixels.size() * 3);
    for (size_t i = 0; i < img.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            bytes[3 * i + size_t(c)] = uint8_t(std::lround(255.0f * srgb_encode(img.pixels[i][c])));
    return bytes;
}

float srgb_encode(float x) {
    if (!(x > 0.0f)) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

bool can_write_image(const std::string& path, std::string* why) {
    const std::string ext = extension_of(path);
    if (ext == ".pfm") return true;
#if defined(BVHLAB_HAVE_OIIO)
    if (OIIO::is_imageio_format_name(ext.size() > 1 ? ext.substr(1) : ext) || ext == ".png" || ext == ".exr" ||
        ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff" || ext == ".hdr")
        return true;
    if (why) *why = "unknown image extension '" + ext + "' (use .exr, .png or .pfm)";
    return false;
#else
    if (why)
        *why = ext.empty() ? "the file name has no extension (use .pfm)"
                           : "this build has no OpenImageIO, so it writes .pfm only (asked for '" + ext + "')";
    return false;
#endif
}

namespace {

scene::TemporaryFile write_image_temporary(const Image& img, const std::string& path) {
    std::string why;
    if (!can_write_image(path, &why)) throw Error("cannot write " + path + ": " + why);
#if defined(BVHLAB_HAVE_OIIO)
    if (const std::string ext = extension_of(path); ext != ".pfm") return write_oiio(img, path, ext);
#endif
    return write_pfm(img, path);
}

}  // namespace

void write_images(const std::vector<std::pair<const Image*, std::string>>& images) {
    std::vector<scene::TemporaryFile> written;
    try {
        for (const auto& [img, path] : images) written.push_back(write_image_temporary(*img, path));
    } catch (...) {
        scene::discard_temporaries(written);
        throw;
    }
    scene::commit_temporaries(written);
}

void write_image(const Image& img, const std::string& path) {
    scene::commit_temporaries({write_image_temporary(img, path)});
}

namespace {

/// Sends this thread's and the libraries' writes to stderr to /dev/null while it lives.
class QuietStderr {
public:
    QuietStderr() {
        std::fflush(stderr);
        saved_ = ::dup(2);
        const int null = ::open("/dev/null", O_WRONLY);
        if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
        if (null >= 0) ::close(null);
    }
    ~QuietStderr() {
        std::fflush(stderr);
        if (saved_ >= 0) {
            ::dup2(saved_, 2);
            ::close(saved_);
        }
    }
    QuietStderr(const QuietStderr&) = delete;
    QuietStderr& operator=(const QuietStderr&) = delete;

private:
    int saved_ = -1;
};

}  // namespace

Image read_image(const std::string& path, ImageValues values) {
    if (const std::string problem = scene::regular_file_problem(path); !problem.empty())
        throw Error("cannot read " + path + ": " + (problem == scene::kDoesNotExist ? "no such file" : problem));
    if (extension_of(path) == ".pfm") return read_pfm(path);
#if defined(BVHLAB_HAVE_OIIO)
    // libpng and OpenImageIO print their own copies of a read error (libpng straight to stderr,
    // OpenImageIO when the reader is destroyed): the error is reported once, below.
    const QuietStderr quiet;
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        const std::string why = OIIO::geterror();
        throw Error("cannot read " + path + ": " + why.substr(0, why.find('\n')));
    }
    const OIIO::ImageSpec& spec = in->spec();
    const int ch = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || ch <= 0) throw Error("cannot read " + path + ": an empty image");
    std::vector<float> px(size_t(spec.width) * size_t(spec.height) * size_t(ch));
    if (!in->read_image(0, 0, 0, ch, OIIO::TypeDesc::FLOAT, px.data())) {
        // The reader's errors, one per line (the PNG reader adds its own copies); the first says
        // what went wrong.
        const std::string why = in->geterror();
        throw Error("cannot read " + path + ": " + why.substr(0, why.find('\n')));
    }
    const std::string space = spec.get_string_attribute("oiio:ColorSpace");
    const bool srgb = values == ImageValues::kColour &&
                      (space == "sRGB" || (space.empty() && spec.format.basetype == OIIO::TypeDesc::UINT8));
    auto linear = [srgb](float c) {
        if (!srgb) return c;
        return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    };
    Image img{uint32_t(spec.width), uint32_t(spec.height)};
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        const float* p = &px[i * size_t(ch)];
        img.pixels[i] =
            ch >= 3 ? Vec3{linear(p[0]), linear(p[1]), linear(p[2])} : Vec3{linear(p[0]), linear(p[0]), linear(p[0])};
    }
    return img;
#else
    (void)values;
    throw Error("cannot read " + path + ": this build has no OpenImageIO, so it reads .pfm images only");
#endif
}

Image read_pfm(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open " + path + ": " + std::strerror(errno));
    std::string magic;
    long long w = 0, h = 0;
    double scale = 0.0;
    in >> magic >> w >> h >> scale;
    if (!in || (magic != "PF" && magic != "Pf") || w <= 0 || h <= 0 || w > 65536 || h > 65536 || scale == 0.0)
        throw Error(path + " is not a PFM file (bad header)");
    in.get();  // the single whitespace after the scale
    const int channels = magic == "PF" ? 3 : 1;
    // The header's size against the file's, before anything is allocated (a 20-byte file can
    // claim 65536 x 65536 pixels, 51.5 GB).
    const auto header = std::streamoff(in.tellg());
    in.seekg(0, std::ios::end);
    const auto bytes = uint64_t(std::streamoff(in.tellg()) - header);
    in.seekg(header);
    const uint64_t need = uint64_t(w) * uint64_t(h) * uint64_t(channels) * sizeof(float);
    if (!in || bytes < need)
        throw Error(path + " is truncated: its header says " + std::to_string(w) + " x " + std::to_string(h) +
                    " pixels (" + std::to_string(need) + " bytes), the file holds " + std::to_string(bytes));
    std::vector<float> data(size_t(w) * size_t(h) * size_t(channels));
    in.read(reinterpret_cast<char*>(data.data()), std::streamsize(data.size() * sizeof(float)));
    if (size_t(in.gcount()) != data.size() * sizeof(float))
        throw Error(path + " is truncated: fewer pixels than its header says");
    if (scale > 0.0)  // big-endian data
        for (float& f : data) {
            uint32_t u;
            std::memcpy(&u, &f, 4);
            u = __builtin_bswap32(u);
            std::memcpy(&f, &u, 4);
        }
    Image img{uint32_t(w), uint32_t(h)};
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x) {
            const float* p = &data[(size_t(img.height - 1 - y) * img.width + x) * size_t(channels)];
            img.at(x, y) = channels == 3 ? Vec3{p[0], p[1], p[2]} : Vec3{p[0], p[0], p[0]};
        }
    return img;
}

}  // namespace bvhlab::render
