// SPDX-License-Identifier: MIT
// Depth bands on the conservative depth cube (pvs/depth_cube.h, set_panel_bands();
// docs/ALGORITHMS.md#depth-bands): a pixel a panel's inset leaves out still hides what lies near the panel's
// plane. Who hides whom beside a floor's edge (a box just below it hidden only through its band, a box far
// below it still visible), the kernel against the plain reference (identical answers), and the guarantee:
// a box proven hidden for an eye box is hidden from every point of it, each segment crossing a panel.
#include "core/random.h"
#include "pvs/depth_cube.h"
#include "tests/depth_cube_checks.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace pvs {
namespace {

using test::segment_blocked;

// Panels around an eye, some near it (where the inset spans several pixels), and small boxes just behind
// them, near their edges, where only a band can hide them; and some far behind, where none can.
struct BandScene {
    glm::vec3 eye;
    std::vector<Aabb> panels;
    std::vector<Aabb> occludees;
};

BandScene band_scene(Rng& rng, double reach) {
    BandScene s;
    s.eye = glm::vec3(20.0f * rng.uniform(), 20.0f * rng.uniform(), 20.0f * rng.uniform());
    const int count = 1 + int(rng.below(4));
    for (int k = 0; k < count; ++k) {
        const int a = int(rng.below(3)), ua = (a + 1) % 3, va = (a + 2) % 3;
        const float sign = rng.uniform() < 0.5f ? -1.0f : 1.0f;
        const float h = float(reach) + 0.05f + 4.0f * rng.uniform() * rng.uniform();
        Aabb p;
        p.min[a] = p.max[a] = s.eye[a] + sign * h;
        p.min[ua] = s.eye[ua] - (0.2f + 4.0f * rng.uniform()) * h;
        p.max[ua] = s.eye[ua] + (0.2f + 4.0f * rng.uniform()) * h;
        p.min[va] = s.eye[va] - (0.2f + 4.0f * rng.uniform()) * h;
        p.max[va] = s.eye[va] + (0.2f + 4.0f * rng.uniform()) * h;
        s.panels.push_back(p);
        for (int n = 0; n < 30; ++n) {
            // Beyond the plane by a little (a band's depth) or by much, near an edge or not.
            const float beyond = n % 5 == 4 ? 2.0f + 20.0f * rng.uniform() : 0.01f + h * rng.uniform();
            glm::vec3 c;
            c[a] = p.min[a] + sign * beyond;
            const int edge_axis = rng.uniform() < 0.5f ? ua : va, other = edge_axis == ua ? va : ua;
            const float edge = rng.uniform() < 0.5f ? p.min[edge_axis] : p.max[edge_axis];
            c[edge_axis] = edge + (rng.uniform() - 0.7f) * 0.6f * (edge == p.min[edge_axis] ? -1.0f : 1.0f);
            c[other] = p.min[other] + (p.max[other] - p.min[other]) * rng.uniform();
            const glm::vec3 size(0.02f + 0.2f * rng.uniform(), 0.02f + 0.2f * rng.uniform(),
                                 0.02f + 0.2f * rng.uniform());
            s.occludees.push_back(Aabb::of(c - 0.5f * size, c + 0.5f * size));
        }
    }
    return s;
}

glm::dvec3 eye_box_for(Rng& rng, int n) {
    glm::dvec3 spread;
    for (int a = 0; a < 3; ++a) spread[a] = 0.05 + 0.5 * double(rng.uniform());
    if (n % 4 >= 2) spread[int(rng.below(3))] = 0.0;  // a patch of a cell face
    return spread;
}

// A floor 1 m below the eye reaching to x = 3, for an eye box of 0.25 m along x and z (flat in y). A small
// box 5 cm below the floor, whose rays from the eye cross the floor 12 to 22 cm inside its edge (inside the
// inset of 25 cm; on the cube's +x face, a side face of the floor), is hidden only through the band; a box
// 20 m below, in about the same directions, stays visible (segments to it pass beside the floor).
TEST(DepthBands, AFloorHidesWhatLiesJustBelowItNearItsEdge) {
    const Aabb floor = Aabb::of({-20.0f, -1.0f, -20.0f}, {3.0f, -1.0f, 20.0f});
    const glm::dvec3 spread(0.25, 0.0, 0.25);
    const glm::vec3 eye(0.0f);
    const Aabb just_below = Aabb::of({2.95f, -1.06f, -0.05f}, {3.02f, -1.05f, 0.05f});
    const Aabb far_below = Aabb::of({62.0f, -21.0f, -0.5f}, {63.0f, -20.0f, 0.5f});
    for (const bool bands : {false, true}) {
        DepthCube cube(64);
        cube.set_panel_bands(bands);
        cube.clear(eye);
        cube.add_panel(floor, spread);
        cube.add_panel_sides(floor, spread);
        EXPECT_EQ(cube.is_hidden(just_below), bands) << "bands " << bands;
        EXPECT_FALSE(cube.is_hidden(far_below)) << "bands " << bands;
        EXPECT_EQ(is_hidden_reference({}, {floor}, spread, eye, just_below, 64, true, {}, {}, bands), bands);
    }
    // And every segment from the eye box to the box just below crosses the floor.
    Rng rng(5, 9);
    for (int k = 0; k < 200; ++k) {
        const glm::dvec3 x = test::box_target(just_below, k, rng);
        const glm::dvec3 q = test::eye_box_point(eye, spread, k, rng);
        ASSERT_TRUE(segment_blocked(q, x, floor)) << k;
    }
}

// The kernel (runs per panel, bands on the pixels it leaves out) and the reference (every pixel, every
// panel) give the same answers, with and without the side faces; and the bands prove more.
TEST(DepthBands, MatchTheReferenceOnRandomScenes) {
    const int scenes = test::in_ci() ? 80 : 300;
    const int resolutions[] = {16, 17, 24, 31, 32, 48, 64};
    Rng rng(41, 7);
    test::CubeCheck check;
    int more = 0;
    DepthCube cube(16), plain(16);
    for (int n = 0; n < scenes && check.failures <= 5; ++n) {
        const glm::dvec3 spread = eye_box_for(rng, n);
        const BandScene s = band_scene(rng, std::max({spread.x, spread.y, spread.z}));
        const int r = resolutions[rng.below(7)];
        if (cube.resolution() != r) {
            cube = DepthCube(r);
            plain = DepthCube(r);
        }
        cube.set_panel_bands(true);
        const bool with_sides = n % 2 == 1;
        for (DepthCube* c : {&cube, &plain}) {
            c->clear(s.eye);
            c->add_panels(s.panels, spread);
            if (with_sides) c->add_panels_sides(s.panels, spread);
        }
        test::expect_same_answers(
            cube, s.occludees,
            [&](const Aabb& b) {
                return is_hidden_reference({}, s.panels, spread, s.eye, b, r, with_sides, {}, {}, true);
            },
            "scene " + std::to_string(n) + " resolution " + std::to_string(r), check);
        for (const Aabb& b : s.occludees) {
            ASSERT_FALSE(plain.is_hidden(b) && !cube.is_hidden(b)) << "scene " << n;
            more += cube.is_hidden(b) && !plain.is_hidden(b);
        }
    }
    EXPECT_EQ(check.failures, 0);
    EXPECT_GT(more, check.tested / 50) << more << " of " << check.tested << " hidden only through bands";
    EXPECT_LT(check.hidden, check.tested * 9 / 10);
}

// A box proven hidden through the bands is hidden from every point of the eye box: each segment from it to
// the box crosses a panel. The eyes sampled are the box's 8 corners (where the inset is reached) and random
// points of its surface. (With the share's height taken from the eye, |h|, instead of the box's nearest
// point, |h| - b_n, this test fails.)
TEST(DepthBands, HiddenMeansEverySegmentFromTheEyeBoxCrossesAPanel) {
    const int scenes = test::in_ci() ? 200 : 600;
    const int points_per_box = test::in_ci() ? 16 : 48;
    const int eyes_per_point = test::in_ci() ? 24 : 48;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(43, 2);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        const glm::dvec3 spread = eye_box_for(rng, n);
        const BandScene s = band_scene(rng, std::max({spread.x, spread.y, spread.z}));
        DepthCube cube(resolutions[rng.below(4)]);
        cube.set_panel_bands(true);
        cube.clear(s.eye);
        cube.add_panels(s.panels, spread);
        cube.add_panels_sides(s.panels, spread);
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, spread, points_per_box, eyes_per_point, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) {
                return std::any_of(s.panels.begin(), s.panels.end(),
                                   [&](const Aabb& p) { return segment_blocked(q, x, p); });
            },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " segments";
    EXPECT_GT(check.hidden, check.tested / 10) << check.hidden << " of " << check.tested << " hidden";
}

// clear_for() resets the bands of its region too: a cube reused with stale bands answers as a fresh one.
TEST(DepthBands, ClearForResetsTheBands) {
    Rng rng(47, 1);
    DepthCube reused(32), fresh(32);
    reused.set_panel_bands(true);
    fresh.set_panel_bands(true);
    for (int n = 0; n < 60; ++n) {
        const glm::dvec3 spread = eye_box_for(rng, n);
        const BandScene s = band_scene(rng, std::max({spread.x, spread.y, spread.z}));
        reused.clear_for(s.eye, s.occludees);
        fresh.clear(s.eye);
        fresh.limit_to(s.occludees);
        for (DepthCube* c : {&reused, &fresh}) {
            c->add_panels(s.panels, spread);
            c->add_panels_sides(s.panels, spread);
        }
        for (const Aabb& b : s.occludees) ASSERT_EQ(reused.is_hidden(b), fresh.is_hidden(b)) << "scene " << n;
    }
}

}  // namespace
}  // namespace pvs
