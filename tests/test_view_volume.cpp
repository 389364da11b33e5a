// SPDX-License-Identifier: MIT
// The view volume: sealed rooms, leaks, boxes, play height; grid clipping and eye points inside it.
#include "cells/eyes.h"
#include "cells/grid.h"
#include "cells/view_volume.h"
#include "core/error.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Two closed rooms side by side (each 6 x 3 x 6 m inside, 0.3 m walls) joined by a doorway, or sealed
// from each other; optionally a hole in room A's outer west wall.
World two_rooms(bool doorway, bool hole_outside) {
    World w;
    const float t = 0.3f;
    test::add_box(w, "floor", Aabb::of({0, 0, 0}, {12.9f, t, 6.6f}));
    test::add_box(w, "roof", Aabb::of({0, 3.3f, 0}, {12.9f, 3.6f, 6.6f}));
    test::add_box(w, "south", Aabb::of({0, 0, 0}, {12.9f, 3.6f, t}));
    test::add_box(w, "north", Aabb::of({0, 0, 6.3f}, {12.9f, 3.6f, 6.6f}));
    test::add_box(w, "east", Aabb::of({12.6f, 0, 0}, {12.9f, 3.6f, 6.6f}));
    if (hole_outside) {
        test::add_box(w, "west_a", Aabb::of({0, 0, 0}, {t, 3.6f, 2.8f}));
        test::add_box(w, "west_b", Aabb::of({0, 0, 3.8f}, {t, 3.6f, 6.6f}));
        test::add_box(w, "west_c", Aabb::of({0, 0, 2.8f}, {t, 1.0f, 3.8f}));
        test::add_box(w, "west_d", Aabb::of({0, 2.0f, 2.8f}, {t, 3.6f, 3.8f}));
    } else {
        test::add_box(w, "west", Aabb::of({0, 0, 0}, {t, 3.6f, 6.6f}));
    }
    if (doorway) {
        test::add_box(w, "middle_a", Aabb::of({6.3f, 0, 0}, {6.6f, 3.6f, 2.8f}));
        test::add_box(w, "middle_b", Aabb::of({6.3f, 0, 3.8f}, {6.6f, 3.6f, 6.6f}));
        test::add_box(w, "middle_c", Aabb::of({6.3f, 2.4f, 2.8f}, {6.6f, 3.6f, 3.8f}));
    } else {
        test::add_box(w, "middle", Aabb::of({6.3f, 0, 0}, {6.6f, 3.6f, 6.6f}));
    }
    return w;
}

ViewVolumeConfig flood_from(std::vector<glm::vec3> seeds, double voxel = 0.1) {
    ViewVolumeConfig c;
    c.voxel_size_m = voxel;
    c.seeds = std::move(seeds);
    return c;
}

TEST(ViewVolume, SealedRoomsAreExactlyTheRooms) {
    Context ctx = quiet_context();
    const World w = two_rooms(true, false);
    const ViewVolume vv = build_view_volume(ctx, flood_from({{3, 1.5f, 3}}), w);
    EXPECT_TRUE(vv.flooded);
    EXPECT_FALSE(vv.leaked);
    // Two rooms of 6 x 3 x 6 m (216 m3) and the doorway; the eye space is that less one voxel along
    // every wall (touched voxels), the view region reaches back to the walls.
    const double rooms = 2 * 6.0 * 3.0 * 6.0;
    EXPECT_GT(vv.eye_volume_m3, 0.85 * rooms);
    EXPECT_LT(vv.eye_volume_m3, rooms);
    EXPECT_GT(vv.view_volume_m3, rooms * 0.98);
    EXPECT_LT(vv.view_volume_m3, rooms * 1.15);
    // The view bounds are the rooms' inside (to a voxel or two), not the outer walls' outside.
    EXPECT_NEAR(vv.view_bounds.min.x, 0.3f, 0.21f);
    EXPECT_NEAR(vv.view_bounds.max.x, 12.6f, 0.21f);
    EXPECT_NEAR(vv.view_bounds.min.y, 0.3f, 0.21f);
    EXPECT_NEAR(vv.view_bounds.max.y, 3.3f, 0.21f);
    EXPECT_TRUE(vv.view.contains({9, 1.5f, 3}));       // the other room, through the doorway
    EXPECT_FALSE(vv.view.contains({6.45f, 1.5f, 1}));  // inside the middle wall
    EXPECT_FALSE(vv.view.contains({-1, 1.5f, 3}));     // outside
}

