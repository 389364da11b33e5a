// SPDX-License-Identifier: MIT
// Occluder synthesis: boxes fill the sealed solid, the sight probe carves what a crack lets eyes see,
// and no proven box ever stands where a ray from the eye space reaches.
#include "cells/eyes.h"
#include "cells/view_volume.h"
#include "core/random.h"
#include "io/gltf_loader.h"
#include "occluders/boxes.h"
#include "occluders/gap_probe.h"
#include "occluders/panels.h"
#include "occluders/seal_probe.h"
#include "occluders/slanted_panels.h"
#include "occluders/solid.h"
#include "occluders/synthesis.h"
#include "rays/ray_scene.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <omp.h>
#include <cstdio>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Room A (x in [0.3, 6.3]) and room B (x in [6.6, 12.6]) under one roof, sealed from each other by the
// middle wall, except, when `slit`, a vertical slit 1 cm wide in it (z in [3.295, 3.305], y in [0.5, 2.5]).
// A target object stands in room B in line with the slit.
World slit_world(bool slit, uint32_t* target) {
    World w;
    const float t = 0.3f;
    test::add_box(w, "floor", Aabb::of({0, 0, 0}, {12.9f, t, 6.6f}));
    test::add_box(w, "roof", Aabb::of({0, 3.3f, 0}, {12.9f, 3.6f, 6.6f}));
    test::add_box(w, "south", Aabb::of({0, 0, 0}, {12.9f, 3.6f, t}));
    test::add_box(w, "north", Aabb::of({0, 0, 6.3f}, {12.9f, 3.6f, 6.6f}));
    test::add_box(w, "east", Aabb::of({12.6f, 0, 0}, {12.9f, 3.6f, 6.6f}));
    test::add_box(w, "west", Aabb::of({0, 0, 0}, {t, 3.6f, 6.6f}));
    if (slit) {
        test::add_box(w, "middle_a", Aabb::of({6.3f, 0, 0}, {6.6f, 3.6f, 3.295f}));
        test::add_box(w, "middle_b", Aabb::of({6.3f, 0, 3.305f}, {6.6f, 3.6f, 6.6f}));
    } else {
        test::add_box(w, "middle", Aabb::of({6.3f, 0, 0}, {6.6f, 3.6f, 6.6f}));
    }
    *target = test::add_box(w, "target", Aabb::of({10.5f, 1.0f, 3.0f}, {11.0f, 2.0f, 3.6f}));
    return w;
}

OccluderConfig test_config() {
    OccluderConfig c;
    c.min_occluder_volume_m3 = 0.05;
    c.probe_eyes = 2048;
    c.probe_rays_per_eye = 8192;
    return c;
}

TEST(Occluders, FillTheSealedRoom) {
    Context ctx = quiet_context();
    uint32_t target = 0;
    const World w = slit_world(false, &target);
    ViewVolumeConfig vc;
    vc.voxel_size_m = 0.1;
    vc.seeds = {{3, 1.5f, 3}};
    const ViewVolume view = build_view_volume(ctx, vc, w);
    RayScene scene(ctx, w);
    OccluderFigures f;
    OccluderConfig c = test_config();
    c.probe_eyes = 256;  // sealed: the probe finds nothing to carve
    c.probe_rays_per_eye = 2048;
    const std::vector<Occluder> boxes = synthesize_occluders(ctx, c, w, view, scene, f);
    ASSERT_FALSE(boxes.empty());
    EXPECT_EQ(f.probe_rays_into_solid, 0u);
    // Room B (sealed off) and the space around the building are solid, and boxes cover most of it; no
    // box reaches into room A, where the eyes are.
    EXPECT_GT(f.solid_m3, 0.8 * 6 * 3 * 6);
    EXPECT_GT(f.covered_m3, 0.8 * f.solid_m3);
    const Aabb room_a = Aabb::of({0.3f, 0.3f, 0.3f}, {6.3f, 3.3f, 6.3f});
    bool fills_room_b = false;
    for (const Occluder& o : boxes) {
        EXPECT_TRUE(o.proven);
        const glm::vec3 lo = glm::max(o.box.min, room_a.min), hi = glm::min(o.box.max, room_a.max);
        EXPECT_FALSE(lo.x < hi.x - 1e-4f && lo.y < hi.y - 1e-4f && lo.z < hi.z - 1e-4f) << "a box in room A";
        fills_room_b |= o.box.contains({9.0f, 1.5f, 1.5f});
    }
    EXPECT_TRUE(fills_room_b);
}

// Sight lines from room A through the 1 cm slit (through a wall 3 voxels thick) to the target: no proven
// box may cut any of them, with occluders made by `c`.
void expect_the_slit_keeps_its_sight_line(const OccluderConfig& c, OccluderFigures& f) {
    Context ctx = quiet_context();
    uint32_t target = 0;
    const World w = slit_world(true, &target);
    ViewVolumeConfig vc;
    vc.voxel_size_m = 0.1;  // ten times the slit: the flood does not pass it
    vc.seeds = {{3, 1.5f, 3}};
    const ViewVolume view = build_view_volume(ctx, vc, w);
    ASSERT_FALSE(view.view.contains({9, 1.5f, 3}));  // room B is sealed off in voxels
    RayScene scene(ctx, w);
    const std::vector<Occluder> boxes = synthesize_occluders(ctx, c, w, view, scene, f);
    // Sight lines from room A through the slit to the target: no proven box may cut any of them.
    int lines = 0;
    for (float ex = 1.0f; ex <= 5.5f; ex += 0.5f) {
        for (float ey = 0.8f; ey <= 2.8f; ey += 0.5f) {
            const glm::vec3 eye(ex, ey, 3.3f);
            for (float ty = 1.05f; ty <= 1.95f; ty += 0.15f) {
                const glm::vec3 target_point(10.5f, ty, 3.3f);
                const glm::vec3 d = glm::normalize(target_point - eye);
                const float dist = glm::length(target_point - eye);
                // Only lines that really pass the slit (nothing opaque in between).
                std::vector<RayTouch> touches;
                scene.trace(eye, &d, 1, touches);
                bool reaches = false;
                for (const RayTouch& t : touches)
                    reaches |= t.object == target && t.stops && t.t <= dist + 1e-3f;
                if (!reaches) continue;
                ++lines;
                for (const Occluder& o : boxes) {
                    if (!o.proven) continue;
                    // Segment-box test by sampling the segment finely.
                    for (float s = 0.0f; s < dist; s += 0.01f) {
                        ASSERT_FALSE(o.box.contains(eye + s * d)) << "a proven box cuts the sight line from ("
                                                                  << eye.x << ", " << eye.y << ") at " << s;
                    }
                }
            }
        }
    }
    EXPECT_GT(lines, 10);
}

TEST(Occluders, ASlitKeepsItsSightLine) {
    OccluderConfig c = test_config();
    c.seal_rays = 0;
    OccluderFigures f;
    expect_the_slit_keeps_its_sight_line(c, f);
    EXPECT_GT(f.probe_rays_into_solid, 0u);  // the sight probe found it
}

// The same slit with no sight probe, no gap probe and one far check eye: the seal probe finds it from room
// B's side.
TEST(Occluders, TheSealProbeFindsASlitThroughAThickWall) {
    OccluderConfig c = test_config();
    c.probe_eyes = 0;
    c.gap_lines = 0;
    c.check_eyes = 1;
    c.check_near_eyes = 0;
    OccluderFigures f;
    expect_the_slit_keeps_its_sight_line(c, f);
    EXPECT_GT(f.seal_leaks, 0u);
    EXPECT_GT(f.seal_removed_voxels, 1000u);  // the sweep through the slit opened much of room B
}

