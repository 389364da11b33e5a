// SPDX-License-Identifier: MIT
// The run-time horizon's lists per block of cells (occluders/horizon_lists.h;
// docs/ALGORITHMS.md#horizon-lists): the runtime's own horizon (runtime/pvsr.c) from seeded eyes of each
// block's cells, every candidate given and tagged, names the occluders that proved some object of the eye's
// PVS hidden. Blocks are dealt to the threads and processes of the bake (core/work_share.h); each block's
// result is a bit set of its own, united over the processes, so the lists do not depend on who chose which
// block.
#include "occluders/horizon_lists.h"

#include "cells/eyes.h"
#include "core/error.h"
#include "runtime/pvsr.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <memory>

namespace pvs {

namespace {

// Pieces an eye's horizon holds (past them the rest of its candidates are dropped: fewer chosen, never
// unsafe; counted in the figures).
constexpr size_t kMaxPieces = size_t(1) << 17;  // about 21 MB a thread
constexpr uint64_t kEyeSeedMix = 0x686f72697a6f6eULL;  // the horizon's eyes differ from the ranking's
constexpr uint64_t kCellEyeSeedMix = 0x63656c6c6c697374ULL;  // and the cells' own lists' from the blocks'

// The candidates as the runtime takes them.
struct Candidates {
    std::vector<float> boxes;     // 6 floats a box
    std::vector<float> planes;    // 5 floats a tile
    std::vector<uint32_t> first;  // a tile's first corner in `corners` (3 floats a corner)
    std::vector<uint32_t> count;
    std::vector<float> corners;
    uint32_t box_count() const { return uint32_t(boxes.size() / 6); }
    uint32_t size() const { return box_count() + uint32_t(first.size()); }
};

Candidates candidates_of(const std::vector<Aabb>& boxes, const std::vector<OccluderPolygon>& tiles) {
    Candidates c;
    for (const Aabb& b : boxes)
        c.boxes.insert(c.boxes.end(), {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z});
    for (const OccluderPolygon& t : tiles) {
        c.planes.insert(c.planes.end(), {t.normal.x, t.normal.y, t.normal.z, t.offset, t.thickness});
        c.first.push_back(uint32_t(c.corners.size() / 3));
        c.count.push_back(uint32_t(t.corners.size()));
        for (const glm::vec3& p : t.corners) c.corners.insert(c.corners.end(), {p.x, p.y, p.z});
    }
    return c;
}

void build(pvsr_horizon* h, const Candidates& c, const glm::vec3& eye) {
    const float e[3] = {eye.x, eye.y, eye.z};
    pvsr_horizon_begin(h, e);
    const uint32_t nb = c.box_count();
    for (uint32_t i = 0; i < nb; ++i) {
        pvsr_horizon_set_tag(h, i);
        pvsr_horizon_add_box(h, &c.boxes[6 * size_t(i)]);
    }
    for (uint32_t t = 0; t < c.first.size(); ++t) {
        pvsr_horizon_set_tag(h, nb + t);
        pvsr_horizon_add_tile(h, &c.planes[5 * size_t(t)], &c.corners[3 * size_t(c.first[t])], c.count[t]);
    }
    pvsr_horizon_end(h);
}

// The horizon of the candidates whose bits are set (a block's list), each tagged with its index.
void build_some(pvsr_horizon* h, const Candidates& c, const uint64_t* bits, size_t words,
                const glm::vec3& eye) {
    const float e[3] = {eye.x, eye.y, eye.z};
    pvsr_horizon_begin(h, e);
    const uint32_t nb = c.box_count();
    for (size_t w = 0; w < words; ++w)
        for (uint64_t u = bits[w]; u != 0; u &= u - 1) {
            const uint32_t i = uint32_t(64 * w) + uint32_t(__builtin_ctzll(u));
            pvsr_horizon_set_tag(h, i);
            if (i < nb) {
                pvsr_horizon_add_box(h, &c.boxes[6 * size_t(i)]);
            } else {
                const uint32_t t = i - nb;
                pvsr_horizon_add_tile(h, &c.planes[5 * size_t(t)], &c.corners[3 * size_t(c.first[t])],
                                      c.count[t]);
            }
        }
    pvsr_horizon_end(h);
}

// Per candidate, the proofs of the block's eyes it served in (saturating).
void count_use(void* user, uint32_t tag) {
    uint32_t& n = (*static_cast<std::vector<uint32_t>*>(user))[tag];
    n += n < UINT32_MAX ? 1u : 0u;
}

// The list of a block or a cell: the candidates used in at least horizon_min_uses proofs, the most used
// first, at most horizon_list_max of them (0: no limit), set in `bits`.
void keep_used(const RankingConfig& config, const std::vector<uint32_t>& uses,
               std::vector<std::pair<uint32_t, uint32_t>>& ranked, uint64_t* bits) {
    ranked.clear();
    for (uint32_t i = 0; i < uint32_t(uses.size()); ++i)
        if (uses[i] >= std::max<uint32_t>(config.horizon_min_uses, 1)) ranked.push_back({uses[i], i});
    size_t keep = ranked.size();
    if (config.horizon_list_max > 0 && keep > config.horizon_list_max) {
        keep = config.horizon_list_max;
        std::partial_sort(ranked.begin(), ranked.begin() + long(keep), ranked.end(),
                          [](const auto& x, const auto& y) {
                              return x.first != y.first ? x.first > y.first : x.second < y.second;
                          });
    }
    for (size_t r = 0; r < keep; ++r) bits[ranked[r].second >> 6] |= uint64_t(1) << (ranked[r].second & 63);
}

// The tags of a proof, kept until every part of the object is known hidden.
void keep_tag(void* user, uint32_t tag) {
    static_cast<std::vector<uint32_t>*>(user)->push_back(tag);
}

}  // namespace

uint32_t horizon_block_count(const CellSet& cells) {
    if (cells.kind != CellSet::Kind::kGrid)
        return uint32_t((uint64_t(cells.size()) + kHorizonBlockCells - 1) / kHorizonBlockCells);
    uint32_t n = 1;
    for (int a = 0; a < 3; ++a)
        n *= (uint32_t(std::max(cells.dims[a], 0)) + kHorizonBlockSide - 1) / kHorizonBlockSide;
    return n;
}

std::vector<uint32_t> horizon_blocks(const CellSet& cells) {
    std::vector<uint32_t> block(cells.size(), 0);
    if (cells.kind != CellSet::Kind::kGrid) {
        for (uint32_t c = 0; c < block.size(); ++c) block[c] = c / kHorizonBlockCells;
        return block;
    }
    const uint32_t d0 = uint32_t(cells.dims.x), d1 = uint32_t(cells.dims.y);
    const uint32_t n0 = (d0 + kHorizonBlockSide - 1) / kHorizonBlockSide;
    const uint32_t n1 = (d1 + kHorizonBlockSide - 1) / kHorizonBlockSide;
    for (uint32_t g = 0; g < cells.grid_to_cell.size(); ++g) {
        const int32_t c = cells.grid_to_cell[g];
        if (c < 0 || size_t(c) >= block.size()) continue;
        block[size_t(c)] = g % d0 / kHorizonBlockSide +
                           n0 * (g / d0 % d1 / kHorizonBlockSide + n1 * (g / (d0 * d1) / kHorizonBlockSide));
    }
    return block;
}

HorizonLists choose_horizon_lists(Context& ctx, const RankingConfig& config, const World& world,
                                  const CellSet& cells, const PvsSet& pvs, const std::vector<Aabb>& boxes,
                                  const std::vector<OccluderPolygon>& tiles, HorizonListFigures& figures,
                                  WorkShare* share, const ObjectParts* parts) {
    figures = HorizonListFigures{};
    HorizonLists out;
    const Candidates cand = candidates_of(boxes, tiles);
    figures.candidates = cand.size();
    if (config.horizon_eyes == 0 || cand.size() == 0 || cells.size() == 0) return out;
    if (pvs.cell_count != cells.size() || pvs.object_count != world.objects.size())
        throw internal_error("horizon lists: the PVS does not match the cells and objects");
    ScopedTimer timer(ctx, "horizon_lists");
    const auto start = std::chrono::steady_clock::now();

    const std::vector<uint32_t> block_of = horizon_blocks(cells);
    const uint32_t blocks = horizon_block_count(cells);
    std::vector<std::vector<uint32_t>> block_cells(blocks);
    for (uint32_t c = 0; c < cells.size(); ++c) block_cells[block_of[c]].push_back(c);
    const size_t words = (size_t(cand.size()) + 63) / 64;
    std::vector<uint64_t> used(size_t(blocks) * words, 0);  // per block, the candidates its eyes used
    std::vector<float> bounds(6 * world.objects.size());
    std::vector<uint8_t> testable(world.objects.size(), 0);
    for (size_t o = 0; o < world.objects.size(); ++o) {
        const Aabb& b = world.objects[o].bounds;
        const float f[6] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
        std::copy(f, f + 6, &bounds[6 * o]);
        testable[o] = (world.objects[o].flags & kObjectAlwaysVisible) == 0 && !b.is_empty();
    }

    // The proofs of the eye's horizon h over cell c's PVS, counted per candidate in `uses`: an object hidden
    // by its bounds, or by every one of its parts (core/object_parts.h), as the runtime's walk culls it.
    // With `culled`, the objects hidden are set there (a row of the PVS's width).
    const auto tally = [&](const pvsr_horizon& h, uint32_t c, std::vector<uint32_t>& uses,
                           std::vector<uint32_t>& part_tags, uint64_t* culled) {
        const uint64_t* row = pvs.row(c);
        for (uint32_t w = 0; w < pvs.words_per_row; ++w)
            for (uint64_t bits = row[w]; bits != 0; bits &= bits - 1) {
                const uint32_t o = 64 * w + uint32_t(__builtin_ctzll(bits));
                if (o >= testable.size() || !testable[o]) continue;
                bool hidden = pvsr_horizon_hidden_by(&h, &bounds[6 * size_t(o)], count_use, &uses) != 0;
                const uint32_t n_parts = parts ? parts->count(o) : 0;
                if (!hidden && n_parts > 0) {
                    part_tags.clear();
                    hidden = true;
                    for (uint32_t k = 0; k < n_parts && hidden; ++k) {
                        const Aabb& p = parts->boxes[parts->offsets[o] + k];
                        const float pb[6] = {p.min.x, p.min.y, p.min.z, p.max.x, p.max.y, p.max.z};
                        hidden = pvsr_horizon_hidden_by(&h, pb, keep_tag, &part_tags) != 0;
                    }
                    if (hidden)
                        for (const uint32_t t : part_tags) count_use(&uses, t);
                }
                if (hidden && culled != nullptr) culled[w] |= uint64_t(1) << (o & 63);
            }
    };

    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    const int columns = int(config.horizon_columns);
    const size_t memory_bytes = pvsr_horizon_memory_bytes(columns, kMaxPieces);
    // One pass over the blocks, dealt to threads and processes: work(b, thread) for each; its bit sets
    // (`bits`) united over the processes and its eyes counted in `counts` (eyes, pieces dropped).
    struct Thread {
        pvsr_horizon h;
        std::vector<glm::vec3> eyes;
        std::vector<uint32_t> uses, part_tags;
        std::vector<std::pair<uint32_t, uint32_t>> ranked;  // (uses, candidate)
        uint64_t eyes_done = 0, dropped = 0;
    };
    // One eye e of cell c: the horizon `fill` builds, its proofs over c's PVS counted in t.uses.
    const auto look = [&](Thread& t, const glm::vec3& e, uint32_t c, const auto& fill, uint64_t* culled) {
        fill(&t.h, e);
        ++t.eyes_done;
        t.dropped += t.h.dropped;
        tally(t.h, c, t.uses, t.part_tags, culled);
    };
    std::vector<uint64_t> counts(2, 0);
    const auto pass = [&](const char* what, std::vector<uint64_t>& bits, const auto& work) {
        ctx.progress_begin(what, blocks, "blocks");
        deal.begin(blocks);
        bool failed = false;
#pragma omp parallel
        {
            std::vector<uint64_t> memory(memory_bytes / 8 + 1);
            Thread t;
            const bool ok =
                pvsr_horizon_init(&t.h, columns, kMaxPieces, memory.data(), memory.size() * 8) != 0;
            t.uses.assign(cand.size(), 0);
            for_each_dealt(deal, ctx, 1, [&](uint64_t b) {
                if (ok) work(uint32_t(b), t);
            });
#pragma omp critical(horizon_lists_counts)
            {
                counts[0] += t.eyes_done;
                counts[1] += t.dropped;
                failed |= !ok;
            }
        }
        if (failed) throw internal_error("horizon lists: a horizon did not take its memory");
        deal.unite(bits.data(), bits.size());
        ctx.progress_end();
    };

    // Each block's list: horizon_eyes spread evenly over the block's cells (in cell order), each eye's
    // horizon built from every candidate.
    pass("horizon lists", used, [&](uint32_t b, Thread& t) {
        const std::vector<uint32_t>& mine = block_cells[b];
        std::fill(t.uses.begin(), t.uses.end(), 0u);
        const uint32_t n = uint32_t(mine.size());
        for (uint32_t k = 0; k < n; ++k) {
            const uint32_t share_of = uint32_t((uint64_t(k + 1) * config.horizon_eyes) / n -
                                               (uint64_t(k) * config.horizon_eyes) / n);
            if (share_of == 0) continue;
            t.eyes.clear();
            sample_eye_points(cells, mine[k], share_of, config.seed ^ kEyeSeedMix, t.eyes);
            for (const glm::vec3& e : t.eyes)
                look(
                    t, e, mine[k], [&](pvsr_horizon* h, const glm::vec3& at) { build(h, cand, at); },
                    nullptr);
        }
        keep_used(config, t.uses, t.ranked, used.data() + size_t(b) * words);
    });

    // Lists per cell: each cell's own, the occluders of its block's list that the proofs of
    // horizon_cell_eyes eyes of the cell used, each eye's horizon built from that list alone; where the cells
    // times their blocks' lists are at most horizon_cell_lists_max (entries). A subset of proven occluders,
    // as any list.
    uint64_t cell_pairs = 0;
    for (uint32_t c = 0; c < cells.size(); ++c)
        for (size_t w = 0; w < words; ++w)
            cell_pairs += uint64_t(__builtin_popcountll(used[size_t(block_of[c]) * words + w]));
    const bool per_cell = config.horizon_cell_eyes > 0 && double(cell_pairs) <= config.horizon_cell_lists_max;
    // With horizon_cell_tests, each cell also keeps the objects of its PVS those eyes' horizons hid (by
    // bounds or by every part): its frames test only those (docs/ALGORITHMS.md#horizon-tests).
    std::vector<uint64_t> cell_used, cell_culled;
    const bool tests = per_cell && config.horizon_cell_tests;
    if (per_cell) {
        cell_used.assign(size_t(cells.size()) * words, 0);
        if (tests) cell_culled.assign(size_t(cells.size()) * pvs.words_per_row, 0);
        pass("horizon cell lists", cell_used, [&](uint32_t b, Thread& t) {
            const uint64_t* pool = used.data() + size_t(b) * words;
            for (const uint32_t c : block_cells[b]) {
                std::fill(t.uses.begin(), t.uses.end(), 0u);
                t.eyes.clear();
                sample_eye_points(cells, c, config.horizon_cell_eyes, config.seed ^ kCellEyeSeedMix, t.eyes);
                uint64_t* culled = tests ? cell_culled.data() + size_t(c) * pvs.words_per_row : nullptr;
                for (const glm::vec3& e : t.eyes)
                    look(
                        t, e, c,
                        [&](pvsr_horizon* h, const glm::vec3& at) { build_some(h, cand, pool, words, at); },
                        culled);
                keep_used(config, t.uses, t.ranked, cell_used.data() + size_t(c) * words);
            }
        });
        if (tests) deal.unite(cell_culled.data(), cell_culled.size());
    }
    deal.add(counts.data(), counts.size());
    const std::vector<uint64_t>& chosen = per_cell ? cell_used : used;
    const uint32_t n_lists = per_cell ? uint32_t(cells.size()) : blocks;

    // Keep the candidates some list names, in their order; the lists in the kept indices.
    std::vector<uint64_t> any(words, 0);
    for (uint32_t b = 0; b < n_lists; ++b)
        for (size_t w = 0; w < words; ++w) any[w] |= chosen[size_t(b) * words + w];
    std::vector<uint32_t> index(cand.size(), UINT32_MAX);
    for (uint32_t i = 0; i < cand.size(); ++i) {
        if (((any[i >> 6] >> (i & 63)) & 1u) == 0) continue;
        if (i < cand.box_count()) {
            index[i] = uint32_t(out.boxes.size());
            out.boxes.push_back(boxes[i]);
        }
    }
    for (uint32_t i = cand.box_count(); i < cand.size(); ++i) {
        if (((any[i >> 6] >> (i & 63)) & 1u) == 0) continue;
        index[i] = uint32_t(out.boxes.size() + out.tiles.size());
        out.tiles.push_back(tiles[i - cand.box_count()]);
    }
    out.offsets.reserve(size_t(n_lists) + 1);
    out.offsets.push_back(0);
    for (uint32_t b = 0; b < n_lists; ++b) {
        const uint64_t* u = chosen.data() + size_t(b) * words;
        for (size_t w = 0; w < words; ++w)
            for (uint64_t bits = u[w]; bits != 0; bits &= bits - 1)
                out.entries.push_back(index[64 * w + size_t(__builtin_ctzll(bits))]);
        out.offsets.push_back(uint32_t(out.entries.size()));
        figures.largest_list = std::max(figures.largest_list, out.offsets[b + 1] - out.offsets[b]);
    }
    if (per_cell) {
        out.cell_list.resize(cells.size());
        for (uint32_t c = 0; c < cells.size(); ++c) out.cell_list[c] = c;
        if (tests) {
            out.test_offsets.reserve(size_t(cells.size()) + 1);
            out.test_offsets.push_back(0);
            for (uint32_t c = 0; c < cells.size(); ++c) {
                const uint64_t* culled = cell_culled.data() + size_t(c) * pvs.words_per_row;
                for (uint32_t w = 0; w < pvs.words_per_row; ++w)
                    for (uint64_t bits = culled[w]; bits != 0; bits &= bits - 1)
                        out.tests.push_back(64 * w + uint32_t(__builtin_ctzll(bits)));
                out.test_offsets.push_back(uint32_t(out.tests.size()));
            }
            figures.tests = out.tests.size();
        }
    } else {
        out.cell_list = block_of;
    }
    figures.kept = uint32_t(out.occluders());
    figures.lists = n_lists;
    figures.per_cell = per_cell;
    figures.entries = out.entries.size();
    figures.eyes = counts[0];
    figures.pieces_dropped = counts[1];
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "horizon lists: {} of {} candidate occluders kept, {} lists (per {}) of {:.1f} on average "
        "(the longest {}), from {} eyes, {:.2f} s",
        figures.kept, figures.candidates, n_lists, per_cell ? "cell" : "block of cells",
        n_lists > 0 ? double(figures.entries) / double(n_lists) : 0.0, figures.largest_list, figures.eyes,
        figures.seconds));
    if (tests)
        ctx.info(fmt::format("horizon lists: a cell's frames test {:.1f} objects of its PVS on average",
                             cells.size() > 0 ? double(figures.tests) / double(cells.size()) : 0.0));
    if (figures.pieces_dropped > 0)
        ctx.info(
            fmt::format("horizon lists: {} pieces found no room in an eye's horizon (fewer occluders "
                        "chosen)",
                        figures.pieces_dropped));
    return out;
}

}  // namespace pvs
