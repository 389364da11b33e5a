// SPDX-License-Identifier: MIT
// The umbra pass (pvs/umbra_volume.h): every block it marks hidden from a region is held to dense segments
// against the occluders it was given (random scenes of solid boxes and panels); staggered pillars that no
// pillar hides alone hide together, through the space the first row hides; with the gaps in line, or a slit
// through a wall, what lies behind stays listed.
#include "core/random.h"
#include "pvs/umbra_volume.h"
#include "tests/random_boxes.h"
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

// Occluders on a grid of `voxel` m from `origin`, `dims` voxels: the solid is the union of `solid_boxes`
// (voxel coordinates, [lo, hi)); each is also a floor-epsilon box (a seed), shrunk by a tenth of a voxel.
ShrunkOccluders make_set(glm::vec3 origin, float voxel, glm::ivec3 dims,
                         const std::vector<std::pair<glm::ivec3, glm::ivec3>>& solid_boxes) {
    ShrunkOccluders occ;
    occ.epsilon_m = {0.1};
    occ.boxes = {{}};
    VoxelMask& m = occ.solid;
    m.origin = origin;
    m.voxel_size_m = voxel;
    m.dims = dims;
    m.bits.assign((m.count() + 63) / 64, 0);
    for (const auto& [lo, hi] : solid_boxes) {
        for (int z = lo.z; z < hi.z; ++z)
            for (int y = lo.y; y < hi.y; ++y)
                for (int x = lo.x; x < hi.x; ++x) {
                    const uint64_t i =
                        uint64_t(x) + uint64_t(dims.x) * (uint64_t(y) + uint64_t(dims.y) * uint64_t(z));
                    m.bits[i >> 6] |= uint64_t(1) << (i & 63);
                }
        const glm::vec3 a = origin + glm::vec3(lo) * voxel + 0.1f * voxel;
        const glm::vec3 b = origin + glm::vec3(hi) * voxel - 0.1f * voxel;
        occ.boxes[0].push_back(Aabb::of(a, b));
    }
    return occ;
}

// The slow reference: does the segment meet a panel (closed) or the inside of a solid box?
bool blocked(const ShrunkOccluders& occ, const std::vector<Aabb>& solid, glm::dvec3 q, glm::dvec3 x) {
    for (const Aabb& p : occ.panels)
        if (segment_meets_closed_box(p, q, x)) return true;
    for (const Aabb& b : solid) {
        const Aabb inner = Aabb::of(b.min + 1e-4f, b.max - 1e-4f);
        if (segment_meets_closed_box(inner, q, x)) return true;
    }
    return false;
}

std::vector<Aabb> world_boxes(glm::vec3 origin, float voxel,
                              const std::vector<std::pair<glm::ivec3, glm::ivec3>>& v) {
    std::vector<Aabb> out;
    for (const auto& [lo, hi] : v)
        out.push_back(Aabb::of(origin + glm::vec3(lo) * voxel, origin + glm::vec3(hi) * voxel));
    return out;
}

