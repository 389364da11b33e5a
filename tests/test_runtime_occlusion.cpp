// SPDX-License-Identifier: MIT
// The run-time culler of moving objects (pvsbake/occlusion.h): scenes whose answer is known (behind a wall,
// peeking round its edge, two walls that only hide together), awkward inputs (eye inside an occluder, a box
// holding the eye, empty, flat and non-finite boxes, a NaN eye), the C API, and zero wrong culls against
// Embree rays on random box worlds (every box the culler hides: no ray from the eye reaches a point of it
// before an occluder), including boxes grown to the edge of what the culler still hides.
#include "core/context.h"
#include "rays/ray_scene.h"
#include "tests/random_polygons.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <pvsbake/occlusion.h>
#include <pvsbake/occlusion_c.h>

#include "runtime/pvsr.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <random>
#include <vector>

namespace pvs {
namespace {

using pvsbake::Box;
using Culler = pvsbake::OcclusionCuller;
using Path = pvsbake::OcclusionCuller::Path;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Box box(float x0, float y0, float z0, float x1, float y1, float z1) {
    return Box{{x0, y0, z0}, {x1, y1, z1}};
}

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Eye 1.7 m above the ground at the origin, looking down +z at a wall 4 m high, x in [-5, 5], z in [5, 5.5].
const float kEye[3] = {0.0f, 1.7f, 0.0f};
const Box kWall = box(-5, 0, 5, 5, 4, 5.5f);

TEST(RuntimeOcclusion, ABoxBehindAWallIsCulled) {
    Culler culler;
    culler.begin_frame(kEye, &kWall, 1);
    EXPECT_EQ(culler.occluders_used(), 1u);
    // A person behind the wall, straddling the eye's x = 0 plane (crossing the eye's planes is fine).
    const Box person = box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f);
    EXPECT_TRUE(culler.is_hidden(person));
    EXPECT_EQ(culler.classify(person), Path::kShadowFrustum);
    EXPECT_TRUE(culler.hidden_by_depth_cube(person));  // the cube alone agrees
    // Farther off to the side but still in the shadow: x = 7.6 at z = 8 is seen through x = 4.75 at z = 5.
    EXPECT_TRUE(culler.is_hidden(box(7.0f, 0, 8, 7.6f, 1.8f, 8.6f)));
    // In front of the wall, above it, and behind the eye: visible.
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 0, 3, 0.3f, 1.8f, 3.6f)));
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 5, 8, 0.3f, 6.8f, 8.6f)));
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 0, -8.6f, 0.3f, 1.8f, -8)));
}

TEST(RuntimeOcclusion, ABoxPeekingRoundTheEdgeIsNot) {
    Culler culler;
    culler.begin_frame(kEye, &kWall, 1);
    // x in [7.5, 8.1] at z = 8 is seen through x in [4.69, 5.06] at z = 5: its right side shows past the
    // edge.
    const Box peeking = box(7.5f, 0, 8, 8.1f, 1.8f, 8.6f);
    EXPECT_FALSE(culler.is_hidden(peeking));
    EXPECT_FALSE(culler.hidden_by_shadow_frusta(peeking));
    EXPECT_FALSE(culler.hidden_by_depth_cube(peeking));
    // A head showing over the top: the wall's top edge at y = 4, z = 5 hides below y = 1.7 + 2.3 * 8 / 5.
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 5.0f, 8, 0.3f, 5.6f, 8.6f)));
    EXPECT_TRUE(culler.is_hidden(box(-0.3f, 4.9f, 8, 0.3f, 5.2f, 8.6f)));
}

// Wall A (x in [-5, 0.1], z in [4, 4.5]) and wall B (x in [-0.5, 5], z in [6, 6.5]) overlap in view only
// together: a box x in [-1, 1] at z = 10 shows past A's right end (x = 1 is seen through x = 0.4 at z = 4)
// and past B's left end (x = -1 through x = -0.6 at z = 6).
TEST(RuntimeOcclusion, TwoWallsThatOnlyTogetherHideABoxFuseOnTheDepthCube) {
    const std::vector<Box> walls = {box(-5, 0, 4, 0.1f, 4, 4.5f), box(-0.5f, 0, 6, 5, 4, 6.5f)};
    const Box target = box(-1, 0, 10, 1, 1.8f, 10.6f);
    Culler culler;
    culler.begin_frame(kEye, walls);
    EXPECT_EQ(culler.classify(target), Path::kDepthBuffer);
    EXPECT_FALSE(culler.hidden_by_shadow_frusta(target));
    EXPECT_TRUE(culler.hidden_by_depth_cube(target));
    EXPECT_TRUE(culler.hidden_by_faces(target));
    for (const Box& wall : walls) {  // each wall alone hides it on no path
        culler.begin_frame(kEye, &wall, 1);
        EXPECT_EQ(culler.classify(target), Path::kVisible);
    }
    // From 8 pixels per face edge on, the pixels the box touches are each covered whole by one wall (x = 0 is
    // a pixel edge on every even resolution); at 2 and 4 they are too coarse, and the faces' exact union
    // hides it. Never by single frusta.
    for (int r : {2, 4, 8, 16, 32, 64, 128}) {
        Culler c(r);
        c.begin_frame(kEye, walls);
        EXPECT_EQ(c.classify(target), r >= 8 ? Path::kDepthBuffer : Path::kFaces) << r;
        EXPECT_FALSE(c.hidden_by_shadow_frusta(target)) << r;
    }
    // Shadow frusta and faces only (resolution 0): the faces fuse.
    Culler frusta_only(0);
    frusta_only.begin_frame(kEye, walls);
    EXPECT_EQ(frusta_only.resolution(), 0);
    EXPECT_EQ(frusta_only.classify(target), Path::kFaces);
}

// A floor and a wall that meet along a line (panels, or solid boxes whose faces meet there) hide together a
// box behind the wall that reaches below the floor: the wall hides its part above y = 0, the floor its part
// below. No pixel of the depth cube along the junction is covered whole by one of them, at any resolution;
// the union of their faces is exact, and a box that peeks over the wall stays visible.
TEST(RuntimeOcclusion, AFloorAndAWallMeetingAtAJunctionHideWhatNeitherHidesAlone) {
    const Box target = box(-1, -1, 6, 1, 1, 7);
    const std::vector<std::vector<Box>> scenes = {
        {box(-5, 0, 0, 5, 0, 5), box(-5, 0, 5, 5, 4, 5)},              // two panels
        {box(-5, -0.5f, 0, 5, 0, 5), box(-5, 0, 5, 5, 4, 5.5f)},       // two solid boxes
        {box(-5, 0, 0, 5, 0, 5.25f), box(-5, -0.5f, 5, 5, 4, 5.5f)}};  // a panel over a box's foot
    for (size_t s = 0; s < scenes.size(); ++s) {
        for (int r : {0, 8, 32, 128}) {
            Culler c(r);
            c.begin_frame(kEye, scenes[s]);
            EXPECT_TRUE(c.hidden_by_faces(target)) << "scene " << s << " resolution " << r;
            if (s <
                2) {  // (the third scene's panel reaches into the wall: pixels along it are covered whole)
                EXPECT_EQ(c.classify(target), Path::kFaces) << "scene " << s << " resolution " << r;
                EXPECT_FALSE(c.hidden_by_depth_cube(target)) << s << " " << r;
            }
            EXPECT_FALSE(c.is_hidden(box(-1, -1, 6, 1, 4.5f, 7))) << s << " " << r;  // over the wall's top
            EXPECT_FALSE(c.is_hidden(box(-1, -1, 3, 1, 1, 4))) << s << " " << r;     // in front of the wall
        }
        for (const Box& one : scenes[s]) {
            Culler c;
            c.begin_frame(kEye, &one, 1);
            EXPECT_FALSE(c.is_hidden(target)) << s;
        }
    }
}

// A slope (a polygon occluder: the ground rising from y = 0 at z = 2 to y = 4 at z = 6, x in [-5, 5]) hides a
// box behind its crest from an eye at its foot; boxes that show over the crest, past its side or in front of
// it stay visible. The eye within the slab, a clockwise or non-convex polygon, and non-finite values are
// refused.
TEST(RuntimeOcclusion, ASlopeHidesWhatIsBehindItsCrest) {
    const float n[3] = {0.0f, 0.707106781f, -0.707106781f};  // up the slope's face, towards the eye's side
    const float offset = n[1] * 0.0f + n[2] * 2.0f;          // through (0, 0, 2) and (0, 4, 6)
    const float plane[5] = {n[0], n[1], n[2], offset, 0.001f};
    const float corners[12] = {-5, 0, 2, -5, 4, 6, 5, 4, 6, 5, 0, 2};  // counter-clockwise seen from +n
    const float eye[3] = {0.0f, 1.0f, -2.0f};
    const Box behind = box(-1, 1, 8, 1, 3, 9);  // below the line of sight over the crest
    for (int r : {0, 32}) {
        Culler c(r);
        c.begin_frame(eye, nullptr, 0);
        EXPECT_FALSE(c.is_hidden(behind));
        ASSERT_TRUE(c.add_polygon(plane, corners, 4));
        EXPECT_EQ(c.polygons_used(), 1u);
        EXPECT_EQ(c.classify(behind), Path::kFaces) << r;
        EXPECT_FALSE(c.is_hidden(box(-1, 1, 8, 1, 6.5f, 9))) << r;  // over the crest
        EXPECT_FALSE(c.is_hidden(box(-1, 2, 0, 1, 3, 1))) << r;     // in front of the slope
        EXPECT_FALSE(c.is_hidden(box(12, 1, 8, 13, 3, 9))) << r;    // past its side
        // With a box in front of the eye too, the polygon still counts (boxes and polygons together).
        c.begin_frame(eye, {box(-0.2f, 0.8f, -0.5f, 0.2f, 1.2f, -0.4f)});
        ASSERT_TRUE(c.add_polygon(plane, corners, 4));
        EXPECT_TRUE(c.is_hidden(behind)) << r;
    }
    Culler c(0);
    c.begin_frame(eye, nullptr, 0);
    const float in_slab[3] = {0.0f, 2.0f, 4.0f};  // on the slope's plane
    Culler on(0);
    on.begin_frame(in_slab, nullptr, 0);
    EXPECT_FALSE(on.add_polygon(plane, corners, 4));
    const float clockwise[12] = {-5, 0, 2, 5, 0, 2, 5, 4, 6, -5, 4, 6};
    EXPECT_FALSE(c.add_polygon(plane, clockwise, 4));
    const float bow_tie[12] = {-5, 0, 2, 5, 4, 6, -5, 4, 6, 5, 0, 2};
    EXPECT_FALSE(c.add_polygon(plane, bow_tie, 4));
    float nan_plane[5] = {n[0], n[1], n[2], kNaN, 0.0f};
    EXPECT_FALSE(c.add_polygon(nan_plane, corners, 4));
    EXPECT_FALSE(c.add_polygon(plane, corners, 2));
    EXPECT_FALSE(c.add_polygon(plane, corners, Culler::kMaxPolygonCorners + 1));
    EXPECT_EQ(c.polygons_used(), 0u);
}

