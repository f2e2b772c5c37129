// SPDX-License-Identifier: MIT
#include "renderer/preview_server.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "accel/core/check.h"

#if defined(BVHLAB_HAVE_SERVER)
#include <httplib.h>
#include <stb_image_write.h>

#include <nlohmann/json.hpp>
#endif

namespace bvhlab::render {

#if defined(BVHLAB_HAVE_SERVER)

namespace {

/// The page: it asks /status for the update after the one it has (the server answers when
/// there is one), then loads that image. Each image it shows is listed (hidden) in #updates with
/// its samples per pixel and a checksum of its pixels, which the page test reads.
constexpr const char* kPage = R"HTML(<!doctype html>
<html><head><meta charset="utf-8"><title>bvhlab: @TITLE@</title>
<style>
body { font-family: sans-serif; background: #1e1e1e; color: #ddd; margin: 1em; }
h1 { font-size: 1.1em; font-weight: normal; }
#status { margin: 0.5em 0; font-variant-numeric: tabular-nums; }
img { max-width: 100%; border: 1px solid #444; }
</style></head>
<body>
<h1 id="title">@TITLE@</h1>
<div id="status"><span id="state">waiting for the first image</span> &middot;
<span id="spp">0</span> of <span id="total">?</span> spp &middot;
<span id="rate">&ndash;</span> Mrays/s &middot; <span id="eta">&ndash;</span> left</div>
<img id="image" alt="the running mean of the render">
<ol id="updates" hidden></ol>
<script>
const $ = (id) => document.getElementById(id);
function checksum(img) {
  const c = document.createElement("canvas");
  c.width = img.naturalWidth; c.height = img.naturalHeight;
  const g = c.getContext("2d");
  g.drawImage(img, 0, 0);
  const d = g.getImageData(0, 0, c.width, c.height).data;
  let s = 0;
  for (let i = 0; i < d.length; i++) s = (Math.imul(s, 31) + d[i]) >>> 0;
  return s;
}
function load(src) {
  return new Promise((ok, fail) => {
    const im = $("image");
    im.onload = () => ok(im);
    im.onerror = fail;
    im.src = src;
  });
}
async function run() {
  let seen = 0;
  for (;;) {
    let s;
    try {
      const r = await fetch("/status?after=" + seen, {cache: "no-store"});
      s = await r.json();
    } catch (e) {
      $("state").textContent = "the render has ended";
      return;
    }
    $("spp").textContent = s.spp;
    $("total").textContent = s.total;
    $("rate").textContent = s.mrays_per_s.toFixed(1);
    $("eta").textContent = s.done ? "0 s" : (s.eta_s < 0 ? "\u2013" : s.eta_s.toFixed(1) + " s");
    if (s.version > seen) {
      seen = s.version;
      try {
        const im = await load("/image.png?v=" + s.version);
        const li = document.createElement("li");
        li.dataset.version = s.version;
        li.dataset.spp = s.image_spp;
        li.dataset.sum = checksum(im);
        li.textContent = s.image_spp + " spp";
        $("updates").appendChild(li);
      } catch (e) {}
    }
    $("state").textContent = s.done ? "done" : "rendering";
    if (s.done && s.version == seen) return;
  }
}
run();
</script>
</body></html>
)HTML";

std::string html_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string page(const std::string& title) {
    std::string p = kPage;
    const std::string t = html_escape(title);
    for (size_t at; (at = p.find("@TITLE@")) != std::string::npos;) p.replace(at, 7, t);
    return p;
}

/// The running mean as an 8-bit sRGB PNG (clamped, as write_image writes PNGs).
std::string encode_png(const Image& img) {
    const std::vector<uint8_t> bytes = srgb_bytes(img);
    std::string out;
    auto append = [](void* ctx, void* data, int size) {
        static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), size_t(size));
    };
    if (!stbi_write_png_to_func(append, &out, int(img.width), int(img.height), 3, bytes.data(), int(img.width) * 3))
        throw Error("cannot encode the preview as PNG");
    return out;
}

}  // namespace

struct PreviewServer::State {
    PreviewServerOptions opts;
    httplib::Server server;
    std::thread listener;
    int port = 0;

    mutable std::mutex mu;
    std::condition_variable cv;
    std::shared_ptr<const std::string> png;  // the newest image, shared with the responses sending it
    uint64_t version = 0;                    // images so far
    uint32_t image_spp = 0;                  // of the newest image
    uint32_t done = 0, total = 0;
    double mrays = 0.0, seconds = 0.0;
    bool finished = false, final_fetched = false, watched = false, stopping = false;
    std::atomic<uint64_t> requests{0};

    nlohmann::json status() const {  // under mu
        const double eta = done > 0 && total > done ? seconds / double(done) * double(total - done) : -1.0;
        return {{"version", version},
                {"image_spp", image_spp},
                {"spp", done},
                {"total", total},
                {"mrays_per_s", mrays},
                {"seconds", seconds},
                {"eta_s", finished ? 0.0 : eta},
                {"done", finished},
                {"title", opts.title}};
    }
};

bool preview_server_available() { return true; }

