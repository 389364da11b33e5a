// SPDX-License-Identifier: MIT
// The conservative mode on scenes whose visibility is known (who sees whom, fusion), and zero misses against
// dense rays on random box worlds.
#include "cells/eyes.h"
#include "cells/view_volume.h"
#include "core/error.h"
#include "core/random.h"
#include "driver/bake.h"
#include "occluders/synthesis.h"
#include "rays/ray_scene.h"
#include "pvs/conservative.h"
#include "samples/random_world.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

double figure(const NamedValues& figures, const std::string& name) {
    for (const auto& [key, value] : figures)
        if (key == name) return value;
    ADD_FAILURE() << "no figure " << name;
    return 0.0;
}

// A figure of the result (/figures) or of the run's work (/run/figures).
double figure(const BakeData& bake, const std::string& name) {
    for (const NamedValues* list : {&bake.figures, &bake.run.figures})
        for (const auto& [key, value] : *list)
            if (key == name) return value;
    ADD_FAILURE() << "no figure " << name;
    return 0.0;
}

// A closed hall (inside x in [0, 12], y in [0, 4], z in [0, 6]; 0.5 m shell) split at x = 6 by a 0.6 m wall
// with a doorway at its far end (z in [4.6, 5.6], y < 2.5) so both halves are reachable. What stands in the
// wall near z in [0, 2] varies: solid, two walls overlapping in view (fusion), the same with a gap, a slit,
// a doorway, a glass pane, a wall thinner than a voxel. The target stands behind it at x in [9, 9.5], z in
// [0.75, 1.25]. Walls are 0.6 m thick: at 0.1 m voxels and epsilon 0.1 m a shrunk occluder remains inside
// them; a thinner wall leaves no box, only its faces (panels, occluders/panels.h).
enum class Middle {
    kSolid,
    kFusedHalves,
    kLowHalfOnly,
    kHighHalfOnly,
    kGappedHalves,
    kSlit,
    kDoorway,
    kGlass,
    kThinShell
};

struct Scene {
    World world;
    uint32_t target = 0;
};

Scene make_scene(Middle middle) {
    Scene s;
    World& w = s.world;
    test::add_box(w, "floor", Aabb::of({-0.5f, -0.5f, -0.5f}, {12.5f, 0, 6.5f}));
    test::add_box(w, "roof", Aabb::of({-0.5f, 4, -0.5f}, {12.5f, 4.5f, 6.5f}));
    test::add_box(w, "west", Aabb::of({-0.5f, 0, -0.5f}, {0, 4, 6.5f}));
    test::add_box(w, "east", Aabb::of({12, 0, -0.5f}, {12.5f, 4, 6.5f}));
    test::add_box(w, "south", Aabb::of({0, 0, -0.5f}, {12, 4, 0}));
    test::add_box(w, "north", Aabb::of({0, 0, 6}, {12, 4, 6.5f}));
    // The dividing wall: x in [5.7, 6.3]; z in [2, 4.6] always solid; the far doorway z in [4.6, 5.6].
    test::add_box(w, "wall_mid", Aabb::of({5.7f, 0, 2}, {6.3f, 4, 4.6f}));
    test::add_box(w, "wall_far", Aabb::of({5.7f, 0, 5.6f}, {6.3f, 4, 6}));
    test::add_box(w, "lintel", Aabb::of({5.7f, 2.5f, 4.6f}, {6.3f, 4, 5.6f}));
    const float x0 = 5.7f, x1 = 6.3f;
    switch (middle) {
        case Middle::kSolid:
            test::add_box(w, "near", Aabb::of({x0, 0, 0}, {x1, 4, 2}));
            break;
        case Middle::kFusedHalves:  // a low wall in the divide and a high wall 0.9 m behind it, 0.6 m thick
                                    // each: from the test cell each alone leaves part of the target in
                                    // sight (rays check it), together they overlap in every view (fusion
                                    // on the depth buffer; no single occluder hides it)
            test::add_box(w, "near_low", Aabb::of({x0, 0, 0}, {x1, 1.7f, 2}));
            test::add_box(w, "near_high", Aabb::of({7.2f, 1.1f, 0}, {7.8f, 4, 2}));
            break;
        case Middle::kLowHalfOnly:
            test::add_box(w, "near_low", Aabb::of({x0, 0, 0}, {x1, 1.7f, 2}));
            break;
        case Middle::kHighHalfOnly:
            test::add_box(w, "near_high", Aabb::of({7.2f, 1.1f, 0}, {7.8f, 4, 2}));
            break;
        case Middle::kGappedHalves:  // the same two walls, with a gap between them in every view
            test::add_box(w, "near_low", Aabb::of({x0, 0, 0}, {x1, 1.1f, 2}));
            test::add_box(w, "near_high", Aabb::of({7.2f, 1.7f, 0}, {7.8f, 4, 2}));
            break;
        case Middle::kSlit:  // 2 cm slit at z in [0.99, 1.01], narrower than epsilon and a voxel
            test::add_box(w, "near_a", Aabb::of({x0, 0, 0}, {x1, 4, 0.99f}));
            test::add_box(w, "near_b", Aabb::of({x0, 0, 1.01f}, {x1, 4, 2}));
            break;
        case Middle::kDoorway:
        case Middle::kGlass:
            test::add_box(w, "near_a", Aabb::of({x0, 0, 0}, {x1, 4, 0.6f}));
            test::add_box(w, "near_b", Aabb::of({x0, 0, 1.4f}, {x1, 4, 2}));
            test::add_box(w, "near_top", Aabb::of({x0, 2.5f, 0.6f}, {x1, 4, 1.4f}));
            if (middle == Middle::kGlass)
                test::add_box(w, "glass", Aabb::of({5.99f, 0, 0.6f}, {6.01f, 2.5f, 1.4f}), false);
            break;
        case Middle::kThinShell:  // 5 cm thick, half a voxel: no solid in it, only its faces (panels)
            test::add_box(w, "near_thin", Aabb::of({5.975f, 0, 0}, {6.025f, 4, 2}));
            break;
    }
    s.target = test::add_box(w, "target", Aabb::of({9, 0.8f, 0.75f}, {9.5f, 1.8f, 1.25f}));
    w.view_seeds = {{3, 1.5f, 3}, {9, 1.5f, 3}};
    return s;
}

BakeConfig conservative_config() {
    BakeConfig c;
    c.mode = BakeMode::kConservative;
    c.view.voxel_size_m = 0.1;
    c.conservative.epsilon_m = 0.1;
    c.cells.cell_size_m = 1.0;
    c.occluders.probe_eyes = 512;
    c.occluders.probe_rays_per_eye = 2048;
    c.occluders.check_eyes = 512;
    c.verify.rays = SampleConfig{16, 2048, 0, 77};
    return c;
}

// Bakes the world with the config, and expects the bake's own verification to have run and found no miss.
BakeData bake_without_misses(const BakeConfig& c, const World& w) {
    Context ctx = quiet_context();
    BakeData bake = bake_world(ctx, c, w, "test", "");
    EXPECT_TRUE(bake.verification.ran);
    EXPECT_TRUE(bake.verification.misses.empty()) << bake.verification.misses.size() << " misses";
    return bake;
}

// Is the target listed for the cell at x in [2, 3], y in [1, 2], z in [0.5, 1.5] (in line with it)?
bool target_listed(Middle middle) {
    Context ctx = quiet_context();
    const Scene s = make_scene(middle);
    const BakeData bake = bake_world(ctx, conservative_config(), s.world, "test", "");
    EXPECT_TRUE(bake.conservative);
    // Zero misses, always.
    EXPECT_TRUE(bake.verification.ran);
    EXPECT_TRUE(bake.verification.misses.empty()) << bake.verification.misses.size() << " misses";
    const int32_t cell = bake.cells.find({2.5f, 1.5f, 1.0f});
    EXPECT_GE(cell, 0);
    if (cell < 0) return true;
    return bake.pvs.test(uint32_t(cell), s.target);
}