// A room over a trench: its floor is two plates 2 cm thick with a 5 mm crack between them (x in [6.3,
// 6.305], all along z), a twentieth of a voxel wide, over a closed trench 1 m wide (x in [5.8, 6.8]). The
// touched voxels of the crack seal the trench for the sight sweep (docs/ALGORITHMS.md#cracks). Is any proven
// box cut by a sight line through the crack into the trench?
World trench_world(float crack_m) {
    World w;
    test::add_box(w, "base", Aabb::of({0, 0, 0}, {12.9f, 0.3f, 6.6f}));
    test::add_box(w, "fill_a", Aabb::of({0, 0.3f, 0}, {5.8f, 1.0f, 6.6f}));
    test::add_box(w, "fill_b", Aabb::of({6.8f, 0.3f, 0}, {12.9f, 1.0f, 6.6f}));
    test::add_box(w, "floor_a", Aabb::of({0, 1.0f, 0}, {6.3f, 1.02f, 6.6f}));
    test::add_box(w, "floor_b", Aabb::of({6.3f + crack_m, 1.0f, 0}, {12.9f, 1.02f, 6.6f}));
    test::add_box(w, "roof", Aabb::of({0, 4.3f, 0}, {12.9f, 4.6f, 6.6f}));
    test::add_box(w, "south", Aabb::of({0, 0, 0}, {12.9f, 4.6f, 0.3f}));
    test::add_box(w, "north", Aabb::of({0, 0, 6.3f}, {12.9f, 4.6f, 6.6f}));
    test::add_box(w, "east", Aabb::of({12.6f, 0, 0}, {12.9f, 4.6f, 6.6f}));
    test::add_box(w, "west", Aabb::of({0, 0, 0}, {0.3f, 4.6f, 6.6f}));
    return w;
}

ViewVolume trench_view(Context& ctx, const World& w) {
    ViewVolumeConfig vc;
    vc.voxel_size_m = 0.1;
    vc.seeds = {{3, 2.5f, 3}};
    return build_view_volume(ctx, vc, w);
}

// The voxel in the middle of the trench, under the crack.
uint64_t trench_voxel_of(const VoxelGrid& grid) {
    const glm::ivec3 c = grid.voxel_of({6.3f, 0.6f, 3.2f});
    return grid.index(c.x, c.y, c.z);
}

// `probe` (Solid& -> figures) run on a copy of `before` with `threads` OpenMP threads; the copy, probed.
template <class Probe, class Figures>
Solid probed_with(int threads, const Solid& before, Probe probe, Figures& figures) {
    const int was = omp_get_max_threads();
    omp_set_num_threads(threads);
    Solid s = before;
    figures = probe(s);
    omp_set_num_threads(was);
    return s;
}

bool a_box_cuts_the_sight_through_the_crack(uint64_t check_seed, uint32_t near_eyes, int& lines,
                                            uint32_t seal_rays = 0, float crack_m = 0.005f,
                                            uint32_t gap_lines = 0,
                                            double tolerance_m = kDefaultGapToleranceM) {
    Context ctx = quiet_context();
    const World w = trench_world(crack_m);
    const ViewVolume view = trench_view(ctx, w);
    EXPECT_FALSE(view.view.contains({6.3f, 0.6f, 3.2f}));  // the trench is sealed off in voxels
    RayScene scene(ctx, w);
    OccluderConfig c = test_config();
    c.probe_eyes = 0;  // no sight probe, and one far check eye: only the eyes near each box may find it
    c.gap_lines = gap_lines;
    c.gap_tolerance_m = tolerance_m;
    c.check_eyes = 1;
    c.check_near_eyes = near_eyes;
    c.seal_rays = seal_rays;
    c.check_seed = check_seed;
    OccluderFigures f;
    const std::vector<Occluder> boxes = synthesize_occluders(ctx, c, w, view, scene, f);
    lines = 0;
    bool cut = false;
    for (float z : {1.5f, 3.25f, 5.0f})
        for (float ex = 5.8f; ex <= 6.8f; ex += 0.1f)
            for (float ey = 1.5f; ey <= 3.5f; ey += 0.5f)
                for (float tx = 6.0f; tx <= 6.6f; tx += 0.01f) {
                    const glm::vec3 eye(ex, ey, z), target_point(tx, 0.3f, z + 0.1f);
                    const glm::vec3 d = glm::normalize(target_point - eye);
                    const float dist = glm::length(target_point - eye);
                    std::vector<RayTouch> touches;
                    scene.trace(eye, &d, 1, touches);
                    bool reaches = false;
                    for (const RayTouch& t : touches) reaches |= t.stops && t.t >= dist - 1e-3f;
                    if (!reaches) continue;
                    ++lines;
                    for (const Occluder& o : boxes) {
                        if (!o.proven) continue;
                        for (float t = 0.0f; t < dist && !cut; t += 0.005f) cut = o.box.contains(eye + t * d);
                    }
                }
    return cut;
}

// The ray check from eyes near each box finds the crack for some seeds; without them, one far eye never
// does. Sampling, not proof: this is why every bake is verified (docs/ALGORITHMS.md#sampled-step).
// (The seal probe, off here, is the next test's.)
TEST(Occluders, EyesNearEachBoxFindACrackInAFloorThatFarEyesMiss) {
    int found_near = 0, found_far = 0;
    for (uint64_t seed = 1; seed <= 12; ++seed) {
        int lines = 0;
        found_near += !a_box_cuts_the_sight_through_the_crack(seed, 256, lines);
        EXPECT_GT(lines, 20);
        found_far += !a_box_cuts_the_sight_through_the_crack(seed, 0, lines);
    }
    EXPECT_GE(found_near, 3);
    EXPECT_EQ(found_far, 0);
}

// The seal probe on its own: the trench is solid after the sweep and open after the probe, through leaky
// voxels at the crack; the same solid for 1 and 3 threads and twice over.
TEST(SealProbe, OpensTheTrenchUnderACrackTheSameForAnyThreadCount) {
    Context ctx = quiet_context();
    const World w = trench_world(0.005f);
    const ViewVolume view = trench_view(ctx, w);
    RayScene scene(ctx, w);
    const Solid before = classify_solid(ctx, view.grid, view.touched, view.eyes);
    const uint64_t trench_voxel = trench_voxel_of(view.grid);
    ASSERT_TRUE(before.solid.get(trench_voxel));
    auto probe = [&](int threads, SealProbeFigures& f) {
        return probed_with(
            threads, before,
            [&](Solid& s) {
                return probe_seals(ctx, view.touched, view.eyes, scene, 32, 4.0, 8, 7, 0.0005, s);
            },
            f);
    };
    SealProbeFigures f1, f1b, f3;
    const Solid one = probe(1, f1), again = probe(1, f1b), three = probe(3, f3);
    EXPECT_GT(f1.leaks, 0u);
    EXPECT_GT(f1.leaky_voxels, 0u);
    EXPECT_FALSE(one.solid.get(trench_voxel));
    EXPECT_EQ(one.solid_voxels, before.solid_voxels - f1.removed_voxels);
    EXPECT_EQ(one.solid_voxels, one.solid.count());
    EXPECT_EQ(one.solid.words, again.solid.words);
    EXPECT_EQ(one.solid.words, three.solid.words);
    EXPECT_EQ(f1.leaks, f3.leaks);
    EXPECT_EQ(f1.rounds, f3.rounds);
    // Without a crack the probe finds nothing and leaves the solid as it was.
    const World sealed = trench_world(0.0f);
    const ViewVolume sealed_view = trench_view(ctx, sealed);
    RayScene sealed_scene(ctx, sealed);
    Solid s = classify_solid(ctx, sealed_view.grid, sealed_view.touched, sealed_view.eyes);
    const std::vector<uint64_t> sealed_before = s.solid.words;
    const SealProbeFigures fs =
        probe_seals(ctx, sealed_view.touched, sealed_view.eyes, sealed_scene, 32, 4.0, 8, 7, 0.0005, s);
    EXPECT_GT(fs.frontier_voxels, 1000u);
    EXPECT_EQ(fs.leaks, 0u);
    EXPECT_EQ(s.solid.words, sealed_before);
}

