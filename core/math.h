// SPDX-License-Identifier: MIT
// pvsbake core: vectors and axis-aligned boxes.
//
// Conventions (every module): glTF axes, right-handed, +Y up, metres. Boxes are closed: a point on a
// face is inside. An empty box has min > max on every axis (see Aabb::empty()).
//
// GLM is the one third-party type allowed in our public headers: it is header-only vocabulary
// (glm::vec3 is three floats), it carries no lifetime and no link dependency.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pvs {

// The float nearest x on its side: float_at_most(x) <= x <= float_at_least(x), each the nearest such float.
inline float float_at_most(double x) {
    const float f = float(x);
    return double(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
inline float float_at_least(double x) {
    const float f = float(x);
    return double(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

struct Aabb {
    glm::vec3 min{std::numeric_limits<float>::infinity()};
    glm::vec3 max{-std::numeric_limits<float>::infinity()};

    static Aabb empty() { return {}; }
    static Aabb of(glm::vec3 lo, glm::vec3 hi) { return {lo, hi}; }

    bool is_empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    void extend(glm::vec3 p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Aabb& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    glm::vec3 center() const { return 0.5f * (min + max); }
    glm::vec3 size() const { return is_empty() ? glm::vec3(0.0f) : max - min; }
    double volume() const {
        const glm::vec3 s = size();
        return double(s.x) * double(s.y) * double(s.z);
    }
    bool contains(glm::vec3 p) const {
        return p.x >= min.x && p.y >= min.y && p.z >= min.z && p.x <= max.x && p.y <= max.y && p.z <= max.z;
    }
    // Closed boxes: touching faces overlap.
    bool overlaps(const Aabb& b) const {
        return min.x <= b.max.x && b.min.x <= max.x && min.y <= b.max.y && b.min.y <= max.y &&
               min.z <= b.max.z && b.min.z <= max.z;
    }
    bool operator==(const Aabb& o) const { return min == o.min && max == o.max; }
};

// The parameter interval [t0, t1] (t0 >= 0) where the ray o + t d meets the closed box, clipped to
// [0, t_max]. False when it misses. Axis-parallel rays (|d_a| < 1e-12) need o inside the slab.
inline bool ray_box_interval(glm::vec3 o, glm::vec3 d, const Aabb& b, float t_max, float& t0, float& t1) {
    t0 = 0.0f;
    t1 = t_max;
    for (int a = 0; a < 3; ++a) {
        if (std::fabs(d[a]) < 1e-12f) {
            if (o[a] < b.min[a] || o[a] > b.max[a]) return false;
            continue;
        }
        float ta = (b.min[a] - o[a]) / d[a], tb = (b.max[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

inline bool is_finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace pvs
