// SPDX-License-Identifier: MIT
// The shaft pass (pvs/shaft_hiding.h): a plane's cover by panels and the proven solid's slice, held to a
// plain reference on many random segments; with cross-plane fusion, held to whole segments against every
// occluder; the umbra against brute force; walls of two planes that hide together what neither hides alone;
// and the whole proof held to segments from random eyes to random points of the objects it proves hidden.
#include "core/random.h"
#include "pvs/region_hiding.h"
#include "pvs/shaft_hiding.h"
#include "occluders/slanted_panels.h"
#include "tests/random_boxes.h"
#include "tests/slanted_fixtures.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pvs {
namespace {

using test::point_in;
using test::segment_meets_closed_box;

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

constexpr float kPanelZ = 5.0f;
constexpr float kVoxel = 0.25f;

// Panels in the plane z = 5: A and B share the side x = 2; C starts 1 mm after B ends (x = 4); D lies over
// the three. The proven solid: voxels of 0.25 m from (-1, -1, -1), solid for z in [7, 8], x in [0, 5],
// y in [0, 4], but for the column at x in [2, 2.25], y in [1, 1.25] (a hole through the slab).
ShrunkOccluders make_occluders() {
    ShrunkOccluders occ;
    occ.epsilon_m = {0.1};
    occ.boxes = {{}};
    const auto panel = [&](float x0, float x1, float y0, float y1) {
        occ.panels.push_back(Aabb::of({x0, y0, kPanelZ}, {x1, y1, kPanelZ}));
    };
    panel(0, 2, 0, 3);
    panel(2, 4, 0, 3);
    panel(4.001f, 6, 0, 3);
    panel(0, 6, 3, 4);
    VoxelMask& m = occ.solid;
    m.origin = glm::vec3(-1.0f);
    m.voxel_size_m = kVoxel;
    m.dims = glm::ivec3(40);
    m.bits.assign((m.count() + 63) / 64, 0);
    for (int z = 0; z < 40; ++z)
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 40; ++x) {
                const glm::vec3 lo = m.origin + glm::vec3(x, y, z) * kVoxel;
                const bool in_slab =
                    lo.z >= 7.0f && lo.z < 8.0f && lo.x >= 0.0f && lo.x < 5.0f && lo.y >= 0.0f && lo.y < 4.0f;
                const bool hole = lo.x == 2.0f && lo.y == 1.0f;
                if (in_slab && !hole) {
                    const uint64_t i = uint64_t(x) + 40u * (uint64_t(y) + 40u * uint64_t(z));
                    m.bits[i >> 6] |= uint64_t(1) << (i & 63);
                }
            }
    return occ;
}

// The plain reference: is the point y of the plane z = c covered, by a closed panel of that plane or by the
// interior of the solid (every voxel holding y solid)?
bool in_solid_interior(const ShrunkOccluders& occ, glm::dvec3 y) {
    const VoxelMask& m = occ.solid;
    const glm::dvec3 rel = (y - glm::dvec3(m.origin)) / double(m.voxel_size_m);
    glm::ivec3 lo, hi;
    for (int k = 0; k < 3; ++k) {
        const double f = std::floor(rel[k]);
        lo[k] = hi[k] = int(f);
        if (rel[k] == f) lo[k] = int(f) - 1;
        if (lo[k] < 0 || hi[k] >= m.dims[k]) return false;
    }
    for (int z = lo.z; z <= hi.z; ++z)
        for (int yy = lo.y; yy <= hi.y; ++yy)
            for (int x = lo.x; x <= hi.x; ++x)
                if (!m.get(uint64_t(x) +
                           uint64_t(m.dims.x) * (uint64_t(yy) + uint64_t(m.dims.y) * uint64_t(z))))
                    return false;
    return true;
}

bool covered(const ShrunkOccluders& occ, glm::dvec3 y, float c) {
    for (const Aabb& p : occ.panels)
        if (p.min.z == c && y.x >= p.min.x && y.x <= p.max.x && y.y >= p.min.y && y.y <= p.max.y) return true;
    return in_solid_interior(occ, y);
}

Aabb box_around(glm::vec3 c, glm::vec3 half) {
    return Aabb::of(c - half, c + half);
}

// Do all of `n` random segments from `from` to `to` meet one of the occluders (a panel is a flat closed box;
// a slanted panel of no thickness is its quad of two triangles)? The slow reference of the scene tests.
bool dense_segments_blocked(const ShrunkOccluders& occ, const Aabb& from, const Aabb& to, Rng rng,
                            int n = 200000) {
    for (int s = 0; s < n; ++s) {
        const glm::dvec3 q(point_in(from, rng)), x(point_in(to, rng));
        bool blocked = false;
        for (const Aabb& p : occ.panels) blocked = blocked || segment_meets_closed_box(p, q, x);
        for (const SlantedPanel& p : occ.slanted) {
            const std::vector<glm::dvec3>& c = p.corners;
            for (size_t i = 1; i + 1 < c.size() && !blocked; ++i)
                blocked = test::segment_meets_triangle(q, x, c[0], c[i], c[i + 1]);
        }
        if (!blocked) return false;
    }
    return true;
}

