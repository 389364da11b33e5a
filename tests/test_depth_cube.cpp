// SPDX-License-Identifier: MIT
// The conservative depth cube map: hand-built scenes (who hides whom), the fast kernel against the plain
// reference on fixed seeds (identical answers), and the conservative guarantee against dense ray sampling.
#include "core/error.h"
#include "core/random.h"
#include "pvs/depth_cube.h"
#include "tests/depth_cube_checks.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pvs {
namespace {

using test::segment_blocked;

Aabb box(glm::vec3 lo, glm::vec3 hi) {
    return Aabb::of(lo, hi);
}

DepthCube cube_with(glm::vec3 eye, const std::vector<Aabb>& occluders, int resolution = 64) {
    DepthCube cube(resolution);
    cube.clear(eye);
    for (const Aabb& b : occluders) cube.add_occluder(b);
    return cube;
}

// Fast and reference must agree on every hand-built case too.
void expect_hidden(const std::vector<Aabb>& occluders, glm::vec3 eye, const Aabb& occludee, bool hidden,
                   int resolution = 64) {
    const DepthCube cube = cube_with(eye, occluders, resolution);
    EXPECT_EQ(cube.is_hidden(occludee), hidden);
    EXPECT_EQ(is_hidden_reference(occluders, eye, occludee, resolution), hidden);
}

const glm::vec3 kOrigin(0.0f);
const Aabb kWall = box({5, -5, -5}, {6, 5, 5});  // 1 m thick, 10 x 10 m, 5 m along +X from the origin

TEST(DepthCube, EmptyMapHidesNothing) {
    const DepthCube cube = cube_with(kOrigin, {});
    EXPECT_EQ(cube.covered_pixel_count(), 0u);
    EXPECT_FALSE(cube.is_hidden(box({8, -1, -1}, {9, 1, 1})));
}

TEST(DepthCube, WallHidesWhatIsBehindItOnly) {
    expect_hidden({kWall}, kOrigin, box({8, -1, -1}, {9, 1, 1}), true);     // behind
    expect_hidden({kWall}, kOrigin, box({6, -1, -1}, {7, 1, 1}), true);     // touching its back
    expect_hidden({kWall}, kOrigin, box({8, 10, -1}, {9, 11, 1}), false);   // beside
    expect_hidden({kWall}, kOrigin, box({2, -1, -1}, {3, 1, 1}), false);    // in front
    expect_hidden({kWall}, kOrigin, box({-9, -1, -1}, {-8, 1, 1}), false);  // behind the eye
    expect_hidden({kWall}, kOrigin, box({8, 4, -1}, {9, 9, 1}), false);     // peeks past the edge (u > 1)
    expect_hidden({kWall}, kOrigin, box({8, -1, -1}, {90, 1, 1}), true);    // long, still in the shadow
    // Near the edge (u <= 0.69), still in the shadow.
    expect_hidden({kWall}, kOrigin, box({8, 4, -1}, {9, 5.5f, 1}), true);
}

TEST(DepthCube, EqualDepthIsVisible) {
    // A flat occludee lying on the wall's front face: same depth, not strictly nearer, so visible.
    expect_hidden({kWall}, kOrigin, box({5, -1, -1}, {5, 1, 1}), false);
    // A hair behind the front face is still within the depth slack: visible.
    expect_hidden({kWall}, kOrigin, box({5.000001f, -1, -1}, {5.000001f, 1, 1}), false);
    expect_hidden({kWall}, kOrigin, box({5.01f, -1, -1}, {5.01f, 1, 1}), true);
}

TEST(DepthCube, StoredDepthIsTheEntryDepthRoundedUp) {
    const DepthCube cube = cube_with(kOrigin, {kWall}, 32);
    // Face +X (0), pixel next to the centre: the rays enter through the front face at depth 5.
    const float d = cube.depth(0, 16, 16);
    EXPECT_GE(d, 5.0f);
    EXPECT_NEAR(d, 5.0f, 1e-4f);
    EXPECT_EQ(cube.depth(1, 16, 16), std::numeric_limits<float>::infinity());  // -X: nothing
    // A 5 x 5 m wall at depth 5 projects onto |u|, |v| <= 0.5 (its front face; the back face projects
    // smaller). At R = 32 pixels are 1/16 wide: pixels 8..23 lie inside, but the corner rays of pixels 8 and
    // 23 only graze the wall's edge (exit == entry), which is not "certainly through": 14 x 14 pixels.
    const DepthCube narrow = cube_with(kOrigin, {box({5, -2.5f, -2.5f}, {6, 2.5f, 2.5f})}, 32);
    EXPECT_LT(narrow.depth(0, 9, 16), 5.001f);
    EXPECT_LT(narrow.depth(0, 22, 16), 5.001f);
    EXPECT_EQ(narrow.depth(0, 8, 16), std::numeric_limits<float>::infinity());
    EXPECT_EQ(narrow.depth(0, 23, 16), std::numeric_limits<float>::infinity());
    EXPECT_EQ(narrow.covered_pixel_count(), 14u * 14u);
    // Slightly wider, the edge pixels are in.
    const DepthCube wider = cube_with(kOrigin, {box({5, -2.501f, -2.501f}, {6, 2.501f, 2.501f})}, 32);
    EXPECT_EQ(wider.covered_pixel_count(), 16u * 16u);
}

TEST(DepthCube, TwoHalfWallsFuseOnTheDepthBuffer) {
    const Aabb lower = box({5, -5, -5}, {6, 0.5f, 5});
    const Aabb upper = box({5.5f, -0.5f, -5}, {6.5f, 5, 5});
    const Aabb target = box({9, -1, -1}, {10, 1, 1});
    expect_hidden({lower}, kOrigin, target, false);
    expect_hidden({upper}, kOrigin, target, false);
    expect_hidden({lower, upper}, kOrigin, target, true);
    // With a gap between them the target is visible.
    expect_hidden({box({5, -5, -5}, {6, -0.2f, 5}), box({5.5f, 0.2f, -5}, {6.5f, 5, 5})}, kOrigin, target,
                  false);
}

TEST(DepthCube, OccluderContainingTheEyeHidesNothing) {
    const Aabb solid = box({-10, -10, -10}, {10, 10, 10});
    const DepthCube cube = cube_with(kOrigin, {solid, kWall});
    // The solid writes nothing; only the wall does.
    const DepthCube wall_only = cube_with(kOrigin, {kWall});
    EXPECT_EQ(cube.covered_pixel_count(), wall_only.covered_pixel_count());
    expect_hidden({solid}, kOrigin, box({2, -1, -1}, {3, 1, 1}), false);
    expect_hidden({solid}, kOrigin, box({20, -1, -1}, {21, 1, 1}), false);
    expect_hidden({box({0, -1, -1}, {1, 1, 1})}, kOrigin, box({5, -0.1f, -0.1f}, {6, 0.1f, 0.1f}), false);
}

TEST(DepthCube, OccludeeAtTheEyeOrTheNearPlaneIsVisible) {
    expect_hidden({kWall}, kOrigin, box({-1, -1, -1}, {1, 1, 1}), false);        // contains the eye
    expect_hidden({kWall}, kOrigin, box({0.00005f, -1, -1}, {9, 1, 1}), false);  // crosses the +X near plane
    expect_hidden({kWall}, kOrigin, Aabb::empty(), false);
}

TEST(DepthCube, FloorNextToTheEyeOccludesOnTheSideFaces) {
    // The floor crosses the near planes of the four side faces; it is clipped to d >= near there, so it
    // still hides what is under it at shallow angles (on face +X here).
    const glm::vec3 eye(0, 1.7f, 0);
    const Aabb floor = box({-50, -1, -50}, {50, 0, 50});
    expect_hidden({floor}, eye, box({10, -3, -0.5f}, {11, -2, 0.5f}), true);
    expect_hidden({floor}, eye, box({10, 0.5f, -0.5f}, {11, 1, 0.5f}), false);
    expect_hidden({floor}, eye, box({60, -3, -0.5f}, {61, -2, 0.5f}), false);  // past the floor's edge
}

TEST(DepthCube, BoxesSpanningSeveralFaces) {
    // A huge wall in front on +X, seen on +X, +Z, -Z, +Y, -Y; the occludee sits on the +X / +Z edge
    // direction (1, 0, 1) and projects onto both faces.
    const Aabb big = box({5, -40, -40}, {6, 40, 40});
    const Aabb diagonal = box({8, -0.5f, 8}, {9, 0.5f, 9});
    expect_hidden({big}, kOrigin, diagonal, true);
    expect_hidden({big}, kOrigin, box({8, 8, 8}, {9, 9, 9}), true);             // the cube corner (1, 1, 1)
    expect_hidden({big}, kOrigin, box({4, -0.5f, 8}, {4.5f, 0.5f, 9}), false);  // in front of it
    // The same wall split into two halves along z = 0: fusion across the occludee's faces.
    expect_hidden({box({5, -40, -40}, {6, 40, 0.5f}), box({5, -40, -0.5f}, {6, 40, 40})}, kOrigin,
                  box({8, -0.5f, -0.5f}, {9, 0.5f, 0.5f}), true);
}

TEST(DepthCube, RejectsABadResolution) {
    EXPECT_THROW(DepthCube(0), Error);
    EXPECT_THROW(DepthCube(kMaxCubeResolution + 1), Error);
    EXPECT_NO_THROW(DepthCube(1));
}

// ---------------------------------------------------------------------------------------------------------
// Random scenes.

struct Scene {
    glm::vec3 eye;
    std::vector<Aabb> occluders;
    std::vector<Aabb> occludees;
};

float snap(float x, float step) {
    return step > 0.0f ? std::round(x / step) * step : x;
}

// Walls and blocks around an eye; half the scenes snap every coordinate (eye included) to a 0.25 m grid,
// so box faces pass exactly through the eye's planes and through pixel edges (the awkward cases).
Scene random_scene(Rng& rng) {
    Scene s;
    const float step = rng.uniform() < 0.5f ? 0.25f : 0.0f;
    auto r3 = [&](float lo, float hi) {
        return glm::vec3(lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform(),
                         lo + (hi - lo) * rng.uniform());
    };
    auto snapped = [&](glm::vec3 p) { return glm::vec3(snap(p.x, step), snap(p.y, step), snap(p.z, step)); };
    s.eye = snapped(r3(0, 20));
    const int n_occ = 3 + int(rng.below(20));
    for (int k = 0; k < n_occ; ++k) {
        glm::vec3 size = r3(1, 6);
        if (rng.uniform() < 0.6f) {  // a wall: thin along one axis, wide along the others
            size = r3(4, 14);
            size[rng.below(3)] = 0.2f + rng.uniform();
        }
        const glm::vec3 c = s.eye + r3(-12, 12);
        s.occluders.push_back(Aabb::of(snapped(c - 0.5f * size), snapped(c + 0.5f * size)));
    }
    for (int k = 0; k < 40; ++k) {
        const glm::vec3 size = r3(0.05f, 2.0f);
        const glm::vec3 c = s.eye + r3(-16, 16);
        Aabb b = Aabb::of(snapped(c - 0.5f * size), snapped(c + 0.5f * size));
        if (rng.uniform() < 0.05f) b.max.x = b.min.x;  // flat boxes
        s.occludees.push_back(b);
    }
    return s;
}

TEST(DepthCube, MatchesTheReferenceOnRandomScenes) {
    const int scenes = test::in_ci() ? 60 : 300;
    const int resolutions[] = {16, 17, 24, 31, 32, 48, 64};
    Rng rng(7, 11);
    test::CubeCheck check;
    DepthCube cube(16);
    for (int n = 0; n < scenes && check.failures <= 5; ++n) {
        const Scene s = random_scene(rng);
        const int r = resolutions[rng.below(7)];
        if (cube.resolution() != r) cube = DepthCube(r);
        cube.clear(s.eye);
        for (const Aabb& b : s.occluders) cube.add_occluder(b);
        test::expect_same_answers(
            cube, s.occludees, [&](const Aabb& b) { return is_hidden_reference(s.occluders, s.eye, b, r); },
            "scene " + std::to_string(n) + " resolution " + std::to_string(r), check);
    }
    EXPECT_EQ(check.failures, 0);
    EXPECT_GT(check.hidden, check.tested / 10) << check.hidden << " of " << check.tested << " hidden";
    EXPECT_LT(check.hidden, check.tested * 9 / 10);
}

TEST(DepthCube, HiddenMeansEveryRayIsBlocked) {
    const int scenes = test::in_ci() ? 80 : 400;
    const int rays_per_box = test::in_ci() ? 500 : 2000;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(3, 5);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        const Scene s = random_scene(rng);
        DepthCube cube(resolutions[rng.below(4)]);
        cube.clear(s.eye);
        for (const Aabb& b : s.occluders) cube.add_occluder(b);
        // Ground truth ignores occluders containing the eye (the cube may not rely on them).
        std::vector<Aabb> blockers;
        for (const Aabb& b : s.occluders) {
            if (!b.contains(s.eye)) blockers.push_back(b);
        }
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, glm::dvec3(0.0), rays_per_box, 1, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) {
                return std::any_of(blockers.begin(), blockers.end(),
                                   [&](const Aabb& o) { return segment_blocked(q, x, o); });
            },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " rays";
    EXPECT_GT(check.hidden, check.tested / 10) << check.hidden << " of " << check.tested << " hidden";
}

