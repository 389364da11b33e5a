// SPDX-License-Identifier: MIT
// pvsbake occluders: occluder synthesis, from a world and its view volume to few large boxes inside the
// opaque solid (docs/ALGORITHMS.md#occluders):
//   solid (occluders/solid.h: voxels sight from the eye space never reaches) -> SIGHT PROBE (rays over the
//   sphere from eye points; every solid voxel a ray passes before its first opaque hit, and its 26
//   neighbours, is carved out: docs/ALGORITHMS.md#sight-probe) -> SEAL PROBE (occluders/seal_probe.h: rays
//   from the solid just behind touched voxels towards the eye space; a line the triangles do not block
//   makes the touched voxels it passed leaky, and the sweep runs again through them) -> boxes
//   (occluders/boxes.h: greedy growth, sort and cut) -> RAY CHECK against the real triangles (Embree): from
//   eye points spread over the view volume, and from eye points near each box, segments to random points of
//   the box; a box any segment reaches before an opaque triangle is rejected
//   (docs/ALGORITHMS.md#ray-check). The probes and the check only ever remove solid; they sample, they do
//   not prove (docs/ALGORITHMS.md#cracks).
#pragma once

#include "cells/view_volume.h"
#include "core/config.h"
#include "core/context.h"
#include "core/work_share.h"
#include "core/occluder.h"
#include "core/world.h"
#include "rays/ray_scene.h"

#include <string>
#include <vector>

namespace pvs {

// The distance from the view region within which solid counts as "near" (the occluders that matter most).
constexpr double kNearViewM = 4.0;

struct OccluderFigures {
    double solid_m3 = 0.0;
    double covered_m3 = 0.0;       // solid inside some kept box (before the ray check)
    double near_m3 = 0.0;          // solid within kNearViewM of the view region
    double near_covered_m3 = 0.0;  // ... inside some proven box
    uint32_t grown = 0;
    uint32_t kept = 0;
    uint32_t rejected_by_rays = 0;  // boxes a sight line reached
    uint32_t trimmed = 0;           // kept boxes cut off the rejected boxes they overlapped
    uint32_t trimmed_away = 0;      // kept boxes that overlapped rejected ones too much to keep a proven part
    uint64_t probe_rays = 0;
    uint64_t probe_rays_into_solid = 0;  // probe rays that passed a solid voxel (through a crack)
    uint64_t probe_rays_escaped = 0;     // probe rays no opaque triangle stopped
    uint64_t probe_rays_narrow = 0;      // probe rays into the solid through openings narrower than the
                                         // probes' least width: they carve nothing
    uint64_t probe_carved_voxels = 0;
    uint64_t check_rays = 0;
    uint64_t gap_voxels = 0;  // the gap probe (occluders/gap_probe.h): voxels looked in
    uint64_t gap_gaps = 0;    // gaps between triangles at least the tolerance wide
    uint64_t gap_lines = 0;
    uint64_t gap_leaks = 0;  // lines across them that saw into the solid
    uint64_t gap_removed_voxels = 0;
    uint64_t seal_frontier_voxels = 0;  // the seal probe (occluders/seal_probe.h)
    uint64_t seal_rays = 0;
    uint64_t seal_leaks = 0;   // its rays that reached the solid from an eye voxel past the triangles
    uint64_t seal_narrow = 0;  // its unblocked rays through openings narrower than the probes' least width
    uint64_t seal_removed_voxels = 0;
    double seconds = 0.0;
};

// When `shrunk` is given, also fills it with the proven solid (the solid, less the voxels of rejected boxes)
// and, for each epsilon of the ladder epsilon_m * 2^k, k = 0..levels, boxes of the proven solid SHRUNK by
// it (eroded by ceil(epsilon / voxel) voxels in the Chebyshev metric, so every point of a shrunk box has its
// whole epsilon-cube inside the proven solid: docs/ALGORITHMS.md#shrunk-occluders): the occluders of the
// conservative solver (pvs/conservative.h).
// With `share` (the processes of an MPI bake), the probes' rays, the ray check's boxes and the shrunk levels
// are dealt between the processes and their results united or passed on (docs/ALGORITHMS.md#processes):
// every process returns the same occluders, as one process alone would. Collective then.
std::vector<Occluder> synthesize_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                           const ViewVolume& view, const RayScene& scene,
                                           OccluderFigures& figures, double epsilon_m = 0.0, int levels = 0,
                                           ShrunkOccluders* shrunk = nullptr, WorkShare* share = nullptr);

struct BlockFigures {
    uint32_t blocks = 0;           // blocks holding eyes
    uint32_t blocks_used = 0;      // blocks given their own occluders
    double solid_m3 = 0.0;         // proven solid in the windows of the blocks used, from their own eyes
    double global_solid_m3 = 0.0;  // ... from all eyes
    uint64_t boxes = 0;            // own shrunk boxes at the floor epsilon, all blocks
    uint64_t boxes_dropped = 0;    // own shrunk boxes (all levels) a segment of the second check reached
    uint64_t rays = 0;             // sight probe and ray check rays
    double seconds = 0.0;
};

// OCCLUDERS PER BLOCK of cells (opt-in, unproven; for levels open to the sky). The solid is what sight from
// the eye space never reaches; in a level open to the sky one eye that sees into a hollow wall (over it, or
// through a gap to the outside) unmakes that wall as an occluder for every cell. But a cell's occluders need
// only lie where no sight from THAT cell's eyes goes (docs/ALGORITHMS.md#block-occluders). So the view volume
// is cut into square blocks of `block_m` in x and z (all heights) from `origin`; for each, sight starts only
// from the eye voxels meeting the block's square grown by a voxel, within a WINDOW of the square grown by
// config.block_reach_m (the window is convex, so sight_reach on its voxels is still a superset of that
// sight). The window's solid is then probed, boxed, ray-checked (against segments from the block's own eyes)
// and shrunk exactly as the global one, joined with the global proven solid (proven for every eye), and kept
// in shrunk.block_sets when it holds more than (1 + block_min_gain) times the global solid of the window. A
// block set's boxes are its own plus the global ones not inside one of its own (beyond the window the global
// boxes still serve); its `free` mask is left empty (the solver uses the global one, a superset of the
// block's free space, for its sight rays, which only ever list objects).
// The solver uses a block's set for every region of eyes lying in the block's square
// (ShrunkOccluders::set_for); on a grid `block_m` should be a multiple of the cell size from the grid's
// origin, so that every cell lies in one block.
BlockFigures synthesize_block_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                        const ViewVolume& view, const RayScene& scene, glm::vec3 origin,
                                        float block_m, ShrunkOccluders& shrunk);

// An AUDIT of occluders per block, independent of how they were made (fresh eyes, fresh points): rays from
// `eyes_per_block` eye points of each block with its own set (seeded), aimed at `points_per_box` random
// points inside every box of that set at the floor epsilon. A ray no opaque triangle stops before its point
// is a FAILURE of the argument (docs/ALGORITHMS.md#block-occluders): sight from the block reaches its
// occluders.
struct BlockAudit {
    uint32_t blocks = 0;  // blocks with their own occluders
    uint64_t rays = 0;
    uint64_t reached = 0;  // rays that reached a point inside a box of their block's set
    std::string first;     // the first such ray, in words
};
BlockAudit audit_block_occluders(const ViewVolume& view, const RayScene& scene, const ShrunkOccluders& shrunk,
                                 uint32_t eyes_per_block, uint32_t points_per_box, uint64_t seed);

}  // namespace pvs