// An opening narrower than the gap tolerance allows stays closed: a 5 mm crack over the trench, probed with
// lines that must be at least 1 cm wide, opens nothing (its rays through the crack are counted as narrow);
// with lines of 0.5 mm it opens.
TEST(SealProbe, LeavesACrackNarrowerThanTheToleranceClosed) {
    Context ctx = quiet_context();
    const World w = trench_world(0.005f);
    const ViewVolume view = trench_view(ctx, w);
    RayScene scene(ctx, w);
    const Solid before = classify_solid(ctx, view.grid, view.touched, view.eyes);
    Solid narrow = before, wide = before;
    const SealProbeFigures closed =
        probe_seals(ctx, view.touched, view.eyes, scene, 32, 4.0, 8, 7, 0.01, narrow);
    EXPECT_GT(closed.narrow, 0u);
    EXPECT_EQ(closed.leaks, 0u);
    EXPECT_EQ(narrow.solid.words, before.solid.words);
    const SealProbeFigures open =
        probe_seals(ctx, view.touched, view.eyes, scene, 32, 4.0, 8, 7, 0.0005, wide);
    EXPECT_GT(open.leaks, 0u);
    EXPECT_LT(wide.solid_voxels, before.solid_voxels);
}

// The seal probe (occluders/seal_probe.h) looks from the trench's side: rays from the solid voxels under the
// floor find the crack, and the sweep through its touched voxels opens the trench, for every seed and for
// cracks from 2 to 8 mm wide (a 50th to a 12th of a voxel), with no sight probe, no eyes near the boxes
// and one far check eye, no gap probe, and a least width of a tenth of a millimetre (at the default the
// probe counts only lines 0.9 mm wide, and its random lines through a 2 mm crack are mostly narrower: the
// gap probe's work). Still sampling; this measures that it is not luck.
TEST(Occluders, TheSealProbeFindsCracksInAFloorFromBelow) {
    int found = 0, tries = 0;
    for (uint64_t seed = 1; seed <= 6; ++seed) {
        for (float crack : {0.002f, 0.005f, 0.008f}) {
            int lines = 0;
            const bool cut = a_box_cuts_the_sight_through_the_crack(seed, 0, lines, 32, crack, 0, 1e-4);
            EXPECT_GT(lines, 5) << "crack " << crack;
            EXPECT_FALSE(cut) << "seed " << seed << ", crack " << crack << " m";
            found += !cut;
            ++tries;
        }
    }
    EXPECT_EQ(found, tries);
}

// The gap probe (occluders/gap_probe.h) on its own: the trench under a 5 mm crack is solid after the sweep
// and open after the probe; the same solid for 1 and 3 threads and twice over; a sealed floor loses nothing.
TEST(GapProbe, OpensTheTrenchUnderACrackTheSameForAnyThreadCount) {
    Context ctx = quiet_context();
    const World w = trench_world(0.005f);
    const ViewVolume view = trench_view(ctx, w);
    RayScene scene(ctx, w);
    const Solid before = classify_solid(ctx, view.grid, view.touched, view.eyes);
    const uint64_t trench_voxel = trench_voxel_of(view.grid);
    ASSERT_TRUE(before.solid.get(trench_voxel));
    auto probe = [&](int threads, GapProbeFigures& f) {
        return probed_with(
            threads, before,
            [&](Solid& s) { return probe_gaps(ctx, view.touched, view.eyes, scene, 0.001, 8, s); }, f);
    };
    GapProbeFigures f1, f1b, f3;
    const Solid one = probe(1, f1), again = probe(1, f1b), three = probe(3, f3);
    EXPECT_GT(f1.gaps, 0u);
    EXPECT_GT(f1.leaks, 0u);
    EXPECT_GT(f1.leaky_voxels, 0u);
    EXPECT_FALSE(one.solid.get(trench_voxel));
    EXPECT_EQ(one.solid_voxels, before.solid_voxels - f1.removed_voxels);
    EXPECT_EQ(one.solid_voxels, one.solid.count());
    EXPECT_EQ(one.solid.words, again.solid.words);
    EXPECT_EQ(one.solid.words, three.solid.words);
    EXPECT_EQ(f1.leaks, f3.leaks);
    const World sealed = trench_world(0.0f);
    const ViewVolume sealed_view = trench_view(ctx, sealed);
    RayScene sealed_scene(ctx, sealed);
    Solid s = classify_solid(ctx, sealed_view.grid, sealed_view.touched, sealed_view.eyes);
    const std::vector<uint64_t> sealed_before = s.solid.words;
    const GapProbeFigures fs =
        probe_gaps(ctx, sealed_view.touched, sealed_view.eyes, sealed_scene, 0.001, 8, s);
    EXPECT_GT(fs.voxels, 1000u);
    EXPECT_EQ(fs.leaks, 0u);
    EXPECT_EQ(s.solid.words, sealed_before);
}

// Every crack from the tolerance up to past what the voxels resolve opens the trench, and one of half the
// tolerance stays closed: no sampling, so no seed to be lucky with.
TEST(GapProbe, OpensEveryCrackAtLeastTheToleranceWideAndNoNarrowerOne) {
    Context ctx = quiet_context();
    for (float crack : {0.0005f, 0.001f, 0.0013f, 0.004f, 0.02f, 0.09f, 0.3f}) {
        const World w = trench_world(crack);
        const ViewVolume view = trench_view(ctx, w);
        RayScene scene(ctx, w);
        Solid s = classify_solid(ctx, view.grid, view.touched, view.eyes);
        const uint64_t trench_voxel = trench_voxel_of(view.grid);
        if (!s.solid.get(trench_voxel)) {
            EXPECT_GT(crack, 0.1f) << "the sweep alone sees through a crack of " << crack << " m";
            continue;  // wide enough for the sweep itself
        }
        const GapProbeFigures f = probe_gaps(ctx, view.touched, view.eyes, scene, 0.001, 8, s);
        EXPECT_EQ(s.solid.get(trench_voxel), crack < 0.001f)
            << "crack " << crack << " m, " << f.gaps << " gaps, " << f.leaks << " leaks";
    }
}

// In the whole occluder stage, with no sampler at all (no sight probe, no seal probe, no eyes near the
// boxes, one far check eye): the gap probe alone keeps every proven box off the sight lines through the
// crack, for cracks of 1 and 3 mm and every seed.
TEST(GapProbe, AloneKeepsTheProvenBoxesOffTheSightThroughTheCrack) {
    for (uint64_t seed = 1; seed <= 3; ++seed)
        for (float crack : {0.001f, 0.003f}) {
            int lines = 0;
            const bool cut = a_box_cuts_the_sight_through_the_crack(seed, 0, lines, 0, crack, 8);
            EXPECT_GT(lines, 5) << "crack " << crack;
            EXPECT_FALSE(cut) << "seed " << seed << ", crack " << crack << " m";
        }
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

// Aims a ray from every eye at `per_box` random points of every proven box; returns how many arrive
// (no opaque triangle before the point) and adds the rays shot to `rays`. Reports the first few.
uint64_t count_seen(const RayScene& scene, const std::vector<Occluder>& boxes,
                    const std::vector<glm::vec3>& eyes, uint32_t per_box, Rng& rng, uint64_t& rays) {
    uint64_t seen = 0;
    std::vector<glm::vec3> origins, dirs;
    std::vector<float> tfar;
    for (const Occluder& o : boxes) {
        if (!o.proven) continue;
        origins.clear();
        dirs.clear();
        tfar.clear();
        for (const glm::vec3& e : eyes) {
            for (uint32_t k = 0; k < per_box; ++k) {
                const glm::vec3 p =
                    o.box.min + o.box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
                origins.push_back(e);
                dirs.push_back(glm::normalize(p - e));
                tfar.push_back(glm::length(p - e));
            }
        }
        std::vector<uint8_t> blocked(origins.size());
        scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                              blocked.data());
        rays += origins.size();
        for (size_t i = 0; i < blocked.size(); ++i) {
            if (blocked[i]) continue;
            if (++seen <= 5) {
                ADD_FAILURE() << "seen: eye (" << origins[i].x << ", " << origins[i].y << ", " << origins[i].z
                              << ") direction (" << dirs[i].x << ", " << dirs[i].y << ", " << dirs[i].z
                              << ") reaches " << tfar[i] << " m into box (" << o.box.min.x << ", "
                              << o.box.min.y << ", " << o.box.min.z << ")-(" << o.box.max.x << ", "
                              << o.box.max.y << ", " << o.box.max.z << ")";
            }
        }
    }
    return seen;
}

