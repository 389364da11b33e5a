// pvsbake core: the view cells of a bake, as plain data (built by cells/, stored by io/).
//
// Conventions: glTF axes, metres. Grid index order: x fastest, then y, then z:
//   grid_index = ix + dims.x * (iy + dims.y * iz).
// Grid cells are half-open for lookup: a point on the face between two cells belongs to the cell with
// the larger index along that axis, except on the grid's max face, which belongs to the last cell.
// Cells dropped from the grid (no view volume in them) have grid_to_cell == -1.
#pragma once

#include "core/math.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs {

struct Cell {
    Aabb bounds;
    int32_t parent = -1;  // octree parent (index into CellSet::nodes), -1 for grid cells
};

struct CellSet {
    enum class Kind : int32_t { kGrid = 0, kOctree = 1 };
    Kind kind = Kind::kGrid;
    glm::vec3 origin{0.0f};      // grid min corner, metres
    float cell_size_m = 0.0f;    // grid cell edge, metres
    glm::ivec3 dims{0};          // grid cells along x, y, z
    std::vector<int32_t> grid_to_cell;  // dims.x*dims.y*dims.z entries; -1 = no cell there
    std::vector<Cell> cells;

    size_t size() const { return cells.size(); }

    // The cell holding p, or -1 when p is outside every cell. O(1).
    int32_t find(glm::vec3 p) const {
        if (kind != Kind::kGrid || cell_size_m <= 0.0f || !is_finite(p)) return -1;
        int idx[3];
        for (int a = 0; a < 3; ++a) {
            const float rel = (p[a] - origin[a]) / cell_size_m;
            if (!(rel >= 0.0f) || rel > float(dims[a])) return -1;
            idx[a] = std::min(int(std::floor(rel)), dims[a] - 1);
        }
        const size_t g = size_t(idx[0]) + size_t(dims.x) * (size_t(idx[1]) + size_t(dims.y) * size_t(idx[2]));
        return grid_to_cell[g];
    }
};

}  // namespace pvs
