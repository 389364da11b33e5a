// SPDX-License-Identifier: MIT
// Ranked occluders per cell (occluders/ranking.h, occluders/cell_ranking.h): the exact solid angle of a box
// against closed forms; the shadow frustum test against a scene (behind a wall: hidden; peeking past its
// edge: not) and against the simple segment test on random inputs; the hierarchy's counts against brute
// force; the ranking in a small world (a big near wall outranks a small far box); the stage's output the
// same for any thread count.
#include "core/context.h"
#include "core/pvs_set.h"
#include "driver/verify_boxes.h"
#include "occluders/cell_ranking.h"
#include "occluders/ranking.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace pvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

Context quiet_context() {
    Context::Options o;
    o.quiet = true;
    o.sink = nullptr;
    return Context(o);
}

// ---------------------------------------------------------------------------------------------------------
// Solid angle.

// A square face of half-edge a seen from distance d on its axis: 4 asin(a^2 / (a^2 + d^2)).
TEST(SolidAngle, SquareFaceFromItsAxis) {
    for (double a : {0.5, 1.0, 3.0}) {
        for (double d : {0.01, 0.5, 1.0, 7.0, 100.0}) {
            const Aabb box = Aabb::of({float(-a), float(-a), 0.0f}, {float(a), float(a), 2.0f});
            const double want = 4.0 * std::asin(a * a / (a * a + d * d));
            EXPECT_NEAR(box_solid_angle_sr(box, {0.0f, 0.0f, float(-d)}), want, 1e-6 * want + 1e-12)
                << a << " " << d;
        }
    }
}

// A rectangle a x b seen from distance d above one corner: atan(ab / (d sqrt(a^2 + b^2 + d^2))). The eye lies
// in the planes of two side faces, which it therefore does not see.
TEST(SolidAngle, RectangleFromAboveACorner) {
    for (double a : {1.0, 2.5}) {
        for (double b : {0.5, 4.0}) {
            for (double d : {0.25, 1.0, 10.0}) {
                const Aabb box = Aabb::of({0, 0, 0}, {float(a), float(b), 1.0f});
                const double want = std::atan(a * b / (d * std::sqrt(a * a + b * b + d * d)));
                EXPECT_NEAR(box_solid_angle_sr(box, {0.0f, 0.0f, float(-d)}), want, 1e-6 * want);
            }
        }
    }
}

TEST(SolidAngle, CubeFromInsideJustOutsideAndFarAway) {
    const Aabb cube = Aabb::of({-1, -1, -1}, {1, 1, 1});
    EXPECT_DOUBLE_EQ(box_solid_angle_sr(cube, {0, 0, 0}), 4.0 * kPi);  // from its centre: everything
    EXPECT_DOUBLE_EQ(box_solid_angle_sr(cube, {1, 1, 1}), 4.0 * kPi);  // closed: a corner is inside
    // Just outside a face's centre: almost a hemisphere.
    const double near = box_solid_angle_sr(cube, {0, 0, 1.0001f});
    EXPECT_LT(near, 2.0 * kPi);
    EXPECT_NEAR(near, 2.0 * kPi, 1e-3);
    // Far away along an axis: the face's area over the distance squared.
    EXPECT_NEAR(box_solid_angle_sr(cube, {0, 0, 1000}), 4.0 / (999.0 * 999.0), 1e-9);
    // Along the diagonal the three faces it shows are alike, and the cube covers what the three faces
    // behind cover (a closed surface): the faces it does not see, summed, give the same.
    const glm::vec3 eye(3, 3, 3);
    const double front = box_solid_angle_sr(cube, eye);
    const glm::dvec3 p(eye);
    auto face = [&](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d) {
        return triangle_solid_angle_sr(a - p, b - p, c - p) + triangle_solid_angle_sr(a - p, c - p, d - p);
    };
    const double back = face({-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}) +
                        face({-1, -1, -1}, {-1, 1, -1}, {-1, 1, 1}, {-1, -1, 1}) +
                        face({-1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, -1});
    EXPECT_NEAR(front, back, 1e-9);
    EXPECT_NEAR(front, 3.0 * face({-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}), 1e-9);
}

