// Test helper: build a World in memory from named boxes (no glTF), and hand-made cell sets.
#pragma once

#include "core/cell_set.h"
#include "core/world.h"

#include <string>

namespace pvs::test {

// Appends a box as one object: 12 triangles, or 10 with face `open_face` left out (0 and 1: z min and
// max; 2 and 3: y; 4 and 5: x). opaque=false: seen through (glass).
inline uint32_t add_box_faces(World& world, const std::string& name, const Aabb& b, bool opaque,
                              uint32_t extra_flags, int open_face) {
    const uint32_t base = uint32_t(world.positions.size());
    for (int i = 0; i < 8; ++i) {
        world.positions.emplace_back(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                     i & 4 ? b.max.z : b.min.z);
    }
    static const uint32_t kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                           {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    WorldObject obj;
    obj.name = name;
    obj.node_path = name;
    obj.bounds = b;
    obj.first_triangle = uint32_t(world.triangles.size());
    obj.triangle_count = open_face >= 0 ? 10 : 12;
    obj.flags = (opaque ? kObjectHasOpaque : kObjectHasSeeThrough) | extra_flags;
    for (int k = 0; k < 12; ++k) {
        if (k / 2 == open_face) continue;
        const auto& f = kFaces[k];
        world.triangles.push_back(Triangle{{base + f[0], base + f[1], base + f[2]}});
        world.triangle_opaque.push_back(opaque ? 1 : 0);
        world.triangle_double_sided.push_back(0);
    }
    world.objects.push_back(obj);
    world.bounds.extend(b);
    return uint32_t(world.objects.size() - 1);
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