// A random region below the panels (z in [0, 3]) and a random target above the slab (z in [9, 12]), boxes
// of half-sizes up to 0.6 m, as the plane-cover tests draw them.
std::pair<Aabb, Aabb> random_pair(Rng& rng) {
    const Aabb region = box_around({rng.uniform() * 6.0f, rng.uniform() * 4.0f, rng.uniform() * 3.0f},
                                   glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 0.6f);
    const Aabb target = box_around({rng.uniform() * 6.0f, rng.uniform() * 4.0f, 9.0f + rng.uniform() * 3.0f},
                                   glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 0.6f);
    return {region, target};
}

// Segment s of a pair: the 64 corner segments first (s < 64), then random ones.
std::pair<glm::dvec3, glm::dvec3> pair_segment(int s, const Aabb& region, const Aabb& target, Rng& rng) {
    const glm::dvec3 q(s < 64 ? glm::vec3(s & 1 ? region.max.x : region.min.x,
                                          s & 2 ? region.max.y : region.min.y,
                                          s & 4 ? region.max.z : region.min.z)
                              : point_in(region, rng));
    const glm::dvec3 x(s < 64 ? glm::vec3(s & 8 ? target.max.x : target.min.x,
                                          s & 16 ? target.max.y : target.min.y,
                                          s & 32 ? target.max.z : target.min.z)
                              : point_in(target, rng));
    return {q, x};
}

// Whenever plane_covers() says so, every one of many segments from the region to the target (the 64 corner
// segments and random ones) crosses the plane where the reference says covered; and where it says not, the
// segments find an uncovered crossing in most cases (it gives up little).
TEST(ShaftHiding, APlaneCoverAgreesWithTheReferenceOnManySegments) {
    Context ctx = quiet_context();
    const ShrunkOccluders occ = make_occluders();
    const ShaftProver prover(ctx, occ, false);
    Rng rng(5, 1);
    int covers = 0, not_covers = 0, refuted = 0;
    for (int i = 0; i < 4000; ++i) {
        // The panels' plane or a plane across the middle of the slab's voxel layer at z in [7.5, 7.75].
        const bool slab = rng.below(2) == 1;
        const float c = slab ? 7.625f : kPanelZ;
        const auto [region, target] = random_pair(rng);
        const bool cover = prover.plane_covers(region, target, 2, c);
        bool all = true;
        glm::dvec2 lo(INFINITY), hi(-INFINITY);  // the corner crossings' bounds
        for (int s = 0; s < 64 + 400 && all; ++s) {
            const auto [q, x] = pair_segment(s, region, target, rng);
            const double t = (double(c) - q.z) / (x.z - q.z);
            const glm::dvec3 y = q + t * (x - q);
            all = covered(occ, y, c);
            lo = glm::min(lo, glm::dvec2(y));
            hi = glm::max(hi, glm::dvec2(y));
        }
        // Random segments seldom cross the 1 mm gap between B and C: a crossing that spans it is uncovered.
        if (all && c == kPanelZ && lo.x < 4.0 && hi.x > 4.001 && lo.y < 3.0 && hi.y > 0.0) all = false;
        if (cover) {
            ++covers;
            EXPECT_TRUE(all) << "case " << i << ": a segment crosses the plane z = " << c << " uncovered";
        } else {
            ++not_covers;
            refuted += all ? 0 : 1;
        }
    }
    EXPECT_GT(covers, 300);
    EXPECT_GT(not_covers, 300);
    EXPECT_GT(refuted, not_covers * 9 / 10) << "the cover gives up where the segments find it covered";
}