// Walls given as their two big faces (panels) instead of boxes, as occluders/panels.h finds them.
std::vector<Aabb> wall_faces(const std::vector<Aabb>& walls) {
    std::vector<Aabb> panels;
    for (const Aabb& w : walls) {
        const glm::vec3 size = w.size();
        const int thin = size.x <= size.y && size.x <= size.z ? 0 : (size.y <= size.z ? 1 : 2);
        for (int side = 0; side < 2; ++side) {
            Aabb p = w;
            p.min[thin] = p.max[thin] = side ? w.max[thin] : w.min[thin];
            panels.push_back(p);
        }
    }
    return panels;
}

TEST(DepthCube, PanelsMatchTheReferenceOnRandomScenes) {
    const int scenes = test::in_ci() ? 60 : 300;
    const int resolutions[] = {16, 17, 24, 31, 32, 48, 64};
    Rng rng(17, 3);
    test::CubeCheck check;
    DepthCube cube(16);
    for (int n = 0; n < scenes && check.failures <= 5; ++n) {
        Scene s = random_scene(rng);
        // Half the occluders become panels (their two largest faces).
        const size_t half = s.occluders.size() / 2;
        const std::vector<Aabb> panels =
            wall_faces(std::vector<Aabb>(s.occluders.begin(), s.occluders.begin() + std::ptrdiff_t(half)));
        s.occluders.erase(s.occluders.begin(), s.occluders.begin() + std::ptrdiff_t(half));
        const int r = resolutions[rng.below(7)];
        // A third of the scenes from the point itself, the rest for a box around it (per-ray insets).
        const glm::dvec3 spread = n % 3 == 0 ? glm::dvec3(0.0) : test::random_eye_box(rng, 0.05, 1.0);
        if (cube.resolution() != r) cube = DepthCube(r);
        cube.clear(s.eye);
        cube.add_panels(panels, spread);
        const bool with_sides = n % 2 == 1;  // half the scenes draw the panels on the side faces too
        if (with_sides) cube.add_panels_sides(panels, spread);
        for (const Aabb& b : s.occluders) cube.add_occluder(b);
        test::expect_same_answers(
            cube, s.occludees,
            [&](const Aabb& b) {
                return is_hidden_reference(s.occluders, panels, spread, s.eye, b, r, with_sides);
            },
            "scene " + std::to_string(n) + " resolution " + std::to_string(r), check);
    }
    EXPECT_EQ(check.failures, 0);
    EXPECT_GT(check.hidden, check.tested / 10) << check.hidden << " of " << check.tested << " hidden";
    EXPECT_LT(check.hidden, check.tested * 9 / 10);
}