// Eye points the map compiler calls playable: random points of the bounds whose BSP leaf (the world's
// .vis.json) has a cluster, kept when they are also in the eye space `eyes`. Both filters matter: the
// compiler's playable space includes the outside of a level it found leaking (many of its playable points
// may see the sky box's outside), and the inside of detail brushes, which do not split its BSP (a point
// 5 mm inside a wall is "playable" there).
std::vector<glm::vec3> bsp_eyes(const std::string& vis_path, const Aabb& bounds, const VoxelMask& eye_space,
                                uint32_t count, uint32_t* outside_view) {
    std::vector<glm::vec3> eyes;
    const nlohmann::json vis = nlohmann::json::parse(test::read_file(vis_path));
    const auto& nodes = vis["nodes"];
    const auto& leaves = vis["leaves"];
    Rng rng(31, 7);
    *outside_view = 0;
    for (uint32_t tries = 0; eyes.size() < count && tries < 200 * count; ++tries) {
        const glm::vec3 p =
            bounds.min + bounds.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
        int n = 0;
        while (n >= 0) {
            const auto& node = nodes[size_t(n)];
            const float d = node["normal"][0].get<float>() * p.x + node["normal"][1].get<float>() * p.y +
                            node["normal"][2].get<float>() * p.z;
            n = node["children"][d >= node["dist"].get<float>() ? 0 : 1].get<int>();
        }
        if (leaves[size_t(-n - 1)]["cluster"].get<int>() < 0) continue;
        if (!eye_space.contains(p)) {
            ++*outside_view;
            continue;
        }
        eyes.push_back(p);
    }
    return eyes;
}

// The property on the real levels: no point inside a proven box is visible from any eye point of the
// view volume (independent eyes and targets, not the ones synthesis used): eyes drawn from the view
// volume, and eyes the map compiler's BSP calls playable.
// Every voxel of every proven box is in the proven solid (docs/ALGORITHMS.md#proven-boxes); returns how many
// proven boxes there are.
size_t expect_proven_boxes_in_solid(const std::vector<Occluder>& boxes, const VoxelMask& solid) {
    size_t proven = 0;
    for (size_t b = 0; b < boxes.size(); ++b) {
        if (!boxes[b].proven) continue;
        ++proven;
        const float v = solid.voxel_size_m;
        const glm::ivec3 lo = glm::ivec3(glm::round((boxes[b].box.min - solid.origin) / v));
        const glm::ivec3 hi = glm::ivec3(glm::round((boxes[b].box.max - solid.origin) / v)) - 1;
        uint64_t outside = 0;
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x)
                    outside += !solid.get(uint64_t(x) + uint64_t(solid.dims.x) *
                                                            (uint64_t(y) + uint64_t(solid.dims.y) * uint64_t(z)));
        EXPECT_EQ(outside, 0u) << "proven box " << b << " has voxels outside the proven solid";
    }
    return proven;
}

void expect_boxes_unseen(const std::string& world_path, uint32_t eyes_n, uint32_t targets_per_box) {
    Context ctx = quiet_context();
    const World w = load_world(ctx, world_path);
    const ViewVolume view = build_view_volume(ctx, ViewVolumeConfig{}, w);
    RayScene scene(ctx, w);
    OccluderFigures f;
    ShrunkOccluders shrunk;
    const std::vector<Occluder> boxes =
        synthesize_occluders(ctx, OccluderConfig{}, w, view, scene, f, 0.125, 0, &shrunk);
    ASSERT_FALSE(boxes.empty());
    EXPECT_GT(expect_proven_boxes_in_solid(boxes, shrunk.solid), 0u);
    CellSet masks;
    masks.eyes = view.eyes;
    std::vector<glm::vec3> eyes;
    sample_eye_points_in(masks, view.view_bounds, 99, eyes_n, 12345, eyes);
    const std::string vis = world_path.substr(0, world_path.size() - 4) + ".vis.json";
    uint32_t outside = 0;
    const std::vector<glm::vec3> compiler_eyes = bsp_eyes(vis, w.bounds, view.eyes, eyes_n, &outside);
    std::printf(
        "%zu eye-space eyes, %zu BSP-playable eyes in the eye space (%u BSP-playable points outside it)\n",
        eyes.size(), compiler_eyes.size(), outside);
    eyes.insert(eyes.end(), compiler_eyes.begin(), compiler_eyes.end());
    Rng rng(4, 5);
    uint64_t rays = 0;
    const uint64_t seen = count_seen(scene, boxes, eyes, targets_per_box, rng, rays);
    EXPECT_EQ(seen, 0u) << "of " << rays << " rays into proven boxes";
    EXPECT_GT(rays, 100000u);
}

// Random overlapping boxes, some rejected: the kept ones only shrink, meet no rejected box, and cover all
// they covered outside the rejected boxes along at least one axis' slab (a check against voxel sets).
TEST(ProvenBoxes, KeptBoxesAreCutOffEveryRejectedBoxTheyOverlap) {
    Rng rng(21, 3);
    uint32_t trimmed = 0, away = 0;
    for (int round = 0; round < 200; ++round) {
        std::vector<VoxelBox> boxes;
        std::vector<uint8_t> rejected;
        for (int i = 0; i < 12; ++i) {
            const glm::ivec3 lo(int(20 * rng.uniform()), int(20 * rng.uniform()), int(20 * rng.uniform()));
            const glm::ivec3 size(1 + int(10 * rng.uniform()), 1 + int(10 * rng.uniform()), 1 + int(10 * rng.uniform()));
            boxes.push_back({lo, lo + size - 1});
            rejected.push_back(rng.uniform() < 0.3 ? 1 : 0);
        }
        const std::vector<VoxelBox> before = boxes;
        const std::vector<uint8_t> was = rejected;
        const TrimFigures t = trim_off_rejected(boxes, rejected, 4);
        trimmed += t.trimmed;
        away += t.trimmed_away;
        for (size_t k = 0; k < boxes.size(); ++k) {
            if (was[k]) {
                EXPECT_EQ(boxes[k], before[k]) << "a rejected box changed";
                EXPECT_TRUE(rejected[k]);
                continue;
            }
            if (rejected[k]) continue;  // trimmed away: below 4 voxels
            if (!(boxes[k] == before[k])) EXPECT_GE(boxes[k].volume(), 4u);
            EXPECT_TRUE(glm::all(glm::greaterThanEqual(boxes[k].lo, before[k].lo)) &&
                        glm::all(glm::lessThanEqual(boxes[k].hi, before[k].hi)))
                << "a kept box grew";
            for (size_t r = 0; r < boxes.size(); ++r) {
                if (!was[r]) continue;
                EXPECT_FALSE(glm::all(glm::lessThanEqual(glm::max(boxes[k].lo, boxes[r].lo),
                                                         glm::min(boxes[k].hi, boxes[r].hi))))
                    << "kept box " << k << " still meets rejected box " << r;
            }
        }
    }
    EXPECT_GT(trimmed, 100u);
    EXPECT_GT(away, 0u);
}

