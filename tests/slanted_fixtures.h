// SPDX-License-Identifier: MIT
// Test helpers for slanted panels: bumpy tilted sheets of opaque triangles, and a segment-triangle test in
// double to check that a segment claimed blocked meets one.
#pragma once

#include "core/math.h"
#include "core/random.h"
#include "core/world.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs::test {

// Does the segment p -> x meet the closed triangle (a, b, c)? (Double; a hit within 1e-9 of an edge counts.)
inline bool segment_meets_triangle(const glm::dvec3& p, const glm::dvec3& x, const glm::dvec3& a,
                                   const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 d = x - p, e1 = b - a, e2 = c - a;
    const glm::dvec3 h = glm::cross(d, e2);
    const double det = glm::dot(e1, h);
    if (std::abs(det) < 1e-15) return false;
    const glm::dvec3 s = p - a;
    const double u = glm::dot(s, h) / det;
    const glm::dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(d, q) / det, t = glm::dot(e2, q) / det;
    const double eps = 1e-9;
    return u >= -eps && v >= -eps && u + v <= 1.0 + eps && t >= -eps && t <= 1.0 + eps;
}

// A bumpy tilted sheet: an n x n grid of quads of 1 m in a random plane (not an axis plane), each vertex
// lifted by up to `bump` along the normal, each quad cut along a random diagonal.
inline World bumpy_sheet(Rng& rng, int n, double bump, glm::dvec3& normal) {
    do {
        normal = glm::normalize(glm::dvec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    } while (std::max({std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)}) > 0.95);
    const glm::dvec3 e1 = glm::normalize(glm::cross(normal, glm::dvec3(0.3, 0.5, 0.7)));
    const glm::dvec3 e2 = glm::cross(normal, e1);
    std::vector<glm::vec3> v;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            v.emplace_back(double(i) * e1 + double(j) * e2 + (2.0 * rng.uniform() - 1.0) * bump * normal);
    World w;
    w.positions = v;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            if (rng.uniform() < 0.5) {
                w.triangles.push_back(Triangle{{a, b, d}});
                w.triangles.push_back(Triangle{{a, d, c}});
            } else {
                w.triangles.push_back(Triangle{{a, b, c}});
                w.triangles.push_back(Triangle{{b, d, c}});
            }
        }
    w.triangle_opaque.assign(w.triangles.size(), 1);
    w.triangle_double_sided.assign(w.triangles.size(), 0);
    WorldObject o;
    o.triangle_count = uint32_t(w.triangles.size());
    for (const glm::vec3& p : v) o.bounds.extend(p);
    o.flags = kObjectHasOpaque;
    w.objects.push_back(o);
    w.bounds = o.bounds;
    return w;
}

// Does the segment p -> x meet any of the world's triangles?
inline bool segment_meets_world(const World& w, const glm::dvec3& p, const glm::dvec3& x) {
    return std::any_of(w.triangles.begin(), w.triangles.end(), [&](const Triangle& t) {
        return segment_meets_triangle(p, x, glm::dvec3(w.positions[t.v[0]]), glm::dvec3(w.positions[t.v[1]]),
                                      glm::dvec3(w.positions[t.v[2]]));
    });
}

}  // namespace pvs::test
