// SPDX-License-Identifier: MIT
// The single-occluder pass (pvs/region_hiding.h): exact tests of one panel or one box between a region
// and an object, checked against many random segments, and the hider on a small scene.
#include "core/random.h"
#include "occluders/slanted_panels.h"
#include "pvs/region_hiding.h"
#include "tests/random_boxes.h"
#include "tests/slanted_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

namespace pvs {
namespace {

using test::bumpy_sheet;
using test::point_in;
using test::random_box;
using test::segment_meets_triangle;

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Does the segment p -> x cross the closed flat rectangle `panel` (flat along `axis`)?
bool crosses(glm::vec3 p, glm::vec3 x, const Aabb& panel, int axis) {
    const double c = panel.min[axis];
    const double dp = p[axis] - c, dx = x[axis] - c;
    if (dp * dx > 0.0) return false;
    const double t = dp / (dp - dx);
    for (int k = 0; k < 3; ++k) {
        if (k == axis) continue;
        const double y = double(p[k]) + t * (double(x[k]) - double(p[k]));
        if (y < panel.min[k] || y > panel.max[k]) return false;
    }
    return true;
}

bool meets(glm::vec3 p, glm::vec3 x, const Aabb& box) {
    float t0, t1;
    const glm::vec3 d = x - p;
    const float len = glm::length(d);
    return len > 0.0f && ray_box_interval(p, d / len, box, len, t0, t1);
}

// Whenever panel_hides() says so, every one of many random segments from the region to the object crosses
// the panel; and it says so often enough for that to mean something.
TEST(RegionHiding, APanelThatHidesIsCrossedByEverySegment) {
    Rng rng(11, 3);
    int hides = 0, trials = 0;
    for (int i = 0; i < 20000 && hides < 300; ++i) {
        const int axis = int(rng.below(3));
        Aabb panel = random_box(rng, 4.0f, 12.0f);
        panel.min[axis] = panel.max[axis] = (rng.uniform() - 0.5f) * 2.0f;
        Aabb region = random_box(rng, 3.0f, 2.0f), object = random_box(rng, 3.0f, 2.0f);
        if (rng.uniform() < 0.3f) region.max[axis] = region.min[axis];  // flat regions (cell faces) too
        // Put the region before the plane and the object beyond it, most of the time.
        const float shift_r = panel.min[axis] - 0.2f - region.max[axis] - 3.0f * rng.uniform();
        const float shift_o = panel.min[axis] + 0.2f - object.min[axis] + 6.0f * rng.uniform();
        region.min[axis] += shift_r;
        region.max[axis] += shift_r;
        object.min[axis] += shift_o;
        object.max[axis] += shift_o;
        if (rng.uniform() < 0.5f) std::swap(region, object);
        ++trials;
        if (!panel_hides(region, object, panel, axis)) continue;
        ++hides;
        for (int s = 0; s < 2000; ++s) {
            const glm::vec3 p = point_in(region, rng), x = point_in(object, rng);
            ASSERT_TRUE(crosses(p, x, panel, axis)) << "trial " << i << ", segment " << s;
        }
        // Each corner too (the extremes).
        for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b) {
                const glm::vec3 p(a & 1 ? region.max.x : region.min.x, a & 2 ? region.max.y : region.min.y,
                                  a & 4 ? region.max.z : region.min.z);
                const glm::vec3 x(b & 1 ? object.max.x : object.min.x, b & 2 ? object.max.y : object.min.y,
                                  b & 4 ? object.max.z : object.min.z);
                ASSERT_TRUE(crosses(p, x, panel, axis));
            }
    }
    EXPECT_GE(hides, 100) << "of " << trials << " trials: the test is vacuous";
    EXPECT_LT(hides, trials);
}

TEST(RegionHiding, ABoxThatHidesIsMetByEverySegment) {
    Rng rng(12, 4);
    int hides = 0, trials = 0;
    for (int i = 0; i < 40000 && hides < 300; ++i) {
        const Aabb box = random_box(rng, 2.0f, 6.0f);
        const int axis = int(rng.below(3));
        Aabb region = random_box(rng, 3.0f, 1.5f), object = random_box(rng, 3.0f, 1.5f);
        const float shift_r = box.min[axis] - region.max[axis] - 3.0f * rng.uniform();
        const float shift_o = box.max[axis] - object.min[axis] + 3.0f * rng.uniform() - 0.5f;
        region.min[axis] += shift_r;
        region.max[axis] += shift_r;
        object.min[axis] += shift_o;
        object.max[axis] += shift_o;
        ++trials;
        if (!box_hides(region, object, box)) continue;
        ++hides;
        for (int s = 0; s < 2000; ++s) {
            const glm::vec3 p = point_in(region, rng), x = point_in(object, rng);
            ASSERT_TRUE(meets(p, x, box)) << "trial " << i << ", segment " << s;
        }
    }
    EXPECT_GE(hides, 100) << "of " << trials << " trials: the test is vacuous";
    EXPECT_LT(hides, trials);
}

// Touching the plane, or reaching past the panel's edge by a hair, is not hidden.
TEST(RegionHiding, EdgesAndContactAreNotHidden) {
    const Aabb panel = Aabb::of({0, 0, 5}, {4, 4, 5});  // flat along z at 5
    const Aabb region = Aabb::of({1, 1, 0}, {3, 3, 1});
    const Aabb behind = Aabb::of({1.5f, 1.5f, 6}, {2.5f, 2.5f, 7});
    EXPECT_TRUE(panel_hides(region, behind, panel, 2));
    EXPECT_TRUE(panel_hides(behind, region, panel, 2));  // either way round
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 5}, {2.5f, 2.5f, 7}), panel, 2));  // touches it
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 3}, {2.5f, 2.5f, 4}), panel, 2));  // in front
    // The object's far corner seen past the panel's edge: (3, 3, 1) -> (x, 3, 9) crosses z = 5 at
    // x = 2 + x / 2... make the object wide enough that some segment passes x > 4.
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 8}, {5.2f, 2.5f, 9}), panel, 2));
    const Aabb box = Aabb::of({0, 0, 4}, {4, 4, 5});
    EXPECT_TRUE(box_hides(region, behind, box));
    EXPECT_FALSE(box_hides(region, Aabb::of({1.5f, 1.5f, 8}, {5.2f, 2.5f, 9}), box));
}

