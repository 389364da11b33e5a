// SPDX-License-Identifier: MIT
// pvsbake occluders: the ranking stage (docs/ALGORITHMS.md#ranking): for every view cell, the few synthesized
// occluder boxes worth testing at run time, best first, with their scores (occluders/ranking.h defines the
// solid angle, the shadow frustum test and the score; after Hudson et al., SoCG 1997).
//
// Conventions: glTF axes, metres, steradians. Only proven boxes (core/occluder.h) are ranked, as stored
// (not shrunk). Eye points come from cells/eyes.h (free space of the cell, never inside solid), seeded by
// (config.seed, cell): the same input gives the same ranking, byte for byte, for any thread count.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/pvs_set.h"
#include "core/work_share.h"
#include "core/world.h"

#include <vector>

namespace pvs {

struct RankingFigures {
    uint32_t boxes_usable = 0;     // proven boxes
    uint64_t ranked = 0;           // entries kept over all cells
    uint32_t cells_with_none = 0;  // cells that kept no occluder
    double score_mean = 0.0;       // of the kept entries
    double solid_angle_mean_sr = 0.0;
    double hidden_triangle_share_mean = 0.0;
    double seconds = 0.0;
};

// Ranks the proven occluders for every cell. config.occluders_per_cell == 0 gives an empty result. With the
// cells' PVS and config.sight_lines > 0, by sight (occluders/sight_ranking.h: the proven occluders, panels
// among them, that stop first the most sight lines from the cell's eyes to its PVS; score = the share of the
// lines each stops first); otherwise by solid angle and depth complexity (occluders/ranking.h). With
// `share`, the cells are dealt over its processes (collective: every process calls it, and every one gets
// the whole result). By sight, `polygons` (the run-time culler's polygon occluders) are candidates too: an
// entry naming one has box = occluders.size() + its index, and measures of 0 (they are the boxes' measures).
RankedOccluders rank_occluders(Context& ctx, const RankingConfig& config, const World& world,
                               const CellSet& cells, const std::vector<Occluder>& occluders,
                               RankingFigures& figures, WorkShare* share = nullptr,
                               const PvsSet* pvs = nullptr,
                               const std::vector<OccluderPolygon>* polygons = nullptr);

}  // namespace pvs