// A panel, the wall's near face alone (flat along z), hides what the wall hides: by its shadow frustum and on
// the depth cube, and two overlapping halves of it together on the depth cube only (fused). Seen edge-on (the
// eye in its plane), or a box flat along two axes, hides nothing; a box peeking past its edge stays visible.
TEST(RuntimeOcclusion, APanelHidesWhatIsBehindItAndNothingEdgeOn) {
    const Box face = box(-5, 0, 5, 5, 4, 5);
    const Box behind = box(-0.5f, 0.5f, 8, 0.5f, 1.5f, 9);
    Culler culler;
    culler.begin_frame(kEye, {face});
    EXPECT_EQ(culler.occluders_used(), 1u);
    EXPECT_EQ(culler.classify(behind), Path::kShadowFrustum);
    EXPECT_TRUE(culler.hidden_by_depth_cube(behind));
    EXPECT_FALSE(culler.is_hidden(box(4.0f, 0.5f, 8, 9.0f, 1.5f, 9)));      // past the edge
    EXPECT_FALSE(culler.is_hidden(box(-0.5f, 0.5f, 4, 0.5f, 1.5f, 4.9f)));  // in front
    // Two overlapping halves of the face (as panels overlap: docs/ALGORITHMS.md#panels): only fused do they
    // hide the box across the overlap.
    culler.begin_frame(kEye, {box(-5, 0, 5, 0.2f, 4, 5), box(-0.2f, 0, 5, 5, 4, 5)});
    EXPECT_EQ(culler.classify(behind), Path::kDepthBuffer);
    // Edge-on: the eye in the panel's plane (or within its margin of it).
    const float in_plane[3] = {0.0f, 1.7f, 5.0f};
    culler.begin_frame(in_plane, {box(1, 0, 5, 5, 4, 5)});
    EXPECT_EQ(culler.occluders_used(), 0u);
    EXPECT_FALSE(culler.is_hidden(box(6, 0.5f, 4, 7, 1.5f, 6)));
    // Flat along two axes: a segment, not a rectangle.
    culler.begin_frame(kEye, {box(-5, 2, 5, 5, 2, 5)});
    EXPECT_EQ(culler.occluders_used(), 0u);
}

TEST(RuntimeOcclusion, AnOccluderHoldingOrTouchingTheEyeIsSkipped) {
    const Box behind = box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f);
    Culler culler;
    const float inside[3] = {0.0f, 1.7f, 5.2f};  // in the wall
    culler.begin_frame(inside, &kWall, 1);
    EXPECT_EQ(culler.occluders_used(), 0u);
    EXPECT_FALSE(culler.is_hidden(behind));
    const float touching[3] = {0.0f, 1.7f, 5.0f};  // on its front face
    culler.begin_frame(touching, &kWall, 1);
    EXPECT_EQ(culler.occluders_used(), 0u);
    EXPECT_FALSE(culler.is_hidden(behind));
    const float near_it[3] = {0.0f, 1.7f, 4.999999f};  // within the margin
    culler.begin_frame(near_it, &kWall, 1);
    EXPECT_EQ(culler.occluders_used(), 0u);
    // A step back, it occludes again.
    const float back[3] = {0.0f, 1.7f, 4.9f};
    culler.begin_frame(back, &kWall, 1);
    EXPECT_EQ(culler.occluders_used(), 1u);
    EXPECT_TRUE(culler.is_hidden(behind));
}

TEST(RuntimeOcclusion, ABoxHoldingOrGrazingTheEyeIsVisible) {
    // Occluders all round the eye: a closed room of six walls.
    const std::vector<Box> room = {box(-3, -1, -3, 3, 0, 3),  box(-3, 4, -3, 3, 5, 3),
                                   box(-4, -1, -3, -3, 5, 3), box(3, -1, -3, 4, 5, 3),
                                   box(-4, -1, -4, 4, 5, -3), box(-4, -1, 3, 4, 5, 4)};
    Culler culler;
    culler.begin_frame(kEye, room);
    EXPECT_EQ(culler.occluders_used(), 6u);
    EXPECT_TRUE(culler.is_hidden(box(-1, 0, 6, 1, 2, 7)));     // outside the room
    EXPECT_FALSE(culler.is_hidden(box(-1, 0, -1, 1, 2, 1)));   // holds the eye
    EXPECT_FALSE(culler.is_hidden(box(0, 1.7f, 0, 1, 2, 1)));  // its corner is the eye
    EXPECT_FALSE(culler.is_hidden(box(-20, 1, 1, 20, 2, 2)));  // crosses the room in front of the eye
    EXPECT_FALSE(culler.is_hidden(box(-20, -20, -20, 20, 20, 20)));
    EXPECT_FALSE(culler.is_hidden(box(0.0005f, 1.7f, 0, 0.01f, 1.8f, 0.01f)));  // within the near plane
}

TEST(RuntimeOcclusion, EmptyFlatAndNonFiniteBoxes) {
    Culler culler;
    culler.begin_frame(kEye, &kWall, 1);
    EXPECT_FALSE(culler.is_hidden(box(1, 1, 9, 0, 0, 8)));  // empty (min > max)
    EXPECT_FALSE(culler.is_hidden(box(kInf, kInf, kInf, -kInf, -kInf, -kInf)));
    EXPECT_FALSE(culler.is_hidden(box(kNaN, 0, 8, 1, 1, 9)));
    EXPECT_FALSE(culler.is_hidden(box(-kInf, 0, 8, 1, 1, 9)));
    (void)culler.classify(box(0, 0, 8, 1, 1, 1e38f));      // huge: either answer is safe; it must not trap
    EXPECT_TRUE(culler.is_hidden(box(0, 1, 8, 0, 1, 8)));  // a point behind the wall
    EXPECT_TRUE(culler.is_hidden(box(-1, 0, 8, 1, 1.8f, 8)));  // a flat box (zero depth)
    // Empty, flat and non-finite occluders are skipped or used safely.
    const std::vector<Box> odd = {box(1, 1, 1, 0, 0, 0), box(kNaN, 0, 5, 1, 1, 6), box(-kInf, 0, 5, 1, 1, 6),
                                  box(-5, 0, 5, 5, 4, 5)};  // the last one: a flat wall
    culler.begin_frame(kEye, odd);
    EXPECT_EQ(culler.occluders_used(), 1u);
    // A flat (zero-thickness) occluder is a panel: the rectangle hides what lies behind it.
    EXPECT_TRUE(culler.is_hidden(box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f)));
}

TEST(RuntimeOcclusion, ANonFiniteEyeMakesEverythingVisible) {
    Culler culler;
    for (const float bad : {kNaN, kInf, -kInf}) {
        const float eye[3] = {0.0f, bad, 0.0f};
        culler.begin_frame(eye, &kWall, 1);
        EXPECT_EQ(culler.occluders_used(), 0u);
        EXPECT_FALSE(culler.is_hidden(box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f)));
    }
    culler.begin_frame(nullptr, &kWall, 1);
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f)));
    culler.begin_frame(kEye, nullptr, 5);  // no occluders
    EXPECT_EQ(culler.occluders_used(), 0u);
    EXPECT_FALSE(culler.is_hidden(box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f)));
    // And back to normal: nothing from the bad frames stays behind.
    culler.begin_frame(kEye, &kWall, 1);
    EXPECT_TRUE(culler.is_hidden(box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f)));
}

TEST(RuntimeOcclusion, FramesDoNotLeakIntoEachOther) {
    Culler culler;
    const Box target = box(-0.3f, 0, 8, 0.3f, 1.8f, 8.6f);
    culler.begin_frame(kEye, &kWall, 1);
    EXPECT_TRUE(culler.hidden_by_depth_cube(target));
    EXPECT_GT(culler.covered_pixels(), 0u);
    const Box elsewhere = box(-5, 0, -5.5f, 5, 4, -5);  // the same wall behind the eye
    culler.begin_frame(kEye, &elsewhere, 1);
    EXPECT_FALSE(culler.hidden_by_depth_cube(target));
    EXPECT_TRUE(culler.hidden_by_depth_cube(box(-0.3f, 0, -8.6f, 0.3f, 1.8f, -8)));
}

// An occluder that a nearer one already hides adds nothing and is skipped, whatever order it comes in.
TEST(RuntimeOcclusion, OccludersHiddenByNearerOnesAreSkipped) {
    const std::vector<Box> occluders = {box(-1, 0, 9, 1, 1.5f, 9.5f),
                                        kWall};  // the first stands behind the wall
    Culler culler;
    culler.begin_frame(kEye, occluders);
    EXPECT_EQ(culler.occluders_used(), 1u);
    EXPECT_EQ(culler.occluders_redundant(), 1u);
    EXPECT_TRUE(culler.is_hidden(box(-0.3f, 0, 12, 0.3f, 1.8f, 12.6f)));
    const std::vector<Box> apart = {box(-1, 0, -9.5f, 1, 1.5f, -9), kWall};  // one behind the eye
    culler.begin_frame(kEye, apart);
    EXPECT_EQ(culler.occluders_used(), 2u);
    EXPECT_EQ(culler.occluders_redundant(), 0u);
}

// Occluders read at a stride: an array of structs holding a Box (as the bake's ranked occluders will be).
TEST(RuntimeOcclusion, OccludersAtAStride) {
    struct Ranked {
        Box box;
        float score;
        float solid_angle_sr;
    };
    const Ranked ranked[2] = {{box(-5, 0, 4, 0.1f, 4, 4.5f), 2.0f, 1.0f},
                              {box(-0.5f, 0, 6, 5, 4, 6.5f), 1.0f, 0.5f}};
    Culler culler;
    culler.begin_frame(kEye, &ranked[0].box, 2, sizeof(Ranked));
    EXPECT_EQ(culler.occluders_used(), 2u);
    EXPECT_EQ(culler.classify(box(-1, 0, 10, 1, 1.8f, 10.6f)), Path::kDepthBuffer);
}