// Panels of one plane fuse where they share a side; a 1 mm gap between two breaks the cover; the solid's
// slice covers except where the hole is, and a plane on a voxel side needs both layers.
TEST(ShaftHiding, CoplanarPanelsFuseAndTheSolidsSliceCovers) {
    Context ctx = quiet_context();
    const ShrunkOccluders occ = make_occluders();
    const ShaftProver prover(ctx, occ, false);
    const Aabb eye = box_around({2.0f, 1.5f, 1.0f}, glm::vec3(0.3f));
    // Across the side A and B share: covered by the two together.
    EXPECT_TRUE(prover.plane_covers(eye, box_around({2.0f, 1.5f, 9.0f}, glm::vec3(0.4f)), 2, kPanelZ));
    // Up into D as well.
    EXPECT_TRUE(prover.plane_covers(eye, box_around({2.0f, 3.0f, 9.0f}, glm::vec3(0.4f)), 2, kPanelZ));
    // Across the gap between B and C: not covered.
    const Aabb at_gap = box_around({4.0f, 1.5f, 1.0f}, glm::vec3(0.3f));
    EXPECT_FALSE(prover.plane_covers(at_gap, box_around({4.0f, 1.5f, 9.0f}, glm::vec3(0.4f)), 2, kPanelZ));
    // Beyond the panels' outer side: not covered.
    EXPECT_FALSE(prover.plane_covers(eye, box_around({6.5f, 1.5f, 9.0f}, glm::vec3(0.4f)), 2, kPanelZ));
    // Not on opposite sides of the plane: never.
    EXPECT_FALSE(prover.plane_covers(eye, box_around({2.0f, 1.5f, 4.0f}, glm::vec3(0.4f)), 2, kPanelZ));
    // The slab: covered away from the hole, not through it.
    const Aabb far_from_hole = box_around({3.5f, 2.5f, 1.0f}, glm::vec3(0.2f));
    EXPECT_TRUE(
        prover.plane_covers(far_from_hole, box_around({3.5f, 2.5f, 10.0f}, glm::vec3(0.2f)), 2, 7.625f));
    const Aabb at_hole = box_around({2.125f, 1.125f, 1.0f}, glm::vec3(0.2f));
    EXPECT_FALSE(
        prover.plane_covers(at_hole, box_around({2.125f, 1.125f, 10.0f}, glm::vec3(0.2f)), 2, 7.625f));
    // On the slab's far side, z = 8: the layer beyond is empty, so not covered.
    EXPECT_FALSE(
        prover.plane_covers(far_from_hole, box_around({3.5f, 2.5f, 10.0f}, glm::vec3(0.2f)), 2, 8.0f));
    // Inside, on the side between two solid layers: covered.
    EXPECT_TRUE(
        prover.plane_covers(far_from_hole, box_around({3.5f, 2.5f, 10.0f}, glm::vec3(0.2f)), 2, 7.5f));
}

// Does the segment q -> x meet an occluder by the reference: cross a covered point of the panels' plane, or
// pass a point of the solid's interior (sampled every millimetre)?
bool segment_blocked(const ShrunkOccluders& occ, glm::dvec3 q, glm::dvec3 x) {
    if ((q.z - kPanelZ) * (x.z - kPanelZ) < 0.0) {
        const double t = (double(kPanelZ) - q.z) / (x.z - q.z);
        const glm::dvec3 y = q + t * (x - q);
        for (const Aabb& p : occ.panels)
            if (y.x >= p.min.x && y.x <= p.max.x && y.y >= p.min.y && y.y <= p.max.y) return true;
    }
    const int steps = int(glm::length(x - q) / 1e-3) + 1;
    for (int i = 0; i <= steps; ++i) {
        const glm::dvec3 y = q + (double(i) / steps) * (x - q);
        if (in_solid_interior(occ, y)) return true;
    }
    return false;
}

// hides(): for random eye regions (every point an eye) and small objects behind the panels or the slab,
// every one of many segments from the region to points of the object's triangles is blocked when it says
// hidden; and it proves some.
class ShaftHidingBothWays : public ::testing::TestWithParam<bool> {};

TEST_P(ShaftHidingBothWays, EverySegmentFromTheRegionToAnObjectItHidesIsBlocked) {
    Context ctx = quiet_context();
    const ShrunkOccluders occ = make_occluders();
    const ShaftProver prover(ctx, occ, GetParam());
    Rng rng(9, 2);
    World w;
    std::vector<uint32_t> objects;
    for (int i = 0; i < 40; ++i) {
        const glm::vec3 c(rng.uniform() * 6.0f, rng.uniform() * 4.0f, 9.0f + rng.uniform() * 2.0f);
        objects.push_back(test::add_box(w, "o" + std::to_string(i), box_around(c, glm::vec3(0.3f))));
    }
    const VoxelMask no_eyes;
    int hidden = 0, tried = 0;
    ShaftFigures figures;
    for (int r = 0; r < 40; ++r) {
        const Aabb region =
            box_around({rng.uniform() * 6.0f, rng.uniform() * 4.0f, 1.0f + rng.uniform() * 2.0f},
                       glm::vec3(0.1f + 0.4f * rng.uniform()));
        const ShaftRegion shaft = shaft_region(no_eyes, region);
        for (uint32_t o : objects) {
            ++tried;
            if (!prover.hides(w, no_eyes, shaft, o, 256, figures)) continue;
            ++hidden;
            const WorldObject& obj = w.objects[o];
            for (int s = 0; s < 300; ++s) {
                const Triangle& tri = w.triangles[obj.first_triangle + rng.below(obj.triangle_count)];
                float b1 = rng.uniform(), b2 = rng.uniform();
                if (b1 + b2 > 1.0f) {
                    b1 = 1.0f - b1;
                    b2 = 1.0f - b2;
                }
                const glm::vec3 a = w.positions[tri.v[0]];
                const glm::vec3 x = a + b1 * (w.positions[tri.v[1]] - a) + b2 * (w.positions[tri.v[2]] - a);
                const glm::vec3 q = point_in(region, rng);
                ASSERT_TRUE(segment_blocked(occ, q, x))
                    << "region " << r << " object " << o << ": a segment passes every occluder";
            }
        }
    }
    EXPECT_GT(hidden, tried / 10) << "the proof never succeeds: the check is vacuous";
    EXPECT_LT(hidden, tried) << "everything proven hidden: the scene is not telling";
    EXPECT_EQ(figures.hidden, uint64_t(hidden));
}

