// SPDX-License-Identifier: MIT
// Occluder synthesis (occluders/boxes.h): boxes stay inside the solid (property test on random grids),
// the fast path gives exactly the reference's boxes (differential test on fixed seeds and awkward grids),
// simple shapes get the few boxes they should, and the limits of the config are honoured.
#include "core/error.h"
#include "core/random.h"
#include "occluders/boxes.h"
#include "voxels/voxels.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <functional>
#include <vector>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

VoxelGrid grid_of(glm::ivec3 dims, float voxel_size_m = 0.25f) {
    VoxelGrid g;
    g.origin = glm::vec3(-3.0f, 1.0f, 2.0f);
    g.voxel_size_m = voxel_size_m;
    g.dims = dims;
    return g;
}

void fill(const VoxelGrid& g, BitVolume& v, glm::ivec3 lo, glm::ivec3 hi, bool value) {
    lo = glm::max(lo, glm::ivec3(0));
    hi = glm::min(hi, g.dims - 1);
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) {
                if (value)
                    v.set(g.index(x, y, z));
                else
                    v.clear(g.index(x, y, z));
            }
}

// Random solid blobs: a union of random boxes, minus random holes, plus random noise voxels.
BitVolume random_blobs(const VoxelGrid& g, uint64_t seed, int blobs, int holes, float noise) {
    Rng rng(seed, 7);
    BitVolume v;
    v.reset(g.count());
    auto corner = [&] {
        return glm::ivec3(int(rng.below(uint32_t(g.dims.x))), int(rng.below(uint32_t(g.dims.y))),
                          int(rng.below(uint32_t(g.dims.z))));
    };
    auto extent = [&](int most) {
        return glm::ivec3(int(rng.below(uint32_t(most))), int(rng.below(uint32_t(most))),
                          int(rng.below(uint32_t(most))));
    };
    for (int b = 0; b < blobs; ++b) {
        const glm::ivec3 lo = corner();
        fill(g, v, lo, lo + extent(std::max(g.dims.x, g.dims.z) / 2 + 1), true);
    }
    for (int h = 0; h < holes; ++h) {
        const glm::ivec3 lo = corner();
        fill(g, v, lo, lo + extent(4), false);
    }
    for (uint64_t i = 0; i < g.count(); ++i) {
        if (rng.uniform() < noise) v.set(i);
    }
    return v;
}

// Every voxel of every box is solid and inside the grid; the union of the boxes, in voxels.
uint64_t check_inside_solid(const VoxelGrid& g, const BitVolume& solid, const std::vector<VoxelBox>& boxes) {
    std::vector<bool> cover(g.count(), false);
    uint64_t bad = 0;
    for (const VoxelBox& b : boxes) {
        EXPECT_GT(b.volume(), 0u);
        EXPECT_TRUE(g.inside(b.lo) && g.inside(b.hi)) << "box outside the grid";
        if (!g.inside(b.lo) || !g.inside(b.hi)) continue;
        for (int z = b.lo.z; z <= b.hi.z; ++z)
            for (int y = b.lo.y; y <= b.hi.y; ++y)
                for (int x = b.lo.x; x <= b.hi.x; ++x) {
                    bad += !solid.get(g.index(x, y, z));
                    cover[g.index(x, y, z)] = true;
                }
    }
    EXPECT_EQ(bad, 0u) << "voxels of boxes outside the solid";
    return uint64_t(std::count(cover.begin(), cover.end(), true));
}

TEST(GrowBoxes, EveryVoxelOfEveryBoxIsSolidOnRandomGrids) {
    Context ctx = quiet_context();
    for (uint64_t seed = 1; seed <= 24; ++seed) {
        const glm::ivec3 dims = seed % 3 == 0 ? glm::ivec3(48, 40, 56) : glm::ivec3(20 + int(seed), 16, 24);
        const VoxelGrid g = grid_of(dims);
        const BitVolume solid =
            random_blobs(g, seed, 2 + int(seed % 7), int(seed % 5) * 10, 0.02f * float(seed % 4));
        BoxConfig config;
        config.min_box_volume_m3 = 0.0;
        config.min_added_share = 0.0;
        BoxStats stats;
        const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, config, &stats);
        const uint64_t covered = check_inside_solid(g, solid, boxes);
        EXPECT_EQ(stats.covered_voxels, covered) << "seed " << seed;
        EXPECT_EQ(stats.solid_voxels, solid.count());
        EXPECT_EQ(stats.kept, boxes.size());
        EXPECT_GE(stats.grown, stats.kept);
        for (size_t k = 1; k < boxes.size(); ++k) EXPECT_GE(boxes[k - 1].volume(), boxes[k].volume());
        // Even with min_added_share 0, each box adds a voxel the boxes before it do not cover.
        std::vector<bool> cover(g.count(), false);
        for (const VoxelBox& b : boxes) {
            uint64_t added = 0;
            for (int z = b.lo.z; z <= b.hi.z; ++z)
                for (int y = b.lo.y; y <= b.hi.y; ++y)
                    for (int x = b.lo.x; x <= b.hi.x; ++x) {
                        added += !cover[g.index(x, y, z)];
                        cover[g.index(x, y, z)] = true;
                    }
            EXPECT_GT(added, 0u) << "seed " << seed;
        }
        // Below the limits, every solid voxel seeds or is covered, and every grown box adding a voxel is
        // kept.
        if (stats.grown < kGrowFactor * config.max_boxes && stats.kept < config.max_boxes) {
            EXPECT_EQ(covered, stats.solid_voxels) << "seed " << seed;
        }
    }
}

