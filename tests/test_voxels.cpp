// SPDX-License-Identifier: MIT
// Conservative voxelization (against an independent clipping reference) and the flood of free space.
#include "core/error.h"
#include "core/random.h"
#include "tests/world_builder.h"
#include "voxels/flood.h"
#include "voxels/voxels.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <vector>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// Reference: clip the triangle by the box's six closed half-spaces (Sutherland-Hodgman); it overlaps
// the box when something is left.
bool reference_overlap(glm::vec3 center, glm::vec3 half, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    std::vector<glm::dvec3> poly = {glm::dvec3(a), glm::dvec3(b), glm::dvec3(c)};
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = -1; side <= 1; side += 2) {
            const double limit = double(center[axis]) + side * double(half[axis]);
            std::vector<glm::dvec3> out;
            for (size_t i = 0; i < poly.size(); ++i) {
                const glm::dvec3 p = poly[i], q = poly[(i + 1) % poly.size()];
                const double dp = side * (p[axis] - limit), dq = side * (q[axis] - limit);  // <= 0 inside
                if (dp <= 0) out.push_back(p);
                if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
            }
            poly = out;
            if (poly.empty()) return false;
        }
    }
    return true;
}

TEST(TriangleBox, MatchesTheClippingReferenceOnRandomCases) {
    Rng rng(1, 2);
    int overlaps = 0, disagreements = 0;
    for (int i = 0; i < 200000; ++i) {
        auto r = [&] { return glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0f - 2.0f; };
        const glm::vec3 a = r(), b = r() * 0.5f + a * 0.5f, c = r();
        const glm::vec3 half =
            glm::vec3(0.1f) + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 0.5f;
        const bool fast = triangle_box_overlap(glm::vec3(0.0f), half, a, b, c);
        const bool slow = reference_overlap(glm::vec3(0.0f), half, a, b, c);
        overlaps += slow;
        disagreements += fast != slow;
    }
    EXPECT_GT(overlaps, 20000);
    EXPECT_EQ(disagreements, 0);
}

TEST(TriangleBox, TouchingCountsAsOverlap) {
    // A triangle lying exactly on the box's face, and one touching it at a vertex.
    EXPECT_TRUE(triangle_box_overlap(glm::vec3(0), glm::vec3(1), {1, -2, -2}, {1, 2, -2}, {1, 0, 2}));
    EXPECT_TRUE(triangle_box_overlap(glm::vec3(0), glm::vec3(1), {1, 1, 1}, {3, 1, 1}, {3, 3, 3}));
    EXPECT_FALSE(
        triangle_box_overlap(glm::vec3(0), glm::vec3(1), {1.01f, -2, -2}, {1.01f, 2, -2}, {1.01f, 0, 2}));
}

// A closed room: a 10 x 4 x 10 m hollow box of 0.2 m walls and a 0.6 m ceiling (six wall objects), optionally
// with a hole.
World room(bool hole) {
    World w;
    const float t = 0.2f;
    test::add_box(w, "floor", Aabb::of({0, 0, 0}, {10, t, 10}));
    test::add_box(w, "ceiling", Aabb::of({0, 3.4f, 0}, {10, 4, 10}));  // 0.6 m thick
    test::add_box(w, "west", Aabb::of({0, 0, 0}, {t, 4, 10}));
    test::add_box(w, "east", Aabb::of({10 - t, 0, 0}, {10, 4, 10}));
    test::add_box(w, "south", Aabb::of({0, 0, 0}, {10, 4, t}));
    if (!hole) {
        test::add_box(w, "north", Aabb::of({0, 0, 10 - t}, {10, 4, 10}));
    } else {  // a 1 m square hole at x in [4.5, 5.5], y in [1.5, 2.5]
        test::add_box(w, "north_a", Aabb::of({0, 0, 10 - t}, {4.5f, 4, 10}));
        test::add_box(w, "north_b", Aabb::of({5.5f, 0, 10 - t}, {10, 4, 10}));
        test::add_box(w, "north_c", Aabb::of({4.5f, 0, 10 - t}, {5.5f, 1.5f, 10}));
        test::add_box(w, "north_d", Aabb::of({4.5f, 2.5f, 10 - t}, {5.5f, 4, 10}));
    }
    return w;
}