INSTANTIATE_TEST_SUITE_P(FusionOffAndOn, ShaftHidingBothWays, ::testing::Bool());

// With fusion, whenever a plane covers, every one of many segments from the region to the target (the 64
// corner segments and random ones) meets an occluder somewhere on its way (the panels' plane or the
// solid's interior), not only in the plane; and fusion covers pairs the plane alone does not.
TEST(ShaftHiding, AFusedCoverBlocksEverySegment) {
    Context ctx = quiet_context();
    const ShrunkOccluders occ = make_occluders();
    const ShaftProver fused(ctx, occ, true), alone(ctx, occ, false);
    Rng rng(7, 3);
    int covers = 0, only_fused = 0;
    for (int i = 0; i < 3000; ++i) {
        const bool slab = rng.below(2) == 1;
        const float c = slab ? 7.625f : kPanelZ;
        const auto [region, target] = random_pair(rng);
        uint64_t umbrae = 0;
        if (!fused.plane_covers(region, target, 2, c, nullptr, &umbrae)) continue;
        ++covers;
        only_fused += alone.plane_covers(region, target, 2, c) ? 0 : 1;
        for (int s = 0; s < 64 + 100; ++s) {
            const auto [q, x] = pair_segment(s, region, target, rng);
            ASSERT_TRUE(segment_blocked(occ, q, x)) << "case " << i << " (plane z = " << c << ", " << umbrae
                                                    << " umbrae): a segment passes every occluder";
        }
    }
    EXPECT_GT(covers, 300);
    EXPECT_GT(only_fused, 20) << "fusion never covers more than the plane alone";
}

// umbra_on_plane() against brute force: a point of the plane is in the umbra only if the segments from
// many points of the eye box to it all meet the occluder box; and most points that brute force finds
// hidden from the corners are in it.
TEST(ShaftHiding, TheUmbraHoldsOnlyPointsHiddenFromTheWholeBox) {
    Rng rng(11, 4);
    int inside_count = 0, agreed = 0, hidden_count = 0;
    for (int i = 0; i < 300; ++i) {
        const Aabb eyes =
            box_around({rng.uniform() * 4.0f, rng.uniform() * 4.0f, 6.0f + rng.uniform() * 2.0f},
                       glm::vec3(0.05f) + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()));
        // Between the plane z = 0 and the eyes (z > 4.9), as umbra_on_plane() asks.
        const Aabb occ = box_around({rng.uniform() * 4.0f, rng.uniform() * 4.0f, 1.5f + rng.uniform() * 1.5f},
                                    glm::vec3(0.1f) + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()));
        const std::array<glm::dvec3, 8> ec = box_corners(eyes), oc = box_corners(occ);
        std::vector<glm::dvec2> umbra;
        const bool some = umbra_on_plane(ec, oc.data(), 8, 2, 0.0, 1, umbra);
        const auto meets = [&](glm::dvec3 q, glm::dvec3 y) { return segment_meets_closed_box(occ, q, y); };
        for (int s = 0; s < 40; ++s) {
            const glm::dvec3 y(-2.0 + 8.0 * rng.uniform(), -2.0 + 8.0 * rng.uniform(), 0.0);
            bool in = some && umbra.size() >= 3;
            for (size_t e = 0; in && e < umbra.size(); ++e) {
                const glm::dvec2 a = umbra[e], b = umbra[(e + 1) % umbra.size()];
                in = (b.x - a.x) * (y.y - a.y) - (b.y - a.y) * (y.x - a.x) >= 0.0;
            }
            bool hidden_corners = true;
            for (const glm::dvec3& q : ec) hidden_corners = hidden_corners && meets(q, y);
            hidden_count += hidden_corners;
            if (in) {
                ++inside_count;
                for (int k = 0; k < 50; ++k)
                    ASSERT_TRUE(meets(glm::dvec3(point_in(eyes, rng)), y))
                        << "case " << i << ": a point of the umbra is seen from the eye box";
            }
            agreed += in == hidden_corners;
        }
    }
    EXPECT_GT(inside_count, 200);
    EXPECT_GT(agreed, 300 * 40 * 99 / 100) << "the umbra differs from the corners' shadows";
    EXPECT_GT(hidden_count, 200);
}