// A box seen from outside never covers more than a hemisphere (a plane separates them), and it agrees
// with its closed-surface twin (the faces it does not see) for random boxes and eyes.
TEST(SolidAngle, RandomBoxesFrontEqualsBack) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-5.0f, 5.0f), s(0.05f, 4.0f);
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 lo(u(rng), u(rng), u(rng));
        const Aabb box = Aabb::of(lo, lo + glm::vec3(s(rng), s(rng), s(rng)));
        const glm::vec3 eye(u(rng), u(rng), u(rng));
        if (box.contains(eye)) continue;
        const double w = box_solid_angle_sr(box, eye);
        ASSERT_GE(w, 0.0);
        ASSERT_LE(w, 2.0 * kPi + 1e-9);
        // The whole surface, every face, sums to twice the front (each direction through the box crosses
        // it twice).
        double all = 0.0;
        const glm::dvec3 p(eye);
        for (int axis = 0; axis < 3; ++axis) {
            for (int side = 0; side < 2; ++side) {
                const int u1 = (axis + 1) % 3, v1 = (axis + 2) % 3;
                glm::dvec3 q[4];
                for (int k = 0; k < 4; ++k) {
                    q[k][axis] = side ? box.max[axis] : box.min[axis];
                    q[k][u1] = (k == 1 || k == 2) ? box.max[u1] : box.min[u1];
                    q[k][v1] = k >= 2 ? box.max[v1] : box.min[v1];
                    q[k] -= p;
                }
                all += triangle_solid_angle_sr(q[0], q[1], q[2]) + triangle_solid_angle_sr(q[0], q[2], q[3]);
            }
        }
        ASSERT_NEAR(all, 2.0 * w, 1e-7 * (1.0 + w)) << i;
    }
}

// ---------------------------------------------------------------------------------------------------------
// Shadow frusta.

// A wall 10 m wide, 3 m high, 5 m in front of the eye: its shadow 8 m from the eye spans x in [-3, 13].
TEST(Shadow, BehindAWallIsHiddenPeekingPastItsEdgeIsNot) {
    const Aabb wall = Aabb::of({0, 0, 5}, {10, 3, 5.5f});
    const glm::vec3 eye(5, 1.5f, 0);
    const ShadowFrustum f = shadow_frustum(wall, eye);
    ASSERT_TRUE(f.valid);
    EXPECT_TRUE(f.contains(Aabb::of({4, 1, 8}, {6, 2, 9})));          // straight behind
    EXPECT_TRUE(f.contains(Aabb::of({11, 1, 8}, {12.9f, 2, 9})));     // behind, near the edge
    EXPECT_FALSE(f.contains(Aabb::of({11, 1, 8}, {13.1f, 2, 9})));    // peeks past the edge
    EXPECT_FALSE(f.contains(Aabb::of({4, 1, 8}, {6, 5.0f, 9})));      // over the top
    EXPECT_FALSE(f.contains(Aabb::of({4, 1, 2}, {6, 2, 3})));         // in front of the wall
    EXPECT_FALSE(f.contains(Aabb::of({4, 1, 4}, {6, 2, 6})));         // straddles its front face
    EXPECT_TRUE(f.contains(Aabb::of({4, 1, 5.1f}, {6, 2, 5.4f})));    // inside the wall counts as hidden
    EXPECT_FALSE(f.contains(Aabb::of({-31, -1, 30}, {-30, 0, 31})));  // far to the side
    EXPECT_FALSE(f.contains(Aabb::empty()));
    EXPECT_TRUE(f.contains(glm::vec3(5, 1.5f, 100)));
    EXPECT_FALSE(f.contains(eye));
    // From inside the wall: no shadow at all.
    EXPECT_FALSE(shadow_frustum(wall, {5, 1, 5.25f}).valid);
    EXPECT_FALSE(shadow_frustum(wall, {5, 1, 5.25f}).contains(Aabb::of({4, 1, 8}, {6, 2, 9})));
}

