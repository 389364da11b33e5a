// SPDX-License-Identifier: MIT
// Test helper: build a World in memory from named boxes (no glTF), and hand-made cell sets.
#pragma once

#include "core/cell_set.h"
#include "core/world.h"
#include "samples/random_world.h"

#include <string>

namespace pvs::test {

// Appends a box as one object: 12 triangles, or 10 with face `open_face` left out (samples/random_world.h).
inline uint32_t add_box_faces(World& world, const std::string& name, const Aabb& b, bool opaque,
                              uint32_t extra_flags, int open_face) {
    return add_box_object(world, name, b, opaque, extra_flags, open_face);
}

// A closed box (12 triangles) as one object. opaque=false: seen through (glass).
inline uint32_t add_box(World& world, const std::string& name, const Aabb& b, bool opaque = true,
                        uint32_t extra_flags = 0) {
    return add_box_faces(world, name, b, opaque, extra_flags, -1);
}

// A yard open to the sky: inside x in [0, 12], z in [0, 6], a 0.5 m floor below y = 0 and 4 m walls of
// 0.5 m, no roof (a flood of free space leaks out over the walls).
inline void add_open_yard(World& world) {
    add_box(world, "floor", Aabb::of({-0.5f, -0.5f, -0.5f}, {12.5f, 0, 6.5f}));
    add_box(world, "west", Aabb::of({-0.5f, 0, -0.5f}, {0, 4, 6.5f}));
    add_box(world, "east", Aabb::of({12, 0, -0.5f}, {12.5f, 4, 6.5f}));
    add_box(world, "south", Aabb::of({0, 0, -0.5f}, {12, 4, 0}));
    add_box(world, "north", Aabb::of({0, 0, 6}, {12, 4, 6.5f}));
}

// One grid cell of edge `size` with its min corner at `origin`.
inline CellSet single_cell(glm::vec3 origin, float size) {
    CellSet cells;
    cells.kind = CellSet::Kind::kGrid;
    cells.origin = origin;
    cells.cell_size_m = size;
    cells.dims = glm::ivec3(1);
    cells.grid_to_cell = {0};
    cells.cells.push_back(Cell{Aabb::of(origin, origin + glm::vec3(size)), -1});
    return cells;
}

}  // namespace pvs::test
