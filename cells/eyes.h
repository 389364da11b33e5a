// SPDX-License-Identifier: MIT
// pvsbake cells: where eyes can be. The ONE place that decides it: the sampled PVS, the verifier and the
// occluder ranking all draw their eye points here (docs/ALGORITHMS.md#eye-points).
//
// With a view volume (CellSet::eyes, cells/view_volume.h) an eye is drawn in (free voxel of the eye space)
// ∩ cell: never inside solid, never outside reachable space. A box no eye voxel meets gets no eye point
// (cells are clipped so that every cell meets the eye space). Without a view volume, the whole box.
//
// Sampling is stratified: without voxels the box is split into about `count` strata (a k x k x k grid,
// shuffled) with one jittered point in each; with voxels the cell's voxels (in index order) are split
// into `count` runs and a uniform point is drawn in a random voxel of each run. The points depend only
// on (seed, cell).
#pragma once

#include "core/cell_set.h"

#include <cstdint>
#include <vector>

namespace pvs {

// Appends `count` stratified random eye points of `box` (a cell, or an octree node being considered)
// under the view volume's eye mask `eyes` (anywhere in the box when it is empty); `stream` is a number
// unique to the box.
void sample_eye_points_in(const VoxelMask& eyes, const Aabb& box, uint64_t stream, uint32_t count,
                          uint64_t seed, std::vector<glm::vec3>& out);
inline void sample_eye_points_in(const CellSet& cells, const Aabb& box, uint64_t stream, uint32_t count,
                                 uint64_t seed, std::vector<glm::vec3>& out) {
    sample_eye_points_in(cells.eyes, box, stream, count, seed, out);
}

// The voxels of `eyes` meeting `box`, in index order (none without an eye mask): what
// sample_eye_points_in() draws from.
std::vector<uint64_t> eye_voxels_in(const VoxelMask& eyes, const Aabb& box);
inline std::vector<uint64_t> eye_voxels_in(const CellSet& cells, const Aabb& box) {
    return eye_voxels_in(cells.eyes, box);
}
// sample_eye_points_in() with the box's eye voxels given (eye_voxels_in()): the same points, without walking
// the mask again, for callers that draw many times from one box.
void sample_eye_points_from(const VoxelMask& eyes, const Aabb& box, const std::vector<uint64_t>& voxels,
                            uint64_t stream, uint32_t count, uint64_t seed, std::vector<glm::vec3>& out);
inline void sample_eye_points_from(const CellSet& cells, const Aabb& box, const std::vector<uint64_t>& voxels,
                                   uint64_t stream, uint32_t count, uint64_t seed, std::vector<glm::vec3>& out) {
    sample_eye_points_from(cells.eyes, box, voxels, stream, count, seed, out);
}

// Appends `count` stratified random eye points of the cell to `out`.
inline void sample_eye_points(const CellSet& cells, uint32_t cell, uint32_t count, uint64_t seed,
                              std::vector<glm::vec3>& out) {
    sample_eye_points_in(cells, cells.cells[cell].bounds, cell, count, seed, out);
}

// Does any voxel of `mask` meet the box's open interior? (A voxel only touching a face does not count.)
// Cells are kept where the EYE mask meets them, so every cell has eye space in it.
bool mask_meets_box(const VoxelMask& mask, const Aabb& box);

// The part of `box` eyes can be in: the bounds of the eye voxels (as in mask_meets_box) clipped to the box.
// Convex, and it holds every eye point the box can get (docs/ALGORITHMS.md#eye-region). The whole box when
// `eyes` is empty (no view volume); an empty box when no eye voxel meets it.
Aabb eye_region(const VoxelMask& eyes, const Aabb& box);

// Appends `count` directions stratified over the whole sphere (equal-area strata in (cos theta, phi),
// one jittered direction per stratum). Unit length.
void sample_sphere_directions(uint32_t count, uint64_t seed, uint64_t stream, std::vector<glm::vec3>& out);

}  // namespace pvs