TEST(DepthCube, APanelHidesWhatIsBehindItSeenFromEitherSideOnly) {
    const Aabb panel = Aabb::of({-2.0f, -2.0f, 5.0f}, {2.0f, 2.0f, 5.0f});  // flat along z at z = 5
    const Aabb behind = Aabb::of({-0.5f, -0.5f, 7.0f}, {0.5f, 0.5f, 8.0f});
    const Aabb in_front = Aabb::of({-0.5f, -0.5f, 3.0f}, {0.5f, 0.5f, 4.0f});
    const Aabb past_its_edge = Aabb::of({3.0f, -0.5f, 7.0f}, {4.0f, 0.5f, 8.0f});
    const Aabb touching_it = Aabb::of({-0.5f, -0.5f, 5.0f}, {0.5f, 0.5f, 6.0f});
    DepthCube cube(64);
    cube.clear({0.0f, 0.0f, 0.0f});
    cube.add_panel(panel);
    EXPECT_TRUE(cube.is_hidden(behind));
    EXPECT_FALSE(cube.is_hidden(in_front));
    EXPECT_FALSE(cube.is_hidden(past_its_edge));
    EXPECT_FALSE(cube.is_hidden(touching_it));  // equal depth counts as visible
    // From the other side, what is now behind it.
    cube.clear({0.0f, 0.0f, 10.0f});
    cube.add_panel(panel);
    EXPECT_TRUE(cube.is_hidden(in_front));
    EXPECT_FALSE(cube.is_hidden(behind));
    // A box is no panel: flat along two axes, or along none, draws nothing.
    cube.clear({0.0f, 0.0f, 0.0f});
    cube.add_panel(Aabb::of({-2.0f, 0.0f, 5.0f}, {2.0f, 0.0f, 5.0f}));
    cube.add_panel(Aabb::of({-2.0f, -2.0f, 5.0f}, {2.0f, 2.0f, 5.5f}));
    EXPECT_EQ(cube.covered_pixel_count(), 0u);
}