// Whenever slanted_hides() says so, every one of many random segments from the region to the object meets
// one of the sheet's triangles (flat and bumpy sheets); and it says so often enough to mean something.
TEST(RegionHiding, ASlantedPanelThatHidesIsCrossedByEverySegmentThroughItsTriangles) {
    Rng rng(29, 5);
    int hides = 0, trials = 0;
    for (int i = 0; i < 20000 && hides < 300; ++i) {
        glm::dvec3 normal;
        // Flat sheets, sheets bumped by rounding-sized amounts, and sheets bumped by 10 cm (a thick slab:
        // there a test of one plane instead of both slab faces passes segments that miss the triangles).
        const double bumps[3] = {0.0, 0.004, 0.1};
        const double bump = bumps[rng.below(3)];
        const World sheet = bumpy_sheet(rng, 1 + int(rng.below(3)), bump, normal);
        const std::vector<SlantedPanel> panels = find_slanted_panels(sheet, 0.25, 0.0);
        if (panels.empty()) continue;
        const SlantedPanel& panel = *std::max_element(
            panels.begin(), panels.end(),
            [](const SlantedPanel& a, const SlantedPanel& b) { return a.area_m2 < b.area_m2; });
        // Small boxes on either side of the sheet around a random point of the polygon (often near an
        // edge, where segments may leave the slab over the edge).
        glm::dvec3 mid(0.0);
        double weights = 0.0;
        for (const glm::dvec3& c : panel.corners) {
            const double w = std::pow(rng.uniform(), 4.0);
            mid += w * c;
            weights += w;
        }
        mid /= weights;
        auto box_at = [&](double side) {
            const glm::dvec3 c =
                mid + side * (0.05 + 1.0 * rng.uniform()) * panel.normal +
                glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 0.6;
            const glm::dvec3 h = glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * 0.2;
            return Aabb::of(glm::vec3(c - h), glm::vec3(c + h));
        };
        const Aabb region = box_at(-1.0), object = box_at(1.0);
        ++trials;
        if (!slanted_hides(region, object, panel)) continue;
        ++hides;
        for (int k = 0; k < 500; ++k) {
            const glm::dvec3 p = glm::dvec3(point_in(region, rng)), x = glm::dvec3(point_in(object, rng));
            bool hit = false;
            for (const Triangle& t : sheet.triangles) {
                hit = hit || segment_meets_triangle(p, x, glm::dvec3(sheet.positions[t.v[0]]),
                                                    glm::dvec3(sheet.positions[t.v[1]]),
                                                    glm::dvec3(sheet.positions[t.v[2]]));
            }
            ASSERT_TRUE(hit) << "trial " << i << ", segment " << k;
        }
    }
    EXPECT_GE(hides, 50) << "of " << trials << " trials: the test is vacuous";
    EXPECT_LT(hides, trials);
}

