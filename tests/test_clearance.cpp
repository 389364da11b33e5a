// SPDX-License-Identifier: MIT
// Sight-line widths (rays/clearance.h): the exact segment-triangle distance against dense sampling, the
// Embree gather of triangles near a segment against testing every triangle, and the width of lines through
// slits of known width.
#include "core/context.h"
#include "core/random.h"
#include "rays/clearance.h"
#include "rays/ray_scene.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace pvs {
namespace {

using glm::dvec3;

dvec3 random_point(Rng& rng, double scale) {
    return dvec3(rng.uniform() * 2 - 1, rng.uniform() * 2 - 1, rng.uniform() * 2 - 1) * scale;
}

// The distance by brute force: points of the segment against points of the triangle, both dense.
double sampled_distance(dvec3 p, dvec3 q, dvec3 a, dvec3 b, dvec3 c, int n) {
    double best = 1e30;
    for (int i = 0; i <= n; ++i) {
        const dvec3 s = p + (q - p) * (double(i) / n);
        for (int j = 0; j <= n; ++j) {
            for (int k = 0; j + k <= n; ++k) {
                const dvec3 t = a + (b - a) * (double(j) / n) + (c - a) * (double(k) / n);
                best = std::min(best, glm::length(s - t));
            }
        }
    }
    return best;
}

TEST(Clearance, SegmentTriangleDistanceAgreesWithDenseSampling) {
    Rng rng(17, 0);
    for (int trial = 0; trial < 300; ++trial) {
        const dvec3 p = random_point(rng, 1.0), q = random_point(rng, 1.0);
        const dvec3 a = random_point(rng, 1.0), b = random_point(rng, 1.0), c = random_point(rng, 1.0);
        const double exact = segment_triangle_distance(p, q, a, b, c);
        const int n = 60;
        const double sampled = sampled_distance(p, q, a, b, c, n);
        // The sampled pair is a real pair: never nearer than the exact distance; and the exact pair is
        // within half a sample spacing (on each set) of sampled points.
        const double spacing = 2.0 * std::sqrt(3.0) * 2.0 / n;
        EXPECT_GE(sampled, exact - 1e-9) << "trial " << trial;
        EXPECT_LE(sampled, exact + spacing) << "trial " << trial;
    }
}

// The nearest point of a triangle against a fine barycentric lattice of it: on the triangle, never
// farther than the best lattice point, and the lattice's best within its spacing.
TEST(Clearance, ClosestPointOnTriangleAgreesWithDenseSampling) {
    Rng rng(23, 0);
    for (int trial = 0; trial < 300; ++trial) {
        const dvec3 p = random_point(rng, 1.0);
        const dvec3 a = random_point(rng, 1.0), b = random_point(rng, 1.0), c = random_point(rng, 1.0);
        const dvec3 q = closest_point_on_triangle(p, a, b, c);
        const int n = 200;
        double best = 1e300;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const dvec3 s = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
                best = std::min(best, glm::length(p - s));
            }
        const double spacing = (glm::length(b - a) + glm::length(c - a)) / n;
        EXPECT_LE(glm::length(p - q), best + 1e-9) << "trial " << trial;
        EXPECT_GE(glm::length(p - q), best - spacing) << "trial " << trial;
        // q lies in the triangle's plane and within it (its distance to the triangle is 0).
        EXPECT_NEAR(segment_triangle_distance(q, q, a, b, c), 0.0, 1e-9) << "trial " << trial;
    }
    // A degenerate triangle (a segment): the nearest point of that segment.
    const dvec3 q = closest_point_on_triangle({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0.25, 0, 0});
    EXPECT_NEAR(glm::length(q - dvec3(0.5, 0, 0)), 0.0, 1e-12);
}

TEST(Clearance, CrossingTouchingAndParallelCases) {
    const dvec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    EXPECT_EQ(segment_triangle_distance({0.2, 0.2, -1}, {0.2, 0.2, 1}, a, b, c), 0.0);  // through it
    EXPECT_NEAR(segment_triangle_distance({0.2, 0.2, 0.5}, {0.2, 0.2, 1}, a, b, c), 0.5, 1e-12);  // above
    EXPECT_NEAR(segment_triangle_distance({2, 0, 0.25}, {2, 1, 0.25}, a, b, c), std::hypot(1.0, 0.25),
                1e-12);  // parallel, off to the side
    EXPECT_NEAR(segment_triangle_distance({-1, -1, 0}, {-1, 2, 0}, a, b, c), 1.0, 1e-12);  // in its plane
    EXPECT_NEAR(segment_triangle_distance({0.3, 0.3, 0.1}, {0.3, 0.3, 0.1}, a, b, c), 0.1, 1e-12);  // a point
    // A degenerate triangle (a segment): the distance to that segment.
    EXPECT_NEAR(segment_triangle_distance({0.5, 1, 0}, {0.5, 2, 0}, a, b, dvec3(0.5, 0, 0)), 1.0, 1e-12);
}

