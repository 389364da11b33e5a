// SPDX-License-Identifier: MIT
// pvsbake driver: verification of the ranked occluders: every box a cell ranks must be solid for that cell's
// eyes, since the run-time culler hides moving objects behind it (docs/ALGORITHMS.md#proven-boxes).
//
// From eye points of up to kCellsPerBox cells that rank a box (cells/eyes.h), segments to random points
// inside it must each meet an opaque triangle: one that does not reaches into the box, and the box is SEEN
// INTO (a bug: the culler could hide what an eye sees). The points depend only on (seed, box): the same
// answer for any thread count.
#pragma once

#include "core/cell_set.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/world.h"
#include "rays/ray_scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

struct RankedBoxCheck {
    uint32_t boxes = 0;      // distinct ranked boxes checked
    uint64_t rays = 0;       // segments traced
    uint32_t seen_into = 0;  // boxes a segment reached into, or not proven
    std::string first;       // the first of them, in words ("" when none)
};

RankedBoxCheck check_ranked_boxes(Context& ctx, const RayScene& scene, const CellSet& cells,
                                  const std::vector<Occluder>& occluders, const RankedOccluders& ranked,
                                  uint64_t seed);

}  // namespace pvs
