// SPDX-License-Identifier: MIT
// pvsbake occluders: the opaque solid, where occluders may live (docs/ALGORITHMS.md#solid).
//
// Conventions: voxels as in voxels/voxels.h. Sight starts at the eye space (the view volume's free
// voxels, or, with no view volume, everything outside the world) and goes in straight lines through
// voxels no opaque triangle touches (sight_reach: the 8 octants of directions, each a monotone sweep; a
// superset of what lines of sight reach). SOLID is what sight never reaches and no opaque triangle
// touches: the inside of closed opaque meshes, everything sealed off from the eyes (behind a shell
// level's walls), and, in a level open to the outside, the inside of walls whose faces toward the outside
// are missing, as long as no line of sight from the eye space goes through the opening into them.
// Touched voxels are never solid (part of them is on the free side of their surface), except inside the
// union of closed box meshes (add_closed_boxes()).
// Not a proof: a crack narrower than a voxel between triangles seals in voxels while sight passes it
// (docs/ALGORITHMS.md#cracks). Boxes built on this solid must be checked against the triangles before a
// conservative bake uses them; occluders/seal_probe.h looks for such cracks from the solid's side and
// reopen_leaks() lets sight through them.
#pragma once

#include "core/cell_set.h"
#include "core/context.h"
#include "core/world.h"
#include "voxels/voxels.h"

#include <vector>

namespace pvs {

struct Solid {
    VoxelGrid grid;
    BitVolume solid;
    uint64_t solid_voxels = 0;
    double solid_m3 = 0.0;
    bool from_eye_space = false;  // false: no view volume, sight came from outside the world
};

// `eyes`: the view volume's eye mask on the same grid as `touched` (empty: flood from the grid border).
Solid classify_solid(Context& ctx, const VoxelGrid& grid, const BitVolume& touched, const VoxelMask& eyes);

// Where sight starts: the eye mask's voxels, or with an empty mask the grid's border layer (outside the
// world). Throws internal_error when the mask is not on the grid.
BitVolume sight_sources(const VoxelGrid& grid, const VoxelMask& eyes);

// Sight again, letting through the `leaky` touched voxels (a line of sight was found passing them: a crack or
// the free part of a touched voxel, occluders/seal_probe.h): every solid voxel it now reaches, and every
// leaky one, leaves the solid. Only removes (the new blocked set is a subset of the old one). Returns the
// voxels removed.
uint64_t reopen_leaks(const BitVolume& touched, const BitVolume& leaky, const BitVolume& sources,
                      Solid& solid);

// What a probe found: the `seen` voxels (a line of sight passed them) leave the solid, then reopen_leaks()
// through the `leaky` ones. Returns the voxels removed by both.
uint64_t open_seen_and_leaky(const BitVolume& touched, const BitVolume& seen, const BitVolume& leaky,
                             const BitVolume& sources, Solid& solid);

// Closed box meshes: the bounds of objects whose triangles are all opaque, all lie in the planes of the six
// faces of the object's bounds, and add up on each face to exactly the face's area (a watertight box, as
// modular walls, floors, pillars and crates are; overlapping triangles that also leave a hole are not
// detected, a risk accepted for meshes built as boxes). Sight can only enter such a box through one of its
// triangles.
std::vector<Aabb> closed_box_objects(const World& world);

// Adds to the solid every voxel wholly inside the UNION of the closed boxes (touched or not): this fills
// the seams where closed meshes meet (a wall standing on a floor: the voxels of the contact plane are
// touched by both, inside neither alone, but inside their union, which sight cannot enter:
// docs/ALGORITHMS.md#closed-boxes). Boxes an eye voxel meets are left out. Returns the voxels added.
uint64_t add_closed_boxes(Context& ctx, const std::vector<Aabb>& boxes, const VoxelMask& eyes, Solid& solid);

}  // namespace pvs