TEST(OccludersProperty, NoProvenBoxIsSeenInTheRealLevels) {
    int ran = 0;
    for (const char* name : {"oa_dm4.glb", "ctf_inyard.glb"}) {
        const std::string path = test::shared_world(name);
        if (path.empty()) continue;
        if (test::in_ci() && std::string(name) == "ctf_inyard.glb")
            continue;  // the benchmark runs it full size
        SCOPED_TRACE(name);
        expect_boxes_unseen(path, test::in_ci() ? 256 : 1024, 4);
        ++ran;
    }
    if (ran == 0) GTEST_SKIP() << "../shared/worlds is absent";
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

// A closed octahedron (8 outward triangles), rotated about y, as one object.
void add_octahedron(World& w, const std::string& name, glm::vec3 c, float r, float angle) {
    const uint32_t base = uint32_t(w.positions.size());
    const float ca = std::cos(angle), sa = std::sin(angle);
    const glm::vec3 pts[6] = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
    for (const glm::vec3& p : pts)
        w.positions.push_back(c + glm::vec3(ca * p.x + sa * p.z, p.y, -sa * p.x + ca * p.z));
    static const uint32_t kFaces[8][3] = {{0, 2, 4}, {4, 2, 1}, {1, 2, 5}, {5, 2, 0},
                                          {4, 3, 0}, {1, 3, 4}, {5, 3, 1}, {0, 3, 5}};
    WorldObject o;
    o.name = name;
    o.first_triangle = uint32_t(w.triangles.size());
    o.triangle_count = 8;
    o.flags = kObjectHasOpaque;
    for (const auto& f : kFaces) {
        w.triangles.push_back(Triangle{{base + f[0], base + f[1], base + f[2]}});
        w.triangle_opaque.push_back(1);
        w.triangle_double_sided.push_back(0);
        for (int k = 0; k < 3; ++k) o.bounds.extend(w.positions[base + f[k]]);
    }
    w.bounds.extend(o.bounds);
    w.objects.push_back(o);
}

TEST(OccludersProperty, RandomClosedMeshesHideNothingTheyShouldNot) {
    Context ctx = quiet_context();
    for (uint64_t seed = 1; seed <= (test::in_ci() ? 2u : 5u); ++seed) {
        SCOPED_TRACE(seed);
        Rng rng(seed, 9);
        World w;
        // An open ground with random closed boxes and rotated octahedra standing on it; the eyes are the
        // free space above the ground (view box), so the solid is the inside of the closed meshes.
        test::add_box(w, "ground", Aabb::of({0, -0.5f, 0}, {20, 0, 20}));
        for (int i = 0; i < 12; ++i) {
            const glm::vec3 lo(1 + 16 * rng.uniform(), 0, 1 + 16 * rng.uniform());
            const glm::vec3 size(0.5f + 3 * rng.uniform(), 0.5f + 3 * rng.uniform(),
                                 0.5f + 3 * rng.uniform());
            test::add_box(w, "box" + std::to_string(i), Aabb::of(lo, lo + size));
            add_octahedron(w, "oct" + std::to_string(i),
                           {2 + 16 * rng.uniform(), 1.5f, 2 + 16 * rng.uniform()},
                           0.8f + 1.5f * rng.uniform(), 6.28f * rng.uniform());
        }
        ViewVolumeConfig vc;
        vc.voxel_size_m = 0.1;
        vc.boxes = {Aabb::of({0, 0, 0}, {20, 4, 20})};
        const ViewVolume view = build_view_volume(ctx, vc, w);
        RayScene scene(ctx, w);
        OccluderConfig oc;
        oc.min_occluder_volume_m3 = 0.01;
        OccluderFigures f;
        ShrunkOccluders shrunk;
        const std::vector<Occluder> boxes = synthesize_occluders(ctx, oc, w, view, scene, f, 0.125, 0, &shrunk);
        ASSERT_FALSE(boxes.empty());
        EXPECT_GT(expect_proven_boxes_in_solid(boxes, shrunk.solid), 0u);
        CellSet masks;
        masks.eyes = view.eyes;
        std::vector<glm::vec3> eyes;
        sample_eye_points_in(masks, view.view_bounds, seed, 512, 777, eyes);
        uint64_t rays = 0;
        // The solid under the ground (with the metre of padding round the world) may be one box: aim several
        // rays from each eye at every box.
        const uint64_t seen = count_seen(scene, boxes, eyes, 4, rng, rays);
        EXPECT_EQ(seen, 0u) << "of " << rays;
        EXPECT_GT(rays, 1000u) << f.kept << " boxes kept, " << f.rejected_by_rays << " rejected";
    }
}

// Closed box meshes: only watertight, opaque, box-shaped objects count.
TEST(ClosedBoxes, FoundOnlyForWatertightOpaqueBoxes) {
    World w;
    test::add_box(w, "box", Aabb::of({0, 0, 0}, {1, 2, 3}));
    test::add_box(w, "glass", Aabb::of({2, 0, 0}, {3, 1, 1}), false);
    test::add_box(w, "open", Aabb::of({4, 0, 0}, {5, 1, 1}));
    w.objects.back().triangle_count -= 2;  // its last face is missing
    const std::vector<Aabb> boxes = closed_box_objects(w);
    ASSERT_EQ(boxes.size(), 1u);
    EXPECT_EQ(boxes[0], Aabb::of({0, 0, 0}, {1, 2, 3}));
}

// A wall standing on a floor: the voxels of the contact plane are touched by both and inside neither alone,
// but inside their union; with a 1 cm gap between them they are not.
bool contact_voxel_solid(float gap) {
    Context ctx = quiet_context();
    const Aabb floor = Aabb::of({0, -0.5f, 0}, {1, 0, 1}), wall = Aabb::of({0, gap, 0}, {1, 1, 1});
    Aabb bounds = floor;
    bounds.extend(wall);
    Solid solid;
    solid.grid = make_voxel_grid(bounds, 0.15, 2);
    solid.solid.reset(solid.grid.count());
    add_closed_boxes(ctx, {floor, wall}, VoxelMask{}, solid);
    const glm::ivec3 c = solid.grid.voxel_of({0.5f, 0.001f, 0.5f});
    EXPECT_TRUE(solid.grid.voxel_box(c).contains({0.5f, 0.0f, 0.5f})) << "the voxel must straddle y = 0";
    EXPECT_TRUE(solid.solid.get(solid.grid.index(c.x, c.y, c.z - 1)) ||
                solid.solid.get(solid.grid.index(c.x, c.y - 2, c.z)))
        << "voxels wholly inside one box are solid";
    return solid.solid.get(solid.grid.index(c.x, c.y, c.z));
}

TEST(ClosedBoxes, FillTheSeamWhereTwoMeet) {
    EXPECT_TRUE(contact_voxel_solid(0.0f));
    EXPECT_FALSE(contact_voxel_solid(0.01f));
}

// ---------------------------------------------------------------------------------------------------------
// Panels: rectangles covered by opaque triangles.

// Appends one triangle (as its own object).
void add_triangle(World& w, glm::vec3 a, glm::vec3 b, glm::vec3 c, bool opaque = true) {
    const uint32_t base = uint32_t(w.positions.size());
    w.positions.insert(w.positions.end(), {a, b, c});
    WorldObject o;
    o.name = "t" + std::to_string(w.objects.size());
    o.first_triangle = uint32_t(w.triangles.size());
    o.triangle_count = 1;
    o.flags = opaque ? kObjectHasOpaque : kObjectHasSeeThrough;
    o.bounds = Aabb::of(glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c)));
    w.triangles.push_back(Triangle{{base, base + 1, base + 2}});
    w.triangle_opaque.push_back(opaque ? 1 : 0);
    w.triangle_double_sided.push_back(0);
    w.objects.push_back(o);
    w.bounds.extend(o.bounds);
}