// Boxes that reach into the slab, or whose segments pass beside the polygon, are not hidden.
TEST(RegionHiding, ASlantedPanelHidesNothingPastItsEdgesOrFromInsideItsSlab) {
    Rng rng(3, 1);
    glm::dvec3 normal;
    const World sheet = bumpy_sheet(rng, 2, 0.0, normal);
    const std::vector<SlantedPanel> panels = find_slanted_panels(sheet, 1e-4, 0.0);
    ASSERT_FALSE(panels.empty());
    const SlantedPanel& p = panels.front();
    glm::dvec3 mid(0.0);
    for (const glm::dvec3& c : p.corners) mid += c;
    mid /= double(p.corners.size());
    auto box = [](const glm::dvec3& c, double h) {
        return Aabb::of(glm::vec3(c - glm::dvec3(h)), glm::vec3(c + glm::dvec3(h)));
    };
    EXPECT_TRUE(slanted_hides(box(mid - 0.5 * p.normal, 0.05), box(mid + 0.5 * p.normal, 0.05), p));
    EXPECT_FALSE(slanted_hides(box(mid - 0.5 * p.normal, 0.05), box(mid, 0.05), p));  // in the slab
    EXPECT_FALSE(slanted_hides(box(mid - 0.5 * p.normal, 0.05),
                               box(mid + 0.5 * p.normal + glm::dvec3(5, 5, 5), 0.05),
                               p));  // beside it
}

// The hider finds its candidates by tracing: an object behind a big wall panel is hidden from a region in
// front, one beside the wall, one the region meets and one in front of the wall are not; the same with
// the wall as a box.
TEST(RegionHiding, TheHiderOnASmallScene) {
    Context ctx = quiet_context();
    World w;
    auto add = [&](const Aabb& b) {
        WorldObject o;
        o.bounds = b;
        w.objects.push_back(o);
        return uint32_t(w.objects.size() - 1);
    };
    const uint32_t behind = add(Aabb::of({1, 1, 8}, {2, 2, 9}));
    const uint32_t beside = add(Aabb::of({12, 1, 8}, {13, 2, 9}));
    const uint32_t meets = add(Aabb::of({0, 0, 0}, {1, 1, 1}));
    const uint32_t front = add(Aabb::of({1, 1, 3}, {2, 2, 4}));
    const uint32_t empty = add(Aabb{});
    const std::vector<uint32_t> all{behind, beside, meets, front, empty};
    const Aabb region = Aabb::of({0.5f, 0.5f, 0.5f}, {2.5f, 2.5f, 2.5f});
    for (int as_box = 0; as_box < 2; ++as_box) {
        ShrunkOccluders set;
        set.epsilon_m = {0.1};
        set.boxes.resize(1);
        if (as_box) {
            set.boxes[0].push_back(Aabb::of({-5, -5, 5}, {7, 7, 6}));
        } else {
            set.panels.push_back(Aabb::of({-5, -5, 5}, {7, 7, 5}));
        }
        const RegionHider hider(ctx, set);
        std::vector<uint64_t> hidden(1, 0);
        EXPECT_EQ(hider.hide(w, region, all, hidden.data()), 1u) << (as_box ? "box" : "panel");
        EXPECT_EQ(hidden[0], uint64_t(1) << behind);
    }
    // The same wall tilted by 20 degrees about x, as a slanted panel (a square of two triangles).
    World wall;
    const float c = std::cos(glm::radians(20.0f)), sn = std::sin(glm::radians(20.0f));
    auto at = [&](float x, float y) { return glm::vec3(x, y * c, 5.5f + y * sn); };
    wall.positions = {at(-5, -5), at(7, -5), at(7, 7), at(-5, 7)};
    wall.triangles = {Triangle{{0, 1, 2}}, Triangle{{0, 2, 3}}};
    wall.triangle_opaque = {1, 1};
    wall.triangle_double_sided = {0, 0};
    ShrunkOccluders set;
    set.epsilon_m = {0.1};
    set.boxes.resize(1);
    set.slanted = find_slanted_panels(wall, 1e-4, 0.0);
    ASSERT_EQ(set.slanted.size(), 1u);
    const RegionHider hider(ctx, set);
    std::vector<uint64_t> hidden(1, 0);
    EXPECT_EQ(hider.hide(w, region, all, hidden.data()), 1u) << "slanted";
    EXPECT_EQ(hidden[0], uint64_t(1) << behind);
}