// For a patch of a cell face 0.5 m around the eye in x and y (flat in z), a 4 x 4 m panel 5 m away along z
// is inset by 0.5 m on each ray: the crossing must lie 1.5 m from its centre (u <= 0.3). For an eye box as
// deep as it is wide (0.5 m along z too) the inset grows with the ray's slope, 0.5 + 0.5 |u| m: the rays
// through the pixels around u = 0.27 cross 1.36 m off the centre, inside the 1.5 m, but not inside the
// 2 - 0.64 m the deeper box asks there.
TEST(DepthCube, APanelForAnEyeBoxIsInsetPerRay) {
    const Aabb panel = Aabb::of({-2.0f, -2.0f, 5.0f}, {2.0f, 2.0f, 5.0f});
    const Aabb off_centre = Aabb::of({1.6f, -0.5f, 7.0f}, {1.85f, 0.5f, 8.0f});      // u in [0.2, 0.27]
    const Aabb nearer_the_edge = Aabb::of({2.0f, -0.5f, 7.0f}, {2.2f, 0.5f, 8.0f});  // u up to 0.31
    const glm::dvec3 flat(0.5, 0.5, 0.0), deep(0.5, 0.5, 0.5);
    DepthCube cube(64);
    cube.clear(kOrigin);
    cube.add_panel(panel, flat);
    EXPECT_TRUE(cube.is_hidden(off_centre));
    EXPECT_FALSE(cube.is_hidden(nearer_the_edge));
    EXPECT_TRUE(is_hidden_reference({}, {panel}, flat, kOrigin, off_centre, 64));
    EXPECT_FALSE(is_hidden_reference({}, {panel}, flat, kOrigin, nearer_the_edge, 64));
    cube.clear(kOrigin);
    cube.add_panel(panel, deep);
    EXPECT_FALSE(cube.is_hidden(off_centre));
    EXPECT_FALSE(is_hidden_reference({}, {panel}, deep, kOrigin, off_centre, 64));
    // The same from the other side of the plane (a negative height), with the panel reaching farther on
    // the side away from the boxes (its two edges are not interchangeable).
    const glm::vec3 beyond(0.0f, 0.0f, 10.0f);
    const Aabb wider = Aabb::of({-3.0f, -2.0f, 5.0f}, {2.0f, 2.0f, 5.0f});
    const auto mirrored = [](const Aabb& b) {
        return Aabb::of({b.min.x, b.min.y, 10.0f - b.max.z}, {b.max.x, b.max.y, 10.0f - b.min.z});
    };
    cube.clear(beyond);
    cube.add_panel(wider, flat);
    EXPECT_TRUE(cube.is_hidden(mirrored(off_centre)));
    EXPECT_FALSE(cube.is_hidden(mirrored(nearer_the_edge)));
    cube.clear(beyond);
    cube.add_panel(wider, deep);
    EXPECT_FALSE(cube.is_hidden(mirrored(off_centre)));
    // From the point itself both are hidden.
    cube.clear(kOrigin);
    cube.add_panel(panel);
    EXPECT_TRUE(cube.is_hidden(nearer_the_edge));
    // A plane the box reaches draws nothing; one it does not reach does, however wide the box is across.
    cube.clear({0.0f, 0.0f, 4.6f});
    cube.add_panel(panel, deep);
    EXPECT_EQ(cube.covered_pixel_count(), 0u);
    cube.add_panel(panel, glm::dvec3(0.5, 0.5, 0.3));
    EXPECT_GT(cube.covered_pixel_count(), 0u);
}