// A rectangle at z = `z` over [x0, x1] x [y0, y1] as two triangles cut along one diagonal.
void add_rect_z(World& w, float z, float x0, float x1, float y0, float y1, bool opaque = true) {
    add_triangle(w, {x0, y0, z}, {x1, y0, z}, {x1, y1, z}, opaque);
    add_triangle(w, {x0, y0, z}, {x1, y1, z}, {x0, y1, z}, opaque);
}

TEST(Panels, TwoHalvesOfARectangleMakeOneAndNeighboursMerge) {
    World w;
    add_rect_z(w, 3.0f, 0, 2, 0, 1);
    add_rect_z(w, 3.0f, 2, 5, 0, 1);  // shares the edge x = 2: merged
    add_rect_z(w, 3.0f, 0, 5, 1, 4);  // then shares y = 1 with the merged one: merged again
    add_rect_z(w, 7.0f, 0, 5, 0, 1);  // another plane: its own
    PanelFigures fig;
    const std::vector<Aabb> panels = find_panels(w, &fig);
    EXPECT_EQ(fig.flat_triangles, 8u);
    EXPECT_EQ(fig.planes, 2u);
    EXPECT_EQ(fig.covered_cells, 4u + 1u);  // grid x {0, 2, 5} x y {0, 1, 4}, and one cell at z = 7
    ASSERT_EQ(panels.size(), 2u);
    EXPECT_EQ(panel_axis(panels[0]), 2);
    EXPECT_EQ(panels[0].min, glm::vec3(0, 0, 3));
    EXPECT_EQ(panels[0].max, glm::vec3(5, 4, 3));
    EXPECT_EQ(panels[1].min, glm::vec3(0, 0, 7));
    EXPECT_EQ(panels[1].max, glm::vec3(5, 1, 7));
    // The faces of a closed box: six panels.
    World box;
    test::add_box(box, "b", Aabb::of({0, 0, 0}, {1, 2, 3}));
    EXPECT_EQ(find_panels(box).size(), 6u);
}

TEST(Panels, OnlyWhatOpaqueTrianglesWhollyCover) {
    World w;
    // Two halves that overlap (both hold the corner (0, 0)): they do not cover the rectangle.
    add_triangle(w, {0, 0, 1}, {2, 0, 1}, {2, 2, 1});
    add_triangle(w, {0, 0, 1}, {2, 0, 1}, {0, 2, 1});
    // Glass.
    add_rect_z(w, 2.0f, 0, 2, 0, 2, false);
    // One half only.
    add_triangle(w, {0, 0, 3}, {2, 0, 3}, {2, 2, 3});
    // Tilted (not in an axis plane).
    add_triangle(w, {0, 0, 4}, {2, 0, 4}, {2, 2, 4.5f});
    add_triangle(w, {0, 0, 4}, {2, 2, 4.5f}, {0, 2, 4.5f});
    // Halves of different rectangles that meet at a corner.
    add_triangle(w, {0, 0, 5}, {1, 0, 5}, {1, 1, 5});
    add_triangle(w, {1, 1, 5}, {2, 2, 5}, {1, 2, 5});
    EXPECT_TRUE(find_panels(w).empty());
}

// Is p (in the plane z = z) inside some opaque triangle of w lying in that plane? Exact enough for test
// points kept 1e-4 m inside panels.
bool covered_at(const World& w, glm::vec3 p) {
    for (size_t t = 0; t < w.triangles.size(); ++t) {
        const Triangle& tri = w.triangles[t];
        const glm::vec3 a = w.positions[tri.v[0]], b = w.positions[tri.v[1]], c = w.positions[tri.v[2]];
        if (!w.triangle_opaque[t] || a.z != p.z || b.z != p.z || c.z != p.z) continue;
        auto side = [&](glm::vec3 e0, glm::vec3 e1) {
            return double(e1.x - e0.x) * double(p.y - e0.y) - double(e1.y - e0.y) * double(p.x - e0.x);
        };
        const double s0 = side(a, b), s1 = side(b, c), s2 = side(c, a);
        if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0)) return true;
    }
    return false;
}

// [2, 3] x [0, 1] at z = 5 as a fan of three triangles around (2.5, 1), a vertex no neighbour shares.
void add_t_junction_fan(World& w) {
    add_triangle(w, {2, 0, 5}, {3, 0, 5}, {2.5f, 1, 5});
    add_triangle(w, {2, 0, 5}, {2.5f, 1, 5}, {2, 1, 5});
    add_triangle(w, {3, 0, 5}, {3, 1, 5}, {2.5f, 1, 5});
}

TEST(Panels, AFanAndTJunctionsGiveTheMaximalRectanglesTheyCover) {
    World w;
    // A pentagon as a fan from (0, 0): covers [0, 4] x [0, 2] and [0, 2] x [0, 4], not the corner beyond
    // the slanted edge from (4, 2) to (2, 4).
    add_triangle(w, {0, 0, 1}, {4, 0, 1}, {4, 2, 1});
    add_triangle(w, {0, 0, 1}, {4, 2, 1}, {2, 4, 1});
    add_triangle(w, {0, 0, 1}, {2, 4, 1}, {0, 4, 1});
    std::vector<Aabb> panels = find_panels(w);
    ASSERT_EQ(panels.size(), 2u);
    std::sort(panels.begin(), panels.end(), [](const Aabb& a, const Aabb& b) { return a.max.x > b.max.x; });
    EXPECT_EQ(panels[0].min, glm::vec3(0, 0, 1));
    EXPECT_EQ(panels[0].max, glm::vec3(4, 2, 1));
    EXPECT_EQ(panels[1].min, glm::vec3(0, 0, 1));
    EXPECT_EQ(panels[1].max, glm::vec3(2, 4, 1));

    // A wall of three meshes with a T-junction: [0, 2] x [0, 1] as one pair, [2, 3] x [0, 1] as a fan
    // whose middle vertex (2.5, 1) is nobody else's, and [0, 3] x [1, 2] above: one panel [0, 3] x [0, 2].
    World t;
    add_rect_z(t, 5.0f, 0, 2, 0, 1);
    add_t_junction_fan(t);
    add_rect_z(t, 5.0f, 0, 3, 1, 2);
    panels = find_panels(t);
    ASSERT_EQ(panels.size(), 1u);
    EXPECT_EQ(panels[0].min, glm::vec3(0, 0, 5));
    EXPECT_EQ(panels[0].max, glm::vec3(3, 2, 5));

    // The same with a crack 1 mm wide between the pair and the fan: two panels, none across the crack.
    World c;
    add_rect_z(c, 5.0f, 0, 1.999f, 0, 1);
    add_t_junction_fan(c);
    for (const Aabb& p : find_panels(c)) EXPECT_FALSE(p.min.x < 1.9995f && p.max.x > 1.9995f) << p.min.x;
}

