// SPDX-License-Identifier: MIT
// Random convex polygon occluders for the culler tests (the form pvsr_culler_add_polygon and
// OcclusionCuller::add_polygon take), and the slow reference of their promise: a segment that crosses the
// slab from side to side, entering and leaving it inside the prism over the corners, is hidden.
#pragma once

#include <cmath>
#include <random>
#include <vector>

namespace pvs::test {

struct TestPolygon {
    float plane[5];              // normal x, y, z, offset, thickness
    std::vector<float> corners;  // 3 floats each, convex, counter-clockwise seen from +normal
    uint32_t count() const { return uint32_t(corners.size() / 3); }
};

// A slanted convex polygon of 3 to 8 corners on an ellipse around `centre` (radii 1 to `radius`), its normal
// random (so off the axis planes), its slab 0 to `max_thickness` thick.
inline TestPolygon random_polygon(std::mt19937& rng, const float centre[3], float radius,
                                  float max_thickness) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double kPi = 3.14159265358979323846;
    double n[3], len = 0.0;
    do {
        len = 0.0;
        for (double& x : n) {
            x = 2.0 * u(rng) - 1.0;
            len += x * x;
        }
    } while (len < 0.04 || len > 1.0);
    len = std::sqrt(len);
    for (double& x : n) x /= len;
    // e1 perpendicular to n, e2 = n x e1: angles increasing from e1 towards e2 are counter-clockwise from +n.
    const int a = std::abs(n[0]) < 0.6 ? 0 : 1;
    double e1[3] = {0, 0, 0};
    e1[a] = 1.0;
    const double d = e1[0] * n[0] + e1[1] * n[1] + e1[2] * n[2];
    double l1 = 0.0;
    for (int k = 0; k < 3; ++k) {
        e1[k] -= d * n[k];
        l1 += e1[k] * e1[k];
    }
    l1 = std::sqrt(l1);
    for (double& x : e1) x /= l1;
    const double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2],
                          n[0] * e1[1] - n[1] * e1[0]};
    const double r1 = 1.0 + (radius - 1.0) * u(rng), r2 = 1.0 + (radius - 1.0) * u(rng);
    const int count = 3 + int(rng() % 6);
    const double start = 2.0 * kPi * u(rng);
    TestPolygon p;
    double offset = 0.0;
    for (int k = 0; k < 3; ++k) offset += n[k] * double(centre[k]);
    for (int i = 0; i < count; ++i) {
        const double t = start + 2.0 * kPi * (double(i) + 0.4 * u(rng)) / double(count);
        for (int k = 0; k < 3; ++k)
            p.corners.push_back(
                float(double(centre[k]) + r1 * std::cos(t) * e1[k] + r2 * std::sin(t) * e2[k]));
    }
    for (int k = 0; k < 3; ++k) p.plane[k] = float(n[k]);
    p.plane[3] = float(offset);
    p.plane[4] = float(max_thickness * u(rng));
    return p;
}

// The reference: does the segment e -> x cross the polygon's slab from side to side, meeting both of its
// planes inside the prism over the corners grown by `grow` metres? (Double, from the float data.)
inline bool segment_crosses_polygon(const float e[3], const double x[3], const TestPolygon& p, double grow) {
    double n[3], len = 0.0;
    for (int k = 0; k < 3; ++k) {
        n[k] = double(p.plane[k]);
        len += n[k] * n[k];
    }
    len = std::sqrt(len);
    for (double& v : n) v /= len;
    const double o = double(p.plane[3]) / len, t = double(p.plane[4]) / len;
    double se = -o, sx = -o;
    for (int k = 0; k < 3; ++k) {
        se += n[k] * double(e[k]);
        sx += n[k] * x[k];
    }
    if (!((se < -t && sx > t) || (se > t && sx < -t))) return false;
    const uint32_t c = p.count();
    for (const double w : {-t, t}) {
        const double s = (w - se) / (sx - se);
        double q[3];
        for (int k = 0; k < 3; ++k) q[k] = double(e[k]) + s * (x[k] - double(e[k]));
        for (uint32_t i = 0; i < c; ++i) {
            const float* p0 = &p.corners[3 * i];
            const float* p1 = &p.corners[3 * ((i + 1) % c)];
            const double dd[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
            double m[3] = {n[1] * dd[2] - n[2] * dd[1], n[2] * dd[0] - n[0] * dd[2],
                           n[0] * dd[1] - n[1] * dd[0]};
            const double ml = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            double side = 0.0;
            for (int k = 0; k < 3; ++k) side += m[k] / ml * (q[k] - double(p0[k]));
            if (side < -grow) return false;
        }
    }
    return true;
}

}  // namespace pvs::test