// A floor panel 2 m below the eye (and a ceiling 2 m above), reaching 20 m to -x but only 6 m to +x: a box
// seen through it at a grazing angle (4 m out per metre down: on the cube's -X face) is hidden by the side
// pass, from the eye and from a patch around it, and not when it is in front of the plane. Its sight lines
// cross the plane 6.4 to 8 m out on the long side (at the corners of the pixels they touch).
TEST(DepthCube, APanelOnTheSideFacesHidesWhatIsSeenThroughItAtGrazingAngles) {
    for (const float up : {-1.0f, 1.0f}) {
        const Aabb panel = Aabb::of({-20.0f, 2.0f * up, -20.0f}, {6.0f, 2.0f * up, 20.0f});
        const auto at = [&](float y0, float y1) {
            return Aabb::of({-9.0f, std::min(y0 * up, y1 * up), -0.2f},
                            {-8.6f, std::max(y0 * up, y1 * up), 0.2f});
        };
        for (const glm::dvec3 spread : {glm::dvec3(0.0), glm::dvec3(0.25, 0.0, 0.25), glm::dvec3(0.25)}) {
            DepthCube cube(64);
            cube.clear(kOrigin);
            cube.add_panel(panel, spread);
            EXPECT_FALSE(cube.is_hidden(at(2.4f, 2.6f)));  // the normal face alone cannot see it
            cube.add_panel_sides(panel, spread);
            EXPECT_TRUE(cube.is_hidden(at(2.4f, 2.6f))) << up << " " << spread.x;
            EXPECT_FALSE(cube.is_hidden(at(1.5f, 1.9f)));
            EXPECT_TRUE(is_hidden_reference({}, {panel}, spread, kOrigin, at(2.4f, 2.6f), 64, true));
        }
    }
}

