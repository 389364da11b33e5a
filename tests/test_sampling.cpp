// SPDX-License-Identifier: MIT
// Ray sampling and verification on hand-built scenes whose visibility is known by construction.
#include "cells/eyes.h"
#include "core/error.h"
#include "driver/verify.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
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
    // Seen through a doorway 1 m wide (glass is see-through): wider than the default gap tolerance, so the
    // miss fails; with a tolerance wider than the doorway it is reported apart as narrow.
    EXPECT_GE(m.opening_width_m, float(kDefaultGapToleranceM));
    EXPECT_EQ(bad.wide_missed_pairs, 1u);
    EXPECT_EQ(bad.narrow_missed_pairs, 0u);
    VerifyConfig wide_tolerance = dense_verify();
    wide_tolerance.gap_tolerance_m = 2.5;
    const VerifyResult narrow = verify_pvs(ctx, wide_tolerance, s.world, scene, kCell, wrong);
    ASSERT_EQ(narrow.missed_pairs, 1u);
    EXPECT_EQ(narrow.narrow_missed_pairs, 1u);
    EXPECT_EQ(narrow.wide_missed_pairs, 0u);
    EXPECT_TRUE(narrow.is_narrow(narrow.misses[0]));
    EXPECT_GT(narrow.narrow_width_max_m, 0.5f);  // the doorway's middle is found, whatever the witness
    EXPECT_LT(narrow.narrow_width_max_m, 2.5f);

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

    // Rays with an origin each: each ray from its own eye touches what it touches traced alone.
    std::vector<glm::vec3> origins(dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i)
        origins[i] = eye + glm::vec3(0.0f, 0.0f, 0.3f * float(i % 5) - 0.6f);
    std::vector<RayTouch> each, alone;
    scene.trace_from(origins.data(), dirs.data(), uint32_t(dirs.size()), each);
    for (uint32_t i = 0; i < dirs.size(); ++i) {
        std::vector<RayTouch> one;
        scene.trace_reference(origins[i], &dirs[i], 1, one);
        for (RayTouch t : one) {
            t.ray = i;
            alone.push_back(t);
        }
    }
    EXPECT_EQ(key(each), key(alone));
    EXPECT_NE(key(each), key(fast));  // the origins matter: some rays reach through the doorway, some not
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