// Two walls meeting at a right angle (thin panels, an L seen from its outer corner) hide an object from a
// whole cell that neither hides alone: every line from the cell to the object passes the corner's line on
// one side or the other. One plane cannot cover the pieces along that line; with fusion the umbra of one
// wall on the other's plane does. Dense segments confirm it; a gap of 2 cm at the corner keeps it listed.
TEST(ShaftHiding, TwoWallsAtARightAngleHideWhatNeitherHidesAlone) {
    Context ctx = quiet_context();
    for (const float gap : {0.0f, 0.02f}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        occ.boxes = {{}};
        occ.panels.push_back(Aabb::of({0.0f, 0.0f, gap}, {0.0f, 3.0f, 4.0f}));   // x = 0, z in [gap, 4]
        occ.panels.push_back(Aabb::of({0.0f, 0.0f, 0.0f}, {4.0f, 3.0f, 0.0f}));  // z = 0, x in [0, 4]
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({1.0f, 1.0f, 1.0f}, {1.5f, 2.0f, 1.5f}));
        const Aabb cell = Aabb::of({-2.0f, 1.0f, -2.0f}, {-1.0f, 2.0f, -1.0f});
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        const bool all_blocked = dense_segments_blocked(occ, cell, w.objects[object].bounds, Rng(13, 5));
        EXPECT_EQ(all_blocked, gap == 0.0f) << "the scene is not what the test means";
        RegionHider one(ctx, occ);
        uint64_t hidden_one = 0;
        EXPECT_EQ(one.hide(w, cell, {object}, &hidden_one), 0u) << "one wall alone hides it";
        ShaftFigures fig_on, fig_off, fig_cap, fig_cup, fig_flood;
        const bool fused =
            ShaftProver(ctx, occ, true, false, false, false).hides(w, no_eyes, shaft, object, 256, fig_on);
        const bool alone =
            ShaftProver(ctx, occ, false, false, false, false).hides(w, no_eyes, shaft, object, 256, fig_off);
        // The outer corner of the L is also a convex cap (pvs/convex_cap.h): it proves the pair alone.
        const bool capped =
            ShaftProver(ctx, occ, false, true, false, false).hides(w, no_eyes, shaft, object, 256, fig_cap);
        // And seen from the object, the L is the inner corner of a cup (docs/ALGORITHMS.md#cups).
        const bool cupped =
            ShaftProver(ctx, occ, false, false, true, false).hides(w, no_eyes, shaft, object, 256, fig_cup);
        // And the L cuts the shaft in two (pvs/shaft_flood.h), in the first piece pair.
        const bool flooded =
            ShaftProver(ctx, occ, false, false, false, true).hides(w, no_eyes, shaft, object, 256, fig_flood);
        EXPECT_EQ(fused, gap == 0.0f) << "gap " << gap << ": " << fig_on.tests << " piece pairs";
        EXPECT_FALSE(alone) << "one plane's cover proved the corner alone";
        EXPECT_EQ(capped, gap == 0.0f) << "gap " << gap << ": " << fig_cap.tests << " piece pairs";
        EXPECT_EQ(fig_cap.capped > 0, gap == 0.0f);
        EXPECT_EQ(cupped, gap == 0.0f) << "gap " << gap << ": " << fig_cup.tests << " piece pairs";
        EXPECT_EQ(fig_cup.cupped > 0, gap == 0.0f);
        EXPECT_EQ(flooded, gap == 0.0f) << "gap " << gap << ": " << fig_flood.tests << " piece pairs";
        EXPECT_EQ(fig_flood.flood.separated > 0, gap == 0.0f);
    }
}