// The plane test agrees with the simple reference (the segment eye-q meets the box) on random boxes, eyes
// and points, up to rounding: checked against the box grown and shrunk by a hair, so a point the test puts
// inside is inside the grown box's reference shadow and a point it puts outside is outside the shrunk one's.
// An AABB is inside exactly when its 8 corners are (the shadow is convex).
TEST(Shadow, AgreesWithTheSegmentReference) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-6.0f, 6.0f), s(0.1f, 3.0f), w(0.0f, 1.5f);
    int inside = 0, outside = 0, boxes_inside = 0;
    for (int i = 0; i < 3000; ++i) {
        const glm::vec3 lo(u(rng), u(rng), u(rng));
        const Aabb box = Aabb::of(lo, lo + glm::vec3(s(rng), s(rng), s(rng)));
        const glm::vec3 eye = i % 5 == 0 ? glm::vec3(lo.x - 1.0f, u(rng), lo.z + 0.5f)  // face-on views too
                                         : glm::vec3(u(rng), u(rng), u(rng));
        if (box.contains(eye)) continue;
        const ShadowFrustum f = shadow_frustum(box, eye);
        ASSERT_TRUE(f.valid);
        const float hair = 1e-3f;
        const Aabb grown = Aabb::of(box.min - hair, box.max + hair);
        const Aabb shrunk = Aabb::of(box.min + hair, box.max - hair);
        for (int k = 0; k < 20; ++k) {
            const glm::vec3 q = box.center() + (box.center() - eye) * w(rng) * 3.0f +
                                glm::vec3(u(rng), u(rng), u(rng)) * 0.5f;
            const bool in = f.contains(q);
            if (in) {
                ASSERT_TRUE(segment_meets_box(eye, q, grown)) << i << " " << k;
                ++inside;
            } else {
                ASSERT_FALSE(segment_meets_box(eye, q, shrunk)) << i << " " << k;
                ++outside;
            }
            const glm::vec3 half(w(rng) * 0.5f, w(rng) * 0.5f, w(rng) * 0.5f);
            const Aabb o = Aabb::of(q - half, q + half);
            bool corners_grown = true, corners_shrunk = true;
            for (int c = 0; c < 8; ++c) {
                const glm::vec3 p(c & 1 ? o.max.x : o.min.x, c & 2 ? o.max.y : o.min.y,
                                  c & 4 ? o.max.z : o.min.z);
                corners_grown = corners_grown && segment_meets_box(eye, p, grown);
                corners_shrunk = corners_shrunk && segment_meets_box(eye, p, shrunk);
            }
            if (f.contains(o)) {
                ASSERT_TRUE(corners_grown) << i << " " << k;
                ++boxes_inside;
            } else {
                ASSERT_FALSE(corners_shrunk) << i << " " << k;
            }
        }
    }
    EXPECT_GT(inside, 5000);  // both sides are exercised
    EXPECT_GT(outside, 5000);
    EXPECT_GT(boxes_inside, 1000);
}