// A tall hall (8 m) with eyes only up to 1.5 m above the floor and 4 m cells, which reach far above the eye
// space: a lamp hangs at 7 m. Eyes see it by looking up, so every cell under the open hall lists it, and a
// crate behind a wall is still culled. No patch may be skipped for lying far from the eye space: sight
// leaves the eye region upwards (docs/ALGORITHMS.md#eye-region).
TEST(Conservative, SeenByLookingUpAboveThePlayHeightIsListed) {
    World w;
    test::add_box(w, "floor", Aabb::of({-0.5f, -0.5f, -0.5f}, {12.5f, 0, 8.5f}));
    test::add_box(w, "roof", Aabb::of({-0.5f, 8, -0.5f}, {12.5f, 8.5f, 8.5f}));
    test::add_box(w, "west", Aabb::of({-0.5f, 0, -0.5f}, {0, 8, 8.5f}));
    test::add_box(w, "east", Aabb::of({12, 0, -0.5f}, {12.5f, 8, 8.5f}));
    test::add_box(w, "south", Aabb::of({0, 0, -0.5f}, {12, 8, 0}));
    test::add_box(w, "north", Aabb::of({0, 0, 8}, {12, 8, 8.5f}));
    test::add_box(w, "divide", Aabb::of({8, 0, 0}, {8.6f, 8, 6}));  // a doorway at z in [6, 8]
    const uint32_t lamp = test::add_box(w, "lamp", Aabb::of({3.8f, 6.8f, 3.8f}, {4.2f, 7.0f, 4.2f}));
    const uint32_t crate = test::add_box(w, "crate", Aabb::of({10, 0, 1}, {11, 1, 2}));
    w.view_seeds = {{2, 1, 2}, {10, 1, 4}};
    BakeConfig c = conservative_config();
    c.cells.cell_size_m = 4.0;
    c.view.play_height_m = 1.5;
    const BakeData bake = bake_without_misses(c, w);
    for (const glm::vec3 eye : {glm::vec3(1, 1, 1), glm::vec3(4, 1, 4), glm::vec3(7, 1, 7)}) {
        const int32_t cell = bake.cells.find(eye);
        ASSERT_GE(cell, 0);
        EXPECT_TRUE(bake.pvs.test(uint32_t(cell), lamp)) << "cell at " << eye.x << ", " << eye.z;
    }
    const int32_t corner = bake.cells.find({1, 1, 1});
    EXPECT_FALSE(bake.pvs.test(uint32_t(corner), crate)) << "the crate is behind the divide";
}

// A yard open to the sky, split by a wall 0.6 m thick whose top face is missing, as in a compiled level
// whose walls lose the faces they share with the sky. Eyes are only up to 2 m above the floor. Flying, a
// flood of free space would go up, over and down into the wall (eyes inside it would see everything);
// walking it does not, and sight goes in straight lines: none from below the wall's top goes down into
// it. So the wall is solid and hides the crate behind it.
TEST(Conservative, AWallOpenOnlyAtItsTopUnderTheSkyHidesWhatIsBehindIt) {
    World w;
    test::add_open_yard(w);
    test::add_box_faces(w, "divide", Aabb::of({5.7f, 0, 0}, {6.3f, 4, 6}), true, 0, 3);  // no top face
    const uint32_t crate = test::add_box(w, "crate", Aabb::of({9, 0.2f, 0.75f}, {9.5f, 1.2f, 1.25f}));
    w.view_seeds = {{3, 1, 3}, {9, 1, 3}};
    BakeConfig c = conservative_config();
    c.view.play_height_m = 2.0;
    const BakeData bake = bake_without_misses(c, w);
    const int32_t cell = bake.cells.find({2.5f, 1.5f, 1.0f});
    ASSERT_GE(cell, 0);
    EXPECT_FALSE(bake.pvs.test(uint32_t(cell), crate)) << "the crate is behind the wall";
    const int32_t near = bake.cells.find({8.5f, 1.5f, 1.0f});
    ASSERT_GE(near, 0);
    EXPECT_TRUE(bake.pvs.test(uint32_t(near), crate));
}

TEST(Conservative, BehindAWallIsCulled) {
    EXPECT_FALSE(target_listed(Middle::kSolid));
}
TEST(Conservative, BehindTwoOverlappingHalfWallsIsCulledByFusion) {
    EXPECT_FALSE(target_listed(Middle::kFusedHalves));
}
// Segments from random points of the test cell to random points of the target that reach it.
uint64_t seen_from_the_test_cell(Middle middle) {
    Context ctx = quiet_context();
    const Scene s = make_scene(middle);
    RayScene scene(ctx, s.world);
    Rng rng(3, 3);
    const Aabb cell = Aabb::of({2, 1, 0.5f}, {3, 2, 1.5f}), t = s.world.objects[s.target].bounds;
    uint64_t seen = 0;
    std::vector<RayTouch> touches;
    for (int i = 0; i < 20000; ++i) {
        const glm::vec3 e = cell.min + cell.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
        const glm::vec3 d =
            glm::normalize(t.min + t.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - e);
        touches.clear();
        scene.trace(e, &d, 1, touches);
        for (const RayTouch& h : touches) seen += h.stops && h.object == s.target;
    }
    return seen;
}

TEST(Conservative, EitherHalfWallAloneLeavesItListed) {
    EXPECT_GT(seen_from_the_test_cell(Middle::kLowHalfOnly), 0u);  // the premise: really in sight
    EXPECT_GT(seen_from_the_test_cell(Middle::kHighHalfOnly), 0u);
    EXPECT_EQ(seen_from_the_test_cell(Middle::kFusedHalves), 0u);
    EXPECT_TRUE(target_listed(Middle::kLowHalfOnly));
    EXPECT_TRUE(target_listed(Middle::kHighHalfOnly));
}
TEST(Conservative, BehindAWallThinnerThanAVoxelIsCulledByItsFaces) {
    EXPECT_FALSE(target_listed(Middle::kThinShell));
}
TEST(Conservative, ThroughAGapBetweenTwoWallsIsListed) {
    EXPECT_TRUE(target_listed(Middle::kGappedHalves));
}
TEST(Conservative, ThroughASlitNarrowerThanEpsilonIsListed) {
    EXPECT_TRUE(target_listed(Middle::kSlit));
}
TEST(Conservative, ThroughADoorwayIsListed) {
    EXPECT_TRUE(target_listed(Middle::kDoorway));
}
TEST(Conservative, BehindGlassIsListed) {
    EXPECT_TRUE(target_listed(Middle::kGlass));
}

// On the octree the wall hides the target as on the grid, with zero misses, and the stage is timed under
// the mode that computed the rows ("conservative_pvs", not "sampled_pvs").
TEST(Conservative, TheOctreeCullsBehindTheWallAndIsTimedAsConservative) {
    Context ctx = quiet_context();
    const Scene s = make_scene(Middle::kSolid);
    BakeConfig c = conservative_config();
    c.cells.kind = CellKind::kOctree;
    c.cells.root_cell_size_m = 4.0;
    c.cells.min_cell_size_m = 1.0;
    const BakeData bake = bake_world(ctx, c, s.world, "test", "");
    EXPECT_EQ(bake.cells.kind, CellSet::Kind::kOctree);
    EXPECT_TRUE(bake.verification.ran);
    EXPECT_TRUE(bake.verification.misses.empty()) << bake.verification.misses.size() << " misses";
    const int32_t cell = bake.cells.find({2.5f, 1.5f, 1.0f});
    ASSERT_GE(cell, 0);
    EXPECT_FALSE(bake.pvs.test(uint32_t(cell), s.target)) << "the target is behind the wall";
    bool conservative_timed = false, sampled_timed = false;
    for (const auto& [stage, seconds] : ctx.timings()) {
        conservative_timed |= stage == "conservative_pvs";
        sampled_timed |= stage == "sampled_pvs";
    }
    EXPECT_TRUE(conservative_timed);
    EXPECT_FALSE(sampled_timed);
}

// The single-occluder pass (pvs/region_hiding.h) only ever leaves objects out that the faces would have
// proved too, or that they could not for the shrinking and the pixels: with it, every row is a subset of
// the row without it; it proves pairs on the wall scene; the target stays culled behind the wall and
// listed through the doorway, with zero misses either way.
TEST(Conservative, TheSingleOccluderPassOnlyNarrowsRows) {
    for (Middle middle : {Middle::kSolid, Middle::kDoorway}) {
        Context ctx = quiet_context();
        const Scene s = make_scene(middle);
        BakeConfig on = conservative_config(), off = conservative_config();
        off.conservative.single_occluder_pass = false;
        const BakeData with = bake_world(ctx, on, s.world, "test", "");
        const BakeData without = bake_world(ctx, off, s.world, "test", "");
        ASSERT_EQ(with.cells.size(), without.cells.size());
        EXPECT_GT(figure(with, "conservative_region_hidden"), 0.0);
        EXPECT_EQ(figure(without, "conservative_region_hidden"), 0.0);
        uint64_t listed_with = 0, listed_without = 0;
        for (uint32_t c = 0; c < with.cells.size(); ++c) {
            for (uint32_t o = 0; o < s.world.objects.size(); ++o) {
                if (with.pvs.test(c, o)) {
                    EXPECT_TRUE(without.pvs.test(c, o)) << "cell " << c << " object " << o;
                }
            }
            listed_with += with.pvs.count(c);
            listed_without += without.pvs.count(c);
        }
        EXPECT_LE(listed_with, listed_without);
        EXPECT_TRUE(with.verification.misses.empty());
        EXPECT_TRUE(without.verification.misses.empty());
        const int32_t cell = with.cells.find({2.5f, 1.5f, 1.0f});
        ASSERT_GE(cell, 0);
        EXPECT_EQ(with.pvs.test(uint32_t(cell), s.target), middle == Middle::kDoorway);
    }
}

