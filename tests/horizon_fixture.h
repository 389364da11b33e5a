// SPDX-License-Identifier: MIT
// A small fixture for the tests of the bake file, the runtime file and the fuzz seeds: horizon lists on a
// bake.
#pragma once

#include "core/occluder.h"
#include "io/bake_file.h"
#include "runtime/pvsr.h"

namespace pvs::test {

// Horizon lists (bake file 1.8, runtime file 2.1) on any bake: two boxes (a solid one and a panel) and a
// tile, one list of the three for every cell; with per_cell, a list per cell (runtime file 5.2): cell c
// keeps all three when c % 4 == 0, else all but occluder c % 4 - 1 (none but the box for c % 7 == 6). With
// tests (bake file 1.10, runtime file 5.3), cell c's frames test the objects o of its row with
// (o + c) % 3 != 0, and none when c % 5 == 4.
inline void add_horizon_lists(BakeData& bake, bool per_cell = false, bool tests = false) {
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
    if (!per_cell) return;
    h.offsets = {0};
    h.entries.clear();
    for (uint32_t c = 0; c < bake.cells.size(); ++c) {
        h.cell_list[c] = c;
        for (uint32_t o = 0; o < 3; ++o)
            if (c % 7 == 6 ? o == 0 : (c % 4 == 0 || o != c % 4 - 1)) h.entries.push_back(o);
        h.offsets.push_back(uint32_t(h.entries.size()));
    }
    if (!tests) return;
    h.test_offsets = {0};
    for (uint32_t c = 0; c < bake.cells.size(); ++c) {
        if (c % 5 != 4)
            for (uint32_t o = 0; o < bake.objects.size(); ++o)
                if ((o + c) % 3 != 0 && bake.pvs.test(c, o)) h.tests.push_back(o);
        h.test_offsets.push_back(uint32_t(h.tests.size()));
    }
}

// Object parts (bake file 1.9, runtime file 2.2) on any bake: every object with a box for bounds gets the
// two halves of it along x, and each third object the four quarters along x and z, each rounded outward to
// the grid the runtime file stores parts on (5.1, pvsr_part_encode), as the bake's are.
inline Aabb on_part_grid(const Aabb& bounds, const Aabb& part) {
    const float b[6] = {bounds.min.x, bounds.min.y, bounds.min.z, bounds.max.x, bounds.max.y, bounds.max.z};
    const float p[6] = {part.min.x, part.min.y, part.min.z, part.max.x, part.max.y, part.max.z};
    uint16_t steps[6];
    float box[6];
    if (!pvsr_part_encode(b, p, steps, box)) return bounds;
    return Aabb::of({box[0], box[1], box[2]}, {box[3], box[4], box[5]});
}

inline void add_object_parts(BakeData& bake) {
    ObjectParts& p = bake.object_parts;
    p = ObjectParts{};
    p.offsets.push_back(0);
    for (size_t o = 0; o < bake.objects.size(); ++o) {
        const Aabb& b = bake.objects[o].bounds;
        if (!b.is_empty()) {
            const float mx = 0.5f * (b.min.x + b.max.x), mz = 0.5f * (b.min.z + b.max.z);
            if (o % 3 == 0) {
                for (int i = 0; i < 4; ++i) {
                    Aabb q = b;
                    ((i & 1) ? q.min.x : q.max.x) = mx;
                    ((i & 2) ? q.min.z : q.max.z) = mz;
                    p.boxes.push_back(on_part_grid(b, q));
                }
            } else {
                p.boxes.push_back(on_part_grid(b, Aabb::of(b.min, {mx, b.max.y, b.max.z})));
                p.boxes.push_back(on_part_grid(b, Aabb::of({mx, b.min.y, b.min.z}, b.max)));
            }
        }
        p.offsets.push_back(uint32_t(p.boxes.size()));
    }
}

}  // namespace pvs::test
