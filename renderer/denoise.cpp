// SPDX-License-Identifier: MIT
#include "renderer/denoise.h"

#include <dlfcn.h>
#include <glob.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "accel/core/check.h"

namespace bvhlab::render {

namespace fs = std::filesystem;

namespace {

constexpr const char* kLibrary = "libOpenImageDenoise.so.2";
constexpr const char* kInstall =
    "pip install pyoidn (its wheel ships the library), or set BVHLAB_OIDN to libOpenImageDenoise.so.2 or its folder";

// The part of OIDN 2's C API that denoising uses (OpenImageDenoise/oidn.h), as dlsym finds it.
enum { kDeviceCpu = 1, kDeviceCuda = 3, kFormatFloat3 = 3 };
using Handle = void*;
struct Oidn {
    void* lib = nullptr;
    Handle (*new_device)(int) = nullptr;
    void (*commit_device)(Handle) = nullptr;
    void (*release_device)(Handle) = nullptr;
    int (*device_error)(Handle, const char**) = nullptr;
    bool (*cuda_supported)(int) = nullptr;  // absent before OIDN 2.1: then CUDA is tried and may fail
    Handle (*new_buffer)(Handle, size_t) = nullptr;
    void (*write_buffer)(Handle, size_t, size_t, const void*) = nullptr;
    void (*read_buffer)(Handle, size_t, size_t, void*) = nullptr;
    void (*release_buffer)(Handle) = nullptr;
    Handle (*new_filter)(Handle, const char*) = nullptr;
    void (*set_image)(Handle, const char*, Handle, int, size_t, size_t, size_t, size_t, size_t) = nullptr;
    void (*set_bool)(Handle, const char*, bool) = nullptr;
    void (*commit_filter)(Handle) = nullptr;
    void (*execute_filter)(Handle) = nullptr;
    void (*release_filter)(Handle) = nullptr;
};

template <typename F>
void bind(Oidn& api, F& fn, const char* name, bool required = true) {
    fn = reinterpret_cast<F>(dlsym(api.lib, name));
    if (!fn && required)
        throw Error(std::string("the OIDN library lacks ") + name + " (bvhlab needs Open Image Denoise 2.x)");
}

Oidn load(const std::string& path) {
    Oidn api;
    api.lib = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!api.lib) throw Error("cannot load Open Image Denoise from " + path + ": " + dlerror());
    bind(api, api.new_device, "oidnNewDevice");
    bind(api, api.commit_device, "oidnCommitDevice");
    bind(api, api.release_device, "oidnReleaseDevice");
    bind(api, api.device_error, "oidnGetDeviceError");
    bind(api, api.cuda_supported, "oidnIsCUDADeviceSupported", false);
    bind(api, api.new_buffer, "oidnNewBuffer");
    bind(api, api.write_buffer, "oidnWriteBuffer");
    bind(api, api.read_buffer, "oidnReadBuffer");
    bind(api, api.release_buffer, "oidnReleaseBuffer");
    bind(api, api.new_filter, "oidnNewFilter");
    bind(api, api.set_image, "oidnSetFilterImage");
    bind(api, api.set_bool, "oidnSetFilterBool");
    bind(api, api.commit_filter, "oidnCommitFilter");
    bind(api, api.execute_filter, "oidnExecuteFilter");
    bind(api, api.release_filter, "oidnReleaseFilter");
    return api;
}

/// The device's pending error as text, or "" (and clears it).
std::string device_error(const Oidn& api, Handle device) {
    const char* message = nullptr;
    const int code = api.device_error(device, &message);
    if (code == 0) return "";
    return message && *message ? message : "error code " + std::to_string(code);
}

std::string library_in(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        for (const char* name : {kLibrary, "libOpenImageDenoise.so"})
            if (fs::exists(fs::path(path) / name, ec)) return (fs::path(path) / name).string();
        return "";
    }
    return fs::exists(path, ec) ? path : "";
}

}  // namespace

std::string find_oidn(const DenoiseOptions& opts, std::string* why) {
    const auto fail = [&](const std::string& reason) {
        if (why) *why = reason;
        return std::string();
    };
    if (!opts.library.empty()) {
        const std::string lib = library_in(opts.library);
        return lib.empty() ? fail("--oidn '" + opts.library + "' holds no " + kLibrary) : lib;
    }
    if (const char* env = std::getenv("BVHLAB_OIDN"); env && *env) {
        const std::string lib = library_in(env);
        return lib.empty() ? fail(std::string("BVHLAB_OIDN='") + env + "' holds no " + kLibrary) : lib;
    }
    // The pyoidn wheel: a virtual environment, the user's site-packages, the system's.
    std::vector<std::string> patterns;
    if (const char* venv = std::getenv("VIRTUAL_ENV"); venv && *venv)
        patterns.push_back(std::string(venv) + "/lib/python3*/site-packages/pyoidn/oidn/lib/" + kLibrary);
    if (const char* home = std::getenv("HOME"); home && *home)
        patterns.push_back(std::string(home) + "/.local/lib/python3*/site-packages/pyoidn/oidn/lib/" + kLibrary);
    for (const char* prefix : {"/usr/local/lib/python3*/dist-packages", "/usr/local/lib/python3*/site-packages",
                               "/usr/lib/python3/dist-packages"})
        patterns.push_back(std::string(prefix) + "/pyoidn/oidn/lib/" + kLibrary);
    for (const std::string& pattern : patterns) {
        glob_t g{};
        if (glob(pattern.c_str(), 0, nullptr, &g) == 0 && g.gl_pathc > 0) {
            const std::string found = g.gl_pathv[g.gl_pathc - 1];
            globfree(&g);
            return found;
        }
        globfree(&g);
    }
    // The system's (or LD_LIBRARY_PATH's) copy.
    if (void* h = dlopen(kLibrary, RTLD_NOW | RTLD_LOCAL)) {
        dlclose(h);
        return kLibrary;
    }
    return fail(std::string("Intel Open Image Denoise was not found: ") + kInstall);
}