TEST(Voxelize, MarksTheShellAndNothingInside) {
    Context ctx = quiet_context();
    const World w = room(false);
    const VoxelGrid g = make_voxel_grid(w.bounds, 0.25, 2);
    BitVolume touched, up;
    voxelize_opaque(ctx, w, g, touched, &up);
    // A voxel in the middle of the room is free; one inside the floor slab is touched.
    const glm::ivec3 mid = g.voxel_of({5, 2, 5});
    EXPECT_FALSE(touched.get(g.index(mid.x, mid.y, mid.z)));
    const glm::ivec3 in_floor = g.voxel_of({5, 0.1f, 5});
    EXPECT_TRUE(touched.get(g.index(in_floor.x, in_floor.y, in_floor.z)));
    // The floor's top face faces up; the ceiling's bottom face does not.
    const glm::ivec3 floor_top = g.voxel_of({5, 0.21f, 5});
    const glm::ivec3 ceiling_bottom = g.voxel_of({5, 3.3f, 5});  // [3.25, 3.5]: only the bottom face
    EXPECT_TRUE(up.get(g.index(floor_top.x, floor_top.y, floor_top.z)));
    EXPECT_TRUE(touched.get(g.index(ceiling_bottom.x, ceiling_bottom.y, ceiling_bottom.z)));
    EXPECT_FALSE(up.get(g.index(ceiling_bottom.x, ceiling_bottom.y, ceiling_bottom.z)));
    // Only voxels near a surface are touched: every touched voxel's box is within one voxel of a wall.
    uint64_t n = 0;
    for (uint64_t i = 0; i < g.count(); ++i) {
        if (!touched.get(i)) continue;
        ++n;
        const glm::vec3 p = g.voxel_center(g.coords(i));
        const bool near_surface = p.x < 0.2f + 0.25f || p.x > 9.8f - 0.25f || p.y < 0.2f + 0.25f ||
                                  p.y > 3.4f - 0.25f || p.z < 0.2f + 0.25f || p.z > 9.8f - 0.25f;
        EXPECT_TRUE(near_surface) << p.x << " " << p.y << " " << p.z;
        if (!near_surface) break;
    }
    EXPECT_GT(n, 0u);
}

TEST(Flood, StaysInASealedRoom) {
    Context ctx = quiet_context();
    const World w = room(false);
    const VoxelGrid g = make_voxel_grid(w.bounds, 0.25, 2);
    BitVolume touched;
    voxelize_opaque(ctx, w, g, touched);
    const FloodResult f = flood_free_space(ctx, g, touched, {{5, 2, 5}});
    EXPECT_FALSE(f.leaked);
    EXPECT_TRUE(f.leak_path.empty());
    // Reached space is the room's free interior (9.6 x 3.6 x 9.6 m less the voxels touching the walls).
    const double volume = double(f.reached_count) * 0.25 * 0.25 * 0.25;
    EXPECT_GT(volume, 8.6 * 2.6 * 8.6);
    EXPECT_LE(volume, 9.6 * 3.6 * 9.6);
    const glm::ivec3 outside = g.voxel_of({-0.3f, 2, 5});
    EXPECT_FALSE(f.reached.get(g.index(outside.x, outside.y, outside.z)));
}