// Every block marked hidden from a random region of random scenes of solid boxes and panels: the 64 corner
// segments and random ones from the region to it all meet an occluder.
TEST(UmbraVolume, EveryHiddenBlockIsHiddenFromTheWholeRegionByDenseSegments) {
    Context ctx = quiet_context();
    Rng rng(71, 3);
    uint64_t hidden_total = 0, checked = 0;
    for (int scene = 0; scene < 12; ++scene) {
        SCOPED_TRACE("scene " + std::to_string(scene));
        const glm::vec3 origin(0.0f);
        const float voxel = 0.25f;
        const glm::ivec3 dims(48, 24, 48);
        std::vector<std::pair<glm::ivec3, glm::ivec3>> solid;
        solid.push_back({{0, 0, 0}, {48, 2, 48}});  // a floor
        for (int i = 0; i < 14; ++i) {
            glm::ivec3 lo(int(rng.uniform() * 44), 2, int(rng.uniform() * 44));
            glm::ivec3 size(1 + int(rng.uniform() * 8), 2 + int(rng.uniform() * 16),
                            1 + int(rng.uniform() * 8));
            if (rng.uniform() < 0.5f)
                size.x = 1 + int(rng.uniform() * 2);
            else
                size.z = 1 + int(rng.uniform() * 2);
            solid.push_back({lo, glm::min(lo + size, dims)});
        }
        ShrunkOccluders occ = make_set(origin, voxel, dims, solid);
        for (int i = 0; i < 4; ++i) {
            const float x = 1.0f + rng.uniform() * 10.0f, z = 1.0f + rng.uniform() * 10.0f;
            if (rng.uniform() < 0.5f)
                occ.panels.push_back(
                    Aabb::of({x, 0.5f, z}, {x, 0.5f + rng.uniform() * 4.0f, z + rng.uniform() * 3.0f}));
            else
                occ.panels.push_back(
                    Aabb::of({x, 0.5f, z}, {x + rng.uniform() * 3.0f, 0.5f + rng.uniform() * 4.0f, z}));
        }
        const std::vector<Aabb> boxes = world_boxes(origin, voxel, solid);
        // A region above the floor, clear of the solid.
        Aabb region;
        for (int attempt = 0; attempt < 100; ++attempt) {
            const glm::vec3 c(1.0f + rng.uniform() * 10.0f, 1.0f + rng.uniform() * 2.0f,
                              1.0f + rng.uniform() * 10.0f);
            region = Aabb::of(c - 0.4f, c + 0.4f);
            bool clear = true;
            for (const Aabb& b : boxes) clear = clear && !b.overlaps(region);
            if (clear) break;
            region = Aabb::empty();
        }
        if (region.is_empty()) continue;
        World w;
        UmbraHider hider(ctx, w, occ, 2);
        const std::vector<uint8_t> hidden = hider.hidden_blocks(region);
        const glm::ivec3 bd = hider.block_dims();
        for (int z = 0; z < bd.z; ++z)
            for (int y = 0; y < bd.y; ++y)
                for (int x = 0; x < bd.x; ++x) {
                    if (!hidden[size_t(x) + size_t(bd.x) * (size_t(y) + size_t(bd.y) * size_t(z))]) continue;
                    ++hidden_total;
                    if (rng.uniform() > 0.1f) continue;  // a tenth of them, densely
                    ++checked;
                    glm::dvec3 lo, hi;
                    hider.block_box({x, y, z}, lo, hi);
                    const Aabb block = Aabb::of(glm::vec3(lo), glm::vec3(hi));
                    for (int s = 0; s < 96; ++s) {
                        const glm::dvec3 q(s < 64 ? glm::vec3(s & 1 ? region.max.x : region.min.x,
                                                              s & 2 ? region.max.y : region.min.y,
                                                              s & 4 ? region.max.z : region.min.z)
                                                  : point_in(region, rng));
                        const glm::dvec3 p(s < 64 ? glm::vec3(s & 8 ? block.max.x : block.min.x,
                                                              s & 16 ? block.max.y : block.min.y,
                                                              s & 32 ? block.max.z : block.min.z)
                                                  : point_in(block, rng));
                        ASSERT_TRUE(blocked(occ, boxes, q, p))
                            << "block (" << x << ", " << y << ", " << z
                            << ") marked hidden, but the segment from (" << q.x << ", " << q.y << ", " << q.z
                            << ") to (" << p.x << ", " << p.y << ", " << p.z << ") meets no occluder";
                    }
                }
    }
    EXPECT_GT(checked, 200u) << "too few hidden blocks to check: the test is vacuous";
    std::printf("%llu blocks hidden, %llu checked\n", (unsigned long long)hidden_total,
                (unsigned long long)checked);
}

