// SPDX-License-Identifier: MIT
// A small local web server that shows a render as it converges: a page with the running mean
// (PNG), the samples per pixel done, the rays per second and the time left. The page waits on
// /status for the next update (a long poll), so it sees every update without polling.
// cpp-httplib serves, stb_image_write encodes the PNGs.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "renderer/image.h"

namespace bvhlab::render {

/// Whether this build has the preview server (cpp-httplib and stb were found).
bool preview_server_available();

struct PreviewServerOptions {
    std::string bind = "127.0.0.1";  ///< the address to listen on: loopback only unless told
    int port = 0;                    ///< 0: any free port (PreviewServer::port says which)
    std::string title;               ///< the page's title: the scene and the command
    double grace_s = 10.0;           ///< after the render, how long a watching page may take to fetch the last image
};

class PreviewServer {
public:
    /// Listens at once. Throws bvhlab::Error when the build has no server, the address is not
    /// one of this machine's, or the port is taken or not allowed.
    explicit PreviewServer(const PreviewServerOptions& options);
    ~PreviewServer();  ///< stops the server (finish() first lets the page see the last image)
    PreviewServer(const PreviewServer&) = delete;
    PreviewServer& operator=(const PreviewServer&) = delete;

    int port() const;
    std::string url() const;  ///< http://ADDRESS:PORT/

    /// A new running mean after `spp` samples per pixel: encoded here, then served.
    void update_image(const Image& mean, uint32_t spp);
    /// Progress: samples done of `total`, rays per second, seconds since the start.
    void update_progress(uint32_t done, uint32_t total, double mrays_per_s, double seconds);
    /// The render is over: the final image is served, the page is told, and the call returns
    /// when a page that was watching has fetched it (or after grace_s), or at once if none watched.
    void finish(const Image& final_mean, uint32_t spp);

    uint64_t image_updates() const;  ///< images served as updates so far
    uint64_t page_requests() const;  ///< requests of the page and its status, for the record

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace bvhlab::render