// OCCLUDERS PER BLOCK (occluders/synthesis.h synthesize_block_occluders). A yard 36 m long, open to the
// sky, eyes up to 2 m above the floor, cut in two by a diagonal wall 1.2 m thick whose side facing the far
// (east) half is missing, as a compiled level's hollow walls are. Eyes in the east half look into the
// wall, so from ALL eyes the wall holds no solid, and it is not axis-aligned, so it gives no axis panels.
// From the west block's own eyes the wall is closed, and the space behind it is out of their sight: the
// west cells cull the sign hung in the east half, and the east cells, which see it, list it. (Its west
// face is also one slanted panel, which the single-occluder pass uses with or without blocks.)
World blocked_yard(uint32_t& crate) {
    World w;
    test::add_box(w, "floor", Aabb::of({-0.5f, -0.5f, -0.5f}, {36.5f, 0, 12.5f}));
    test::add_box(w, "west", Aabb::of({-0.5f, 0, -0.5f}, {0, 4, 12.5f}));
    test::add_box(w, "east", Aabb::of({36, 0, -0.5f}, {36.5f, 4, 12.5f}));
    test::add_box(w, "south", Aabb::of({0, 0, -0.5f}, {36, 4, 0}));
    test::add_box(w, "north", Aabb::of({0, 0, 12}, {36, 4, 12.5f}));
    // From (12, 0) to (16, 12) on its west face, 1.2 m thick in x; side 1 (east face) open.
    add_prism_object(
        w, "diagonal",
        {glm::vec2(12, -0.01f), glm::vec2(13.2f, -0.01f), glm::vec2(17.2f, 12.01f), glm::vec2(16, 12.01f)}, 0,
        4, 1);
    // A sign hung behind the wall. (An object standing on the floor there stays listed: the floor's touched
    // voxels are in no solid, so the shadow's boxes stop a few voxels above it;
    // docs/ALGORITHMS.md#block-occluders.)
    crate = test::add_box(w, "sign", Aabb::of({22, 1.4f, 5}, {23, 2.4f, 6}));
    w.view_seeds = {{4, 1, 6}, {28, 1, 6}};
    return w;
}

// The yard's view volume, rays, global occluders and 8 m block occluders, handed to `check`.
template <class Check>
void with_yard_blocks(const Check& check) {
    uint32_t sign = 0;
    const World w = blocked_yard(sign);
    BakeConfig c = conservative_config();
    c.view.play_height_m = 2.0;
    Context ctx = quiet_context();
    const ViewVolume view = build_view_volume(ctx, c.view, w);
    RayScene scene(ctx, w);
    OccluderFigures f;
    ShrunkOccluders shrunk;
    synthesize_occluders(ctx, c.occluders, w, view, scene, f, c.conservative.epsilon_m, 2, &shrunk);
    const BlockFigures b =
        synthesize_block_occluders(ctx, c.occluders, w, view, scene, view.view_bounds.min, 8.0f, shrunk);
    check(view, scene, shrunk, b);
}

// The same yard, one stage down: the west block's own occluders fill the space behind the wall (out of
// its eyes' sight), the global ones and the east block's do not (east eyes see it).
TEST(Conservative, AWestBlocksOwnOccludersFillTheSpaceBehindTheHollowWall) {
    with_yard_blocks(
        [](const ViewVolume&, const RayScene&, const ShrunkOccluders& shrunk, const BlockFigures& b) {
            EXPECT_GT(b.blocks_used, 0u);
            const glm::vec3 behind(19, 1.5f, 5.5f);
            const auto holds = [&](const ShrunkOccluders& set) {
                for (const Aabb& box : set.boxes[0])
                    if (box.contains(behind)) return true;
                return false;
            };
            EXPECT_FALSE(holds(shrunk)) << "east eyes see the space behind the wall";
            const int32_t west = shrunk.set_for(Aabb::of({2, 0.5f, 6}, {4, 2, 8}));
            const int32_t east = shrunk.set_for(Aabb::of({26, 0.5f, 6}, {28, 2, 8}));
            ASSERT_GE(west, 0);
            EXPECT_TRUE(holds(shrunk.set(west))) << "no west eye sees the space behind the wall";
            EXPECT_FALSE(holds(shrunk.set(east)));
        });
}

// With blocks, the west block's own occluders hide the sign from the west cells; without them, the wall's
// west face as a slanted panel does (docs/ALGORITHMS.md#slanted-panels). The east cells list it either way.
TEST(Conservative, BehindAHollowWallOthersSeeIntoIsCulledByTheBlocksOwnOccludersOrItsSlantedFace) {
    uint32_t crate = 0;
    const World w = blocked_yard(crate);
    for (const bool blocks : {true, false}) {
        BakeConfig c = conservative_config();
        c.view.play_height_m = 2.0;
        c.cells.cell_size_m = 2.0;
        c.occluders.block_m = blocks ? 8.0 : 0.0;
        const BakeData bake = bake_without_misses(c, w);
        const int32_t west = bake.cells.find({3, 1, 6}), east = bake.cells.find({27, 1, 6});
        ASSERT_GE(west, 0);
        ASSERT_GE(east, 0);
        EXPECT_TRUE(bake.pvs.test(uint32_t(east), crate)) << "the east cells see the crate";
        EXPECT_FALSE(bake.pvs.test(uint32_t(west), crate))
            << (blocks ? "the west block's own occluders hide the crate"
                       : "the wall's slanted west face hides it");
        double used = -1;
        for (const auto& [name, value] : bake.figures)
            if (name == "occluder_blocks_with_own_occluders") used = value;
        if (blocks) {
            EXPECT_GT(used, 0.0);
        }
    }
}

// A closed room from the origin to `size`, of walls, floor and roof 0.5 m thick.
void add_closed_room(World& w, glm::vec3 size) {
    const float t = 0.5f;
    test::add_box(w, "floor", Aabb::of({-t, -t, -t}, {size.x + t, 0, size.z + t}));
    test::add_box(w, "roof", Aabb::of({-t, size.y, -t}, {size.x + t, size.y + t, size.z + t}));
    test::add_box(w, "west", Aabb::of({-t, 0, -t}, {0, size.y, size.z + t}));
    test::add_box(w, "east", Aabb::of({size.x, 0, -t}, {size.x + t, size.y, size.z + t}));
    test::add_box(w, "south", Aabb::of({0, 0, -t}, {size.x, size.y, 0}));
    test::add_box(w, "north", Aabb::of({0, 0, size.z}, {size.x, size.y, size.z + t}));
}

// FUSION OF OFF-AXIS WALLS. A closed room 20 x 3 x 12 m; two full-height walls 5 cm thick (no solid in
// them, no axis panel), one turned 49 degrees off x from (6, 2) to (10, 6.6), the other turned -56 degrees
// from (8, 10) to (11, 5.6). From the cell at x in [2, 3], z in [5.5, 6.5] they overlap in view, and a
// target at x in [16, 17], z in [5, 7] lies behind the two together, behind neither alone (so the
// single-occluder pass cannot prove it): only their slanted faces drawn on the same depth cubes can
// (`--slanted-cubes`, docs/ALGORITHMS.md#slanted-inset).
TEST(Conservative, BehindTwoOffAxisWallsIsCulledByTheirFusion) {
    World w;
    const glm::vec3 size(20, 3, 12);
    add_closed_room(w, size);
    const auto wall = [&](const std::string& name, glm::vec2 a, glm::vec2 b) {
        const glm::vec2 along = glm::normalize(b - a), across(-along.y, along.x);
        add_prism_object(w, name, {a, b, b + 0.05f * across, a + 0.05f * across}, 0.0f, size.y, -1);
    };
    wall("first", {6, 2}, {10, 6.6f});
    wall("second", {8, 10}, {11, 5.6f});
    const uint32_t target = test::add_box(w, "target", Aabb::of({16, 1, 5}, {17, 2, 7}));
    w.view_seeds = {{2.5f, 1.5f, 6}, {18, 1.5f, 6}};
    BakeConfig c = conservative_config();
    c.conservative.slanted_cubes = true;
    const BakeData bake = bake_without_misses(c, w);
    const int32_t cell = bake.cells.find({2.5f, 1.5f, 6.0f}), near = bake.cells.find({15.5f, 1.5f, 6.0f});
    ASSERT_GE(cell, 0);
    ASSERT_GE(near, 0);
    EXPECT_FALSE(bake.pvs.test(uint32_t(cell), target)) << "the two walls together hide the target";
    EXPECT_TRUE(bake.pvs.test(uint32_t(near), target));
}

// Does a bake of `w` (verified by dense rays to have no miss) list `target` for the cell at `eye`?
// `shaft_hidden`: the pairs its shaft pass proved hidden.
bool listed_at(const BakeConfig& c, const World& w, glm::vec3 eye, uint32_t target, uint64_t& shaft_hidden) {
    const BakeData bake = bake_without_misses(c, w);
    shaft_hidden = uint64_t(figure(bake, "conservative_shaft_hidden"));
    const int32_t cell = bake.cells.find(eye);
    EXPECT_GE(cell, 0);
    return cell < 0 || bake.pvs.test(uint32_t(cell), target);
}