TEST(ViewVolume, AClosedDoorKeepsTheOtherRoomOut) {
    Context ctx = quiet_context();
    const World w = two_rooms(false, false);
    const ViewVolume vv = build_view_volume(ctx, flood_from({{3, 1.5f, 3}}), w);
    EXPECT_TRUE(vv.view.contains({3, 1.5f, 3}));
    EXPECT_FALSE(vv.view.contains({9, 1.5f, 3}));
    EXPECT_LT(vv.eye_volume_m3, 6.0 * 3.0 * 6.0);
}

TEST(ViewVolume, AHoleInTheOuterWallLeaksThroughTheHole) {
    Context ctx = quiet_context();
    const World w = two_rooms(true, true);
    const ViewVolume vv = build_view_volume(ctx, flood_from({{9, 1.5f, 3}}), w);
    ASSERT_TRUE(vv.leaked);
    ASSERT_GE(vv.leak_path.size(), 2u);
    EXPECT_NEAR(vv.leak_path.front().x, 9.0f, 0.1f);
    EXPECT_FALSE(w.bounds.contains(vv.leak_path.back()));
    bool crossed = false;  // where the path crosses the west wall's plane it is inside the hole
    for (size_t k = 0; k + 1 < vv.leak_path.size(); ++k) {
        const glm::vec3 p = vv.leak_path[k], q = vv.leak_path[k + 1];
        if ((p.x - 0.15f) * (q.x - 0.15f) > 0) continue;
        const glm::vec3 x = p + (0.15f - p.x) / (q.x - p.x) * (q - p);
        EXPECT_GT(x.z, 2.8f);
        EXPECT_LT(x.z, 3.8f);
        EXPECT_GT(x.y, 1.0f);
        EXPECT_LT(x.y, 2.0f);
        crossed = true;
    }
    EXPECT_TRUE(crossed);
    const std::string obj = leak_path_obj(vv.leak_path);
    EXPECT_NE(obj.find("\nl 1 2"), std::string::npos);
}

TEST(ViewVolume, BoxesAndPlayHeightOnlyRemoveSpace) {
    Context ctx = quiet_context();
    const World w = two_rooms(true, false);
    ViewVolumeConfig c = flood_from({{3, 1.5f, 3}});
    const ViewVolume all = build_view_volume(ctx, c, w);
    c.boxes.push_back(Aabb::of({0, 0, 0}, {6.3f, 4, 6.6f}));  // room A only
    const ViewVolume boxed = build_view_volume(ctx, c, w);
    EXPECT_LT(boxed.eye_volume_m3, 0.55 * all.eye_volume_m3);
    EXPECT_FALSE(boxed.view.contains({9, 1.5f, 3}));
    c.boxes.clear();
    c.play_height_m = 1.0;
    const ViewVolume low = build_view_volume(ctx, c, w);
    EXPECT_TRUE(low.eyes.contains({3, 0.8f, 3}));
    EXPECT_FALSE(low.eyes.contains({3, 2.5f, 3}));  // 2.2 m above the floor
    EXPECT_LT(low.eye_volume_m3, 0.4 * all.eye_volume_m3);
}

// A yard open to the sky, split by a 4 m wall with a doorway (z in [2.5, 3.5]), closed by a glass pane or
// open; the only seed stands on a 5 m pedestal in the west half.
World walled_yard(bool glass) {
    World w;
    test::add_open_yard(w);
    test::add_box(w, "divide_a", Aabb::of({5.7f, 0, 0}, {6.3f, 4, 2.5f}));
    test::add_box(w, "divide_b", Aabb::of({5.7f, 0, 3.5f}, {6.3f, 4, 6}));
    if (glass) test::add_box(w, "glass", Aabb::of({5.95f, 0, 2.5f}, {6.05f, 4, 3.5f}), false);
    test::add_box(w, "pedestal", Aabb::of({1, 0, 1}, {3, 5, 3}));
    return w;
}

