// SPDX-License-Identifier: MIT
// pvsbake occluders: the run-time horizon's occluders and the list of them that each block of cells, or where
// it is cheap each cell, gives the runtime (runtime/pvsr.h, pvsr_horizon; docs/ALGORITHMS.md#horizon-lists).
//
// The candidates are every proven occluder the bake knows: its proven boxes, the world's panels (exact
// rectangles of opaque surface, as flat boxes) and its slanted panels as tiles (occluders/slanted_panels.h,
// runtime_tiles). A block's list holds those whose pieces the runtime's own horizon used to prove some object
// of a PVS hidden, from seeded eyes in the block's cells: every candidate is given, each tagged, and
// pvsr_horizon_hidden_by() names the tags of the chains that proved each hidden object. Any list is safe
// (every candidate is proven); the eyes only decide which occluders are worth a frame's time.
//
// Blocks follow the runtime file's rule (runtime/pvsr.c, palette_block): on a grid, the 4 x 4 x 4 block of
// grid positions holding the cell (x fastest, then y, then z); on an octree, cells 64 b .. 64 b + 63. The
// result depends only on the inputs and the seed, not on threads or processes.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/object_parts.h"
#include "core/occluder.h"
#include "core/pvs_set.h"
#include "core/work_share.h"
#include "core/world.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct HorizonListFigures {
    uint32_t candidates = 0;      // occluders offered to the eyes' horizons
    uint32_t kept = 0;            // occluders some list names (the file's)
    uint32_t lists = 0;           // blocks, or cells with per_cell
    bool per_cell = false;  // a list per cell (a subset of its block's: RankingConfig::horizon_cell_eyes)
    uint64_t entries = 0;         // over every list
    uint64_t tests = 0;           // objects the cells' frames test, over every cell (lists per cell)
    uint32_t largest_list = 0;    // entries of the longest list
    uint64_t eyes = 0;            // eyes whose horizons chose
    uint64_t pieces_dropped = 0;  // pieces an eye's horizon had no room for (fewer chosen, never unsafe)
    double seconds = 0.0;
};

// The grid positions' blocks and cells' blocks of the runtime file's rule (above).
constexpr uint32_t kHorizonBlockSide = 4;
constexpr uint32_t kHorizonBlockCells = 64;
uint32_t horizon_block_count(const CellSet& cells);
// Per cell, its block.
std::vector<uint32_t> horizon_blocks(const CellSet& cells);

// The candidates: `boxes` (proven boxes and panels, solid or flat along one axis) and `tiles`. Each block's
// list as above; then, with config.horizon_cell_eyes > 0 and the cells times their blocks' list lengths at
// most config.horizon_cell_lists_max, a list per cell (cell_list[c] = c): the occluders of its block's list
// that horizon_cell_eyes seeded eyes of the cell used, each eye's horizon built from the block's list. With
// config.horizon_eyes == 0, or no candidate, an empty result. With `share`, the blocks are dealt over its
// processes (collective: every process calls it, and every one gets the whole result). With `parts`, an
// object whose bounds an eye's horizon does not hide counts the proofs of its parts when they hide every
// part, as the runtime's walk then culls it (docs/ALGORITHMS.md#object-parts). With lists per cell and
// config.horizon_cell_tests, each cell's tests are the objects of its PVS those eyes' horizons hid, as the
// walk culls them (docs/ALGORITHMS.md#horizon-tests).
HorizonLists choose_horizon_lists(Context& ctx, const RankingConfig& config, const World& world,
                                  const CellSet& cells, const PvsSet& pvs, const std::vector<Aabb>& boxes,
                                  const std::vector<OccluderPolygon>& tiles, HorizonListFigures& figures,
                                  WorkShare* share = nullptr, const ObjectParts* parts = nullptr);

}  // namespace pvs
