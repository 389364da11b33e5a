// pvsbake pvs: the conservative PVS with occluder fusion, by occluder shrinking (after P. Wonka, M. Wimmer,
// D. Schmalstieg, "Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs", EGWR 2000; see
// ../shared/design/ALGORITHMS.md section 3).
//
// Why it is safe (the argument the code stands on):
// 1. Occluders are boxes of the proven solid shrunk by epsilon (pvs/occluder_synthesis.h): every point of a
//    shrunk box has its whole epsilon-ball inside the solid, where no sight line goes.
// 2. If the segment from a sample point s to a point x meets a shrunk box at y = s + t (x - s), then for any
//    q with |q - s| <= epsilon, the point q + t (x - q) of segment qx is within (1 - t) epsilon of y, so
//    inside the solid: segment qx is blocked too. Pointwise, so it holds for the union of boxes: fusion for
//    free.
// 3. Sight from an eye inside a cell either ends inside the cell (objects whose bounds meet the cell are
//    always listed) or leaves the cell's box through a point q of its boundary. The boundary is sampled on
//    a square grid whose every point is within epsilon of a sample (spacing <= epsilon * sqrt(2)), so q is
//    within epsilon of some sample s, and the part of the sight line beyond q is blocked whenever sx is.
//    The segment from the eye to q is unobstructed, so q lies in free space the flood reached or in a
//    voxel next to it (the view region); cracks aside, which the sight probe handles. So samples are only
//    needed near the view region: a sample is skipped when no voxel of `reach` (the view region grown by
//    ceil(epsilon / voxel) + 1 voxels) holds it, since then no point of the view region is within
//    epsilon of it. Without this, a cell straddling a wall would sample the room behind it.
// 4. From each sample, the depth cube (pvs/depth_cube.h) proves an object's bounds hidden only when every
//    segment from s to the bounds meets a shrunk box. An object is left out of a cell's PVS only if it is
//    proven hidden from EVERY sample of the cell's boundary (samples inside a shrunk box are skipped: their
//    ball lies in the solid, no sight line passes there).
// What it rests on beyond this argument: the solid being truly closed to sight (cracks narrower than a
// voxel are found by the sight probe and the ray check of occluder synthesis, which sample).
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/pvs_set.h"
#include "core/world.h"

#include <vector>

namespace pvs {

struct ConservativeFigures {
    uint64_t samples = 0;          // boundary sample points tested
    uint64_t samples_skipped = 0;  // inside a shrunk occluder
    uint64_t samples_far = 0;      // farther than epsilon from the view region
    uint64_t object_tests = 0;
    double seconds = 0.0;
};

// The conservative rows of arbitrary boxes (cells, or octree nodes being considered): rows has boxes.size()
// rows. Lists pvs_always_visible objects and objects whose bounds meet the box, then every object some
// boundary sample cannot prove hidden. `shrunk` are the epsilon-shrunk occluder boxes. Parallel over boxes.
void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const std::vector<Aabb>& shrunk,
                           const VoxelMask& reach, PvsSet& rows, ConservativeFigures& figures);

// The region where boundary samples are needed: `view` grown by ceil(epsilon / voxel) + 1 voxels.
VoxelMask sample_reach(const VoxelMask& view, double epsilon_m);

// The conservative PVS of every cell.
PvsSet bake_conservative_pvs(Context& ctx, const ConservativeConfig& config, const World& world,
                             const CellSet& cells, const std::vector<Aabb>& shrunk, const VoxelMask& reach,
                             ConservativeFigures& figures);

}  // namespace pvs
