// SPDX-License-Identifier: MIT
// The visibility-driven octree: small cells where visibility changes (a maze), big ones where it does
// not (an open field); lookups descend to the right leaf.
#include "cells/octree.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Under one roof (y in [0, 3]): x in [0, 16] an open hall with a pillar per corner; a solid wall at
// x = 16; x in [16, 32] a maze of 2 m rooms.
World field_and_maze();

// Eyes only under the roof: a mask of 0.5 m voxels filling [0, 32] x [0, 3] x [0, 16].
CellSet under_the_roof() {
    CellSet masks;
    VoxelMask m;
    m.origin = glm::vec3(0.0f);
    m.voxel_size_m = 0.5f;
    m.dims = glm::ivec3(64, 6, 32);
    m.bits.assign((m.count() + 63) / 64, ~uint64_t(0));
    if (m.count() % 64) m.bits.back() &= (uint64_t(1) << (m.count() % 64)) - 1;
    masks.view = m;
    masks.eyes = m;
    return masks;
}

World field_and_maze() {
    World w;
    test::add_box(w, "ground", Aabb::of({0, -0.2f, 0}, {32, 0, 16}));
    test::add_box(w, "roof", Aabb::of({0, 3, 0}, {32, 3.2f, 16}));
    test::add_box(w, "divide", Aabb::of({15.8f, 0, 0}, {16.0f, 3, 16}));
    for (float x : {1.0f, 14.5f})
        for (float z : {1.0f, 14.5f})
            test::add_box(w, "pillar", Aabb::of({x, 0, z}, {x + 0.5f, 3, z + 0.5f}));
    int n = 0;
    for (int i = 1; i <= 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            const float x = 16.0f + 2.0f * float(i), z = 2.0f * float(j);
            // Walls along z at every 2 m in x, each with a doorway in a different place; and along x.
            test::add_box(w, "wall_x" + std::to_string(n++),
                          Aabb::of({x - 0.1f, 0, z}, {x + 0.1f, 3, z + (j % 2 ? 2.0f : 1.2f)}));
            if (i < 8)
                test::add_box(w, "wall_z" + std::to_string(n++),
                              Aabb::of({x + (i % 2 ? 0.8f : 0.0f), 0, z - 0.1f},
                                       {x + (i % 2 ? 2.0f : 1.2f), 3, z + 0.1f}));
        }
    }
    return w;
}

// The sampled mode as the octree's oracle (the objects must outlive the oracle).
RegionPvsOracle sampled_oracle(const SampledPvsConfig& sc, const World& w, const RayScene& scene,
                               const CellSet& masks) {
    return [&sc, &w, &scene, &masks](const std::vector<Aabb>& boxes, const std::vector<uint64_t>& streams,
                                     const std::vector<const uint64_t*>&, PvsSet& rows) {
        uint64_t guard = 0;
        sample_box_rows(sc, w, scene, masks, boxes, streams, sc.rays.rays_per_eye, rows, guard, nullptr);
    };
}

TEST(Octree, TheMazeGetsTheSmallCells) {
    Context ctx = quiet_context();
    const World w = field_and_maze();
    RayScene scene(ctx, w);
    SampledPvsConfig sc;
    sc.rays = SampleConfig{8, 512, 0, 3};
    const CellSet masks = under_the_roof();
    const RegionPvsOracle oracle = sampled_oracle(sc, w, scene, masks);
    CellConfig cc;
    cc.kind = CellKind::kOctree;
    cc.min_cell_size_m = 1.0;
    cc.root_cell_size_m = 8.0;
    cc.split_threshold = 0.3;
    PvsSet leaf;
    OctreeStats stats;
    const CellSet cells = build_octree(ctx, cc, masks, Aabb::of({0, 0, 0}, {32, 3, 16}),
                                       uint32_t(w.objects.size()), oracle, leaf, stats);
    ASSERT_GT(cells.size(), 0u);
    EXPECT_EQ(leaf.cell_count, cells.size());
    double field_edge = 0, maze_edge = 0;
    int field_n = 0, maze_n = 0;
    for (const Cell& c : cells.cells) {
        (c.bounds.center().x < 16 ? field_edge : maze_edge) += c.bounds.size().x;
        (c.bounds.center().x < 16 ? field_n : maze_n)++;
    }
    ASSERT_GT(field_n, 0);
    ASSERT_GT(maze_n, 0);
    EXPECT_GT(maze_n, 4 * field_n);
    EXPECT_LT(maze_edge / maze_n, 0.5 * field_edge / field_n);
    EXPECT_GT(stats.splits, 0u);
    EXPECT_GT(stats.merged, 0u);
    // Every point finds the leaf that holds it.
    for (const glm::vec3 p :
         {glm::vec3(3, 1, 3), glm::vec3(20.3f, 1.4f, 5.1f), glm::vec3(31.9f, 2.9f, 15.9f)}) {
        const int32_t c = cells.find(p);
        ASSERT_GE(c, 0);
        EXPECT_TRUE(cells.cells[size_t(c)].bounds.contains(p));
    }
    EXPECT_EQ(cells.find({-1, 1, 1}), -1);
}

