// SPDX-License-Identifier: MIT
// Convex caps (pvs/convex_cap.h): the hull of opaque polygons meeting at edges, checked against dense
// segments tested polygon by polygon (the slow reference), and their construction on small scenes.
#include "pvs/convex_cap.h"

#include "core/random.h"
#include "pvs/region_hiding.h"
#include "tests/slanted_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pvs {
namespace {

CapPolygon polygon(std::vector<glm::dvec3> corners) {
    CapPolygon p;
    p.corners = std::move(corners);
    p.normal = glm::normalize(glm::cross(p.corners[1] - p.corners[0], p.corners[2] - p.corners[0]));
    p.offset = glm::dot(p.normal, p.corners[0]);
    return p;
}

// Does the segment meet one of the polygons (each cut into a fan of triangles)?
bool meets_any(const std::vector<CapPolygon>& ps, const glm::dvec3& q, const glm::dvec3& x) {
    for (const CapPolygon& p : ps)
        for (size_t i = 1; i + 1 < p.corners.size(); ++i)
            if (test::segment_meets_triangle(q, x, p.corners[0], p.corners[i], p.corners[i + 1])) return true;
    return false;
}

glm::dvec3 point_in(const Aabb& b, Rng& rng) {
    return glm::dvec3(b.min) +
           glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * glm::dvec3(b.max - b.min);
}

// The two sides of an L: x = 0 for z in [0, 4], z = 0 for x in [0, 4], both y in [0, 3].
std::vector<CapPolygon> corner() {
    return {polygon({{0, 0, 0}, {0, 3, 0}, {0, 3, 4}, {0, 0, 4}}), polygon({{0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 0}})};
}

// Seen from outside the L, the cap is the prism x >= 0, z >= 0, x + z <= 4 between y = 0 and 3: five faces,
// the two walls opaque. From inside the L no neighbour bends away.
TEST(ConvexCap, TheOuterCornerOfAnLIsAPrismWithTwoOpaqueFaces) {
    const std::vector<CapPolygon> ps = corner();
    const std::vector<ConvexCap> caps = build_caps(ps);
    ASSERT_EQ(caps.size(), 4u);
    // Polygon 0's normal: +x or -x, whichever the corners' order gave; its outer side is x < 0.
    const size_t outer = ps[0].normal.x < 0.0 ? 0 : 1;
    const ConvexCap& cap = caps[outer];
    ASSERT_FALSE(cap.empty());
    EXPECT_EQ(cap.polygons, 2u);
    EXPECT_EQ(cap.normal.size(), 5u);
    int opaque = 0;
    for (uint8_t o : cap.opaque) opaque += o;
    EXPECT_EQ(opaque, 2);
    EXPECT_TRUE(caps[1 - outer].empty()) << "from inside the L a cap was made";
    // From a cell outside the corner, an object inside it is hidden; from a cell beside the wall's end
    // (which sees the prism's slanted face), it is not.
    const Aabb object = Aabb::of({1.0f, 1.0f, 1.0f}, {1.5f, 2.0f, 1.5f});
    EXPECT_TRUE(cap_hides(cap, Aabb::of({-2.0f, 1.0f, -2.0f}, {-1.0f, 2.0f, -1.0f}), object));
    EXPECT_FALSE(cap_hides(cap, Aabb::of({-2.0f, 1.0f, 4.5f}, {-1.0f, 2.0f, 5.5f}), object));
    // An eye above the walls' top sees the prism's top face, which is open.
    EXPECT_FALSE(cap_hides(cap, Aabb::of({-2.0f, 3.5f, -2.0f}, {-1.0f, 4.0f, -1.0f}), object));
}

// With a gap of 2 cm between the two walls there is no shared edge, so no cap.
TEST(ConvexCap, WallsWithAGapMakeNoCap) {
    std::vector<CapPolygon> ps = corner();
    ps[0] = polygon({{0, 0, 0.02}, {0, 3, 0.02}, {0, 3, 4}, {0, 0, 4}});
    for (const ConvexCap& c : build_caps(ps)) EXPECT_TRUE(c.empty());
}

// The slow reference: random boxes turned at random, two or three faces meeting at a corner or an edge
// taken as the cap's polygons; random pairs of boxes. Whatever cap_hides() claims, no dense segment
// between the boxes misses every polygon; and it claims enough to matter.
TEST(ConvexCap, EverySegmentBetweenBoxesACapHidesMeetsAPolygon) {
    Rng rng(29, 3);
    int claimed = 0, pairs = 0;
    for (int trial = 0; trial < 300; ++trial) {
        // A box of half-sizes h, turned by an orthonormal frame, around the origin.
        const glm::dvec3 h(0.5 + 2.0 * rng.uniform(), 0.5 + 2.0 * rng.uniform(), 0.5 + 2.0 * rng.uniform());
        glm::dvec3 e0 = glm::normalize(glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
        glm::dvec3 e1 = glm::normalize(glm::cross(e0, glm::dvec3(0.3, 0.9, -0.2)));
        const glm::dvec3 e2 = glm::cross(e0, e1);
        if (trial % 3 == 0) {  // some boxes on the axes, like panels
            e0 = {1, 0, 0};
            e1 = {0, 1, 0};
        }
        const glm::dvec3 f2 = trial % 3 == 0 ? glm::dvec3(0, 0, 1) : e2;
        const auto at = [&](double a, double b, double c) { return a * h.x * e0 + b * h.y * e1 + c * h.z * f2; };
        // The faces at +e0, +e1 and (for some) +e2.
        std::vector<CapPolygon> ps;
        ps.push_back(polygon({at(1, -1, -1), at(1, 1, -1), at(1, 1, 1), at(1, -1, 1)}));
        ps.push_back(polygon({at(-1, 1, -1), at(-1, 1, 1), at(1, 1, 1), at(1, 1, -1)}));
        if (trial % 2 == 0) ps.push_back(polygon({at(-1, -1, 1), at(1, -1, 1), at(1, 1, 1), at(-1, 1, 1)}));
        const std::vector<ConvexCap> caps = build_caps(ps);
        for (int k = 0; k < 20; ++k) {
            const auto box_near = [&](double reach, double size) {
                const glm::dvec3 c((rng.uniform() - 0.5) * 2.0 * reach, (rng.uniform() - 0.5) * 2.0 * reach,
                                   (rng.uniform() - 0.5) * 2.0 * reach);
                const glm::dvec3 s(size * rng.uniform(), size * rng.uniform(), size * rng.uniform());
                return Aabb::of(glm::vec3(c), glm::vec3(c + s));
            };
            const Aabb from = box_near(8.0, 2.0), to = box_near(1.5, 0.8);
            ++pairs;
            bool hides = false;
            for (const ConvexCap& cap : caps) hides = hides || cap_hides(cap, from, to);
            if (!hides) continue;
            ++claimed;
            for (int s = 0; s < 4000; ++s) {
                const glm::dvec3 q = point_in(from, rng), x = point_in(to, rng);
                ASSERT_TRUE(meets_any(ps, q, x)) << "trial " << trial << ": a segment misses the cap";
            }
        }
    }
    EXPECT_GT(claimed, pairs / 50) << claimed << " of " << pairs;
}

// Turned boxes' faces at +e0, +e1 and +e2 as cap polygons, the caps of a random one.
struct RandomCap {
    std::vector<CapPolygon> polygons;
    std::vector<ConvexCap> caps;
};
RandomCap random_cap(Rng& rng) {
    const glm::dvec3 h(0.5 + 2.0 * rng.uniform(), 0.5 + 2.0 * rng.uniform(), 0.5 + 2.0 * rng.uniform());
    const glm::dvec3 e0 = glm::normalize(glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    const glm::dvec3 e1 = glm::normalize(glm::cross(e0, glm::dvec3(0.3, 0.9, -0.2)));
    const glm::dvec3 e2 = glm::cross(e0, e1);
    const auto at = [&](double a, double b, double c) { return a * h.x * e0 + b * h.y * e1 + c * h.z * e2; };
    RandomCap r;
    r.polygons.push_back(polygon({at(1, -1, -1), at(1, 1, -1), at(1, 1, 1), at(1, -1, 1)}));
    r.polygons.push_back(polygon({at(-1, 1, -1), at(-1, 1, 1), at(1, 1, 1), at(1, 1, -1)}));
    r.polygons.push_back(polygon({at(-1, -1, 1), at(1, -1, 1), at(1, 1, 1), at(-1, 1, 1)}));
    r.caps = build_caps(r.polygons);
    return r;
}

// A cap's cross-section with an axis plane holds only points inside the shrunk hull, and every point deep
// inside it; and every segment from a box the cap guards to a point inside the hull meets a polygon.
TEST(ConvexCap, ASliceLiesInTheHullAndWhatACapGuardsMeetsItsPolygons) {
    Rng rng(31, 7);
    int guarded = 0, sliced = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const RandomCap rc = random_cap(rng);
        for (const ConvexCap& cap : rc.caps) {
            if (cap.empty()) continue;
            const auto depth = [&](const glm::dvec3& x) {  // how far inside every face
                double d = INFINITY;
                for (size_t f = 0; f < cap.normal.size(); ++f)
                    d = std::min(d, cap.offset[f] - glm::dot(cap.normal[f], x));
                return d;
            };
            const int axis = int(rng.below(3)), u = (axis + 1) % 3, v = (axis + 2) % 3;
            const double c = (rng.uniform() - 0.5) * 4.0;
            std::vector<glm::dvec2> slice, scratch;
            cap_slice(cap, axis, c, glm::dvec2(-5.0), glm::dvec2(5.0), slice, scratch);
            sliced += slice.empty() ? 0 : 1;
            for (int s = 0; s < 2000; ++s) {
                glm::dvec3 x;
                x[axis] = c;
                x[u] = (rng.uniform() - 0.5) * 10.0;
                x[v] = (rng.uniform() - 0.5) * 10.0;
                bool in = slice.size() >= 3;
                for (size_t i = 0; i < slice.size() && in; ++i) {
                    const glm::dvec2 a = slice[i], b = slice[(i + 1) % slice.size()];
                    in = (b.x - a.x) * (x[v] - a.y) - (b.y - a.y) * (x[u] - a.x) >= 0.0;
                }
                const double d = depth(x);
                if (in) ASSERT_GT(d, kHideToleranceM - 1e-9) << "a point of the slice lies outside the shrunk hull";
                if (d > kHideToleranceM + 1e-6) ASSERT_TRUE(in) << "a point deep in the hull is not in the slice";
            }
            // A box the cap guards: every segment from it to a point of the hull meets a polygon first.
            const glm::dvec3 c0((rng.uniform() - 0.5) * 16.0, (rng.uniform() - 0.5) * 16.0,
                                (rng.uniform() - 0.5) * 16.0);
            const Aabb from = Aabb::of(glm::vec3(c0), glm::vec3(c0 + 1.5 * glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform())));
            if (!cap_guards(cap, from)) continue;
            ++guarded;
            for (int s = 0; s < 2000; ++s) {
                const glm::dvec3 x((rng.uniform() - 0.5) * 6.0, (rng.uniform() - 0.5) * 6.0,
                                   (rng.uniform() - 0.5) * 6.0);
                if (depth(x) <= kHideToleranceM) continue;
                ASSERT_TRUE(meets_any(rc.polygons, point_in(from, rng), x))
                    << "a segment from a guarded box reaches the hull's inside past the polygons";
            }
        }
    }
    EXPECT_GT(guarded, 20);
    EXPECT_GT(sliced, 50);
}

}  // namespace
}  // namespace pvs
