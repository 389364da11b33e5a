// SPDX-License-Identifier: MIT
// Corner pairs on the conservative depth cube (pvs/depth_cube.h, add_corner();
// docs/ALGORITHMS.md#corner-pairs): which panels pair (occluders/panels.h, panel_corners()), who hides whom
// at a concave corner, a convex one and a wall standing on a floor (hidden by the two panels together, by
// neither alone), the same scenes with a 2 cm slit at the junction (the object behind stays visible), the
// kernel against the plain reference (identical answers), and the guarantee: a box proven hidden for an eye
// box is hidden from every point of it, each segment crossing a panel.
#include "core/random.h"
#include "occluders/panels.h"
#include "pvs/depth_cube.h"
#include "tests/depth_cube_checks.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace pvs {
namespace {

using test::segment_blocked;

// A panel flat along `axis` at `plane`, spanning [lo, hi] on the other two axes (in axis order).
Aabb panel(int axis, float plane, glm::vec2 lo, glm::vec2 hi) {
    Aabb p;
    p.min[axis] = p.max[axis] = plane;
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    p.min[std::min(ua, va)] = lo.x;
    p.max[std::min(ua, va)] = hi.x;
    p.min[std::max(ua, va)] = lo.y;
    p.max[std::max(ua, va)] = hi.y;
    return p;
}

std::vector<std::array<Aabb, 2>> corner_boxes(const std::vector<Aabb>& panels) {
    std::vector<std::array<Aabb, 2>> out;
    for (const auto& [i, j] : panel_corners(panels)) out.push_back({panels[i], panels[j]});
    return out;
}

// Draws the panels (front and sides) and, when `corners`, their corner pairs; the kernel and the reference
// must agree on `box`, and the kernel's answer is returned.
bool hidden(const std::vector<Aabb>& panels, glm::vec3 eye, glm::dvec3 spread, const Aabb& box, bool corners,
            int r = 64) {
    DepthCube cube(r);
    cube.clear(eye);
    cube.add_panels(panels, spread);
    cube.add_panels_sides(panels, spread);
    const std::vector<std::array<Aabb, 2>> pairs =
        corners ? corner_boxes(panels) : std::vector<std::array<Aabb, 2>>{};
    for (const auto& pair : pairs) cube.add_corner(pair[0], pair[1], spread);
    const bool fast = cube.is_hidden(box);
    EXPECT_EQ(fast, is_hidden_reference({}, panels, spread, eye, box, r, true, {}, pairs));
    return fast;
}

Aabb box_at(glm::vec3 c, float h) {
    return Aabb::of(c - glm::vec3(h), c + glm::vec3(h));
}

TEST(PanelCorners, PairsPanelsMeetingAlongALineOnly) {
    // A wall (flat along x at x = 2, y in [0, 3]) on a floor (flat along y at y = 0, x in [-4, 2]): an L.
    const Aabb wall = panel(0, 2.0f, {0.0f, -2.0f}, {3.0f, 2.0f});    // (y, z)
    const Aabb floor = panel(1, 0.0f, {-4.0f, -2.0f}, {2.0f, 2.0f});  // (x, z)
    // The floor running on under the wall (a T), a floor 2 cm short of the wall, one beside it along z, a
    // parallel wall.
    const Aabb through = panel(1, 0.0f, {-4.0f, -2.0f}, {6.0f, 2.0f});
    const Aabb short_floor = panel(1, 0.0f, {-4.0f, -2.0f}, {1.98f, 2.0f});
    const Aabb beside = panel(1, 0.0f, {-4.0f, 2.0f}, {2.0f, 5.0f});
    const Aabb parallel = panel(0, 3.0f, {0.0f, -2.0f}, {3.0f, 2.0f});
    using Pairs = std::vector<std::array<uint32_t, 2>>;
    EXPECT_EQ(panel_corners({wall, floor}), (Pairs{{0, 1}}));
    EXPECT_EQ(panel_corners({through, wall}), (Pairs{{0, 1}}));
    EXPECT_EQ(panel_corners({wall, short_floor}), Pairs{});
    EXPECT_EQ(panel_corners({wall, beside}), Pairs{});  // they touch at a point of the line only
    EXPECT_EQ(panel_corners({wall, parallel, floor}), (Pairs{{0, 2}}));
}

// Two walls at a room's inner corner (x = 4 for z <= 4, z = 4 for x <= 4), seen from inside: a box beyond
// the corner is hidden by the two together. Each alone loses a strip along the corner to the inset of its
// end for the eye box, where the box's rays pass. With a 2 cm slit between the walls it is seen.
TEST(CornerPairs, AConcaveCornerHidesWhatNeitherWallHidesAlone) {
    const glm::vec3 eye(0.0f, 1.0f, 0.0f);
    const glm::dvec3 spread(0.25, 0.25, 0.0);
    const Aabb wall_x = panel(0, 4.0f, {-1.0f, -6.0f}, {4.0f, 4.0f});  // (y, z)
    const Aabb wall_z = panel(2, 4.0f, {-6.0f, -1.0f}, {4.0f, 4.0f});  // (x, y)
    const Aabb behind = box_at({6.0f, 1.0f, 6.0f}, 0.2f);
    EXPECT_FALSE(hidden({wall_x, wall_z}, eye, spread, behind, false));
    EXPECT_TRUE(hidden({wall_x, wall_z}, eye, spread, behind, true));
    // Beyond one wall only, each wall alone hides it.
    EXPECT_TRUE(hidden({wall_x, wall_z}, eye, spread, box_at({7.0f, 1.0f, 0.0f}, 0.2f), false));
    const Aabb slit_z = panel(2, 4.0f, {-6.0f, -1.0f}, {3.98f, 4.0f});
    EXPECT_FALSE(hidden({wall_x, slit_z}, eye, spread, behind, true));
    // Through the slit, a box right behind it is seen: a ray from the eye passes the gap.
    EXPECT_FALSE(hidden({wall_x, slit_z}, eye, spread, box_at({4.5f, 1.0f, 4.5f}, 0.05f), true));
}

// The outer corner of a block (x >= 4 and z >= 4 solid; its faces x = 4 for z >= 4 and z = 4 for x >= 4),
// seen from outside: what lies inside the block's corner region, beyond both faces, is hidden.
TEST(CornerPairs, AConvexCornerHidesWhatLiesBehindBothFaces) {
    const glm::vec3 eye(0.0f, 1.0f, 0.0f);
    const glm::dvec3 spread(0.25, 0.25, 0.0);
    const Aabb face_x = panel(0, 4.0f, {-1.0f, 4.0f}, {4.0f, 10.0f});  // (y, z)
    const Aabb face_z = panel(2, 4.0f, {4.0f, -1.0f}, {10.0f, 4.0f});  // (x, y)
    const Aabb inside = box_at({4.6f, 1.0f, 4.6f}, 0.1f);
    EXPECT_FALSE(hidden({face_x, face_z}, eye, spread, inside, false));
    EXPECT_TRUE(hidden({face_x, face_z}, eye, spread, inside, true));
    const Aabb slit_x = panel(0, 4.0f, {-1.0f, 4.02f}, {4.0f, 10.0f});
    EXPECT_FALSE(hidden({slit_x, face_z}, eye, spread, inside, true));
}

// A wall standing at a floor's edge over a drop (the floor x <= 3, the wall x = 3 from the floor up), seen
// from above the floor: what lies behind the wall below the floor's level is hidden by the two together; the
// rays to it pass at the junction, within each one's inset. With the wall lifted 2 cm it is seen through
// the slit. A floor running on under the wall (a T) hides it alone.
TEST(CornerPairs, AWallAtAFloorsEdgeHidesWhatIsBehindAndBelow) {
    const glm::vec3 eye(0.0f, 2.0f, 0.0f);
    const glm::dvec3 spread(0.25, 0.0, 0.25);
    const Aabb floor = panel(1, 0.0f, {-8.0f, -8.0f}, {3.0f, 8.0f});  // (x, z)
    const Aabb wall = panel(0, 3.0f, {0.0f, -8.0f}, {4.0f, 8.0f});    // (y, z)
    const Aabb behind_below = box_at({6.0f, -2.0f, 0.0f}, 0.3f);      // the line from the eye over the edge
    EXPECT_FALSE(hidden({floor, wall}, eye, spread, behind_below, false));
    EXPECT_TRUE(hidden({floor, wall}, eye, spread, behind_below, true));
    const Aabb lifted = panel(0, 3.0f, {0.02f, -8.0f}, {4.0f, 8.0f});
    EXPECT_FALSE(hidden({floor, lifted}, eye, spread, behind_below, true));
    const Aabb through = panel(1, 0.0f, {-8.0f, -8.0f}, {8.0f, 8.0f});
    EXPECT_TRUE(hidden({through, wall}, eye, spread, behind_below, true));
}

// Random junctions: two panels meeting as an L, a T or a cross, in random axes, sides and lengths, a few
// more panels about, an eye box off both planes or not, and small boxes about the junction.
struct CornerScene {
    glm::vec3 eye;
    glm::dvec3 spread;
    std::vector<Aabb> panels;
    std::vector<Aabb> occludees;
};

CornerScene random_corner_scene(Rng& rng) {
    CornerScene s;
    const float step = rng.uniform() < 0.5f ? 0.25f : 0.0f;
    const auto snap = [step](float x) { return step > 0.0f ? std::round(x / step) * step : x; };
    const auto between = [&](float lo, float hi) { return lo + (hi - lo) * rng.uniform(); };
    s.eye = glm::vec3(snap(between(-1, 1)), snap(between(-1, 1)), snap(between(-1, 1)));
    s.spread = test::random_eye_box(rng, 0.05, 0.6);
    const int junctions = 1 + int(rng.below(3));
    for (int n = 0; n < junctions; ++n) {
        const int na = int(rng.below(3)), nb = (na + 1 + int(rng.below(2))) % 3, k = 3 - na - nb;
        const float ca = snap(s.eye[na] + (rng.uniform() < 0.5f ? -1.0f : 1.0f) * between(0.3f, 5.0f));
        const float cb = snap(s.eye[nb] + (rng.uniform() < 0.5f ? -1.0f : 1.0f) * between(0.3f, 5.0f));
        const float k0 = snap(s.eye[k] - between(-2.0f, 8.0f)), k1 = snap(s.eye[k] + between(-2.0f, 8.0f));
        if (!(k0 < k1)) continue;
        // Each panel reaches the other's plane from one side, or runs on through it.
        const auto extent = [&](float c, float& lo, float& hi) {
            const float len = snap(between(0.5f, 8.0f));
            const uint32_t kind = rng.below(3);
            lo = kind == 0 ? c : c - len;
            hi = kind == 1 ? c : c + (kind == 2 ? snap(between(0.5f, 8.0f)) : len);
        };
        Aabb a, b;
        a.min[na] = a.max[na] = ca;
        extent(cb, a.min[nb], a.max[nb]);
        a.min[k] = k0 - snap(between(0.0f, 2.0f));
        a.max[k] = k1;
        b.min[nb] = b.max[nb] = cb;
        extent(ca, b.min[na], b.max[na]);
        b.min[k] = k0;
        b.max[k] = k1 + snap(between(0.0f, 2.0f));
        s.panels.push_back(a);
        s.panels.push_back(b);
        for (int o = 0; o < 30; ++o) {
            glm::vec3 c;
            c[na] = ca + between(-3.0f, 3.0f);
            c[nb] = cb + between(-3.0f, 3.0f);
            c[k] = between(k0 - 1.0f, k1 + 1.0f);
            const glm::vec3 size(between(0.02f, 0.6f), between(0.02f, 0.6f), between(0.02f, 0.6f));
            s.occludees.push_back(Aabb::of(c - 0.5f * size, c + 0.5f * size));
        }
    }
    return s;
}

TEST(CornerPairs, MatchTheReferenceOnRandomJunctions) {
    const int scenes = test::in_ci() ? 60 : 300;
    const int resolutions[] = {16, 17, 24, 31, 32, 48, 64};
    Rng rng(29, 7);
    test::CubeCheck check;
    int pairs = 0, gained = 0;
    DepthCube cube(16), plain(16);
    for (int n = 0; n < scenes && check.failures <= 5; ++n) {
        const CornerScene s = random_corner_scene(rng);
        const int r = resolutions[rng.below(7)];
        if (cube.resolution() != r) cube = plain = DepthCube(r);
        const std::vector<std::array<Aabb, 2>> corners = corner_boxes(s.panels);
        pairs += int(corners.size());
        for (DepthCube* c : {&cube, &plain}) {
            c->clear(s.eye);
            c->add_panels(s.panels, s.spread);
            c->add_panels_sides(s.panels, s.spread);
        }
        for (const auto& pair : corners) cube.add_corner(pair[0], pair[1], s.spread);
        for (const Aabb& b : s.occludees) gained += cube.is_hidden(b) && !plain.is_hidden(b);
        test::expect_same_answers(
            cube, s.occludees,
            [&](const Aabb& b) {
                return is_hidden_reference({}, s.panels, s.spread, s.eye, b, r, true, {}, corners);
            },
            "scene " + std::to_string(n) + " resolution " + std::to_string(r), check);
    }
    EXPECT_EQ(check.failures, 0);
    EXPECT_GT(pairs, scenes / 2);
    EXPECT_GT(gained, check.tested / 400) << gained << " of " << check.tested << " hidden only by the pairs";
}

TEST(CornerPairs, HiddenMeansEverySegmentFromTheEyeBoxCrossesAPanel) {
    const int scenes = test::in_ci() ? 150 : 600;
    const int points_per_box = test::in_ci() ? 16 : 48;
    const int eyes_per_point = test::in_ci() ? 24 : 48;
    const int resolutions[] = {16, 32, 64, 128};
    Rng rng(31, 2);
    test::CubeCheck check;
    for (int n = 0; n < scenes; ++n) {
        const CornerScene s = random_corner_scene(rng);
        DepthCube cube(resolutions[rng.below(4)]);
        cube.clear(s.eye);
        cube.add_panels(s.panels, s.spread);
        cube.add_panels_sides(s.panels, s.spread);
        for (const auto& pair : corner_boxes(s.panels)) cube.add_corner(pair[0], pair[1], s.spread);
        test::expect_blocked_segments(
            cube, s.occludees, s.eye, s.spread, points_per_box, eyes_per_point, rng,
            [&](const glm::dvec3& q, const glm::dvec3& x) {
                return std::any_of(s.panels.begin(), s.panels.end(),
                                   [&](const Aabb& p) { return segment_blocked(q, x, p); });
            },
            "scene " + std::to_string(n), check);
    }
    EXPECT_EQ(check.failures, 0) << "of " << check.segments << " segments";
    EXPECT_GT(check.hidden, check.tested / 20) << check.hidden << " of " << check.tested << " hidden";
}

}  // namespace
}  // namespace pvs
