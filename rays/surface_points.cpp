// SPDX-License-Identifier: MIT
#include "rays/surface_points.h"

#include <algorithm>
#include <cmath>

namespace pvs {

// Per triangle: the running sum of triangle areas within its object (m2), to pick a triangle of an object
// with probability proportional to its area.
std::vector<double> cumulative_areas(const World& world) {
    std::vector<double> out(world.triangles.size(), 0.0);
    for (const WorldObject& obj : world.objects) {
        double sum = 0.0;
        for (uint32_t i = obj.first_triangle; i < obj.first_triangle + obj.triangle_count; ++i) {
            const Triangle& t = world.triangles[i];
            const glm::vec3 a = world.positions[t.v[0]], b = world.positions[t.v[1]],
                            c = world.positions[t.v[2]];
            sum += 0.5 * double(glm::length(glm::cross(b - a, c - a)));
            out[i] = sum;
        }
    }
    return out;
}

uint32_t random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object, Rng& rng,
                         glm::vec3& point) {
    const WorldObject& obj = world.objects[object];
    const auto first = cum_area.begin() + obj.first_triangle;
    const auto last = first + obj.triangle_count;
    const double pick = double(rng.uniform()) * *(last - 1);
    const auto it = std::min(std::upper_bound(first, last, pick), last - 1);
    const uint32_t t = obj.first_triangle + uint32_t(it - first);
    const Triangle& tri = world.triangles[t];
    const double r = std::sqrt(rng.uniform()), v = rng.uniform();
    point = glm::vec3((1.0 - r) * glm::dvec3(world.positions[tri.v[0]]) +
                      r * (1.0 - v) * glm::dvec3(world.positions[tri.v[1]]) +
                      r * v * glm::dvec3(world.positions[tri.v[2]]));
    return t;
}

glm::vec3 random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object,
                          Rng& rng) {
    glm::vec3 point;
    random_point_on(world, cum_area, object, rng, point);
    return point;
}

}  // namespace pvs