// The hider stops each ray at the first occluder that hides its object; its reference tests every occluder
// each ray touches. On random scenes of boxes, wall panels and tilted walls, both hide the same objects.
TEST(RegionHiding, TheHiderAgreesWithItsReference) {
    Context ctx = quiet_context();
    Rng rng(7, 11);
    for (int scene = 0; scene < 6; ++scene) {
        World w;
        for (int i = 0; i < 300; ++i) {
            WorldObject o;
            o.bounds = random_box(rng, 40.0f, 1.5f);
            w.objects.push_back(o);
        }
        World walls;
        for (int i = 0; i < 20; ++i) {  // tilted squares of two triangles
            const glm::vec3 c = point_in(Aabb::of(glm::vec3(-20.0f), glm::vec3(20.0f)), rng);
            const float a = glm::radians(10.0f + 70.0f * rng.uniform()), half = 2.0f + 4.0f * rng.uniform();
            const glm::vec3 u(std::cos(a), std::sin(a), 0.0f), v(0.0f, 0.0f, 1.0f);
            const uint32_t base = uint32_t(walls.positions.size());
            for (const glm::vec2 s : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)})
                walls.positions.push_back(c + half * (s.x * u + s.y * v));
            walls.triangles.push_back(Triangle{{base, base + 1, base + 2}});
            walls.triangles.push_back(Triangle{{base, base + 2, base + 3}});
        }
        walls.triangle_opaque.assign(walls.triangles.size(), 1);
        walls.triangle_double_sided.assign(walls.triangles.size(), 0);
        ShrunkOccluders set;
        set.epsilon_m = {0.1};
        set.boxes.resize(1);
        for (int i = 0; i < 60; ++i) set.boxes[0].push_back(random_box(rng, 40.0f, 6.0f));
        for (int i = 0; i < 60; ++i) {
            Aabb p = random_box(rng, 40.0f, 8.0f);
            const int axis = int(rng.below(3));
            p.max[axis] = p.min[axis];
            set.panels.push_back(p);
        }
        set.slanted = find_slanted_panels(walls, 1e-4, 0.0);
        const RegionHider hider(ctx, set);
        std::vector<uint32_t> all(w.objects.size());
        for (uint32_t o = 0; o < all.size(); ++o) all[o] = o;
        uint32_t total = 0;
        for (int r = 0; r < 20; ++r) {
            const Aabb region = random_box(rng, 40.0f, 2.0f);
            std::vector<uint64_t> fast((all.size() + 63) / 64, 0), slow(fast.size(), 0);
            const uint32_t n = hider.hide(w, region, all, fast.data());
            EXPECT_EQ(n, hider.hide_reference(w, region, all, slow.data()))
                << "scene " << scene << " region " << r;
            EXPECT_EQ(fast, slow) << "scene " << scene << " region " << r;
            total += n;
        }
        EXPECT_GT(total, 0u) << "scene " << scene << ": nothing hidden, the test tests nothing";
    }
}

}  // namespace
}  // namespace pvs