// Two rows of pillars (the proven solid, 0.6 m wide, 0.4 m gaps), the second row's pillars behind the first
// row's gaps: the object behind is hidden from the whole cell though no pillar hides it alone; the second
// row's pillars join through the space the first row hides. With the second row in line with the first
// (gaps in line), it stays listed.
TEST(UmbraVolume, StaggeredPillarsHideTogetherAndGapsInLineDoNot) {
    Context ctx = quiet_context();
    for (const bool staggered : {true, false}) {
        SCOPED_TRACE(staggered ? "staggered" : "in line");
        const glm::vec3 origin(-4.0f, -1.0f, -4.0f);
        const float voxel = 0.1f;
        const glm::ivec3 dims(120, 60, 120);
        std::vector<std::pair<glm::ivec3, glm::ivec3>> solid;
        solid.push_back({{0, 0, 0}, {120, 10, 120}});  // the floor, y in [-1, 0]
        // Pillars along x (0.6 m wide, every 1 m), y in [0, 4]; row 1 at z in [2, 2.4], row 2 at z in [2.6,
        // 3].
        for (int k = -3; k <= 3; ++k) {
            const int x0 = 40 + 10 * k;  // x = k m
            solid.push_back({{x0, 10, 60}, {x0 + 6, 50, 64}});
            const int x1 = staggered ? x0 + 5 : x0;
            solid.push_back({{x1, 10, 66}, {x1 + 6, 50, 70}});
        }
        const ShrunkOccluders occ = make_set(origin, voxel, dims, solid);
        World w;
        const uint32_t object = test::add_box(w, "o", Aabb::of({0.0f, 0.5f, 5.0f}, {0.5f, 1.0f, 5.5f}));
        const Aabb cell = Aabb::of({-0.2f, 1.0f, -1.0f}, {0.6f, 1.8f, -0.2f});
        UmbraHider hider(ctx, w, occ, 1);
        uint64_t hidden = 0;
        UmbraFigures f;
        EXPECT_EQ(hider.hide(w, cell, {object}, &hidden, &f), staggered ? 1u : 0u)
            << f.blockers << " blockers, " << f.nodes_hidden << " nodes hidden";
        // No pillar alone: a pillar of the same rows, with the rest gone, hides it from no cell this wide.
        const std::vector<Aabb> boxes = world_boxes(origin, voxel, solid);
        Rng rng(5, 1);
        bool clear_line = false;
        for (int s = 0; s < 20000 && !clear_line; ++s)
            clear_line = !blocked(occ, boxes, glm::dvec3(point_in(cell, rng)),
                                  glm::dvec3(point_in(w.objects[object].bounds, rng)));
        EXPECT_EQ(clear_line, !staggered) << "the scene is not what the test means";
    }
}

// A wall with a 5 cm slit: what lies behind the slit stays listed, what lies behind the wall away from it
// is hidden.
TEST(UmbraVolume, ASlitThroughAWallKeepsWhatIsBehindItListed) {
    Context ctx = quiet_context();
    const glm::vec3 origin(-4.0f, -1.0f, -4.0f);
    const float voxel = 0.05f;
    const glm::ivec3 dims(160, 120, 160);
    std::vector<std::pair<glm::ivec3, glm::ivec3>> solid;
    solid.push_back({{0, 0, 0}, {160, 20, 160}});     // floor
    solid.push_back({{0, 20, 80}, {80, 100, 84}});    // wall, x in [-4, 0]
    solid.push_back({{81, 20, 80}, {160, 100, 84}});  // wall, x in [0.05, 4]: a slit at x in [0, 0.05]
    const ShrunkOccluders occ = make_set(origin, voxel, dims, solid);
    World w;
    const uint32_t behind_slit = test::add_box(w, "slit", Aabb::of({-0.2f, 1.0f, 1.0f}, {0.2f, 1.4f, 1.4f}));
    const uint32_t behind_wall = test::add_box(w, "wall", Aabb::of({2.5f, 1.0f, 1.0f}, {2.9f, 1.4f, 1.4f}));
    const Aabb cell = Aabb::of({-0.5f, 0.5f, -1.5f}, {0.5f, 1.5f, -0.5f});
    UmbraHider hider(ctx, w, occ, 2);
    uint64_t hidden = 0;
    hider.hide(w, cell, {behind_slit, behind_wall}, &hidden);
    EXPECT_FALSE(hidden & (uint64_t(1) << behind_slit)) << "hidden through the slit";
    EXPECT_TRUE(hidden & (uint64_t(1) << behind_wall)) << "the wall alone hides it";
}

}  // namespace
}  // namespace pvs
