// SPDX-License-Identifier: MIT
// pvsbake occluders: occluder synthesis, few large axis-aligned boxes inside the solid voxels (after
// Andújar, Saona-Vázquez, Navazo, Brunet, "Integrating Occlusion Culling and Levels of Detail through
// Hardly-Visible Sets", 2000, and the "occluder skin" idea of taking the largest boxes of inner voxels;
// see docs/ALGORITHMS.md#boxes).
//
// Conventions: voxels as in voxels/voxels.h (glTF axes, metres; voxel (x, y, z) has index
// x + dims.x * (y + dims.y * z)). A VoxelBox is an inclusive voxel range lo..hi on every axis.
// Conservative: every voxel of every returned box is solid (a hard rule: a box reaching outside the
// solid would hide objects that can be seen). Boxes may overlap each other. box_bounds() is the union
// of the boxes VoxelGrid::voxel_box() gives for the box's voxels, computed the same way.
//
// Algorithm (grow_boxes):
//   1. Seeds: for every solid voxel, the edge of the largest all-solid cube with that voxel as its min
//      corner (the classic max-square recurrence in 3D, capped at kMaxSeedCube). Seeds are taken in
//      decreasing cube size, ties by increasing voxel index.
//   2. Growth: from the next seed that no grown box covers yet, start with that cube and stretch it one
//      voxel layer at a time, round-robin over +x, -x, +y, -y, +z, -z, while the new layer is all solid
//      and inside the grid; stop when a whole round adds nothing. Mark its voxels covered.
//   3. Stop rule: seeding ends when all solid voxels are covered or when kGrowFactor * max_boxes grown
//      boxes have at least min_box_volume_m3 (smaller grown boxes still cover their voxels, so noise
//      cannot seed twice, but they do not count: a one-voxel-thick wall seeds with cube 1 and may still
//      grow into a large occluder, so small seeds are never skipped).
//   4. Sort and cut: grown boxes by decreasing volume (ties: grown order); keep a box while fewer than
//      max_boxes are kept, its volume is >= min_box_volume_m3, and the voxels it adds (not covered by
//      boxes kept before it) are > 0 and >= min_added_share of its own volume.
// Deterministic: the same input gives the same boxes for any thread count.
#pragma once

#include "core/context.h"
#include "core/math.h"
#include "voxels/voxels.h"

#include <cstdint>
#include <vector>

namespace pvs {

// Grown boxes (of at least min_box_volume_m3) allowed per kept box before seeding stops.
constexpr uint32_t kGrowFactor = 8;
// Seed cube edges are counted up to this (in voxels); bigger cubes tie and break ties by voxel index.
constexpr int kMaxSeedCube = 255;

struct VoxelBox {
    glm::ivec3 lo{0}, hi{-1};  // inclusive voxel range; empty when hi < lo on some axis

    uint64_t volume() const {
        if (hi.x < lo.x || hi.y < lo.y || hi.z < lo.z) return 0;
        return uint64_t(hi.x - lo.x + 1) * uint64_t(hi.y - lo.y + 1) * uint64_t(hi.z - lo.z + 1);
    }
    bool operator==(const VoxelBox& o) const { return lo == o.lo && hi == o.hi; }
};

struct BoxConfig {
    uint32_t max_boxes = 512;        // [Limit: >= 1] keep at most this many (--max-occluders)
    double min_box_volume_m3 = 0.5;  // [Limit: >= 0] [Units: m3] drop boxes smaller than this
                                     // (--min-occluder-volume)
    double min_added_share = 0.05;   // [Limit: 0..1] keep a box only while it adds at least this share of
                                     // its own volume that earlier kept boxes do not already cover (and
                                     // always at least one voxel)
};

struct BoxStats {
    uint64_t solid_voxels = 0;    // solid voxels in the grid
    uint64_t covered_voxels = 0;  // solid voxels inside some kept box
    uint32_t grown = 0;           // boxes grown from seeds, the small ones included
    uint32_t kept = 0;            // boxes returned
    double seconds = 0.0;         // wall time of grow_boxes
};

// Greedy growth, then sort and cut (see above). `solid` holds grid.count() bits. Throws pvs::Error
// (bad input) naming the option when the config is outside its limits. Memory: about 3.2 bytes a voxel
// (seed cubes 1, a summed-area table of 16-bit sums 2, a bit of cover), and 8 bytes a seed for the seeds of
// one window of 4.2 M voxels at a time; time roughly linear in voxels plus the volume of the grown boxes.
// Boxes come sorted by decreasing volume.
std::vector<VoxelBox> grow_boxes(Context& ctx, const VoxelGrid& grid, const BitVolume& solid,
                                 const BoxConfig& config, BoxStats* stats = nullptr);

// Reference: the same seeds, growth, stop rule and cut, computed voxel by voxel with no summed-area
// table and no shortcuts. Slow (for the differential test); gives exactly grow_boxes()'s boxes.
std::vector<VoxelBox> grow_boxes_reference(const VoxelGrid& grid, const BitVolume& solid,
                                           const BoxConfig& config);

// The box in metres: from voxel_box(lo).min to voxel_box(hi).max.
Aabb box_bounds(const VoxelGrid& grid, const VoxelBox& box);

// Cuts every kept box (rejected[k] == 0) off each rejected box it overlaps, so that the kept boxes lie in
// the solid less the rejected boxes (the proven solid: docs/ALGORITHMS.md#proven-boxes): per overlap, the
// largest of the six slabs of the kept box outside the rejected one. A kept box left with fewer than
// `min_voxels` is marked rejected. Boxes only shrink; the rejected ones are not changed.
struct TrimFigures {
    uint32_t trimmed = 0;       // kept boxes that were cut
    uint32_t trimmed_away = 0;  // of them, those left too small and rejected
};
TrimFigures trim_off_rejected(std::vector<VoxelBox>& boxes, std::vector<uint8_t>& rejected, uint64_t min_voxels);

}  // namespace pvs