// A sealed level is flooded level by level on all threads: the same voxels at 1 and 3 threads as a plain
// breadth-first search with the same steps, flying and walking (random band and glass), on a grid big
// enough for its levels to run in parallel. A hole in the shell makes it leak: then the path comes from
// the search on one thread, and the voxels are the same again.
TEST(Flood, SealedLevelsMatchABreadthFirstSearchAtAnyThreadCount) {
    Context ctx = quiet_context();
    VoxelGrid g;
    g.voxel_size_m = 1.0f;
    g.dims = {120, 50, 110};
    Rng rng(41, 2);
    BitVolume blocked, band, glass;
    blocked.reset(g.count());
    band.reset(g.count());
    glass.reset(g.count());
    for (uint64_t i = 0; i < g.count(); ++i) {
        const glm::ivec3 c = g.coords(i);
        const bool shell = glm::any(glm::equal(c, glm::ivec3(0))) || glm::any(glm::equal(c, g.dims - 1));
        if (shell || rng.uniform() < 0.12f) blocked.set(i);
        if (rng.uniform() < 0.8f) band.set(i);
        if (rng.uniform() < 0.03f) glass.set(i);
    }
    const std::vector<glm::vec3> seeds = {{60.5f, 25.5f, 55.5f}, {10.5f, 40.5f, 100.5f}};
    for (const glm::vec3& p : seeds) blocked.clear(g.index(int(p.x), int(p.y), int(p.z)));
    const glm::ivec3 steps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const bool walking : {false, true}) {
        const WalkRules rules{band, glass};
        const WalkRules* walk = walking ? &rules : nullptr;
        std::vector<uint8_t> want(g.count(), 0);
        std::vector<uint64_t> queue;
        for (const glm::vec3& p : seeds) {
            const uint64_t i = g.index(int(p.x), int(p.y), int(p.z));
            want[i] = 1;
            queue.push_back(i);
        }
        for (size_t q = 0; q < queue.size(); ++q) {
            const uint64_t i = queue[q];
            for (int s = 0; s < 6; ++s) {
                const glm::ivec3 n = g.coords(i) + steps[s];
                if (!g.inside(n)) continue;
                const uint64_t j = g.index(n.x, n.y, n.z);
                if (want[j] || blocked.get(j)) continue;
                // Walking: into the band from anywhere, out of it sideways or down, outside it only down;
                // glass only from above.
                if (walking && s != 3 && ((!band.get(j) && (s == 2 || !band.get(i))) || glass.get(j))) continue;
                want[j] = 1;
                queue.push_back(j);
            }
        }
        ASSERT_GT(queue.size(), 100000u) << "too small a flood to run in parallel";
        const int threads = omp_get_max_threads();
        for (const int t : {1, 3}) {
            omp_set_num_threads(t);
            const FloodResult f = flood_free_space(ctx, g, blocked, seeds, 4, walk);
            omp_set_num_threads(threads);
            EXPECT_FALSE(f.leaked);
            uint64_t wrong = 0;
            for (uint64_t i = 0; i < g.count(); ++i) wrong += f.reached.get(i) != bool(want[i]);
            EXPECT_EQ(wrong, 0u) << (walking ? "walking" : "flying") << ", " << t << " threads";
            EXPECT_EQ(f.reached_count, queue.size());
        }
    }
    // A hole to the outside at the seed's height: the flood leaks, and reaches what the search reaches.
    BitVolume holed = blocked;
    for (int x = 0; x < 61; ++x) holed.clear(g.index(x, 25, 55));
    const int threads = omp_get_max_threads();
    omp_set_num_threads(3);
    const FloodResult a = flood_free_space(ctx, g, holed, seeds);
    omp_set_num_threads(1);
    const FloodResult b = flood_free_space(ctx, g, holed, seeds);
    omp_set_num_threads(threads);
    EXPECT_TRUE(a.leaked);
    EXPECT_FALSE(a.leak_path.empty());
    EXPECT_EQ(a.leak_path.size(), b.leak_path.size());
    EXPECT_TRUE(a.reached.words == b.reached.words);
    EXPECT_GT(a.reached_count, 100000u);
}

