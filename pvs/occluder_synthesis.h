// pvsbake pvs: occluder synthesis, from a world and its view volume to few large boxes inside the opaque
// solid (ALGORITHMS.md sections 1 and 2):
//   solid (occluders/solid.h: voxels sight from the eye space never reaches) -> SIGHT PROBE (rays over the
//   sphere from eye points; every solid voxel a ray passes before its first opaque hit, and its 26
//   neighbours, is carved out: sight got there through a crack narrower than a voxel) -> boxes
//   (occluders/boxes.h: greedy growth, sort and cut) -> RAY CHECK against the real triangles (Embree): from
//   eye points spread over the view volume, segments to points on each box's faces; a box any segment reaches
//   before an opaque triangle is rejected. This catches boxes sealed off only by a crack narrower than a
//   voxel when the sampled sight lines pass the crack; it is a sampled check, not a proof (see the closing
//   note).
#pragma once

#include "cells/view_volume.h"
#include "core/config.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/world.h"
#include "pvs/embree_scene.h"

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
    uint64_t probe_rays = 0;
    uint64_t probe_rays_into_solid = 0;  // probe rays that passed a solid voxel (through a crack)
    uint64_t probe_rays_escaped = 0;     // probe rays no opaque triangle stopped
    uint64_t probe_carved_voxels = 0;
    uint64_t check_rays = 0;
    double seconds = 0.0;
};

// When `shrunk` is given, also fills it with the proven solid (the solid, less the voxels of rejected boxes)
// and, for each epsilon of the ladder epsilon_m * 2^k, k = 0..levels, boxes of the proven solid SHRUNK by
// it (eroded by ceil(epsilon / voxel) voxels in the Chebyshev metric, so every point of a shrunk box has its
// whole epsilon-ball inside the proven solid): the occluders of the conservative solver
// (pvs/conservative.h).
std::vector<Occluder> synthesize_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                           const ViewVolume& view, const RayScene& scene,
                                           OccluderFigures& figures, double epsilon_m = 0.0, int levels = 0,
                                           ShrunkOccluders* shrunk = nullptr);

}  // namespace pvs