TEST(RuntimeOcclusion, CApiMirrorsTheCppApi) {
    pvsbake_culler* c = pvsbake_culler_create(0);
    ASSERT_NE(c, nullptr);
    const float walls[12] = {-5, 0, 4, 0.1f, 4, 4.5f, -0.5f, 0, 6, 5, 4, 6.5f};
    pvsbake_culler_begin_frame(c, kEye, walls, 2);
    const float fused[6] = {-1, 0, 10, 1, 1.8f, 10.6f};
    const float single[6] = {1, 0, 10, 2, 1.8f, 10.6f};
    const float front[6] = {-1, 0, 2, 1, 1.8f, 2.6f};
    EXPECT_EQ(pvsbake_culler_classify(c, fused), PVSBAKE_CULL_DEPTH_BUFFER);
    EXPECT_EQ(pvsbake_culler_classify(c, single), PVSBAKE_CULL_SHADOW_FRUSTUM);
    EXPECT_EQ(pvsbake_culler_classify(c, front), PVSBAKE_CULL_VISIBLE);
    EXPECT_EQ(pvsbake_culler_is_hidden(c, fused), 1);
    EXPECT_EQ(pvsbake_culler_is_hidden(c, front), 0);
    EXPECT_EQ(pvsbake_culler_is_hidden(c, nullptr), 0);
    EXPECT_EQ(pvsbake_culler_is_hidden(nullptr, fused), 0);
    pvsbake_culler_begin_frame(c, kEye, nullptr, 3);
    EXPECT_EQ(pvsbake_culler_is_hidden(c, fused), 0);
    // A polygon: a slanted sheet across the view (4 m to 5 m ahead) hides the box behind it.
    const float sheet[12] = {-5, 0, 4, 5, 0, 4, 5, 4, 5, -5, 4, 5};
    const float plane[5] = {0.0f, -0.242535625f, 0.970142500f, 3.88057f, 0.001f};
    EXPECT_EQ(pvsbake_culler_add_polygon(c, plane, sheet, 4), 1);
    EXPECT_EQ(pvsbake_culler_classify(c, fused), PVSBAKE_CULL_FACES);
    EXPECT_EQ(pvsbake_culler_add_polygon(c, plane, sheet, 2), 0);
    EXPECT_EQ(pvsbake_culler_add_polygon(nullptr, plane, sheet, 4), 0);
    pvsbake_culler_begin_frame(nullptr, kEye, walls, 2);
    pvsbake_culler_free(c);
    pvsbake_culler_free(nullptr);
    pvsbake_culler* frusta_only = pvsbake_culler_create(-1);
    ASSERT_NE(frusta_only, nullptr);
    pvsbake_culler_begin_frame(frusta_only, kEye, walls, 2);
    EXPECT_EQ(pvsbake_culler_classify(frusta_only, fused), PVSBAKE_CULL_FACES);
    EXPECT_EQ(pvsbake_culler_classify(frusta_only, single), PVSBAKE_CULL_SHADOW_FRUSTUM);
    pvsbake_culler_free(frusta_only);
}

// ---------------------------------------------------------------------------------------------------------
// Zero wrong culls against rays.

Aabb to_aabb(const Box& b) {
    return Aabb::of({b.min[0], b.min[1], b.min[2]}, {b.max[0], b.max[1], b.max[2]});
}

bool inside(const Box& b, const float p[3], float pad) {
    for (int a = 0; a < 3; ++a) {
        if (p[a] < b.min[a] - pad || p[a] > b.max[a] + pad) return false;
    }
    return true;
}

// Points of a box to aim at: the 8 corners, the 12 edge midpoints, the 6 face centres, the centre, and
// `extra` random points on its faces and inside.
std::vector<glm::vec3> aim_points(const Box& b, int extra, std::mt19937& rng) {
    std::vector<glm::vec3> pts;
    const auto at = [&](float fx, float fy, float fz) {
        pts.emplace_back(b.min[0] + fx * (b.max[0] - b.min[0]), b.min[1] + fy * (b.max[1] - b.min[1]),
                         b.min[2] + fz * (b.max[2] - b.min[2]));
    };
    const float h[3] = {0.0f, 0.5f, 1.0f};
    for (float fx : h)
        for (float fy : h)
            for (float fz : h) at(fx, fy, fz);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int k = 0; k < extra; ++k) {
        float f[3] = {u(rng), u(rng), u(rng)};
        if (k % 3 != 0) f[k % 3] = float(k % 2);  // on a face
        at(f[0], f[1], f[2]);
    }
    return pts;
}

// Rays from the eye to every aim point of the box; returns how many reach their point unblocked.
uint32_t rays_reaching(const RayScene& scene, const float eye_f[3], const Box& b, int extra,
                       std::mt19937& rng, uint64_t& rays) {
    const glm::vec3 eye(eye_f[0], eye_f[1], eye_f[2]);
    const std::vector<glm::vec3> pts = aim_points(b, extra, rng);
    std::vector<glm::vec3> origins, dirs;
    std::vector<float> tfar;
    for (const glm::vec3& p : pts) {
        const glm::vec3 d = p - eye;
        const float len = glm::length(d);
        if (!(len > 0.0f)) continue;
        origins.push_back(eye);
        dirs.push_back(d / len);
        tfar.push_back(len);
    }
    std::vector<uint8_t> blocked(origins.size());
    scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()), blocked.data());
    rays += origins.size();
    return uint32_t(std::count(blocked.begin(), blocked.end(), uint8_t(0)));
}

struct PropertyTally {
    uint64_t queries = 0, hidden_frustum = 0, hidden_cube = 0, hidden_faces = 0, wrong = 0, rays = 0,
             edge_boxes = 0;
    void count(Path path) {
        (path == Path::kShadowFrustum ? hidden_frustum
         : path == Path::kFaces       ? hidden_faces
                                      : hidden_cube) += 1;
    }
};

// The faces' union hides what every segment meets within 1e-9 of the coordinates' scale of a face
// (docs/ALGORITHMS.md#runtime-faces), and Embree's float rays graze edges within their own precision: rays
// are traced against the occluders grown by 0.1 mm, so that a ray grazing an edge of a box grown to the edge
// of what the culler hides does not count as seen.
constexpr float kRayTolerance_m = 1e-4f;
Box grown(const Box& b, float by) {
    return box(b.min[0] - by, b.min[1] - by, b.min[2] - by, b.max[0] + by, b.max[1] + by, b.max[2] + by);
}

// Random box worlds: K walls (thin on one axis), eyes outside them, query boxes of person to vehicle size,
// half of them placed behind a random wall as seen from the eye. Every box the culler hides is checked with
// rays; then grown by bisection to the largest copy the culler still hides, which is checked again.
// panels: every other occluder is a panel (flat along its thin axis: a rectangle, two-sided in the world).
void random_worlds(int worlds, int eyes_per_world, int queries_per_eye, int resolution, uint32_t seed,
                   PropertyTally& t, bool panels = false) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto range = [&](float a, float b) { return a + (b - a) * u(rng); };
    Context ctx = quiet_context();
    for (int w = 0; w < worlds; ++w) {
        const int k = 2 + int(rng() % 15);
        std::vector<Box> occ;
        World world;
        for (int i = 0; i < k; ++i) {
            float c[3], half[3];
            for (int a = 0; a < 3; ++a) {
                c[a] = range(-15.0f, 15.0f);
                half[a] = range(1.0f, 6.0f);
            }
            half[rng() % 3] = range(0.1f, 0.8f);
            if (panels && i % 2 == 0) {  // flat along its thinnest axis
                const int a = half[0] < half[1] ? (half[0] < half[2] ? 0 : 2) : (half[1] < half[2] ? 1 : 2);
                half[a] = 0.0f;
            }
            const Box b = box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
                              c[2] + half[2]);
            occ.push_back(b);
            test::add_box(world, "occ" + std::to_string(i), to_aabb(grown(b, kRayTolerance_m)));
        }
        const RayScene scene(ctx, world, BuildQuality::kMedium, 1);
        Culler culler(resolution);
        for (int e = 0; e < eyes_per_world; ++e) {
            float eye[3];
            bool ok = false;
            for (int tries = 0; tries < 100 && !ok; ++tries) {
                for (float& x : eye) x = range(-18.0f, 18.0f);
                ok =
                    std::none_of(occ.begin(), occ.end(), [&](const Box& b) { return inside(b, eye, 0.05f); });
            }
            if (!ok) continue;
            culler.begin_frame(eye, occ);
            for (int q = 0; q < queries_per_eye; ++q) {
                float c[3];
                if (q % 2 == 0) {  // behind a wall: past a random point of it, farther from the eye
                    const Box& b = occ[rng() % occ.size()];
                    const float s = range(1.05f, 3.0f);
                    for (int a = 0; a < 3; ++a) c[a] = eye[a] + s * (range(b.min[a], b.max[a]) - eye[a]);
                } else {
                    for (float& x : c) x = range(-20.0f, 20.0f);
                }
                float half[3] = {range(0.1f, 1.5f), range(0.1f, 1.5f), range(0.1f, 1.5f)};
                Box qb = box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
                             c[2] + half[2]);
                ++t.queries;
                const Path path = culler.classify(qb);
                if (path == Path::kVisible) continue;
                t.count(path);
                const uint32_t seen = rays_reaching(scene, eye, qb, 40, rng, t.rays);
                t.wrong += seen;
                EXPECT_EQ(seen, 0u) << "world " << w << " eye " << eye[0] << " " << eye[1] << " " << eye[2]
                                    << " box " << qb.min[0] << " " << qb.min[1] << " " << qb.min[2] << " "
                                    << qb.max[0] << " " << qb.max[1] << " " << qb.max[2] << " path "
                                    << int(path);
                // Grow the box about its centre to the edge of what the culler still hides (the margins are
                // tested where they matter), and check that box with rays too.
                if (q % 4 < 2) {
                    float lo = 0.0f, hi = 40.0f;
                    for (int it = 0; it < 24; ++it) {
                        const float mid = 0.5f * (lo + hi);
                        Box g = qb;
                        for (int a = 0; a < 3; ++a) {
                            g.min[a] -= mid;
                            g.max[a] += mid;
                        }
                        (culler.is_hidden(g) ? lo : hi) = mid;
                    }
                    for (int a = 0; a < 3; ++a) {
                        qb.min[a] -= lo;
                        qb.max[a] += lo;
                    }
                    ASSERT_TRUE(culler.is_hidden(qb));
                    ++t.edge_boxes;
                    const uint32_t seen_edge = rays_reaching(scene, eye, qb, 200, rng, t.rays);
                    t.wrong += seen_edge;
                    EXPECT_EQ(seen_edge, 0u) << "edge box of world " << w;
                }
            }
        }
    }
}