TEST(Flood, FindsTheLeakAndItsPathLeavesThroughTheHole) {
    Context ctx = quiet_context();
    const World w = room(true);
    const VoxelGrid g = make_voxel_grid(w.bounds, 0.25, 2);
    BitVolume touched;
    voxelize_opaque(ctx, w, g, touched);
    const FloodResult f = flood_free_space(ctx, g, touched, {{5, 2, 5}});
    ASSERT_TRUE(f.leaked);
    ASSERT_GE(f.leak_path.size(), 2u);
    EXPECT_NEAR(f.leak_path.front().x, 5.0f, 0.25f);
    EXPECT_FALSE(g.bounds().contains(f.leak_path.back() + glm::vec3(0, 0, 0)) &&
                 w.bounds.contains(f.leak_path.back()));  // ends outside the world's bounds
    // Where the path crosses the north wall's plane (z = 9.9), it is inside the hole.
    bool crossed = false;
    for (size_t k = 0; k + 1 < f.leak_path.size(); ++k) {
        const glm::vec3 p = f.leak_path[k], q = f.leak_path[k + 1];
        if ((p.z - 9.9f) * (q.z - 9.9f) > 0) continue;
        const float u = (9.9f - p.z) / (q.z - p.z);
        const glm::vec3 x = p + u * (q - p);
        EXPECT_GT(x.x, 4.5f);
        EXPECT_LT(x.x, 5.5f);
        EXPECT_GT(x.y, 1.5f);
        EXPECT_LT(x.y, 2.5f);
        crossed = true;
    }
    EXPECT_TRUE(crossed);
}

TEST(Flood, MovesASeedOutOfSolidAndDropsOneOutside) {
    Context ctx = quiet_context();
    const World w = room(false);
    const VoxelGrid g = make_voxel_grid(w.bounds, 0.25, 2);
    BitVolume touched;
    voxelize_opaque(ctx, w, g, touched);
    const FloodResult f = flood_free_space(ctx, g, touched, {{5, 0.1f, 5}, {500, 0, 0}});
    EXPECT_EQ(f.seeds_used, 1u);
    EXPECT_EQ(f.seeds_moved, 1u);
    EXPECT_EQ(f.seeds_dropped, 1u);
    EXPECT_FALSE(f.leaked);
    EXPECT_GT(f.reached_count, 1000u);
}

