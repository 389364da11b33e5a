// How far each object reaches from the rest of the world (cells/world_extent.h).
#include "cells/world_extent.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace pvs {

namespace {

double distance_to_box(const Aabb& box, glm::vec3 p) {
    const glm::dvec3 d = glm::max(glm::max(glm::dvec3(box.min) - glm::dvec3(p), glm::dvec3(p) - glm::dvec3(box.max)),
                                  glm::dvec3(0.0));
    return std::sqrt(glm::dot(d, d));
}

}  // namespace

std::vector<ObjectReach> farthest_objects(const World& world, size_t count) {
    const size_t n = world.objects.size();
    // What every object is measured against besides the other objects: the view seeds and boxes.
    Aabb markers;
    for (const glm::vec3& s : world.view_seeds) markers.extend(s);
    for (const Aabb& b : world.view_volume_boxes)
        if (!b.is_empty()) markers.extend(b);
    // The bounds of every object but i: a prefix and a suffix union, O(n).
    std::vector<Aabb> before(n + 1), after(n + 1);
    for (size_t i = 0; i < n; ++i) {
        before[i + 1] = before[i];
        if (world.objects[i].triangle_count) before[i + 1].extend(world.objects[i].bounds);
    }
    for (size_t i = n; i-- > 0;) {
        after[i] = after[i + 1];
        if (world.objects[i].triangle_count) after[i].extend(world.objects[i].bounds);
    }
    std::vector<ObjectReach> out;
    for (size_t i = 0; i < n; ++i) {
        Aabb rest = markers;
        if (!before[i].is_empty()) rest.extend(before[i]);
        if (!after[i + 1].is_empty()) rest.extend(after[i + 1]);
        const WorldObject& o = world.objects[i];
        if (rest.is_empty() || o.triangle_count == 0) continue;
        ObjectReach r{uint32_t(i), 0.0, {}};
        for (uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t)
            for (uint32_t v : world.triangles[t].v) {
                const double d = distance_to_box(rest, world.positions[v]);
                if (d > r.distance_m) r = {uint32_t(i), d, world.positions[v]};
            }
        if (r.distance_m > 0.0) out.push_back(r);
    }
    std::sort(out.begin(), out.end(), [](const ObjectReach& a, const ObjectReach& b) {
        return a.distance_m != b.distance_m ? a.distance_m > b.distance_m : a.object < b.object;
    });
    // Only those that stand out: within a tenth of the farthest reach.
    const double floor_m = out.empty() ? 0.0 : 0.1 * out.front().distance_m;
    std::erase_if(out, [&](const ObjectReach& r) { return r.distance_m < floor_m; });
    if (out.size() > count) out.resize(count);
    return out;
}

std::string format_distance(double metres) {
    if (metres >= 1000.0) return fmt::format("{:.1f} km", metres * 1e-3);
    if (metres >= 10.0) return fmt::format("{:.0f} m", metres);
    return fmt::format("{:.2f} m", metres);
}

std::string describe_reaches(const World& world, const std::vector<ObjectReach>& reaches) {
    std::string out;
    for (const ObjectReach& r : reaches) {
        if (!out.empty()) out += "; ";
        out += fmt::format("object '{}' has a vertex {} from the rest of the world (at {:.1f}, {:.1f}, {:.1f})",
                           world.objects[r.object].name, format_distance(r.distance_m), r.vertex.x, r.vertex.y,
                           r.vertex.z);
    }
    return out;
}

}  // namespace pvs
