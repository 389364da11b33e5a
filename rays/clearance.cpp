// SPDX-License-Identifier: MIT
// Sight-line widths: exact segment-triangle distances over the opaque triangles near a segment.
// The closest-point routines follow C. Ericson, "Real-Time Collision Detection" (2005), 5.1.5 and 5.1.9.
#include "rays/clearance.h"

#include "core/random.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

using glm::dvec3;

double sq(dvec3 v) {
    return glm::dot(v, v);
}

// Squared distance from point p to the closed triangle abc.
double point_triangle_sq(dvec3 p, dvec3 a, dvec3 b, dvec3 c) {
    return sq(p - closest_point_on_triangle(p, a, b, c));
}

// Squared distance between the segments [p1, q1] and [p2, q2] (either may be a point).
double segment_segment_sq(dvec3 p1, dvec3 q1, dvec3 p2, dvec3 q2) {
    const dvec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = sq(d1), e = sq(d2), f = glm::dot(d2, r);
    double s = 0.0, t = 0.0;
    if (a <= 0.0 && e <= 0.0) return sq(r);
    if (a <= 0.0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = glm::dot(d1, r);
        if (e <= 0.0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = glm::dot(d1, d2);
            const double denom = a * e - b * b;
            s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1.0) {
                t = 1.0;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return sq((p1 + d1 * s) - (p2 + d2 * t));
}

// Does the closed segment [p, q] meet the triangle's plane inside the triangle? (Not for segments lying in
// the plane: their distance is found on the edges.)
bool segment_crosses_triangle(dvec3 p, dvec3 q, dvec3 a, dvec3 b, dvec3 c) {
    const dvec3 n = glm::cross(b - a, c - a);
    const double dp = glm::dot(n, p - a), dq = glm::dot(n, q - a);
    if ((dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || dp == dq) return false;
    const double t = dp / (dp - dq);
    const dvec3 x = p + t * (q - p);
    // Inside when x is on the inner side of all three edges (same sign as n).
    const double e0 = glm::dot(glm::cross(b - a, x - a), n);
    const double e1 = glm::dot(glm::cross(c - b, x - b), n);
    const double e2 = glm::dot(glm::cross(a - c, x - c), n);
    return e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
}

// The core of the segment [e, x] for width w: shortened by w / 2 at each end; false when nothing is left.
bool core_of(dvec3 e, dvec3 x, double w, dvec3& p, dvec3& q) {
    const double length = glm::length(x - e);
    if (length <= w) return false;
    const dvec3 u = (x - e) / length;
    p = e + 0.5 * w * u;
    q = x - 0.5 * w * u;
    return true;
}

// The object triangle t belongs to (objects hold contiguous ranges of triangles).
uint32_t object_of_triangle(const World& world, uint32_t t) {
    const auto it =
        std::upper_bound(world.objects.begin(), world.objects.end(), t,
                         [](uint32_t tri, const WorldObject& o) { return tri < o.first_triangle; });
    return uint32_t(it - world.objects.begin()) - 1;
}

}  // namespace

dvec3 closest_point_on_segment(dvec3 p, dvec3 a, dvec3 b) {
    const dvec3 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    if (!(len2 > 0.0)) return a;
    return a + std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) * ab;
}

dvec3 closest_point_on_triangle(dvec3 p, dvec3 a, dvec3 b, dvec3 c) {
    // Voronoi regions of the corners and edges (Ericson 5.1.5).
    const dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
    const dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    const double denom = va + vb + vc;
    if (!(std::abs(denom) > 0.0)) {
        // A degenerate triangle: its nearest point is on one of its edges.
        const dvec3 q[3] = {closest_point_on_segment(p, a, b), closest_point_on_segment(p, b, c),
                            closest_point_on_segment(p, c, a)};
        const double s0 = sq(p - q[0]), s1 = sq(p - q[1]), s2 = sq(p - q[2]);
        return s0 <= s1 && s0 <= s2 ? q[0] : (s1 <= s2 ? q[1] : q[2]);
    }
    return a + ab * (vb / denom) + ac * (vc / denom);
}

double segment_triangle_distance(dvec3 p, dvec3 q, dvec3 a, dvec3 b, dvec3 c) {
    if (segment_crosses_triangle(p, q, a, b, c)) return 0.0;
    // Both sets are convex and apart: a closest pair has an end of the segment or a point of an edge.
    double best = std::min(point_triangle_sq(p, a, b, c), point_triangle_sq(q, a, b, c));
    best = std::min(best, segment_segment_sq(p, q, a, b));
    best = std::min(best, segment_segment_sq(p, q, b, c));
    best = std::min(best, segment_segment_sq(p, q, c, a));
    return std::sqrt(best);
}

std::vector<TriangleCorners> opaque_triangles_near_segment_reference(const World& world, glm::vec3 p,
                                                                     glm::vec3 q, float radius) {
    std::vector<TriangleCorners> out;
    for (size_t t = 0; t < world.triangles.size(); ++t) {
        if (!world.triangle_opaque[t]) continue;
        const Triangle& tri = world.triangles[t];
        const TriangleCorners corners{world.positions[tri.v[0]], world.positions[tri.v[1]],
                                      world.positions[tri.v[2]], object_of_triangle(world, uint32_t(t))};
        if (segment_triangle_distance(p, q, corners.a, corners.b, corners.c) <= double(radius))
            out.push_back(corners);
    }
    return out;
}

double distance_to_triangles(dvec3 p, dvec3 q, const std::vector<TriangleCorners>& triangles, double cap,
                             uint32_t ignore) {
    double best = cap;
    for (const TriangleCorners& t : triangles) {
        if (t.object == ignore) continue;
        best = std::min(best, segment_triangle_distance(p, q, t.a, t.b, t.c));
        if (best <= 0.0) break;
    }
    return best;
}

float sight_line_width(glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                       const std::vector<TriangleCorners>& triangles, float max_width_m, float resolution_m) {
    // holds(w): the core for w keeps w / 2 from every triangle. Not monotone in w in general (a longer core
    // for a smaller w may pass nearer a triangle), so the bisection finds a w that holds, within the
    // resolution of a change; the definition asks only for the existence of such a w.
    const dvec3 e(eye), x(seen);
    const auto holds = [&](double w) {
        dvec3 p, q;
        if (!core_of(e, x, w, p, q)) return false;
        return distance_to_triangles(p, q, triangles, 0.5 * w, seen_object) >= 0.5 * w;
    };
    double lo = 0.0, hi = std::min(double(max_width_m), glm::length(x - e));
    if (hi <= 0.0) return 0.0;
    if (holds(hi)) return float(hi);
    const double step = std::max(double(resolution_m), 1e-7);
    while (hi - lo > step) {
        const double mid = 0.5 * (lo + hi);
        (holds(mid) ? lo : hi) = mid;
    }
    return float(lo);
}

float sight_line_width(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                       float max_width_m, float resolution_m) {
    std::vector<TriangleCorners> near;
    scene.opaque_triangles_near(eye, seen, 0.5f * max_width_m, near);
    return sight_line_width(eye, seen, seen_object, near, max_width_m, resolution_m);
}

bool sight_line_at_least(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                         float width_m) {
    const dvec3 e(eye), x(seen);
    dvec3 p, q;
    if (!core_of(e, x, double(width_m), p, q)) return false;
    std::vector<TriangleCorners> near;
    scene.opaque_triangles_near(glm::vec3(p), glm::vec3(q), 0.5f * width_m, near);
    return distance_to_triangles(p, q, near, 0.5 * double(width_m), seen_object) >= 0.5 * double(width_m);
}

namespace {

// Where the ray from `eye` along unit `direction` first touches `object` before it is stopped, if it does.
bool touches_object(const RayScene& scene, glm::vec3 eye, glm::vec3 direction, uint32_t object, float& t,
                    std::vector<RayTouch>& touches) {
    touches.clear();
    scene.trace(eye, &direction, 1, touches);
    bool found = false;
    for (const RayTouch& touch : touches) {
        if (touch.object == object && (!found || touch.t < t)) {
            t = touch.t;
            found = true;
        }
    }
    return found;
}

// The steps of the local searches around a line of `length` for a width of `width_m`: one end moved at a
// time by a near-normal offset whose scale is log-uniform from a twentieth of the length (at least the
// width, at most 0.25 m: large enough to turn an oblique line towards an opening's normal) down to 1e-4 of
// the width (to stay in a seam a few micrometres wide).
class SearchSteps {
public:
    SearchSteps(float length, float width_m, Rng& rng)
        : rng_(rng),
          largest_(std::clamp(0.05f * length, width_m, std::max(width_m, 0.25f))),
          decades_(std::log10(largest_ / (width_m * 1e-4f))) {}

    glm::vec3 next() {
        const float scale = largest_ * std::pow(10.0f, -decades_ * rng_.uniform());
        glm::vec3 d;
        // Sum of uniforms: cheap, bounded, near enough to a normal for a local search.
        for (int k = 0; k < 3; ++k) d[k] = (rng_.uniform() + rng_.uniform() + rng_.uniform() - 1.5f) * scale;
        return d;
    }

private:
    Rng& rng_;
    float largest_, decades_;
};

// Where along the segment [a, b] a line may be turned about: the points of the segment nearest the corners,
// edge midpoints and centroids of the opaque triangles within `radius` of it (the walls of the opening it
// passes), as parameters in [0, 1]. Turning about such a point keeps the line in the opening while it
// straightens.
std::vector<float> pivots_along(const RayScene& scene, glm::vec3 a, glm::vec3 b, float radius) {
    std::vector<TriangleCorners> near;
    scene.opaque_triangles_near(a, b, radius, near);
    std::vector<float> out;
    const glm::vec3 ab = b - a;
    const float ab2 = glm::dot(ab, ab);
    if (!(ab2 > 0.0f)) return out;
    for (const TriangleCorners& t : near) {
        for (const glm::vec3& p : {t.a, t.b, t.c, 0.5f * (t.a + t.b), 0.5f * (t.b + t.c), 0.5f * (t.c + t.a),
                                   (t.a + t.b + t.c) / 3.0f})
            out.push_back(std::clamp(glm::dot(p - a, ab) / ab2, 0.0f, 1.0f));
    }
    return out;
}

// The line through `pivot` from `from`, as far beyond the pivot as `old_end` was.
glm::vec3 through(glm::vec3 from, glm::vec3 pivot, glm::vec3 old_end) {
    const glm::vec3 d = pivot - from;
    const float len = glm::length(d);
    return len > 0.0f ? pivot + d / len * glm::length(old_end - pivot) : old_end;
}

}  // namespace

SightLine widest_sight_line_near(const RayScene& scene, uint32_t object, glm::vec3 eye, glm::vec3 direction,
                                 float distance_m, float max_width_m,
                                 const std::function<bool(glm::vec3)>& eye_allowed, uint32_t tries,
                                 uint64_t seed) {
    const float resolution = max_width_m * 1e-3f;
    SightLine best{eye, eye + direction * distance_m, 0.0f};
    best.width_m = sight_line_width(scene, best.eye, best.seen, object, max_width_m, resolution);
    Rng rng(seed, object);
    SearchSteps steps(distance_m, max_width_m, rng);
    std::vector<RayTouch> touches;
    std::vector<float> pivots = pivots_along(scene, best.eye, best.seen, max_width_m);
    for (uint32_t i = 0; i < tries && best.width_m < max_width_m; ++i) {
        // In turn: move the eye (within the eyes allowed), move the point aimed at, or move the eye and
        // turn the line about a point near the walls it passes (an oblique line through a wide opening is
        // narrow until it is turned).
        const uint32_t move = i % 3;
        const glm::vec3 e = move != 1 ? best.eye + steps.next() : best.eye;
        glm::vec3 aim = move == 1 ? best.seen + steps.next() : best.seen;
        if (move == 2) {
            if (pivots.empty()) continue;
            const float u = pivots[rng.below(uint32_t(pivots.size()))];
            aim = through(e, best.eye + (best.seen - best.eye) * u, best.seen);
        }
        if (move != 1 && !eye_allowed(e)) continue;
        const glm::vec3 d = aim - e;
        const float length = glm::length(d);
        if (!(length > 0.0f)) continue;
        float t = 0.0f;
        if (!touches_object(scene, e, d / length, object, t, touches)) continue;
        const glm::vec3 seen = e + d / length * t;
        const float w = sight_line_width(scene, e, seen, object, max_width_m, resolution);
        if (w > best.width_m) {
            best = SightLine{e, seen, w};
            pivots = pivots_along(scene, best.eye, best.seen, max_width_m);
        }
    }
    return best;
}

bool opening_at_least(const RayScene& scene, glm::vec3 a, glm::vec3 b, float width_m, uint32_t tries,
                      uint64_t seed, const std::function<bool(glm::vec3)>& a_ok,
                      const std::function<bool(glm::vec3)>& b_ok) {
    if (sight_line_at_least(scene, a, b, kNoObject, width_m)) return true;
    Rng rng(seed, 0x6f70656eULL);
    SearchSteps steps(glm::length(b - a), width_m, rng);
    const float resolution = width_m * 1e-3f;
    glm::vec3 best_a = a, best_b = b;
    float best = sight_line_width(scene, a, b, kNoObject, width_m, resolution);
    std::vector<float> pivots = pivots_along(scene, a, b, width_m);
    for (uint32_t i = 0; i < tries; ++i) {
        // In turn: move a, move b, or move a and turn the line about a point near the walls it passes.
        const uint32_t move = i % 3;
        const glm::vec3 na = move != 1 ? best_a + steps.next() : best_a;
        glm::vec3 nb = move == 1 ? best_b + steps.next() : best_b;
        if (move == 2) {
            if (pivots.empty()) continue;
            nb = through(na, best_a + (best_b - best_a) * pivots[rng.below(uint32_t(pivots.size()))], best_b);
        }
        if ((move != 1 && a_ok && !a_ok(na)) || (move != 0 && b_ok && !b_ok(nb))) continue;
        const float w = sight_line_width(scene, na, nb, kNoObject, width_m, resolution);
        if (w > best) {
            best = w;
            best_a = na;
            best_b = nb;
            if (best >= width_m) return true;
            pivots = pivots_along(scene, best_a, best_b, width_m);
        }
    }
    return false;
}

}  // namespace pvs