// Random soups of axis-plane triangles (fans of random convex polygons on a coarse grid, pairs, slivers,
// overlaps, near misses): every point of every panel lies in some opaque triangle of its plane.
TEST(PanelsProperty, EveryPointOfAPanelIsCovered) {
    Rng rng(7, 1);
    uint64_t checked = 0, panels_seen = 0;
    for (int world = 0; world < 60; ++world) {
        World w;
        const float z = float(world % 3);
        for (int poly = 0; poly < 6; ++poly) {
            // A convex polygon: points on a circle, coordinates on a 1/8 grid (shared-edge exactness).
            const float cx = float(rng.below(8)), cy = float(rng.below(8)), r = 0.5f + float(rng.below(4));
            const int n = 3 + int(rng.below(5));
            std::vector<glm::vec3> ring;
            const float phase = rng.uniform() * 6.283f;
            for (int k = 0; k < n; ++k) {
                const float ang = phase + 6.2831853f * float(k) / float(n);
                ring.emplace_back(std::round((cx + r * std::cos(ang)) * 8.0f) / 8.0f,
                                  std::round((cy + r * std::sin(ang)) * 8.0f) / 8.0f, z);
            }
            for (int k = 1; k + 1 < n; ++k) add_triangle(w, ring[0], ring[size_t(k)], ring[size_t(k + 1)]);
            // Sometimes a rectangle beside it, a hair apart or touching.
            if (rng.below(2)) {
                const float gap = rng.below(2) ? 0.0f : 1e-3f;
                add_rect_z(w, z, cx + r + gap, cx + r + 2.0f, cy - 1.0f, cy + 1.0f);
            }
        }
        for (const Aabb& p : find_panels(w)) {
            ++panels_seen;
            ASSERT_EQ(panel_axis(p), 2);
            for (int k = 0; k < 200; ++k) {
                // Points of the closed rectangle, corners and edges included, pulled 1e-4 m inside.
                const float fu = rng.below(4) == 0 ? float(rng.below(2)) : rng.uniform();
                const float fv = rng.below(4) == 0 ? float(rng.below(2)) : rng.uniform();
                const glm::vec3 q(p.min.x + 1e-4f + fu * (p.max.x - p.min.x - 2e-4f),
                                  p.min.y + 1e-4f + fv * (p.max.y - p.min.y - 2e-4f), p.min.z);
                ASSERT_TRUE(covered_at(w, q)) << "world " << world << " point " << q.x << ", " << q.y;
                ++checked;
            }
        }
    }
    EXPECT_GT(panels_seen, 100u);
    EXPECT_GT(checked, 20000u);
}

// ---------------------------------------------------------------------------------------------------------
// Slanted panels: convex polygons tiled by coplanar opaque triangles off the axis planes.

// Maps (u, v) of a plane tilted 37 degrees about x (and turned 20 degrees about y), lifted by h along its
// normal, to world space.
glm::vec3 tilted(float u, float v, float h = 0.0f) {
    const float a = glm::radians(37.0f), b = glm::radians(20.0f);
    const glm::vec3 e1(std::cos(b), 0.0f, -std::sin(b));
    const glm::vec3 e2 = glm::vec3(std::sin(b) * std::sin(a), std::cos(a), std::cos(b) * std::sin(a));
    return glm::vec3(1, 2, 3) + u * e1 + v * e2 + h * glm::normalize(glm::cross(e1, e2));
}

bool convex_ccw(const SlantedPanel& p) {
    const size_t n = p.corners.size();
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 a = p.corners[i], b = p.corners[(i + 1) % n], c = p.corners[(i + 2) % n];
        if (glm::dot(glm::cross(b - a, c - b), p.normal) < -1e-9) return false;
    }
    return n >= 3;
}

double total_area(const std::vector<SlantedPanel>& panels) {
    double a = 0.0;
    for (const SlantedPanel& p : panels) a += p.area_m2;
    return a;
}

TEST(SlantedPanels, ATiltedRectangleOfTwoTrianglesIsOneConvexPanel) {
    World w;
    add_triangle(w, tilted(0, 0), tilted(3, 0), tilted(3, 2));
    add_triangle(w, tilted(0, 0), tilted(3, 2), tilted(0, 2));
    SlantedPanelFigures fig;
    const std::vector<SlantedPanel> panels = find_slanted_panels(w, 1e-4, 0.0, &fig);
    EXPECT_EQ(fig.slanted_triangles, 2u);
    ASSERT_EQ(panels.size(), 1u);
    EXPECT_EQ(panels[0].corners.size(), 4u);
    EXPECT_EQ(panels[0].triangles, 2u);
    EXPECT_NEAR(panels[0].area_m2, 6.0, 1e-5);
    EXPECT_TRUE(convex_ccw(panels[0]));
    EXPECT_LT(panels[0].thickness, 1e-5);
    const glm::dvec3 want = glm::normalize(
        glm::cross(glm::dvec3(tilted(1, 0) - tilted(0, 0)), glm::dvec3(tilted(0, 1) - tilted(0, 0))));
    EXPECT_GT(std::abs(glm::dot(panels[0].normal, want)), 1.0 - 1e-9);
}

TEST(SlantedPanels, ShapesSplitIntoConvexPiecesThatTileThemAndFoldsAreNotMerged) {
    World w;
    // An L of three unit squares: not convex, so at least two pieces, of area 3 together.
    for (const auto& [u, v] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{0, 1}}) {
        add_triangle(w, tilted(float(u), float(v)), tilted(float(u + 1), float(v)),
                     tilted(float(u + 1), float(v + 1)));
        add_triangle(w, tilted(float(u), float(v)), tilted(float(u + 1), float(v + 1)),
                     tilted(float(u), float(v + 1)));
    }
    std::vector<SlantedPanel> panels = find_slanted_panels(w, 1e-4, 0.0);
    EXPECT_GE(panels.size(), 2u);
    EXPECT_NEAR(total_area(panels), 3.0, 1e-5);
    for (const SlantedPanel& p : panels) EXPECT_TRUE(convex_ccw(p));
    // A fan of six triangles (a hexagon): its centre stays a corner until the last triangle, so the fan
    // grows into pieces of at most half of it (the limit of growing convex polygons one triangle at a
    // time); whether a half closes at exactly 180 degrees depends on rounding.
    World fan;
    std::vector<glm::vec3> rim;
    for (int k = 0; k < 6; ++k)
        rim.push_back(
            tilted(std::cos(glm::radians(60.0f * float(k))), std::sin(glm::radians(60.0f * float(k)))));
    for (int k = 0; k < 6; ++k) add_triangle(fan, tilted(0, 0), rim[size_t(k)], rim[size_t(k + 1) % 6]);
    panels = find_slanted_panels(fan, 1e-4, 0.0);
    EXPECT_GE(panels.size(), 2u);
    EXPECT_LE(panels.size(), 3u);
    EXPECT_NEAR(total_area(panels), 1.5 * std::sqrt(3.0), 1e-5);
    // A ridge: two slopes sharing an edge are two panels. A triangle lifted by 1 mm off the plane of its
    // neighbour joins it only when the thickness allows.
    World ridge;
    add_triangle(ridge, {0, 0, 0}, {4, 0, 0}, {2, 1, 1});
    add_triangle(ridge, {0, 0, 0}, {2, 1, 1}, {0, 1, 1});
    add_triangle(ridge, {0, 1, 1}, {2, 1, 1}, {2, 0, 2});
    EXPECT_EQ(find_slanted_panels(ridge, 1e-4, 0.0).size(), 2u);
    World lifted;
    add_triangle(lifted, tilted(0, 0), tilted(2, 0), tilted(2, 2));
    add_triangle(lifted, tilted(0, 0), tilted(2, 2), tilted(0, 2, 0.001f));
    EXPECT_EQ(find_slanted_panels(lifted, 1e-4, 0.0).size(), 2u);
    ASSERT_EQ(find_slanted_panels(lifted, 0.002, 0.0).size(), 1u);
    EXPECT_NEAR(find_slanted_panels(lifted, 0.002, 0.0)[0].thickness, 0.001, 1e-4);
}

TEST(SlantedPanels, AxisPlanesGlassHalfEdgesAndSmallPiecesAreLeftOut) {
    World w;
    add_rect_z(w, 1.0f, 0, 2, 0, 2);                                              // an axis plane
    add_triangle(w, tilted(0, 0), tilted(2, 0), tilted(2, 2), /*opaque=*/false);  // glass
    // A T-junction: the long edge of one triangle is two edges of the others: not shared whole.
    add_triangle(w, tilted(10, 0), tilted(12, 0), tilted(11, -1));
    add_triangle(w, tilted(10, 0), tilted(11, 1), tilted(11, 0));
    add_triangle(w, tilted(11, 0), tilted(11, 1), tilted(12, 0));
    SlantedPanelFigures fig;
    const std::vector<SlantedPanel> panels = find_slanted_panels(w, 1e-4, 0.0, &fig);
    EXPECT_EQ(fig.slanted_triangles, 3u);
    EXPECT_EQ(panels.size(), 2u);  // the lower triangle alone, the upper two together
    EXPECT_EQ(find_slanted_panels(w, 1e-4, 1.5).size(), 0u);  // each piece is 1 m2
}

