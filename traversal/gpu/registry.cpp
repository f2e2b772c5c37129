// SPDX-License-Identifier: MIT
#include "traversal/gpu/registry.h"

#include <algorithm>
#include <cstring>
#include <mutex>

#include "accel/core/check.h"

namespace bvhlab::trav {

namespace {

/// Function-local so registration from other translation units' static initialisers never
/// runs before the table exists.
std::vector<KernelInfo>& table() {
    static std::vector<KernelInfo> t;
    return t;
}

std::mutex& table_mutex() {
    static std::mutex m;
    return m;
}

}  // namespace

bool register_kernel(const KernelInfo& k) {
    std::lock_guard<std::mutex> lock(table_mutex());
    for (const KernelInfo& e : table())
        if (std::strcmp(e.name, k.name) == 0) throw Error(std::string("two GPU kernels are named '") + k.name + "'");
    table().push_back(k);
    return true;
}

std::vector<KernelInfo> registered_kernels() {
    std::vector<KernelInfo> out;
    {
        std::lock_guard<std::mutex> lock(table_mutex());
        out = table();
    }
    std::sort(out.begin(), out.end(), [](const KernelInfo& a, const KernelInfo& b) {
        if (a.layout != b.layout) return a.layout < b.layout;
        return std::strcmp(a.name, b.name) < 0;
    });
    return out;
}

const KernelInfo& find_kernel(const std::string& name) {
    std::lock_guard<std::mutex> lock(table_mutex());
    std::string names;
    for (const KernelInfo& e : table()) {
        if (name == e.name) return e;
        names += (names.empty() ? "" : ", ") + std::string(e.name);
    }
    if (names.empty()) throw Error("no GPU kernel '" + name + "': this bvhlab has no GPU kernels (built without CUDA)");
    throw Error("no GPU kernel '" + name + "' (registered: " + names + "; `bvhlab kernels` describes them)");
}

const KernelInfo& default_kernel(Layout layout, bool short_stack) {
    std::lock_guard<std::mutex> lock(table_mutex());
    if (table().empty())
        throw Error(std::string("no default GPU kernel for the ") + layout_name(layout) +
                    " layout: this bvhlab has no GPU kernels (built without CUDA)");
    for (const KernelInfo& e : table())
        if (e.is_default && e.layout == layout && (layout != Layout::kKd || e.short_stack == short_stack)) return e;
    throw Error(std::string("no GPU kernel is registered as the default for the ") + layout_name(layout) + " layout" +
                (layout == Layout::kKd ? (short_stack ? " with a short stack" : " with a full stack") : ""));
}

}  // namespace bvhlab::trav