// The hierarchy counts what brute force counts.
TEST(Shadow, OccludeesCountLikeBruteForce) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-30.0f, 30.0f), s(0.1f, 4.0f);
    std::vector<Aabb> bounds;
    std::vector<uint32_t> triangles;
    for (int i = 0; i < 700; ++i) {
        const glm::vec3 lo(u(rng), u(rng) * 0.2f, u(rng));
        bounds.push_back(Aabb::of(lo, lo + glm::vec3(s(rng), s(rng), s(rng))));
        triangles.push_back(i % 13 == 0 ? 0 : 1 + uint32_t(rng() % 50));  // some without triangles
    }
    bounds[7] = Aabb::empty();
    const Occludees occludees(bounds, triangles);
    EXPECT_EQ(occludees.object_count(), 700u);
    uint64_t some = 0;
    for (int i = 0; i < 300; ++i) {
        const glm::vec3 lo(u(rng) * 0.3f, u(rng) * 0.05f, u(rng) * 0.3f);
        const Aabb box = Aabb::of(lo, lo + glm::vec3(s(rng) * 2.0f, s(rng), s(rng) * 2.0f));
        const glm::vec3 eye(u(rng) * 0.3f, u(rng) * 0.05f, u(rng) * 0.3f);
        const ShadowFrustum f = shadow_frustum(box, eye);
        uint32_t want_objects = 0;
        uint64_t want_triangles = 0;
        for (size_t o = 0; o < bounds.size(); ++o) {
            if (triangles[o] > 0 && f.contains(bounds[o])) {
                ++want_objects;
                want_triangles += triangles[o];
            }
        }
        uint32_t objects = 0;
        uint64_t tris = 0;
        occludees.count_hidden(f, objects, tris);
        ASSERT_EQ(objects, want_objects) << i;
        ASSERT_EQ(tris, want_triangles) << i;
        uint32_t visited = 0;
        occludees.for_each_hidden(f, [&](uint32_t o) {
            ++visited;
            EXPECT_TRUE(f.contains(bounds[o]));
        });
        ASSERT_EQ(visited, want_objects);
        some += objects;
    }
    EXPECT_GT(some, 100u);
}

// ---------------------------------------------------------------------------------------------------------
// Ranking.

// One 2 m cell at the origin looking down +z: a big wall 3 m away and a small box 18 m away, with
// things to hide behind both.
struct Scene {
    World world;
    std::vector<Occluder> occluders;
    CellSet cells = test::single_cell({0, 0, 0}, 2.0f);
};

Scene wall_and_small_box() {
    Scene s;
    const Aabb wall = Aabb::of({-6, -1, 3}, {8, 5, 3.5f});
    const Aabb small = Aabb::of({0.6f, 0.6f, 18}, {1.4f, 1.4f, 18.8f});
    test::add_box(s.world, "wall", wall);
    test::add_box(s.world, "small", small);
    for (int i = 0; i < 6; ++i) {  // crates behind the wall
        const float x = -2.0f + 1.0f * float(i);
        test::add_box(s.world, "crate" + std::to_string(i), Aabb::of({x, 0.5f, 8}, {x + 0.5f, 1.0f, 8.5f}));
    }
    test::add_box(s.world, "pebble", Aabb::of({0.95f, 0.95f, 30}, {1.05f, 1.05f, 30.1f}));  // behind both
    test::add_box(s.world, "aside", Aabb::of({30, 0, 0}, {31, 1, 1}));                      // behind none
    // The occluders lie inside the objects' solid, as synthesis finds them (a box equal to its object's
    // bounds would put the object in its own shadow: the shadow includes the box).
    s.occluders.push_back(Occluder{Aabb::of(small.min + 0.05f, small.max - 0.05f), 0.25f, true, {1}});
    s.occluders.push_back(Occluder{Aabb::of(wall.min + 0.1f, wall.max - 0.1f), 0.25f, true, {0}});
    s.occluders.push_back(Occluder{Aabb::of({-6, -1, -3.5f}, {8, 5, -3}), 0.25f, false, {}});  // not proven
    return s;
}