TEST(GrowBoxes, MatchesTheReferenceOnRandomGrids) {
    Context ctx = quiet_context();
    std::vector<BoxConfig> configs(4);
    configs[0].min_box_volume_m3 = 0.0;
    configs[1].max_boxes = 3;
    configs[1].min_box_volume_m3 = 0.0;
    configs[1].min_added_share = 0.0;
    configs[2].max_boxes = 2;  // the grow cap (16 boxes) ends the seeding on noisy grids
    configs[2].min_box_volume_m3 = 0.0;
    configs[2].min_added_share = 0.5;
    // configs[3]: the defaults (0.5 m3 is 32 voxels of 0.25 m).
    int compared = 0, nonempty = 0;
    auto compare = [&](const VoxelGrid& g, const BitVolume& solid, const std::string& what) {
        for (size_t c = 0; c < configs.size(); ++c) {
            const std::vector<VoxelBox> fast = grow_boxes(ctx, g, solid, configs[c]);
            const std::vector<VoxelBox> slow = grow_boxes_reference(g, solid, configs[c]);
            ASSERT_EQ(fast.size(), slow.size()) << what << ", config " << c;
            for (size_t k = 0; k < fast.size(); ++k) {
                ASSERT_EQ(fast[k], slow[k]) << what << ", config " << c << ", box " << k;
            }
            check_inside_solid(g, solid, fast);
            ++compared;
            nonempty += !fast.empty();
        }
    };
    const VoxelGrid g = grid_of({20, 16, 24});
    for (uint64_t seed = 1; seed <= 40; ++seed) {
        const BitVolume solid =
            random_blobs(g, 100 + seed, 1 + int(seed % 6), int(seed % 4) * 8, 0.03f * float(seed % 3));
        compare(g, solid, "seed " + std::to_string(seed));
    }
    BitVolume empty, full;
    empty.reset(g.count());
    full.reset(g.count());
    fill(g, full, glm::ivec3(0), g.dims - 1, true);
    compare(g, empty, "empty grid");
    compare(g, full, "full grid");
    // The solid of sealed levels: full grids with rooms and corridors carved out.
    for (uint64_t seed = 1; seed <= 3; ++seed) {
        const VoxelGrid level = grid_of({40, 32, 36});
        BitVolume solid;
        solid.reset(level.count());
        fill(level, solid, glm::ivec3(0), level.dims - 1, true);
        Rng rng(seed, 11);
        for (int r = 0; r < 30; ++r) {
            const glm::ivec3 lo(int(rng.below(40)), int(rng.below(32)), int(rng.below(36)));
            glm::ivec3 e(int(rng.below(8)), int(rng.below(8)), int(rng.below(8)));
            if (r % 2) e[int(rng.below(3))] = 1 + int(rng.below(20));  // a corridor
            fill(level, solid, lo, lo + e, false);
        }
        compare(level, solid, "carved level " + std::to_string(seed));
    }
    // Thin shapes: one voxel thick in some axis, and grids one voxel thick.
    const VoxelGrid flat = grid_of({30, 1, 25}, 1.0f);
    compare(flat, random_blobs(flat, 5, 6, 10, 0.05f), "flat grid");
    const VoxelGrid line = grid_of({1, 40, 1}, 1.0f);
    compare(line, random_blobs(line, 6, 3, 2, 0.1f), "line grid");
    EXPECT_EQ(compared, 4 * 47);
    EXPECT_GT(nonempty, 100);
}

