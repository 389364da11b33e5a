// SPDX-License-Identifier: MIT
// pvsview's view model (viewer/view_model.h): which objects are coloured, cell figures, picking, cameras,
// the view volume's surface. Plain data, no window.
#include "viewer/view_model.h"

#include "tests/world_builder.h"

#include <gtest/gtest.h>

#include <set>

namespace pvs::viewer {
namespace {

// Two opaque boxes and a glass one; a 2-cell grid along x; cell 0 sees objects 0 and 2, cell 1 sees 1.
struct Fixture {
    World world;
    BakeData bake;
    Fixture() {
        test::add_box(world, "a", Aabb::of({-3, -1, -1}, {-1, 1, 1}));
        test::add_box(world, "b", Aabb::of({1, -1, -1}, {3, 1, 1}));
        test::add_box(world, "glass", Aabb::of({-0.5f, -1, -1}, {0.5f, 1, 1}), false);
        for (const WorldObject& o : world.objects)
            bake.objects.push_back({o.name, o.bounds, o.triangle_count, o.flags});
        bake.cells.origin = {-4, -6, -1};
        bake.cells.cell_size_m = 4;
        bake.cells.dims = {2, 1, 1};
        bake.cells.grid_to_cell = {0, 1};
        bake.cells.cells = {Cell{Aabb::of({-4, -6, -1}, {0, -2, 3}), -1},
                            Cell{Aabb::of({0, -6, -1}, {4, -2, 3}), -1}};
        bake.pvs = PvsSet::make(2, 3);
        bake.pvs.set(0, 0);
        bake.pvs.set(0, 2);
        bake.pvs.set(1, 1);
        bake.verification.ran = true;
        bake.verification.cell_sampled_visible = {1, 1};
        bake.verification.misses.push_back(Miss{1, 0, {1, -5, 0}, {0, 1, 0}, 4.0f});
        bake.occluders = {Occluder{Aabb::of({-3, -1, -1}, {-1, 1, 1}), 0.25f, true, {0}},
                          Occluder{Aabb::of({1, -1, -1}, {3, 1, 1}), 0.25f, true, {1}}};
        bake.ranked.offsets = {0, 2, 2};  // cell 0: boxes 1 then 0; cell 1: none
        bake.ranked.entries = {{1, 0.5f, 1.5f, 2.0f, 0.25f}, {0, 0.25f, 0.75f, 1.0f, 0.125f}};
    }
};

TEST(ViewModel, RankedOccludersOfThePickedCell) {
    Fixture f;
    const std::vector<Aabb> boxes = ranked_occluder_boxes(f.bake, 0);
    ASSERT_EQ(boxes.size(), 2u);
    EXPECT_EQ(boxes[0], f.bake.occluders[1].box);  // best first
    EXPECT_EQ(boxes[1], f.bake.occluders[0].box);
    EXPECT_TRUE(ranked_occluder_boxes(f.bake, 1).empty());
    EXPECT_TRUE(ranked_occluder_boxes(f.bake, 5).empty());
    const std::string text = cell_overlay_text(f.bake, cell_figures(f.bake, 0), 1);
    EXPECT_NE(
        text.find("ranked occluders (cyan): 2; the best scores 0.500, 1.50 sr, hides 2.0 objects, 25.0%"),
        std::string::npos)
        << text;
    EXPECT_NE(cell_overlay_text(f.bake, cell_figures(f.bake, 1), 1).find("ranked occluders: none"),
              std::string::npos);
}

TEST(ViewModel, ObjectStatesFollowThePickedCellsPvs) {
    Fixture f;
    EXPECT_EQ(object_states(f.bake, -1, false), std::vector<ObjectState>(3, ObjectState::kNeutral));
    EXPECT_EQ(object_states(f.bake, 0, false),
              (std::vector<ObjectState>{ObjectState::kVisible, ObjectState::kFaded, ObjectState::kVisible}));
    EXPECT_EQ(object_states(f.bake, 1, true),
              (std::vector<ObjectState>{ObjectState::kHidden, ObjectState::kVisible, ObjectState::kHidden}));
    EXPECT_EQ(object_states(f.bake, 7, true), std::vector<ObjectState>(3, ObjectState::kNeutral));
}

TEST(ViewModel, TriangleColorsShowVisibleObjectsInTheirColourAndGlassTranslucent) {
    Fixture f;
    const auto colors = triangle_colors(f.world, object_states(f.bake, 0, true));
    ASSERT_EQ(colors.size(), f.world.triangles.size());
    const WorldObject& a = f.world.objects[0];
    const WorldObject& b = f.world.objects[1];
    const WorldObject& glass = f.world.objects[2];
    EXPECT_EQ(colors[a.first_triangle], object_color(0));
    EXPECT_EQ(colors[b.first_triangle][3], 0);  // hidden
    EXPECT_EQ(colors[glass.first_triangle][3], kVisibleSeeThroughAlpha);
    const auto faded = triangle_colors(f.world, object_states(f.bake, 0, false));
    EXPECT_EQ(faded[b.first_triangle], kFadedOpaque);
    const auto neutral = triangle_colors(f.world, object_states(f.bake, -1, false));
    EXPECT_EQ(neutral[a.first_triangle], kNeutralOpaque);
    EXPECT_EQ(neutral[glass.first_triangle], kNeutralSeeThrough);
}

TEST(ViewModel, ObjectColoursAreDistinctSaturatedAndNotRed) {
    std::set<Rgba> seen;
    for (uint32_t o = 0; o < 64; ++o) {
        const Rgba c = object_color(o);
        const int hi = std::max({c[0], c[1], c[2]}), lo = std::min({c[0], c[1], c[2]});
        EXPECT_GT(hi - lo, 100) << o;                             // never grey
        EXPECT_FALSE(c[0] == hi && c[1] < 80 && c[2] < 80) << o;  // never the misses' red
        seen.insert(c);
    }
    EXPECT_EQ(seen.size(), 64u);
}

TEST(ViewModel, HeatMapRunsFromBlueToRed) {
    const Rgba cold = heat_color(0.0), hot = heat_color(1.0);
    EXPECT_GT(cold[2], cold[0]);
    EXPECT_GT(hot[0], hot[2]);
    EXPECT_EQ(heat_color(-3.0), cold);
    EXPECT_EQ(heat_color(7.0), hot);
}

TEST(ViewModel, CellFiguresCountObjectsTrianglesSampledSetAndMisses) {
    Fixture f;
    const CellFigures c0 = cell_figures(f.bake, 0);
    EXPECT_EQ(c0.objects_visible, 2u);
    EXPECT_EQ(c0.objects_total, 3u);
    EXPECT_EQ(c0.triangles_visible, 24u);
    EXPECT_EQ(c0.triangles_total, 36u);
    EXPECT_EQ(c0.sampled_visible, 1);
    EXPECT_DOUBLE_EQ(c0.overestimation, 2.0);
    EXPECT_EQ(c0.misses, 0u);
    EXPECT_EQ(c0.listed, (std::vector<uint32_t>{0, 2}));
    const CellFigures c1 = cell_figures(f.bake, 1);
    EXPECT_EQ(c1.misses, 1u);
    const std::string text = cell_overlay_text(f.bake, c0, 1);
    EXPECT_NE(text.find("cell 0 of 2"), std::string::npos) << text;
    EXPECT_NE(text.find("2 of 3 objects"), std::string::npos) << text;
    EXPECT_NE(text.find("overestimation: 2.00x"), std::string::npos) << text;
    EXPECT_NE(text.find("and 1 more"), std::string::npos) << text;
    EXPECT_EQ(cell_figures(f.bake, -1).cell, -1);
    EXPECT_EQ(cell_figures(f.bake, 2).cell, -1);
    f.bake.verification = {};
    EXPECT_EQ(cell_figures(f.bake, 0).sampled_visible, -1);
    EXPECT_NE(help_text().find("Right / Left"), std::string::npos);
    EXPECT_NE(bake_overlay_text(f.bake, "w.glb").find("2 cells (grid), 3 objects"), std::string::npos);
}

TEST(ViewModel, ASurfacePointPicksTheCellInFrontOfIt) {
    Fixture f;
    EXPECT_EQ(cell_for_surface_point(f.bake.cells, {1, -5, 0}, {0, 1, 0}, 0.25f, 4), 1);
    // Just outside the grid (below it), stepping toward the eye enters cell 0.
    EXPECT_EQ(cell_for_surface_point(f.bake.cells, {-1, -6.5f, 0}, {0, 1, 0}, 0.25f, 4), 0);
    // Far away, looking away: the nearest cell's bounds.
    EXPECT_EQ(cell_for_surface_point(f.bake.cells, {30, -5, 0}, {1, 0, 0}, 0.25f, 4), 1);
    EXPECT_EQ(cell_for_surface_point(CellSet{}, {0, 0, 0}, {0, 1, 0}, 0.25f, 4), -1);
}

TEST(ViewModel, CameraAndSizeParsing) {
    const auto cam = parse_camera("0,0,20, 0,0,0, 0,1,0");
    ASSERT_TRUE(cam);
    EXPECT_EQ(cam->eye, glm::vec3(0, 0, 20));
    EXPECT_EQ(cam->up, glm::vec3(0, 1, 0));
    EXPECT_FALSE(parse_camera("0,0,20,0,0,0,0,1"));    // eight numbers
    EXPECT_FALSE(parse_camera("0,0,20,0,0,0,0,0,1"));  // up along the view direction
    EXPECT_FALSE(parse_camera("1,1,1,1,1,1,0,1,0"));   // eye on the target
    EXPECT_FALSE(parse_camera("0,0,20,0,0,0,0,1,zero"));
    EXPECT_FALSE(parse_camera("0,0,nan,0,0,0,0,1,0"));
    const auto size = parse_size("960x540");
    ASSERT_TRUE(size);
    EXPECT_EQ((*size)[0], 960);
    EXPECT_EQ((*size)[1], 540);
    EXPECT_FALSE(parse_size("960"));
    EXPECT_FALSE(parse_size("8x8"));
    EXPECT_FALSE(parse_size("100x-5"));
    EXPECT_FALSE(parse_size("99999x100"));
}

TEST(ViewModel, DefaultCameraSeesTheWholeBoxAndProjectionIsVtks) {
    const Aabb box = Aabb::of({-10, 0, -5}, {10, 4, 5});
    const CameraPose cam = camera_for_box(box, 30.0, 16.0 / 9.0, 35.0);
    bool touches = false;
    for (int i = 0; i < 8; ++i) {
        const glm::vec3 corner(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y,
                               i & 4 ? box.max.z : box.min.z);
        const auto px = project_to_pixel(cam, 30.0, 1600, 900, corner);
        ASSERT_TRUE(px);
        EXPECT_GE(px->x, 0.0f);
        EXPECT_LE(px->x, 1600.0f);
        EXPECT_GE(px->y, 0.0f);
        EXPECT_LE(px->y, 900.0f);
        touches |= px->x < 130.0f || px->x > 1470.0f || px->y < 72.0f || px->y > 828.0f;
    }
    EXPECT_TRUE(touches);  // framed tight: some corner is within 8% of an edge
    const CameraPose down{{0, 0, 20}, {0, 0, 0}, {0, 1, 0}};
    const auto centre = project_to_pixel(down, 30.0, 400, 300, {0, 0, 0});
    ASSERT_TRUE(centre);
    EXPECT_FLOAT_EQ(centre->x, 200.0f);
    EXPECT_FLOAT_EQ(centre->y, 150.0f);
    const auto right_up = project_to_pixel(down, 30.0, 400, 300, {1, 1, 0});
    ASSERT_TRUE(right_up);
    EXPECT_GT(right_up->x, 200.0f);  // +x is right
    EXPECT_LT(right_up->y, 150.0f);  // +y is up, row 0 is the top
    EXPECT_FALSE(project_to_pixel(down, 30.0, 400, 300, {0, 0, 30}));
}

TEST(ViewModel, FocusBoxHoldsTheCellAndItsPvsObjects) {
    Fixture f;
    f.world.bounds = Aabb::of({-3, -1, -1}, {3, 1, 1});
    const Aabb box = focus_box(f.bake, f.world, 0);
    EXPECT_TRUE(box.contains(f.bake.cells.cells[0].bounds.center()));
    EXPECT_TRUE(box.contains(f.world.objects[0].bounds.center()));
    EXPECT_FALSE(box.contains(f.world.objects[1].bounds.center()));
    EXPECT_EQ(focus_box(f.bake, f.world, -1), f.world.bounds);
}

TEST(ViewModel, VoxelMaskSurfaceHasOneQuadPerOpenFace) {
    VoxelMask m;
    m.voxel_size_m = 0.5f;
    m.dims = {3, 1, 1};
    m.bits = {0b011};  // two voxels side by side, the third unset
    const auto quads = voxel_mask_surface(m);
    EXPECT_EQ(quads.size(), 10u * 4u);
    for (const glm::vec3& p : quads) {
        EXPECT_LE(p.x, 1.0f);  // nothing drawn around the unset voxel
    }
    EXPECT_TRUE(voxel_mask_surface(VoxelMask{}).empty());
}

}  // namespace
}  // namespace pvs::viewer