TEST(Ranking, BigNearWallOutranksSmallFarBox) {
    Scene s = wall_and_small_box();
    Context ctx = quiet_context();
    RankingConfig config;
    config.min_solid_angle_sr = 0.0005;  // let the small box in
    RankingFigures figures;
    const RankedOccluders r = rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures);
    ASSERT_EQ(r.offsets.size(), 2u);
    ASSERT_EQ(r.count(0), 2u);  // the unproven box is never ranked
    const RankedOccluder& first = r.entries[0];
    const RankedOccluder& second = r.entries[1];
    EXPECT_EQ(first.box, 1u);  // the wall
    EXPECT_EQ(second.box, 0u);
    EXPECT_GT(first.score, second.score);
    EXPECT_GT(first.solid_angle_sr, 1.0f);
    EXPECT_LT(second.solid_angle_sr, 0.01f);
    // Behind the wall from every eye: the 6 crates, the pebble and the small box (object 1); never the wall
    // itself (its front is in front of its own shadow).
    EXPECT_FLOAT_EQ(first.hidden_objects, 8.0f);
    EXPECT_NEAR(first.hidden_triangle_share, 8.0 / 10.0, 1e-6);
    EXPECT_GT(second.hidden_objects, 0.0f);  // the pebble, from some eyes
    EXPECT_LE(second.hidden_objects, 1.0f);
    EXPECT_EQ(figures.boxes_usable, 2u);
    // With the default threshold (0.01 sr) the small box is no candidate: its solid angle stays below.
    RankingFigures f2;
    const RankedOccluders r2 = rank_occluders(ctx, RankingConfig{}, s.world, s.cells, s.occluders, f2);
    ASSERT_EQ(r2.count(0), 1u);
    EXPECT_EQ(r2.entries[0].box, 1u);
    // Keep only the best one; 0 = off.
    config.occluders_per_cell = 1;
    EXPECT_EQ(rank_occluders(ctx, config, s.world, s.cells, s.occluders, f2).entries.size(), 1u);
    config.occluders_per_cell = 0;
    EXPECT_TRUE(rank_occluders(ctx, config, s.world, s.cells, s.occluders, f2).empty());
}

// Ranking by sight (occluders/sight_ranking.h): the cell's PVS is every object; the wall's front face as a
// panel stops first every sight line to what lies behind the wall (the wall's own box lies behind it), so it
// comes first, with the share of the lines it stops as its score; the unproven box never comes; a cell with
// an empty PVS keeps none.
TEST(RankingBySight, TheFaceThatStopsTheCellsSightFirstComesFirst) {
    Scene s = wall_and_small_box();
    s.occluders.push_back(Occluder{Aabb::of({-6, -1, 3}, {8, 5, 3}), 0.0f, true, {}});  // 3: the wall's face
    Context ctx = quiet_context();
    RankingConfig config;
    config.sight_lines = 4096;
    PvsSet pvs = PvsSet::make(1, uint32_t(s.world.objects.size()));
    for (uint32_t o = 0; o < s.world.objects.size(); ++o) pvs.set(0, o);
    RankingFigures figures;
    const RankedOccluders r =
        rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures, nullptr, &pvs);
    ASSERT_EQ(r.offsets.size(), 2u);
    ASSERT_GE(r.count(0), 1u);
    EXPECT_EQ(r.entries[0].box, 3u);
    // 8 of the 10 objects (the crates, the small box, the pebble), each of 12 triangles, lie behind the wall:
    // at least 0.8 of the lines, less those to the small box's and pebble's sides the wall does not cover.
    EXPECT_GT(r.entries[0].score, 0.7f);
    EXPECT_LE(r.entries[0].score, 1.0f);
    EXPECT_GT(r.entries[0].solid_angle_sr, 1.0f);
    for (uint32_t k = 0; k < r.count(0); ++k) {
        EXPECT_NE(r.entries[k].box, 2u) << "an unproven box";
        EXPECT_GT(r.entries[k].score, 0.0f);
        if (k > 0) EXPECT_LE(r.entries[k].score, r.entries[k - 1].score);
    }
    // With the PVS empty, no line: none kept. Without the PVS: by solid angle and depth complexity.
    PvsSet none = PvsSet::make(1, uint32_t(s.world.objects.size()));
    EXPECT_EQ(rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures, nullptr, &none).count(0),
              0u);
    const RankedOccluders by_frusta = rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures);
    ASSERT_GE(by_frusta.count(0), 1u);
    EXPECT_NE(by_frusta.entries[0].score, r.entries[0].score);
}

