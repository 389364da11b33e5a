// SPDX-License-Identifier: MIT
// The gap probe: lines across the gaps between nearby opaque triangles, looking for sight into the solid.
#include "occluders/gap_probe.h"

#include "rays/clearance.h"
#include "voxels/voxel_walk.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

using glm::dvec3;

// Voxels from the solid a gap's middle may lie (its voxel is near the solid; the gap may be the far end of
// a crack whose near end opens onto the solid).
constexpr int kNearSolidVoxels = 2;

// The edge of the blocks searched, in voxels: a gap's middle is looked for once per block (from its centre),
// so along a long slit one line fan every kBlockVoxels voxels.
constexpr int kBlockVoxels = 2;

bool shares_corner(const TriangleCorners& s, const TriangleCorners& t) {
    const glm::vec3 a[3] = {s.a, s.b, s.c}, b[3] = {t.a, t.b, t.c};
    for (const glm::vec3& p : a)
        for (const glm::vec3& q : b)
            if (p == q) return true;
    return false;
}

// Do the boxes of the two triangles come within `gap` of each other?
bool boxes_within(const TriangleCorners& s, const TriangleCorners& t, float gap) {
    const glm::vec3 lo_s = glm::min(s.a, glm::min(s.b, s.c)), hi_s = glm::max(s.a, glm::max(s.b, s.c));
    const glm::vec3 lo_t = glm::min(t.a, glm::min(t.b, t.c)), hi_t = glm::max(t.a, glm::max(t.b, t.c));
    return glm::all(glm::lessThanEqual(lo_s - gap, hi_t)) && glm::all(glm::lessThanEqual(lo_t - gap, hi_s));
}

// The pair's closest points near `start`: alternating nearest points (for two convex sets they converge to
// a closest pair; where the closest pairs form a face, as between parallel walls, to the one near start).
void local_closest_pair(const TriangleCorners& s, const TriangleCorners& t, dvec3 start, dvec3& a, dvec3& b) {
    const dvec3 sa(s.a), sb(s.b), sc(s.c), ta(t.a), tb(t.b), tc(t.c);
    a = closest_point_on_triangle(start, sa, sb, sc);
    b = closest_point_on_triangle(a, ta, tb, tc);
    for (int k = 0; k < 3; ++k) {
        a = closest_point_on_triangle(b, sa, sb, sc);
        b = closest_point_on_triangle(a, ta, tb, tc);
    }
}

// Two unit vectors completing unit n to an orthonormal basis.
void basis_of(glm::vec3 n, glm::vec3& u, glm::vec3& v) {
    const glm::vec3 other = std::abs(n.x) < 0.6f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    u = glm::normalize(glm::cross(n, other));
    v = glm::cross(n, u);
}

// Does a triangle of `tris` other than the i-th have both p and q as corners?
bool edge_shared(const std::vector<TriangleCorners>& tris, size_t i, glm::vec3 p, glm::vec3 q) {
    for (size_t j = 0; j < tris.size(); ++j) {
        if (j == i) continue;
        const TriangleCorners& t = tris[j];
        const bool has_p = t.a == p || t.b == p || t.c == p, has_q = t.a == q || t.b == q || t.c == q;
        if (has_p && has_q) return true;
    }
    return false;
}

// The distance from c to the nearest of `tris` (at most cap), and that nearest point.
double room_at(dvec3 c, const std::vector<TriangleCorners>& tris, double cap, dvec3* nearest) {
    double best = cap * cap;
    for (const TriangleCorners& t : tris) {
        const dvec3 q = closest_point_on_triangle(c, dvec3(t.a), dvec3(t.b), dvec3(t.c));
        const double d2 = glm::dot(c - q, c - q);
        if (d2 < best) {
            best = d2;
            if (nearest) *nearest = q;
        }
    }
    return std::sqrt(best);
}

