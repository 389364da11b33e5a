// SPDX-License-Identifier: MIT
// Worlds whose extent would break the voxel caps: the automatic voxel size fits any shape within
// --max-voxels; a world that needs voxels coarser than --max-voxel-size or the cells to do so keeps voxels of
// that limit when it is just large (a town), and is refused, naming the objects that stand apart, when a
// stray vertex makes it large; an explicit --voxel-size is refused only past the grid's own limit.
#include "cells/world_extent.h"
#include "core/error.h"
#include "driver/memory_plan.h"
#include "samples/town_world.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

#include <random>

namespace pvs {
namespace {

// A closed 8 x 3 x 8 m room, a crate and a spawn point; the crate has one more triangle reaching to
// `stray` (the crate's own corner when stray is inside the room).
World room_with_crate(glm::vec3 stray) {
    World w;
    test::add_box(w, "room", Aabb::of({-4, 0, -4}, {4, 3, 4}));
    test::add_box(w, "crate", Aabb::of({1, 0, 1}, {2, 1, 2}));
    const uint32_t first = uint32_t(w.positions.size());
    w.positions.insert(w.positions.end(), {{1, 1, 1}, {2, 1, 1}, stray});
    w.triangles.push_back({{first, first + 1, first + 2}});
    w.triangle_opaque.push_back(1);
    w.triangle_double_sided.push_back(0);
    w.objects.back().triangle_count += 1;
    w.objects.back().bounds.extend(stray);
    w.bounds.extend(stray);
    w.view_seeds.push_back({-2, 1.5f, -2});
    return w;
}

TEST(WorldExtent, TheFarthestObjectIsTheOneWithTheStrayVertex) {
    const World w = room_with_crate({2, 0.5f, 1.0e6f});
    const std::vector<ObjectReach> far = farthest_objects(w, 3);
    ASSERT_EQ(far.size(), 2u);  // the room reaches a few metres out of the crate and the seed too
    EXPECT_EQ(w.objects[far[0].object].name, "crate");
    EXPECT_EQ(w.objects[far[1].object].name, "room");
    EXPECT_LT(far[1].distance_m, 10.0);
    // Only the crate stands apart: the room reaches less far than the rest (crate and seed) is long.
    const std::vector<ObjectReach> strays = stray_objects(w, 3);
    ASSERT_EQ(strays.size(), 1u);
    EXPECT_EQ(w.objects[strays[0].object].name, "crate");
    EXPECT_NEAR(far[0].distance_m, 1.0e6 - 4.0, 1.0);
    EXPECT_EQ(far[0].vertex.z, 1.0e6f);
    EXPECT_NE(describe_reaches(w, far).find("object 'crate' has a vertex 1000.0 km from the rest"),
              std::string::npos)
        << describe_reaches(w, far);
    // A world of one object without seeds has no rest to measure from.
    World alone;
    test::add_box(alone, "only", Aabb::of({0, 0, 0}, {1, 1, 1}));
    EXPECT_TRUE(farthest_objects(alone, 3).empty());
    EXPECT_TRUE(stray_objects(alone, 3).empty());
    // A big level exported as one mesh, with a view seed: it reaches far from the seed, but stands apart from
    // nothing.
    World merged = make_town_world(TownParams{});
    merged.objects.resize(1);
    merged.objects[0].triangle_count = uint32_t(merged.triangles.size());
    merged.objects[0].bounds = merged.bounds;
    EXPECT_FALSE(farthest_objects(merged, 3).empty());
    EXPECT_TRUE(stray_objects(merged, 3).empty());
}

// Padding (a metre, at least 2 voxels a side) and rounding included, whatever the shape: a needle a
// thousand kilometres long, a sheet, a cube, a speck.
TEST(WorldExtent, TheAutomaticVoxelSizeFitsAnyShapeWithinTheCap) {
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> exponent(-3.0, 6.0);
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 e(std::pow(10.0, exponent(rng)), std::pow(10.0, exponent(rng)), std::pow(10.0, exponent(rng)));
        const Aabb bounds = Aabb::of(glm::vec3(-0.5f) * e, glm::vec3(0.5f) * e);
        const uint64_t cap = uint64_t(1000) << (i % 21);  // up to make_voxel_grid()'s 1 G
        const double preferred = 0.0625;
        const double size = default_voxel_size(bounds, preferred, cap);
        SCOPED_TRACE(testing::Message() << e.x << " x " << e.y << " x " << e.z << " m, cap " << cap);
        ASSERT_GE(size, preferred);
        EXPECT_LE(voxel_grid_count(bounds, size, void_pad_voxels(size)), double(cap));
        EXPECT_LE(double(make_voxel_grid(bounds, size, void_pad_voxels(size)).count()), double(cap));
        // The least such size within 1%: 2% finer would not fit (unless it is the preferred size).
        if (size > preferred * 1.02) {
            EXPECT_GT(voxel_grid_count(bounds, size / 1.02, void_pad_voxels(size / 1.02)), double(cap));
        }
    }
}

TEST(WorldExtent, AStrayVertexIsRefusedNamingItsObjectUnlessCoarseVoxelsAreAllowed) {
    const World w = room_with_crate({2, 0.5f, 1.0e6f});
    ViewVolumeConfig config;
    config.cell_edge_m = 2.0;
    try {
        (void)view_voxel_grid(config, w, 0.0625, 0);
        FAIL() << "a world a thousand kilometres long was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
        const std::string m = e.what();
        for (const char* says : {"object 'crate'", "1000.0 km", "--max-voxel-size 0.25", "--allow-coarse-voxels"})
            EXPECT_NE(m.find(says), std::string::npos) << says << " in: " << m;
    }
    config.allow_coarse_voxels = true;
    const VoxelGrid grid = view_voxel_grid(config, w, 0.0625, 0);
    EXPECT_LE(grid.count(), config.max_voxels);
    EXPECT_GT(grid.voxel_size_m, 0.25f);
    // The same world without the stray vertex keeps its preferred voxels.
    config.allow_coarse_voxels = false;
    EXPECT_FLOAT_EQ(view_voxel_grid(config, room_with_crate({2, 1, 2}), 0.0625, 0).voxel_size_m, 0.0625f);
}

TEST(WorldExtent, AWorldThatIsJustLargeKeepsVoxelsOfTheLimitAndAnExplicitSizeOnlyMeetsTheGridsLimit) {
    const World w = room_with_crate({2, 1, 2});
    ViewVolumeConfig config;
    config.max_voxel_size_m = 100.0;
    config.cell_edge_m = 0.5;
    config.max_voxels = 1000;  // the room would need voxels of about 1.4 m: coarser than the cells
    const VoxelGrid grid = view_voxel_grid(config, w, 0.0625, 0);
    EXPECT_FLOAT_EQ(grid.voxel_size_m, 0.5f) << "the voxels stay at the cells' edge";
    EXPECT_GT(grid.count(), config.max_voxels);
    config.allow_coarse_voxels = true;  // asked for: coarser, within the target
    EXPECT_GT(view_voxel_grid(config, w, 0.0625, 0).voxel_size_m, 1.0f);
    EXPECT_LE(view_voxel_grid(config, w, 0.0625, 0).count(), config.max_voxels);

    config = ViewVolumeConfig{};
    config.max_voxels = 1000;
    config.voxel_size_m = 0.05;  // 3.7 M voxels: over the target, within the grid's limit
    EXPECT_FLOAT_EQ(view_voxel_grid(config, w, 0.0625, 0).voxel_size_m, 0.05f);
    config.voxel_size_m = 0.0005;
    try {
        (void)view_voxel_grid(config, w, 0.0625, 0);
        FAIL() << "an explicit voxel size past the grid's limit was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
        EXPECT_NE(std::string(e.what()).find("more than a voxel grid can hold"), std::string::npos) << e.what();
    }
}

// A big open level is not a fault: a town of 330 x 330 m, 46 m high, keeps 0.25 m voxels (346 M, past the
// 200 M target), names no object as stray (the ground reaches a little past the buildings), and its memory
// plan is about 3 GiB. The same town with one vertex thrown a thousand kilometres is still refused, naming it.
TEST(WorldExtent, ABigTownBakesAtItsVoxelsAndAStrayVertexInItIsStillRefused) {
    World town = make_town_world(TownParams{});
    EXPECT_NEAR(town.bounds.size().x, 330.0f, 0.01f);
    EXPECT_NEAR(town.bounds.size().y, 47.0f, 0.01f);  // the 1 m ground slab and the 46 m tower
    EXPECT_TRUE(stray_objects(town, 3).empty()) << describe_reaches(town, stray_objects(town, 3));
    ViewVolumeConfig config;
    config.cell_edge_m = 2.0;
    const VoxelGrid grid = view_voxel_grid(config, town, 0.0625, 0);
    EXPECT_FLOAT_EQ(grid.voxel_size_m, 0.25f);
    EXPECT_GT(grid.count(), config.max_voxels);
    BakeConfig bake;
    const MemoryPlan plan = plan_memory(bake, town, grid.count(), 0, 2);
    EXPECT_LT(plan.total(), 4.0 * double(uint64_t(1) << 30)) << describe(plan);
    EXPECT_NO_THROW(check_memory(plan, 8.0 * double(uint64_t(1) << 30), "the view volume and occluders"));
    try {
        check_memory(plan, 1.0 * double(uint64_t(1) << 30), "the view volume and occluders");
        FAIL() << "a plan of " << describe(plan) << " fitted 1 GiB";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--max-memory"), std::string::npos) << e.what();
    }

    // One vertex of one building thrown far away.
    const uint32_t b = 17;
    const uint32_t v = town.triangles[town.objects[b].first_triangle].v[0];
    town.positions[v] = {10.0f, 1.0e6f, 10.0f};
    town.objects[b].bounds.extend(town.positions[v]);
    town.bounds.extend(town.positions[v]);
    const std::vector<ObjectReach> strays = stray_objects(town, 3);
    ASSERT_EQ(strays.size(), 1u);
    EXPECT_EQ(strays[0].object, b);
    try {
        (void)view_voxel_grid(config, town, 0.0625, 0);
        FAIL() << "a town a thousand kilometres high was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("object '" + town.objects[b].name + "'"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace pvs