// A polygon occluder (a slanted sheet in front of the wall, nearer than any box) stops first what the wall's
// box would: by sight it comes first, named after the boxes (index = occluder count + its own), with its
// share of the lines and no box measures.
TEST(RankingBySight, APolygonNearerThanTheWallComesFirstAfterTheBoxesIndices) {
    Scene s = wall_and_small_box();
    OccluderPolygon p;
    p.normal = glm::normalize(glm::vec3(0.0f, -0.5f, 6.0f));
    p.corners = {
        {-6, -1, 2.0f}, {8, -1, 2.0f}, {8, 5, 2.5f}, {-6, 5, 2.5f}};  // counter-clockwise from +normal
    p.offset = glm::dot(p.normal, p.corners[0]);
    p.thickness = 0.001f;
    for (const glm::vec3& c : p.corners) p.bounds.extend(c);
    const std::vector<OccluderPolygon> polygons = {p};
    Context ctx = quiet_context();
    RankingConfig config;
    config.sight_lines = 4096;
    PvsSet pvs = PvsSet::make(1, uint32_t(s.world.objects.size()));
    for (uint32_t o = 0; o < s.world.objects.size(); ++o) pvs.set(0, o);
    RankingFigures figures;
    const RankedOccluders r =
        rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures, nullptr, &pvs, &polygons);
    ASSERT_GE(r.count(0), 1u);
    EXPECT_EQ(r.entries[0].box, uint32_t(s.occluders.size()));
    EXPECT_GT(r.entries[0].score, 0.7f);
    EXPECT_EQ(r.entries[0].solid_angle_sr, 0.0f);
    // Without it, the wall's box leads as before.
    const RankedOccluders boxes =
        rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures, nullptr, &pvs);
    ASSERT_GE(boxes.count(0), 1u);
    EXPECT_LT(boxes.entries[0].box, uint32_t(s.occluders.size()));
}

// Verification's check of the ranked boxes (driver/verify_boxes.h): boxes inside the wall are never seen
// into from the cell's eyes; a box across a 2 m crack in the wall (its two halves apart) is.
TEST(Ranking, VerificationFindsARankedBoxThatSpansACrack) {
    Scene s = wall_and_small_box();
    Context ctx = quiet_context();
    RankingConfig config;
    config.min_solid_angle_sr = 0.0005;
    RankingFigures figures;
    RankedOccluders r = rank_occluders(ctx, config, s.world, s.cells, s.occluders, figures);
    {
        RayScene scene(ctx, s.world);
        const RankedBoxCheck sound = check_ranked_boxes(ctx, scene, s.cells, s.occluders, r, 5);
        EXPECT_EQ(sound.boxes, 2u);
        EXPECT_EQ(sound.rays, 2u * 16u * 8u);  // 16 eyes of the one cell, 8 points in each box
        EXPECT_EQ(sound.seen_into, 0u) << sound.first;
    }
    // The same wall with a 2 m crack through its middle, and the box still across it.
    Scene cracked = s;
    cracked.world = World{};
    test::add_box(cracked.world, "wall_left", Aabb::of({-6, -1, 3}, {0, 5, 3.5f}));
    test::add_box(cracked.world, "wall_right", Aabb::of({2, -1, 3}, {8, 5, 3.5f}));
    test::add_box(cracked.world, "small", Aabb::of({0.6f, 0.6f, 18}, {1.4f, 1.4f, 18.8f}));
    RayScene scene(ctx, cracked.world);
    const RankedBoxCheck bad = check_ranked_boxes(ctx, scene, cracked.cells, cracked.occluders, r, 5);
    EXPECT_EQ(bad.seen_into, 1u) << bad.first;
    EXPECT_NE(bad.first.find("ranked box 1"), std::string::npos) << bad.first;
    // An unproven box that a ranking names is reported too.
    r.entries[0].box = 2;
    const RankedBoxCheck unproven = check_ranked_boxes(ctx, scene, s.cells, s.occluders, r, 5);
    EXPECT_GE(unproven.seen_into, 1u);
}

