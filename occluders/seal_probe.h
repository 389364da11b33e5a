// SPDX-License-Identifier: MIT
// pvsbake occluders: the SEAL PROBE, sight through touched voxels into the solid, looked for from the
// solid's side (why, and why from that side: docs/ALGORITHMS.md#seal-probe).
//
// The sight sweep (occluders/solid.h) takes every voxel an opaque triangle touches as a wall; a line of
// sight can still pass through such a voxel (a crack between meshes narrower than a voxel, or the part of
// the voxel the triangle does not cut), and behind it the sweep calls space solid
// (docs/ALGORITHMS.md#cracks).
//
// How: from every FRONTIER voxel of the solid (a solid voxel next to a voxel neither solid nor touched, or to
// a touched voxel joined to such a voxel through at most kTouchedDepth touched voxels, seal_probe.cpp: behind
// a touched layer up to that thick), `rays` rays, each from its own random point of the voxel in its own
// direction (stratified over the sphere). Each is walked voxel by voxel (exact traversal) for at most
// `reach_m`. A ray that enters an EYE voxel (the sight sources: the eye mask, or the grid's border layer with
// no view volume), having left the solid within its first few voxels, is tested as a segment against the real
// triangles (both sides block) to the middle of its chord through that voxel. Unblocked, it is a line of
// sight from the eye space into the solid: the solid voxels it passed leave the solid, and the touched voxels
// it passed are LEAKY. The sweep then runs again with the leaky voxels let through (reopen_leaks), so sight
// spreads through the crack in every direction the crack opens to, not only along the rays found; the
// frontier that this opens is probed in the next round (near each find with more rays), for at most `rounds`
// rounds. Only ever removes solid: safe whatever it finds.
//
// Still sampling, not proof: a crack can be missed (a slot seen from no frontier point along no sampled
// direction, or whose eye side lies beyond `reach_m`). Every bake is verified by rays (driver/verify.h).
// Deterministic: the rays of a voxel depend only on the seed and the voxel's index. With `share`, each round's
// frontier is dealt between the processes and their finds united (docs/ALGORITHMS.md#processes): every
// process ends with the same solid.
#pragma once

#include "core/context.h"
#include "core/work_share.h"
#include "occluders/solid.h"
#include "rays/ray_scene.h"

#include <cstdint>

namespace pvs {

struct SealProbeFigures {
    uint32_t rounds = 0;
    uint64_t frontier_voxels = 0;  // probed, all rounds
    uint64_t rays = 0;             // walked
    uint64_t segments = 0;         // tested against the triangles (the walk met an eye voxel in reach)
    uint64_t leaks = 0;            // segments no opaque triangle blocked, at least min_width_m wide
    uint64_t narrow = 0;           // unblocked segments narrower than that: openings closed on purpose
    uint64_t leaky_voxels = 0;     // touched voxels such a segment passed
    uint64_t removed_voxels = 0;   // left the solid (seen, or reached again through the leaky voxels)
    double seconds = 0.0;
};

// `eyes`: the view volume's eye mask on the solid's grid (empty: sight starts outside the world).
// `min_width_m`: an unblocked segment counts as a leak only when its sight line is at least this wide
// (rays/clearance.h; 0: every unblocked segment); narrower ones are counted in `narrow`.
SealProbeFigures probe_seals(Context& ctx, const BitVolume& touched, const VoxelMask& eyes,
                             const RayScene& scene, uint32_t rays, double reach_m, int rounds, uint64_t seed,
                             double min_width_m, Solid& solid, WorkShare* share = nullptr);

}  // namespace pvs
