// SPDX-License-Identifier: MIT
// Error type and invariant checks. Library code throws bvhlab::Error; only tools/ exit.
#pragma once

#include <stdexcept>
#include <string>

#include "accel/core/hd.h"

namespace bvhlab {

/// Every error the library reports: a one-line, human-readable message.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

[[noreturn]] void check_failed(const char* file, int line, const char* expr, const std::string& msg);

}  // namespace bvhlab

/// Always-on invariant check; throws bvhlab::Error with file:line on failure.
#define BVHLAB_CHECK(expr, msg)                                              \
    do {                                                                     \
        if (!(expr)) ::bvhlab::check_failed(__FILE__, __LINE__, #expr, msg); \
    } while (0)
