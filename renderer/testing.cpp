// SPDX-License-Identifier: MIT
#include "renderer/testing.h"

#include <atomic>

namespace bvhlab::render::testing {

namespace {
std::atomic<PlantedBug> g_bug{PlantedBug::kNone};
}  // namespace

PlantedBug planted_bug() { return g_bug.load(std::memory_order_relaxed); }

ScopedPlantedBug::ScopedPlantedBug(PlantedBug bug) : previous_(g_bug.exchange(bug)) {}

ScopedPlantedBug::~ScopedPlantedBug() { g_bug.store(previous_); }

}  // namespace bvhlab::render::testing
