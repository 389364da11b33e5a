// SPDX-License-Identifier: MIT
// pvsbake cells: the view volume, where a player's eye can be (docs/ALGORITHMS.md#view-volume).
//
// Sources, combined by INTERSECTION (each one only ever removes space):
//   - explicit boxes: the world's pvs_view_volume nodes and --view-box;
//   - reachable space: the flood of free voxels (no opaque triangle touches them) from the view seeds
//     (the world's pvs_view_seed nodes and --view-seed); a flood that reaches the world's bounds LEAKS:
//     reported with its path, and the bake carries on with all the flood reached;
//   - play height: only space up to --play-height above an upward-facing opaque surface (the BAND). With
//     a play height the flood from the seeds WALKS instead of flying (voxels/flood.h): it stays in the
//     band, steps off ledges and falls, and never walks sideways through a see-through surface. So eyes
//     never get over a wall, out through the sky or through a window into the inside of walls or the
//     void around a level: places a body cannot reach, where eyes would see the backs of everything.
// None given: the world bounds, with a warning (the bake is larger and slower than it needs to be); the
// conservative mode refuses that unless asked (--eyes-anywhere).
//
// Conventions: voxels as in voxels/voxels.h. Two masks come out:
//   eyes  - the free voxels left after the intersection: eye points are drawn here (never in a voxel an
//           opaque triangle touches, so never inside solid);
//   view  - eyes grown by one voxel (26 neighbours): the view region, reaching up to the walls, which the
//           cells cover and where a lookup finds a cell. Conservative for eyes: a point a player can reach
//           is in `view` whenever it is within one voxel of free reachable space. The conservative bake's
//           promise covers the eyes mask, not that rim (docs/ALGORITHMS.md#eye-space).
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/world.h"
#include "voxels/voxels.h"

#include <string>
#include <vector>

namespace pvs {

struct ViewVolume {
    bool voxelized = false;            // false: no source given, the view volume is the world bounds
    std::vector<std::string> sources;  // "boxes", "flood", "play_height", or "world_bounds"
    VoxelMask eyes;
    VoxelMask view;
    VoxelGrid grid;     // the voxels of the masks (when voxelized); without a source, the grid occluder
                        // synthesis voxelizes the world on
    BitVolume touched;  // voxels an opaque triangle touches (for occluder synthesis)
    Aabb view_bounds;   // bounds of `view` (or the world bounds)
    double eye_volume_m3 = 0.0;
    double view_volume_m3 = 0.0;
    double world_bounds_m3 = 0.0;
    // The flood, when seeds were given.
    bool flooded = false;
    bool leaked = false;
    std::vector<glm::vec3> leak_path;
    uint32_t seeds_used = 0;
    uint32_t seeds_moved = 0;
    uint32_t seeds_dropped = 0;
};

// Throws pvs::Error (bad input) when there is no source and config.need_sources without eyes_anywhere, and
// when the voxels break their caps (view_voxel_grid(), cells/world_extent.h).
ViewVolume build_view_volume(Context& ctx, const ViewVolumeConfig& config, const World& world);


// The voxel grid build_view_volume() uses (view_voxel_grid(), cells/world_extent.h): config.auto_voxel_size_m
// over the world's bounds when there is a source, else the default size (for occluder synthesis alone).
// Throws as view_voxel_grid() does.
VoxelGrid planned_view_grid(const ViewVolumeConfig& config, const World& world);

// The leak path as a Wavefront OBJ polyline ("v x y z" lines and one "l 1 2 ..."), which VTK, Blender and
// most viewers load over the world.
std::string leak_path_obj(const std::vector<glm::vec3>& path);

}  // namespace pvs