PreviewServer::PreviewServer(const PreviewServerOptions& options) : state_(std::make_unique<State>()) {
    State& s = *state_;
    s.opts = options;
    BVHLAB_CHECK(options.port >= 0 && options.port <= 65535, "--serve: the port must be in [0, 65535]");
    s.server.new_task_queue = [] { return new httplib::ThreadPool(8); };
    const std::string html = page(options.title);
    s.server.Get("/", [&s, html](const httplib::Request&, httplib::Response& res) {
        ++s.requests;
        {
            std::lock_guard<std::mutex> lock(s.mu);
            s.watched = true;
        }
        res.set_header("Cache-Control", "no-store");
        res.set_content(html, "text/html; charset=utf-8");
    });
    s.server.Get("/status", [&s](const httplib::Request& req, httplib::Response& res) {
        ++s.requests;
        uint64_t after = 0;
        if (req.has_param("after")) {
            try {
                after = std::stoull(req.get_param_value("after"));
            } catch (...) {
                res.status = 400;
                res.set_content("after= takes an image version (a number)\n", "text/plain");
                return;
            }
        }
        std::unique_lock<std::mutex> lock(s.mu);
        s.watched = true;
        // The long poll: answered by the next image, the end, or after 10 s with what there is.
        s.cv.wait_for(lock, std::chrono::seconds(10), [&] { return s.version > after || s.finished || s.stopping; });
        res.set_header("Cache-Control", "no-store");
        res.set_content(s.status().dump(), "application/json");
    });
    s.server.Get("/image.png", [&s](const httplib::Request& req, httplib::Response& res) {
        ++s.requests;
        std::lock_guard<std::mutex> lock(s.mu);
        if (!s.png) {
            res.status = 404;
            res.set_content("no image yet\n", "text/plain");
            return;
        }
        res.set_header("Cache-Control", "no-store");
        // The final image counts as fetched once it has been sent whole (the releaser runs then),
        // so that the server does not stop in the middle of it.
        // Only a request for the final version counts: a page that asked for an earlier one
        // after the end gets the final bytes but still comes back for the final status.
        uint64_t asked = 0;
        try {
            asked = req.has_param("v") ? std::stoull(req.get_param_value("v")) : 0;
        } catch (...) {
        }
        const bool last = s.finished && asked == s.version;
        res.set_content_provider(
            s.png->size(), "image/png",
            [png = s.png](size_t offset, size_t length, httplib::DataSink& sink) {
                return sink.write(png->data() + offset, length);
            },
            [&s, last](bool success) {
                if (!last || !success) return;
                std::lock_guard<std::mutex> l(s.mu);
                s.final_fetched = true;
                s.cv.notify_all();
            });
    });
    if (options.port == 0) {
        s.port = s.server.bind_to_any_port(options.bind);
    } else {
        s.port = s.server.bind_to_port(options.bind, options.port) ? options.port : -1;
    }
    if (s.port <= 0)
        throw Error("--serve: cannot listen on " + options.bind + ":" + std::to_string(options.port) +
                    " (the port is taken or not allowed, or the address is not one of this machine's)");
    s.listener = std::thread([&s] { s.server.listen_after_bind(); });
}

PreviewServer::~PreviewServer() {
    State& s = *state_;
    {
        std::lock_guard<std::mutex> lock(s.mu);
        s.stopping = true;
    }
    s.cv.notify_all();
    s.server.stop();
    if (s.listener.joinable()) s.listener.join();
}

int PreviewServer::port() const { return state_->port; }

std::string PreviewServer::url() const {
    const std::string& b = state_->opts.bind;
    const std::string host = b.find(':') != std::string::npos ? "[" + b + "]" : b;  // IPv6
    return "http://" + host + ":" + std::to_string(state_->port) + "/";
}

void PreviewServer::update_image(const Image& mean, uint32_t spp) {
    auto png = std::make_shared<const std::string>(encode_png(mean));
    {
        std::lock_guard<std::mutex> lock(state_->mu);
        state_->png = std::move(png);
        state_->image_spp = spp;
        ++state_->version;
    }
    state_->cv.notify_all();
}

void PreviewServer::update_progress(uint32_t done, uint32_t total, double mrays_per_s, double seconds) {
    std::lock_guard<std::mutex> lock(state_->mu);
    state_->done = done;
    state_->total = total;
    state_->mrays = mrays_per_s;
    state_->seconds = seconds;
}

void PreviewServer::finish(const Image& final_mean, uint32_t spp) {
    State& s = *state_;
    auto png = std::make_shared<const std::string>(encode_png(final_mean));
    std::unique_lock<std::mutex> lock(s.mu);
    s.png = std::move(png);
    s.image_spp = spp;
    s.done = std::max(s.done, spp);
    ++s.version;
    s.finished = true;
    s.cv.notify_all();
    if (s.watched) s.cv.wait_for(lock, std::chrono::duration<double>(s.opts.grace_s), [&] { return s.final_fetched; });
}

uint64_t PreviewServer::image_updates() const {
    std::lock_guard<std::mutex> lock(state_->mu);
    return state_->version;
}

uint64_t PreviewServer::page_requests() const { return state_->requests.load(); }

#else  // no cpp-httplib or stb in this build

struct PreviewServer::State {};

bool preview_server_available() { return false; }

PreviewServer::PreviewServer(const PreviewServerOptions&) {
    throw Error(
        "--serve: this build has no preview server (cpp-httplib and stb were not found when it was "
        "configured: tools/install_deps.sh installs libcpp-httplib-dev and libstb-dev)");
}
PreviewServer::~PreviewServer() = default;
int PreviewServer::port() const { return 0; }
std::string PreviewServer::url() const { return ""; }
void PreviewServer::update_image(const Image&, uint32_t) {}
void PreviewServer::update_progress(uint32_t, uint32_t, double, double) {}
void PreviewServer::finish(const Image&, uint32_t) {}
uint64_t PreviewServer::image_updates() const { return 0; }
uint64_t PreviewServer::page_requests() const { return 0; }

#endif

}  // namespace bvhlab::render