// THE SHAFT PASS (docs/ALGORITHMS.md#shaft-pass). A closed room 14 x 3 x 8 m; two full-height walls 5 cm
// thick (no solid in them, only their faces), the near one at x = 6 from z = 0 to 4.3, the far one at x = 9
// from z = 4.45 to 8. A target at x in [11, 11.5], z in [3, 5] lies behind the two together: from the cell at
// x in [2, 3], z in [3, 4], every line that passes the near wall's end meets the far wall at least 7.5 cm
// inside its end. Neither wall alone hides it (so the single-occluder pass cannot), and the depth cubes lose
// more than that margin to their pixels and the panels' inset; cut into piece pairs, each covered by one
// wall, the shaft pass proves it.
World two_walls_at_different_depths(uint32_t& target) {
    World w;
    const glm::vec3 size(14, 3, 8);
    add_closed_room(w, size);
    test::add_box(w, "near", Aabb::of({5.975f, 0, 0}, {6.025f, size.y, 4.3f}));
    test::add_box(w, "far", Aabb::of({8.975f, 0, 4.45f}, {9.025f, size.y, size.z}));
    target = test::add_box(w, "target", Aabb::of({11, 0.5f, 3}, {11.5f, 2.5f, 5}));
    w.view_seeds = {{2.5f, 1.5f, 3.5f}, {12.5f, 1.5f, 4}};
    return w;
}

TEST(Conservative, BehindTwoWallsAtDifferentDepthsTheShaftPassCulls) {
    uint32_t target = 0;
    const World w = two_walls_at_different_depths(target);
    BakeConfig c = conservative_config();
    const auto listed = [&](int budget, uint64_t& shaft_hidden) {
        c.conservative.shaft_budget = budget;
        return listed_at(c, w, {2.5f, 1.5f, 3.5f}, target, shaft_hidden);
    };
    uint64_t without_hidden = 0, with_hidden = 0;
    EXPECT_TRUE(listed(0, without_hidden)) << "the cubes alone prove it: the scene no longer tests the pass";
    EXPECT_EQ(without_hidden, 0u);
    EXPECT_FALSE(listed(1024, with_hidden)) << "the shaft pass did not prove what the two walls hide";
    EXPECT_GT(with_hidden, 0u);
}

// THE SHAFT PASS'S CAP (docs/ALGORITHMS.md#shaft-cap): the scene above, whose target only the pass proves,
// on the grid and the octree. Within the cap (the default) the pass runs and culls the target; a cap below
// cells x objects skips it (the target stays listed, the figure says how many candidates were skipped), and
// the file is then the one a bake with the pass off writes.
TEST(Conservative, TheShaftPassRunsWithinItsCapAndIsSkippedOverIt) {
    uint32_t target = 0;
    const World w = two_walls_at_different_depths(target);
    const glm::vec3 eye(2.5f, 1.5f, 3.5f);
    for (const CellKind kind : {CellKind::kGrid, CellKind::kOctree}) {
        BakeConfig c = conservative_config();
        c.cells.kind = kind;
        c.conservative.shaft_budget = 1024;
        const BakeData within = bake_without_misses(c, w);
        EXPECT_EQ(figure(within, "conservative_shaft_skipped_candidates"), 0.0);
        EXPECT_FALSE(within.pvs.test(uint32_t(within.cells.find(eye)), target)) << "within the cap";
        c.conservative.shaft_max_pairs = 1;
        const BakeData over = bake_without_misses(c, w);
        EXPECT_GT(figure(over, "conservative_shaft_skipped_candidates"), 0.0);
        EXPECT_TRUE(over.pvs.test(uint32_t(over.cells.find(eye)), target)) << "over the cap";
        c.conservative.shaft_budget = 0;
        c.conservative.shaft_max_pairs = BakeConfig().conservative.shaft_max_pairs;
        const BakeData off = bake_without_misses(c, w);
        EXPECT_EQ(over.pvs.words, off.pvs.words);
        EXPECT_EQ(figure(off, "conservative_shaft_skipped_candidates"), 0.0);
    }
}

// A small bake's pass doubles its pair budget while cells x objects x the budget stay within
// --shaft-small-spend (docs/ALGORITHMS.md#shaft-small): at most six times and to 4096; never where the pass
// does not run, and never with the spend off.
TEST(Conservative, ASmallBakesShaftPassDoublesItsBudgetWithinItsSpend) {
    World w;
    w.objects.resize(100);
    ConservativeConfig c;  // budget 64, spend 8 M piece pairs, cap 4 M pairs
    EXPECT_EQ(shaft_pair_budget(c, w, 10), 4096) << "1,000 candidates";
    EXPECT_EQ(shaft_pair_budget(c, w, 400), 128) << "40,000 candidates: 5.1 M at 128, 10.2 M at 256";
    EXPECT_EQ(shaft_pair_budget(c, w, 1000), 64) << "100,000 candidates: 12.8 M at 128";
    EXPECT_EQ(shaft_pair_budget(c, w, 100000), 64) << "over the cap: the pass does not run";
    w.objects[0].flags |= kObjectAlwaysVisible;  // 99 candidates a cell
    EXPECT_EQ(shaft_pair_budget(c, w, 640), 128) << "63,360 candidates: 8.1 M at 128";
    c.shaft_budget = 1024;
    EXPECT_EQ(shaft_pair_budget(c, w, 1), 4096) << "not past --shaft-budget's own limit";
    c.shaft_budget = 0;
    EXPECT_EQ(shaft_pair_budget(c, w, 1), 0) << "no pass";
    c.shaft_budget = 64;
    c.shaft_small_spend = 0.0;
    EXPECT_EQ(shaft_pair_budget(c, w, 1), 64) << "the spend off";
}

// Every row of `fewer` lists at most what the same cell's row of `more` lists (the same grid); `why` says
// what a pair listed only by `fewer` would mean.
void expect_rows_within(const BakeData& fewer, const BakeData& more, const std::string& why) {
    ASSERT_EQ(fewer.cells.size(), more.cells.size());
    for (uint32_t cell = 0; cell < more.cells.size(); ++cell)
        for (uint32_t o = 0; o < more.pvs.object_count; ++o)
            EXPECT_FALSE(fewer.pvs.test(cell, o) && !more.pvs.test(cell, o))
                << "cell " << cell << ", object " << o << ": " << why;
}

// OVER THE CAP, THE HEAVIEST FIRST (docs/ALGORITHMS.md#shaft-cap): a pass whose cells x objects are over
// --shaft-max-pairs tries the floor(cap / cells) objects with the most triangles (ties: the lower index),
// never an always-visible one, in index order; none when not even one fits, when they hold less than
// --shaft-min-share of the triangles, or when the budget is off. The digest tells a re-bake which: 0 for
// all, else a hash of the names that ignores their order.
TEST(Conservative, OverItsCapTheShaftPassTriesTheObjectsWithTheMostTriangles) {
    World w;
    w.objects.resize(6);
    const uint32_t tris[6] = {4, 30, 12, 30, 2, 50};
    for (uint32_t o = 0; o < 6; ++o) {
        w.objects[o].triangle_count = tris[o];
        w.objects[o].name = "object" + std::to_string(o);
    }
    w.objects[5].flags |= kObjectAlwaysVisible;  // the heaviest, but always listed: never tried
    ConservativeConfig c;
    c.shaft_max_pairs = 50;  // 10 cells: all 5 leavable; 20 or 25 cells: 2; 40: 1; 60: none
    EXPECT_EQ(shaft_objects(c, w, 10), (std::vector<uint32_t>{0, 1, 2, 3, 4})) << "within the cap: all";
    EXPECT_EQ(shaft_objects_digest(w, shaft_objects(c, w, 10)), 0.0);
    EXPECT_EQ(shaft_objects(c, w, 20), (std::vector<uint32_t>{1, 3})) << "the two of 30 triangles: 60 of 78";
    EXPECT_EQ(shaft_objects(c, w, 25), (std::vector<uint32_t>{1, 3}));
    EXPECT_TRUE(shaft_objects(c, w, 40).empty()) << "30 of 78 triangles: under the default share, a half";
    c.shaft_min_share = 0.0;
    EXPECT_EQ(shaft_objects(c, w, 40), (std::vector<uint32_t>{1})) << "a tie: the lower index";
    EXPECT_TRUE(shaft_objects(c, w, 60).empty());
    EXPECT_TRUE(shaft_pass_runs(c, w, 40));
    EXPECT_FALSE(shaft_pass_runs(c, w, 60));
    c.shaft_max_pairs = 0;
    EXPECT_EQ(shaft_objects(c, w, 1000000).size(), 5u) << "no limit";
    c.shaft_budget = 0;
    EXPECT_TRUE(shaft_objects(c, w, 1).empty()) << "the pass off";
    // The digest: of the names, whatever their order; another choice, another digest.
    const double d13 = shaft_objects_digest(w, {1, 3}), d1 = shaft_objects_digest(w, {1});
    EXPECT_NE(d13, 0.0);
    EXPECT_NE(d13, d1);
    std::swap(w.objects[1].name, w.objects[3].name);
    EXPECT_EQ(shaft_objects_digest(w, {1, 3}), d13);
}