TEST(VoxelGrid, RefusesAGridTooLarge) {
    EXPECT_THROW(make_voxel_grid(Aabb::of({0, 0, 0}, {1000, 1000, 1000}), 0.01, 1), Error);
    const double s = default_voxel_size(Aabb::of({0, 0, 0}, {1000, 1000, 1000}), 0.1, 100'000'000);
    EXPECT_GT(s, 0.1);
    EXPECT_NO_THROW(make_voxel_grid(Aabb::of({0, 0, 0}, {1000, 1000, 1000}), s, 1));
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

TEST(Dilate, GrowsBySoManyVoxelsInTheChebyshevMetric) {
    VoxelGrid g;
    g.voxel_size_m = 1.0f;
    g.dims = glm::ivec3(11, 9, 7);
    BitVolume in;
    in.reset(g.count());
    in.set(g.index(5, 4, 3));
    for (int r : {0, 1, 2, 3}) {
        const BitVolume out = dilate(g, in, r);
        for (uint64_t i = 0; i < g.count(); ++i) {
            const glm::ivec3 c = g.coords(i);
            const int d = std::max({std::abs(c.x - 5), std::abs(c.y - 4), std::abs(c.z - 3)});
            EXPECT_EQ(out.get(i), d <= r) << r << " at " << c.x << "," << c.y << "," << c.z;
        }
    }
}

// Random sets, voxels on the grid's faces and row ends among them, against the definition: a voxel is set
// when a set voxel lies within `radius` in the Chebyshev metric (nothing spills from one row or plane into
// the next, whatever the dims' remainders modulo 64).
TEST(Dilate, MatchesTheDefinitionOnRandomSets) {
    Rng rng(31, 7);
    for (int n = 0; n < 12; ++n) {
        VoxelGrid g;
        g.voxel_size_m = 1.0f;
        g.dims = glm::ivec3(3 + int(rng.below(70)), 2 + int(rng.below(12)), 1 + int(rng.below(9)));
        BitVolume in;
        in.reset(g.count());
        for (uint64_t i = 0; i < g.count(); ++i)
            if (rng.uniform() < 0.01f) in.set(i);
        in.set(g.index(g.dims.x - 1, 0, 0));  // a row's last voxel: moved up it would enter the next row
        in.set(g.index(0, g.dims.y - 1, g.dims.z - 1));
        const int radius = int(rng.below(6));
        const BitVolume out = dilate(g, in, radius);
        int wrong = 0;
        for (uint64_t i = 0; i < g.count() && wrong < 5; ++i) {
            const glm::ivec3 c = g.coords(i);
            bool near = false;
            for (int z = std::max(0, c.z - radius); z <= std::min(g.dims.z - 1, c.z + radius) && !near; ++z)
                for (int y = std::max(0, c.y - radius); y <= std::min(g.dims.y - 1, c.y + radius) && !near;
                     ++y)
                    for (int x = std::max(0, c.x - radius);
                         x <= std::min(g.dims.x - 1, c.x + radius) && !near; ++x)
                        near = in.get(g.index(x, y, z));
            if (out.get(i) != near) {
                ++wrong;
                ADD_FAILURE() << "dims " << g.dims.x << "x" << g.dims.y << "x" << g.dims.z << " radius "
                              << radius << " at " << c.x << "," << c.y << "," << c.z << ": " << out.get(i);
            }
        }
        EXPECT_EQ(out.count(), [&] {
            uint64_t k = 0;
            for (uint64_t i = 0; i < g.count(); ++i) k += out.get(i);
            return k;
        }()) << "bits set past the last voxel";
        // clear_border() on the same set: exactly the voxels within `radius` of a face go.
        BitVolume inner = in;
        clear_border(g, inner, radius);
        for (uint64_t i = 0; i < g.count(); ++i) {
            const glm::ivec3 c = g.coords(i);
            const bool border = glm::any(glm::lessThan(c, glm::ivec3(radius))) ||
                                glm::any(glm::greaterThanEqual(c, g.dims - radius));
            ASSERT_EQ(inner.get(i), in.get(i) && !border)
                << c.x << "," << c.y << "," << c.z << " k " << radius;
        }
    }
}

// The word-wise passes against plain loops, on a volume big enough for several threads and runs, with a
// partial last run: the same sums and the same indices, ascending, at 1 and 3 threads.
TEST(WordPasses, MatchPlainLoopsAtAnyThreadCount) {
    const size_t n = 3 * kParallelWords + 4097;
    std::vector<uint64_t> a(n), b(n);
    Rng rng(11, 2);
    for (size_t w = 0; w < n; ++w) {
        a[w] = (uint64_t(rng.below(1u << 30)) << 34) ^ rng.below(1u << 30);
        b[w] = w % 7 == 0 ? ~uint64_t(0) : (uint64_t(rng.below(1u << 30)) << 3);
    }
    a[n - 1] |= uint64_t(1) << 63;
    const auto word = [&](size_t w) { return a[w] & ~b[w]; };
    uint64_t want_sum = 0;
    std::vector<uint64_t> want_bits;
    for (size_t w = 0; w < n; ++w) {
        want_sum += uint64_t(__builtin_popcountll(word(w)));
        for (int k = 0; k < 64; ++k)
            if ((word(w) >> k) & 1u) want_bits.push_back(uint64_t(w) * 64 + uint64_t(k));
    }
    const int threads = omp_get_max_threads();
    for (const int t : {1, 3}) {
        omp_set_num_threads(t);
        EXPECT_EQ(sum_words(n, [&](size_t w) { return uint64_t(__builtin_popcountll(word(w))); }), want_sum)
            << t << " threads";
        EXPECT_TRUE(set_bit_indices(n, word) == want_bits) << t << " threads";
        std::vector<uint64_t> c(n);
        for_each_word(n, [&](size_t w) { c[w] = word(w); });
        for (size_t w = 0; w < n; ++w) ASSERT_EQ(c[w], word(w)) << t << " threads, word " << w;
    }
    omp_set_num_threads(threads);
    EXPECT_TRUE(set_bit_indices(0, word).empty());
}

// On a grid big enough for the word loops to run on several threads (rows of 131 voxels, so the rows and
// planes start at every offset in a word): the same bits at 1 and 3 threads, and those of a reference that
// sets the (2r + 1)^3 cube around each set voxel of a sparse set.
TEST(Dilate, BigGridsMatchASparseReferenceAtAnyThreadCount) {
    VoxelGrid g;
    g.voxel_size_m = 1.0f;
    g.dims = glm::ivec3(131, 97, 103);
    BitVolume in;
    in.reset(g.count());
    Rng rng(5, 3);
    for (int k = 0; k < 400; ++k) in.set(rng.below(g.count()));
    in.set(g.index(g.dims.x - 1, 5, 7));
    in.set(g.index(0, g.dims.y - 1, g.dims.z - 1));
    for (const int radius : {1, 4}) {
        BitVolume want;
        want.reset(g.count());
        for (uint64_t i = 0; i < g.count(); ++i) {
            if (!in.get(i)) continue;
            const glm::ivec3 c = g.coords(i);
            const glm::ivec3 lo = glm::max(c - radius, glm::ivec3(0)), hi = glm::min(c + radius, g.dims - 1);
            for (int z = lo.z; z <= hi.z; ++z)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int x = lo.x; x <= hi.x; ++x) want.set(g.index(x, y, z));
        }
        const int threads = omp_get_max_threads();
        omp_set_num_threads(1);
        const BitVolume one = dilate(g, in, radius);
        BitVolume one_inner = want;
        clear_border(g, one_inner, radius);
        omp_set_num_threads(3);
        const BitVolume three = dilate(g, in, radius);
        BitVolume three_inner = want;
        clear_border(g, three_inner, radius);
        omp_set_num_threads(threads);
        EXPECT_TRUE(one.words == want.words) << "radius " << radius;
        EXPECT_TRUE(three.words == want.words) << "radius " << radius;
        EXPECT_TRUE(one_inner.words == three_inner.words) << "radius " << radius;
        uint64_t inside = 0;
        for (uint64_t i = 0; i < g.count(); ++i) {
            const glm::ivec3 c = g.coords(i);
            const bool border = glm::any(glm::lessThan(c, glm::ivec3(radius))) ||
                                glm::any(glm::greaterThanEqual(c, g.dims - radius));
            inside += want.get(i) && !border;
        }
        EXPECT_EQ(three_inner.count(), inside) << "radius " << radius;
    }
}

