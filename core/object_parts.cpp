// SPDX-License-Identifier: MIT
// Part boxes of objects (core/object_parts.h).
#include "core/object_parts.h"

#include <algorithm>

namespace pvs {

namespace {

double grown_volume(const Aabb& b) {
    double v = 1.0;
    for (int a = 0; a < 3; ++a) v *= double(b.max[a]) - double(b.min[a]) + 2.0 * kPartSlackM;
    return v;
}

}  // namespace

ObjectParts object_parts(const World& world, uint32_t max_parts) {
    ObjectParts out;
    if (max_parts < 2) return out;
    max_parts = std::min(max_parts, kMaxObjectParts);
    out.offsets.reserve(world.objects.size() + 1);
    out.offsets.push_back(0);
    std::vector<uint32_t> tris;
    std::vector<Aabb> parts;
    struct Range {
        size_t a, b;
        uint32_t parts;
    };
    std::vector<Range> todo;
    for (const WorldObject& obj : world.objects) {
        tris.resize(obj.triangle_count);
        for (uint32_t k = 0; k < obj.triangle_count; ++k) tris[k] = obj.first_triangle + k;
        const auto centre = [&](uint32_t t) {
            const Triangle& tri = world.triangles[t];
            return (world.positions[tri.v[0]] + world.positions[tri.v[1]] + world.positions[tri.v[2]]) / 3.0f;
        };
        parts.clear();
        todo.assign(1, Range{0, tris.size(), max_parts});
        while (!todo.empty()) {
            const Range r = todo.back();
            todo.pop_back();
            if (r.b <= r.a) continue;
            if (r.parts <= 1 || r.b - r.a == 1) {
                Aabb box;
                for (size_t k = r.a; k < r.b; ++k)
                    for (int c = 0; c < 3; ++c) box.extend(world.positions[world.triangles[tris[k]].v[c]]);
                parts.push_back(box);
                continue;
            }
            Aabb cb;
            for (size_t k = r.a; k < r.b; ++k) cb.extend(centre(tris[k]));
            const glm::vec3 e = cb.max - cb.min;
            const int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
            const size_t mid = (r.a + r.b) / 2;
            // Ties broken by index, so the split does not depend on the library's nth_element.
            std::nth_element(tris.begin() + long(r.a), tris.begin() + long(mid), tris.begin() + long(r.b),
                             [&](uint32_t x, uint32_t y) {
                                 const float cx = centre(x)[axis], cy = centre(y)[axis];
                                 return cx != cy ? cx < cy : x < y;
                             });
            todo.push_back({mid, r.b, r.parts - r.parts / 2});
            todo.push_back({r.a, mid, r.parts / 2});
        }
        double volume = 0.0;
        bool inside = !obj.bounds.is_empty();
        for (const Aabb& p : parts) {
            volume += grown_volume(p);
            inside = inside && glm::all(glm::greaterThanEqual(p.min, obj.bounds.min)) &&
                     glm::all(glm::lessThanEqual(p.max, obj.bounds.max));
        }
        if (parts.size() >= 2 && inside && (obj.flags & kObjectAlwaysVisible) == 0 &&
            volume < kPartVolumeShare * grown_volume(obj.bounds))
            out.boxes.insert(out.boxes.end(), parts.begin(), parts.end());
        out.offsets.push_back(uint32_t(out.boxes.size()));
    }
    return out;
}

}  // namespace pvs
