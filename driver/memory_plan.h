// SPDX-License-Identifier: MIT
// pvsbake driver: the memory a bake expects, said before its stages run and held against --max-memory, so
// that a bake too large for the machine is refused with its figures instead of being killed by the kernel
// halfway through a night (docs/ALGORITHMS.md#memory-plan).
//
// Conventions: bytes. The figures are a model, not a measure: per voxel, per triangle, per PVS bit and per
// thread, with constants taken from measured peaks (docs/RESULTS.md, "Memory plan"); they aim to be an
// upper estimate of the peak resident memory (docs/ALGORITHMS.md#memory-plan).
#pragma once

#include "core/config.h"
#include "core/world.h"

#include <cstdint>
#include <string>

namespace pvs {

struct MemoryPlan {
    double world_bytes = 0.0;       // the world and its ray-tracing scene
    double voxel_bytes = 0.0;       // the view volume and occluder synthesis over `voxels`
    double pvs_bytes = 0.0;         // the rows of `cells` x the objects, with their copies
    double per_thread_bytes = 0.0;  // each worker's depth cubes and samples
    uint64_t voxels = 0;
    uint64_t cells = 0;
    int threads = 1;
    bool cells_bound = false;  // `cells` is the most the view bounds can hold (before the flood)

    double total() const {
        return world_bytes + voxel_bytes + pvs_bytes + double(threads) * per_thread_bytes;
    }
};

// The plan of a bake of `world` over `voxels` voxels and `cells` cells with `threads` workers.
MemoryPlan plan_memory(const BakeConfig& config, const World& world, uint64_t voxels, uint64_t cells,
                       int threads);

// The most a bake may use: config.run.max_memory_mib, or when 0 the machine's memory (or the control
// group's limit, when lower) less a margin of a tenth, at least 1 GiB.
double max_memory_bytes(const RunConfig& config);

// "1.4 GiB (world 0.1, voxels 0.9, PVS 0.2, 2 threads x 0.1)".
std::string describe(const MemoryPlan& plan);

// Throws pvs::Error (bad input) naming the stage, the plan, the limit and what would shrink it when the
// plan's total passes `limit_bytes` (without its PVS when `cells` is only a bound).
void check_memory(const MemoryPlan& plan, double limit_bytes, const std::string& stage);

}  // namespace pvs