DenoiseResult denoise(const Image& beauty, const Image& albedo, const Image& normal, const DenoiseOptions& opts) {
    BVHLAB_CHECK(beauty.width > 0 && beauty.height > 0, "an empty image cannot be denoised");
    BVHLAB_CHECK(albedo.width == beauty.width && albedo.height == beauty.height && normal.width == beauty.width &&
                     normal.height == beauty.height,
                 "the albedo and normal images must have the beauty image's size");
    if (opts.device != "auto" && opts.device != "cpu" && opts.device != "cuda")
        throw Error("denoise device '" + opts.device + "' is not auto, cpu or cuda");
    std::string why;
    const std::string path = find_oidn(opts, &why);
    if (path.empty()) throw Error(why);
    const Oidn api = load(path);

    DenoiseResult out;
    out.library = path;
    Handle device = nullptr;
    if (opts.device != "cpu" && (!api.cuda_supported || api.cuda_supported(0))) {
        device = api.new_device(kDeviceCuda);
        if (device) api.commit_device(device);
        if (device && !device_error(api, device).empty()) {
            api.release_device(device);
            device = nullptr;
        }
        if (!device && opts.device == "cuda") throw Error("OIDN's CUDA device is not available here");
        if (device) out.device = "cuda";
    } else if (opts.device == "cuda") {
        throw Error("OIDN's CUDA device is not available here");
    }
    if (!device) {
        device = api.new_device(kDeviceCpu);
        if (!device) throw Error("OIDN could not make a CPU device");
        api.commit_device(device);
        if (const std::string e = device_error(api, device); !e.empty()) {
            api.release_device(device);
            throw Error("OIDN's CPU device: " + e);
        }
        out.device = "cpu";
    }

    const size_t w = beauty.width, h = beauty.height, bytes = w * h * sizeof(Vec3);
    static_assert(sizeof(Vec3) == 12, "an image is packed float3");
    std::vector<Handle> buffers, filters;
    const auto cleanup = [&] {
        for (Handle f : filters) api.release_filter(f);
        for (Handle b : buffers) api.release_buffer(b);
        api.release_device(device);
    };
    try {
        const auto buffer = [&](const Image* from) {
            Handle b = api.new_buffer(device, bytes);
            if (!b)
                throw Error("OIDN could not allocate " + std::to_string(bytes) +
                            " bytes: " + device_error(api, device));
            buffers.push_back(b);
            if (from) api.write_buffer(b, 0, bytes, from->pixels.data());
            return b;
        };
        Handle color = buffer(&beauty), alb = buffer(&albedo), nrm = buffer(&normal), result = buffer(nullptr);
        const auto filter = [&](std::initializer_list<std::pair<const char*, Handle>> images, bool hdr,
                                bool clean_aux) {
            Handle f = api.new_filter(device, "RT");
            if (!f) throw Error("OIDN has no RT filter: " + device_error(api, device));
            filters.push_back(f);
            for (const auto& [name, b] : images) api.set_image(f, name, b, kFormatFloat3, w, h, 0, 0, 0);
            if (hdr) api.set_bool(f, "hdr", true);
            if (clean_aux) api.set_bool(f, "cleanAux", true);
            api.commit_filter(f);
            return f;
        };
        // The auxiliary images are prefiltered in place, then the beauty filter trusts them.
        Handle fa = filter({{"albedo", alb}, {"output", alb}}, false, false);
        Handle fn = filter({{"normal", nrm}, {"output", nrm}}, false, false);
        Handle fb = filter({{"color", color}, {"albedo", alb}, {"normal", nrm}, {"output", result}}, true, true);
        if (const std::string e = device_error(api, device); !e.empty()) throw Error("OIDN: " + e);
        const auto t0 = std::chrono::steady_clock::now();
        for (Handle f : {fa, fn, fb}) api.execute_filter(f);
        out.image = Image(beauty.width, beauty.height);
        api.read_buffer(result, 0, bytes, out.image.pixels.data());
        out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (const std::string e = device_error(api, device); !e.empty()) throw Error("OIDN: " + e);
    } catch (...) {
        cleanup();
        throw;
    }
    cleanup();
    return out;
}

}  // namespace bvhlab::render