TEST(Clearance, EmbreeGatherHoldsEveryTriangleTheReferenceFinds) {
    Rng rng(5, 0);
    World world;
    for (int i = 0; i < 60; ++i) {
        const glm::vec3 lo(float(rng.uniform() * 20), float(rng.uniform() * 6), float(rng.uniform() * 20));
        const glm::vec3 size(float(0.05 + rng.uniform() * 2), float(0.05 + rng.uniform() * 2),
                             float(0.05 + rng.uniform() * 2));
        test::add_box(world, "box" + std::to_string(i), Aabb::of(lo, lo + size), i % 7 != 0);
    }
    Context ctx;
    const RayScene scene(ctx, world);
    for (int trial = 0; trial < 200; ++trial) {
        const glm::vec3 p(float(rng.uniform() * 22 - 1), float(rng.uniform() * 8 - 1),
                          float(rng.uniform() * 22 - 1));
        const glm::vec3 q(float(rng.uniform() * 22 - 1), float(rng.uniform() * 8 - 1),
                          float(rng.uniform() * 22 - 1));
        const float radius = trial % 2 ? 0.001f : float(rng.uniform() * 0.5);
        std::vector<TriangleCorners> fast;
        scene.opaque_triangles_near(p, q, radius, fast);
        const std::vector<TriangleCorners> reference =
            opaque_triangles_near_segment_reference(world, p, q, radius);
        for (const TriangleCorners& r : reference) {
            const bool found = std::any_of(fast.begin(), fast.end(), [&](const TriangleCorners& f) {
                return f.a == r.a && f.b == r.b && f.c == r.c;
            });
            EXPECT_TRUE(found) << "trial " << trial << ": a triangle within " << radius
                               << " m was not gathered";
        }
        // And the distance both give is the same.
        EXPECT_DOUBLE_EQ(distance_to_triangles(p, q, fast, radius),
                         distance_to_triangles(p, q, reference, radius))
            << "trial " << trial;
    }
}

// A wall 0.2 m thick across x = [0, 0.2] with a vertical slit of width `gap` centred on z = 0 (two boxes).
World slit_world(float gap) {
    World world;
    test::add_box(world, "left", Aabb::of({0, -2, -3}, {0.2f, 2, -0.5f * gap}));
    test::add_box(world, "right", Aabb::of({0, -2, 0.5f * gap}, {0.2f, 2, 3}));
    return world;
}

TEST(Clearance, ALineThroughASlitIsAsWideAsTheSlitLessTwiceItsOffset) {
    Context ctx;
    for (const float gap : {0.0005f, 0.002f, 0.01f, 0.05f, 0.25f}) {
        const World world = slit_world(gap);
        const RayScene scene(ctx, world);
        const float resolution = gap * 0.01f;
        // Through the middle, perpendicular to the wall: exactly the gap.
        EXPECT_NEAR(sight_line_width(scene, {-2, 0, 0}, {2, 0, 0}, kNoObject, 1.0f, resolution), gap,
                    2 * resolution)
            << "gap " << gap;
        // Offset by a quarter of the gap: half the gap.
        EXPECT_NEAR(
            sight_line_width(scene, {-2, 0, 0.25f * gap}, {2, 0, 0.25f * gap}, kNoObject, 1.0f, resolution),
            0.5f * gap, 2 * resolution)
            << "gap " << gap;
        EXPECT_TRUE(sight_line_at_least(scene, {-2, 0, 0}, {2, 0, 0}, kNoObject, 0.99f * gap)) << gap;
        EXPECT_FALSE(sight_line_at_least(scene, {-2, 0, 0}, {2, 0, 0}, kNoObject, 1.01f * gap)) << gap;
        // Aslant through a slit in a wall 0.2 m thick: narrower than the slit.
        const float slant =
            sight_line_width(scene, {-2, 0, -0.5f}, {2, 0, 0.5f}, kNoObject, 1.0f, resolution);
        EXPECT_LT(slant, gap);
    }
}