// The scene of the two walls with a second target behind them both (a shelf above the first), lighter than
// it (12 triangles against 24); over the cap with room for one object a cell (and no least share), the pass
// proves the heavier and leaves the lighter listed, the report says what it tried, and every row lies
// between the full pass's and no pass's. With the default least share (a half) one object is too few: the
// pass does not run.
TEST(Conservative, OverItsCapTheShaftPassProvesTheHeaviestAndListsTheRest) {
    uint32_t heavy = 0;
    World w = two_walls_at_different_depths(heavy);
    {  // the target's triangles twice: an object of 24 (its triangles are the world's last)
        const uint32_t copy = test::add_box(w, "copy", w.objects[heavy].bounds);
        ASSERT_EQ(copy, heavy + 1);
        w.objects[heavy].triangle_count += w.objects[copy].triangle_count;
        w.objects.pop_back();
    }
    const uint32_t light = test::add_box(w, "light", Aabb::of({11, 2.6f, 3}, {11.5f, 2.9f, 5}));
    const glm::vec3 eye(2.5f, 1.5f, 3.5f);
    BakeConfig c = conservative_config();
    c.conservative.shaft_budget = 1024;
    const BakeData all = bake_without_misses(c, w);
    const uint32_t cell = uint32_t(all.cells.find(eye));
    ASSERT_FALSE(all.pvs.test(cell, heavy)) << "the full pass no longer proves the scene";
    ASSERT_FALSE(all.pvs.test(cell, light)) << "the full pass no longer proves the scene";
    EXPECT_EQ(figure(all, "conservative_shaft_objects"), double(w.objects.size()));
    EXPECT_EQ(figure(all, "conservative_shaft_objects_digest"), 0.0);
    c.conservative.shaft_budget = 0;
    const BakeData off = bake_without_misses(c, w);
    ASSERT_TRUE(off.pvs.test(cell, light))
        << "the cubes alone prove the light target: the scene tests nothing";
    c.conservative.shaft_budget = 1024;
    c.conservative.shaft_max_pairs = all.cells.size();  // one object a cell
    const BakeData too_few = bake_without_misses(c, w);
    EXPECT_EQ(figure(too_few, "conservative_shaft_objects"), 0.0);
    EXPECT_EQ(too_few.pvs.words, off.pvs.words) << "under the least share the pass does not run";
    c.conservative.shaft_min_share = 0.0;
    const BakeData one = bake_without_misses(c, w);
    EXPECT_FALSE(one.pvs.test(cell, heavy)) << "the heaviest object is tried and proven";
    EXPECT_TRUE(one.pvs.test(cell, light)) << "the lighter one is not tried";
    EXPECT_EQ(figure(one, "conservative_shaft_objects"), 1.0);
    EXPECT_NEAR(figure(one, "conservative_shaft_objects_triangle_share"), 24.0 / double(w.triangles.size()),
                1e-12);
    EXPECT_NE(figure(one, "conservative_shaft_objects_digest"), 0.0);
    EXPECT_EQ(figure(one, "conservative_shaft_skipped_candidates"),
              double(all.cells.size() * (w.objects.size() - 1)));
    expect_rows_within(all, one, "the full pass lists what the heaviest-first pass does not");
    expect_rows_within(one, off, "the heaviest-first pass lists what no pass does not");
    // The octree decides per level over the cells its boxes can split into; its boxes then choose alike
    // (driver/bake.cpp): a level over the cap runs a partial pass, with no miss.
    c.cells.kind = CellKind::kOctree;
    c.conservative.shaft_max_pairs = 3 * all.cells.size();
    const BakeData octree = bake_without_misses(c, w);
    EXPECT_GE(figure(octree, "conservative_shaft_objects"), 1.0);
    EXPECT_LT(figure(octree, "conservative_shaft_objects"), double(w.objects.size()))
        << "no level over the cap";
    EXPECT_NE(figure(octree, "conservative_shaft_objects_digest"), 0.0);
    EXPECT_GT(figure(octree, "conservative_shaft_skipped_candidates"), 0.0);
}

// THE SHAFT PASS'S HIERARCHY (docs/ALGORITHMS.md#shaft-hierarchy): the scene above on 1 m cells, the pass
// over blocks of 4 x 4 x 4 cells halved down to cells. A node's proof holds for every cell of it, and a
// node that cannot prove an object hands it to its halves, down to the cells, which try it exactly as the
// per-cell pass does; so every row lists at most what the per-cell pass lists, and at most what the bake
// without the pass lists. The target is proven hidden from several cells by one node's proof (more cells
// settled than proofs), cells still prove what no node of theirs tried or proved, fewer cells try alone,
// and dense rays find no miss.
TEST(Conservative, TheShaftHierarchyProvesWhatThePerCellPassProvesAndNodesSettleTheirCells) {
    uint32_t target = 0;
    const World w = two_walls_at_different_depths(target);
    BakeConfig c = conservative_config();
    c.conservative.shaft_budget = 1024;
    const BakeData per_cell = bake_without_misses(c, w);
    c.conservative.shaft_block = 4;
    const BakeData tree = bake_without_misses(c, w);
    c.conservative.shaft_budget = 0;
    const BakeData off = bake_without_misses(c, w);
    EXPECT_LT(grid_shaft_blocks(tree.cells, 4).size(), tree.cells.size());
    expect_rows_within(per_cell, off, "listed only with the pass");
    expect_rows_within(tree, per_cell, "the per-cell pass proved it hidden, the hierarchy did not");
    uint64_t node_proofs = 0, node_settled = 0;
    for (int l = 1; l < kShaftLevels; ++l) {
        const std::string at = "conservative_shaft_level" + std::to_string(l) + "_";
        node_proofs += uint64_t(figure(tree, at + "proven"));
        node_settled += uint64_t(figure(tree, at + "settled"));
    }
    EXPECT_GT(node_proofs, 0u) << "no node proved anything";
    EXPECT_GT(node_settled, node_proofs) << "no node proof settled more than one cell";
    EXPECT_GT(figure(tree, "conservative_shaft_level0_proven"), 0.0) << "no cell of a failed node proved";
    EXPECT_LT(figure(tree, "conservative_shaft_level0_tried"), figure(per_cell, "conservative_shaft_level0_tried"));
    uint32_t hidden_near_eye = 0;
    for (const glm::vec3 eye : {glm::vec3(2.5f, 1.5f, 3.5f), glm::vec3(3.5f, 1.5f, 3.5f),
                                glm::vec3(2.5f, 1.5f, 2.5f), glm::vec3(3.5f, 1.5f, 2.5f)}) {
        const int32_t cell = tree.cells.find(eye);
        ASSERT_GE(cell, 0);
        hidden_near_eye += off.pvs.test(uint32_t(cell), target) && !tree.pvs.test(uint32_t(cell), target);
    }
    EXPECT_GE(hidden_near_eye, 1u) << "the hierarchy proved the target hidden from no cell the cubes left it in";
}

// GIVING UP WHERE BOTH WITNESSES FAIL (docs/ALGORITHMS.md#shaft-give-up): on a random world, the pass over
// blocks of 4 x 4 x 4 cells with nodes of every level giving up what both their witnesses could not prove.
// A given-up pair only stays listed, so every row lists at least what the exact hierarchy lists and at most
// what the bake without the pass lists; pairs are given up, and fewer proofs are tried.
TEST(Conservative, NodesWhoseWitnessesBothFailGiveUpTheirCellsAndRowsOnlyGrow) {
    const World w = make_random_world(4, 0).world;
    BakeConfig c = conservative_config();
    c.conservative.shaft_budget = 256;
    c.conservative.shaft_block = 4;
    const BakeData exact = bake_without_misses(c, w);
    c.conservative.shaft_give_up = 1;
    const BakeData given_up = bake_without_misses(c, w);
    c.conservative.shaft_budget = 0;
    const BakeData off = bake_without_misses(c, w);
    expect_rows_within(exact, given_up, "giving up left out what the exact pass lists");
    expect_rows_within(given_up, off, "listed only with the pass");
    double given = 0.0;
    for (int l = 1; l < kShaftLevels; ++l)
        given += figure(given_up, "conservative_shaft_level" + std::to_string(l) + "_given_up");
    EXPECT_GT(given, 0.0) << "no node gave up: the world no longer tests the rule";
    EXPECT_LT(figure(given_up, "conservative_shaft_pairs"), figure(exact, "conservative_shaft_pairs"));
    EXPECT_EQ(figure(exact, "conservative_shaft_level1_given_up"), 0.0);
}

