// SPDX-License-Identifier: MIT
// The renderer's test-only fault injection: a deliberate light-transport bug that the tests
// plant to prove that the CPU/GPU image comparison can fail. Nothing outside tests/ includes
// this header; the shipping settings (RenderSettings) have no such field. While a
// ScopedPlantedBug lives, every render (CPU and GPU drivers) runs with the bug.
#pragma once

#include "renderer/core/stages.h"

namespace bvhlab::render::testing {

/// The bug every render runs with now (kNone unless a ScopedPlantedBug lives).
PlantedBug planted_bug();

/// Plants `bug` for its lifetime and restores the previous one after. Not thread-safe against
/// renders running on other threads.
class ScopedPlantedBug {
public:
    explicit ScopedPlantedBug(PlantedBug bug);
    ~ScopedPlantedBug();
    ScopedPlantedBug(const ScopedPlantedBug&) = delete;
    ScopedPlantedBug& operator=(const ScopedPlantedBug&) = delete;

private:
    PlantedBug previous_;
};

}  // namespace bvhlab::render::testing