TEST(DepthCube, HiddenByPanelsMeansEveryRayCrossesOne) {
    const int scenes = test::in_ci() ? 80 : 400;
    const int rays_per_box = test::in_ci() ? 500 : 2000;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(5, 9);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        const Scene s = random_scene(rng);
        const std::vector<Aabb> panels = wall_faces(s.occluders);
        DepthCube cube(resolutions[rng.below(4)]);
        cube.clear(s.eye);
        cube.add_panels(panels);
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, glm::dvec3(0.0), rays_per_box, 1, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) {
                return std::any_of(panels.begin(), panels.end(),
                                   [&](const Aabb& p) { return segment_blocked(q, x, p); });
            },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " rays";
    EXPECT_GT(check.hidden, check.tested / 20) << check.hidden << " of " << check.tested << " hidden";
}

// Where a panel's inset per ray is tightest: one panel just beyond the eye box (`reach` is its largest
// half-extent), along a random
// axis and side, and small boxes far behind it in every direction of its cube face, many near its edges, and
// more seen through it at grazing angles (on the side faces).
// The bound r sqrt(1 + u^2) is nearly reached by an eye moved sideways and towards the plane at once, with
// the target far behind the plane.
Scene tight_panel_scene(Rng& rng, double reach, std::vector<Aabb>& panels) {
    Scene s;
    s.eye = glm::vec3(20.0f * rng.uniform(), 20.0f * rng.uniform(), 20.0f * rng.uniform());
    const int a = int(rng.below(3)), ua = (a + 1) % 3, va = (a + 2) % 3;
    const float sign = rng.uniform() < 0.5f ? -1.0f : 1.0f;
    const float h = float(reach) + 0.05f + 2.0f * rng.uniform();
    Aabb panel;
    panel.min[a] = panel.max[a] = s.eye[a] + sign * h;
    panel.min[ua] = s.eye[ua] - (0.3f + 3.0f * rng.uniform()) * h;
    panel.max[ua] = s.eye[ua] + (0.3f + 3.0f * rng.uniform()) * h;
    panel.min[va] = s.eye[va] - (0.3f + 3.0f * rng.uniform()) * h;
    panel.max[va] = s.eye[va] + (0.3f + 3.0f * rng.uniform()) * h;
    panels = {panel};
    for (int k = 0; k < 60; ++k) {
        const float depth = h + 2.0f + 30.0f * rng.uniform();
        glm::vec3 c;
        c[a] = s.eye[a] + sign * depth;
        c[ua] = s.eye[ua] + depth * (2.0f * rng.uniform() - 1.0f);
        c[va] = s.eye[va] + depth * (2.0f * rng.uniform() - 1.0f);
        const glm::vec3 size(0.02f + 0.3f * rng.uniform(), 0.02f + 0.3f * rng.uniform(),
                             0.02f + 0.3f * rng.uniform());
        s.occludees.push_back(Aabb::of(c - 0.5f * size, c + 0.5f * size));
    }
    // And boxes seen through the panel at grazing angles, more than 45 degrees from its normal (on the cube's
    // side faces), where the tangents exceed 1 and the inset grows.
    for (int k = 0; k < 40; ++k) {
        const float depth = h + 0.5f + 10.0f * rng.uniform();
        glm::vec3 c;
        c[a] = s.eye[a] + sign * depth;
        const float reach = 1.0f + 3.0f * rng.uniform(), angle = 6.2831853f * rng.uniform();
        c[ua] = s.eye[ua] + depth * reach * std::cos(angle);
        c[va] = s.eye[va] + depth * reach * std::sin(angle);
        const glm::vec3 size(0.02f + 0.3f * rng.uniform(), 0.02f + 0.3f * rng.uniform(),
                             0.02f + 0.3f * rng.uniform());
        s.occludees.push_back(Aabb::of(c - 0.5f * size, c + 0.5f * size));
    }
    return s;
}