// Two staggered rows of pillars (boxes of the proven solid, 0.6 m wide with 0.4 m gaps, the second row's
// pillars over the first row's gaps) hide an object from a whole cell that neither row hides alone. The
// plane across the second row is covered by its own solid slice and, in its gaps, by the umbrae of the
// first row's pillars. Dense segments confirm it; with the second row moved over the first's pillars
// (gaps in line), the object stays listed.
TEST(ShaftHiding, StaggeredPillarsFuse) {
    Context ctx = quiet_context();
    for (const bool staggered : {true, false}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        std::vector<Aabb> pillars;
        for (int k = -2; k < 9; ++k) {
            pillars.push_back(Aabb::of({float(k), 0.0f, 5.0f}, {float(k) + 0.6f, 3.0f, 5.6f}));
            const float x = float(k) + (staggered ? 0.5f : 0.0f);
            pillars.push_back(Aabb::of({x, 0.0f, 6.0f}, {x + 0.6f, 3.0f, 6.6f}));
        }
        occ.boxes = {pillars};
        VoxelMask& m = occ.solid;
        m.origin = glm::vec3(-3.0f, -1.0f, -1.0f);
        m.voxel_size_m = 0.1f;
        m.dims = glm::ivec3(150, 50, 130);
        m.bits.assign((m.count() + 63) / 64, 0);
        for (int z = 0; z < m.dims.z; ++z)
            for (int y = 0; y < m.dims.y; ++y)
                for (int x = 0; x < m.dims.x; ++x) {
                    const glm::vec3 c = m.origin + (glm::vec3(x, y, z) + 0.5f) * m.voxel_size_m;
                    bool in = false;
                    for (const Aabb& b : pillars) in = in || b.contains(c);
                    if (in) {
                        const uint64_t i = uint64_t(x) + uint64_t(m.dims.x) *
                                                             (uint64_t(y) + uint64_t(m.dims.y) * uint64_t(z));
                        m.bits[i >> 6] |= uint64_t(1) << (i & 63);
                    }
                }
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({2.8f, 1.0f, 10.0f}, {3.4f, 2.0f, 10.5f}));
        const Aabb cell = Aabb::of({2.5f, 1.0f, 0.0f}, {3.5f, 2.0f, 1.0f});
        Rng rng(17, 6);
        bool all_blocked = true;
        int first_row_misses = 0;
        for (int s = 0; s < 100000 && all_blocked; ++s) {
            const glm::dvec3 q(point_in(cell, rng)), x(point_in(w.objects[object].bounds, rng));
            bool first = false, any = false;
            for (size_t i = 0; i < pillars.size(); ++i)
                if (segment_meets_closed_box(pillars[i], q, x)) {
                    any = true;
                    first = first || i % 2 == 0;
                }
            all_blocked = any;
            first_row_misses += first ? 0 : 1;
        }
        EXPECT_EQ(all_blocked, staggered) << "the scene is not what the test means";
        EXPECT_GT(first_row_misses, 0) << "the first row alone hides it";
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        ShaftFigures fig_on, fig_off;
        const bool fused = ShaftProver(ctx, occ, true).hides(w, no_eyes, shaft, object, 1024, fig_on);
        const bool alone = ShaftProver(ctx, occ, false).hides(w, no_eyes, shaft, object, 1024, fig_off);
        EXPECT_EQ(fused, staggered) << (staggered ? "staggered" : "in line") << ": " << fig_on.tests
                                    << " piece pairs, " << fig_on.umbrae << " umbrae";
        EXPECT_FALSE(alone && !staggered);
    }
}

// A wall (a panel) with a slit 2 cm wide, and a second wall behind it with a 2 cm slit in line, in front
// of an object: sight passes both slits, so the object stays listed, with fusion as without.
TEST(ShaftHiding, AnObjectBehindSlitsInLineStaysListed) {
    Context ctx = quiet_context();
    ShrunkOccluders occ;
    occ.epsilon_m = {0.1};
    occ.boxes = {{}};
    for (const float z : {4.0f, 6.0f}) {
        occ.panels.push_back(Aabb::of({-4.0f, 0.0f, z}, {2.99f, 3.0f, z}));
        occ.panels.push_back(Aabb::of({3.01f, 0.0f, z}, {10.0f, 3.0f, z}));
    }
    World w;
    const uint32_t object = test::add_box(w, "o", Aabb::of({2.5f, 1.0f, 9.0f}, {3.5f, 2.0f, 9.5f}));
    const Aabb cell = Aabb::of({2.5f, 1.0f, 0.0f}, {3.5f, 2.0f, 1.0f});
    const VoxelMask no_eyes;
    const ShaftRegion shaft = shaft_region(no_eyes, cell);
    ShaftFigures figures;
    EXPECT_FALSE(ShaftProver(ctx, occ, true).hides(w, no_eyes, shaft, object, 4096, figures));
    EXPECT_FALSE(ShaftProver(ctx, occ, false).hides(w, no_eyes, shaft, object, 4096, figures));
}

// A gable roof (two thin slopes meeting at a ridge along x, no solid under them) hides an object under the
// ridge from eyes above it that see both slopes: every line from them crosses one slope or the other.
// No axis plane holds either slope, so plane covers and their umbrae never fuse them; the convex cap of the
// two slopes (pvs/convex_cap.h) does. Dense segments confirm it; with a gap of 2 cm at the ridge the object

// A slanted panel of no thickness: the quad `corners` (two triangles), its normal turned towards `up`.
SlantedPanel slanted_quad(std::vector<glm::dvec3> corners, glm::dvec3 up) {
    SlantedPanel p;
    p.corners = std::move(corners);
    p.normal = glm::normalize(glm::cross(p.corners[1] - p.corners[0], p.corners[2] - p.corners[0]));
    if (glm::dot(p.normal, up) < 0.0) {
        std::reverse(p.corners.begin(), p.corners.end());
        p.normal = -p.normal;
    }
    p.offset = glm::dot(p.normal, p.corners[0]);
    EXPECT_TRUE(set_slanted_edges(p));
    for (const glm::dvec3& c : p.corners) p.bounds.extend(glm::vec3(c));
    p.triangles = 2;
    return p;
}

