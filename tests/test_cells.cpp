// SPDX-License-Identifier: MIT
// Uniform grid: dimensions, lookup at borders and corners; eye points and sphere directions.
#include "cells/eyes.h"
#include "cells/grid.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

TEST(Grid, CoversTheRegionWithWholeCells) {
    Context ctx = quiet_context();
    const CellSet g =
        build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 2.0}, Aabb::of({0, 0, 0}, {5, 2, 4}));
    EXPECT_EQ(g.dims, glm::ivec3(3, 1, 2));
    ASSERT_EQ(g.size(), 6u);
    EXPECT_EQ(g.cells[0].bounds, Aabb::of({0, 0, 0}, {2, 2, 2}));
    // x fastest, then y, then z.
    EXPECT_EQ(g.cells[4].bounds, Aabb::of({2, 0, 2}, {4, 2, 4}));
}

TEST(Grid, LookupAtBordersAndCorners) {
    Context ctx = quiet_context();
    const CellSet g =
        build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 1.0}, Aabb::of({-2, 0, 0}, {2, 1, 2}));
    ASSERT_EQ(g.dims, glm::ivec3(4, 1, 2));
    EXPECT_EQ(g.find({-2, 0, 0}), 0);  // the min corner
    EXPECT_EQ(g.find({-1.5f, 0.5f, 0.5f}), 0);
    EXPECT_EQ(g.find({-1, 0.5f, 0.5f}), 1);  // a shared face belongs to the higher cell
    EXPECT_EQ(g.find({2, 1, 2}), 7);         // the max corner belongs to the last cell
    EXPECT_EQ(g.find({1.999f, 0.999f, 1.999f}), 7);
    EXPECT_EQ(g.find({0, 0.5f, 1.0f}), 2 + 4);
    EXPECT_EQ(g.find({-2.001f, 0.5f, 0.5f}), -1);  // outside
    EXPECT_EQ(g.find({0, 1.001f, 0.5f}), -1);
    EXPECT_EQ(g.find({0, 0.5f, std::nanf("")}), -1);
}

TEST(Grid, RefusesAGridTooLargeToHold) {
    Context ctx = quiet_context();
    try {
        build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 0.01}, Aabb::of({0, 0, 0}, {1000, 1000, 1000}));
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
        EXPECT_NE(std::string(e.what()).find("--cell-size"), std::string::npos) << e.what();
    }
}

TEST(Eyes, StratifiedInsideTheCellAndDeterministic) {
    Context ctx = quiet_context();
    const CellSet g =
        build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 2.0}, Aabb::of({0, 0, 0}, {4, 2, 2}));
    std::vector<glm::vec3> a, b, other;
    sample_eye_points(g, 1, 27, 42, a);
    sample_eye_points(g, 1, 27, 42, b);
    sample_eye_points(g, 1, 27, 43, other);
    ASSERT_EQ(a.size(), 27u);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, other);
    // 27 = 3 x 3 x 3 strata: each stratum holds exactly one point.
    int hits[27] = {};
    for (const glm::vec3& p : a) {
        ASSERT_TRUE(g.cells[1].bounds.contains(p));
        const glm::ivec3 s = glm::min(glm::ivec3((p - g.cells[1].bounds.min) / (2.0f / 3.0f)), glm::ivec3(2));
        ++hits[s.x + 3 * (s.y + 3 * s.z)];
    }
    for (int h : hits) EXPECT_EQ(h, 1);
}

// Drawing from the eye voxels gathered once (what verification's rounds do) gives the points a fresh walk of
// the mask gives, all in eye voxels of the cell.
TEST(Eyes, FromGatheredEyeVoxelsTheSamePointsAsFromTheMask) {
    Context ctx = quiet_context();
    CellSet g = build_uniform_grid(ctx, CellConfig{CellKind::kGrid, 2.0}, Aabb::of({0, 0, 0}, {4, 2, 2}));
    g.eyes.origin = glm::vec3(0.0f);
    g.eyes.voxel_size_m = 0.25f;
    g.eyes.dims = glm::ivec3(16, 8, 8);
    g.eyes.bits.assign(size_t(g.eyes.count() + 63) / 64, 0);
    for (uint64_t i = 0; i < g.eyes.count(); ++i)
        if ((i * 2654435761u) % 7 < 3) g.eyes.bits[i / 64] |= uint64_t(1) << (i % 64);
    const std::vector<uint64_t> voxels = eye_voxels_in(g, g.cells[1].bounds);
    ASSERT_FALSE(voxels.empty());
    for (uint64_t stream = 0; stream < 8; ++stream) {
        std::vector<glm::vec3> walked, drawn;
        sample_eye_points_in(g, g.cells[1].bounds, stream, 5, 42, walked);
        sample_eye_points_from(g, g.cells[1].bounds, voxels, stream, 5, 42, drawn);
        ASSERT_EQ(walked.size(), 5u);
        EXPECT_EQ(walked, drawn) << "stream " << stream;
        for (const glm::vec3& p : drawn) {
            EXPECT_TRUE(g.cells[1].bounds.contains(p));
            EXPECT_TRUE(g.eyes.contains(p)) << p.x << " " << p.y << " " << p.z;
        }
    }
}

TEST(Directions, UnitAndSpreadOverTheSphere) {
    std::vector<glm::vec3> d;
    sample_sphere_directions(2048, 7, 3, d);
    ASSERT_EQ(d.size(), 2048u);
    glm::dvec3 mean(0.0);
    int octant[8] = {};
    for (const glm::vec3& v : d) {
        EXPECT_NEAR(glm::length(v), 1.0f, 1e-5f);
        mean += glm::dvec3(v);
        ++octant[(v.x > 0) + 2 * (v.y > 0) + 4 * (v.z > 0)];
    }
    mean /= double(d.size());
    EXPECT_LT(glm::length(mean), 0.02);
    for (int n : octant) EXPECT_NEAR(n, 256, 40);
}

}  // namespace
}  // namespace pvs
