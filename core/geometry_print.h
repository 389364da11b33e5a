// SPDX-License-Identifier: MIT
// pvsbake core: a bake's geometry print, what an incremental re-bake compares (pvs/reuse.h): everything
// the conservative solver reads, hashed by place, so that a later bake can tell where its world differs.
//
// Conventions: glTF axes, metres. Tiles are cubes of `tile_m` from `origin`, index x fastest:
//   tile = tx + dims.x * (ty + dims.y * tz).
// A tile's hash is a function of the elements that meet it (closed boxes) and of the voxels in it, not of
// their order; two prints are comparable only when `header` is equal (the same voxel grid and tiles).
#pragma once

#include "core/math.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct GeometryPrint {
    uint64_t header = 0;            // the voxel grid, the tiles and the solver's global inputs; 0 = no print
    glm::vec3 origin{0.0f};         // the tiles' min corner
    float tile_m = 0.0f;            // tile edge
    glm::ivec3 dims{0};             // tiles along x, y, z
    std::vector<uint64_t> tiles;    // dims.x * dims.y * dims.z hashes
    uint64_t outside = 0;           // the elements that reach outside the tiles
    std::vector<uint64_t> objects;  // per object: its triangles, opacity and flags

    bool empty() const { return header == 0; }
    Aabb tile_box(uint64_t tile) const {
        const uint64_t nx = uint64_t(dims.x), ny = uint64_t(dims.y);
        const glm::vec3 at(float(tile % nx), float((tile / nx) % ny), float(tile / (nx * ny)));
        return Aabb::of(origin + at * tile_m, origin + (at + 1.0f) * tile_m);
    }
};

}  // namespace pvs