// Random worlds (random_worlds) at each resolution: no wrong cull, and the scenes hide many boxes by the
// frusta and some by the cube alone (a culler hiding nothing fails here).
void expect_random_worlds_hold(const char* label, std::initializer_list<int> resolutions, uint32_t seed,
                               bool panels) {
    const bool ci = test::in_ci();
    for (int resolution : resolutions) {
        PropertyTally t;
        random_worlds(ci ? 12 : 60, 6, ci ? 100 : 200, resolution, seed + uint32_t(resolution), t, panels);
        std::printf(
            "%sresolution %d: %llu queries, hidden %llu by frusta + %llu by the cube only + %llu by the "
            "faces "
            "only, %llu edge boxes, %llu rays, %llu wrong\n",
            label, resolution, (unsigned long long)t.queries, (unsigned long long)t.hidden_frustum,
            (unsigned long long)t.hidden_cube, (unsigned long long)t.hidden_faces,
            (unsigned long long)t.edge_boxes, (unsigned long long)t.rays, (unsigned long long)t.wrong);
        EXPECT_EQ(t.wrong, 0u);
        EXPECT_GT(t.hidden_frustum, t.queries / 20);
        EXPECT_GT(t.hidden_faces, 0u);
        if (resolution >= Culler::kDefaultResolution) {
            EXPECT_GT(t.hidden_cube, 0u);
        }
    }
}

TEST(RuntimeOcclusionProperty, NeverCullsABoxARayReaches) {
    expect_random_worlds_hold("", {Culler::kDefaultResolution, 64, 8}, 20261123u, false);
}

// Panels (rectangles of the opaque surface) among the occluders: half of each world's occluders are flat.
TEST(RuntimeOcclusionProperty, PanelsNeverCullABoxARayReaches) {
    expect_random_worlds_hold("panels, ", {Culler::kDefaultResolution, 8}, 20261129u, true);
}

// The same on a scene made for fusion: a row of wall segments at different depths that overlap in view
// only together, so the depth cube does the work.
TEST(RuntimeOcclusionProperty, FusedWallsNeverCullABoxARayReaches) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Box> occ;
    World world;
    for (int i = 0; i < 16; ++i) {  // segments 1.6 m wide every 1.2 m of x, alternating z = 6 and z = 7
        const float x0 = -10.0f + 1.2f * float(i), z0 = i % 2 ? 7.0f : 6.0f;
        occ.push_back(box(x0, -1, z0, x0 + 1.6f, 5, z0 + 0.3f));
        test::add_box(world, "wall" + std::to_string(i), to_aabb(grown(occ.back(), kRayTolerance_m)));
    }
    Context ctx = quiet_context();
    const RayScene scene(ctx, world, BuildQuality::kMedium, 1);
    Culler culler(Culler::kDefaultResolution);
    PropertyTally t;
    for (int e = 0; e < 40; ++e) {
        const float eye[3] = {-4.0f + 8.0f * u(rng), 0.5f + 3.0f * u(rng), -2.0f + 5.0f * u(rng)};
        culler.begin_frame(eye, occ);
        for (int q = 0; q < 200; ++q) {
            const float c[3] = {-6.0f + 12.0f * u(rng), 0.0f + 4.0f * u(rng), 10.0f + 10.0f * u(rng)};
            const float h = 0.2f + 1.0f * u(rng);
            const Box qb = box(c[0] - h, c[1] - h, c[2] - h, c[0] + h, c[1] + h, c[2] + h);
            ++t.queries;
            const Path path = culler.classify(qb);
            if (path == Path::kVisible) continue;
            t.count(path);
            const uint32_t seen = rays_reaching(scene, eye, qb, 60, rng, t.rays);
            t.wrong += seen;
            EXPECT_EQ(seen, 0u);
        }
    }
    std::printf(
        "fused walls: %llu queries, hidden %llu by frusta + %llu by the cube only + %llu by the faces only, "
        "%llu rays, %llu wrong\n",
        (unsigned long long)t.queries, (unsigned long long)t.hidden_frustum,
        (unsigned long long)t.hidden_cube, (unsigned long long)t.hidden_faces, (unsigned long long)t.rays,
        (unsigned long long)t.wrong);
    EXPECT_EQ(t.wrong, 0u);
    EXPECT_GT(t.hidden_cube, t.queries / 10);
}

// The slow reference of the faces tests: does the segment from the eye to p (double) meet box b grown by grow
// metres? (A slab test in double; a segment that only starts inside counts.)
bool segment_meets_grown_box(const float e[3], const double p[3], const Box& b, double grow) {
    double t0 = 0.0, t1 = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double d = p[a] - double(e[a]), lo = double(b.min[a]) - grow, hi = double(b.max[a]) + grow;
        if (d == 0.0) {
            if (double(e[a]) < lo || double(e[a]) > hi) return false;
            continue;
        }
        double ta = (lo - double(e[a])) / d, tb = (hi - double(e[a])) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1 && t0 < 1.0;
}

// 3 to 14 random boxes within 12 m of the origin, half-sizes 1 to 6 m, thin on one axis: every other one a
// panel (flat there).
std::vector<Box> random_boxes_and_panels(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto range = [&](float a, float b) { return a + (b - a) * u(rng); };
    std::vector<Box> occ;
    const int k = 3 + int(rng() % 12);
    for (int i = 0; i < k; ++i) {
        float c[3], half[3];
        for (int a = 0; a < 3; ++a) {
            c[a] = range(-12.0f, 12.0f);
            half[a] = range(1.0f, 6.0f);
        }
        const int thin = int(rng() % 3);
        half[thin] = i % 2 == 0 ? 0.0f : range(0.1f, 0.8f);
        occ.push_back(box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
                          c[2] + half[2]));
    }
    return occ;
}

// An eye within 15 m of the origin, 5 cm or more outside every box; false when 100 draws found none.
bool eye_outside(const std::vector<Box>& occ, std::mt19937& rng, float eye[3]) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int tries = 0; tries < 100; ++tries) {
        for (int a = 0; a < 3; ++a) eye[a] = -15.0f + 30.0f * u(rng);
        if (std::none_of(occ.begin(), occ.end(), [&](const Box& b) { return inside(b, eye, 0.05f); }))
            return true;
    }
    return false;
}

// A query box past a random point of a random occluder, 1.05 to 3 times as far from the eye, half-sizes
// 5 cm to 1.5 m.
Box query_behind(const std::vector<Box>& occ, const float eye[3], std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto range = [&](float a, float b) { return a + (b - a) * u(rng); };
    const Box& b = occ[rng() % occ.size()];
    const float s = range(1.05f, 3.0f);
    float c[3], half[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = eye[a] + s * (range(b.min[a], b.max[a]) - eye[a]);
        half[a] = range(0.05f, 1.5f);
    }
    return box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
               c[2] + half[2]);
}

// Point n of a box's 64 sampled points: its 8 corners, its centre, then random points in it.
void sample_point(const Box& qb, int n, std::mt19937& rng, double p[3]) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int a = 0; a < 3; ++a) {
        const double lo = qb.min[a], hi = qb.max[a];
        p[a] = n < 8 ? ((n >> a) & 1 ? hi : lo) : n == 8 ? 0.5 * (lo + hi) : lo + (hi - lo) * u(rng);
    }
}

// The faces' union against a slow reference without rays: every box the faces hide has each of its sampled
// points (corners, centre and random ones) behind some occluder, by an exact segment test in double against
// the occluders grown by 1e-6 m (the faces grow by 1e-9 of the scale); and the union is tight: of the boxes
// whose every sampled point is behind an occluder as given, the faces hide nearly all. Random boxes and
// panels, random eyes, query boxes behind them.
TEST(RuntimeOcclusionProperty, TheFacesHideWhatSegmentsToEveryPointMeetAndLittleElse) {
    std::mt19937 rng(20261205u);
    const bool ci = test::in_ci();
    uint64_t hidden = 0, points = 0, all_points_hidden = 0, of_them_hidden = 0;
    for (int world = 0; world < (ci ? 60 : 300); ++world) {
        const std::vector<Box> occ = random_boxes_and_panels(rng);
        float eye[3];
        if (!eye_outside(occ, rng, eye)) continue;
        Culler culler(0);
        culler.begin_frame(eye, occ);
        for (int q = 0; q < 60; ++q) {
            const Box qb = query_behind(occ, eye, rng);
            const bool by_faces = culler.hidden_by_faces(qb);
            bool all = true;
            for (int n = 0; n < 64; ++n) {
                double p[3];
                sample_point(qb, n, rng, p);
                const bool grown = std::any_of(occ.begin(), occ.end(), [&](const Box& o) {
                    return segment_meets_grown_box(eye, p, o, 1e-6);
                });
                const bool exact = std::any_of(occ.begin(), occ.end(), [&](const Box& o) {
                    return segment_meets_grown_box(eye, p, o, 0.0);
                });
                if (by_faces) {
                    ++points;
                    ASSERT_TRUE(grown) << "world " << world << " box " << q << " point " << n;
                }
                all = all && exact;
            }
            hidden += by_faces;
            if (all) {
                ++all_points_hidden;
                of_them_hidden += by_faces;
            }
        }
    }
    std::printf(
        "faces: %llu boxes hidden (%llu points checked); of %llu boxes with every sampled point behind "
        "an occluder, %llu hidden\n",
        (unsigned long long)hidden, (unsigned long long)points, (unsigned long long)all_points_hidden,
        (unsigned long long)of_them_hidden);
    EXPECT_GT(hidden, ci ? 100u : 500u);
    EXPECT_GT(double(of_them_hidden), 0.9 * double(all_points_hidden));
}

