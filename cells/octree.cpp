// SPDX-License-Identifier: MIT
// Visibility-driven octree of view cells: split where the children's PVSs differ, down to a minimum size.
#include "cells/octree.h"

#include "cells/eyes.h"
#include "cells/grid.h"
#include "core/error.h"

#include <fmt/format.h>

#include <cmath>

namespace pvs {

namespace {

uint32_t row_count(const PvsSet& p, uint32_t r) {
    return p.count(r);
}

uint32_t row_difference(const PvsSet& a, uint32_t ra, const PvsSet& b, uint32_t rb) {
    uint32_t n = 0;
    for (uint32_t w = 0; w < a.words_per_row; ++w)
        n += uint32_t(__builtin_popcountll(a.row(ra)[w] ^ b.row(rb)[w]));
    return n;
}

// Does the box hold eye space (the octree keeps only such nodes, as the grid keeps only such cells)?
bool has_view(const CellSet& masks, const Aabb& box) {
    if (!masks.eyes.empty()) return mask_meets_box(masks.eyes, box);
    return masks.view.empty() || mask_meets_box(masks.view, box);
}

}  // namespace

CellSet build_octree(Context& ctx, const CellConfig& config, const CellSet& masks, const Aabb& region,
                     uint32_t object_count, const RegionPvsOracle& oracle, PvsSet& leaf_pvs,
                     OctreeStats& stats) {
    ScopedTimer timer(ctx, "octree");
    const double root_size = largest_cell_edge_m(config);
    const int levels = int(std::lround(std::log2(root_size / config.min_cell_size_m)));
    CellConfig root_config = config;
    root_config.cell_size_m = root_size;
    CellSet roots = build_uniform_grid(ctx, root_config, region);

    CellSet out;
    out.kind = CellSet::Kind::kOctree;
    out.origin = roots.origin;
    out.cell_size_m = roots.cell_size_m;
    out.dims = roots.dims;
    out.grid_to_cell.assign(roots.grid_to_cell.size(), -1);
    out.view = masks.view;
    out.eyes = masks.eyes;

    // Node PVS rows live in one growing PvsSet, indexed by node.
    std::vector<uint32_t> row_of_node;  // node -> row in `rows`, or UINT32_MAX
    PvsSet rows = PvsSet::make(0, object_count);
    auto evaluate = [&](const std::vector<int32_t>& node_ids) {
        if (node_ids.empty()) return;
        std::vector<Aabb> boxes;
        std::vector<uint64_t> streams;
        std::vector<const uint64_t*> bounds;  // into `rows`, which grows only after the oracle returns
        for (int32_t n : node_ids) {
            boxes.push_back(out.nodes[size_t(n)].bounds);
            streams.push_back((uint64_t(1) << 40) + uint64_t(n));
            const int32_t parent = out.nodes[size_t(n)].parent;
            bounds.push_back(parent >= 0 && size_t(parent) < row_of_node.size() &&
                                     row_of_node[size_t(parent)] != UINT32_MAX
                                 ? rows.row(row_of_node[size_t(parent)])
                                 : nullptr);
        }
        PvsSet batch = PvsSet::make(uint32_t(boxes.size()), object_count);
        oracle(boxes, streams, bounds, batch);
        const uint32_t first = rows.cell_count;
        rows.cell_count += batch.cell_count;
        rows.words.insert(rows.words.end(), batch.words.begin(), batch.words.end());
        row_of_node.resize(out.nodes.size(), UINT32_MAX);
        for (size_t i = 0; i < node_ids.size(); ++i) row_of_node[size_t(node_ids[i])] = first + uint32_t(i);
        stats.evaluated += uint32_t(node_ids.size());
    };

    std::vector<int32_t> frontier;
    for (size_t g = 0; g < roots.grid_to_cell.size(); ++g) {
        const int32_t c = roots.grid_to_cell[g];
        if (c < 0 || !has_view(masks, roots.cells[size_t(c)].bounds)) continue;
        out.grid_to_cell[g] = int32_t(out.nodes.size());
        out.nodes.push_back(OctreeNode{roots.cells[size_t(c)].bounds, -1, -1, -1});
        frontier.push_back(out.grid_to_cell[g]);
    }
    stats.roots = uint32_t(frontier.size());
    ctx.info(fmt::format("octree: {} root cells of {} m, down to {} m ({} levels), split threshold {}",
                         frontier.size(), root_size, config.min_cell_size_m, levels, config.split_threshold));
    // One progress per level, with its box count known in advance (an ETA for the long levels).
    ctx.progress_begin(fmt::format("octree roots of {} m", root_size), frontier.size(), "boxes");
    evaluate(frontier);
    ctx.progress_end();
    uint64_t leaves = frontier.size();
    for (uint32_t depth = 0; !frontier.empty(); ++depth) {
        // Children of every node that may split, evaluated in one batch.
        std::vector<int32_t> parents, children;
        for (int32_t n : frontier) {
            const Aabb b = out.nodes[size_t(n)].bounds;
            if (b.size().x < 2.0f * float(config.min_cell_size_m) * 0.999f) continue;  // children below min
            parents.push_back(n);
            const glm::vec3 c = b.center();
            const int32_t first = int32_t(out.nodes.size());
            for (int o = 0; o < 8; ++o) {
                Aabb cb;
                cb.min = glm::vec3(o & 1 ? c.x : b.min.x, o & 2 ? c.y : b.min.y, o & 4 ? c.z : b.min.z);
                cb.max = glm::vec3(o & 1 ? b.max.x : c.x, o & 2 ? b.max.y : c.y, o & 4 ? b.max.z : c.z);
                out.nodes.push_back(OctreeNode{cb, -1, -1, n});
            }
            out.nodes[size_t(n)].first_child = first;  // provisional: undone if not split
            for (int o = 0; o < 8; ++o)
                if (has_view(masks, out.nodes[size_t(first + o)].bounds)) children.push_back(first + o);
        }
        if (!children.empty()) {
            ctx.progress_begin(fmt::format("octree level {} of {}, {} m", depth + 1, levels,
                                           root_size / double(uint64_t(1) << (depth + 1))),
                               children.size(), "boxes");
            evaluate(children);  // the oracle advances the progress per box
            ctx.progress_end();
        }
        std::vector<int32_t> next;
        for (int32_t n : parents) {
            const int32_t first = out.nodes[size_t(n)].first_child;
            const uint32_t pr = row_of_node[size_t(n)];
            const double parent_size = std::max(1u, row_count(rows, pr));
            uint32_t worst = 0, with_view = 0;
            for (int o = 0; o < 8; ++o) {
                const uint32_t cr = row_of_node[size_t(first + o)];
                if (cr == UINT32_MAX) continue;
                ++with_view;
                worst = std::max(worst, row_difference(rows, pr, rows, cr));
            }
            const bool differs = double(worst) > config.split_threshold * parent_size;
            const bool budget_ok = config.max_cells == 0 || leaves - 1 + with_view <= config.max_cells;
            if (differs && budget_ok) {
                ++stats.splits;
                leaves += with_view - 1;
                stats.depth = std::max(stats.depth, depth + 1);
                for (int o = 0; o < 8; ++o)
                    if (row_of_node[size_t(first + o)] != UINT32_MAX) next.push_back(first + o);
            } else {
                if (differs) stats.budget_reached = true;
                ++stats.merged;
                out.nodes[size_t(n)].first_child = -1;  // the children stay in the array, unreachable
            }
        }
        frontier = std::move(next);
    }

    // Compact: keep reachable nodes (breadth-first from the roots, children consecutive), number the
    // leaves with view volume as cells.
    std::vector<OctreeNode> kept;
    std::vector<int32_t> remap(out.nodes.size(), -1);
    std::vector<int32_t> queue;
    for (int32_t& root : out.grid_to_cell) {
        if (root < 0) continue;
        remap[size_t(root)] = int32_t(kept.size());
        kept.push_back(out.nodes[size_t(root)]);
        kept.back().parent = -1;
        queue.push_back(root);
        root = remap[size_t(root)];
    }
    std::vector<uint32_t> cell_rows;
    for (size_t q = 0; q < queue.size(); ++q) {
        const int32_t old = queue[q];
        const int32_t now = remap[size_t(old)];
        const int32_t first = out.nodes[size_t(old)].first_child;
        if (first < 0) {
            if (row_of_node.size() > size_t(old) && row_of_node[size_t(old)] != UINT32_MAX) {
                kept[size_t(now)].cell = int32_t(out.cells.size());
                out.cells.push_back(Cell{kept[size_t(now)].bounds, kept[size_t(now)].parent});
                cell_rows.push_back(row_of_node[size_t(old)]);
            }
            continue;
        }
        kept[size_t(now)].first_child = int32_t(kept.size());
        for (int o = 0; o < 8; ++o) {
            remap[size_t(first + o)] = int32_t(kept.size());
            kept.push_back(out.nodes[size_t(first + o)]);
            kept.back().parent = now;
            kept.back().first_child = out.nodes[size_t(first + o)].first_child;
            queue.push_back(first + o);
        }
    }
    out.nodes = std::move(kept);
    leaf_pvs = PvsSet::make(uint32_t(out.cells.size()), object_count);
    for (size_t c = 0; c < cell_rows.size(); ++c) {
        std::copy(rows.row(cell_rows[c]), rows.row(cell_rows[c]) + rows.words_per_row,
                  leaf_pvs.row(uint32_t(c)));
    }
    ctx.info(
        fmt::format("octree: {} cells from {} roots; {} splits where visibility differed, {} merged back, "
                    "{} boxes evaluated, depth {}{}",
                    out.cells.size(), stats.roots, stats.splits, stats.merged, stats.evaluated, stats.depth,
                    stats.budget_reached ? " (cell budget reached)" : ""));
    return out;
}

}  // namespace pvs