// The summed-area table counts modulo 2^16: a layer of 300 x 300 voxels holding exactly 2^16 empty
// voxels has count 0 modulo 2^16 and must still be found not solid.
TEST(GrowBoxes, ExactWhenALayerHoldsAMultipleOf65536EmptyVoxels) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({300, 300, 3});
    BitVolume solid;
    solid.reset(g.count());
    fill(g, solid, glm::ivec3(0), g.dims - 1, true);
    fill(g, solid, {0, 0, 1}, {255, 255, 1}, false);  // 256 * 256 empty voxels in the middle layer
    BoxConfig config;
    config.min_box_volume_m3 = 0.0;
    config.min_added_share = 0.0;
    const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, config);
    EXPECT_EQ(check_inside_solid(g, solid, boxes), solid.count());
    EXPECT_EQ(boxes, grow_boxes_reference(g, solid, config));
    // The full bottom layer is one box.
    bool bottom = false;
    for (const VoxelBox& b : boxes) bottom |= b == VoxelBox{{0, 0, 0}, {299, 299, 0}};
    EXPECT_TRUE(bottom);
}

// Solid made of two overlapping slabs (a plus, and an L): a handful of boxes cover nearly all of it.
TEST(GrowBoxes, TwoOverlappingSlabsGetAFewBoxesCoveringThem) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({48, 40, 36});
    struct Shape {
        const char* name;
        glm::ivec3 a_lo, a_hi, b_lo, b_hi;
    };
    const Shape shapes[] = {
        {"plus", {2, 14, 3}, {45, 23, 32}, {18, 1, 3}, {27, 38, 32}},
        {"L", {2, 2, 2}, {40, 9, 30}, {2, 2, 2}, {9, 35, 30}},
        {"plus through z", {5, 15, 0}, {44, 22, 35}, {3, 3, 12}, {46, 36, 19}},
    };
    for (const Shape& s : shapes) {
        BitVolume solid;
        solid.reset(g.count());
        fill(g, solid, s.a_lo, s.a_hi, true);
        fill(g, solid, s.b_lo, s.b_hi, true);
        BoxStats stats;
        const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, BoxConfig{}, &stats);
        EXPECT_EQ(check_inside_solid(g, solid, boxes), stats.covered_voxels);
        EXPECT_GE(boxes.size(), 1u) << s.name;
        EXPECT_LE(boxes.size(), 4u) << s.name;
        EXPECT_GE(double(stats.covered_voxels), 0.95 * double(stats.solid_voxels)) << s.name;
        // Each slab is one of the boxes.
        bool a = false, b = false;
        for (const VoxelBox& box : boxes) {
            a |= box == VoxelBox{s.a_lo, s.a_hi};
            b |= box == VoxelBox{s.b_lo, s.b_hi};
        }
        EXPECT_TRUE(a && b) << s.name;
    }
}

TEST(GrowBoxes, ASolidCubeIsExactlyOneBox) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({30, 20, 25});
    BitVolume solid;
    solid.reset(g.count());
    fill(g, solid, {4, 3, 7}, {15, 14, 18}, true);
    const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, BoxConfig{});
    ASSERT_EQ(boxes.size(), 1u);
    EXPECT_EQ(boxes[0], (VoxelBox{{4, 3, 7}, {15, 14, 18}}));
    // A box, not a cube, touching the grid's faces.
    solid.reset(g.count());
    fill(g, solid, {0, 5, 0}, {29, 19, 3}, true);
    const std::vector<VoxelBox> slab = grow_boxes(ctx, g, solid, BoxConfig{});
    ASSERT_EQ(slab.size(), 1u);
    EXPECT_EQ(slab[0], (VoxelBox{{0, 5, 0}, {29, 19, 3}}));
}

// A full grid of 260^3 voxels: seed cubes are capped at kMaxSeedCube, growth still finds the whole grid.
TEST(GrowBoxes, ACubeBeyondTheSeedCapIsStillOneBox) {
    Context ctx = quiet_context();
    const int n = kMaxSeedCube + 5;
    const VoxelGrid g = grid_of({n, n, n}, 1.0f);
    BitVolume solid;
    solid.reset(g.count());
    for (uint64_t& w : solid.words) w = ~uint64_t(0);
    BoxStats stats;
    const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, BoxConfig{}, &stats);
    ASSERT_EQ(boxes.size(), 1u);
    EXPECT_EQ(boxes[0], (VoxelBox{glm::ivec3(0), glm::ivec3(n - 1)}));
    EXPECT_EQ(stats.solid_voxels, g.count());  // the bits past the grid's end are not counted
    EXPECT_EQ(stats.covered_voxels, g.count());
    EXPECT_EQ(stats.grown, 1u);
}

