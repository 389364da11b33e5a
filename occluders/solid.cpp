// SPDX-License-Identifier: MIT
// Solid classification: sight from the eye space through untouched voxels (voxels/flood.h sight_reach);
// the rest, less the touched voxels, is solid.
#include "occluders/solid.h"

#include "core/error.h"
#include "voxels/flood.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace pvs {

Solid classify_solid(Context& ctx, const VoxelGrid& grid, const BitVolume& touched, const VoxelMask& eyes) {
    ScopedTimer timer(ctx, "solid");
    Solid out;
    out.grid = grid;
    out.from_eye_space = !eyes.empty();
    const BitVolume sources = sight_sources(grid, eyes);
    const BitVolume reached = sight_reach(grid, touched, sources);
    out.solid.reset(grid.count());
    for_each_word(out.solid.words.size(),
                  [&](size_t w) { out.solid.words[w] = ~(reached.words[w] | touched.words[w]); });
    const uint64_t tail = grid.count() % 64;
    if (tail) out.solid.words.back() &= (uint64_t(1) << tail) - 1;
    out.solid_voxels = out.solid.count();
    out.solid_m3 =
        double(out.solid_voxels) * double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    ctx.info(fmt::format("solid: {:.0f} m3 in {} voxels ({})", out.solid_m3, out.solid_voxels,
                         out.from_eye_space ? "sealed off from the eyes" : "inside closed meshes"));
    return out;
}

BitVolume sight_sources(const VoxelGrid& grid, const VoxelMask& eyes) {
    BitVolume sources;
    sources.reset(grid.count());
    if (!eyes.empty()) {
        if (eyes.dims != grid.dims || eyes.origin != grid.origin || eyes.voxel_size_m != grid.voxel_size_m) {
            throw internal_error("sight_sources: the eye mask is not on the voxel grid");
        }
        sources.words = eyes.bits;
        return sources;
    }
    for (int z = 0; z < grid.dims.z; ++z)
        for (int y = 0; y < grid.dims.y; ++y)
            for (int x = 0; x < grid.dims.x; ++x) {
                const bool border = x == 0 || y == 0 || z == 0 || x == grid.dims.x - 1 ||
                                    y == grid.dims.y - 1 || z == grid.dims.z - 1;
                if (border) sources.set(grid.index(x, y, z));
            }
    return sources;
}

uint64_t reopen_leaks(const BitVolume& touched, const BitVolume& leaky, const BitVolume& sources,
                      Solid& solid) {
    BitVolume blocked;
    blocked.words.resize(touched.words.size());
    for_each_word(blocked.words.size(),
                  [&](size_t w) { blocked.words[w] = touched.words[w] & ~leaky.words[w]; });
    const BitVolume reached = sight_reach(solid.grid, blocked, sources);
    const uint64_t removed = sum_words(solid.solid.words.size(), [&](size_t w) {
        const uint64_t gone = solid.solid.words[w] & (reached.words[w] | leaky.words[w]);
        solid.solid.words[w] &= ~gone;
        return uint64_t(__builtin_popcountll(gone));
    });
    solid.solid_voxels -= removed;
    const double v = solid.grid.voxel_size_m;
    solid.solid_m3 = double(solid.solid_voxels) * v * v * v;
    return removed;
}

uint64_t open_seen_and_leaky(const BitVolume& touched, const BitVolume& seen, const BitVolume& leaky,
                             const BitVolume& sources, Solid& solid) {
    const uint64_t seen_removed = sum_words(seen.words.size(), [&](size_t w) {
        const uint64_t gone = solid.solid.words[w] & seen.words[w];
        solid.solid.words[w] &= ~gone;
        return uint64_t(__builtin_popcountll(gone));
    });
    solid.solid_voxels -= seen_removed;
    return seen_removed + reopen_leaks(touched, leaky, sources, solid);
}