// Polygon occluders (slanted convex polygons with a slab) among boxes and panels: every box the faces test
// hides has every sampled point behind some occluder by the slow references (a segment meeting a box, or
// crossing a polygon's slab inside its prism, each grown by 1e-6 m), and the test hides most of the boxes
// whose every sampled point is so hidden.
TEST(RuntimeOcclusionProperty, PolygonsHideWhatSegmentsToEveryPointCrossAndLittleElse) {
    std::mt19937 rng(20261206u);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto range = [&](float a, float b) { return a + (b - a) * u(rng); };
    const bool ci = test::in_ci();
    uint64_t hidden = 0, by_polygon_only = 0, all_points_hidden = 0, of_them_hidden = 0, refused = 0;
    for (int world = 0; world < (ci ? 80 : 400); ++world) {
        std::vector<Box> occ;
        for (int i = 0, k = int(rng() % 4); i < k; ++i) {
            float c[3], half[3];
            for (int a = 0; a < 3; ++a) {
                c[a] = range(-10.0f, 10.0f);
                half[a] = range(1.0f, 5.0f);
            }
            half[rng() % 3] = i % 2 == 0 ? 0.0f : range(0.1f, 0.8f);
            occ.push_back(box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
                              c[2] + half[2]));
        }
        std::vector<test::TestPolygon> polys;
        for (int i = 0, k = 2 + int(rng() % 5); i < k; ++i) {
            const float centre[3] = {range(-10.0f, 10.0f), range(-10.0f, 10.0f), range(-10.0f, 10.0f)};
            polys.push_back(test::random_polygon(rng, centre, 7.0f, 0.05f));
        }
        const float eye[3] = {range(-14.0f, 14.0f), range(-14.0f, 14.0f), range(-14.0f, 14.0f)};
        Culler culler(0);
        culler.begin_frame(eye, occ);
        std::vector<test::TestPolygon> used;
        for (const test::TestPolygon& p : polys) {
            if (culler.add_polygon(p.plane, p.corners.data(), p.count()))
                used.push_back(p);
            else
                ++refused;
        }
        if (used.empty()) continue;
        const auto behind = [&](const double p[3], double grow) {
            return std::any_of(occ.begin(), occ.end(),
                               [&](const Box& o) { return segment_meets_grown_box(eye, p, o, grow); }) ||
                   std::any_of(used.begin(), used.end(), [&](const test::TestPolygon& t) {
                       return test::segment_crosses_polygon(eye, p, t, grow);
                   });
        };
        for (int q = 0; q < 60; ++q) {  // boxes seen through a polygon's corner region, farther away
            const test::TestPolygon& t = used[rng() % used.size()];
            const float* corner = &t.corners[3 * (rng() % t.count())];
            const float* other = &t.corners[3 * (rng() % t.count())];
            const float mix = u(rng), s = range(1.05f, 3.0f);
            float c[3], half[3];
            for (int a = 0; a < 3; ++a) {
                const float p = corner[a] + mix * (other[a] - corner[a]);
                c[a] = eye[a] + s * (p - eye[a]);
                half[a] = range(0.05f, 1.5f);
            }
            const Box qb = box(c[0] - half[0], c[1] - half[1], c[2] - half[2], c[0] + half[0], c[1] + half[1],
                               c[2] + half[2]);
            const bool by_faces = culler.hidden_by_faces(qb);
            bool all = true;
            for (int n = 0; n < 64; ++n) {
                double p[3];
                for (int a = 0; a < 3; ++a) {
                    const double lo = qb.min[a], hi = qb.max[a];
                    p[a] = n < 8    ? ((n >> a) & 1 ? hi : lo)
                           : n == 8 ? 0.5 * (lo + hi)
                                    : lo + (hi - lo) * u(rng);
                }
                if (by_faces) {
                    ASSERT_TRUE(behind(p, 1e-6)) << "world " << world << " box " << q << " point " << n;
                }
                all = all && behind(p, 0.0);
            }
            hidden += by_faces;
            if (by_faces) {
                Culler boxes_only(0);
                boxes_only.begin_frame(eye, occ);
                by_polygon_only += !boxes_only.is_hidden(qb);
            }
            if (all) {
                ++all_points_hidden;
                of_them_hidden += by_faces;
            }
        }
    }
    std::printf(
        "polygons: %llu boxes hidden (%llu need a polygon); of %llu boxes with every sampled point "
        "behind an occluder, %llu hidden; %llu polygons refused\n",
        (unsigned long long)hidden, (unsigned long long)by_polygon_only,
        (unsigned long long)all_points_hidden, (unsigned long long)of_them_hidden,
        (unsigned long long)refused);
    EXPECT_GT(by_polygon_only, ci ? 50u : 250u);
    EXPECT_GT(double(of_them_hidden), 0.8 * double(all_points_hidden));
}

// The shadow frusta against their definition: a box is in B's shadow when the segment from the eye to each
// of its corners meets B (the shadow is convex). Random boxes; the planes may only be stricter.
TEST(RuntimeOcclusionProperty, ShadowFrustaAgreeWithCornerSegments) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-10.0f, 10.0f), s(0.05f, 4.0f);
    const auto segment_meets = [](const float e[3], const float p[3], const Box& b) {
        double t0 = 0.0, t1 = 1.0;
        for (int a = 0; a < 3; ++a) {
            const double d = double(p[a]) - e[a];
            if (d == 0.0) {
                if (e[a] < b.min[a] || e[a] > b.max[a]) return false;
                continue;
            }
            double ta = (double(b.min[a]) - e[a]) / d, tb = (double(b.max[a]) - e[a]) / d;
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        return t0 <= t1;
    };
    Culler culler(0);
    uint64_t hidden = 0;
    for (int n = 0; n < 20000; ++n) {
        const float eye[3] = {u(rng), u(rng), u(rng)};
        const float c[3] = {u(rng), u(rng), u(rng)};
        const Box b =
            box(c[0] - s(rng), c[1] - s(rng), c[2] - s(rng), c[0] + s(rng), c[1] + s(rng), c[2] + s(rng));
        culler.begin_frame(eye, &b, 1);
        for (int q = 0; q < 20; ++q) {
            const float f = 1.0f + 2.0f * std::abs(u(rng)) / 10.0f;
            const float p[3] = {eye[0] + f * (c[0] - eye[0]) + u(rng) / 4,
                                eye[1] + f * (c[1] - eye[1]) + u(rng) / 4,
                                eye[2] + f * (c[2] - eye[2]) + u(rng) / 4};
            const float h = s(rng) / 8;
            const Box qb = box(p[0] - h, p[1] - h, p[2] - h, p[0] + h, p[1] + h, p[2] + h);
            bool all = true;
            for (int k = 0; k < 8 && all; ++k) {
                const float corner[3] = {k & 1 ? qb.max[0] : qb.min[0], k & 2 ? qb.max[1] : qb.min[1],
                                         k & 4 ? qb.max[2] : qb.min[2]};
                all = segment_meets(eye, corner, b);
            }
            const bool by_planes = culler.hidden_by_shadow_frusta(qb);
            if (by_planes) {
                ++hidden;
                EXPECT_TRUE(all) << "frustum hides a box whose corner segment misses the occluder";
            }
        }
    }
    EXPECT_GT(hidden, 1000u);
    std::printf("shadow frusta: %llu hidden, all confirmed by corner segments\n", (unsigned long long)hidden);
}

// ---------------------------------------------------------------------------------------------------------
// The occlusion horizon of the C99 runtime (pvsr_horizon, docs/ALGORITHMS.md#runtime-horizon).

// A horizon with its own memory; begin() .. end() take one frame's occluders.
class Horizon {
public:
    explicit Horizon(int columns = 256, size_t pieces = 1 << 16)
        : memory_(pvsr_horizon_memory_bytes(columns, pieces) / 8 + 1) {
        ok_ = pvsr_horizon_init(&h_, columns, pieces, memory_.data(), memory_.size() * 8) != 0;
    }
    bool ok() const { return ok_; }
    // The polygons go in as polygon occluders, or as tiles (`tiles`: their promise is the caller's).
    void frame(const float eye[3], const std::vector<Box>& boxes,
               const std::vector<test::TestPolygon>& polys = {}, bool tiles = false) {
        pvsr_horizon_begin(&h_, eye);
        for (const Box& b : boxes) {
            const float f[6] = {b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]};
            pvsr_horizon_add_box(&h_, f);
        }
        for (const test::TestPolygon& p : polys)
            added_ += tiles ? pvsr_horizon_add_tile(&h_, p.plane, p.corners.data(), p.count())
                            : pvsr_horizon_add_polygon(&h_, p.plane, p.corners.data(), p.count());
        pvsr_horizon_end(&h_);
    }
    int added() const { return added_; }
    bool hidden(const Box& b) const {
        const float f[6] = {b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]};
        return pvsr_horizon_is_hidden(&h_, f) != 0;
    }
    pvsr_horizon& raw() { return h_; }

private:
    std::vector<uint64_t> memory_;
    pvsr_horizon h_;
    bool ok_ = false;
    int added_ = 0;
};

// The floor and the wall of the culler's junction test, as panels, solid boxes, or a panel over a box's
// foot: together they hide the box behind the wall that reaches below the floor, neither alone does, and
// boxes over the wall's top or in front of it stay visible.
TEST(RuntimeHorizon, AFloorAndAWallMeetingAtAJunctionHideWhatNeitherHidesAlone) {
    const Box target = box(-1, -1, 6, 1, 1, 7);
    const std::vector<std::vector<Box>> scenes = {
        {box(-5, 0, 0, 5, 0, 5), box(-5, 0, 5, 5, 4, 5)},
        {box(-5, -0.5f, 0, 5, 0, 5), box(-5, 0, 5, 5, 4, 5.5f)},
        {box(-5, 0, 0, 5, 0, 5.25f), box(-5, -0.5f, 5, 5, 4, 5.5f)}};
    for (size_t s = 0; s < scenes.size(); ++s) {
        for (int columns : {16, 256, 2048}) {
            Horizon h(columns);
            ASSERT_TRUE(h.ok());
            h.frame(kEye, scenes[s]);
            EXPECT_TRUE(h.hidden(target)) << "scene " << s << " columns " << columns;
            EXPECT_FALSE(h.hidden(box(-1, -1, 6, 1, 4.5f, 7))) << s << " " << columns;  // over the wall's top
            EXPECT_FALSE(h.hidden(box(-1, -1, 3, 1, 1, 4))) << s << " " << columns;  // in front of the wall
            EXPECT_FALSE(h.hidden(box(-12, -1, 6, -10, 1, 7))) << s << " " << columns;  // past its side
        }
        for (const Box& one : scenes[s]) {
            Horizon h;
            h.frame(kEye, {one});
            EXPECT_FALSE(h.hidden(target)) << s;
        }
    }
}

