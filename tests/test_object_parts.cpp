// SPDX-License-Identifier: MIT
// Object parts (core/object_parts.h): every point of every triangle lies in a part, parts lie in the
// object's bounds, and the cuts follow the surface where its bounds hold empty space.
#include "core/object_parts.h"
#include "core/random.h"
#include "runtime/pvsr.h"
#include "world_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace pvs {
namespace {

// Appends an object of the given triangles (corners in order).
uint32_t add_triangles(World& world, const std::string& name, const std::vector<glm::vec3>& corners) {
    WorldObject o;
    o.name = name;
    o.first_triangle = uint32_t(world.triangles.size());
    o.flags = kObjectHasOpaque;
    for (size_t k = 0; k + 2 < corners.size(); k += 3) {
        const uint32_t base = uint32_t(world.positions.size());
        for (int c = 0; c < 3; ++c) {
            world.positions.push_back(corners[k + size_t(c)]);
            o.bounds.extend(corners[k + size_t(c)]);
        }
        world.triangles.push_back(Triangle{{base, base + 1, base + 2}});
        world.triangle_opaque.push_back(1);
        world.triangle_double_sided.push_back(1);
    }
    o.triangle_count = uint32_t(world.triangles.size()) - o.first_triangle;
    world.bounds.extend(o.bounds);
    world.objects.push_back(o);
    return uint32_t(world.objects.size() - 1);
}

// Two triangles of the rectangle [x0, x1] x [z0, z1] at height y.
void add_rectangle(std::vector<glm::vec3>& corners, float x0, float x1, float z0, float z1, float y) {
    corners.insert(corners.end(),
                   {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z0}, {x1, y, z1}, {x0, y, z1}});
}

bool in_some(const std::vector<Aabb>& parts, glm::vec3 p) {
    for (const Aabb& b : parts)
        if (b.contains(p)) return true;
    return false;
}

// Every corner, every point along every edge and inside of every triangle, as floats, lies in a part; the
// parts lie in the bounds and are at most as many as asked.
void expect_covering(const World& world, uint32_t o, uint32_t max_parts, Rng& rng) {
    const std::vector<Aabb> parts = object_part_boxes(world, o, max_parts);
    const WorldObject& obj = world.objects[o];
    ASSERT_FALSE(parts.empty());
    EXPECT_LE(parts.size(), size_t(max_parts));
    for (const Aabb& b : parts) {
        EXPECT_FALSE(b.is_empty());
        EXPECT_TRUE(obj.bounds.contains(b.min) && obj.bounds.contains(b.max));
    }
    for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
        const glm::dvec3 a(world.positions[world.triangles[t].v[0]]),
            b(world.positions[world.triangles[t].v[1]]), c(world.positions[world.triangles[t].v[2]]);
        for (int k = 0; k < 200; ++k) {
            double u = rng.uniform(), v = rng.uniform();
            if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
            if (k < 3)
                u = k == 1, v = k == 2;  // the corners
            else if (k < 60 && k % 3 == 0)
                v = 0.0;  // along edge a-b
            else if (k < 60 && k % 3 == 1)
                u = 0.0;  // along edge a-c
            else if (k < 60)
                v = 1.0 - u;  // along edge b-c
            const glm::dvec3 p = a + u * (b - a) + v * (c - a);
            EXPECT_TRUE(in_some(parts, glm::vec3(p))) << obj.name << " max " << max_parts << " triangle " << t
                                                      << " point " << p.x << " " << p.y << " " << p.z;
        }
    }
}

// The runtime file's grid of parts (5.1, pvsr_part_encode): over bounds of every scale, from a millimetre to
// ten kilometres across and from the origin to a million metres away, a part's box holds the part, lies in
// the bounds, is within about 2^-15 of the bounds' span of the part on each side, and encodes to itself (so
// a bake's parts, already on the grid, are stored as they are); what is not a box inside finite bounds is
// refused.
TEST(ObjectParts, PartsOnTheRuntimeGridHoldThePartAndEncodeToThemselves) {
    Rng rng(11, 1);
    int tested = 0;
    for (int t = 0; t < 20000; ++t) {
        const float scale = std::pow(10.0f, -3.0f + 7.0f * rng.uniform());
        const float away =
            t % 4 == 0 ? 0.0f : std::pow(10.0f, 6.0f * rng.uniform()) * (rng.uniform() < 0.5f ? -1 : 1);
        float bounds[6], part[6];
        for (int a = 0; a < 3; ++a) {
            const float x = away + scale * (rng.uniform() - 0.5f), y = away + scale * (rng.uniform() - 0.5f);
            bounds[a] = std::min(x, y);
            bounds[a + 3] = t % 7 == 0 && a == 1 ? bounds[a] : std::max(x, y);  // some flat
            const float u = rng.uniform(), v = rng.uniform();
            part[a] = bounds[a] + std::min(u, v) * (bounds[a + 3] - bounds[a]);
            part[a + 3] = bounds[a] + std::max(u, v) * (bounds[a + 3] - bounds[a]);
            part[a] = std::clamp(part[a], bounds[a], bounds[a + 3]);
            part[a + 3] = std::clamp(part[a + 3], part[a], bounds[a + 3]);
        }
        uint16_t steps[6], again[6];
        float box[6], box2[6];
        ASSERT_TRUE(pvsr_part_encode(bounds, part, steps, box)) << t;
        double span = 0.0, far = 0.0;
        for (int a = 0; a < 3; ++a) {
            span = std::max(span, double(bounds[a + 3]) - double(bounds[a]));
            far = std::max({far, std::fabs(double(bounds[a])), std::fabs(double(bounds[a + 3]))});
        }
        const double slack = std::max(span * std::ldexp(1.0, -15), far * std::ldexp(1.0, -23));
        for (int a = 0; a < 3; ++a) {
            EXPECT_TRUE(bounds[a] <= box[a] && box[a] <= part[a] && part[a + 3] <= box[a + 3] &&
                        box[a + 3] <= bounds[a + 3])
                << t << " axis " << a;
            EXPECT_LE(double(part[a]) - double(box[a]), slack) << t;
            EXPECT_LE(double(box[a + 3]) - double(part[a + 3]), slack) << t;
        }
        ASSERT_TRUE(pvsr_part_encode(bounds, box, again, box2));
        EXPECT_EQ(std::memcmp(box, box2, sizeof box), 0) << t;
        EXPECT_EQ(std::memcmp(steps, again, sizeof steps), 0) << t;
        ++tested;
    }
    EXPECT_EQ(tested, 20000);
    const float bounds[6] = {0, 0, 0, 1, 1, 1}, inf = std::numeric_limits<float>::infinity();
    uint16_t steps[6];
    float box[6];
    const float outside[6] = {0, 0, 0, 1, 2, 1}, upside[6] = {0.5f, 0, 0, 0.25f, 1, 1};
    const float open[6] = {0, 0, 0, inf, 1, 1}, nan[6] = {0, std::nanf(""), 0, 1, 1, 1};
    EXPECT_FALSE(pvsr_part_encode(bounds, outside, steps, box));
    EXPECT_FALSE(pvsr_part_encode(bounds, upside, steps, box));
    EXPECT_FALSE(pvsr_part_encode(open, bounds, steps, box));
    EXPECT_FALSE(pvsr_part_encode(bounds, nan, steps, box));
    EXPECT_TRUE(pvsr_part_encode(bounds, bounds, steps, box));
    EXPECT_EQ(std::memcmp(box, bounds, sizeof box), 0);
}