// THE BLOCKS' PROOFS BEFORE THE FACES (docs/ALGORITHMS.md#shaft-early): on the two-walls scene and a random
// world, each block's root tries, before the faces, what no probe ray from it reaches. What it proves, no
// face tests and no row lists: rows list at most what the bake without the pass lists, the early proofs
// settle several cells each, the faces draw fewer samples, and dense rays find no miss.
TEST(Conservative, BlocksProveBeforeTheFacesAndTheFacesSkipWhatTheyProve) {
    uint32_t target = 0;
    const World scene = two_walls_at_different_depths(target);
    const World random = make_random_world(4, 0).world;
    for (const auto& [w, block] : {std::pair{&scene, 4}, std::pair{&random, 2}}) {
        SCOPED_TRACE(fmt::format("{} world, blocks of {}", w == &scene ? "scene" : "random", block));
        BakeConfig c = conservative_config();
        c.conservative.shaft_budget = 256;
        c.conservative.shaft_block = block;
        const BakeData late = bake_without_misses(c, *w);
        c.conservative.shaft_early = true;
        const BakeData early = bake_without_misses(c, *w);
        c.conservative.shaft_budget = 0;
        const BakeData off = bake_without_misses(c, *w);
        expect_rows_within(early, off, "listed only with the pass");
        EXPECT_GT(figure(early, "conservative_shaft_early_proven"), 0.0);
        EXPECT_GT(figure(early, "conservative_shaft_early_settled"),
                  figure(early, "conservative_shaft_early_proven"));
        EXPECT_LT(figure(early, "conservative_samples"), figure(late, "conservative_samples"));
        EXPECT_EQ(figure(late, "conservative_shaft_early_tried"), 0.0);
    }
}

// THE PROBE (docs/ALGORITHMS.md#shaft-probe): rays from eye points of a cell settle what they reach as
// visible before the shaft pass tries a proof. A proof only holds for what no eye sees, so the rows are
// those of the pass without the probe, on the scene above and on a random world, per cell and by blocks;
// the probe settles pairs, and the pass tries fewer.
TEST(Conservative, TheShaftProbeSettlesVisiblePairsAndChangesNoRow) {
    uint32_t target = 0;
    const World scene = two_walls_at_different_depths(target);
    const World random = make_random_world(4, 0).world;
    for (const auto& [w, block] : {std::pair{&scene, 1}, std::pair{&scene, 4}, std::pair{&random, 2}}) {
        SCOPED_TRACE(fmt::format("{} world, blocks of {}", w == &scene ? "scene" : "random", block));
        BakeConfig c = conservative_config();
        c.conservative.shaft_budget = 256;
        c.conservative.shaft_block = block;
        c.conservative.shaft_probe_rays = 0;
        const BakeData without = bake_without_misses(c, *w);
        c.conservative.shaft_probe_rays = 64;
        const BakeData with = bake_without_misses(c, *w);
        EXPECT_EQ(with.pvs.words, without.pvs.words);
        EXPECT_GT(figure(with, "conservative_shaft_probe_seen"), 0.0);
        EXPECT_LT(figure(with, "conservative_shaft_pairs"), figure(without, "conservative_shaft_pairs"));
        EXPECT_EQ(figure(without, "conservative_shaft_probe_rays"), 0.0);
    }
}

// CROSS-PLANE FUSION (docs/ALGORITHMS.md#cross-plane-fusion). A closed room 14 x 3 x 8 m; two full-height
// walls 5 cm thick (only their faces as occluders) meet at a right angle: the near one at x = 6 from z = 0
// to 4, the far one at z = 4 from x = 6 to 12, closing a pocket open to the room only at x in [12, 14]. A
// target in the pocket, near the corner, is hidden from the cell at x in [2, 3], z in [5, 6] by the two
// walls together: every line from the cell passes the corner on one side or the other. Neither wall alone
// hides it, the cubes lose the corner to the panels' inset, and one plane's cover never fuses the two
// walls at their edge; the umbra of one wall on the other's plane does, so does the convex cap of the
// walls' two outer faces at the corner, and so does the flood (the two walls cut the shaft in two). Each
// bake is verified by dense rays.
TEST(Conservative, BehindTwoWallsMeetingAtACornerTheFusedShaftPassCulls) {
    World w;
    const glm::vec3 size(14, 3, 8);
    add_closed_room(w, size);
    test::add_box(w, "near", Aabb::of({5.975f, 0, 0}, {6.025f, size.y, 4.025f}));
    test::add_box(w, "far", Aabb::of({5.975f, 0, 3.975f}, {12.0f, size.y, 4.025f}));
    const uint32_t target = test::add_box(w, "target", Aabb::of({6.5f, 0.5f, 2.5f}, {7.0f, 2.5f, 3.5f}));
    w.view_seeds = {{2.5f, 1.5f, 5.5f}, {9.0f, 1.5f, 1.5f}};
    BakeConfig c = conservative_config();
    const auto listed = [&](int budget, bool fusion, bool caps, bool flood, uint64_t& shaft_hidden) {
        c.conservative.shaft_budget = budget;
        c.conservative.shaft_fusion = fusion;
        c.conservative.shaft_caps = caps;
        c.conservative.shaft_flood = flood;
        return listed_at(c, w, {2.5f, 1.5f, 5.5f}, target, shaft_hidden);
    };
    uint64_t hidden = 0;
    EXPECT_TRUE(listed(0, true, true, true, hidden))
        << "the cubes alone prove it: the scene no longer tests the pass";
    EXPECT_TRUE(listed(1024, false, false, false, hidden))
        << "one plane's cover proved the corner: the scene is not telling";
    EXPECT_FALSE(listed(1024, true, false, false, hidden))
        << "the fused shaft pass did not prove what the corner hides";
    EXPECT_GT(hidden, 0u);
    // The walls' outer faces at the corner also make a convex cap (docs/ALGORITHMS.md#convex-caps).
    EXPECT_FALSE(listed(1024, false, true, false, hidden)) << "the convex cap of the corner did not prove it";
    EXPECT_GT(hidden, 0u);
    // And the two walls separate the cell from the pocket in the shaft (docs/ALGORITHMS.md#shaft-flood).
    EXPECT_FALSE(listed(1024, false, false, true, hidden)) << "the flood did not prove what the corner hides";
    EXPECT_GT(hidden, 0u);
}

// The safety property of block occluders, on the yard: no ray from eyes of a block (fresh ones, not those
// synthesis used) reaches a point inside one of that block's shrunk boxes before an opaque triangle.
TEST(Conservative, NoRayFromABlocksEyesReachesIntoItsOwnOccluders) {
    with_yard_blocks([](const ViewVolume& view, const RayScene& scene, const ShrunkOccluders& shrunk,
                        const BlockFigures&) {
        const BlockAudit r = audit_block_occluders(view, scene, shrunk, 128, 8, 99);
        EXPECT_GT(r.blocks, 0u);
        EXPECT_GT(r.rays, 100000u);
        EXPECT_EQ(r.reached, 0u) << r.first;
    });
}

// The same on an octree: its nodes take their block's occluders too (conservative_box_rows).
TEST(Conservative, OnAnOctreeTheWestCellsCullTheCrateBehindTheHollowWall) {
    uint32_t crate = 0;
    const World w = blocked_yard(crate);
    BakeConfig c = conservative_config();
    c.view.play_height_m = 2.0;
    c.cells.kind = CellKind::kOctree;
    c.cells.min_cell_size_m = 2.0;
    c.cells.root_cell_size_m = 8.0;
    c.occluders.block_m = 8.0;
    const BakeData bake = bake_without_misses(c, w);
    const int32_t west = bake.cells.find({3, 1, 6}), east = bake.cells.find({27, 1, 6});
    ASSERT_GE(west, 0);
    ASSERT_GE(east, 0);
    EXPECT_TRUE(bake.pvs.test(uint32_t(east), crate));
    EXPECT_FALSE(bake.pvs.test(uint32_t(west), crate));
}

// ---- Property: on random enclosed box worlds the conservative bake misses nothing dense rays see ----
// (the worlds: samples/random_world.h)

std::string text(glm::vec3 v) {
    std::ostringstream s;
    s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return s.str();
}

std::string text(const Aabb& b) {
    return text(b.min) + "-" + text(b.max);
}

// The bake builds the epsilon ladder only as high as its cells' faces can use: on 1 m cells with epsilon
// 0.1 m, the levels 0.1 to 0.8 m (a face's top patch has a half-side of 0.5 m). The rows are those of the
// whole ladder of refine_levels, whose higher levels no patch is ever sampled at.
// The global shrunk occluders a conservative bake of `world` with config `c` solves against.
ShrunkOccluders shrunk_occluders(Context& ctx, const BakeConfig& c, const World& world,
                                 const RayScene& scene) {
    const ViewVolume view = build_view_volume(ctx, c.view, world);
    OccluderFigures f;
    ShrunkOccluders out;
    synthesize_occluders(ctx, c.occluders, world, view, scene, f, c.conservative.epsilon_m,
                         c.conservative.refine_levels, &out);
    return out;
}