// Flying (no play height), the flood goes over the wall and out to the sky: both halves and a leak. With a
// play height the flood walks: it drops off the pedestal into the west half, never gets over the wall, and
// goes through the doorway only when no glass closes it.
TEST(ViewVolume, WithAPlayHeightEyesWalkAndDropButDoNotFlyOrPassGlass) {
    Context ctx = quiet_context();
    ViewVolumeConfig c = flood_from({{2, 6, 2}});
    const ViewVolume flying = build_view_volume(ctx, c, walled_yard(true));
    EXPECT_TRUE(flying.leaked);
    EXPECT_TRUE(flying.eyes.contains({9, 1, 3}));
    c.play_height_m = 1.8;
    const ViewVolume walking = build_view_volume(ctx, c, walled_yard(true));
    EXPECT_FALSE(walking.leaked);
    EXPECT_TRUE(walking.eyes.contains({2, 6, 2}));      // on the pedestal
    EXPECT_TRUE(walking.eyes.contains({4.5f, 1, 5}));   // dropped into the west half
    EXPECT_FALSE(walking.eyes.contains({9, 1, 3}));     // the east half: behind glass, or over the wall
    EXPECT_FALSE(walking.eyes.contains({4.5f, 3, 5}));  // above the play height
    const ViewVolume through_door = build_view_volume(ctx, c, walled_yard(false));
    EXPECT_FALSE(through_door.leaked);
    EXPECT_TRUE(through_door.eyes.contains({9, 1, 3}));  // walked through the open doorway
}

TEST(ViewVolume, NoSourceMeansTheWorldBoundsWithAWarning) {
    Context ctx = quiet_context();
    const World w = two_rooms(true, false);
    const ViewVolume vv = build_view_volume(ctx, ViewVolumeConfig{}, w);
    EXPECT_FALSE(vv.voxelized);
    EXPECT_EQ(vv.view_bounds, w.bounds);
    ASSERT_FALSE(ctx.warnings().empty());
    EXPECT_NE(ctx.warnings()[0].find("anywhere"), std::string::npos);
}

TEST(ViewVolume, GridIsClippedAndEyesStayInFreeReachableSpace) {
    Context ctx = quiet_context();
    const World w = two_rooms(false, false);  // room B sealed off: it holds no cell
    const ViewVolume vv = build_view_volume(ctx, flood_from({{3, 1.5f, 3}}), w);
    CellSet cells = build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 1.0}, vv.view_bounds);
    clip_grid_to_view(ctx, cells, vv.view, vv.eyes);
    EXPECT_LE(cells.size(), 7u * 4u * 7u);
    for (const Cell& c : cells.cells) EXPECT_LT(c.bounds.min.x, 6.3f);
    EXPECT_GE(cells.find({3, 1.5f, 3}), 0);
    EXPECT_EQ(cells.find({9, 1.5f, 3}), -1);
    for (uint32_t c = 0; c < cells.size(); ++c) {
        std::vector<glm::vec3> eyes;
        sample_eye_points(cells, c, 8, 1, eyes);
        for (const glm::vec3& e : eyes) {
            ASSERT_TRUE(cells.cells[c].bounds.contains(e));
            // Never inside a wall: inside room A's free interior.
            EXPECT_GT(e.x, 0.3f);
            EXPECT_LT(e.x, 6.3f);
            EXPECT_GT(e.y, 0.3f);
            EXPECT_LT(e.y, 3.3f);
            EXPECT_GT(e.z, 0.3f);
            EXPECT_LT(e.z, 6.3f);
        }
    }
}

TEST(ViewVolume, BadSeedsAndBoxesAreClearErrors) {
    Context ctx = quiet_context();
    const World w = two_rooms(true, false);
    EXPECT_THROW(build_view_volume(ctx, flood_from({{500, 0, 0}}), w), Error);
    ViewVolumeConfig c;
    c.boxes.push_back(Aabb::of({100, 100, 100}, {101, 101, 101}));  // nowhere near the world
    EXPECT_THROW(build_view_volume(ctx, c, w), Error);
}

}  // namespace
}  // namespace pvs