// stays listed.
TEST(ShaftHiding, TheTwoSlopesOfARoofRidgeHideWhatNeitherHidesAlone) {
    Context ctx = quiet_context();
    for (const double gap : {0.0, 0.02}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        occ.boxes = {{}};
        // The ridge at y = 3, z = 2 from x = 0 to 4; the eaves at y = 2, z = 0 and z = 4.
        occ.slanted.push_back(slanted_quad({{0, 2, 0}, {4, 2, 0}, {4, 3, 2}, {0, 3, 2}}, {0, 1, 0}));
        occ.slanted.push_back(
            slanted_quad({{0, 3 - gap / 2, 2 + gap}, {4, 3 - gap / 2, 2 + gap}, {4, 2, 4}, {0, 2, 4}}, {0, 1, 0}));
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({1.5f, 2.2f, 1.5f}, {2.5f, 2.6f, 2.5f}));
        const Aabb cell = Aabb::of({1.5f, 4.0f, 1.0f}, {2.5f, 4.5f, 3.0f});
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        const bool all_blocked = dense_segments_blocked(occ, cell, w.objects[object].bounds, Rng(17, 2));
        EXPECT_EQ(all_blocked, gap == 0.0) << "the scene is not what the test means";
        RegionHider one(ctx, occ);
        uint64_t hidden_one = 0;
        EXPECT_EQ(one.hide(w, cell, {object}, &hidden_one), 0u) << "one slope alone hides it";
        ShaftFigures without, with;
        EXPECT_FALSE(ShaftProver(ctx, occ, true, false).hides(w, no_eyes, shaft, object, 1024, without))
            << "plane covers fused the slopes: the scene no longer tests the caps";
        EXPECT_EQ(ShaftProver(ctx, occ, true, true).hides(w, no_eyes, shaft, object, 1024, with), gap == 0.0)
            << "gap " << gap << ": " << with.tests << " piece pairs";
    }
}

// Two walls meeting at 37 degrees (thin: a panel in the plane x = 0 for z in [0, 4], and a slanted panel
// from the same corner edge at 37 degrees to it), seen from in front of the wedge's tip, hide an object
// inside the wedge that neither hides alone. Their outer faces make a convex cap. Dense segments confirm
// it; with a gap of 2 cm at the corner the object stays listed.
TEST(ShaftHiding, TwoWallsAt37DegreesHideWhatNeitherHidesAlone) {
    Context ctx = quiet_context();
    const double angle = 37.0 * 3.14159265358979323846 / 180.0;
    const double s = std::sin(angle), co = std::cos(angle);
    for (const double gap : {0.0, 0.02}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        occ.boxes = {{}};
        occ.panels.push_back(Aabb::of({0.0f, 0.0f, float(gap)}, {0.0f, 3.0f, 4.0f}));
        occ.slanted.push_back(
            slanted_quad({{0, 0, 0}, {4 * s, 0, 4 * co}, {4 * s, 3, 4 * co}, {0, 3, 0}}, {co, 0, -s}));
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({0.3f, 1.0f, 1.8f}, {0.6f, 2.0f, 2.4f}));
        const Aabb cell = Aabb::of({-0.5f, 1.0f, -2.5f}, {1.0f, 2.0f, -1.5f});
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        const bool all_blocked = dense_segments_blocked(occ, cell, w.objects[object].bounds, Rng(37, 1));
        EXPECT_EQ(all_blocked, gap == 0.0) << "the scene is not what the test means";
        RegionHider one(ctx, occ);
        uint64_t hidden_one = 0;
        EXPECT_EQ(one.hide(w, cell, {object}, &hidden_one), 0u) << "one wall alone hides it";
        ShaftFigures with;
        EXPECT_EQ(ShaftProver(ctx, occ, false, true).hides(w, no_eyes, shaft, object, 1024, with), gap == 0.0)
            << "gap " << gap << ": " << with.tests << " piece pairs";
        EXPECT_EQ(with.capped > 0, gap == 0.0);
    }
}

// A hollow staircase (thin panels: four risers of 0.3 m and treads of 0.5 m, the last tread running on as a
// landing) hides an object under its steps from a cell before its foot: every line from the cell to the
// object crosses a riser or a tread, but no single one. Each step's nose is a convex cap of its riser and
// tread; the concave corners behind the treads fuse through the treads' umbrae on the risers' planes. The
// halving must cut the pieces around every nose and corner: thousands of piece pairs, far beyond the
// budgets a bake uses, so the budget here is large. Dense segments confirm it; with a 2 cm slit under one
// nose (the riser stopping short of its tread) the object stays listed.
TEST(ShaftHiding, AStaircaseHidesWhatNoSingleStepHides) {
    Context ctx = quiet_context();
    for (const float slit : {0.0f, 0.02f}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        occ.boxes = {{}};
        for (int k = 0; k < 4; ++k) {
            const float z = 2.0f + 0.5f * float(k), y0 = 0.3f * float(k), y1 = 0.3f * float(k + 1);
            // Riser k in the plane z; the slit, when asked, under the nose of step 1.
            occ.panels.push_back(Aabb::of({0.0f, y0, z}, {3.0f, k == 1 ? y1 - slit : y1, z}));
            occ.panels.push_back(Aabb::of({0.0f, y1, z}, {3.0f, y1, k == 3 ? 8.0f : z + 0.5f}));  // tread k
        }
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({1.2f, 0.1f, 3.0f}, {1.8f, 0.5f, 3.4f}));
        const Aabb cell = Aabb::of({1.0f, 0.5f, 0.0f}, {2.0f, 1.0f, 1.0f});
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        const bool all_blocked = dense_segments_blocked(occ, cell, w.objects[object].bounds, Rng(19, 4));
        EXPECT_EQ(all_blocked, slit == 0.0f) << "the scene is not what the test means";
        RegionHider one(ctx, occ);
        uint64_t hidden_one = 0;
        EXPECT_EQ(one.hide(w, cell, {object}, &hidden_one), 0u) << "one step alone hides it";
        ShaftFigures figures;
        EXPECT_EQ(ShaftProver(ctx, occ).hides(w, no_eyes, shaft, object, 1 << 16, figures), slit == 0.0f)
            << "slit " << slit << ": " << figures.tests << " piece pairs";
    }
}

