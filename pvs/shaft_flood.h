// SPDX-License-Identifier: MIT
// pvsbake solver: separation in the shaft, a proof by the union of occluders whatever planes they lie in.
// Every segment between two boxes lies in the hull of the two; when the axis panels and the proven solid cut
// that hull into parts with the boxes in different ones, every segment meets an occluder before its end
// (docs/ALGORITHMS.md#shaft-flood).
//
// Contract: ShaftFlood::separates() is true only if every segment from a point of the box `region` to a
// point of the box `target`, both grown by kHideToleranceM, meets a panel or the proven solid at a point
// other than its end. The test is exact: a grid whose planes hold every occluder it uses, so that each cell
// is wholly inside the solid or not and each cell face wholly inside a panel or not, flooded from the cells
// meeting `region` through faces no panel covers, over cells that are not solid and meet the hull, stepping
// one way along each axis as a segment does (once per choice of ways on the axes where the boxes overlap,
// docs/ALGORITHMS.md#shaft-flood); false (not proven) when the flood reaches a cell meeting `target`.
// Occluders beyond the grid's budget of planes are left out, which only ever leaves a pair unproven.
#pragma once

#include "core/box_tree.h"
#include "core/math.h"
#include "core/occluder.h"

#include <cstdint>
#include <vector>

namespace pvs {

// A box in double: a tile of the proven solid (its sides on the voxel grid's planes, computed as
// origin + k * edge in double) or an axis panel (flat on one axis).
struct FloodBox {
    glm::dvec3 lo{0.0}, hi{0.0};
};

// The proven solid as boxes that tile it exactly, no two sharing a voxel, each within one chunk of
// kSolidTileChunk voxels on every axis from the grid's origin: in a chunk, runs of solid voxels along x,
// merged over y where the runs match, then over z where the rectangles match. Deterministic. A tile depends
// only on the voxels of its chunk, which lies in one tile of the geometry print (docs/ALGORITHMS.md#reuse),
// so what the flood reads near a pair is printed near it.
constexpr int kSolidTileChunk = 16;
std::vector<FloodBox> solid_tiles(const VoxelMask& solid);

struct FloodFigures {
    uint64_t tries = 0;      // separates() calls
    uint64_t separated = 0;  // of them, proven
    uint64_t cells = 0;      // grid cells they built
    uint64_t dropped = 0;    // occluders left out for the budget of planes
    double seconds = 0.0;    // thread seconds of the tries

    FloodFigures& operator+=(const FloodFigures& o) {
        tries += o.tries;
        separated += o.separated;
        cells += o.cells;
        dropped += o.dropped;
        seconds += o.seconds;
        return *this;
    }
};

class ShaftFlood {
public:
    // The axis panels of `panels` (those flat on one axis) and the tiles of `solid`.
    ShaftFlood(const std::vector<Aabb>& panels, const VoxelMask& solid);

    // See the contract above. Thread-safe.
    bool separates(const Aabb& region, const Aabb& target, FloodFigures& figures) const;

    size_t occluders() const { return boxes_.size(); }

private:
    std::vector<FloodBox> boxes_;  // the panels (flat), then the solid's tiles
    std::vector<int8_t> flat_;     // per box: the axis a panel is flat on, -1 for a tile
    std::vector<Aabb> bounds_;     // per box, in float, rounded outward (for the tree)
    BoxTree tree_;
};

}  // namespace pvs
