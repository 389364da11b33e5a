// Ray sampling and verification on hand-built scenes whose visibility is known by construction.
#include "cells/eyes.h"
#include "core/error.h"
#include "pvs/embree_scene.h"
#include "pvs/ray_sampler.h"
#include "pvs/verify.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <set>

namespace pvs {
namespace {

using test::add_box;
using test::single_cell;

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// A wall at x = 0 (10 x 10 m) between the cell (x in [-2.5, -1.5]) and the far side (x > 0).
// Pieces: the wall has a doorway |z| < 0.5, |y| < 1 when `doorway`, else a glass pane fills it when
// `glass`, else it is whole.
struct WallScene {
    World world;
    uint32_t near_object, far_in_line, far_behind, glass = UINT32_MAX;
    std::set<uint32_t> wall_pieces;
};

WallScene make_wall_scene(bool doorway, bool glass) {
    WallScene s;
    World& w = s.world;
    if (!doorway && !glass) {
        s.wall_pieces.insert(add_box(w, "wall", Aabb::of({-0.1f, -5, -5}, {0.1f, 5, 5})));
    } else {
        s.wall_pieces.insert(add_box(w, "wall_left", Aabb::of({-0.1f, -5, -5}, {0.1f, 5, -0.5f})));
        s.wall_pieces.insert(add_box(w, "wall_right", Aabb::of({-0.1f, -5, 0.5f}, {0.1f, 5, 5})));
        s.wall_pieces.insert(add_box(w, "wall_above", Aabb::of({-0.1f, 1, -0.5f}, {0.1f, 5, 0.5f})));
        s.wall_pieces.insert(add_box(w, "wall_below", Aabb::of({-0.1f, -5, -0.5f}, {0.1f, -1, 0.5f})));
        if (glass) s.glass = add_box(w, "glass", Aabb::of({-0.01f, -1, -0.5f}, {0.01f, 1, 0.5f}), false);
    }
    s.near_object = add_box(w, "near", Aabb::of({-4, -0.25f, -0.25f}, {-3.5f, 0.25f, 0.25f}));
    s.far_in_line = add_box(w, "far_in_line", Aabb::of({3, -0.25f, -0.25f}, {3.5f, 0.25f, 0.25f}));
    s.far_behind = add_box(w, "far_behind", Aabb::of({3, -0.25f, 4}, {3.5f, 0.25f, 4.5f}));
    return s;
}

const CellSet kCell = single_cell({-2.5f, -0.5f, -0.5f}, 1.0f);

VerifyConfig dense_verify() {
    VerifyConfig v;
    v.rays = SampleConfig{16, 4096, 0, 11};
    return v;
}

std::set<uint32_t> row_set(const PvsSet& p, uint32_t cell) {
    std::set<uint32_t> s;
    for (uint32_t o = 0; o < p.object_count; ++o)
        if (p.test(cell, o)) s.insert(o);
    return s;
}

TEST(Sampling, WallHidesWhatIsBehindIt) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(false, false);
    RayScene scene(ctx, s.world);
    const VerifyResult r = verify_pvs(ctx, dense_verify(), s.world, scene, kCell,
                                      PvsSet::make(1, uint32_t(s.world.objects.size())));
    std::set<uint32_t> expected = s.wall_pieces;
    expected.insert(s.near_object);
    EXPECT_EQ(row_set(r.sampled, 0), expected);
}

TEST(Sampling, DoorwayShowsWhatIsInLineOnly) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(true, false);
    RayScene scene(ctx, s.world);
    const VerifyResult r = verify_pvs(ctx, dense_verify(), s.world, scene, kCell,
                                      PvsSet::make(1, uint32_t(s.world.objects.size())));
    std::set<uint32_t> expected = s.wall_pieces;
    expected.insert(s.near_object);
    expected.insert(s.far_in_line);
    EXPECT_EQ(row_set(r.sampled, 0), expected);
}

TEST(Sampling, GlassIsSeenAndSeenThrough) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(false, true);
    RayScene scene(ctx, s.world);
    const VerifyResult r = verify_pvs(ctx, dense_verify(), s.world, scene, kCell,
                                      PvsSet::make(1, uint32_t(s.world.objects.size())));
    std::set<uint32_t> expected = s.wall_pieces;
    expected.insert(s.near_object);
    expected.insert(s.glass);
    expected.insert(s.far_in_line);
    EXPECT_EQ(row_set(r.sampled, 0), expected);
}