// Which occluders hide what: the floor and the wall of the scene above, tagged, and a far wall nothing needs.
// A box they hide together reports both tags (and no other); a box over the floor's edge, hidden by the wall
// alone, reports the wall; a visible box reports nothing. The answers are pvsr_horizon_is_hidden's.
TEST(RuntimeHorizon, HiddenByReportsTheTagsOfTheOccludersThatHideTheBox) {
    Horizon h(64);
    const float eye[3] = {kEye[0], kEye[1], kEye[2]};
    const float floor_[6] = {-5, 0, 0, 5, 0, 5}, wall[6] = {-5, 0, 5, 5, 4, 5},
                far_wall[6] = {-20, 0, 30, 20, 9, 31};
    pvsr_horizon_begin(&h.raw(), eye);
    pvsr_horizon_set_tag(&h.raw(), 7);
    pvsr_horizon_add_box(&h.raw(), floor_);
    pvsr_horizon_set_tag(&h.raw(), 9);
    pvsr_horizon_add_box(&h.raw(), wall);
    pvsr_horizon_set_tag(&h.raw(), 11);
    pvsr_horizon_add_box(&h.raw(), far_wall);
    pvsr_horizon_end(&h.raw());
    const auto tags = [&](const float b[6], int* hidden) {
        std::vector<uint32_t> out;
        *hidden = pvsr_horizon_hidden_by(
            &h.raw(), b,
            [](void* user, uint32_t tag) { static_cast<std::vector<uint32_t>*>(user)->push_back(tag); },
            &out);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    };
    int hidden = 0;
    const float together[6] = {-1, -1, 6, 1, 1, 7}, behind_wall[6] = {-1, 2, 6, 1, 3, 7},
                over[6] = {-1, -1, 6, 1, 4.5f, 7};
    EXPECT_EQ(tags(together, &hidden), (std::vector<uint32_t>{7, 9}));
    EXPECT_EQ(hidden, 1);
    EXPECT_EQ(hidden, pvsr_horizon_is_hidden(&h.raw(), together));
    EXPECT_EQ(tags(behind_wall, &hidden), (std::vector<uint32_t>{9}));
    EXPECT_EQ(hidden, 1);
    EXPECT_TRUE(tags(over, &hidden).empty());
    EXPECT_EQ(hidden, 0);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h.raw(), over), 0);
    EXPECT_EQ(pvsr_horizon_hidden_by(&h.raw(), together, nullptr, nullptr), 1);  // no callback: the answer
}

// The slope of the culler's test cut in two flat polygons (no slab) that share the edge at z = 4: together
// they hide the box behind the crest, which neither hides alone (its directions cross both); over the crest,
// in front and past the side stay visible. (Polygons with a slab meet only where the directions through both
// of each one's cross-sections meet, which leaves a seam as wide as the slab's parallax: they fuse when
// thin.)
TEST(RuntimeHorizon, TwoPolygonsSharingAnEdgeHideWhatNeitherHidesAlone) {
    const float n[3] = {0.0f, 0.707106781f, -0.707106781f};
    const float plane[5] = {n[0], n[1], n[2], n[2] * 2.0f, 0.0f};
    test::TestPolygon lower, upper;
    std::copy_n(plane, 5, lower.plane);
    std::copy_n(plane, 5, upper.plane);
    lower.corners = {-5, 0, 2, -5, 2, 4, 5, 2, 4, 5, 0, 2};  // counter-clockwise seen from +n
    upper.corners = {-5, 2, 4, -5, 4, 6, 5, 4, 6, 5, 2, 4};
    const float eye[3] = {0.0f, 1.0f, -2.0f};
    const Box behind = box(-1, 1, 8, 1, 3, 9);
    Horizon both, low, up;
    both.frame(eye, {}, {lower, upper});
    low.frame(eye, {}, {lower});
    up.frame(eye, {}, {upper});
    EXPECT_TRUE(both.hidden(behind));
    EXPECT_FALSE(low.hidden(behind));
    EXPECT_FALSE(up.hidden(behind));
    EXPECT_FALSE(both.hidden(box(-1, 1, 8, 1, 6.5f, 9)));  // over the crest
    EXPECT_FALSE(both.hidden(box(-1, 2, 0, 1, 3, 1)));     // in front of the slope
    EXPECT_FALSE(both.hidden(box(12, 1, 8, 13, 3, 9)));    // past its side
    // Refused: the eye within the slab, a clockwise polygon, too few corners, a value that is not finite.
    const float in_slab[3] = {0.0f, 2.0f, 4.0f};
    pvsr_horizon_begin(&both.raw(), in_slab);
    EXPECT_EQ(pvsr_horizon_add_polygon(&both.raw(), plane, lower.corners.data(), 4), 0);
    pvsr_horizon_begin(&both.raw(), eye);
    const float clockwise[12] = {-5, 0, 2, 5, 0, 2, 5, 2, 4, -5, 2, 4};
    EXPECT_EQ(pvsr_horizon_add_polygon(&both.raw(), plane, clockwise, 4), 0);
    EXPECT_EQ(pvsr_horizon_add_polygon(&both.raw(), plane, lower.corners.data(), 2), 0);
    const float nan_plane[5] = {n[0], n[1], n[2], kNaN, 0.0f};
    EXPECT_EQ(pvsr_horizon_add_polygon(&both.raw(), nan_plane, lower.corners.data(), 4), 0);
    EXPECT_EQ(pvsr_horizon_add_polygon(&both.raw(), plane, lower.corners.data(), 4), 1);
}