// Panels drawn for an eye box around the eye: a box proven hidden is hidden from every point of the eye box,
// each segment from it to the box crossing a panel. Half the scenes are random walls, half the tight case
// above; half the eye boxes are flat along one axis, as the patches of cell faces are. The eyes sampled are
// the box's 8 corners, where the inset per ray, b_u + b_n |u|, is reached (an eye moved sideways and towards
// the plane at once), and random points of its surface. (With an inset of b_u alone, this test fails.)
TEST(DepthCube, HiddenByPanelsForAnEyeBoxMeansEverySegmentFromTheBoxCrossesOne) {
    const int scenes = test::in_ci() ? 200 : 600;
    const int points_per_box = test::in_ci() ? 16 : 48;
    const int eyes_per_point = test::in_ci() ? 24 : 48;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(23, 4);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        glm::dvec3 spread;
        for (int a = 0; a < 3; ++a) spread[a] = 0.1 + 0.9 * double(rng.uniform());
        if (n % 4 >= 2) spread[int(rng.below(3))] = 0.0;
        std::vector<Aabb> panels;
        Scene s;
        if (n % 2 == 0) {
            s = random_scene(rng);
            panels = wall_faces(s.occluders);
        } else {
            s = tight_panel_scene(rng, std::max({spread.x, spread.y, spread.z}), panels);
        }
        DepthCube cube(resolutions[rng.below(4)]);
        cube.clear(s.eye);
        cube.add_panels(panels, spread);
        cube.add_panels_sides(panels, spread);
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, spread, points_per_box, eyes_per_point, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) {
                return std::any_of(panels.begin(), panels.end(),
                                   [&](const Aabb& p) { return segment_blocked(q, x, p); });
            },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " segments";
    EXPECT_GT(check.hidden, check.tested / 20) << check.hidden << " of " << check.tested << " hidden";
}

