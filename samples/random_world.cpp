// SPDX-License-Identifier: MIT
#include "samples/random_world.h"

#include "core/random.h"

#include <algorithm>
#include <cmath>

namespace pvs {

uint32_t add_box_object(World& world, const std::string& name, const Aabb& b, bool opaque, uint32_t extra_flags,
                        int open_face) {
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

uint32_t add_prism_object(World& w, const std::string& name, const std::array<glm::vec2, 4>& xz, float y0,
                          float y1, int open_side) {
    const uint32_t base = uint32_t(w.positions.size());
    Aabb bounds;
    for (int k = 0; k < 4; ++k)
        for (const float y : {y0, y1}) {
            w.positions.emplace_back(xz[size_t(k)].x, y, xz[size_t(k)].y);
            bounds.extend(w.positions.back());
        }
    WorldObject obj;
    obj.name = name;
    obj.node_path = name;
    obj.bounds = bounds;
    obj.first_triangle = uint32_t(w.triangles.size());
    obj.flags = kObjectHasOpaque;
    const auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
        w.triangles.push_back(Triangle{{base + a, base + b, base + c}});
        w.triangle_opaque.push_back(1);
        w.triangle_double_sided.push_back(0);
    };
    tri(0, 4, 2), tri(2, 4, 6);  // bottom (vertex 2k at y0, 2k + 1 at y1)
    tri(1, 3, 5), tri(3, 7, 5);  // top
    for (uint32_t k = 0; k < 4; ++k) {
        if (int(k) == open_side) continue;
        const uint32_t a = 2 * k, b = 2 * ((k + 1) % 4);
        tri(a, b, a + 1), tri(b, b + 1, a + 1);
    }
    obj.triangle_count = uint32_t(w.triangles.size()) - obj.first_triangle;
    w.objects.push_back(obj);
    w.bounds.extend(bounds);
    return uint32_t(w.objects.size() - 1);
}

RandomWorld make_random_world(uint64_t seed, uint64_t attempt) {
    Rng rng(seed, 1000 + attempt);
    const auto in = [&](float lo, float hi) { return lo + (hi - lo) * rng.uniform(); };
    RandomWorld r;
    World& w = r.world;
    const glm::vec3 size(in(12, 16), in(3, 4), in(12, 16));
    const float t = in(0.5f, 1.0f);
    const auto add = [&](const std::string& name, const Aabb& b, bool opaque) {
        add_box_object(w, name, b, opaque);
        if (opaque) r.opaque.push_back(b);
    };
    // Interior boxes are clipped to the room (they may touch its shell, never pierce it); what the clip
    // leaves flat or empty is dropped.
    const auto add_inside = [&](const std::string& name, Aabb b, bool opaque) {
        b.min = glm::max(b.min, glm::vec3(0.0f));
        b.max = glm::min(b.max, size);
        if (glm::all(glm::lessThan(b.min + glm::vec3(0.01f), b.max))) add(name, b, opaque);
    };
    add("floor", Aabb::of({-t, -t, -t}, {size.x + t, 0, size.z + t}), true);
    add("roof", Aabb::of({-t, size.y, -t}, {size.x + t, size.y + t, size.z + t}), true);
    add("west", Aabb::of({-t, 0, -t}, {0, size.y, size.z + t}), true);
    add("east", Aabb::of({size.x, 0, -t}, {size.x + t, size.y, size.z + t}), true);
    add("south", Aabb::of({0, 0, -t}, {size.x, size.y, 0}), true);
    add("north", Aabb::of({0, 0, size.z}, {size.x, size.y, size.z + t}), true);

    // One or two partitions across the whole room (full height, 0.3 to 0.6 m thick), each with a doorway,
    // under a lintel or not: most of what culls.
    const uint32_t partitions = 1 + rng.below(2);
    const int first_along = rng.below(2) ? 0 : 2;
    for (uint32_t i = 0; i < partitions; ++i) {
        const int along = i == 0 ? first_along : 2 - first_along;  // the second one crosses the first
        const int across = 2 - along;
        const float thick = in(0.3f, 0.6f);
        const float at = in(0.3f, 0.7f) * size[across];
        const float door_width = in(0.8f, 2.0f);
        const float door_at = in(0.0f, size[along] - door_width);
        const float door_height = rng.uniform() < 0.7f ? in(2.0f, size.y - 0.3f) : size.y;
        const auto part = [&](const std::string& name, float a0, float a1, float y0) {
            glm::vec3 lo(0.0f, y0, 0.0f), hi(size);
            lo[along] = a0;
            hi[along] = a1;
            lo[across] = at;
            hi[across] = at + thick;
            if (a1 > a0) add_inside(name, Aabb::of(lo, hi), true);
        };
        const std::string name = "partition" + std::to_string(i);
        part(name + "a", 0.0f, door_at, 0.0f);
        part(name + "b", door_at + door_width, size[along], 0.0f);
        if (door_height < size.y) part(name + "_lintel", door_at, door_at + door_width, door_height);
    }
    const uint32_t walls = 2 + rng.below(4);
    for (uint32_t i = 0; i < walls; ++i) {
        const int along = rng.below(2) ? 0 : 2;  // the wall's long axis
        const int across = 2 - along;
        const float thick = in(0.3f, 0.6f);
        const float length = in(3.0f, 0.75f * size[along]);
        const float start = rng.uniform() < 0.3f ? 0.0f : in(0.0f, size[along] - length);
        const float at = in(1.0f, size[across] - 1.0f - thick);
        glm::vec3 lo(0.0f), hi(size);
        lo[along] = start;
        hi[along] = start + length;
        lo[across] = at;
        hi[across] = at + thick;
        const float kind = rng.uniform();
        if (kind >= 0.85f) {
            lo.y = in(1.5f, size.y - 0.5f);  // hanging from the roof
        } else if (kind >= 0.6f) {
            hi.y = in(1.0f, size.y - 0.5f);  // a low wall
        }
        add_inside("wall" + std::to_string(i), Aabb::of(lo, hi), true);
    }
    // Up to two walls turned 15 to 75 degrees off the axes (no axis panel comes from them; their faces are
    // slanted panels, docs/ALGORITHMS.md#slanted-panels), 2 to 5 m long and 0.2 to 0.5 m thick, full height
    // or low, a third of them hollow (one long side left out, as a compiled level's walls are).
    const uint32_t turned = rng.below(3);
    for (uint32_t i = 0; i < turned; ++i) {
        const float angle = glm::radians(in(15.0f, 75.0f)) * (rng.below(2) ? 1.0f : -1.0f);
        const float length = in(2.0f, 5.0f), thick = in(0.2f, 0.5f);
        const glm::vec2 along(std::cos(angle), std::sin(angle)), across(-along.y, along.x);
        const glm::vec2 centre(in(3.5f, size.x - 3.5f), in(3.5f, size.z - 3.5f));
        const glm::vec2 a = centre - 0.5f * length * along - 0.5f * thick * across;
        const glm::vec2 b = a + length * along, c = b + thick * across, d = a + thick * across;
        const float height = rng.uniform() < 0.7f ? size.y : in(1.0f, size.y - 0.5f);
        const int open_side = rng.below(3) == 0 ? 0 : -1;
        const std::array<glm::vec2, 4> footprint{a, b, c, d};
        add_prism_object(w, "turned" + std::to_string(i), footprint, 0.0f, height, open_side);
        Aabb bounds;
        for (const glm::vec2& p : footprint) {
            bounds.extend(glm::vec3(p.x, 0.0f, p.y));
            bounds.extend(glm::vec3(p.x, height, p.y));
        }
        r.opaque.push_back(bounds);
    }
    const uint32_t pillars = 2 + rng.below(4);
    for (uint32_t i = 0; i < pillars; ++i) {
        const glm::vec2 foot(in(0.4f, 1.2f), in(0.4f, 1.2f));
        const glm::vec3 lo(in(0.0f, size.x - foot.x), 0.0f, in(0.0f, size.z - foot.y));
        add_inside("pillar" + std::to_string(i), Aabb::of(lo, {lo.x + foot.x, size.y, lo.z + foot.y}), true);
    }
    const uint32_t crates = 3 + rng.below(6);
    Aabb last_crate = Aabb::of({0, 0, 0}, {1, 1, 1});
    for (uint32_t i = 0; i < crates; ++i) {
        const glm::vec3 s(in(0.4f, 1.5f), in(0.4f, 1.5f), in(0.4f, 1.5f));
        glm::vec3 lo(in(0.0f, size.x - s.x), 0.0f, in(0.0f, size.z - s.z));
        const float kind = rng.uniform();
        if (kind >= 0.8f) {
            lo.y = in(0.5f, std::max(0.5f, size.y - s.y - 0.3f));  // in the air
        } else if (kind >= 0.6f && i > 0 && last_crate.max.y + s.y < size.y) {
            lo = glm::vec3(last_crate.min.x + in(-0.3f, 0.3f), last_crate.max.y,
                           last_crate.min.z + in(-0.3f, 0.3f));  // stacked on the previous one
        }
        last_crate = Aabb::of(lo, lo + s);
        add_inside("crate" + std::to_string(i), last_crate, true);
    }
    const uint32_t glass = 1 + rng.below(3);
    for (uint32_t i = 0; i < glass; ++i) {
        glm::vec3 s;
        if (rng.uniform() < 0.5f) {  // a pane
            const int across = rng.below(2) ? 0 : 2;
            s = glm::vec3(in(1.0f, 4.0f), in(1.0f, size.y), in(1.0f, 4.0f));
            s[across] = in(0.02f, 0.1f);
        } else {  // a block
            s = glm::vec3(in(0.3f, 1.5f), in(0.3f, 1.5f), in(0.3f, 1.5f));
        }
        const glm::vec3 lo(in(0.0f, size.x - s.x), in(0.0f, size.y - s.y), in(0.0f, size.z - s.z));
        add_inside("glass" + std::to_string(i), Aabb::of(lo, lo + s), false);
    }
    const uint32_t targets = 8 + rng.below(9);
    for (uint32_t i = 0; i < targets; ++i) {
        const glm::vec3 s(in(0.1f, 0.4f), in(0.1f, 0.4f), in(0.1f, 0.4f));
        const glm::vec3 lo(in(0.0f, size.x - s.x), in(0.0f, size.y - s.y), in(0.0f, size.z - s.z));
        add_inside("target" + std::to_string(i), Aabb::of(lo, lo + s), rng.uniform() >= 0.2f);
    }

    const uint32_t seeds = 2 + rng.below(3);
    for (uint32_t i = 0; i < seeds; ++i) {
        for (int attempt_point = 0; attempt_point < 100; ++attempt_point) {
            const glm::vec3 p(in(0.2f, size.x - 0.2f), in(0.2f, size.y - 0.2f), in(0.2f, size.z - 0.2f));
            const bool in_solid = std::any_of(r.opaque.begin(), r.opaque.end(), [&](const Aabb& b) {
                return Aabb::of(b.min - glm::vec3(0.2f), b.max + glm::vec3(0.2f)).contains(p);
            });
            if (!in_solid) {
                w.view_seeds.push_back(p);
                break;
            }
        }
    }
    return r;
}

}  // namespace pvs