TEST(Clearance, TheEndsOfTheLineMayTouchSurfaces) {
    // The point seen lies on a wall and the eye stands 1 mm from another: a 10 cm line between them is
    // still 10 cm wide only if nothing else comes near its core.
    World world;
    test::add_box(world, "target", Aabb::of({1, -1, -1}, {1.1f, 1, 1}));
    test::add_box(world, "behind_eye", Aabb::of({-1.101f, -1, -1}, {-1.001f, 1, 1}));
    Context ctx;
    const RayScene scene(ctx, world);
    EXPECT_NEAR(sight_line_width(scene, {-1, 0, 0}, {1, 0, 0}, kNoObject, 0.5f, 1e-4f), 0.5f, 1e-4f);
    // Met aslant, the surface seen comes nearer the core than half the width: its own triangles do not
    // count, another object's do.
    const glm::vec3 aslant_eye(-0.5f, 0, -0.8f);
    EXPECT_NEAR(sight_line_width(scene, aslant_eye, {1, 0, 0}, 0, 0.5f, 1e-4f), 0.5f, 1e-4f);
    EXPECT_LT(sight_line_width(scene, aslant_eye, {1, 0, 0}, kNoObject, 0.5f, 1e-4f), 0.5f);
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

// A witness aslant through a slit wider than the tolerance, in a thick wall, is itself narrow: the search
// must turn the line towards the slit's normal, not only shift it, or a real miss would pass as narrow.
TEST(Clearance, TheSearchNearAWitnessTurnsAnObliqueLineThroughAWideSlit) {
    Context ctx;
    const float tolerance = 0.001f, gap = 0.004f;  // the wall is 0.2 m thick
    World world = slit_world(gap);
    const uint32_t target = test::add_box(world, "target", Aabb::of({3, -1, -1}, {3.5f, 1, 1}));
    const RayScene scene(ctx, world);
    const auto anywhere = [](glm::vec3) { return true; };
    for (const float slope : {0.016f, 0.0175f}) {
        // Through the middle of the slit at x = 0.1, climbing `slope` in z per metre of x.
        const glm::vec3 eye(-2, 0.3f, -2.1f * slope);
        const glm::vec3 seen(3, 0.3f, 2.9f * slope);
        const float witness = sight_line_width(scene, eye, seen, target, tolerance, tolerance * 1e-3f);
        ASSERT_LT(witness, tolerance) << "the witness itself must be narrow for this test";
        for (uint64_t seed = 1; seed <= 8; ++seed) {
            const SightLine line =
                widest_sight_line_near(scene, target, eye, glm::normalize(seen - eye),
                                       glm::length(seen - eye), tolerance, anywhere, 1024, seed);
            EXPECT_GE(line.width_m, tolerance)
                << "slope " << slope << " seed " << seed << ": the witness was " << witness << " m wide";
        }
    }
}

// The verifier's measure of a miss: the widest line found near its ray, to the object it touched.
TEST(Clearance, TheSearchNearAWitnessFindsTheWidthOfTheSlitItPassed) {
    Context ctx;
    const float tolerance = 0.001f;
    const auto anywhere = [](glm::vec3) { return true; };
    for (const float gap : {0.0002f, 0.0005f, 0.004f, 0.05f}) {
        World world = slit_world(gap);
        const uint32_t target = test::add_box(world, "target", Aabb::of({3, -1, -1}, {3.5f, 1, 1}));
        const RayScene scene(ctx, world);
        // A witness grazing one side of the slit (a tenth of the gap from the left wall).
        const glm::vec3 eye(-2, 0.3f, -0.4f * gap);
        const glm::vec3 seen(3, 0.3f, -0.4f * gap);
        const glm::vec3 dir = glm::normalize(seen - eye);
        const SightLine line = widest_sight_line_near(scene, target, eye, dir, glm::length(seen - eye),
                                                      tolerance, anywhere, 256, 9);
        if (gap >= tolerance) {
            EXPECT_GE(line.width_m, tolerance) << "gap " << gap << ": a wide opening must be found wide";
        } else {
            EXPECT_LT(line.width_m, tolerance) << "gap " << gap;
            EXPECT_LE(line.width_m, gap * 1.001f) << "gap " << gap << ": never wider than the slit";
            EXPECT_GE(line.width_m, 0.5f * gap) << "gap " << gap << ": the search moves towards the middle";
        }
    }
}

}  // namespace
}  // namespace pvs
