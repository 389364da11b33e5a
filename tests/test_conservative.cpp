// The conservative mode on scenes whose visibility is known: who sees whom, fusion, and zero misses.
#include "core/error.h"
#include "pvs/bake.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// A closed hall (inside x in [0, 12], y in [0, 4], z in [0, 6]; 0.5 m shell) split at x = 6 by a 0.6 m wall
// with a doorway at its far end (z in [4.6, 5.6], y < 2.5) so both halves are reachable. What stands in the
// wall near z in [0, 2] varies: solid, two walls overlapping in view (fusion), the same with a gap, a slit,
// a doorway, a glass pane. The target stands behind it at x in [9, 9.5], z in [0.75, 1.25]. Walls are
// 0.6 m thick: at 0.1 m voxels and epsilon 0.1 m a shrunk occluder remains inside them (thinner walls
// shrink away, which is the price of epsilon, not an error).
enum class Middle {
    kSolid,
    kFusedHalves,
    kLowHalfOnly,
    kHighHalfOnly,
    kGappedHalves,
    kSlit,
    kDoorway,
    kGlass
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
        case Middle::kFusedHalves:  // a low wall in the divide and a high wall 1.2 m behind it, 0.6 m thick
                                    // each: each alone leaves part of the target in sight, together they
                                    // overlap in every sample's view (fusion on the depth buffer)
            test::add_box(w, "near_low", Aabb::of({x0, 0, 0}, {x1, 1.9f, 2}));
            test::add_box(w, "near_high", Aabb::of({7.2f, 0.8f, 0}, {7.8f, 4, 2}));
            break;
        case Middle::kLowHalfOnly:
            test::add_box(w, "near_low", Aabb::of({x0, 0, 0}, {x1, 1.9f, 2}));
            break;
        case Middle::kHighHalfOnly:
            test::add_box(w, "near_high", Aabb::of({7.2f, 0.8f, 0}, {7.8f, 4, 2}));
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

TEST(Conservative, BehindAWallIsCulled) {
    EXPECT_FALSE(target_listed(Middle::kSolid));
}
TEST(Conservative, BehindTwoOverlappingHalfWallsIsCulledByFusion) {
    EXPECT_FALSE(target_listed(Middle::kFusedHalves));
}
TEST(Conservative, EitherHalfWallAloneLeavesItListed) {
    EXPECT_TRUE(target_listed(Middle::kLowHalfOnly));
    EXPECT_TRUE(target_listed(Middle::kHighHalfOnly));
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

}  // namespace
}  // namespace pvs