// Aimed rays (driver/verify.h): rays from fresh eye points at points on the objects the uniform rays missed.
namespace pvs {
namespace {

// Every object of the world listed, but `left_out`.
PvsSet all_but(const World& world, uint32_t cells, uint32_t left_out) {
    PvsSet p = PvsSet::make(cells, uint32_t(world.objects.size()));
    for (uint32_t c = 0; c < cells; ++c)
        for (uint32_t o = 0; o < world.objects.size(); ++o)
            if (o != left_out) p.set(c, o);
    return p;
}

// 2,000 rays for the one cell, half of them aimed (or none with aimed_share = 0).
VerifyConfig small_budget(double aimed_share) {
    VerifyConfig v;
    v.rays = SampleConfig{16, 1024, 2000, 21};
    v.aimed_share = aimed_share;
    return v;
}

// A wall at x = 0 with a slit |z| < 0.1 (full height) between the cell (kCell, x in [-2.5, -1.5]) and a
// 10 cm cube 20 m behind it on the slit's axis. It covers about 2e-7 of the sphere and only eyes with
// |z| < 0.11 see it: 1,000 uniform rays have about a 1 in 10,000 chance to touch it.
struct SlitScene {
    World world;
    uint32_t tiny = 0;
};

SlitScene make_slit_scene() {
    SlitScene s;
    add_box(s.world, "wall_left", Aabb::of({-0.1f, -5, -5}, {0.1f, 5, -0.1f}));
    add_box(s.world, "wall_right", Aabb::of({-0.1f, -5, 0.1f}, {0.1f, 5, 5}));
    s.tiny = add_box(s.world, "tiny", Aabb::of({20, -0.05f, -0.05f}, {20.1f, 0.05f, 0.05f}));
    return s;
}

// The one reported miss is the tiny cube, from an eye of the cell, by a ray that really reaches it through
// the slit: it hits the cube's near face (x = 20, |y|, |z| <= 5 cm) and crosses the wall (x = 0) at |z| <
// 0.1.
void expect_the_miss_through_the_slit(const VerifyResult& r, const SlitScene& s) {
    ASSERT_EQ(r.misses.size(), 1u);
    const Miss& m = r.misses[0];
    EXPECT_EQ(m.object, s.tiny);
    EXPECT_TRUE(kCell.cells[0].bounds.contains(m.eye));
    const glm::vec3 hit = m.eye + m.distance_m * m.direction;
    EXPECT_NEAR(hit.x, 20.0f, 1e-3f);
    EXPECT_LE(std::abs(hit.y), 0.05f + 1e-3f);
    EXPECT_LE(std::abs(hit.z), 0.05f + 1e-3f);
    const float t_wall = -m.eye.x / m.direction.x;
    EXPECT_LT(std::abs(m.eye.z + t_wall * m.direction.z), 0.1f);
    EXPECT_NEAR(glm::length(m.direction), 1.0f, 1e-5f);
}

TEST(AimedRays, FindTheMissOfATinyObjectThroughASlitThatUniformRaysDoNot) {
    Context ctx = quiet_context();
    SlitScene s = make_slit_scene();
    RayScene scene(ctx, s.world);
    const PvsSet pvs = all_but(s.world, 1, s.tiny);

    const VerifyResult uniform = verify_pvs(ctx, small_budget(0.0), s.world, scene, kCell, pvs);
    EXPECT_EQ(uniform.missed_pairs, 0u);
    EXPECT_FALSE(uniform.sampled.test(0, s.tiny));
    EXPECT_EQ(uniform.aimed_rays, 0u);

    const VerifyResult aimed = verify_pvs(ctx, small_budget(0.5), s.world, scene, kCell, pvs);
    // The same total budget: 1,000 uniform rays (16 eyes x 62) and up to 1,000 aimed at the one untouched
    // object, one per round until a ray sees it; then nothing is left to aim at.
    EXPECT_LE(aimed.rays, 2000u);
    EXPECT_EQ(aimed.aimed_rays_per_cell, 1000u);
    EXPECT_EQ(aimed.aimed_candidates, 1u);
    EXPECT_EQ(aimed.aimed_listed_candidates, 0u);
    EXPECT_EQ(aimed.aimed_targets, 1u);
    EXPECT_GT(aimed.aimed_rays, 0u);
    EXPECT_LT(aimed.aimed_rays, 1000u);
    EXPECT_EQ(aimed.aimed_rounds, aimed.aimed_rays);
    ASSERT_EQ(aimed.missed_pairs, 1u);
    EXPECT_EQ(aimed.aimed_missed_pairs, 1u);
    EXPECT_EQ(aimed.aimed_new_pairs, 1u);
    EXPECT_EQ(aimed.cells_with_misses, 1u);
    EXPECT_GT(aimed.missed_rays, 0u);
    expect_the_miss_through_the_slit(aimed, s);
}

TEST(AimedRays, NeverReportAMissForATrulyHiddenObject) {
    Context ctx = quiet_context();
    WallScene s = make_wall_scene(false, false);  // a whole wall: far_in_line and far_behind are hidden
    // And a cube shut in a closed shell beside the cell.
    add_box(s.world, "shell_floor", Aabb::of({-3, -2, 2}, {-1, -1.9f, 4}));
    add_box(s.world, "shell_roof", Aabb::of({-3, -0.1f, 2}, {-1, 0, 4}));
    add_box(s.world, "shell_west", Aabb::of({-3, -2, 2}, {-2.9f, 0, 4}));
    add_box(s.world, "shell_east", Aabb::of({-1.1f, -2, 2}, {-1, 0, 4}));
    add_box(s.world, "shell_south", Aabb::of({-3, -2, 2}, {-1, 0, 2.1f}));
    add_box(s.world, "shell_north", Aabb::of({-3, -2, 3.9f}, {-1, 0, 4}));
    const uint32_t shut = add_box(s.world, "shut_in", Aabb::of({-2.2f, -1.2f, 2.8f}, {-1.8f, -0.8f, 3.2f}));
    RayScene scene(ctx, s.world);
    const uint32_t n = uint32_t(s.world.objects.size());
    PvsSet pvs = PvsSet::make(1, n);
    for (uint32_t o = 0; o < n; ++o) pvs.set(0, o);
    pvs.clear(0, s.far_in_line);
    pvs.clear(0, s.far_behind);
    pvs.clear(0, shut);
    for (uint64_t budget : {uint64_t(0), uint64_t(20000), uint64_t(100)}) {
        VerifyConfig v;
        v.rays = SampleConfig{16, 1024, budget, 31};
        v.aimed_share = 0.5;
        const VerifyResult r = verify_pvs(ctx, v, s.world, scene, kCell, pvs);
        EXPECT_EQ(r.missed_pairs, 0u) << "budget " << budget;
        EXPECT_EQ(r.missed_rays, 0u) << "budget " << budget;
        EXPECT_TRUE(r.misses.empty());
        EXPECT_FALSE(r.sampled.test(0, s.far_in_line));
        EXPECT_FALSE(r.sampled.test(0, s.far_behind));
        EXPECT_FALSE(r.sampled.test(0, shut));
        // The three hidden objects were candidates and were aimed at (all three when the budget allows).
        EXPECT_GE(r.aimed_candidates, 3u) << "budget " << budget;
        EXPECT_GT(r.aimed_rays, 0u) << "budget " << budget;
        if (budget == 0) {
            EXPECT_EQ(r.aimed_targets, r.aimed_candidates);
        }
        if (budget == 100) {  // half of 100 rays for the one cell
            EXPECT_LE(r.aimed_rays, 50u);
        }
    }
}

// `count` 5 cm pebbles close behind the whole part of a wall at x = 0 (x in [0.5, 1.5], z >= 2, |y| < 1): a
// line from kCell (x in [-2.5, -1.5], |z| < 0.5) to them crosses x = 0 at z > 0.7, where the wall is whole.
std::vector<uint32_t> add_hidden_pebbles(World& world, uint32_t count) {
    std::vector<uint32_t> out;
    for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 lo(0.5f + 0.1f * float(i % 10), -0.9f + 0.1f * float((i / 10) % 18),
                           2.0f + 0.2f * float(i / 180));
        out.push_back(add_box(world, "pebble" + std::to_string(i), Aabb::of(lo, lo + glm::vec3(0.05f))));
    }
    return out;
}

// A doorway (|z| < 0.5, |y| < 1) in a wall at x = 0; a 10 cm cube 12 m behind it that every eye of kCell
// sees through the doorway (about 4e-6 of the sphere: uniform rays do not touch it), and 200 pebbles
// hidden behind the wall.
struct DoorwayScene {
    World world;
    uint32_t tiny = 0;
    std::vector<uint32_t> pebbles;
};

DoorwayScene make_doorway_scene() {
    DoorwayScene s;
    add_box(s.world, "wall_left", Aabb::of({-0.1f, -5, -5}, {0.1f, 5, -0.5f}));
    add_box(s.world, "wall_right", Aabb::of({-0.1f, -5, 0.5f}, {0.1f, 5, 5}));
    add_box(s.world, "wall_above", Aabb::of({-0.1f, 1, -0.5f}, {0.1f, 5, 0.5f}));
    add_box(s.world, "wall_below", Aabb::of({-0.1f, -5, -0.5f}, {0.1f, -1, 0.5f}));
    s.tiny = add_box(s.world, "tiny", Aabb::of({12, -0.05f, -0.05f}, {12.1f, 0.05f, 0.05f}));
    s.pebbles = add_hidden_pebbles(s.world, 200);
    return s;
}

// The PVS lists the tiny cube (truly visible) and leaves out the 200 hidden pebbles (correctly): 201
// untouched candidates for 10 aimed rays. Aimed at a random subset, the cube had 10 chances in 201 to get
// a ray; with aimed_listed_share 0.5 the listed group (the cube) gets 5 rounds, the first one sees it and
// the 4 rays it does not need go to the pebbles.
TEST(AimedRays, ListedShareFindsASmallListedObjectAmongManyHiddenCandidates) {
    Context ctx = quiet_context();
    DoorwayScene s = make_doorway_scene();
    RayScene scene(ctx, s.world);
    PvsSet pvs = PvsSet::make(1, uint32_t(s.world.objects.size()));
    for (uint32_t o = 0; o < s.world.objects.size(); ++o) pvs.set(0, o);
    for (uint32_t o : s.pebbles) pvs.clear(0, o);
    VerifyConfig v;
    v.rays = SampleConfig{16, 1024, 20, 21};  // 10 aimed rays for the one cell
    v.aimed_share = 0.5;
    const VerifyResult r = verify_pvs(ctx, v, s.world, scene, kCell, pvs);
    EXPECT_EQ(r.aimed_rays_per_cell, 10u);
    EXPECT_EQ(r.aimed_rays, 10u);  // the whole aimed budget, no more
    EXPECT_GE(r.aimed_candidates, 201u);
    EXPECT_EQ(r.missed_pairs, 0u);
    EXPECT_TRUE(r.sampled.test(0, s.tiny));
    EXPECT_GE(r.aimed_new_pairs, 1u);
    for (uint32_t o : s.pebbles) EXPECT_FALSE(r.sampled.test(0, o));
    EXPECT_GE(r.aimed_listed_candidates, 1u);
    EXPECT_EQ(r.aimed_listed_new_pairs, r.aimed_new_pairs);
    EXPECT_LT(r.aimed_listed_rays, 5u);  // the cube is seen before the listed share is spent
    EXPECT_GE(r.aimed_targets, 6u);      // the cube and the pebbles of the rays it left

    // With no share for the listed objects every aimed ray goes to the pebbles: the cube goes unseen.
    v.aimed_listed_share = 0.0;
    const VerifyResult none = verify_pvs(ctx, v, s.world, scene, kCell, pvs);
    EXPECT_EQ(none.aimed_rays, 10u);
    EXPECT_EQ(none.aimed_listed_rays, 0u);
    EXPECT_FALSE(none.sampled.test(0, s.tiny));
    EXPECT_EQ(none.aimed_new_pairs, 0u);
}

// Two cells beside a slit |z| < 0.1 (full height) in a wall at x = 0, and a 10 cm cube 10 m behind the slit
// on its axis. An eye at distance d before the wall sees the cube only when |z| < 0.1 (1 + d / 10) (d is
// 1.5 to 2.5 m here). Cell A (z in [-0.3, 0.1]) sees it from about half of its eyes; cell B beside it
// (z in [0.1, 20.1]) only from a sliver z < 0.115..0.125 along their shared face: 0.1% of its eyes.
struct SliverScene {
    World world;
    CellSet cells;
    uint32_t tiny = 0;
    static constexpr uint32_t kA = 0, kB = 1;
};

SliverScene make_sliver_scene() {
    SliverScene s;
    add_box(s.world, "wall_left", Aabb::of({-0.1f, -50, -50}, {0.1f, 50, -0.1f}));
    add_box(s.world, "wall_right", Aabb::of({-0.1f, -50, 0.1f}, {0.1f, 50, 50}));
    s.tiny = add_box(s.world, "tiny", Aabb::of({10, -0.05f, -0.05f}, {10.1f, 0.05f, 0.05f}));
    s.cells.kind = CellSet::Kind::kGrid;
    s.cells.cells.push_back(Cell{Aabb::of({-2.5f, -0.5f, -0.3f}, {-1.5f, 0.5f, 0.1f}), -1});
    s.cells.cells.push_back(Cell{Aabb::of({-2.5f, -0.5f, 0.1f}, {-1.5f, 0.5f, 20.1f}), -1});
    return s;
}

// A lists the cube, B leaves it out: a miss that only B's sliver sees. With 20 aimed rays per cell, B's
// own rays are unlikely to touch it (about 2%); the neighbour pass aims from B at the point where A's ray saw
// the cube, from the point of B nearest A's eye, and finds the miss.
TEST(NeighbourPass, FindsAMissThatOnlyASliverOfTheCellBesideAWitnessSees) {
    Context ctx = quiet_context();
    const SliverScene s = make_sliver_scene();
    RayScene scene(ctx, s.world);
    PvsSet pvs = all_but(s.world, 2, s.tiny);
    pvs.set(SliverScene::kA, s.tiny);
    VerifyConfig v;
    v.rays = SampleConfig{16, 1024, 80, 21};  // 20 aimed rays per cell (the uniform rays take at least 256)
    v.aimed_share = 0.5;

    v.neighbour_share = 0.0;
    const VerifyResult own = verify_pvs(ctx, v, s.world, scene, s.cells, pvs);
    EXPECT_EQ(own.aimed_rays_per_cell, 20u);
    EXPECT_TRUE(own.sampled.test(SliverScene::kA, s.tiny));
    EXPECT_FALSE(own.sampled.test(SliverScene::kB, s.tiny));
    EXPECT_EQ(own.missed_pairs, 0u);
    EXPECT_EQ(own.neighbour_passes, 0u);
    EXPECT_EQ(own.neighbour_rays, 0u);

    v.neighbour_share = 0.5;
    const VerifyResult r = verify_pvs(ctx, v, s.world, scene, s.cells, pvs);
    EXPECT_TRUE(r.sampled.test(SliverScene::kA, s.tiny));
    EXPECT_GE(r.neighbour_passes, 1u);
    EXPECT_GE(r.neighbour_rays, 1u);
    EXPECT_LE(r.neighbour_rays, 10u);  // half of each cell's 20 aimed rays at most
    EXPECT_LE(r.aimed_rays + r.neighbour_rays, 40u);
    ASSERT_EQ(r.missed_pairs, 1u);
    EXPECT_EQ(r.neighbour_missed_pairs, 1u);
    EXPECT_EQ(r.neighbour_new_pairs, 1u);
    ASSERT_EQ(r.misses.size(), 1u);
    const Miss& m = r.misses[0];
    EXPECT_EQ(m.cell, SliverScene::kB);
    EXPECT_EQ(m.object, s.tiny);
    // A real sight line from B's sliver: it crosses the wall in the slit and ends on the cube.
    EXPECT_TRUE(s.cells.cells[SliverScene::kB].bounds.contains(m.eye));
    EXPECT_LT(m.eye.z, 0.1f + 0.1f * (-m.eye.x) / 10.0f);
    const float t_wall = -m.eye.x / m.direction.x;
    EXPECT_LT(std::abs(m.eye.z + t_wall * m.direction.z), 0.1f);
    const glm::vec3 hit = m.eye + m.distance_m * m.direction;
    EXPECT_TRUE(Aabb::of({9.999f, -0.051f, -0.051f}, {10.101f, 0.051f, 0.051f}).contains(hit));
}

// The slit scene's tiny cube, visible and left out (a miss), among 50 pebbles the PVS lists but the wall
// hides (overestimation). With aimed_listed_share 0.5, 500 rays go to the pebbles in rounds that never see
// them, and the cube still gets a round of its own per ray until one sees it through the slit; the rays it
// leaves go back to the pebbles, so the cell spends its 1,000 aimed rays.
TEST(AimedRays, HalfTheRaysForListedObjectsStillFindTheMissThroughASlit) {
    Context ctx = quiet_context();
    SlitScene s = make_slit_scene();
    const std::vector<uint32_t> pebbles = add_hidden_pebbles(s.world, 50);
    RayScene scene(ctx, s.world);
    const PvsSet pvs = all_but(s.world, 1, s.tiny);
    VerifyConfig v = small_budget(0.5);
    v.aimed_listed_share = 0.5;
    const VerifyResult r = verify_pvs(ctx, v, s.world, scene, kCell, pvs);
    EXPECT_EQ(r.aimed_rays_per_cell, 1000u);
    EXPECT_EQ(r.aimed_rays, 1000u);
    EXPECT_GE(r.aimed_listed_candidates, 50u);
    EXPECT_EQ(r.aimed_candidates, r.aimed_listed_candidates + 1);
    EXPECT_GT(r.aimed_listed_rays, 500u);  // its share and what the cube's group did not need
    EXPECT_EQ(r.aimed_listed_new_pairs, 0u);
    for (uint32_t o : pebbles) EXPECT_FALSE(r.sampled.test(0, o));
    ASSERT_EQ(r.missed_pairs, 1u);
    EXPECT_EQ(r.aimed_missed_pairs, 1u);
    expect_the_miss_through_the_slit(r, s);
}

// The grid world of SameSeedSameFiguresForOneAndTwoThreads: walls with gaps and crates, 2 m cells.
struct GridWorld {
    World world;
    CellSet cells;
};

GridWorld make_grid_world() {
    GridWorld g;
    for (int i = 0; i < 6; ++i) {
        const float x = float(i) * 3.0f;
        add_box(g.world, "wall" + std::to_string(i),
                Aabb::of({x, 0, float(i % 3) - 4}, {x + 0.2f, 3, float(i % 3)}));
        add_box(g.world, "crate" + std::to_string(i), Aabb::of({x + 1, 0, 1}, {x + 1.5f, 0.5f, 1.5f}));
        add_box(g.world, "pebble" + std::to_string(i),
                Aabb::of({x + 2, 0.1f, float(i % 2) - 2}, {x + 2.05f, 0.15f, float(i % 2) - 1.95f}));
    }
    CellSet& cells = g.cells;
    cells.kind = CellSet::Kind::kGrid;
    cells.origin = g.world.bounds.min;
    cells.cell_size_m = 2.0f;
    cells.dims = glm::ivec3(glm::ceil((g.world.bounds.max - g.world.bounds.min) / 2.0f));
    for (int z = 0; z < cells.dims.z; ++z)
        for (int y = 0; y < cells.dims.y; ++y)
            for (int x = 0; x < cells.dims.x; ++x) {
                cells.grid_to_cell.push_back(int32_t(cells.cells.size()));
                const glm::vec3 lo = cells.origin + 2.0f * glm::vec3(x, y, z);
                cells.cells.push_back(Cell{Aabb::of(lo, lo + glm::vec3(2.0f)), -1});
            }
    return g;
}

// `widths`: the opening widths too (both results measured them).
void expect_same_misses(const VerifyResult& a, const VerifyResult& b, bool widths = true) {
    ASSERT_EQ(a.misses.size(), b.misses.size());
    for (size_t i = 0; i < a.misses.size(); ++i) {
        if (widths) {
            EXPECT_EQ(a.misses[i].opening_width_m, b.misses[i].opening_width_m);
        }
        EXPECT_EQ(a.misses[i].cell, b.misses[i].cell);
        EXPECT_EQ(a.misses[i].object, b.misses[i].object);
        EXPECT_EQ(a.misses[i].eye, b.misses[i].eye);
        EXPECT_EQ(a.misses[i].direction, b.misses[i].direction);
        EXPECT_EQ(a.misses[i].distance_m, b.misses[i].distance_m);
    }
}

TEST(AimedRays, SameResultForOneAndTwoThreads) {
    Context ctx = quiet_context();
    GridWorld g = make_grid_world();
    RayScene scene(ctx, g.world);
    const uint32_t n_cells = uint32_t(g.cells.size());
    // An aggressive PVS from few rays: it leaves out visible objects, so there are misses to report.
    SampledPvsConfig sc;
    sc.rays = SampleConfig{2, 32, 0, 3};
    omp_set_num_threads(1);
    const PvsSet pvs = bake_sampled_pvs(ctx, sc, g.world, scene, g.cells).pvs;
    // No budget (eyes_per_cell aimed eyes); a budget with several aimed eyes per cell; one too small for
    // one ray per candidate (a random subset).
    for (uint64_t budget : {uint64_t(0), uint64_t(n_cells) * 2000, uint64_t(n_cells) * 10}) {
        VerifyConfig vc;
        vc.rays = SampleConfig{4, 256, budget, 4};
        vc.aimed_share = 0.5;
        omp_set_num_threads(1);
        const VerifyResult one = verify_pvs(ctx, vc, g.world, scene, g.cells, pvs);
        omp_set_num_threads(2);
        const VerifyResult two = verify_pvs(ctx, vc, g.world, scene, g.cells, pvs);
        EXPECT_GT(one.aimed_rays, 0u) << "budget " << budget;
        EXPECT_GT(one.neighbour_rays, 0u) << "budget " << budget;
        EXPECT_GT(one.missed_pairs, 0u) << "budget " << budget;
        EXPECT_EQ(one.sampled, two.sampled) << "budget " << budget;
        EXPECT_EQ(one.figures(), two.figures()) << "budget " << budget;  // times are in run_figures()
        EXPECT_EQ(one.cell_sampled_visible, two.cell_sampled_visible);
        expect_same_misses(one, two);
        if (budget == uint64_t(n_cells) * 10) {
            EXPECT_LT(one.aimed_targets, one.aimed_candidates);
        }
        if (budget == 0) {
            EXPECT_EQ(one.aimed_targets, one.aimed_candidates);
        }
    }
}

// Verification with uniform rays only, written out (aimed_share = 0 must trace exactly these).
struct UniformOnly {
    PvsSet sampled;
    uint64_t rays = 0;
    uint32_t rays_per_eye = 0;
    std::vector<Miss> first_misses;  // per cell, the first ray of each missed object, by object
};

UniformOnly uniform_only(const VerifyConfig& config, const RayScene& scene, const World& world,
                         const CellSet& cells, const PvsSet& pvs) {
    UniformOnly u;
    u.sampled = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    u.rays_per_eye = rays_per_eye_within_budget(config.rays, cells.size());
    CellRays rays;
    for (uint32_t c = 0; c < cells.size(); ++c) {
        trace_cell(scene, cells, c, config.rays, u.rays_per_eye, rays);
        u.rays += rays.directions.size();
        std::vector<Miss> cell;
        std::set<uint32_t> reported;
        for (const RayTouch& t : rays.touches) {
            u.sampled.set(c, t.object);
            if (pvs.test(c, t.object) || !reported.insert(t.object).second) continue;
            cell.push_back(
                Miss{c, t.object, rays.eyes[t.ray / rays.rays_per_eye], rays.directions[t.ray], t.t});
        }
        std::sort(cell.begin(), cell.end(), [](const Miss& a, const Miss& b) { return a.object < b.object; });
        u.first_misses.insert(u.first_misses.end(), cell.begin(), cell.end());
    }
    return u;
}

TEST(AimedRays, ShareZeroReproducesTheUniformOnlyResult) {
    Context ctx = quiet_context();
    GridWorld g = make_grid_world();
    RayScene scene(ctx, g.world);
    const uint32_t n_cells = uint32_t(g.cells.size());
    SampledPvsConfig sc;
    sc.rays = SampleConfig{2, 32, 0, 3};
    const PvsSet pvs = bake_sampled_pvs(ctx, sc, g.world, scene, g.cells).pvs;
    for (uint64_t budget : {uint64_t(0), uint64_t(n_cells) * 1000}) {
        VerifyConfig vc;
        vc.rays = SampleConfig{4, 512, budget, 4};
        vc.aimed_share = 0.0;
        const VerifyResult r = verify_pvs(ctx, vc, g.world, scene, g.cells, pvs);
        const UniformOnly u = uniform_only(vc, scene, g.world, g.cells, pvs);
        EXPECT_EQ(r.aimed_rays, 0u);
        EXPECT_EQ(r.aimed_candidates, 0u);
        EXPECT_EQ(r.rays_per_eye, u.rays_per_eye) << "budget " << budget;
        EXPECT_EQ(r.rays, u.rays);
        EXPECT_EQ(r.sampled, u.sampled);
        EXPECT_GT(r.missed_pairs, 0u);
        EXPECT_EQ(r.missed_pairs, u.first_misses.size());
        VerifyResult expected;
        expected.misses = u.first_misses;
        expect_same_misses(r, expected, false);
        if (budget > 0) {  // 1,000 rays per cell over 4 eyes
            EXPECT_EQ(r.rays_per_eye, 250u);
        }
        // With aimed rays the uniform rays shrink to half the budget and the aimed ones add on top.
        if (budget > 0) {
            vc.aimed_share = 0.5;
            const VerifyResult half = verify_pvs(ctx, vc, g.world, scene, g.cells, pvs);
            EXPECT_EQ(half.rays_per_eye, 125u);
            EXPECT_LE(half.rays, budget);
            EXPECT_GT(half.aimed_rays, 0u);
        }
    }
}

}  // namespace
}  // namespace pvs