TEST(Octree, NeverSplitsBelowTheMinimumAndStopsAtTheBudget) {
    Context ctx = quiet_context();
    const World w = field_and_maze();
    RayScene scene(ctx, w);
    SampledPvsConfig sc;
    sc.rays = SampleConfig{4, 256, 0, 3};
    CellSet masks;
    const RegionPvsOracle oracle = sampled_oracle(sc, w, scene, masks);
    CellConfig cc;
    cc.kind = CellKind::kOctree;
    cc.min_cell_size_m = 2.0;
    cc.root_cell_size_m = 8.0;
    cc.split_threshold = 0.0;  // split wherever anything differs
    PvsSet leaf;
    OctreeStats stats;
    const CellSet all = build_octree(ctx, cc, masks, Aabb::of({0, 0, 0}, {32, 3, 16}),
                                     uint32_t(w.objects.size()), oracle, leaf, stats);
    for (const Cell& c : all.cells) EXPECT_GE(c.bounds.size().x, 2.0f - 1e-4f);
    cc.max_cells = 20;
    OctreeStats limited;
    const CellSet few = build_octree(ctx, cc, masks, Aabb::of({0, 0, 0}, {32, 3, 16}),
                                     uint32_t(w.objects.size()), oracle, leaf, limited);
    EXPECT_LE(few.size(), 20u);
    EXPECT_TRUE(limited.budget_reached);
    EXPECT_LT(few.size(), all.size());
}

TEST(Octree, CountsEachBoxOnceInItsProgress) {
    // The oracle advances the progress per box (RegionPvsOracle); the octree begins one progress per call
    // whose total is that call's box count (a level's ETA), and must not add the batch again, or the
    // count and the boxes/s rate of a long bake read twice what they are.
    Context ctx = quiet_context();
    std::vector<uint64_t> totals;
    const RegionPvsOracle oracle = [&ctx, &totals](const std::vector<Aabb>& boxes,
                                                   const std::vector<uint64_t>&,
                                                   const std::vector<const uint64_t*>&, PvsSet& rows) {
        EXPECT_EQ(ctx.progress_done(), 0u) << "a call's progress starts at zero";
        totals.push_back(ctx.progress_total());
        // Boxes at the region's left edge see object 0, the others object 1: the left edge splits.
        for (uint32_t i = 0; i < boxes.size(); ++i) {
            const uint32_t o = boxes[i].min.x < 0.5f ? 0u : 1u;
            rows.row(i)[0] |= uint64_t(1) << o;
            ctx.progress_advance();
        }
        EXPECT_EQ(totals.back(), boxes.size()) << "the progress total is the call's box count";
    };
    CellConfig cc;
    cc.kind = CellKind::kOctree;
    cc.min_cell_size_m = 1.0;
    cc.root_cell_size_m = 8.0;
    PvsSet leaf;
    OctreeStats stats;
    const CellSet cells =
        build_octree(ctx, cc, CellSet{}, Aabb::of({0, 0, 0}, {16, 8, 8}), 2, oracle, leaf, stats);
    EXPECT_GT(stats.splits, 0u);
    EXPECT_GT(stats.evaluated, stats.roots);
    EXPECT_GT(cells.size(), 2u);
    ASSERT_GE(totals.size(), 2u);
    EXPECT_EQ(totals.front(), stats.roots);
    EXPECT_EQ(ctx.progress_done(), totals.back()) << "the last level counted once";
    uint64_t sum = 0;
    for (uint64_t t : totals) sum += t;
    EXPECT_EQ(sum, stats.evaluated);
}

}  // namespace
}  // namespace pvs