// Tiles (the horizon's form of the panels): each keeps its panel's corners as the float vertices they are, so
// panels sharing an edge share those corners exactly; every corner lies within the slab as the runtime reads
// it (the float plane divided by its normal's length); a panel of more than kTileMaxCorners corners is left
// out. On random tilted sheets of quads, some lifted off the plane.
TEST(SlantedPanelsProperty, TilesKeepTheCornersExactlyAndHoldThemInTheirSlab) {
    Rng rng(43, 1);
    size_t tiles = 0, shared = 0;
    for (int trial = 0; trial < (test::in_ci() ? 20 : 100); ++trial) {
        World w;
        const int nu = 1 + int(rng.uniform() * 5), nv = 1 + int(rng.uniform() * 5);
        for (int i = 0; i < nu; ++i)
            for (int j = 0; j < nv; ++j) {
                const float u = float(i), v = float(j), lift = rng.uniform() < 0.3 ? 2e-5f : 0.0f;
                add_triangle(w, tilted(u, v), tilted(u + 1, v), tilted(u + 1, v + 1, lift));
                add_triangle(w, tilted(u, v), tilted(u + 1, v + 1, lift), tilted(u, v + 1));
            }
        const std::vector<SlantedPanel> panels = find_slanted_panels(w, 1e-4, 0.0);
        const std::vector<OccluderPolygon> t = runtime_tiles(panels, 0.0);
        size_t want = 0;
        for (const SlantedPanel& p : panels) want += p.corners.size() <= kTileMaxCorners;
        EXPECT_EQ(t.size(), want) << "trial " << trial;
        std::vector<glm::vec3> vertices(w.positions.begin(), w.positions.end());
        for (const OccluderPolygon& q : t) {
            ++tiles;
            EXPECT_TRUE(q.tile);
            const glm::dvec3 nf(q.normal);
            const double len = glm::length(nf);
            for (const glm::vec3& c : q.corners) {
                EXPECT_NE(std::find(vertices.begin(), vertices.end(), c), vertices.end())
                    << "a corner that is no vertex of the world";
                EXPECT_LE(std::abs(glm::dot(nf / len, glm::dvec3(c)) - double(q.offset) / len),
                          double(q.thickness) / len - kTileSlabGrowM * 0.5);
            }
        }
        for (size_t a = 0; a < t.size(); ++a)  // neighbours share corners exactly
            for (size_t b = a + 1; b < t.size(); ++b)
                for (const glm::vec3& c : t[a].corners)
                    shared += std::find(t[b].corners.begin(), t[b].corners.end(), c) != t[b].corners.end();
    }
    EXPECT_GT(tiles, 0u);
    EXPECT_GT(shared, 0u);
}

// Random tilted sheets of quads, each split along a random diagonal, some lifted off the plane: the panels
// are convex, no triangle is in two, together they hold exactly the triangles' area, and every point of a
// panel lies in one of its plane's triangles.
TEST(SlantedPanelsProperty, PanelsAreConvexAndExactlyTiledByTheirTriangles) {
    Rng rng(41, 0);
    for (int trial = 0; trial < (test::in_ci() ? 20 : 200); ++trial) {
        World w;
        const int nu = 1 + int(rng.uniform() * 5), nv = 1 + int(rng.uniform() * 5);
        double want = 0.0;
        std::vector<std::vector<bool>> laid(size_t(nu), std::vector<bool>(size_t(nv), false));
        for (int i = 0; i < nu; ++i) {
            for (int j = 0; j < nv; ++j) {
                if (rng.uniform() < 0.2) continue;  // holes make the sheet non-convex
                laid[size_t(i)][size_t(j)] = true;
                const float u = float(i), v = float(j);
                if (rng.uniform() < 0.5) {
                    add_triangle(w, tilted(u, v), tilted(u + 1, v), tilted(u + 1, v + 1));
                    add_triangle(w, tilted(u, v), tilted(u + 1, v + 1), tilted(u, v + 1));
                } else {
                    add_triangle(w, tilted(u, v), tilted(u + 1, v), tilted(u, v + 1));
                    add_triangle(w, tilted(u + 1, v), tilted(u + 1, v + 1), tilted(u, v + 1));
                }
                want += 1.0;
            }
        }
        const std::vector<SlantedPanel> panels = find_slanted_panels(w, 1e-4, 0.0);
        EXPECT_NEAR(total_area(panels), want, 1e-4 * (want + 1.0)) << "trial " << trial;
        uint32_t members = 0;
        for (const SlantedPanel& p : panels) {
            members += p.triangles;
            ASSERT_TRUE(convex_ccw(p)) << "trial " << trial;
            // Random points of the panel (convex combinations of its corners) lie on the sheet.
            for (int k = 0; k < 20; ++k) {
                glm::dvec3 q(0.0);
                double sum = 0.0;
                for (const glm::dvec3& c : p.corners) {
                    const double wgt = rng.uniform();
                    q += wgt * c;
                    sum += wgt;
                }
                q /= sum;
                // Back to (u, v): the sheet's square holding it must be one that was laid.
                const glm::dvec3 o = glm::dvec3(tilted(0, 0));
                const glm::dvec3 e1 = glm::dvec3(tilted(1, 0)) - o, e2 = glm::dvec3(tilted(0, 1)) - o;
                const double u = glm::dot(q - o, e1) / glm::dot(e1, e1),
                             v = glm::dot(q - o, e2) / glm::dot(e2, e2);
                EXPECT_LT(std::abs(glm::dot(q - o, glm::normalize(glm::cross(e1, e2)))), 1e-5);
                const int iu = int(std::floor(u)), iv = int(std::floor(v));
                ASSERT_TRUE(iu >= 0 && iv >= 0 && iu < nu && iv < nv && laid[size_t(iu)][size_t(iv)])
                    << "trial " << trial << ": (" << u << ", " << v << ") is not on the sheet";
            }
        }
        EXPECT_EQ(members, uint32_t(w.triangles.size()));
    }
}

TEST(Panels, InsetShrinksTheRectangleAndDropsWhatVanishes) {
    const std::vector<Aabb> panels = {Aabb::of({0, 0, 3}, {5, 4, 3}), Aabb::of({0, 0, 7}, {0.5f, 9, 7}),
                                      Aabb::of({0, 0, 0}, {1, 1, 1})};  // the last is no panel
    const std::vector<Aabb> inset = inset_panels(panels, 0.3);
    ASSERT_EQ(inset.size(), 1u);
    EXPECT_GE(double(inset[0].min.x), 0.3);
    EXPECT_LE(double(inset[0].max.x), 4.7);
    EXPECT_NEAR(inset[0].min.y, 0.3f, 1e-6f);
    EXPECT_NEAR(inset[0].max.y, 3.7f, 1e-6f);
    EXPECT_EQ(inset[0].min.z, 3.0f);
    EXPECT_EQ(inset[0].max.z, 3.0f);
    // Never rounded outward: the float nearest 0.1 is below it, so the inset edge goes up past it.
    const std::vector<Aabb> thin = inset_panels({Aabb::of({0, 0, 1}, {1, 1, 1})}, 0.1);
    ASSERT_EQ(thin.size(), 1u);
    EXPECT_GE(double(thin[0].min.x), 0.1);
    EXPECT_LE(double(thin[0].max.x), 0.9);
}

}  // namespace
}  // namespace pvs