TEST(Verify, FindsTheMissInAWrongPvsAndNoneInARightOne) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(false, true);
    RayScene scene(ctx, s.world);
    const uint32_t n = uint32_t(s.world.objects.size());
    PvsSet right = PvsSet::make(1, n);
    for (uint32_t o : s.wall_pieces) right.set(0, o);
    right.set(0, s.near_object);
    right.set(0, s.glass);
    right.set(0, s.far_in_line);
    const VerifyResult ok = verify_pvs(ctx, dense_verify(), s.world, scene, kCell, right);
    EXPECT_EQ(ok.missed_pairs, 0u);
    EXPECT_TRUE(ok.misses.empty());
    EXPECT_NEAR(ok.overestimation_mean, 1.0, 1e-9);

    PvsSet wrong = right;
    wrong.clear(0, s.far_in_line);  // seen only through the glass
    const VerifyResult bad = verify_pvs(ctx, dense_verify(), s.world, scene, kCell, wrong);
    ASSERT_EQ(bad.missed_pairs, 1u);
    ASSERT_EQ(bad.misses.size(), 1u);
    const Miss& m = bad.misses[0];
    EXPECT_EQ(m.object, s.far_in_line);
    EXPECT_EQ(m.cell, 0u);
    EXPECT_TRUE(kCell.cells[0].bounds.contains(m.eye));
    // The reported ray really reaches the object: eye + t * direction lies on its box.
    const glm::vec3 hit = m.eye + m.distance_m * m.direction;
    EXPECT_NEAR(hit.x, 3.0f, 1e-3f);
    EXPECT_GT(bad.missed_rays, 0u);

    PvsSet overfull = right;
    overfull.set(0, s.far_behind);  // listed though hidden: overestimation, not a miss
    const VerifyResult over = verify_pvs(ctx, dense_verify(), s.world, scene, kCell, overfull);
    EXPECT_EQ(over.missed_pairs, 0u);
    EXPECT_NEAR(over.overestimation_mean, 8.0 / 7.0, 1e-9);  // 7 seen, 8 listed
}

TEST(Verify, StreamedTracingMatchesTheOneRayReference) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(true, true);
    RayScene scene(ctx, s.world);
    std::vector<glm::vec3> dirs;
    sample_sphere_directions(3000, 5, 0, dirs);
    const glm::vec3 eye(-2.0f, 0.1f, 0.05f);
    std::vector<RayTouch> fast, slow;
    scene.trace(eye, dirs.data(), uint32_t(dirs.size()), fast);
    scene.trace_reference(eye, dirs.data(), uint32_t(dirs.size()), slow);
    auto key = [](std::vector<RayTouch> v) {
        std::set<std::pair<uint32_t, uint32_t>> out;
        for (const RayTouch& t : v) out.insert({t.ray, t.object});
        return out;
    };
    EXPECT_EQ(key(fast), key(slow));
    EXPECT_FALSE(fast.empty());
}