std::vector<Aabb> closed_box_objects(const World& world) {
    std::vector<Aabb> out;
    for (const WorldObject& obj : world.objects) {
        const Aabb b = obj.bounds;
        if (obj.triangle_count < 12 || b.is_empty()) continue;
        const glm::dvec3 size = glm::dvec3(b.max) - glm::dvec3(b.min);
        if (!(size.x > 0.0 && size.y > 0.0 && size.z > 0.0)) continue;
        std::array<double, 6> area{};  // per face: axis * 2 + (0 at min, 1 at max)
        bool ok = true;
        for (uint32_t t = obj.first_triangle; ok && t < obj.first_triangle + obj.triangle_count; ++t) {
            if (!world.triangle_opaque[t]) {
                ok = false;
                break;
            }
            const glm::vec3 p[3] = {world.positions[world.triangles[t].v[0]],
                                    world.positions[world.triangles[t].v[1]],
                                    world.positions[world.triangles[t].v[2]]};
            int face = -1;
            for (int a = 0; a < 3 && face < 0; ++a) {
                if (p[0][a] == b.min[a] && p[1][a] == b.min[a] && p[2][a] == b.min[a]) face = 2 * a;
                if (p[0][a] == b.max[a] && p[1][a] == b.max[a] && p[2][a] == b.max[a]) face = 2 * a + 1;
            }
            if (face < 0) {
                ok = false;
                break;
            }
            const glm::dvec3 e1 = glm::dvec3(p[1]) - glm::dvec3(p[0]),
                             e2 = glm::dvec3(p[2]) - glm::dvec3(p[0]);
            area[size_t(face)] += 0.5 * glm::length(glm::cross(e1, e2));
        }
        for (int f = 0; ok && f < 6; ++f) {
            const int a = f / 2;
            const double face_area = size[(a + 1) % 3] * size[(a + 2) % 3];
            ok = std::abs(area[size_t(f)] - face_area) <= 1e-5 * face_area;
        }
        if (ok) out.push_back(b);
    }
    return out;
}

namespace {

// Is the closed box v covered by the union of the closed boxes? Subtracts each box in turn; what is left
// with no volume (a plane or a line) is in the closure of the covered part, so in the closed union.
bool covered_by_union(const Aabb& v, const std::vector<const Aabb*>& boxes) {
    constexpr float kThin = 1e-6f;
    std::vector<Aabb> pieces{v}, next;
    for (const Aabb* bp : boxes) {
        const Aabb& b = *bp;
        next.clear();
        for (Aabb p : pieces) {
            if (!p.overlaps(b)) {
                next.push_back(p);
                continue;
            }
            for (int a = 0; a < 3; ++a) {  // peel off the parts of p outside b, axis by axis
                if (p.min[a] < b.min[a]) {
                    Aabb q = p;
                    q.max[a] = b.min[a];
                    next.push_back(q);
                    p.min[a] = b.min[a];
                }
                if (p.max[a] > b.max[a]) {
                    Aabb q = p;
                    q.min[a] = b.max[a];
                    next.push_back(q);
                    p.max[a] = b.max[a];
                }
            }
        }
        pieces.clear();
        for (const Aabb& p : next) {
            const glm::vec3 s = p.size();
            if (s.x > kThin && s.y > kThin && s.z > kThin) pieces.push_back(p);
        }
        if (pieces.empty()) return true;
    }
    return pieces.empty();
}

}  // namespace

uint64_t add_closed_boxes(Context& ctx, const std::vector<Aabb>& boxes, const VoxelMask& eyes, Solid& solid) {
    const VoxelGrid& grid = solid.grid;
    std::vector<Aabb> usable;
    for (const Aabb& b : boxes) {
        bool eye_inside = false;
        if (!eyes.empty()) {
            const glm::ivec3 lo = grid.voxel_of(b.min), hi = grid.voxel_of(b.max);
            for (int z = lo.z; z <= hi.z && !eye_inside; ++z)
                for (int y = lo.y; y <= hi.y && !eye_inside; ++y)
                    for (int x = lo.x; x <= hi.x && !eye_inside; ++x)
                        eye_inside = eyes.get(grid.index(x, y, z)) && grid.voxel_box({x, y, z}).overlaps(b);
        }
        if (!eye_inside) usable.push_back(b);
    }
    // Per voxel a box meets: the boxes meeting it (only voxels not already solid).
    std::unordered_map<uint64_t, std::vector<const Aabb*>> meeting;
    for (const Aabb& b : usable) {
        const glm::ivec3 lo = grid.voxel_of(b.min), hi = grid.voxel_of(b.max);
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const uint64_t i = grid.index(x, y, z);
                    if (!solid.solid.get(i) && grid.voxel_box({x, y, z}).overlaps(b))
                        meeting[i].push_back(&b);
                }
    }
    std::vector<uint64_t> order;
    for (const auto& [i, list] : meeting) order.push_back(i);
    std::sort(order.begin(), order.end());
    uint64_t added = 0;
    for (uint64_t i : order) {
        if (covered_by_union(grid.voxel_box(grid.coords(i)), meeting[i])) {
            solid.solid.set(i);
            ++added;
        }
    }
    solid.solid_voxels += added;
    solid.solid_m3 =
        double(solid.solid_voxels) * double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    ctx.info(
        fmt::format("solid: {} closed box meshes ({} with an eye inside left out) add {} voxels, seams "
                    "between them included",
                    usable.size(), boxes.size() - usable.size(), added));
    return added;
}

}  // namespace pvs
