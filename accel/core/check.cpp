// SPDX-License-Identifier: MIT
// Out-of-line failure path of BVHLAB_CHECK.
#include "accel/core/check.h"

#include <cstdlib>

namespace bvhlab {

void check_failed(const char* file, int line, const char* expr, const std::string& msg) {
    // The user sees what went wrong, never the source text or location (the error contract);
    // BVHLAB_DEBUG=1 adds them for a bug report.
    const char* debug = std::getenv("BVHLAB_DEBUG");
    if (debug && *debug && std::string(debug) != "0")
        throw Error(msg + " (check '" + expr + "' failed at " + file + ":" + std::to_string(line) + ")");
    throw Error(msg);
}

}  // namespace bvhlab
