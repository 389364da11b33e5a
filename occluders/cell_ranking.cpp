// The ranking stage: occluders/ranking.h's per-cell ranking over every cell, in parallel (OpenMP over cells,
// each cell's eyes drawn from its own seeded stream and its result kept in its own slot, then joined in cell
// order, so that the output does not depend on the schedule). After Hudson et al., SoCG 1997.
#include "occluders/cell_ranking.h"

#include "cells/eyes.h"
#include "occluders/ranking.h"

#include <fmt/format.h>

#include <chrono>

namespace pvs {

RankedOccluders rank_occluders(Context& ctx, const RankingConfig& config, const World& world,
                               const CellSet& cells, const std::vector<Occluder>& occluders,
                               RankingFigures& figures) {
    figures = RankingFigures{};
    RankedOccluders ranked;
    if (config.occluders_per_cell == 0) return ranked;
    ScopedTimer timer(ctx, "occluder_ranking");
    const auto start = std::chrono::steady_clock::now();
    std::vector<Aabb> boxes;
    std::vector<uint32_t> usable;
    boxes.reserve(occluders.size());
    for (uint32_t i = 0; i < occluders.size(); ++i) {
        boxes.push_back(occluders[i].box);
        if (occluders[i].proven) usable.push_back(i);
    }
    figures.boxes_usable = uint32_t(usable.size());
    const Occludees occludees(world);
    const int64_t n_cells = int64_t(cells.size());
    std::vector<std::vector<RankedOccluder>> per_cell(static_cast<size_t>(n_cells));
    ctx.progress_begin("occluder ranking", uint64_t(n_cells), "cells");
#pragma omp parallel
    {
        std::vector<glm::vec3> eyes;
#pragma omp for schedule(dynamic, 16)
        for (int64_t c = 0; c < n_cells; ++c) {
            eyes.clear();
            sample_eye_points(cells, uint32_t(c), config.eyes_per_cell, config.seed, eyes);
            rank_cell_occluders(config, boxes, usable, occludees, eyes, per_cell[size_t(c)]);
            ctx.progress_advance();
        }
    }
    ctx.progress_end();
    ranked.offsets.reserve(size_t(n_cells) + 1);
    ranked.offsets.push_back(0);
    for (const std::vector<RankedOccluder>& list : per_cell) {
        ranked.entries.insert(ranked.entries.end(), list.begin(), list.end());
        ranked.offsets.push_back(uint32_t(ranked.entries.size()));
        figures.cells_with_none += list.empty() ? 1 : 0;
    }
    figures.ranked = ranked.entries.size();
    for (const RankedOccluder& r : ranked.entries) {
        figures.score_mean += r.score;
        figures.solid_angle_mean_sr += r.solid_angle_sr;
        figures.hidden_triangle_share_mean += r.hidden_triangle_share;
    }
    if (!ranked.entries.empty()) {
        const double n = double(ranked.entries.size());
        figures.score_mean /= n;
        figures.solid_angle_mean_sr /= n;
        figures.hidden_triangle_share_mean /= n;
    }
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "occluder ranking: {} of {} boxes usable, {:.2f} ranked per cell ({} cells with none), "
        "{:.2f} s",
        usable.size(), occluders.size(), n_cells > 0 ? double(ranked.entries.size()) / double(n_cells) : 0.0,
        figures.cells_with_none, figures.seconds));
    return ranked;
}

}  // namespace pvs
