// SPDX-License-Identifier: MIT
// pvsbake core: the view cells of a bake, as plain data (built by cells/, stored by io/).
//
// Conventions: glTF axes, metres. Grid index order: x fastest, then y, then z:
//   grid_index = ix + dims.x * (iy + dims.y * iz).
// Grid cells are half-open for lookup: a point on the face between two cells belongs to the cell with
// the larger index along that axis, except on the grid's max face, which belongs to the last cell.
// Cells dropped from the grid (no view volume in them) have grid_to_cell == -1. With a view volume, a
// point outside it has no cell even inside a cell's box.
#pragma once

#include "core/math.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs {

// A set of voxels (bit per voxel, x fastest) over a box: where eyes can be. Empty = no mask.
struct VoxelMask {
    glm::vec3 origin{0.0f};
    float voxel_size_m = 0.0f;
    glm::ivec3 dims{0};
    std::vector<uint64_t> bits;  // ceil(dims.x * dims.y * dims.z / 64) words

    bool empty() const { return bits.empty(); }
    uint64_t count() const { return uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z); }
    bool get(uint64_t i) const { return (bits[i >> 6] >> (i & 63)) & 1u; }
    // Is p in a voxel of the mask? Voxels are closed boxes: a point on a face of a set voxel is in.
    bool contains(glm::vec3 p) const {
        if (empty() || !is_finite(p)) return false;
        const glm::vec3 rel = (p - origin) / voxel_size_m;
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            if (!(rel[a] >= 0.0f) || rel[a] > float(dims[a])) return false;
            const float f = std::floor(rel[a]);
            hi[a] = std::min(int(f), dims[a] - 1);
            lo[a] = rel[a] == f ? std::min(std::max(int(f) - 1, 0), hi[a]) : hi[a];  // on a face: both sides
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    if (get(uint64_t(x) + uint64_t(dims.x) * (uint64_t(y) + uint64_t(dims.y) * uint64_t(z))))
                        return true;
        return false;
    }
    bool operator==(const VoxelMask& o) const {
        return origin == o.origin && voxel_size_m == o.voxel_size_m && dims == o.dims && bits == o.bits;
    }
};

struct Cell {
    Aabb bounds;
    int32_t parent = -1;  // octree parent (index into CellSet::nodes), -1 for grid cells and roots
};

// An octree node. Children are 8 consecutive nodes from first_child, octant bits x = 1, y = 2, z = 4
// (bit set: the child's min corner is the parent's centre on that axis).
struct OctreeNode {
    Aabb bounds;
    int32_t first_child = -1;  // -1: a leaf
    int32_t cell = -1;         // a leaf's cell; -1 when the leaf holds no view volume
    int32_t parent = -1;
};

struct CellSet {
    enum class Kind : int32_t { kGrid = 0, kOctree = 1 };
    Kind kind = Kind::kGrid;
    glm::vec3 origin{0.0f};             // grid min corner, metres
    float cell_size_m = 0.0f;           // grid cell edge, metres
    glm::ivec3 dims{0};                 // grid cells along x, y, z
    std::vector<int32_t> grid_to_cell;  // dims.x*dims.y*dims.z entries; -1 = no cell there. For an
                                        // octree: the root grid, each entry a root node (or -1)
    std::vector<Cell> cells;
    std::vector<OctreeNode> nodes;  // octree only
    // The view volume (cells/view_volume.h), when one was built: `view` is where a lookup finds a cell
    // (the view region, up to the walls), `eyes` where eye points are drawn (free space only).
    VoxelMask view;
    VoxelMask eyes;

    size_t size() const { return cells.size(); }

    // The cell holding p, or -1 when p is outside every cell or outside the view volume. O(1) on a grid,
    // O(depth) on an octree.
    int32_t find(glm::vec3 p) const {
        if (cell_size_m <= 0.0f || !is_finite(p)) return -1;
        if (!view.empty() && !view.contains(p)) return -1;
        int idx[3];
        for (int a = 0; a < 3; ++a) {
            const float rel = (p[a] - origin[a]) / cell_size_m;
            if (!(rel >= 0.0f) || rel > float(dims[a])) return -1;
            idx[a] = std::min(int(std::floor(rel)), dims[a] - 1);
        }
        const size_t g = size_t(idx[0]) + size_t(dims.x) * (size_t(idx[1]) + size_t(dims.y) * size_t(idx[2]));
        if (kind == Kind::kGrid) return grid_to_cell[g];
        int32_t n = grid_to_cell[g];
        while (n >= 0 && nodes[size_t(n)].first_child >= 0) {
            const glm::vec3 c = nodes[size_t(n)].bounds.center();
            n = nodes[size_t(n)].first_child + (p.x >= c.x ? 1 : 0) + (p.y >= c.y ? 2 : 0) +
                (p.z >= c.z ? 4 : 0);
        }
        return n >= 0 ? nodes[size_t(n)].cell : -1;
    }
};

}  // namespace pvs
