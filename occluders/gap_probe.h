// pvsbake occluders: the GAP PROBE, openings at least the gap tolerance wide looked for where the triangles
// leave them: between two triangles near the solid (why, and what it finds: docs/ALGORITHMS.md#gap-probe).
//
// The sight sweep (occluders/solid.h) takes every voxel an opaque triangle touches as a wall, so an opening
// narrower than a few voxels can seal in voxels while sight passes it (docs/ALGORITHMS.md#cracks). Such an
// opening is a gap between triangles: between the two sides of a slit, two meshes that nearly meet, the
// edges of a hole. Its narrowest place lies in a touched voxel, and a line through the middle of that place,
// across the gap, passes it as widely as the gap is wide.
//
// How: for every touched voxel next to the solid, every pair of opaque triangles near it, the pair's LOCAL
// closest points (alternating nearest points, started at the voxel's centre); when they are between the
// least width (kGapWidthShare of the tolerance) and max_gap_m apart and their midpoint lies in or next to the
// voxel, with no other triangle nearer to it than half the gap, `lines` lines through the midpoint across the
// gap (a fan over the plane perpendicular to it) are traced both ways to the first opaque triangle. A line
// whose clear part meets both an EYE voxel (the sight sources) and a solid voxel is a line of sight into the
// solid: the solid voxels it passes leave the solid (when the line is at least the least width wide,
// rays/clearance.h), the touched ones it passes are leaky, and the sweep runs again through them
// (reopen_leaks). Only ever removes solid: safe whatever it finds; deterministic (no sampling).
//
// max_gap_m = kMaxGapVoxels voxels: an opening that wide lets the sight sweep through by construction
// (docs/ALGORITHMS.md#gap-probe), so wider gaps are not looked at.
#pragma once

#include "core/context.h"
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
// (0: off).
GapProbeFigures probe_gaps(Context& ctx, const BitVolume& touched, const VoxelMask& eyes,
                           const RayScene& scene, double tolerance_m, uint32_t lines, Solid& solid);

}  // namespace pvs
