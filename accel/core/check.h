// SPDX-License-Identifier: MIT
// Error type and invariant checks. Library code throws bvhlab::Error; only tools/ exit.
#pragma once

#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "accel/core/hd.h"

namespace bvhlab {

/// Every error the library reports: a one-line, human-readable message.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// BVHLAB_CHECK's failure path, out of line (header-only, so that the scene module, which
/// sits below the acceleration structures, needs no library of theirs). The user sees what went
/// wrong, never the source text or location (the error contract); BVHLAB_DEBUG=1 adds them for
/// a bug report.
[[noreturn]] __attribute__((noinline, cold)) inline void check_failed(const char* file, int line, const char* expr,
                                                                      const std::string& msg) {
    const char* debug = std::getenv("BVHLAB_DEBUG");
    if (debug && *debug && std::string(debug) != "0")
        throw Error(msg + " (check '" + expr + "' failed at " + file + ":" + std::to_string(line) + ")");
    throw Error(msg);
}

}  // namespace bvhlab

namespace bvhlab {

/// "" when lo <= v <= hi, else "<name> <v> is not in [<lo>, <hi>]" (NaN is never in range):
/// the one-line form of every option range check.
template <typename T>
std::string range_problem(const char* name, T v, T lo, T hi) {
    if (v >= lo && v <= hi) return "";
    std::ostringstream s;  // floats as %g: 1e+20, not 100000002004087734272.000000
    s << name << " " << v << " is not in [" << lo << ", " << hi << "]";
    return s.str();
}

}  // namespace bvhlab

/// Always-on invariant check; throws bvhlab::Error with file:line on failure.
#define BVHLAB_CHECK(expr, msg)                                              \
    do {                                                                     \
        if (!(expr)) ::bvhlab::check_failed(__FILE__, __LINE__, #expr, msg); \
    } while (0)
