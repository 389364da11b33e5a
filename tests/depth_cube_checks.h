// SPDX-License-Identifier: MIT
// Test helpers for the depth cube (pvs/depth_cube.h): the kernel against the reference on a scene's
// occludees, and the conservative guarantee for an eye box checked on segments from it.
#pragma once

#include "core/math.h"
#include "core/random.h"
#include "pvs/depth_cube.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace pvs::test {

// Does the segment from eye to x meet the box strictly before x? (double slab test over t in [0, 1))
inline bool segment_blocked(glm::dvec3 eye, glm::dvec3 x, const Aabb& b) {
    double t0 = 0.0, t1 = 1.0;
    const glm::dvec3 d = x - eye;
    for (int k = 0; k < 3; ++k) {
        const double lo = double(b.min[k]) - eye[k], hi = double(b.max[k]) - eye[k];
        if (d[k] == 0.0) {
            if (lo > 0.0 || hi < 0.0) return false;
            continue;
        }
        const double a = lo / d[k], c = hi / d[k];
        t0 = std::max(t0, std::min(a, c));
        t1 = std::min(t1, std::max(a, c));
    }
    return t0 <= t1 && t0 < 1.0;
}

// Point k of a box for the segment checks: its 8 corners first, then random points inside it, every fourth
// one moved onto a random face.
inline glm::dvec3 box_target(const Aabb& b, int k, Rng& rng) {
    glm::dvec3 x;
    for (int a = 0; a < 3; ++a) {
        const double t = k < 8 ? double((k >> a) & 1) : double(rng.uniform());
        x[a] = double(b.min[a]) + t * (double(b.max[a]) - double(b.min[a]));
    }
    if (k >= 8 && k % 4 == 0) {
        const int a = int(rng.below(3));
        x[a] = rng.uniform() < 0.5f ? double(b.min[a]) : double(b.max[a]);
    }
    return x;
}

// Eye e of an eye box of half-extents `spread` around `eye`: its 8 corners first (where the inset per ray is
// reached: an eye moved sideways and towards the plane at once), then random points of its surface.
inline glm::dvec3 eye_box_point(glm::vec3 eye, glm::dvec3 spread, int e, Rng& rng) {
    glm::dvec3 corner;  // in [-1, 1]^3
    if (e < 8) {
        for (int a = 0; a < 3; ++a) corner[a] = (e >> a) & 1 ? 1.0 : -1.0;
    } else {
        for (int a = 0; a < 3; ++a) corner[a] = 2.0 * double(rng.uniform()) - 1.0;
        corner[int(rng.below(3))] = rng.uniform() < 0.5f ? -1.0 : 1.0;
    }
    return glm::dvec3(eye) + spread * corner;
}

// The half-extents of an eye box: lo to hi metres per axis, and flat along one axis (a patch of a cell face)
// in half the draws.
inline glm::dvec3 random_eye_box(Rng& rng, double lo, double hi) {
    glm::dvec3 spread;
    for (int a = 0; a < 3; ++a) spread[a] = lo + (hi - lo) * double(rng.uniform());
    if (rng.uniform() < 0.5f) spread[int(rng.below(3))] = 0.0;
    return spread;
}

// Tallies of a random-scene check.
struct CubeCheck {
    int hidden = 0, tested = 0;
    long long failures = 0, segments = 0;
};

// Does the kernel agree with `reference(box)` on every occludee? Counts into `check`; reports the first
// few disagreements (prefixed by `where`).
template <class Reference>
void expect_same_answers(const DepthCube& cube, const std::vector<Aabb>& occludees,
                         const Reference& reference, const std::string& where, CubeCheck& check) {
    for (const Aabb& b : occludees) {
        const bool fast = cube.is_hidden(b), slow = reference(b);
        check.hidden += fast;
        ++check.tested;
        if (fast != slow && ++check.failures <= 5)
            ADD_FAILURE() << where << ": fast " << fast << ", reference " << slow;
    }
}

// For every occludee the cube proves hidden: `points` points of it and `eyes` eyes of the eye box, each
// segment from an eye to a point must be `blocked(q, x)`. Counts into `check`; reports the first few that
// are not.
template <class Blocked>
void expect_blocked_segments(const DepthCube& cube, const std::vector<Aabb>& occludees, glm::vec3 eye,
                             glm::dvec3 spread, int points, int eyes, Rng& rng, const Blocked& blocked,
                             const std::string& where, CubeCheck& check) {
    for (const Aabb& b : occludees) {
        ++check.tested;
        if (!cube.is_hidden(b)) continue;
        ++check.hidden;
        for (int k = 0; k < points; ++k) {
            const glm::dvec3 x = box_target(b, k, rng);
            for (int e = 0; e < eyes; ++e) {
                const glm::dvec3 q = eye_box_point(eye, spread, e, rng);
                ++check.segments;
                if (!blocked(q, x) && ++check.failures <= 5) {
                    ADD_FAILURE() << where << ", eye box (" << spread.x << ", " << spread.y << ", "
                                  << spread.z << "): segment from (" << q.x << ", " << q.y << ", " << q.z
                                  << ") to (" << x.x << ", " << x.y << ", " << x.z << ") is not blocked";
                }
            }
        }
    }
}

}  // namespace pvs::test
