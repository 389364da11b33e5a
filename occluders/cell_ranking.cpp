// SPDX-License-Identifier: MIT
// The ranking stage: occluders/ranking.h's per-cell ranking over every cell, dealt to the threads and
// processes of the bake (core/work_share.h; each cell's eyes drawn from its own seeded stream and its result
// kept in its own slot, then joined in cell order, so that the output does not depend on who ranked which
// cell). After Hudson et al., SoCG 1997.
#include "occluders/cell_ranking.h"

#include "cells/eyes.h"
#include "core/error.h"
#include "occluders/ranking.h"
#include "occluders/sight_ranking.h"
#include "rays/surface_points.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>

namespace pvs {

namespace {

// The cells' lists as fixed records of 32-bit words, for uniting over processes (WorkShare::unite ORs
// words; a record is written by the one process that ranked its cell and is zero elsewhere): the count,
// then `per_cell` entries of RankedOccluder's five fields.
class RankRecords {
public:
    RankRecords(size_t cells, uint32_t per_cell)
        : per_cell_(per_cell),
          stride_(1 + kFields * size_t(per_cell)),
          words_((cells * stride_ + 1) / 2, 0) {}
    // `list` holds at most `per_cell` entries (rank_cell_occluders keeps occluders_per_cell at most).
    void put(size_t cell, const std::vector<RankedOccluder>& list) {
        if (list.size() > per_cell_)
            throw Error(ErrorKind::kInternal, "ranking: a cell's list outgrew its record");
        const uint32_t n = uint32_t(list.size());
        std::memcpy(at(cell), &n, sizeof n);
        if (n > 0) std::memcpy(at(cell) + sizeof n, list.data(), list.size() * sizeof(RankedOccluder));
    }
    void get(size_t cell, std::vector<RankedOccluder>& list) const {
        uint32_t n = 0;
        std::memcpy(&n, at(cell), sizeof n);
        list.resize(n);
        if (n > 0) std::memcpy(list.data(), at(cell) + sizeof n, list.size() * sizeof(RankedOccluder));
    }
    uint64_t* words() { return words_.data(); }
    size_t size() const { return words_.size(); }

private:
    static constexpr size_t kFields = sizeof(RankedOccluder) / sizeof(uint32_t);
    static_assert(sizeof(RankedOccluder) == kFields * sizeof(uint32_t), "RankedOccluder is 32-bit fields");
    unsigned char* at(size_t cell) {
        return reinterpret_cast<unsigned char*>(words_.data()) + 4 * cell * stride_;
    }
    const unsigned char* at(size_t cell) const {
        return reinterpret_cast<const unsigned char*>(words_.data()) + 4 * cell * stride_;
    }
    size_t per_cell_;
    size_t stride_;  // words of 32 bits per cell
    std::vector<uint64_t> words_;
};

// One cell ranked by sight: the candidates (usable[k]) that stop first the most of its sight lines, with the
// measures of occluders/ranking.h for the kept ones; ties by the lower occluder index.
void rank_cell_by_sight(const RankingConfig& config, const OccluderSightScene& scene, const World& world,
                        const std::vector<double>& cum_area, const std::vector<Aabb>& boxes,
                        const std::vector<uint32_t>& usable, const Occludees& occludees, const uint64_t* row,
                        const std::vector<glm::vec3>& eyes, uint32_t cell, std::vector<RankedOccluder>& out) {
    out.clear();
    Rng rng(config.seed ^ 0x7369676874ULL, cell);
    std::vector<uint32_t> counts;
    count_first_hits(scene, world, cum_area, row, eyes, config.sight_lines, rng, counts);
    std::vector<std::pair<uint32_t, uint32_t>> hits;  // (count, candidate)
    for (uint32_t k = 0; k < counts.size(); ++k)
        if (counts[k] > 0) hits.emplace_back(counts[k], k);
    const size_t keep = std::min<size_t>(config.occluders_per_cell, hits.size());
    std::partial_sort(hits.begin(), hits.begin() + std::ptrdiff_t(keep), hits.end(),
                      [](const auto& a, const auto& b) {
                          return a.first > b.first || (a.first == b.first && a.second < b.second);
                      });
    for (size_t i = 0; i < keep; ++i) {
        RankedOccluder r;
        r.score = float(double(hits[i].first) / double(config.sight_lines));
        if (hits[i].second >= usable.size()) {  // a polygon: no box measures
            r.box = uint32_t(boxes.size() + (hits[i].second - usable.size()));
            out.push_back(r);
            continue;
        }
        const uint32_t box = usable[hits[i].second];
        r.box = box;
        for (const glm::vec3& e : eyes) {
            const double w = box_solid_angle_sr(boxes[box], e);
            if (w < kFourPi) r.solid_angle_sr = std::max(r.solid_angle_sr, float(w));
        }
        BoxMeasures m;
        measure_hidden(boxes[box], occludees, eyes, m);
        r.hidden_objects = float(m.hidden_objects_mean);
        r.hidden_triangle_share = float(m.hidden_triangle_share_mean);
        out.push_back(r);
    }
}

}  // namespace

RankedOccluders rank_occluders(Context& ctx, const RankingConfig& config, const World& world,
                               const CellSet& cells, const std::vector<Occluder>& occluders,
                               RankingFigures& figures, WorkShare* share, const PvsSet* pvs,
                               const std::vector<OccluderPolygon>* polygons) {
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
    const bool by_sight = config.sight_lines > 0 && pvs != nullptr && pvs->cell_count == cells.size() &&
                          pvs->object_count == world.objects.size();
    std::unique_ptr<OccluderSightScene> sight;
    std::vector<double> cum_area;
    const std::vector<OccluderPolygon> no_polygons;
    const std::vector<OccluderPolygon>& polys = polygons != nullptr && by_sight ? *polygons : no_polygons;
    if (by_sight && !(usable.empty() && polys.empty())) {
        std::vector<Aabb> candidates;
        for (uint32_t i : usable) candidates.push_back(boxes[i]);
        sight = std::make_unique<OccluderSightScene>(ctx, candidates, polys);
        cum_area = cumulative_areas(world);
    }
    std::vector<std::vector<RankedOccluder>> per_cell(static_cast<size_t>(n_cells));
    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    ctx.progress_begin("occluder ranking", uint64_t(n_cells), "cells");
    deal.begin(uint64_t(n_cells));
#pragma omp parallel
    {
        std::vector<glm::vec3> eyes;
        for_each_dealt(deal, ctx, 16, [&](uint64_t c) {
            eyes.clear();
            sample_eye_points(cells, uint32_t(c), config.eyes_per_cell, config.seed, eyes);
            if (sight) {
                rank_cell_by_sight(config, *sight, world, cum_area, boxes, usable, occludees,
                                   pvs->row(uint32_t(c)), eyes, uint32_t(c), per_cell[size_t(c)]);
            } else if (!by_sight) {
                rank_cell_occluders(config, boxes, usable, occludees, eyes, per_cell[size_t(c)]);
            }
        });
    }
    if (deal.processes() > 1) {  // every process gets every cell's list
        RankRecords records(per_cell.size(), config.occluders_per_cell);
        for (size_t c = 0; c < per_cell.size(); ++c)
            if (!per_cell[c].empty()) records.put(c, per_cell[c]);
        deal.unite(records.words(), records.size());
        for (size_t c = 0; c < per_cell.size(); ++c) records.get(c, per_cell[c]);
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
        "occluder ranking ({}): {} of {} boxes usable, {:.2f} ranked per cell ({} cells with none), "
        "{:.2f} s",
        by_sight ? "by sight" : "by solid angle and depth complexity", usable.size(), occluders.size(),
        n_cells > 0 ? double(ranked.entries.size()) / double(n_cells) : 0.0, figures.cells_with_none,
        figures.seconds));
    return ranked;
}

}  // namespace pvs