// A point of locally most room near `start`: steps away from the nearest triangle, as long as the room
// grows (halving a step that does not), for a few steps. Returns start when it has no room at all.
dvec3 most_room_near(dvec3 start, const std::vector<TriangleCorners>& tris, double least, double cap) {
    dvec3 c = start, q(0.0);
    double room = room_at(c, tris, cap, &q);
    if (!(room > 0.0)) return start;
    for (int step = 0; step < 12 && room < cap; ++step) {
        const dvec3 away = (c - q) / std::max(glm::length(c - q), 1e-12);
        double move = std::max(room, least);
        bool moved = false;
        for (int half = 0; half < 4 && !moved; ++half, move *= 0.5) {
            dvec3 q2(0.0);
            const dvec3 c2 = c + away * move;
            const double room2 = room_at(c2, tris, cap, &q2);
            if (room2 > room) {
                c = c2;
                q = q2;
                room = room2;
                moved = true;
            }
        }
        if (!moved) break;
    }
    return c;
}

struct Gap {
    glm::vec3 middle{0.0f};
    glm::vec3 across{0.0f};  // unit, from one side to the other
    glm::vec3 square{0.0f};  // a hole's: its sheet's unit normal, traced too (0: none)
};

}  // namespace

GapProbeFigures probe_gaps(Context& ctx, const BitVolume& touched, const VoxelMask& eyes,
                           const RayScene& scene, double tolerance_m, uint32_t lines, Solid& solid,
                           WorkShare* share) {
    ScopedTimer timer(ctx, "gap_probe");
    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    const auto start = std::chrono::steady_clock::now();
    GapProbeFigures figures;
    const VoxelGrid& grid = solid.grid;
    const float h = grid.voxel_size_m;
    const float max_gap = float(kMaxGapVoxels) * h, min_gap = float(kGapWidthShare * tolerance_m);
    if (lines == 0 || !(min_gap > 0.0f) || min_gap >= max_gap) return figures;
    const BitVolume sources = sight_sources(grid, eyes);

    // The voxels a gap's middle is looked for in: near a touched voxel and near the solid.
    const BitVolume near_solid = dilate(grid, solid.solid, kNearSolidVoxels);
    const BitVolume near_touched = dilate(grid, touched, kNearSolidVoxels);
    // ... gathered into blocks of kBlockVoxels^3 voxels, each searched as one.
    const glm::ivec3 block_dims = (grid.dims + kBlockVoxels - 1) / kBlockVoxels;
    std::vector<uint8_t> block_used(size_t(block_dims.x) * size_t(block_dims.y) * size_t(block_dims.z), 0);
    // (Threads may mark one block from different words: each an atomic store of the same value.)
    figures.voxels = sum_words(near_solid.words.size(), [&](size_t w) {
        const uint64_t word = near_solid.words[w] & near_touched.words[w];
        for (uint64_t bits = word; bits; bits &= bits - 1) {
            const glm::ivec3 c =
                grid.coords(uint64_t(w) * 64 + uint64_t(__builtin_ctzll(bits))) / kBlockVoxels;
            std::atomic_ref<uint8_t>(
                block_used[size_t(c.x) +
                           size_t(block_dims.x) * (size_t(c.y) + size_t(block_dims.y) * size_t(c.z))])
                .store(1, std::memory_order_relaxed);
        }
        return uint64_t(__builtin_popcountll(word));
    });
    std::vector<glm::ivec3> blocks;
    for (int z = 0; z < block_dims.z; ++z)
        for (int y = 0; y < block_dims.y; ++y)
            for (int x = 0; x < block_dims.x; ++x)
                if (block_used[size_t(x) +
                               size_t(block_dims.x) * (size_t(y) + size_t(block_dims.y) * size_t(z))])
                    blocks.emplace_back(x, y, z);
    const float block_m = float(kBlockVoxels) * h;
    const float radius = 0.5f * std::sqrt(3.0f) * block_m + 0.5f * max_gap;
    const float kPi = 3.14159265358979f;

    BitVolume seen, leaky;  // written by every thread (an atomic OR), read after the loop
    seen.reset(grid.count());
    leaky.reset(grid.count());
    uint64_t pairs = 0, open_edges = 0, gaps_found = 0, traced = 0, leaks = 0;
    ctx.progress_begin("gap probe", blocks.size(), "blocks");
    deal.begin(blocks.size());
#pragma omp parallel reduction(+ : pairs, open_edges, gaps_found, traced, leaks)
    {
        std::vector<TriangleCorners> tris;
        std::vector<Gap> gaps;
        std::vector<glm::vec3> origins, dirs;
        std::vector<RayTouch> touches;
        std::vector<float> hit;
        for_each_dealt(deal, ctx, 64, [&](uint64_t k) {
            const glm::vec3 lo = grid.origin + glm::vec3(blocks[size_t(k)] * kBlockVoxels) * h;
            const Aabb box = Aabb::of(lo, lo + glm::vec3(block_m));
            const glm::vec3 centre = lo + 0.5f * glm::vec3(block_m);
            tris.clear();
            scene.opaque_triangles_near(centre, centre, radius, tris);
            // Only those truly within the radius (the query goes by bounds: a long triangle aslant comes
            // with every block near its box).
            const dvec3 dc(centre);
            tris.erase(std::remove_if(tris.begin(), tris.end(),
                                      [&](const TriangleCorners& t) {
                                          const dvec3 q = closest_point_on_triangle(dc, dvec3(t.a),
                                                                                    dvec3(t.b), dvec3(t.c));
                                          return glm::length(q - dc) > double(radius);
                                      }),
                       tris.end());
            gaps.clear();
            for (size_t i = 0; i < tris.size(); ++i)
                for (size_t j = i + 1; j < tris.size(); ++j) {
                    if (!boxes_within(tris[i], tris[j], max_gap) || shares_corner(tris[i], tris[j])) continue;
                    ++pairs;
                    dvec3 a, b;
                    local_closest_pair(tris[i], tris[j], dvec3(centre), a, b);
                    const double g = glm::length(b - a);
                    if (!(g >= double(min_gap)) || g > double(max_gap)) continue;
                    const glm::vec3 m = glm::vec3(0.5 * (a + b));
                    if (!box.contains(m)) continue;  // another block's gap
                    // Room for the tube at the middle: no third triangle nearer than half the least gap.
                    if (distance_to_triangles(dvec3(m), dvec3(m), tris, 0.5 * double(min_gap)) <
                        0.5 * double(min_gap))
                        continue;
                    gaps.push_back(Gap{m, glm::vec3((b - a) / g)});
                }
            // Holes: past an open edge (no other triangle near has both its corners), outward in the
            // triangle's plane from the edge's middle (a short edge) or its point nearest the block's centre,
            // climbing the distance to the triangles to the point of most room.
            for (size_t i = 0; i < tris.size(); ++i) {
                const TriangleCorners& t = tris[i];
                const glm::vec3 corner[3] = {t.a, t.b, t.c};
                const glm::vec3 n = glm::cross(t.b - t.a, t.c - t.a);
                if (!(glm::length(n) > 0.0f)) continue;
                for (int e = 0; e < 3; ++e) {
                    const glm::vec3 p = corner[e], q = corner[(e + 1) % 3], r = corner[(e + 2) % 3];
                    if (edge_shared(tris, i, p, q)) continue;
                    ++open_edges;
                    glm::vec3 out = glm::normalize(glm::cross(q - p, n));
                    if (glm::dot(out, r - p) > 0.0f) out = -out;
                    const dvec3 foot = glm::length(q - p) < max_gap
                                           ? 0.5 * (dvec3(p) + dvec3(q))
                                           : closest_point_on_segment(dvec3(centre), dvec3(p), dvec3(q));
                    const dvec3 start = foot + dvec3(out) * (0.5 * double(min_gap));
                    const dvec3 best =
                        most_room_near(start, tris, 0.5 * double(min_gap), 0.5 * double(max_gap));
                    if (!box.contains(glm::vec3(best))) continue;
                    if (room_at(best, tris, 0.5 * double(max_gap), nullptr) >= 0.5 * double(min_gap))
                        gaps.push_back(Gap{glm::vec3(best), out, glm::normalize(n)});
                }
            }
            gaps_found += gaps.size();
            if (gaps.empty()) return;
            // Lines across each gap: a fan over the plane perpendicular to it (half turn: a line goes both
            // ways), each traced both ways from the middle.
            origins.clear();
            dirs.clear();
            for (const Gap& gap : gaps) {
                glm::vec3 u, v;
                basis_of(gap.across, u, v);
                // A hole's line square to its sheet first: it threads holes in line in the sheets of a
                // hollow wall, which a fan line aslant by a few degrees misses.
                const bool square = gap.square != glm::vec3(0.0f);
                for (uint32_t l = 0; l < lines + (square ? 1 : 0); ++l) {
                    const float angle = kPi * (float(l) + 0.5f) / float(lines);
                    const glm::vec3 d = l == lines ? gap.square : std::cos(angle) * u + std::sin(angle) * v;
                    origins.push_back(gap.middle);
                    dirs.push_back(d);
                    origins.push_back(gap.middle);
                    dirs.push_back(-d);
                }
            }
            traced += origins.size() / 2;
            touches.clear();
            scene.trace_from(origins.data(), dirs.data(), uint32_t(origins.size()), touches);
            hit.assign(origins.size(), std::numeric_limits<float>::infinity());
            for (const RayTouch& t : touches)
                if (t.stops) hit[t.ray] = std::min(hit[t.ray], t.t);
            for (size_t r = 0; r < origins.size(); r += 2) {
                // The clear part of the line: from the middle to the first opaque triangle each way. It
                // counts when it passes an eye voxel and a solid voxel.
                bool source_found = false, solid_found = false;
                glm::vec3 source_point{0.0f}, solid_point{0.0f};
                for (size_t s = r; s < r + 2; ++s) {
                    const float reach = std::isfinite(hit[s]) ? hit[s] - 1e-3f * h : 1e30f;
                    VoxelWalk walk(grid, origins[s], dirs[s], reach);
                    do {
                        const uint64_t i = walk.index();
                        const float mid = 0.5f * (walk.t_enter() + std::min(walk.t_exit(), reach));
                        if (!source_found && sources.get(i)) {
                            source_found = true;
                            source_point = origins[s] + dirs[s] * mid;
                        }
                        if (!solid_found && solid.solid.get(i)) {
                            solid_found = true;
                            solid_point = origins[s] + dirs[s] * mid;
                        }
                    } while (walk.next());
                }
                if (!source_found || !solid_found) continue;
                if (!sight_line_at_least(scene, source_point, solid_point, kNoObject, min_gap)) continue;
                ++leaks;
                for (size_t s = r; s < r + 2; ++s) {
                    const float reach = std::isfinite(hit[s]) ? hit[s] - 1e-3f * h : 1e30f;
                    VoxelWalk walk(grid, origins[s], dirs[s], reach);
                    do {
                        const uint64_t i = walk.index();
                        if (touched.get(i)) leaky.set_atomic(i);
                        if (solid.solid.get(i)) seen.set_atomic(i);
                    } while (walk.next());
                }
            }
        });
    }
    ctx.progress_end();
    // The processes' finds and counts together (docs/ALGORITHMS.md#processes).
    deal.unite(seen.words.data(), seen.words.size());
    deal.unite(leaky.words.data(), leaky.words.size());
    uint64_t counts[5] = {pairs, open_edges, gaps_found, traced, leaks};
    deal.add(counts, 5);
    pairs = counts[0];
    open_edges = counts[1];
    gaps_found = counts[2];
    traced = counts[3];
    leaks = counts[4];
    figures.pairs = pairs;
    figures.open_edges = open_edges;
    figures.gaps = gaps_found;
    figures.lines = traced;
    figures.leaks = leaks;
    figures.leaky_voxels = leaky.count();
    if (leaks > 0) figures.removed_voxels = open_seen_and_leaky(touched, seen, leaky, sources, solid);
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "gap probe: {} voxels, {} triangle pairs, {} open edges, {} gaps {:.1f}..{:.1f} mm wide, {} lines; "
        "{} see into "
        "the solid through {} touched voxels; {} voxels leave the solid; {:.2f} s",
        figures.voxels, figures.pairs, figures.open_edges, figures.gaps, 1e3 * min_gap, 1e3 * max_gap,
        figures.lines, figures.leaks, figures.leaky_voxels, figures.removed_voxels, figures.seconds));
    return figures;
}

}  // namespace pvs
