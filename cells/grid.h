// SPDX-License-Identifier: MIT
// pvsbake cells: the uniform grid of view cells.
//
// Conventions: glTF axes, metres; grid index order x fastest (core/cell_set.h). The grid starts at the
// region's min corner and has ceil(extent / cell size) cells per axis (at least one), so it covers the
// region; the last cells may reach past it.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"

namespace pvs {

// The largest grid build_uniform_grid() accepts, in cells (a clear error beyond it).
constexpr uint64_t kMaxGridCells = 50'000'000;

// A grid over `region` (the bounds of the view volume). Throws pvs::Error (bad input)
// naming --cell-size when the grid would exceed kMaxGridCells or the region is empty.
CellSet build_uniform_grid(Context& ctx, const CellConfig& config, const Aabb& region);

// Drops the cells no voxel of the eye space `eyes` overlaps (with volume: a voxel only touching a cell's
// face does not count), renumbers the rest in grid order and stores the masks in the set (lookups also
// check `view`). Returns the cells dropped.
uint64_t clip_grid_to_view(Context& ctx, CellSet& cells, const VoxelMask& view, const VoxelMask& eyes);

}  // namespace pvs