// A pocket open only at its top, beside a hole that sight enters from below: a flood turns the corner
// into the pocket, straight sight cannot (it would have to go up through the hole and then down). A slice
// one voxel thick (dims.z = 1), x to the right, y up.
TEST(Sight, DoesNotTurnTheCornerAFloodTurns) {
    Context ctx = quiet_context();
    VoxelGrid g;
    g.voxel_size_m = 1.0f;
    g.dims = {20, 12, 1};
    BitVolume blocked, sources;
    blocked.reset(g.count());
    sources.reset(g.count());
    auto at = [&](int x, int y) { return g.index(x, y, 0); };
    for (int x = 0; x < 20; ++x) {
        if (x != 2) blocked.set(at(x, 5));                        // the ceiling, a hole at x = 2
        if (x != 2 && (x < 10 || x > 12)) blocked.set(at(x, 6));  // the pocket: x 10..12 at y = 6
    }
    sources.set(at(2, 0));
    const BitVolume seen = sight_reach(g, blocked, sources);
    EXPECT_TRUE(seen.get(at(2, 0)));
    EXPECT_TRUE(seen.get(at(0, 4)));    // below the ceiling, up and to the side
    EXPECT_TRUE(seen.get(at(19, 0)));   // along the floor
    EXPECT_TRUE(seen.get(at(2, 6)));    // in the hole
    EXPECT_TRUE(seen.get(at(11, 7)));   // above the pocket, through the hole
    EXPECT_TRUE(seen.get(at(19, 11)));  // the far corner above
    for (int x = 10; x <= 12; ++x) EXPECT_FALSE(seen.get(at(x, 6))) << x;  // the pocket
    for (uint64_t i = 0; i < g.count(); ++i) EXPECT_FALSE(seen.get(i) && blocked.get(i)) << i;
    // The flood of free space does turn the corner.
    const FloodResult f = flood_free_space(ctx, g, blocked, {{2.5f, 0.5f, 0.5f}});
    EXPECT_TRUE(f.reached.get(at(11, 6)));
}

