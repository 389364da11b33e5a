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

}  // namespace pvs::test