// Twelve separate cubes of edges 1..12 voxels.
BitVolume separate_cubes(const VoxelGrid& g) {
    BitVolume solid;
    solid.reset(g.count());
    for (int k = 1; k <= 12; ++k) {
        const glm::ivec3 lo{(k - 1) % 4 * 14, (k - 1) / 4 * 14, 1};
        fill(g, solid, lo, lo + (k - 1), true);
    }
    return solid;
}

TEST(GrowBoxes, MaxBoxesKeepsTheLargest) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({56, 42, 14}, 1.0f);
    const BitVolume solid = separate_cubes(g);
    BoxConfig config;
    config.min_box_volume_m3 = 0.0;
    EXPECT_EQ(grow_boxes(ctx, g, solid, config).size(), 12u);
    config.max_boxes = 5;
    const std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, config);
    ASSERT_EQ(boxes.size(), 5u);
    for (int k = 0; k < 5; ++k)
        EXPECT_EQ(boxes[size_t(k)].volume(), uint64_t((12 - k) * (12 - k) * (12 - k)));
    config.max_boxes = 1;
    ASSERT_EQ(grow_boxes(ctx, g, solid, config).size(), 1u);
}

TEST(GrowBoxes, MinBoxVolumeDropsSmallBoxes) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({56, 42, 14}, 0.5f);  // 0.125 m3 a voxel
    const BitVolume solid = separate_cubes(g);
    BoxConfig config;
    config.min_box_volume_m3 = 64 * 0.125;  // cubes of edge >= 4 voxels (2 m)
    std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, config);
    ASSERT_EQ(boxes.size(), 9u);
    for (const VoxelBox& b : boxes) EXPECT_GE(double(b.volume()) * 0.125, config.min_box_volume_m3);
    config.min_box_volume_m3 = 64 * 0.125 + 0.01;
    EXPECT_EQ(grow_boxes(ctx, g, solid, config).size(), 8u);
    config.min_box_volume_m3 = 1e9;
    EXPECT_TRUE(grow_boxes(ctx, g, solid, config).empty());
}

// A thick plus: the box of slab b (6000 voxels) comes first; slab a's box (4000) adds 2000, half of it.
TEST(GrowBoxes, MinAddedShareDropsBoxesOthersCover) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({40, 30, 10}, 1.0f);
    BitVolume solid;
    solid.reset(g.count());
    fill(g, solid, {0, 10, 0}, {39, 19, 9}, true);  // a
    fill(g, solid, {10, 0, 0}, {29, 29, 9}, true);  // b
    BoxConfig config;
    config.min_added_share = 0.49;
    std::vector<VoxelBox> boxes = grow_boxes(ctx, g, solid, config);
    ASSERT_EQ(boxes.size(), 2u);
    EXPECT_EQ(boxes[0], (VoxelBox{{10, 0, 0}, {29, 29, 9}}));
    EXPECT_EQ(boxes[1], (VoxelBox{{0, 10, 0}, {39, 19, 9}}));
    config.min_added_share = 0.51;
    boxes = grow_boxes(ctx, g, solid, config);
    ASSERT_EQ(boxes.size(), 1u);
    EXPECT_EQ(boxes[0], (VoxelBox{{10, 0, 0}, {29, 29, 9}}));
}

TEST(GrowBoxes, EmptySolidGivesNoBoxes) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({17, 9, 13});
    BitVolume solid;
    solid.reset(g.count());
    BoxStats stats;
    EXPECT_TRUE(grow_boxes(ctx, g, solid, BoxConfig{}, &stats).empty());
    EXPECT_EQ(stats.solid_voxels, 0u);
    EXPECT_EQ(stats.grown, 0u);
    EXPECT_TRUE(grow_boxes_reference(g, solid, BoxConfig{}).empty());
    // A grid with no voxels at all.
    const VoxelGrid none = grid_of({0, 0, 0});
    BitVolume nothing;
    EXPECT_TRUE(grow_boxes(ctx, none, nothing, BoxConfig{}).empty());
}