// A tunnel along x longer than several words, both ways; and a line through the corner between two
// blocked voxels, which only a corner step follows.
TEST(Sight, RunsDownALongTunnelBothWaysAndThroughACorner) {
    VoxelGrid g;
    g.voxel_size_m = 1.0f;
    g.dims = {200, 3, 3};
    BitVolume blocked, sources;
    blocked.reset(g.count());
    sources.reset(g.count());
    for (uint64_t i = 0; i < g.count(); ++i) {
        const glm::ivec3 c = g.coords(i);
        if (c.y != 1 || c.z != 1) blocked.set(i);
    }
    for (int end : {0, 199}) {
        sources.reset(g.count());
        sources.set(g.index(end, 1, 1));
        const BitVolume seen = sight_reach(g, blocked, sources);
        for (int x = 0; x < 200; ++x) ASSERT_TRUE(seen.get(g.index(x, 1, 1))) << end << " " << x;
        EXPECT_EQ(seen.count(), 200u);
    }
    g.dims = {70, 4, 4};
    for (int octant = 0; octant < 8; ++octant) {
        const int sx = octant & 1 ? -1 : 1, sy = octant & 2 ? -1 : 1, sz = octant & 4 ? -1 : 1;
        const glm::ivec3 a(sx > 0 ? 62 : 65, sy > 0 ? 1 : 2, sz > 0 ? 1 : 2), b = a + glm::ivec3(sx, sy, sz);
        blocked.reset(g.count());
        sources.reset(g.count());
        for (uint64_t i = 0; i < g.count(); ++i) blocked.set(i);
        blocked.clear(g.index(a.x, a.y, a.z));
        blocked.clear(g.index(b.x, b.y, b.z));
        sources.set(g.index(a.x, a.y, a.z));
        const BitVolume seen = sight_reach(g, blocked, sources);
        EXPECT_TRUE(seen.get(g.index(b.x, b.y, b.z))) << octant;
        EXPECT_EQ(seen.count(), 2u) << octant;
    }
}

// The sweep's definition, a voxel at a time: per octant (sx, sy, sz), a voxel is reached when it is open
// and a source, or open and one of its 7 predecessors (minus a nonzero combination of sx, sy, sz steps)
// is reached; sight_reach is the union over the octants. Against it, at 1 and 3 threads (the octants run
// on several threads and OR their rows into one volume), on grids whose rows end at odd offsets.
TEST(Sight, EqualsAVoxelByVoxelSweepAtAnyThreadCount) {
    Rng rng(23, 5);
    for (int trial = 0; trial < 4; ++trial) {
        VoxelGrid g;
        g.voxel_size_m = 1.0f;
        g.dims = {37 + 41 * trial, 9 + trial, 7 + 2 * trial};
        BitVolume blocked, sources;
        blocked.reset(g.count());
        sources.reset(g.count());
        for (uint64_t i = 0; i < g.count(); ++i) {
            if (rng.uniform() < 0.3f) blocked.set(i);
            if (rng.uniform() < 0.002f) sources.set(i);
        }
        std::vector<uint8_t> want(g.count(), 0);
        for (int octant = 0; octant < 8; ++octant) {
            const glm::ivec3 st(octant & 1 ? -1 : 1, octant & 2 ? -1 : 1, octant & 4 ? -1 : 1);
            std::vector<uint8_t> reach(g.count(), 0);
            for (int kz = 0; kz < g.dims.z; ++kz)
                for (int ky = 0; ky < g.dims.y; ++ky)
                    for (int kx = 0; kx < g.dims.x; ++kx) {
                        const glm::ivec3 c(st.x > 0 ? kx : g.dims.x - 1 - kx, st.y > 0 ? ky : g.dims.y - 1 - ky,
                                           st.z > 0 ? kz : g.dims.z - 1 - kz);
                        const uint64_t i = g.index(c.x, c.y, c.z);
                        if (blocked.get(i)) continue;
                        bool r = sources.get(i);
                        for (int e = 1; e < 8 && !r; ++e) {
                            const glm::ivec3 p = c - glm::ivec3(e & 1 ? st.x : 0, e & 2 ? st.y : 0, e & 4 ? st.z : 0);
                            r = g.inside(p) && reach[g.index(p.x, p.y, p.z)];
                        }
                        reach[i] = r;
                        want[i] |= r;
                    }
        }
        const int threads = omp_get_max_threads();
        for (const int t : {1, 3}) {
            omp_set_num_threads(t);
            const BitVolume seen = sight_reach(g, blocked, sources);
            omp_set_num_threads(threads);
            uint64_t wrong = 0;
            for (uint64_t i = 0; i < g.count(); ++i) wrong += seen.get(i) != bool(want[i]);
            EXPECT_EQ(wrong, 0u) << "trial " << trial << ", " << t << " threads";
            for (uint64_t i = g.count(); i < seen.words.size() * 64; ++i)
                ASSERT_FALSE(seen.get(i)) << "a bit past the last voxel, trial " << trial;
        }
    }
}

