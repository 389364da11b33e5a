// SPDX-License-Identifier: MIT
// pvsbake occluders: the GAP PROBE, openings at least the gap tolerance wide looked for where the triangles
// leave them (why, and what it finds: docs/ALGORITHMS.md#gap-probe).
//
// The sight sweep (occluders/solid.h) takes every voxel an opaque triangle touches as a wall, so an opening
// narrower than a few voxels can seal in voxels while sight passes it (docs/ALGORITHMS.md#cracks). Such an
// opening is a gap between triangles: the two sides of a slit, two meshes that nearly meet, the edges of a
// hole. A line through the middle of its narrowest place, across the gap, passes it as widely as it is wide.
//
// How: the voxels within kNearSolidVoxels of the solid and of a touched voxel, in blocks of kBlockVoxels^3;
// in each block, the opaque triangles near it, and
// - for every pair of them with no corner in common, their LOCAL closest points (alternating nearest points
//   from the block's centre): a GAP when they are between the least width (kGapWidthShare of the tolerance)
//   and max_gap_m apart, their midpoint lies in the block and no third triangle comes nearer to it than half
//   the least width;
// - past every OPEN edge (no other triangle near has both its corners), in its triangle's plane, a climb of
//   the distance to the triangles to the hole's middle: a gap when the room there is at least half the least
//   width and it lies in the block.
// Through each gap's middle, `lines` lines across the gap (a fan over the plane perpendicular to it; for a
// hole, also the line square to its sheet) are traced both ways to the first opaque triangle. A line whose
// clear part meets both an EYE voxel (the sight sources) and a solid voxel, and is at least the least width
// wide between them (rays/clearance.h), is a line of sight into the solid: the solid voxels it passes leave
// the solid, the touched ones it passes are leaky, and the sweep runs again through them (reopen_leaks).
// Only ever removes solid: safe whatever it finds. Deterministic: no sampling, and the same answer for any
// number of threads.
//
// max_gap_m = kMaxGapVoxels voxels: an opening that wide lets the sight sweep through by construction
// (docs/ALGORITHMS.md#wide-openings), so wider gaps are not looked at.
#pragma once

#include "core/context.h"
#include "core/work_share.h"
#include "occluders/solid.h"
#include "rays/ray_scene.h"

#include <cstdint>

namespace pvs {

// The probes' least width as a share of the gap tolerance: a line narrower than kGapWidthShare T opens
// nothing. Below 1 so that an opening exactly T wide, whose corners were rounded to float, still counts
// (docs/ALGORITHMS.md#gap-probe).
constexpr double kGapWidthShare = 0.9;

// Widest gap the probe looks at, in voxels: past 2 sqrt(3) voxels the sweep sees through (the margin covers
// the voxelizer's rounding).
constexpr double kMaxGapVoxels = 3.6;

struct GapProbeFigures {
    uint64_t voxels = 0;        // touched voxels next to the solid, probed
    uint64_t pairs = 0;         // triangle pairs looked at
    uint64_t open_edges = 0;    // triangle edges no other triangle near shares
    uint64_t gaps = 0;          // local gaps in range with a clear midpoint
    uint64_t lines = 0;         // lines traced (each both ways)
    uint64_t leaks = 0;         // lines of sight into the solid found
    uint64_t leaky_voxels = 0;  // touched voxels such a line passed
    uint64_t removed_voxels = 0;
    double seconds = 0.0;
};

// `eyes`: the view volume's eye mask on the solid's grid (empty: sight starts outside the world).
// `tolerance_m` > 0: the gap tolerance T; gaps narrower than kGapWidthShare T stay closed. `lines` per gap
// (0: off). With `share`, the blocks are dealt between the processes and their finds united
// (docs/ALGORITHMS.md#processes): every process ends with the same solid.
GapProbeFigures probe_gaps(Context& ctx, const BitVolume& touched, const VoxelMask& eyes,
                           const RayScene& scene, double tolerance_m, uint32_t lines, Solid& solid,
                           WorkShare* share = nullptr);

}  // namespace pvs
