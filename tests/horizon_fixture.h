// SPDX-License-Identifier: MIT
// A small fixture for the tests of the bake file, the runtime file and the fuzz seeds: horizon lists on a
// bake.
#pragma once

#include "core/occluder.h"
#include "io/bake_file.h"

namespace pvs::test {

// Horizon lists (bake file 1.8, runtime file 2.1) on any bake: two boxes (a solid one and a panel) and a
// tile, one list of the three for every cell.
inline void add_horizon_lists(BakeData& bake) {
    HorizonLists& h = bake.horizon;
    h = HorizonLists{};
    h.boxes = {Aabb::of({1, 0, 1}, {2, 3, 1.5f}), Aabb::of({0, 0, 3}, {4, 0, 4})};
    OccluderPolygon t;
    t.tile = true;
    t.normal = glm::normalize(glm::vec3(0.0f, 0.6f, 0.8f));
    t.offset = 2.0f;
    t.thickness = 1e-6f;
    t.corners = {{-1, 0, 2.5f}, {3, 0, 2.5f}, {3, 3, 0.25f}, {-1, 3, 0.25f}};
    for (const glm::vec3& c : t.corners) t.bounds.extend(c);
    h.tiles.push_back(t);
    h.cell_list.assign(bake.cells.size(), 0);
    h.offsets = {0, 3};
    h.entries = {0, 1, 2};
}

}  // namespace pvs::test