// Property: every voxel a straight ray from a source voxel passes before it enters a blocked voxel is in
// sight_reach (random grids, blocked voxels and rays; rays marched in steps of a tenth of a voxel).
TEST(Sight, HoldsEveryVoxelARayReaches) {
    Rng rng(11, 3);
    for (int trial = 0; trial < 6; ++trial) {
        VoxelGrid g;
        g.voxel_size_m = 1.0f;
        g.dims = {67 + trial, 23, 19 + trial};  // rows longer than a word, odd sizes
        BitVolume blocked, sources;
        blocked.reset(g.count());
        sources.reset(g.count());
        const float density = 0.08f + 0.04f * float(trial);
        for (uint64_t i = 0; i < g.count(); ++i)
            if (rng.uniform() < density) blocked.set(i);
        // A closed shell of blocked voxels: its inside is out of every sight.
        const glm::ivec3 lo(40, 5, 5), hi(50, 15, 12);
        auto in_shell = [&](glm::ivec3 c) {
            return glm::all(glm::greaterThanEqual(c, lo)) && glm::all(glm::lessThanEqual(c, hi));
        };
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const bool wall =
                        x == lo.x || x == hi.x || y == lo.y || y == hi.y || z == lo.z || z == hi.z;
                    if (wall)
                        blocked.set(g.index(x, y, z));
                    else
                        blocked.clear(g.index(x, y, z));
                }
        std::vector<glm::ivec3> src;
        while (src.size() < 5) {
            const glm::ivec3 c(int(rng.uniform() * float(g.dims.x)) % g.dims.x,
                               int(rng.uniform() * float(g.dims.y)) % g.dims.y,
                               int(rng.uniform() * float(g.dims.z)) % g.dims.z);
            if (in_shell(c)) continue;
            blocked.clear(g.index(c.x, c.y, c.z));
            sources.set(g.index(c.x, c.y, c.z));
            src.push_back(c);
        }
        const BitVolume seen = sight_reach(g, blocked, sources);
        uint64_t checked = 0;
        for (int r = 0; r < 4000; ++r) {
            const glm::ivec3 c = src[size_t(r) % src.size()];
            const glm::vec3 o = glm::vec3(c) + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
            glm::vec3 d(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
            if (glm::length(d) < 1e-3f) continue;
            d = glm::normalize(d);
            for (float t = 0.0f;; t += 0.1f) {
                const glm::vec3 p = o + t * d;
                if (!g.bounds().contains(p)) break;
                const glm::ivec3 v = g.voxel_of(p);
                const uint64_t i = g.index(v.x, v.y, v.z);
                if (blocked.get(i)) break;
                ASSERT_TRUE(seen.get(i))
                    << "trial " << trial << " ray " << r << " voxel " << v.x << " " << v.y << " " << v.z;
                ++checked;
            }
        }
        EXPECT_GT(checked, 10000u);
        EXPECT_FALSE(seen.get(g.index(45, 10, 8))) << trial;  // inside the shell
        uint64_t outside_free = 0, outside_seen = 0;
        for (uint64_t i = 0; i < g.count(); ++i) {
            if (blocked.get(i) || in_shell(g.coords(i))) continue;
            ++outside_free;
            outside_seen += seen.get(i);
        }
        EXPECT_GT(outside_seen, outside_free / 2) << trial;
    }
}

}  // namespace
}  // namespace pvs
