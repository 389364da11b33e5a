// SPDX-License-Identifier: MIT
// Random points and boxes for the property tests (a seeded core/random.h stream, so every run draws the
// same).
#pragma once

#include "core/math.h"
#include "core/random.h"

namespace pvs::test {

// A point of the box b, uniform.
inline glm::vec3 point_in(const Aabb& b, Rng& rng) {
    return b.min + b.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
}

// A box centred in [-span / 2, span / 2]^3 with sides up to max_size.
inline Aabb random_box(Rng& rng, float span, float max_size) {
    const glm::vec3 c = (glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f) * span;
    const glm::vec3 h = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * max_size * 0.5f;
    return Aabb::of(c - h, c + h);
}

// Does the segment q -> x meet the closed box (a slab test in double)? The slow reference of the shaft tests.
inline bool segment_meets_closed_box(const Aabb& b, glm::dvec3 q, glm::dvec3 x) {
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        const double d = x[k] - q[k];
        if (d == 0.0) {
            if (q[k] < b.min[k] || q[k] > b.max[k]) return false;
            continue;
        }
        double e0 = (double(b.min[k]) - q[k]) / d, e1 = (double(b.max[k]) - q[k]) / d;
        if (e0 > e1) std::swap(e0, e1);
        t0 = std::max(t0, e0);
        t1 = std::min(t1, e1);
    }
    return t0 <= t1;
}

}  // namespace pvs::test