// A scene baked with the scene tests' settings, with the global shrunk occluders its bake solved against:
// for tests that call the solver directly on the bake's eye space.
struct SolvedScene {
    Context ctx = quiet_context();
    Scene s;
    BakeConfig c = conservative_config();
    RayScene scene;
    ShrunkOccluders occ;
    BakeData bake;
    explicit SolvedScene(Middle middle)
        : s(make_scene(middle)),
          scene(ctx, s.world),
          occ(shrunk_occluders(ctx, c, s.world, scene)),
          bake(bake_world(ctx, c, s.world, "test", "")) {}
};

TEST(Conservative, TheLadderStopsAtTheLevelTheCellsUseWithTheSameRows) {
    BakeConfig c = conservative_config();
    EXPECT_EQ(largest_cell_edge_m(c.cells), 1.0);
    EXPECT_EQ(conservative_levels_used(c.conservative, 1.0), 3);
    EXPECT_EQ(conservative_levels_used(c.conservative, 0.2), 0);
    EXPECT_EQ(conservative_levels_used(c.conservative, 0.25), 1);
    EXPECT_EQ(conservative_levels_used(c.conservative, 100.0), c.conservative.refine_levels);
    CellConfig octree;
    octree.kind = CellKind::kOctree;
    octree.min_cell_size_m = 1.0;
    octree.root_cell_size_m = 12.0;  // rounded to 16 = 1 m * 2^4, as build_octree() does
    EXPECT_EQ(largest_cell_edge_m(octree), 16.0);

    Context ctx = quiet_context();
    const Scene s = make_scene(Middle::kFusedHalves);
    const BakeData bake = bake_world(ctx, c, s.world, "test", "");
    EXPECT_EQ(figure(bake, "conservative_epsilon_levels"), 4.0);
    RayScene scene(ctx, s.world);
    const ShrunkOccluders whole = shrunk_occluders(ctx, c, s.world, scene);
    ASSERT_EQ(whole.epsilon_m.size(), size_t(c.conservative.refine_levels) + 1);
    ConservativeFigures cf;
    const PvsSet rows = bake_conservative_pvs(ctx, c.conservative, s.world, bake.cells, whole, scene, cf);
    EXPECT_TRUE(rows == bake.pvs);
    const int32_t cell = bake.cells.find({2.5f, 1.5f, 1.0f});
    ASSERT_GE(cell, 0);
    EXPECT_FALSE(bake.pvs.test(uint32_t(cell), s.target));
}

// A face skips the objects its cell already lists (the grid solves its faces in six phases; the box path one
// face after another). On the doorway scene, whose target some cells see and others do not: skips happen,
// the rows are the same for any thread count, and the grid's shared faces give the same rows as solving
// every cell's six faces on its own (conservative_box_rows), including who sees the target.
TEST(Conservative, FacesSkipWhatTheirCellListsWithTheSameRowsForAnyThreadCount) {
    SolvedScene t(Middle::kDoorway);
    Context& ctx = t.ctx;
    const CellSet& cells = t.bake.cells;
    ASSERT_GT(cells.size(), 10u);

    std::vector<PvsSet> by_threads;
    for (int threads : {1, 3}) {
        omp_set_num_threads(threads);
        ConservativeFigures cf;
        by_threads.push_back(
            bake_conservative_pvs(ctx, t.c.conservative, t.s.world, cells, t.occ, t.scene, cf));
        EXPECT_GT(cf.known_listed, 0u) << threads << " threads";
    }
    omp_set_num_threads(omp_get_num_procs());
    EXPECT_TRUE(by_threads[0] == by_threads[1]);

    std::vector<Aabb> boxes;
    for (const Cell& cell : cells.cells) boxes.push_back(cell.bounds);
    PvsSet each = PvsSet::make(uint32_t(cells.size()), uint32_t(t.s.world.objects.size()));
    ConservativeFigures cf;
    conservative_box_rows(ctx, t.c.conservative, t.s.world, boxes, cells.eyes, t.occ, t.scene, each, cf);
    EXPECT_GT(cf.known_listed, 0u);
    EXPECT_TRUE(each == by_threads[1]);

    // Who sees the target: the cell in front of the doorway (x in [4, 5], z in [0.5, 1.5]) and one on the
    // target's side do; a cell in the far corner (x in [0, 1], z in [5, 6]) does not.
    const auto lists_target = [&](glm::vec3 p) {
        const int32_t cell = cells.find(p);
        EXPECT_GE(cell, 0) << p.x << ", " << p.y << ", " << p.z;
        return cell >= 0 && by_threads[1].test(uint32_t(cell), t.s.target);
    };
    EXPECT_TRUE(lists_target({4.5f, 1.5f, 1.0f}));
    EXPECT_TRUE(lists_target({8.5f, 1.5f, 3.0f}));
    EXPECT_FALSE(lists_target({0.5f, 1.5f, 5.5f}));
}

// An octree box tests only what its parent's row lists (docs/ALGORITHMS.md#octree-parent-bound). On the
// solid-wall scene, a 4 m box in the west half (from which the target is hidden) and its eight children:
// every child's row lies in the parent's and in its own row without the bound; each child skips exactly what
// the parent left out; and the bound is really applied: a bound that leaves out the far wall of the doorway,
// which the child in front of it sees, leaves it out of that child's row.
TEST(Conservative, AnOctreeBoxTestsOnlyWhatItsParentLists) {
    SolvedScene t(Middle::kSolid);
    Context& ctx = t.ctx;
    const uint32_t n_objects = uint32_t(t.s.world.objects.size());
    const Aabb parent = Aabb::of({0, 0, 0}, {4, 4, 4});
    std::vector<Aabb> children;
    for (int o = 0; o < 8; ++o)
        children.push_back(Aabb::of({o & 1 ? 2.0f : 0.0f, o & 2 ? 2.0f : 0.0f, o & 4 ? 2.0f : 0.0f},
                                    {o & 1 ? 4.0f : 2.0f, o & 2 ? 4.0f : 2.0f, o & 4 ? 4.0f : 2.0f}));
    const auto rows_of = [&](const std::vector<Aabb>& boxes, const std::vector<const uint64_t*>* bounds,
                             ConservativeFigures& cf) {
        PvsSet rows = PvsSet::make(uint32_t(boxes.size()), n_objects);
        conservative_box_rows(ctx, t.c.conservative, t.s.world, boxes, t.bake.cells.eyes, t.occ, t.scene,
                              rows, cf, nullptr, bounds);
        return rows;
    };
    ConservativeFigures cf_parent, cf_free, cf_bound, cf_fake;
    const PvsSet parent_row = rows_of({parent}, nullptr, cf_parent);
    ASSERT_LT(parent_row.count(0), n_objects) << "the parent culls nothing: the bound would be vacuous";
    const PvsSet free_rows = rows_of(children, nullptr, cf_free);
    const std::vector<const uint64_t*> bounds(children.size(), parent_row.row(0));
    const PvsSet bound_rows = rows_of(children, &bounds, cf_bound);
    EXPECT_EQ(cf_free.parent_hidden, 0u);
    uint64_t with_eyes = 0;
    for (const Aabb& child : children) with_eyes += eye_region(t.bake.cells.eyes, child).is_empty() ? 0 : 1;
    EXPECT_EQ(with_eyes, children.size());
    EXPECT_EQ(cf_bound.parent_hidden, uint64_t(n_objects - parent_row.count(0)) * with_eyes)
        << "every child skips exactly what the parent left out (no object is always visible here)";
    for (uint32_t i = 0; i < children.size(); ++i)
        for (uint32_t o = 0; o < n_objects; ++o) {
            if (!bound_rows.test(i, o)) continue;
            EXPECT_TRUE(parent_row.test(0, o))
                << "child " << i << " lists object " << o << " its parent left out";
            EXPECT_TRUE(free_rows.test(i, o))
                << "child " << i << " lists object " << o << " only with the bound";
        }
    EXPECT_FALSE(parent_row.test(0, t.s.target));
    // The child at x in [2, 4], z in [2, 4] (o = 5), low, sees the west face of the wall beyond the doorway.
    uint32_t far_wall = n_objects;
    for (uint32_t o = 0; o < n_objects; ++o)
        if (t.s.world.objects[o].name == "wall_far") far_wall = o;
    ASSERT_LT(far_wall, n_objects);
    ASSERT_TRUE(free_rows.test(5, far_wall));
    EXPECT_TRUE(bound_rows.test(5, far_wall));
    std::vector<uint64_t> fake(parent_row.words_per_row, ~uint64_t(0));
    fake[far_wall >> 6] &= ~(uint64_t(1) << (far_wall & 63));
    const std::vector<const uint64_t*> fake_bounds(children.size(), fake.data());
    const PvsSet fake_rows = rows_of(children, &fake_bounds, cf_fake);
    EXPECT_FALSE(fake_rows.test(5, far_wall)) << "the bound was not applied";
}