// The score follows its documented definition.
TEST(Ranking, ScoreIsTheGeometricMeanOfTheTwoShares) {
    BoxMeasures m;
    m.solid_angle_mean_sr = kFourPi / 4.0;  // a quarter of the sphere
    m.hidden_objects_mean = 10.0;           // of 100: 0.1
    m.hidden_triangle_share_mean = 0.3;
    EXPECT_NEAR(ranking_score(m, 100), std::sqrt(0.25 * 0.2), 1e-12);
    m.hidden_objects_mean = 0.0;
    m.hidden_triangle_share_mean = 0.0;
    EXPECT_EQ(ranking_score(m, 100), 0.0);  // hides nothing: no score, however big
}

// Many cells, many boxes: the same bytes for 1 and 2 threads, best first in every cell, at most K, and
// every entry a proven box.
TEST(Ranking, SameResultForAnyThreadCount) {
    World world;
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.0f, 20.0f), s(0.2f, 3.0f);
    std::vector<Occluder> occluders;
    for (int i = 0; i < 60; ++i) {
        const glm::vec3 lo(u(rng), u(rng) * 0.2f, u(rng));
        const Aabb b = Aabb::of(lo, lo + glm::vec3(s(rng), s(rng), s(rng)));
        test::add_box(world, std::to_string(i), b);
        if (i % 2 == 0) occluders.push_back(Occluder{b, 0.25f, i % 6 != 0, {}});
    }
    CellSet cells;
    cells.kind = CellSet::Kind::kGrid;
    cells.cell_size_m = 4.0f;
    cells.dims = {5, 1, 5};
    for (int z = 0; z < 5; ++z)
        for (int x = 0; x < 5; ++x) {
            cells.grid_to_cell.push_back(int32_t(cells.cells.size()));
            const glm::vec3 lo(float(x) * 4.0f, 0.0f, float(z) * 4.0f);
            cells.cells.push_back(Cell{Aabb::of(lo, lo + 4.0f), -1});
        }
    Context ctx = quiet_context();
    RankingConfig config;
    config.occluders_per_cell = 5;
    std::vector<RankedOccluders> results, by_sight;
    PvsSet pvs = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    for (uint32_t c = 0; c < cells.size(); ++c)
        for (uint32_t o = 0; o < world.objects.size(); ++o)
            if ((c + o) % 3 != 0) pvs.set(c, o);
    for (int threads : {1, 2}) {
        omp_set_num_threads(threads);
        RankingFigures f;
        results.push_back(rank_occluders(ctx, config, world, cells, occluders, f));
        by_sight.push_back(rank_occluders(ctx, config, world, cells, occluders, f, nullptr, &pvs));
    }
    ASSERT_EQ(by_sight[0].offsets, by_sight[1].offsets);
    EXPECT_GT(by_sight[0].entries.size(), 25u);
    EXPECT_EQ(std::memcmp(by_sight[0].entries.data(), by_sight[1].entries.data(),
                          by_sight[0].entries.size() * sizeof(RankedOccluder)),
              0);
    omp_set_num_threads(omp_get_num_procs());
    const RankedOccluders& r = results[0];
    ASSERT_EQ(r.offsets, results[1].offsets);
    ASSERT_EQ(r.entries.size(), results[1].entries.size());
    EXPECT_EQ(
        std::memcmp(r.entries.data(), results[1].entries.data(), r.entries.size() * sizeof(RankedOccluder)),
        0);
    EXPECT_GT(r.entries.size(), 25u);
    for (uint32_t c = 0; c < cells.size(); ++c) {
        EXPECT_LE(r.count(c), 5u);
        for (uint32_t k = r.offsets[c]; k < r.offsets[c + 1]; ++k) {
            const RankedOccluder& e = r.entries[k];
            ASSERT_LT(e.box, occluders.size());
            EXPECT_TRUE(occluders[e.box].proven);
            EXPECT_GE(e.solid_angle_sr, config.min_solid_angle_sr * (1.0 - 1e-6));
            if (k > r.offsets[c]) {
                EXPECT_LE(e.score, r.entries[k - 1].score);
            }
        }
    }
}

}  // namespace
}  // namespace pvs