// clear_for() resets only the pixels of the boxes it is given, and the cube is reused from one scene to the
// next with stale depths everywhere else: its answers on those boxes equal a fresh cube's (clear() then
// limit_to()), and a box reaching past the region is never reported hidden from stale pixels.
TEST(DepthCube, ClearForAnswersAsAFreshCubeAndNeverReadsStalePixels) {
    Rng rng(23, 5);
    DepthCube reused(48), fresh(48);
    int hidden = 0, tested = 0, wide_hidden = 0;
    for (int n = 0; n < (test::in_ci() ? 80 : 300); ++n) {
        const Scene s = random_scene(rng);
        // Interest: half the occludees.
        const std::vector<Aabb> interest(s.occludees.begin(),
                                         s.occludees.begin() + std::ptrdiff_t(s.occludees.size() / 2));
        reused.clear_for(s.eye, interest);
        fresh.clear(s.eye);
        fresh.limit_to(interest);
        for (const Aabb& b : s.occluders) {
            reused.add_occluder(b);
            fresh.add_occluder(b);
        }
        for (const Aabb& b : interest) {
            const bool a = reused.is_hidden(b);
            ASSERT_EQ(a, fresh.is_hidden(b)) << "scene " << n;
            hidden += a;
            ++tested;
        }
        // A box around everything touches pixels outside the region on some face: never hidden from them.
        Aabb wide = Aabb::of(s.eye - glm::vec3(50.0f), s.eye + glm::vec3(50.0f));
        wide.min.x = s.eye.x + 1.0f;  // not holding the eye
        wide_hidden += reused.is_hidden(wide) && !fresh.is_hidden(wide);
        // Fill every pixel of the reused cube with a near shell, so the next scene inherits stale depths;
        // with nothing to test (an empty region) even a box wholly behind the shell is not hidden.
        reused.clear(s.eye);
        for (int a = 0; a < 3; ++a)
            for (const float sign : {-1.0f, 1.0f}) {
                Aabb slab = Aabb::of(s.eye - glm::vec3(100.0f), s.eye + glm::vec3(100.0f));
                slab.min[a] = s.eye[a] + (sign > 0 ? 0.5f : -0.6f);
                slab.max[a] = s.eye[a] + (sign > 0 ? 0.6f : -0.5f);
                reused.add_occluder(slab);
            }
        const Aabb behind =
            Aabb::of(s.eye + glm::vec3(2.0f, -0.1f, -0.1f), s.eye + glm::vec3(3.0f, 0.1f, 0.1f));
        ASSERT_TRUE(reused.is_hidden(behind));
        reused.clear_for(s.eye, {});
        wide_hidden += reused.is_hidden(behind) + reused.is_hidden(wide);
    }
    EXPECT_EQ(wide_hidden, 0);
    EXPECT_GT(hidden, 0);
    EXPECT_GT(tested, hidden);
}

}  // namespace
}  // namespace pvs