// A wall made of two triangles split along its diagonal: the seam is slanted in every column it crosses, and
// the pieces meet along it (their chords are the same line), so the two hide together what neither hides
// alone; a slit along the seam keeps it visible.
TEST(RuntimeHorizon, TrianglesMeetingAlongASlantedSeamHideTogether) {
    test::TestPolygon a, b, a_slit;
    const float plane[5] = {0.0f, 0.0f, -1.0f, -5.0f, 0.0f};  // z = 5, the normal towards the eye
    for (test::TestPolygon* p : {&a, &b, &a_slit}) std::copy_n(plane, 5, p->plane);
    a.corners = {-4, -2, 5, 4, 4, 5, 4, -2, 5};  // counter-clockwise seen from +n
    b.corners = {-4, -2, 5, -4, 4, 5, 4, 4, 5};
    a_slit.corners = {-4, -2.05f, 5, 4, 3.95f, 5, 4, -2.05f, 5};  // a 5 cm slit under the seam
    const float eye[3] = {0.0f, 1.0f, 0.0f};
    const Box behind = box(-1, 0, 8, 1, 2, 9);
    for (const int columns : {16, 64, 256}) {
        Horizon both(columns), alone_a(columns), alone_b(columns), slit(columns);
        both.frame(eye, {}, {a, b});
        alone_a.frame(eye, {}, {a});
        alone_b.frame(eye, {}, {b});
        slit.frame(eye, {}, {a_slit, b});
        EXPECT_TRUE(both.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(alone_a.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(alone_b.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(slit.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(both.hidden(box(-1, 0, 2, 1, 2, 3))) << "in front of the wall";
        EXPECT_FALSE(both.hidden(box(-1, 5.5f, 8, 1, 6.5f, 9))) << "over the wall";
    }
}

// Two slopes meeting at a crease, each declared with a 1 cm slab: as polygon occluders their slabs' two
// cross-sections leave a seam at the crease, so what lies behind it in their union stays drawn; as tiles
// (each a disk of surface bounded by its corners) they meet exactly there and hide it. Apart by 5 cm, they
// hide it in neither form.
TEST(RuntimeHorizon, TilesMeetingAtACreaseHideWhatTheirSlabsLeaveOpen) {
    const double na = std::sqrt(17.0), nb = std::sqrt(5.0);
    test::TestPolygon a, b, b_apart;
    const float plane_a[5] = {0.0f, float(4.0 / na), float(-1.0 / na), float(-2.0 / na), 0.01f};
    const float plane_b[5] = {0.0f, float(2.0 / nb), float(-1.0 / nb), float(-4.0 / nb), 0.01f};
    std::copy_n(plane_a, 5, a.plane);
    std::copy_n(plane_b, 5, b.plane);
    std::copy_n(plane_b, 5, b_apart.plane);
    b_apart.plane[3] = float(-4.1 / nb);                   // the plane 2 y - z = -4.1: 5 cm further along z
    a.corners = {-5, 0, 2, -5, 1, 6, 5, 1, 6, 5, 0, 2};    // y = (z - 2) / 4, counter-clockwise seen from +n
    b.corners = {-5, 1, 6, -5, 3, 10, 5, 3, 10, 5, 1, 6};  // y = 1 + (z - 6) / 2
    b_apart.corners = {-5, 1, 6.1f, -5, 3, 10.1f, 5, 3, 10.1f, 5, 1, 6.1f};
    const float eye[3] = {0.0f, 3.0f, 0.0f};
    const Box behind = box(-1, -3, 14, 1, -1, 15);
    for (const int columns : {16, 256}) {
        Horizon tiles(columns), polygons(columns), alone(columns), apart(columns);
        tiles.frame(eye, {}, {a, b}, true);
        polygons.frame(eye, {}, {a, b}, false);
        alone.frame(eye, {}, {b}, true);
        apart.frame(eye, {}, {a, b_apart}, true);
        EXPECT_EQ(tiles.added(), 2);
        EXPECT_EQ(apart.added(), 2);
        EXPECT_TRUE(tiles.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(polygons.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(alone.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(apart.hidden(behind)) << columns << " columns";
        EXPECT_FALSE(tiles.hidden(box(-1, 4, 14, 1, 6, 15))) << "over the crest";
        EXPECT_FALSE(tiles.hidden(box(-1, 2, 3, 1, 2.5f, 4))) << "in front of the slope";
    }
}

// A wall receding in depth across the view: its pieces over wide blocks of columns reach deeper than a box
// behind its near part, so the test takes each piece's depth over the box's own directions. A box before the
// wall, or past its end, stays visible.
TEST(RuntimeHorizon, ARecedingWallHidesWhatLiesBehindItsNearPart) {
    const double r = std::sqrt(0.5);
    test::TestPolygon wall;  // the plane z - x = 12
    const float plane[5] = {float(-r), 0.0f, float(r), float(12.0 * r), 0.0f};
    std::copy_n(plane, 5, wall.plane);
    wall.corners = {-10, -5, 2, 10, -5, 22, 10, 10, 22, -10, 10, 2};  // counter-clockwise seen from +n
    for (const int columns : {16, 256}) {
        Horizon h(columns);
        h.frame(kEye, {}, {wall}, true);
        ASSERT_EQ(h.added(), 1);
        EXPECT_TRUE(h.hidden(box(-3, 0, 11, -2, 1, 12))) << columns << " columns";
        EXPECT_FALSE(h.hidden(box(-3, 0, 8, -2, 1, 8.5f))) << "before the wall";
        EXPECT_FALSE(h.hidden(box(16, 0, 30, 17, 1, 31))) << "past its end";
    }
}

// A long box receding beside the line of sight (2 m to 20 m ahead, 1.2 m to the side): a near wall hides its
// near part and the directions of its far end beside the near wall's edge meet a far wall, which lies before
// the box only there (the box is 18 m away in those directions, nearer than the far wall elsewhere). Each
// piece is judged against the box's depth in the directions it serves, so together they hide the box; with
// the far wall narrower, those directions pass between the walls' edges and the box stays visible.
TEST(RuntimeHorizon, AFarWallHidesTheFarEndOfALongBoxWhereItServesIt) {
    const Box near_wall = box(0.1f, -2, 1.5f, 3, 5, 1.5f);
    const Box far_wall = box(-1, -2, 9, 1, 5, 9);
    const Box narrow_far_wall = box(-1, -2, 9, 0.5f, 5, 9);
    const Box target = box(1.2f, 1.4f, 2, 1.5f, 2.0f, 20);
    for (const int columns : {256, 1024}) {
        Horizon h(columns);
        h.frame(kEye, {near_wall, far_wall});
        EXPECT_TRUE(h.hidden(target)) << columns << " columns";
        EXPECT_FALSE(h.hidden(box(1.2f, 1.4f, 1, 1.5f, 2.0f, 20))) << "reaching before the near wall";
        Horizon narrow(columns);
        narrow.frame(kEye, {near_wall, narrow_far_wall});
        EXPECT_FALSE(narrow.hidden(target)) << columns << " columns, between the walls' edges";
        for (const Box& one : {near_wall, far_wall}) {
            Horizon single(columns);
            single.frame(kEye, {one});
            EXPECT_FALSE(single.hidden(target)) << columns << " columns";
        }
    }
}

// The same long box made tall (1.4 m, centred on the eye's height): in the columns of its far end its
// directions span a few degrees up and down, not the tens of degrees of its near end, so a low far wall
// (1 m tall, seen across 0.11 of a unit of direction) covers them there; a wall 0.2 m lower at the top
// leaves the far end's upper directions open.
TEST(RuntimeHorizon, ALowFarWallHidesTheFarEndOfATallLongBox) {
    const Box near_wall = box(0.1f, -2, 1.5f, 3, 5, 1.5f);
    const Box target = box(1.2f, 1.0f, 2, 1.5f, 2.4f, 20);
    for (const int columns : {256, 1024}) {
        Horizon h(columns);
        h.frame(kEye, {near_wall, box(-1, 1.2f, 9, 1, 2.2f, 9)});
        EXPECT_TRUE(h.hidden(target)) << columns << " columns";
        Horizon lower(columns);
        lower.frame(kEye, {near_wall, box(-1, 1.2f, 9, 1, 2.0f, 9)});
        EXPECT_FALSE(lower.hidden(target)) << columns << " columns, over the lower wall";
    }
}

// A floor upstairs, seen from below through the ceiling slab it stands on: in the columns ahead its
// directions span from steep to shallow, and the slab's underside is deeper at the shallow end than the
// floor is at the steep one, so no bound of depths over the directions separates them; but the whole
// floor lies beyond the plane of the underside, so every sight line meets the slab first. What reaches
// below the underside or past the slab's edge stays drawn.
TEST(RuntimeHorizon, ACeilingHidesTheWholeFloorAboveItsPlane) {
    const Box slab = box(-10, 3.0f, 1, 10, 3.4f, 30);
    const Box floor = box(-1, 3.45f, 2, 1, 3.45f, 25);
    for (const int columns : {16, 256, 1024}) {
        Horizon h(columns);
        h.frame(kEye, {slab});
        EXPECT_TRUE(h.hidden(floor)) << columns << " columns";
        EXPECT_TRUE(h.hidden(box(-1, 3.45f, 2, 1, 5, 25))) << columns << " columns, a room over it";
        EXPECT_FALSE(h.hidden(box(-1, 2.9f, 2, 1, 3.45f, 25))) << columns << " columns, below the underside";
        EXPECT_FALSE(h.hidden(box(-1, 3.45f, 2, 1, 3.45f, 50))) << columns << " columns, seen past the edge";
    }
}

// Two walls side by side meeting along a vertical seam whose direction falls inside a column (at any
// column count tried): each gives the seam's column a piece over its own part, so together they hide the
// box behind the seam; with a 2 cm gap at the seam the box stays visible through it, and neither wall
// hides it alone.
TEST(RuntimeHorizon, WallsMeetingInsideAColumnHideWhatLiesBehindTheSeam) {
    const Box target = box(-0.5f, 1, 8, 0.5f, 2, 9);
    for (const int columns : {16, 256, 1024}) {
        Horizon h(columns);
        h.frame(kEye, {box(-3, 0, 5, 0.013f, 4, 5), box(0.013f, 0, 5, 3, 4, 5)});
        EXPECT_TRUE(h.hidden(target)) << columns << " columns";
        EXPECT_FALSE(h.hidden(box(-0.5f, 7, 8, 0.5f, 8, 9))) << columns << " columns, over the walls";
        Horizon gap(columns);
        gap.frame(kEye, {box(-3, 0, 5, 0.003f, 4, 5), box(0.023f, 0, 5, 3, 4, 5)});
        EXPECT_FALSE(gap.hidden(target)) << columns << " columns, through the gap";
        for (const Box& one : {box(-3, 0, 5, 0.013f, 4, 5), box(0.013f, 0, 5, 3, 4, 5)}) {
            Horizon single(columns);
            single.frame(kEye, {one});
            EXPECT_FALSE(single.hidden(target)) << columns << " columns";
        }
    }
}

// A ceiling seen from below, and a flat light standing on its far edge (a case from ctf_inyard, floats as
// found): the light's lowest edge is seen along the ceiling (a sight line meets the ceiling only at its end),
// so it stays drawn; every sight line to the light lifted by 1 cm crosses the ceiling first. The tolerance
// of meeting pieces does not hold at the box's own lowest direction.
TEST(RuntimeHorizon, ABoxOnAnOccludersEdgeIsSeenAlongIt) {
    const float eye[3] = {-55.43578338623047f, -8.999100685119629f, 7.689573764801025f};
    const Box ceiling = box(-61.7728004f, -6.09600019f, 4.87680006f, -55.270401f, -6.09600019f, 17.8815994f);
    for (const int columns : {16, 256}) {
        Horizon h(columns);
        h.frame(eye, {ceiling});
        EXPECT_FALSE(
            h.hidden(box(-60.0f, -6.09600019f, 17.8815994f, -58.5215988f, -5.68959999f, 17.8815994f)))
            << columns << " columns";
        EXPECT_TRUE(h.hidden(box(-60.0f, -6.08600019f, 17.8f, -58.5215988f, -5.68959999f, 17.8f)))
            << columns << " columns";
    }
}

// A wall behind a nearer, larger wall spanning the same directions across: what the walls hide stays hidden,
// and a box between them is hidden by the nearer one only.
TEST(RuntimeHorizon, AWallBehindANearerOneAddsNothingWrong) {
    Horizon h(64);
    h.frame(kEye, {box(-2, -1, 5, 2, 5, 5.5f), box(-4, 0, 10, 4, 3, 10.5f)});
    EXPECT_TRUE(h.hidden(box(-1, 0.5f, 12, 1, 1.5f, 13)));
    EXPECT_TRUE(h.hidden(box(-1, 0.5f, 7, 1, 1.5f, 8)));
    EXPECT_FALSE(h.hidden(box(-1, 0.5f, 2, 1, 1.5f, 3)));
    EXPECT_FALSE(h.hidden(box(-1, 12, 12, 1, 13, 13)));  // over both
}

// Memory missing, misaligned or short: nothing is hidden. A box holding the eye, a panel seen edge-on, a box
// flat along two axes, empty or non-finite boxes add nothing; a non-finite eye hides nothing; nothing is
// hidden before end(), and nothing is added after it; pieces past the memory are dropped (fewer pieces, never
// a wrong cull).
TEST(RuntimeHorizon, AwkwardInputs) {
    pvsr_horizon h;
    std::vector<uint64_t> memory(pvsr_horizon_memory_bytes(64, 1024) / 8 + 1);
    EXPECT_EQ(pvsr_horizon_init(&h, 64, 1024, nullptr, 0), 0);
    EXPECT_EQ(
        pvsr_horizon_init(&h, 64, 1024, reinterpret_cast<char*>(memory.data()) + 4, memory.size() * 8 - 4),
        0);
    EXPECT_EQ(pvsr_horizon_init(&h, 64, 1024, memory.data(), pvsr_horizon_memory_bytes(64, 1024) - 1), 0);
    const float wall[6] = {-5, 0, 5, 5, 4, 5.5f}, target[6] = {-1, 0.5f, 8, 1, 1.5f, 9};
    pvsr_horizon_begin(&h, kEye);
    EXPECT_EQ(pvsr_horizon_add_box(&h, wall), 0);
    pvsr_horizon_end(&h);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, target), 0);
    ASSERT_EQ(pvsr_horizon_init(&h, 64, 1024, memory.data(), memory.size() * 8), 1);
    pvsr_horizon_begin(&h, kEye);
    EXPECT_EQ(pvsr_horizon_add_box(&h, wall), 1);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, target), 0);  // before end()
    const float holding[6] = {-1, 0, -1, 1, 3, 1}, edge_on[6] = {-3, 1.7f, 1, 3, 1.7f, 4},
                two_flat[6] = {-3, 1, 2, 3, 1, 2}, empty[6] = {1, 1, 3, 0, 2, 4},
                not_finite[6] = {-1, 0, 3, 1, kInf, 4};
    EXPECT_EQ(pvsr_horizon_add_box(&h, holding), 0);
    EXPECT_EQ(pvsr_horizon_add_box(&h, edge_on), 0);
    EXPECT_EQ(pvsr_horizon_add_box(&h, two_flat), 0);
    EXPECT_EQ(pvsr_horizon_add_box(&h, empty), 0);
    EXPECT_EQ(pvsr_horizon_add_box(&h, not_finite), 0);
    // A panel just past the near plane and far to the side: its directions lie far outside every column.
    const float far_side[6] = {1e18f, 1.0f, 0.0015f, 2e18f, 2.0f, 0.0015f};
    pvsr_horizon_add_box(&h, far_side);
    pvsr_horizon_end(&h);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, target), 1);
    EXPECT_EQ(pvsr_horizon_add_box(&h, wall), 0);  // the frame is ended: nothing more until begin
    pvsr_horizon_end(&h);                          // a second end changes nothing
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, target), 1);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, empty), 0);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, not_finite), 0);
    const float nan_eye[3] = {kNaN, 1.7f, 0.0f};
    pvsr_horizon_begin(&h, nan_eye);
    EXPECT_EQ(pvsr_horizon_add_box(&h, wall), 0);
    pvsr_horizon_end(&h);
    EXPECT_EQ(pvsr_horizon_is_hidden(&h, target), 0);
    Horizon tiny(64, 1);  // room for one piece: the left half of the wall fills it, the right is dropped
    tiny.frame(kEye, {box(-5, 0, 5, 0, 4, 5.5f), box(0, 0, 5, 5, 4, 5.5f)});
    EXPECT_GT(tiny.raw().dropped, 0u);
    EXPECT_TRUE(tiny.hidden(box(-2, 0.5f, 8, -1, 1.5f, 9)));
    EXPECT_FALSE(tiny.hidden(box(1, 0.5f, 8, 2, 1.5f, 9)));
}

