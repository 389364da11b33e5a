// SPDX-License-Identifier: MIT
// pvsbake cells: the voxels a world's extent gets, within their caps, and how far each object reaches from
// the rest of the world, to name the stray geometry that makes a world's bounds huge (a vertex thrown a
// thousand kilometres away by a bad export or flipped bytes) when those bounds would make the voxels too
// coarse or too many (docs/ALGORITHMS.md#world-extent).
//
// Conventions: glTF axes (right-handed, +Y up), metres, world space. "The rest" of an object is the bounds
// of every other object's triangles, with the view seeds and view boxes of the world: where the level is.
// An object's reach is the greatest distance from one of its vertices to the rest (0 inside it).
#pragma once

#include "core/config.h"
#include "core/world.h"
#include "voxels/voxels.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

struct ObjectReach {
    uint32_t object = 0;
    double distance_m = 0.0;  // from its farthest vertex to the bounds of the rest
    glm::vec3 vertex{0.0f};   // that vertex
};

// The `count` objects that reach farthest from the rest, farthest first; only those reaching out of it
// (distance > 0). With a single object and no view seeds or boxes there is no rest: none.
std::vector<ObjectReach> farthest_objects(const World& world, size_t count);

// An object stands apart when it reaches from the rest at least as far as the rest's longest edge (and at
// least kStrayMinReachM), the rest holding another object: the ground of a big level reaches a little past
// its buildings, a vertex thrown by a bad export reaches far past the whole level.
constexpr double kStrayMinReachM = 10.0;  // [Units: m]

// The `count` objects that stand apart from the rest, farthest first (farthest_objects()).
std::vector<ObjectReach> stray_objects(const World& world, size_t count);

// "object 'crate' has a vertex 1048.6 km from the rest of the world (at 1048576.0, 0.5, 1.0)", one clause
// per reach, joined by "; " ("" when there are none).
std::string describe_reaches(const World& world, const std::vector<ObjectReach>& reaches);

// A distance for people: "0.42 m", "312 m", "1048.6 km".
std::string format_distance(double metres);

// The voxel grid of the world's bounds a view volume uses (docs/ALGORITHMS.md#world-extent), padded by
// `pad_voxels` (0 = void_pad_voxels()):
// - config.voxel_size_m when given, refused (pvs::Error, bad input) only past the grid's own limit
//   (kMaxVoxels);
// - automatic: `preferred_m`, coarser to stay within config.max_voxels (default_voxel_size()) up to the
//   limit max_voxel_size_m (or the cells' edge, when smaller). A world that needs coarser voxels than the
//   limit to stay within max_voxels keeps voxels of the limit and more of them, up to kMaxVoxels (the memory
//   plan then says whether they fit the machine), unless an object stands apart from the rest
//   (stray_objects()): then it is refused, naming those objects. allow_coarse_voxels bakes anyway with the
//   voxels that fit max_voxels.
// The size never depends on the machine: the same world and options give the same grid everywhere.
VoxelGrid view_voxel_grid(const ViewVolumeConfig& config, const World& world, double preferred_m,
                          int pad_voxels);

}  // namespace pvs