TEST(ObjectParts, EveryPointOfEveryTriangleLiesInAPart) {
    Rng rng(7, 11);
    World world;
    for (int i = 0; i < 12; ++i) {  // soups of random triangles, some long and thin, at odd coordinates
        std::vector<glm::vec3> corners;
        const glm::vec3 origin(float(rng.uniform() * 200 - 100), float(rng.uniform() * 20),
                               float(rng.uniform() * 200));
        const int n = 1 + int(rng.uniform() * 40);
        for (int k = 0; k < 3 * n; ++k)
            corners.push_back(origin + glm::vec3(float(rng.uniform() * 7.3),
                                                 float(rng.uniform() * (i % 3 == 0 ? 0.0 : 2.1)),
                                                 float(rng.uniform() * 5.9)));
        add_triangles(world, "soup" + std::to_string(i), corners);
    }
    for (uint32_t o = 0; o < uint32_t(world.objects.size()); ++o)
        for (const uint32_t max_parts : {1u, 2u, 3u, 8u, 64u}) expect_covering(world, o, max_parts, rng);
}

// An L-shaped floor: its bounds hold a quarter of empty floor, which its parts leave out (a cut at the
// inner corner), where the median of the triangles' centres cuts across it.
TEST(ObjectParts, AnLShapedFloorIsCutAlongItsShape) {
    World world;
    std::vector<glm::vec3> corners;
    add_rectangle(corners, 0, 8, 0, 4, 0);
    add_rectangle(corners, 0, 4, 4, 8, 0);
    const uint32_t o = add_triangles(world, "floor", corners);
    for (const uint32_t max_parts : {2u, 8u}) {
        const std::vector<Aabb> parts = object_part_boxes(world, o, max_parts);
        double area = 0.0;
        for (const Aabb& b : parts) area += double(b.size().x) * double(b.size().z);
        EXPECT_NEAR(area, 48.0, 1e-3) << max_parts << " parts: the L, not its bounds (64)";
        EXPECT_FALSE(in_some(parts, {6, 0, 6})) << "the empty quarter";
    }
    const ObjectParts all = object_parts(world, 8);
    EXPECT_EQ(all.count(o), 2u) << "two rectangles, and no cut of them saves more";
    Rng rng(3, 5);
    expect_covering(world, o, 8, rng);
}

// A closed box fills its bounds: its parts would hold more than the bounds, so it keeps none; nor does an
// object flagged always visible; and the same world gives the same parts.
TEST(ObjectParts, CompactAndAlwaysVisibleObjectsKeepNone) {
    World world;
    test::add_box(world, "crate", Aabb::of({0, 0, 0}, {1, 1, 1}));
    std::vector<glm::vec3> corners;
    add_rectangle(corners, 0, 8, 0, 4, 0);
    add_rectangle(corners, 0, 4, 4, 8, 0);
    const uint32_t floor = add_triangles(world, "floor", corners);
    const uint32_t sky = add_triangles(world, "sky", corners);
    world.objects[sky].flags |= kObjectAlwaysVisible;
    const ObjectParts parts = object_parts(world, 8);
    EXPECT_EQ(parts.count(0), 0u);
    EXPECT_GE(parts.count(floor), 2u);
    EXPECT_EQ(parts.count(sky), 0u);
    const ObjectParts again = object_parts(world, 8);
    EXPECT_EQ(again.offsets, parts.offsets);
    EXPECT_EQ(again.boxes, parts.boxes);
    EXPECT_TRUE(object_parts(world, 1).offsets.empty());
}

}  // namespace
}  // namespace pvs