TEST(Verify, SameSeedSameFiguresForOneAndTwoThreads) {
    Context ctx = quiet_context();
    World world;
    // A small random-ish world: a row of walls with gaps and objects between them.
    for (int i = 0; i < 6; ++i) {
        const float x = float(i) * 3.0f;
        add_box(world, "wall" + std::to_string(i),
                Aabb::of({x, 0, float(i % 3) - 4}, {x + 0.2f, 3, float(i % 3)}));
        add_box(world, "crate" + std::to_string(i), Aabb::of({x + 1, 0, 1}, {x + 1.5f, 0.5f, 1.5f}));
    }
    CellSet cells;
    {
        cells.kind = CellSet::Kind::kGrid;
        cells.origin = world.bounds.min;
        cells.cell_size_m = 2.0f;
        cells.dims = glm::ivec3(glm::ceil((world.bounds.max - world.bounds.min) / 2.0f));
        for (int z = 0; z < cells.dims.z; ++z)
            for (int y = 0; y < cells.dims.y; ++y)
                for (int x = 0; x < cells.dims.x; ++x) {
                    cells.grid_to_cell.push_back(int32_t(cells.cells.size()));
                    const glm::vec3 lo = cells.origin + 2.0f * glm::vec3(x, y, z);
                    cells.cells.push_back(Cell{Aabb::of(lo, lo + glm::vec3(2.0f)), -1});
                }
    }
    RayScene scene(ctx, world);
    SampledPvsConfig sc;
    sc.rays = SampleConfig{4, 256, 0, 3};
    VerifyConfig vc;
    vc.rays = SampleConfig{4, 256, 0, 4};
    omp_set_num_threads(1);
    const SampledPvs a = bake_sampled_pvs(ctx, sc, world, scene, cells);
    const VerifyResult va = verify_pvs(ctx, vc, world, scene, cells, a.pvs);
    omp_set_num_threads(2);
    const SampledPvs b = bake_sampled_pvs(ctx, sc, world, scene, cells);
    const VerifyResult vb = verify_pvs(ctx, vc, world, scene, cells, b.pvs);
    EXPECT_EQ(a.pvs, b.pvs);
    EXPECT_EQ(va.sampled, vb.sampled);
    EXPECT_EQ(va.missed_pairs, vb.missed_pairs);
    ASSERT_EQ(va.misses.size(), vb.misses.size());
    for (size_t i = 0; i < va.misses.size(); ++i) {
        EXPECT_EQ(va.misses[i].cell, vb.misses[i].cell);
        EXPECT_EQ(va.misses[i].object, vb.misses[i].object);
        EXPECT_EQ(va.misses[i].eye, vb.misses[i].eye);
    }
    EXPECT_EQ(va.overestimation_mean, vb.overestimation_mean);
    EXPECT_EQ(va.cell_sampled_visible, vb.cell_sampled_visible);
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

TEST(GuardBand, ListsWhatRaysPassedCloseToAndNothingFar) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(true, false);
    // Hidden just behind the wall, beside the doorway's edge: the steepest sight line through the doorway
    // reaches z = 0.5625 at x = 0.2 (eye at x = -1.5, z = -0.5), short of the box; rays pass within 10 cm.
    const uint32_t peeking =
        add_box(s.world, "peeking", Aabb::of({0.12f, -0.25f, 0.62f}, {0.2f, 0.25f, 0.9f}));
    RayScene scene(ctx, s.world);
    CellRays rays;
    const SampleConfig sc{16, 2048, 0, 5};
    trace_cell(scene, kCell, 0, sc, sc.rays_per_eye, rays);
    PvsSet seen = PvsSet::make(1, uint32_t(s.world.objects.size()));
    for (const RayTouch& t : rays.touches) seen.set(0, t.object);
    ASSERT_FALSE(seen.test(0, peeking));  // hidden by construction

    PvsSet band = seen;
    const uint32_t added = add_guard_band(s.world, rays, 5.0f * 3.14159265f / 180.0f, band.row(0));
    EXPECT_TRUE(band.test(0, peeking));
    EXPECT_FALSE(band.test(0, s.far_behind));  // 4 m aside: far outside a 5 degree band
    EXPECT_GE(added, 1u);
    // Nothing the rays saw is dropped.
    for (uint32_t o = 0; o < s.world.objects.size(); ++o)
        if (seen.test(0, o)) {
            EXPECT_TRUE(band.test(0, o));
        }
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

TEST(Verify, RepeatedQueriesGiveTheFiltersAnswer) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(false, true);
    add_box(s.world, "second_glass", Aabb::of({1.5f, -1, -1}, {1.52f, 1, 1}), false);
    RayScene scene(ctx, s.world);
    std::vector<glm::vec3> dirs;
    sample_sphere_directions(4000, 9, 1, dirs);
    std::vector<RayTouch> filtered, repeated;
    scene.trace(glm::vec3(-2.0f, 0.0f, 0.0f), dirs.data(), uint32_t(dirs.size()), filtered);
    scene.trace_repeated(glm::vec3(-2.0f, 0.0f, 0.0f), dirs.data(), uint32_t(dirs.size()), repeated);
    auto key = [](const std::vector<RayTouch>& v) {
        std::set<std::pair<uint32_t, uint32_t>> out;
        for (const RayTouch& t : v) out.insert({t.ray, t.object});
        return out;
    };
    EXPECT_EQ(key(filtered), key(repeated));
}

}  // namespace
}  // namespace pvs
