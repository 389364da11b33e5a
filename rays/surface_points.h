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

// A uniform random point on the object's surface: a triangle by area, then a uniform point in it.
// `cum_area` is cumulative_areas(world).
glm::vec3 random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object, Rng& rng);

}  // namespace pvs
