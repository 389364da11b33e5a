// SPDX-License-Identifier: MIT
// The seal probe: rays from the solid's frontier voxels to the eye space, tested against the triangles.
#include "occluders/seal_probe.h"

#include "rays/clearance.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "core/work_share.h"
#include "voxels/voxel_walk.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

// A ray may pass this many solid voxels (after its own) before it gives up: the frontier lies next to
// non-solid space, so a ray that stays in the solid longer probes other frontier voxels' seals.
constexpr int kMaxSolidSteps = 3;

// After a round that found leaks, the frontier within kHotRadius voxels of them is probed again with
// kHotRaysFactor times the rays (a crack along a seam or a slit is found in pieces).
constexpr int kHotRadius = 2;
constexpr uint32_t kHotRaysFactor = 4;

// How deep into touched voxels the frontier looks: a crack through a wall up to this many voxels thick.
constexpr int kTouchedDepth = 8;

// Solid voxels next to an OPEN voxel (neither solid nor touched), or to a touched voxel joined to an open
// one by at most kTouchedDepth steps through touched voxels; less those already probed, which they join.
std::vector<uint64_t> frontier_of(const Solid& solid, const BitVolume& touched, BitVolume& probed) {
    const VoxelGrid& grid = solid.grid;
    BitVolume open;
    open.words.resize(solid.solid.words.size());
    for_each_word(open.words.size(),
                  [&](size_t w) { open.words[w] = ~(solid.solid.words[w] | touched.words[w]); });
    const uint64_t tail = grid.count() % 64;
    if (tail) open.words.back() &= (uint64_t(1) << tail) - 1;
    BitVolume near = open;  // grown through touched voxels only
    for (int k = 0; k < kTouchedDepth; ++k) {
        near = dilate(grid, near, 1);
        for_each_word(near.words.size(),
                      [&](size_t w) { near.words[w] &= open.words[w] | touched.words[w]; });
    }
    near = dilate(grid, near, 1);
    const auto frontier = [&](size_t w) { return solid.solid.words[w] & near.words[w] & ~probed.words[w]; };
    std::vector<uint64_t> out = set_bit_indices(open.words.size(), frontier);
    for_each_word(probed.words.size(),
                  [&](size_t w) { probed.words[w] |= near.words[w] & solid.solid.words[w]; });
    return out;
}

// Lines tried around an unblocked segment narrower than the least width, looking for the opening's middle.
constexpr uint32_t kOpeningTries = 256;

}  // namespace

