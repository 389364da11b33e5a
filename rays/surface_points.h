// SPDX-License-Identifier: MIT
// pvsbake rays: uniform random points on an object's surface (aimed verification rays, and the benchmarks
// that ask whether an object is visible from a cell).
#pragma once

#include "core/random.h"
#include "core/world.h"

#include <vector>

namespace pvs {

// Per triangle: the running sum of triangle areas within its object (m2), to pick a triangle of an object
// with probability proportional to its area.
std::vector<double> cumulative_areas(const World& world);

// A uniform random point on the object's surface: a triangle by area, then a uniform point in it, computed
// in double and rounded to floats, so that it lies within the triangle's bounds (a float sum of the corners
// can leave them by a few float steps: off the object's own plane and bounds, where a ray may reach a point
// the object does not have). `cum_area` is cumulative_areas(world). Returns the world triangle's index.
uint32_t random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object, Rng& rng,
                         glm::vec3& point);
// The same, the point only.
glm::vec3 random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object, Rng& rng);

}  // namespace pvs
