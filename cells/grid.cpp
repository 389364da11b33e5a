// SPDX-License-Identifier: MIT
// Uniform grid of view cells over a region.
#include "cells/grid.h"

#include "cells/eyes.h"
#include "core/error.h"

#include <fmt/format.h>

#include <cmath>

namespace pvs {

CellSet build_uniform_grid(Context& ctx, const CellConfig& config, const Aabb& region) {
    ScopedTimer timer(ctx, "cells");
    if (region.is_empty() || !is_finite(region.min) || !is_finite(region.max)) {
        throw bad_input("build_uniform_grid: the region to cover is empty");
    }
    if (!(config.cell_size_m > 0.0)) {
        throw bad_input(
            fmt::format("build_uniform_grid: --cell-size must be > 0 m (got {})", config.cell_size_m));
    }
    CellSet set;
    set.kind = CellSet::Kind::kGrid;
    set.origin = region.min;
    set.cell_size_m = float(config.cell_size_m);
    uint64_t total = 1;
    const glm::vec3 extent = region.max - region.min;
    for (int a = 0; a < 3; ++a) {
        const double n = std::ceil(double(extent[a]) / config.cell_size_m);
        set.dims[a] = int(std::max(1.0, std::min(n, 1e9)));
        total *= uint64_t(set.dims[a]);
        if (total > kMaxGridCells) break;
    }
    if (total > kMaxGridCells) {
        throw bad_input(fmt::format(
            "build_uniform_grid: a {} m grid over {:.1f} x {:.1f} x {:.1f} m needs more than {} cells; "
            "use a larger --cell-size",
            config.cell_size_m, extent.x, extent.y, extent.z, kMaxGridCells));
    }
    set.grid_to_cell.resize(total);
    set.cells.reserve(total);
    const float s = set.cell_size_m;
    for (int z = 0; z < set.dims.z; ++z) {
        for (int y = 0; y < set.dims.y; ++y) {
            for (int x = 0; x < set.dims.x; ++x) {
                const size_t g =
                    size_t(x) + size_t(set.dims.x) * (size_t(y) + size_t(set.dims.y) * size_t(z));
                Cell cell;
                cell.bounds.min = set.origin + glm::vec3(float(x), float(y), float(z)) * s;
                cell.bounds.max = set.origin + glm::vec3(float(x + 1), float(y + 1), float(z + 1)) * s;
                set.grid_to_cell[g] = int32_t(set.cells.size());
                set.cells.push_back(cell);
            }
        }
    }
    ctx.info(fmt::format("cells: uniform grid {} x {} x {} of {} m = {} cells", set.dims.x, set.dims.y,
                         set.dims.z, config.cell_size_m, set.cells.size()));
    return set;
}

uint64_t clip_grid_to_view(Context& ctx, CellSet& cells, const VoxelMask& view, const VoxelMask& eyes) {
    ScopedTimer timer(ctx, "cells_clip");
    cells.view = view;
    cells.eyes = eyes;
    if (view.empty()) return 0;
    // Which cells hold eye space, on all threads; then the kept cells renumbered in grid order.
    const VoxelMask& held = eyes.empty() ? view : eyes;
    std::vector<uint8_t> meets(cells.grid_to_cell.size(), 0);
    const int64_t slots = int64_t(meets.size());
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t g = 0; g < slots; ++g) {
        const int32_t c = cells.grid_to_cell[size_t(g)];
        if (c >= 0) meets[size_t(g)] = mask_meets_box(held, cells.cells[size_t(c)].bounds) ? 1 : 0;
    }
    std::vector<Cell> kept;
    kept.reserve(cells.cells.size());
    uint64_t dropped = 0;
    for (size_t g = 0; g < cells.grid_to_cell.size(); ++g) {
        const int32_t c = cells.grid_to_cell[g];
        if (c < 0) continue;
        if (!meets[g]) {
            cells.grid_to_cell[g] = -1;
            ++dropped;
            continue;
        }
        cells.grid_to_cell[g] = int32_t(kept.size());
        kept.push_back(cells.cells[size_t(c)]);
    }
    cells.cells = std::move(kept);
    ctx.info(fmt::format("cells: {} cells hold view volume ({} dropped)", cells.cells.size(), dropped));
    return dropped;
}

}  // namespace pvs