SealProbeFigures probe_seals(Context& ctx, const BitVolume& touched, const VoxelMask& eyes,
                             const RayScene& scene, uint32_t rays, double reach_m, int rounds, uint64_t seed,
                             double min_width_m, Solid& solid, WorkShare* share) {
    ScopedTimer timer(ctx, "seal_probe");
    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    const auto start = std::chrono::steady_clock::now();
    SealProbeFigures figures;
    if (rays == 0 || rounds <= 0) return figures;
    const VoxelGrid& grid = solid.grid;
    const BitVolume sources = sight_sources(grid, eyes);
    const float reach = float(reach_m);
    // Where the ends of a line may move while looking for an opening's middle: the eye end in the eye space
    // (the sight sources) ...
    const auto in_sources = [&](glm::vec3 p) {
        const glm::ivec3 c = grid.voxel_of(p);
        return grid.inside(c) && sources.get(grid.index(c.x, c.y, c.z));
    };
    // ... and the solid end: the solid (a line must still join the eye space to the solid).
    const auto in_solid = [&](glm::vec3 p) {
        const glm::ivec3 c = grid.voxel_of(p);
        return grid.inside(c) && solid.solid.get(grid.index(c.x, c.y, c.z));
    };
    BitVolume probed, leaky;  // leaky: written by every thread (an atomic OR), read only between rounds
    probed.reset(grid.count());
    leaky.reset(grid.count());
    for (int round = 0; round < rounds; ++round) {
        const std::vector<uint64_t> frontier = frontier_of(solid, touched, probed);
        // Rounds after the first probe only what the leaks before opened or came near: harder.
        const uint32_t round_rays = round == 0 ? rays : kHotRaysFactor * rays;
        const uint64_t round_seed = seed + uint64_t(round) * 0x9e3779b97f4a7c15ULL;
        if (frontier.empty()) break;
        ++figures.rounds;
        figures.frontier_voxels += frontier.size();
        uint64_t walked = 0, segments = 0, leaks = 0, narrow = 0;
        BitVolume seen;  // written by every thread (an atomic OR), read only after the loop
        seen.reset(grid.count());
        ctx.progress_begin(fmt::format("seal probe, round {}", round + 1), frontier.size(), "voxels");
        deal.begin(frontier.size());
#pragma omp parallel reduction(+ : walked, segments, leaks, narrow)
        {
            std::vector<glm::vec3> dirs, origins, seg_dirs;
            std::vector<float> tfar;
            std::vector<uint8_t> blocked;
            for_each_dealt(deal, ctx, 256, [&](uint64_t f) {
                const uint64_t vi = frontier[size_t(f)];
                const Aabb box = grid.voxel_box(grid.coords(vi));
                Rng rng(round_seed, vi ^ 0x5345414cULL);
                dirs.clear();
                sample_sphere_directions(round_rays, round_seed, vi, dirs);
                origins.clear();
                seg_dirs.clear();
                tfar.clear();
                for (const glm::vec3& d : dirs) {
                    const glm::vec3 p =
                        box.min + box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
                    ++walked;
                    VoxelWalk walk(grid, p, d, reach);
                    int solid_steps = 0;
                    while (walk.next()) {
                        const uint64_t i = walk.index();
                        if (sources.get(i)) {
                            origins.push_back(p);
                            seg_dirs.push_back(d);
                            tfar.push_back(0.5f * (walk.t_enter() + walk.t_exit()));
                            break;
                        }
                        if (solid.solid.get(i) && ++solid_steps > kMaxSolidSteps) break;
                    }
                }
                if (origins.empty()) return;
                segments += origins.size();
                blocked.resize(origins.size());
                scene.occluded_opaque(origins.data(), seg_dirs.data(), tfar.data(), uint32_t(origins.size()),
                                      blocked.data());
                for (size_t s = 0; s < origins.size(); ++s) {
                    if (blocked[s]) continue;
                    // An opening narrower than the tolerance allows stays closed
                    // (docs/ALGORITHMS.md#gap-tolerance).
                    const glm::vec3 eye_end = origins[s] + seg_dirs[s] * tfar[s];
                    if (min_width_m > 0.0 &&
                        !opening_at_least(scene, eye_end, origins[s], float(min_width_m), kOpeningTries,
                                          round_seed ^ (vi << 8) ^ s, in_sources, in_solid)) {
                        ++narrow;
                        continue;
                    }
                    ++leaks;
                    // Sight from the eye voxel reaches the origin: what the segment passes is seen or leaky.
                    seen.set_atomic(vi);
                    VoxelWalk walk(grid, origins[s], seg_dirs[s], tfar[s]);
                    while (walk.next()) {
                        const uint64_t i = walk.index();
                        if (sources.get(i)) break;
                        if (touched.get(i)) leaky.set_atomic(i);
                        if (solid.solid.get(i)) seen.set_atomic(i);
                    }
                }
            });
        }
        ctx.progress_end();
        // The processes' finds and counts together (docs/ALGORITHMS.md#processes): every process then
        // opens the same voxels and probes the same next frontier.
        deal.unite(seen.words.data(), seen.words.size());
        deal.unite(leaky.words.data(), leaky.words.size());
        uint64_t counts[4] = {walked, segments, leaks, narrow};
        deal.add(counts, 4);
        walked = counts[0];
        segments = counts[1];
        leaks = counts[2];
        narrow = counts[3];
        figures.rays += walked;
        figures.segments += segments;
        figures.leaks += leaks;
        figures.narrow += narrow;
        ctx.debug(fmt::format("seal probe round {}: {} frontier voxels, {} rays, {} segments, {} leaks",
                              round + 1, frontier.size(), walked, segments, leaks));
        if (leaks == 0) continue;  // the next round probes only a frontier this one opened: none
        figures.removed_voxels += open_seen_and_leaky(touched, seen, leaky, sources, solid);
        // A crack runs on: the frontier voxels near what this round found are probed again.
        BitVolume found = seen;
        for_each_word(found.words.size(), [&](size_t w) { found.words[w] |= leaky.words[w]; });
        const BitVolume hot = dilate(grid, found, kHotRadius);
        for_each_word(probed.words.size(), [&](size_t w) { probed.words[w] &= ~hot.words[w]; });
    }
    figures.leaky_voxels = leaky.count();
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "seal probe: {} rounds, {} frontier voxels, {:.1f} M rays, {} segments to eye voxels; {} reach the "
        "solid past the triangles through {} touched voxels; {} voxels leave the solid ({:.0f} m3 left); "
        "{:.2f} s",
        figures.rounds, figures.frontier_voxels, double(figures.rays) * 1e-6, figures.segments, figures.leaks,
        figures.leaky_voxels, figures.removed_voxels, solid.solid_m3, figures.seconds));
    return figures;
}

}  // namespace pvs
