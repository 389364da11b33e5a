// SPDX-License-Identifier: MIT
// pvsbake voxels: exact voxel traversal of a ray (J. Amanatides and A. Woo, "A Fast Voxel Traversal
// Algorithm for Ray Tracing", Eurographics 1987).
//
// Conventions: voxels as in voxels/voxels.h. The walk starts in the voxel holding p (clamped to the grid)
// and visits, in order, every further voxel the ray p + t d (t in [0, reach]) enters.
#pragma once

#include "voxels/voxels.h"

#include <algorithm>
#include <limits>

namespace pvs {

class VoxelWalk {
public:
    VoxelWalk(const VoxelGrid& grid, glm::vec3 p, glm::vec3 d, float reach) : grid_(grid), reach_(reach) {
        c_ = grid.voxel_of(p);
        for (int a = 0; a < 3; ++a) {
            const float lo = grid.origin[a] + float(c_[a]) * grid.voxel_size_m;
            if (d[a] > 0.0f) {
                step_[a] = 1;
                t_max_[a] = (lo + grid.voxel_size_m - p[a]) / d[a];
                t_delta_[a] = grid.voxel_size_m / d[a];
            } else if (d[a] < 0.0f) {
                step_[a] = -1;
                t_max_[a] = (lo - p[a]) / d[a];
                t_delta_[a] = -grid.voxel_size_m / d[a];
            } else {
                step_[a] = 0;
                t_max_[a] = t_delta_[a] = std::numeric_limits<float>::infinity();
            }
        }
    }
    // Steps into the next voxel; false when the walk leaves the grid or its reach.
    bool next() {
        const int a = t_max_.x < t_max_.y ? (t_max_.x < t_max_.z ? 0 : 2) : (t_max_.y < t_max_.z ? 1 : 2);
        t_enter_ = std::max(0.0f, t_max_[a]);
        if (!(t_enter_ <= reach_)) return false;
        c_[a] += step_[a];
        t_max_[a] += t_delta_[a];
        return grid_.inside(c_);
    }
    // The voxel the walk is in (the start voxel before the first next()).
    uint64_t index() const { return grid_.index(c_.x, c_.y, c_.z); }
    // Where the ray entered it, and where it leaves it.
    float t_enter() const { return t_enter_; }
    float t_exit() const { return std::min(t_max_.x, std::min(t_max_.y, t_max_.z)); }

private:
    const VoxelGrid& grid_;
    float reach_;
    glm::ivec3 c_{0}, step_{0};
    glm::vec3 t_max_{0.0f}, t_delta_{0.0f};
    float t_enter_ = 0.0f;
};

}  // namespace pvs
