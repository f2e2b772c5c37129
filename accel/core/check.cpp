// SPDX-License-Identifier: MIT
// Out-of-line failure path of BVHLAB_CHECK.
#include "accel/core/check.h"

namespace bvhlab {

void check_failed(const char* file, int line, const char* expr, const std::string& msg) {
    throw Error(msg + " (check '" + expr + "' failed at " + file + ":" + std::to_string(line) + ")");
}

}  // namespace bvhlab