TEST(GrowBoxes, SameBoxesTwiceAndForAnyThreadCount) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({140, 120, 130});  // over 2^21 voxels: the table is built in parallel
    const BitVolume solid = random_blobs(g, 77, 40, 300, 0.01f);
    const int threads = omp_get_max_threads();
    const std::vector<VoxelBox> first = grow_boxes(ctx, g, solid, BoxConfig{});
    const std::vector<VoxelBox> second = grow_boxes(ctx, g, solid, BoxConfig{});
    omp_set_num_threads(1);
    const std::vector<VoxelBox> one = grow_boxes(ctx, g, solid, BoxConfig{});
    omp_set_num_threads(3);
    const std::vector<VoxelBox> three = grow_boxes(ctx, g, solid, BoxConfig{});
    omp_set_num_threads(threads);
    EXPECT_GT(first.size(), 3u);
    EXPECT_EQ(first, second);
    EXPECT_EQ(first, one);
    EXPECT_EQ(first, three);
}

// A big level of thick walls and floors with doors (over 2^21 voxels, walls of over 4,096 rows): the seed
// scan, the batched clearing and the cut run on all threads, and must give the boxes of the plain
// reference at any thread count.
TEST(GrowBoxes, MatchesTheReferenceOnABigLevelAtAnyThreadCount) {
    Context ctx = quiet_context();
    const VoxelGrid level = grid_of({150, 110, 140});
    BitVolume solid;
    solid.reset(level.count());
    Rng rng(5, 13);
    for (int w = 0; w < 12; ++w) {
        const int axis = w % 3, at = int(rng.below(uint64_t(level.dims[axis] - 6)));
        glm::ivec3 lo(0), hi = level.dims - 1;
        lo[axis] = at;
        hi[axis] = at + 2 + int(rng.below(4));
        fill(level, solid, lo, hi, true);
        for (int d = 0; d < 3; ++d) {  // doors through it
            glm::ivec3 dlo(int(rng.below(140)), int(rng.below(100)), int(rng.below(130)));
            glm::ivec3 dhi =
                dlo + glm::ivec3(2 + int(rng.below(8)), 2 + int(rng.below(8)), 2 + int(rng.below(8)));
            dlo[axis] = lo[axis];
            dhi[axis] = hi[axis];
            fill(level, solid, dlo, glm::min(dhi, level.dims - 1), false);
        }
    }
    BoxConfig config;
    config.min_box_volume_m3 = 0.0;
    const std::vector<VoxelBox> slow = grow_boxes_reference(level, solid, config);
    const int threads = omp_get_max_threads();
    for (const int t : {1, 2, 3}) {
        omp_set_num_threads(t);
        EXPECT_EQ(grow_boxes(ctx, level, solid, config), slow) << t << " threads";
    }
    omp_set_num_threads(threads);
    EXPECT_GT(slow.size(), 20u);
    const auto rows = [](const VoxelBox& b) { return (b.hi.y - b.lo.y + 1) * (b.hi.z - b.lo.z + 1); };
    EXPECT_TRUE(std::any_of(slow.begin(), slow.end(), [&](const VoxelBox& b) { return rows(b) >= 4096; }));
}

TEST(GrowBoxes, RejectsAConfigOutsideItsLimits) {
    Context ctx = quiet_context();
    const VoxelGrid g = grid_of({4, 4, 4});
    BitVolume solid;
    solid.reset(g.count());
    auto rejects = [&](const BoxConfig& c, const char* option) {
        try {
            grow_boxes(ctx, g, solid, c);
            ADD_FAILURE() << "accepted a bad " << option;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
            EXPECT_NE(std::string(e.what()).find(option), std::string::npos) << e.what();
        }
        EXPECT_THROW(grow_boxes_reference(g, solid, c), Error);
    };
    BoxConfig c;
    c.max_boxes = 0;
    rejects(c, "--max-occluders");
    c = BoxConfig{};
    c.min_box_volume_m3 = -1.0;
    rejects(c, "--min-occluder-volume");
    c.min_box_volume_m3 = std::nan("");
    rejects(c, "--min-occluder-volume");
    c = BoxConfig{};
    c.min_added_share = 1.5;
    rejects(c, "min_added_share");
}

TEST(BoxBounds, IsTheUnionOfItsVoxelBoxes) {
    const VoxelGrid g = grid_of({10, 10, 10}, 0.5f);
    const VoxelBox b{{1, 2, 3}, {4, 2, 8}};
    const Aabb a = box_bounds(g, b);
    EXPECT_EQ(a.min, g.voxel_box(b.lo).min);
    EXPECT_EQ(a.max, g.voxel_box(b.hi).max);
    EXPECT_FLOAT_EQ(a.size().x, 2.0f);
    EXPECT_FLOAT_EQ(a.size().y, 0.5f);
    EXPECT_FLOAT_EQ(a.size().z, 3.0f);
    EXPECT_EQ((VoxelBox{{0, 0, 0}, {-1, 0, 0}}).volume(), 0u);
}

}  // namespace
}  // namespace pvs