// Cups (docs/ALGORITHMS.md#cups): a room of panels, each of its six walls cut into a few panels that meet
// exactly, around a cell; objects outside it. Closed, the room is one cup: every object is proven hidden,
// with no fusion and no caps, and the planes alone (no cups) prove none of those beyond an edge or a
// corner of the room. With a hole of 5 cm in one wall, every object proven hidden is checked against dense
// segments, and some objects are seen through the hole and stay listed.
TEST(ShaftHiding, ARoomOfPanelsIsOneCup) {
    Context ctx = quiet_context();
    const float lo = 0.0f, hi = 4.0f;
    Rng rng(41, 3);
    for (const bool hole : {false, true}) {
        ShrunkOccluders occ;
        occ.epsilon_m = {0.1};
        occ.boxes = {{}};
        for (int a = 0; a < 3; ++a)
            for (const float c : {lo, hi}) {
                // The wall x[a] = c, cut at a random line across it into two panels meeting exactly, the
                // hole (on the wall x = hi) cut out of the second.
                const int u = (a + 1) % 3, v = (a + 2) % 3;
                const float cut = 1.0f + 2.0f * rng.uniform();
                const auto panel = [&](float u0, float u1, float v0, float v1) {
                    glm::vec3 p0, p1;
                    p0[a] = p1[a] = c;
                    p0[u] = u0, p1[u] = u1, p0[v] = v0, p1[v] = v1;
                    occ.panels.push_back(Aabb::of(p0, p1));
                };
                panel(lo, cut, lo, hi);
                if (hole && a == 0 && c == hi) {
                    const float h0 = 2.0f, h1 = 2.05f;
                    panel(cut, hi, lo, h0);
                    panel(cut, hi, h1, hi);
                    panel(cut, h0, h0, h1);
                    panel(h1, hi, h0, h1);
                } else {
                    panel(cut, hi, lo, hi);
                }
            }
        World w;
        std::vector<uint32_t> objects;
        for (int i = 0; i < 24; ++i) {
            glm::vec3 c;
            for (int k = 0; k < 3; ++k) {
                // Outside the room on one to three axes: beyond a wall, an edge or a corner.
                const int where = i % 3 >= k ? int(rng.below(2)) * 2 - 1 : 0;
                c[k] = where == 0 ? 1.0f + 2.0f * rng.uniform() : (where < 0 ? -1.5f : 5.5f);
            }
            objects.push_back(test::add_box(w, "o" + std::to_string(i), box_around(c, glm::vec3(0.4f))));
        }
        const Aabb cell = Aabb::of({1.2f, 1.5f, 1.3f}, {2.8f, 2.5f, 2.6f});
        const VoxelMask no_eyes;
        const ShaftRegion shaft = shaft_region(no_eyes, cell);
        int cupped = 0, planes = 0, seen = 0;
        for (const uint32_t o : objects) {
            ShaftFigures fig, fig_planes;
            const bool hidden =
                ShaftProver(ctx, occ, false, false, true, false).hides(w, no_eyes, shaft, o, 256, fig);
            const bool by_planes = ShaftProver(ctx, occ, false, false, false, false)
                                       .hides(w, no_eyes, shaft, o, 256, fig_planes);
            const bool blocked = dense_segments_blocked(occ, cell, w.objects[o].bounds, Rng(43, o), 20000);
            if (hidden) {
                EXPECT_TRUE(blocked) << "object " << o << ": proven hidden, and a segment passes";
            }
            if (!hole) {
                EXPECT_TRUE(hidden) << "object " << o << ": the closed room did not hide it";
            }
            cupped += hidden ? 1 : 0;
            planes += by_planes ? 1 : 0;
            seen += blocked ? 0 : 1;
        }
        EXPECT_LT(planes, cupped) << "the planes alone prove as much: the test does not need cups";
        if (hole) {
            EXPECT_GT(seen, 0) << "nothing is seen through the hole: the scene is not telling";
        }
    }
}

}  // namespace
}  // namespace pvs