// The scene tests' settings (0.1 m voxels and epsilon, default cube maps) on 2 m cells, verified by many
// more rays than a bake would spend, with a seed of their own per world.
BakeConfig property_config(uint64_t seed) {
    BakeConfig c = conservative_config();
    c.cells.cell_size_m = 2.0;
    const uint64_t verify_seed = 0x5eed0000ULL + seed;
    c.verify.rays =
        test::in_ci() ? SampleConfig{16, 1024, 0, verify_seed} : SampleConfig{32, 2048, 0, verify_seed};
    // The first world takes the second look on a fine cube at floor samples (--fine-cube-resolution; it
    // costs about 4x the PVS time, so only one).
    if (seed == 1) c.conservative.fine_cube_resolution = 256;
    // The second world halves its floor patches once more for the panels (--panel-refine-levels; about
    // 4x the PVS time too).
    if (seed == 2) c.conservative.panel_refine_levels = 1;
    // The third draws the slanted panels, the corner pairs and the panels' depth bands on the depth cubes
    // (--slanted-cubes, --corner-pairs, --panel-bands).
    if (seed == 3) {
        c.conservative.slanted_cubes = true;
        c.conservative.corner_pairs = true;
        c.conservative.panel_bands = true;
    }
    // The fourth to sixth take the shaft pass on what the faces listed (--shaft-budget), the sixth over the
    // hierarchy of blocks of 2 x 2 x 2 cells (--shaft-block), with the blocks' proofs before the faces
    // (--shaft-early) and nodes giving up where both witnesses fail (--shaft-give-up).
    if (seed >= 4 && seed <= 6) c.conservative.shaft_budget = 256;
    if (seed == 6) {
        c.conservative.shaft_block = 2;
        c.conservative.shaft_early = true;
        c.conservative.shaft_give_up = 1;
    }
    return c;
}

// Bakes `worlds` random box worlds on `cells` and verifies each with dense rays: zero misses, and the bake
// culls something. Returns the sum of the bakes' figure `figure_name` (so a caller can check that a
// mechanism took part).
double random_worlds_have_no_miss(const CellConfig& cells, uint64_t worlds, const std::string& figure_name) {
    double figure_sum = 0.0;
    uint64_t cells_total = 0, listed_total = 0, pairs_total = 0, sampled_total = 0, rays_total = 0;
    uint32_t worlds_culling = 0;
    uint64_t fine_samples = 0, panel_splits = 0, region_hidden = 0, shaft_hidden = 0;
    for (uint64_t seed = 1; seed <= worlds; ++seed) {
        SCOPED_TRACE("world seed " + std::to_string(seed));
        const auto start = std::chrono::steady_clock::now();
        Context ctx = quiet_context();
        RandomWorld rw;
        BakeData bake;
        bool baked = false;
        // A world whose view volume cannot be built (no seed in free space) is drawn again,
        // deterministically.
        for (uint64_t attempt = 0; attempt < 5 && !baked; ++attempt) {
            rw = make_random_world(seed, attempt);
            try {
                BakeConfig config = property_config(seed);
                if (cells.kind == CellKind::kOctree) config.cells = cells;
                bake = bake_world(ctx, config, rw.world, "random", "");
                baked = true;
            } catch (const Error& e) {
                if (e.kind() != ErrorKind::kBadInput) throw;
                std::printf("world seed %llu attempt %llu: %s; drawn again\n", (unsigned long long)seed,
                            (unsigned long long)attempt, e.what());
            }
        }
        EXPECT_TRUE(baked) << "no usable world in 5 attempts";
        EXPECT_TRUE(bake.conservative);
        EXPECT_TRUE(bake.verification.ran);
        EXPECT_GT(bake.cells.size(), 0u);
        if (!baked || !bake.conservative || !bake.verification.ran || bake.cells.size() == 0)
            return figure_sum;
        const World& w = rw.world;
        const uint32_t n_objects = uint32_t(w.objects.size());

        fine_samples += uint64_t(figure(bake, "conservative_fine_samples"));
        panel_splits += uint64_t(figure(bake, "conservative_panel_splits"));
        region_hidden += uint64_t(figure(bake, "conservative_region_hidden"));
        shaft_hidden += uint64_t(figure(bake, "conservative_shaft_hidden"));
        figure_sum += figure(bake, figure_name);
        const uint64_t missed_pairs = uint64_t(figure(bake.verification.figures, "missed_pairs"));
        EXPECT_EQ(missed_pairs, 0u) << "world seed " << seed << ": " << bake.verification.misses.size()
                                    << " misses reported";
        EXPECT_TRUE(bake.verification.misses.empty());
        if (!bake.verification.misses.empty()) {
            std::ostringstream m;
            m << "world seed " << seed << " (" << n_objects << " objects, " << bake.cells.size()
              << " cells); first misses:\n";
            for (size_t i = 0; i < std::min<size_t>(8, bake.verification.misses.size()); ++i) {
                const Miss& miss = bake.verification.misses[i];
                const WorldObject& o = w.objects[miss.object];
                m << "  cell " << miss.cell << " " << text(bake.cells.cells[miss.cell].bounds) << " misses '"
                  << o.name << "' " << text(o.bounds) << (o.flags & kObjectHasOpaque ? "" : " (see-through)")
                  << ": eye " << text(miss.eye) << " direction " << text(miss.direction) << " at "
                  << miss.distance_m << " m\n";
            }
            m << "world:\n";
            for (const WorldObject& o : w.objects)
                m << "  " << o.name << " " << text(o.bounds)
                  << (o.flags & kObjectHasOpaque ? "" : " see-through") << "\n";
            for (const glm::vec3& s : w.view_seeds) m << "  seed " << text(s) << "\n";
            ADD_FAILURE() << m.str();
        }

        uint64_t listed = 0, sampled = 0;
        for (uint32_t c = 0; c < bake.cells.size(); ++c) listed += bake.pvs.count(c);
        for (uint32_t n : bake.verification.cell_sampled_visible) sampled += n;
        EXPECT_GT(sampled, 0u) << "the rays saw nothing: the check is vacuous";
        const uint64_t pairs = uint64_t(bake.cells.size()) * n_objects;
        worlds_culling += listed < pairs;
        cells_total += bake.cells.size();
        listed_total += listed;
        pairs_total += pairs;
        sampled_total += sampled;
        const uint64_t rays = uint64_t(figure(bake.verification.figures, "rays"));
        rays_total += rays;
        std::printf(
            "world seed %2llu: %3u objects, %4zu cells, PVS %5.1f objects, rays saw %5.1f, %6.1f M rays, "
            "%.1f s\n",
            (unsigned long long)seed, n_objects, bake.cells.size(),
            double(listed) / double(bake.cells.size()), double(sampled) / double(bake.cells.size()),
            double(rays) * 1e-6,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::printf(
        "%llu worlds, %llu cells: PVS %.1f%% of objects, rays saw %.1f%%, %.1f M rays; %u worlds cull\n",
        (unsigned long long)worlds, (unsigned long long)cells_total,
        100.0 * double(listed_total) / double(pairs_total),
        100.0 * double(sampled_total) / double(pairs_total), double(rays_total) * 1e-6, worlds_culling);
    // Not vacuous: the bake leaves objects out somewhere (zero misses by listing everything proves nothing).
    EXPECT_LT(listed_total, pairs_total) << "no world culls anything";
    EXPECT_GE(worlds_culling * 2, uint32_t(worlds)) << "fewer than half the worlds cull anything";
    EXPECT_GT(fine_samples, 0u) << "no world took the second look on the fine cube";
    EXPECT_GT(panel_splits, 0u) << "no world halved a floor patch for the panels";
    EXPECT_GT(region_hidden, 0u) << "the single-occluder pass proved nothing in any world";
    EXPECT_GT(shaft_hidden, 0u) << "the shaft pass proved nothing in any world";
    return figure_sum;
}

TEST(ConservativeProperty, RandomBoxWorldsHaveNoMissAgainstDenseRays) {
    random_worlds_have_no_miss(CellConfig{}, test::in_ci() ? 6 : 20, "conservative_region_hidden");
}

// The octree: its boxes test only what their parents list (docs/ALGORITHMS.md#octree-parent-bound), and its
// leaves are verified as the grid's cells are.
TEST(ConservativeProperty, RandomBoxWorldsOnTheOctreeHaveNoMissAgainstDenseRays) {
    CellConfig octree;
    octree.kind = CellKind::kOctree;
    octree.min_cell_size_m = 1.0;
    octree.root_cell_size_m = 4.0;
    const double parent_hidden =
        random_worlds_have_no_miss(octree, test::in_ci() ? 6 : 20, "conservative_parent_hidden");
    EXPECT_GT(parent_hidden, 0.0) << "no octree box left out anything its parent had left out";
}

}  // namespace
}  // namespace pvs