// Does the segment from e to x meet the triangle (a, b, c) grown by `grow` metres in its plane? Exact enough
// in double for a slow reference.
bool segment_meets_triangle(const float e[3], const double x[3], const double a[3], const double b[3],
                            const double c[3], double grow) {
    double ab[3], ac[3], n[3], d[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        d[k] = x[k] - double(e[k]);
    }
    n[0] = ab[1] * ac[2] - ab[2] * ac[1];
    n[1] = ab[2] * ac[0] - ab[0] * ac[2];
    n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double denom = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if (!(nl > 0.0) || denom == 0.0) return false;
    const double t =
        (n[0] * (a[0] - double(e[0])) + n[1] * (a[1] - double(e[1])) + n[2] * (a[2] - double(e[2]))) / denom;
    if (t < 0.0 || t > 1.0) return false;
    double p[3];
    for (int k = 0; k < 3; ++k) p[k] = double(e[k]) + t * d[k];
    const double* v[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {  // inside every edge, grown
        const double* p0 = v[k];
        const double* p1 = v[(k + 1) % 3];
        const double ed[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        const double m[3] = {n[1] * ed[2] - n[2] * ed[1], n[2] * ed[0] - n[0] * ed[2],
                             n[0] * ed[1] - n[1] * ed[0]};
        const double ml = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(ml > 0.0)) return false;
        if ((m[0] * (p[0] - p0[0]) + m[1] * (p[1] - p0[1]) + m[2] * (p[2] - p0[2])) / ml < -grow)
            return false;
    }
    return true;
}

// Random terrains: a height field of 6 x 6 float vertices 2 m apart, each quad two triangles, given to the
// horizon as tiles (a quad's four corners with its slab over both triangles, or each triangle alone). Every
// sampled point of every box the horizon hides has its segment from the eye meet a triangle grown by 1e-6 m,
// and the tiles hide more than the same polygons given as polygon occluders.
TEST(RuntimeHorizonProperty, TilesHideOnlyWhatSegmentsToTheSurfaceMeet) {
    std::mt19937 rng(20261205u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const bool ci = test::in_ci();
    uint64_t hidden = 0, hidden_as_polygons = 0, points = 0, queries = 0, tiles_added = 0;
    for (int world = 0; world < (ci ? 40 : 200); ++world) {
        const int n = 6;
        const double step = 2.0, x0 = -5.0 + 10.0 * u(rng), z0 = -5.0 + 10.0 * u(rng);
        std::vector<double> height(size_t(n * n));
        for (double& y : height) y = double(float(3.0 * u(rng)));
        const auto vertex = [&](int i, int k, double out[3]) {
            out[0] = double(float(x0 + step * i));
            out[1] = height[size_t(k * n + i)];
            out[2] = double(float(z0 + step * k));
        };
        struct Tri {
            double v[3][3];
        };
        std::vector<Tri> tris;
        std::vector<test::TestPolygon> tiles;
        // A tile of corners (in order, counter-clockwise seen from above): its plane through the corners'
        // mean with the normal of Newell's method, its slab the corners' largest distance, plus 1 um.
        const auto add_tile = [&](const std::vector<const double*>& corners) {
            double nn[3] = {0, 0, 0}, g[3] = {0, 0, 0};
            const size_t m = corners.size();
            for (size_t q = 0; q < m; ++q) {
                const double* p0 = corners[q];
                const double* p1 = corners[(q + 1) % m];
                nn[0] += (p0[1] - p1[1]) * (p0[2] + p1[2]);
                nn[1] += (p0[2] - p1[2]) * (p0[0] + p1[0]);
                nn[2] += (p0[0] - p1[0]) * (p0[1] + p1[1]);
                for (int k = 0; k < 3; ++k) g[k] += p0[k] / double(m);
            }
            const double len = std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
            test::TestPolygon t;
            for (int k = 0; k < 3; ++k) t.plane[k] = float(nn[k] / len);
            const double fn[3] = {t.plane[0], t.plane[1], t.plane[2]};
            const double fl = std::sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
            const double o = (fn[0] * g[0] + fn[1] * g[1] + fn[2] * g[2]) / fl;
            double thick = 0.0;
            for (const double* c : corners) {
                thick = std::max(thick, std::abs((fn[0] * c[0] + fn[1] * c[1] + fn[2] * c[2]) / fl - o));
                for (int k = 0; k < 3; ++k) t.corners.push_back(float(c[k]));
            }
            t.plane[3] = float(o * fl);
            t.plane[4] = float((thick + 1e-6) * fl);
            tiles.push_back(t);
        };
        for (int k = 0; k + 1 < n; ++k)
            for (int i = 0; i + 1 < n; ++i) {
                double p00[3], p10[3], p01[3], p11[3];
                vertex(i, k, p00);
                vertex(i + 1, k, p10);
                vertex(i, k + 1, p01);
                vertex(i + 1, k + 1, p11);
                Tri t1, t2;  // split along p00 - p11; counter-clockwise seen from above (+y)
                std::copy_n(p00, 3, t1.v[0]);
                std::copy_n(p01, 3, t1.v[1]);
                std::copy_n(p11, 3, t1.v[2]);
                std::copy_n(p00, 3, t2.v[0]);
                std::copy_n(p11, 3, t2.v[1]);
                std::copy_n(p10, 3, t2.v[2]);
                tris.push_back(t1);
                tris.push_back(t2);
                if (rng() % 2)
                    add_tile({p00, p01, p11, p10});
                else {
                    add_tile({p00, p01, p11});
                    add_tile({p00, p11, p10});
                }
            }
        const float eye[3] = {float(x0 + 10.0 * u(rng) - 2.0), float(4.0 + 6.0 * u(rng)),
                              float(z0 + 10.0 * u(rng) - 2.0)};
        const int columns = world % 2 == 0 ? 64 : 512;
        Horizon h(columns, 1 << 18), as_polygons(columns, 1 << 18);
        h.frame(eye, {}, tiles, true);
        as_polygons.frame(eye, {}, tiles, false);
        tiles_added += uint64_t(h.added());
        for (int q = 0; q < 200; ++q) {
            const double c[3] = {x0 - 4.0 + 18.0 * u(rng), -3.0 + 5.0 * u(rng), z0 - 4.0 + 18.0 * u(rng)};
            const double half = 0.1 + 0.6 * u(rng);
            const Box qb = box(float(c[0] - half), float(c[1] - half), float(c[2] - half), float(c[0] + half),
                               float(c[1] + half), float(c[2] + half));
            ++queries;
            hidden_as_polygons += as_polygons.hidden(qb);
            if (!h.hidden(qb)) continue;
            ++hidden;
            for (int s = 0; s < 64; ++s) {
                double p[3];
                sample_point(qb, s, rng, p);
                ++points;
                const bool met = std::any_of(tris.begin(), tris.end(), [&](const Tri& t) {
                    return segment_meets_triangle(eye, p, t.v[0], t.v[1], t.v[2], 1e-6);
                });
                ASSERT_TRUE(met) << "world " << world << " box " << q << " point " << s;
            }
        }
    }
    std::printf(
        "tiles: %llu of %llu boxes hidden (%llu points checked; as polygon occluders %llu), %llu tiles\n",
        (unsigned long long)hidden, (unsigned long long)queries, (unsigned long long)points,
        (unsigned long long)hidden_as_polygons, (unsigned long long)tiles_added);
    EXPECT_GT(hidden, queries / 10);
    EXPECT_GT(hidden, hidden_as_polygons);
}

// Random boxes, panels and slanted polygons, random eyes, query boxes behind them, at several column counts:
// every box the horizon hides has each of its sampled points behind some occluder by the slow references (a
// segment meeting a box, or crossing a polygon's slab inside its prism, each grown by 1e-6 m), and it hides
// many, some of them hidden by no one occluder alone.
TEST(RuntimeHorizonProperty, HidesOnlyWhatSegmentsToEveryPointMeet) {
    std::mt19937 rng(20261207u);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto range = [&](float a, float b) { return a + (b - a) * u(rng); };
    const bool ci = test::in_ci();
    uint64_t hidden = 0, points = 0, fused = 0, queries = 0;
    for (int world = 0; world < (ci ? 60 : 300); ++world) {
        const std::vector<Box> occ = random_boxes_and_panels(rng);
        std::vector<test::TestPolygon> polys;
        for (int i = 0, k = int(rng() % 5); i < k; ++i) {
            const float centre[3] = {range(-10.0f, 10.0f), range(-10.0f, 10.0f), range(-10.0f, 10.0f)};
            polys.push_back(test::random_polygon(rng, centre, 7.0f, 0.05f));
        }
        float eye[3];
        if (!eye_outside(occ, rng, eye)) continue;
        const int columns = world % 3 == 0 ? 16 : world % 3 == 1 ? 128 : 1024;
        Horizon h(columns, 1 << 18);
        h.frame(eye, occ, polys);
        const auto behind = [&](const double p[3], double grow) {
            return std::any_of(occ.begin(), occ.end(),
                               [&](const Box& o) { return segment_meets_grown_box(eye, p, o, grow); }) ||
                   std::any_of(polys.begin(), polys.end(), [&](const test::TestPolygon& t) {
                       return test::segment_crosses_polygon(eye, p, t, grow);
                   });
        };
        for (int q = 0; q < 60; ++q) {
            Box qb = query_behind(occ, eye, rng);
            if (q % 2 == 1) {  // a long box, reaching across depths where different occluders serve it
                const int a = int(rng() % 3);
                const float len = range(2.0f, 12.0f);
                (rng() % 2 ? qb.max[a] : qb.min[a]) += rng() % 2 ? len : -len;
                if (qb.min[a] > qb.max[a]) std::swap(qb.min[a], qb.max[a]);
            }
            ++queries;
            if (!h.hidden(qb)) continue;
            ++hidden;
            for (int n = 0; n < 64; ++n) {
                double p[3];
                sample_point(qb, n, rng, p);
                ++points;
                ASSERT_TRUE(behind(p, 1e-6)) << "world " << world << " box " << q << " point " << n;
            }
            bool one_alone = false;  // hidden by a single occluder's horizon too?
            for (const Box& o : occ) {
                Horizon single(columns);
                single.frame(eye, {o});
                if (single.hidden(qb)) {
                    one_alone = true;
                    break;
                }
            }
            fused += !one_alone;
        }
    }
    std::printf("horizon: %llu of %llu boxes hidden (%llu points checked), %llu by no single box\n",
                (unsigned long long)hidden, (unsigned long long)queries, (unsigned long long)points,
                (unsigned long long)fused);
    EXPECT_GT(hidden, queries / 10);
    EXPECT_GT(fused, 0u);
}

}  // namespace
}  // namespace pvs
