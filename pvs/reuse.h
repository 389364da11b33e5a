// SPDX-License-Identifier: MIT
// pvsbake solver: the incremental re-bake. After an edit of the world, the (cell, object) pairs the edit
// cannot change keep the old bake's bit; the solver tests only the others, and the rows are those a full
// bake of the new world makes. The argument: docs/ALGORITHMS.md#reuse.
//
// In short: the solver decides each pair on its own (nothing it reads for object k depends on which other
// objects are being tested), and everything it reads for (cell c, object k) lies in the box around c and k,
// grown by a margin (`reach_margin_m`): the rays through the depth cube's pixels of k up to k's depth, the
// segments the single-occluder and shaft passes test, the voxels around c. So where the geometry print of the
// old and the new bake agree on every tile that box meets, and c and k are the same, the bit is the same.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/geometry_print.h"
#include "core/occluder.h"
#include "core/pvs_set.h"
#include "core/world.h"

#include <string>

namespace pvs {

// The print of everything the conservative solver reads (core/geometry_print.h): the triangles with their
// opacity, the shrunk boxes of every epsilon, the panels and slanted panels (with the shaft pass, its convex
// caps over their polygons' bounds), the proven solid, the free voxels and the eye voxels; and per object,
// its triangles, opacity and flags (its index too when the shaft pass, whose random lines are seeded by it,
// is on). Deterministic. Empty when `eyes` is.
GeometryPrint geometry_print(const ConservativeConfig& config, const World& world,
                             const ShrunkOccluders& occluders, const VoxelMask& eyes);

// The margin by which the box around a cell and an object is grown to hold everything the solver reads for
// the pair: two voxels, and the angular size of two depth-cube pixels at the span of the tiles
// (docs/ALGORITHMS.md#reuse).
double reach_margin_m(const ConservativeConfig& config, const GeometryPrint& print, float voxel_size_m);

struct ReuseFigures {
    uint64_t pairs = 0;            // (cell, object) pairs of the new bake
    uint64_t kept = 0;             // of them, bits kept from the old bake
    uint64_t cells_matched = 0;    // cells the old bake has, with the same box
    uint64_t cells_whole = 0;      // cells every pair of which is kept
    uint64_t objects_matched = 0;  // objects the old world has, unchanged
    uint64_t changed_tiles = 0;    // tiles whose print differs
    uint64_t changed_boxes = 0;    // boxes those tiles were merged into
    double seconds = 0.0;
};

// What the old bake gives: its cells, rows and print.
struct ReuseSource {
    const CellSet& cells;
    const PvsSet& pvs;
    const GeometryPrint& print;
};

struct ReusePlan {
    PvsSet settled;  // per cell of the new bake: the pairs whose bit is kept
    PvsSet listed;   // the kept bits: the old row on the settled pairs, zero elsewhere
    ReuseFigures figures;
    std::string whole;  // why nothing is kept, or empty
};

// Plans the re-bake of `cells` (a grid) of `world`, whose print is `now`, from the old bake. A pair is
// settled when its cell's box is an old cell's box, its object is an unchanged old object, and no tile
// whose print changed meets the box around the cell and the object grown by reach_margin_m(). When the
// prints cannot be compared (another voxel grid or epsilon ladder, or the old bake has none), nothing is
// settled and `whole` says why.
ReusePlan plan_reuse(Context& ctx, const ConservativeConfig& config, const World& world, const CellSet& cells,
                     const GeometryPrint& now, const ReuseSource& old);

}  // namespace pvs
