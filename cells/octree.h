// SPDX-License-Identifier: MIT
// pvsbake cells: a visibility-driven octree of view cells (docs/ALGORITHMS.md#octree).
//
// Root cells of `root_cell_size_m` (min_cell_size_m times a power of two) cover the view region; a cell
// is split into eight where visibility changes inside it: when some child's PVS differs from the
// parent's (symmetric difference) by more than `split_threshold` of the parent's PVS size. Splitting
// stops at `min_cell_size_m` and at `max_cells`. Children that would not have been split apart (all
// near-identical to their parent) are merged back: the parent stays a leaf. Children holding no view
// volume stay as empty leaves (no cell), so lookups there find none.
// The PVS of a candidate box comes from a caller's oracle (the bake mode's own PVS), so cells/ needs no
// ray tracer. Deterministic: boxes are evaluated in a fixed order with fixed stream numbers.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/pvs_set.h"

#include <functional>
#include <vector>

namespace pvs {

// Fills `rows` (boxes.size() rows of `rows.object_count` bits) with the PVS of each box; streams[i] is a
// number unique to box i. bounds[i] is the row the oracle gave the box's parent (a box that holds box i), or
// null for a root: a conservative oracle proved every object that row leaves out hidden from every eye of the
// parent, so from every eye of box i, and may leave it out without a test
// (docs/ALGORITHMS.md#octree-parent-bound). Called from one thread; it may parallelize inside. It advances
// the Context's progress by one per box it finishes: build_octree() begins one progress per call, whose total
// is the call's box count, and does not count them again.
using RegionPvsOracle =
    std::function<void(const std::vector<Aabb>& boxes, const std::vector<uint64_t>& streams,
                       const std::vector<const uint64_t*>& bounds, PvsSet& rows)>;

struct OctreeStats {
    uint32_t roots = 0;
    uint32_t splits = 0;     // cells split because their children's visibility differed
    uint32_t merged = 0;     // candidate splits undone: children near-identical to the parent
    uint32_t evaluated = 0;  // boxes whose PVS the oracle computed
    uint32_t depth = 0;      // deepest level below the roots
    bool budget_reached = false;
};

// `masks` holds the view volume (CellSet::view, ::eyes) the cells inherit. Returns the leaf cells and
// their PVS rows in `leaf_pvs` (one row per cell, as the oracle computed them).
CellSet build_octree(Context& ctx, const CellConfig& config, const CellSet& masks, const Aabb& region,
                     uint32_t object_count, const RegionPvsOracle& oracle, PvsSet& leaf_pvs,
                     OctreeStats& stats);

}  // namespace pvs
