// SPDX-License-Identifier: MIT
// pvsbake voxels: flood of free space from view seeds, and leak finding (after Quake's vis and its
// point file; docs/ALGORITHMS.md#flood); sight through free voxels (docs/ALGORITHMS.md#sight-sweep).
//
// Conventions: voxels as in voxels/voxels.h; 6-connected (face neighbours). The flood starts at the
// voxels of the seeds (points known to be in playable space) and spreads through voxels not blocked
// (not touched by an opaque triangle). What it reaches is the reachable free space; what it never
// reaches is sealed off from every seed by opaque voxels. If it reaches the grid's border layer (the
// grid is padded, so the border is outside the world's bounds) the level LEAKS: the result says so and
// gives the leak path, voxel centres from a seed to the border, and the flood still covers all it reached.
// Every level floods on all threads (OpenMP); a leaking one is searched again on one thread, breadth first,
// up to its first border voxel, for its path (docs/ALGORITHMS.md#flood). The result does not depend on the thread count.
// Note: a voxel seal is not a visibility proof (a crack narrower than a voxel is sealed in voxels);
// occluders built on "unreached" space must be checked against the triangles.
#pragma once

#include "core/context.h"
#include "voxels/voxels.h"

#include <vector>

namespace pvs {

struct FloodResult {
    BitVolume reached;
    uint64_t reached_count = 0;
    bool leaked = false;
    std::vector<glm::vec3> leak_path;  // seed to border, at the turns of the voxel path (empty if sealed)
    uint32_t seeds_used = 0;
    uint32_t seeds_moved = 0;    // seeds inside a blocked voxel, moved to the nearest free one
    uint32_t seeds_dropped = 0;  // seeds outside the grid or with no free voxel near
};

// `max_seed_move_voxels`: how far a seed inside a blocked voxel may move to a free one.
// `walk` (optional): a WALK instead of a flight: the flood enters a voxel of the band from any side;
// it leaves the band only sideways (off a ledge) or down, and moves through free voxels outside the band
// only down (falling). With the play-height band (the space a player's eye can be above floors) this is
// walking, climbing up to the band's height, and dropping off ledges: free space reached only by flying
// (over a wall, out through the sky) is not entered, nor is a see-through surface walked through
// sideways. Walking, reaching the grid's top is not a leak.
struct WalkRules {
    const BitVolume& band;   // where an eye can be: within the play height above a floor
    const BitVolume& glass;  // voxels see-through triangles touch: walked into only from above (a pool's
                             // surface), never sideways (a window)
};
FloodResult flood_free_space(Context& ctx, const VoxelGrid& grid, const BitVolume& blocked,
                             const std::vector<glm::vec3>& seeds, int max_seed_move_voxels = 4,
                             const WalkRules* walk = nullptr);

// SIGHT from `sources` through voxels not `blocked`: the union over the 8 sign octants of the voxels that
// monotone voxel paths (every step adds 0 or the octant's sign on each axis: a face, edge or corner step)
// reach from the sources. Holds every voxel some straight line from a source voxel can pass before it enters
// a blocked voxel (plus some no line does: a superset, which is the safe side;
// docs/ALGORITHMS.md#sight-sweep). Unlike a flood, sight does not turn corners: space behind an opening is
// reached only in the directions the opening looks. One sweep per octant, 64 voxels at a time; parallel
// over octants (OpenMP).
BitVolume sight_reach(const VoxelGrid& grid, const BitVolume& blocked, const BitVolume& sources);

}  // namespace pvs
