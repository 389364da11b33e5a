// SPDX-License-Identifier: MIT
// The memory a bake expects (driver/memory_plan.h).
#include "driver/memory_plan.h"

#include "core/error.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace pvs {

namespace {

// The model's constants, from measured peaks (docs/RESULTS.md, "Memory plan").
constexpr double kBaseBytes = 16.0 * (1 << 20);       // the process, its libraries, Embree's device
constexpr double kBytesPerTriangle = 600.0;           // the World, the Embree scene, panels, object lists
constexpr double kBytesPerVoxel = 9.0;                // bit layers, the leak search's steps, eye voxel lists
constexpr double kRowCopies = 4.0;                    // rows, their checkpoint journal, the file's encoding
constexpr double kThreadBaseBytes = 8.0 * (1 << 20);  // a worker's samples, shaft pieces, stacks
constexpr double kCubeBytesPerPixel = 4.0 * 4.0;      // depth and object planes of a cube, and a second look

double gib(double bytes) {
    return bytes / double(uint64_t(1) << 30);
}

}  // namespace

MemoryPlan plan_memory(const BakeConfig& config, const World& world, uint64_t voxels, uint64_t cells,
                       int threads) {
    MemoryPlan p;
    p.voxels = voxels;
    p.cells = cells;
    p.threads = std::max(1, threads);
    p.world_bytes = kBaseBytes + kBytesPerTriangle * double(world.triangles.size());
    p.voxel_bytes = kBytesPerVoxel * double(voxels);
    const double row_bytes = 8.0 * std::ceil(double(world.objects.size()) / 64.0);
    p.pvs_bytes = kRowCopies * row_bytes * double(cells);
    const double res =
        double(std::max(config.conservative.cube_resolution, config.conservative.fine_cube_resolution));
    p.per_thread_bytes = kThreadBaseBytes + 6.0 * res * res * kCubeBytesPerPixel;
    return p;
}

double max_memory_bytes(const RunConfig& config) {
    if (config.max_memory_mib > 0.0) return config.max_memory_mib * double(1 << 20);
    double machine = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    std::ifstream cgroup("/sys/fs/cgroup/memory.max");
    double limit = 0.0;
    if (cgroup >> limit && limit > 0.0) machine = std::min(machine, limit);  // "max" reads as no number
    return machine - std::max(machine * 0.1, double(uint64_t(1) << 30));
}

std::string describe(const MemoryPlan& p) {
    return fmt::format(
        "{:.2f} GiB (world {:.2f}, {:.1f} M voxels {:.2f}, {}{} cells' PVS {:.2f}, {} thread{} x {:.2f})",
        gib(p.total()), gib(p.world_bytes), double(p.voxels) * 1e-6, gib(p.voxel_bytes),
        p.cells_bound ? "at most " : "", p.cells, gib(p.pvs_bytes), p.threads, p.threads == 1 ? "" : "s",
        gib(p.per_thread_bytes));
}

void check_memory(const MemoryPlan& plan, double limit_bytes, const std::string& stage) {
    if (plan.total() - (plan.cells_bound ? plan.pvs_bytes : 0.0) <= limit_bytes) return;
    throw bad_input(fmt::format(
        "memory plan: {} expects {}, over the {:.2f} GiB this bake may use (--max-memory, default the machine's "
        "memory less a tenth): use coarser voxels (--voxel-size, --max-voxel-size), larger cells, fewer "
        "--threads, or raise --max-memory",
        stage, describe(plan), gib(limit_bytes)));
}

}  // namespace pvs
