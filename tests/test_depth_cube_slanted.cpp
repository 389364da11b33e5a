// SPDX-License-Identifier: MIT
// Slanted panels on the conservative depth cube (pvs/depth_cube.h, add_slanted_panel()): who hides whom
// behind off-axis walls, fusion of off-axis walls, the kernel against the plain reference (identical
// answers), and the guarantee against the real triangles: a box proven hidden for an eye box is hidden from
// every point of it, each segment meeting an opaque triangle.
#include "core/random.h"
#include "occluders/slanted_panels.h"
#include "pvs/depth_cube.h"
#include "tests/depth_cube_checks.h"
#include "tests/slanted_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pvs {
namespace {

using test::bumpy_sheet;
using test::segment_meets_world;

// Appends the triangle (a, b, c), opaque, to the world.
void add_triangle(World& w, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const uint32_t base = uint32_t(w.positions.size());
    for (const glm::dvec3& p : {a, b, c}) w.positions.emplace_back(p);
    w.triangles.push_back(Triangle{{base, base + 1, base + 2}});
    w.triangle_opaque.push_back(1);
    w.triangle_double_sided.push_back(0);
}

// A wall of two triangles, 4 m wide and 3 m tall, standing on y = -1.5, centred at `centre` and turned by
// `degrees` about the vertical axis (0: facing x).
World turned_wall(glm::dvec3 centre, double degrees, double half_width = 2.0) {
    const double a = glm::radians(degrees);
    const glm::dvec3 along(-std::sin(a), 0.0, std::cos(a)), up(0.0, 1.0, 0.0);
    const glm::dvec3 p00 = centre - half_width * along - 1.5 * up,
                     p10 = centre + half_width * along - 1.5 * up;
    const glm::dvec3 p01 = centre - half_width * along + 1.5 * up,
                     p11 = centre + half_width * along + 1.5 * up;
    World w;
    add_triangle(w, p00, p10, p11);
    add_triangle(w, p00, p11, p01);
    return w;
}

std::vector<SlantedPanel> panels_of(const World& w) {
    return find_slanted_panels(w, 1e-4, 0.0);
}

// A small box (half-size h) centred on the point.
Aabb box_at(glm::dvec3 c, double h = 0.1) {
    return Aabb::of(glm::vec3(c - glm::dvec3(h)), glm::vec3(c + glm::dvec3(h)));
}

// Kernel and reference agree on a hand-built case.
bool hidden_both(const std::vector<SlantedPanel>& panels, glm::dvec3 spread, const Aabb& b, int r = 64) {
    DepthCube cube(r);
    cube.clear(glm::vec3(0.0f));
    cube.add_slanted_panels(panels, spread);
    const bool fast = cube.is_hidden(b);
    EXPECT_EQ(fast, is_hidden_reference({}, {}, spread, glm::vec3(0.0f), b, r, false, panels));
    return fast;
}

// A wall of two triangles at 37 degrees, 5 m along +x: it hides a box behind its middle from the eye and
// from an eye box around it, not a box seen past its edge nor one in front of it; seen from behind it hides
// the eye's side just as well. An eye box reaching its plane draws nothing.
TEST(SlantedPanelsOnTheCube, AWallOfTwoTrianglesAt37DegreesHidesWhatIsBehindItOnly) {
    const World wall = turned_wall({5.0, 0.0, 0.0}, 37.0);
    const std::vector<SlantedPanel> panels = panels_of(wall);
    ASSERT_EQ(panels.size(), 1u);
    const glm::dvec3 point(0.0), patch(0.5, 0.5, 0.0), deep(0.5, 0.5, 0.5);
    const Aabb behind = box_at({9.0, 0.0, 0.0}, 0.3);
    EXPECT_TRUE(hidden_both(panels, point, behind));
    EXPECT_TRUE(hidden_both(panels, patch, behind));
    EXPECT_TRUE(hidden_both(panels, deep, behind));
    // Past the ends of the wall: seen from the eye, its ends lie at z / x = 1.597 / 3.796 and -1.597 / 6.204,
    // so at x = 9 at z = 3.79 and z = -2.32.
    EXPECT_FALSE(hidden_both(panels, point, box_at({9.0, 0.0, 4.0})));
    EXPECT_FALSE(hidden_both(panels, point, box_at({9.0, 0.0, -2.5})));
    EXPECT_FALSE(hidden_both(panels, point, box_at({9.0, 3.0, 0.0})));  // over it
    EXPECT_FALSE(hidden_both(panels, point, box_at({3.0, 0.0, 0.0})));  // in front of it
    // Just inside an end from the eye, not from an eye box 0.5 m wide (the inset per ray).
    EXPECT_TRUE(hidden_both(panels, point, box_at({9.0, 0.0, -2.15}, 0.05)));
    EXPECT_FALSE(hidden_both(panels, patch, box_at({9.0, 0.0, -2.15}, 0.05)));
    // Seen from behind the wall: the eye's side is hidden (the cube is around the origin, so move the wall).
    const std::vector<SlantedPanel> before = panels_of(turned_wall({-4.0, 0.0, 0.0}, 180.0 + 37.0));
    ASSERT_EQ(before.size(), 1u);
    EXPECT_TRUE(hidden_both(before, patch, box_at({-8.0, 0.0, 0.0}, 0.3)));
    // An eye box reaching the wall's plane: nothing is drawn, nothing hidden.
    EXPECT_FALSE(hidden_both(panels, glm::dvec3(5.0, 0.5, 5.0), behind));
}

// Two off-axis walls, one nearer, overlapping in view (z / x from -0.05 to 0.18): a box straddling them is
// hidden by both together (on the depth buffer), by neither alone.
TEST(SlantedPanelsOnTheCube, OffAxisWallsFuse) {
    World near_wall = turned_wall({5.0, 0.0, -1.0}, 30.0), far_wall = turned_wall({7.0, 0.0, 1.5}, -25.0);
    const std::vector<SlantedPanel> a = panels_of(near_wall), b = panels_of(far_wall);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    const std::vector<SlantedPanel> both{a[0], b[0]};
    const Aabb straddling = Aabb::of({12.0f, -0.5f, -1.2f}, {12.5f, 0.5f, 2.6f});
    const glm::dvec3 patch(0.2, 0.2, 0.0);
    EXPECT_TRUE(hidden_both(both, patch, straddling));
    EXPECT_FALSE(hidden_both(a, patch, straddling));
    EXPECT_FALSE(hidden_both(b, patch, straddling));
}

// A random scene of slanted panels: 1 to 3 bumpy sheets in random planes, each of 1 to 4 metre squares,
// moved to random places around an eye, facing it more or less; and small boxes behind them (towards the
// eye's view of a random point of a sheet, many near its edges) and anywhere.
struct SlantedScene {
    glm::vec3 eye{0.0f};
    World triangles;
    std::vector<SlantedPanel> panels;
    std::vector<Aabb> occludees;
};

SlantedScene random_slanted_scene(Rng& rng, double bump) {
    SlantedScene s;
    s.eye = glm::vec3(20.0f * rng.uniform(), 20.0f * rng.uniform(), 20.0f * rng.uniform());
    const int sheets = 1 + int(rng.below(3));
    std::vector<glm::dvec3> points;  // a point of each sheet
    for (int k = 0; k < sheets; ++k) {
        glm::dvec3 normal;
        World sheet = bumpy_sheet(rng, 1 + int(rng.below(4)), bump, normal);
        // Put the sheet's middle 0.6 to 6 m from the eye, in a direction at most about 50 degrees from its
        // normal (either side).
        glm::dvec3 middle(0.0);
        for (const glm::vec3& p : sheet.positions) middle += glm::dvec3(p);
        middle /= double(sheet.positions.size());
        const double side = rng.uniform() < 0.5f ? -1.0 : 1.0;
        const glm::dvec3 dir = glm::normalize(
            side * normal + 0.8 * glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
        const glm::dvec3 shift = glm::dvec3(s.eye) + (0.6 + 5.4 * double(rng.uniform())) * dir - middle;
        for (glm::vec3& p : sheet.positions) p = glm::vec3(glm::dvec3(p) + shift);
        const Triangle& t = sheet.triangles[size_t(rng.below(uint32_t(sheet.triangles.size())))];
        points.push_back((glm::dvec3(sheet.positions[t.v[0]]) + glm::dvec3(sheet.positions[t.v[1]]) +
                          glm::dvec3(sheet.positions[t.v[2]])) /
                         3.0);
        const uint32_t base = uint32_t(s.triangles.positions.size());
        for (const glm::vec3& p : sheet.positions) s.triangles.positions.push_back(p);
        for (Triangle t : sheet.triangles) {
            for (uint32_t& v : t.v) v += base;
            s.triangles.triangles.push_back(t);
            s.triangles.triangle_opaque.push_back(1);
            s.triangles.triangle_double_sided.push_back(0);
        }
        for (const SlantedPanel& p : find_slanted_panels(sheet, 0.25, 0.0)) s.panels.push_back(p);
    }
    for (int k = 0; k < 50; ++k) {
        const glm::dvec3 eye(s.eye);
        glm::dvec3 c;
        if (k % 3 != 2) {  // behind a sheet, near where the eye sees the middle of one of its triangles
            const glm::dvec3 p =
                points[size_t(rng.below(uint32_t(points.size())))] +
                0.6 * glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
            c = eye + (1.2 + 3.0 * double(rng.uniform())) * (p - eye);
        } else {
            c = eye + 16.0 * glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
        }
        const glm::dvec3 h(0.02 + 0.4 * rng.uniform(), 0.02 + 0.4 * rng.uniform(),
                           0.02 + 0.4 * rng.uniform());
        s.occludees.push_back(Aabb::of(glm::vec3(c - h), glm::vec3(c + h)));
    }
    return s;
}

// The half-extents of an eye box: a point in a quarter of the draws, else 0.02 to 0.5 m per axis, flat along
// one axis (a patch of a cell face) in half of those.
glm::dvec3 random_eye_box(Rng& rng) {
    return rng.below(4) == 0 ? glm::dvec3(0.0) : test::random_eye_box(rng, 0.02, 0.5);
}

TEST(SlantedPanelsOnTheCube, MatchTheReferenceOnRandomScenes) {
    const int scenes = test::in_ci() ? 60 : 300;
    const int resolutions[] = {16, 17, 24, 31, 32, 48, 64};
    Rng rng(41, 7);
    test::CubeCheck check;
    DepthCube cube(16);
    for (int n = 0; n < scenes && check.failures <= 5; ++n) {
        const double bumps[3] = {0.0, 0.004, 0.1};
        const SlantedScene s = random_slanted_scene(rng, bumps[n % 3]);
        const int r = resolutions[rng.below(7)];
        const glm::dvec3 spread = random_eye_box(rng);
        if (cube.resolution() != r) cube = DepthCube(r);
        cube.clear(s.eye);
        // Half the scenes draw every panel, half nearest first, skipping those already hidden: the same
        // depths.
        if (n % 2 == 0) {
            for (const SlantedPanel& p : s.panels) cube.add_slanted_panel(p, spread);
        } else {
            cube.add_slanted_panels(s.panels, spread);
        }
        test::expect_same_answers(
            cube, s.occludees,
            [&](const Aabb& b) { return is_hidden_reference({}, {}, spread, s.eye, b, r, false, s.panels); },
            "scene " + std::to_string(n) + " resolution " + std::to_string(r), check);
    }
    EXPECT_EQ(check.failures, 0);
    EXPECT_GT(check.hidden, check.tested / 20) << check.hidden << " of " << check.tested << " hidden";
}

// Whenever the cube proves a box hidden for an eye box, every segment from a point of the eye box to a point
// of the box meets one of the sheets' triangles. The eyes are the eye box's corners (where the inset per ray
// is reached) and random points of its surface; the sheets are flat, bumped by rounding-sized amounts, or by
// 10 cm (there a test of one plane instead of both slab faces lets segments through).
TEST(SlantedPanelsOnTheCube, HiddenForAnEyeBoxMeansEverySegmentMeetsATriangle) {
    const int scenes = test::in_ci() ? 150 : 600;
    const int points_per_box = test::in_ci() ? 12 : 40;
    const int eyes_per_point = test::in_ci() ? 16 : 40;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(43, 9);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        const double bumps[3] = {0.0, 0.004, 0.1};
        const SlantedScene s = random_slanted_scene(rng, bumps[n % 3]);
        const glm::dvec3 spread = random_eye_box(rng);
        DepthCube cube(resolutions[rng.below(4)]);
        cube.clear(s.eye);
        cube.add_slanted_panels(s.panels, spread);
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, spread, points_per_box, eyes_per_point, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) { return segment_meets_world(s.triangles, q, x); },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " segments";
    EXPECT_GT(check.hidden, check.tested / 20) << check.hidden << " of " << check.tested << " hidden";
}

}  // namespace
}  // namespace pvs
