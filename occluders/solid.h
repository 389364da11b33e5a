// pvsbake occluders: the opaque solid, where occluders may live (ALGORITHMS.md section 1).
//
// Conventions: voxels as in occluders/voxels.h. Sight starts at the eye space (the view volume's free
// voxels, or, with no view volume, everything outside the world) and spreads through every voxel no
// opaque triangle touches. SOLID is what that flood never reaches and no opaque triangle touches: the
// inside of closed opaque meshes and everything sealed off from the eyes (behind a shell level's walls).
// Touched voxels are never solid: part of them is on the free side of their surface.
// Not a proof: a crack narrower than a voxel between triangles seals in voxels while sight passes it.
// Boxes built on this solid must be checked against the triangles before a conservative bake uses them.
#pragma once

#include "core/cell_set.h"
#include "core/context.h"
#include "occluders/voxels.h"

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

}  // namespace pvs
