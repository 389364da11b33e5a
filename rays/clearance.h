// SPDX-License-Identifier: MIT
// pvsbake rays: how wide an opening a line of sight passes, against the real opaque triangles
// (docs/ALGORITHMS.md#openings).
//
// Conventions: glTF axes, metres. Distances are Euclidean, between closed sets (a triangle with its edges,
// a segment with its ends); computed in double and returned as float. The WIDTH of a sight line from e to
// x is the largest w such that no opaque triangle comes within w / 2 of the CORE of the segment, the
// segment shortened by w / 2 at each end (so a tube of diameter w around the line is clear, except within
// w / 2 of the eye and of the point seen); when x lies on an object, the triangles of that object do not
// count (a line of the tube that meets them sees the object too, and a surface met aslant comes nearer
// the core than w / 2). An opening is at least T wide when some sight line through it has width >= T: the
// gap tolerance's promise is stated in these words.
#pragma once

#include "core/world.h"
#include "rays/ray_scene.h"

#include <functional>
#include <vector>

namespace pvs {

// The nearest point of the segment [a, b] to p.
glm::dvec3 closest_point_on_segment(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b);

// The nearest point of the closed triangle abc to p (degenerate triangles: of their edges).
glm::dvec3 closest_point_on_triangle(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

// Exact distance between the segment [p, q] and the triangle (0 when they meet). Degenerate segments (p ==
// q) and degenerate triangles are handled (the distance to a point, to an edge).
double segment_triangle_distance(glm::dvec3 p, glm::dvec3 q, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

// The opaque triangles within `radius` of the segment [p, q], every one of the world tested one by one: the
// reference for RayScene::opaque_triangles_near().
std::vector<TriangleCorners> opaque_triangles_near_segment_reference(const World& world, glm::vec3 p,
                                                                     glm::vec3 q, float radius);

// No object: every triangle counts.
constexpr uint32_t kNoObject = UINT32_MAX;

// The distance from the segment [p, q] to the nearest of `triangles` not of `ignore`, at most `cap`.
double distance_to_triangles(glm::dvec3 p, glm::dvec3 q, const std::vector<TriangleCorners>& triangles,
                             double cap, uint32_t ignore = kNoObject);

// The width of the sight line from `eye` to `seen` on object `seen_object` (kNoObject: a point in free
// space), at most `max_width_m` and at most the segment's length; found by bisection to `resolution_m`
// (the result is a width that holds, rounded down). `triangles`: the opaque triangles within
// max_width_m / 2 of the segment (or a superset).
float sight_line_width(glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                       const std::vector<TriangleCorners>& triangles, float max_width_m, float resolution_m);

// The same, gathering the triangles near the segment from the scene.
float sight_line_width(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                       float max_width_m, float resolution_m);

// Does the sight line from `eye` to `seen` (on `seen_object`, or kNoObject) have width at least `width_m`?
// (One distance query: exact.)
bool sight_line_at_least(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, uint32_t seen_object,
                         float width_m);

// The widest sight line found near a witness: a ray from `eye` along unit `direction` that touched
// `object` at `distance_m`. Lines are tried from eyes near `eye` that `eye_allowed` accepts, aimed at points
// near the witness point; a line counts when its ray touches `object` before an opaque triangle stops it,
// and its width is measured to the point touched. A randomized local search over `tries` lines at scales
// from `max_width_m` down to a ten-thousandth of it (deterministic for a seed); stops early once a line of
// width `max_width_m` is found. The witness line itself is measured first.
struct SightLine {
    glm::vec3 eye{0.0f};
    glm::vec3 seen{0.0f};
    float width_m = 0.0f;
};
SightLine widest_sight_line_near(const RayScene& scene, uint32_t object, glm::vec3 eye, glm::vec3 direction,
                                 float distance_m, float max_width_m,
                                 const std::function<bool(glm::vec3)>& eye_allowed, uint32_t tries,
                                 uint64_t seed);

// Is there a sight line of width at least `width_m` through the opening the segment [a, b] passes (both
// ends in free space)? The segment itself first, then a randomized local search over `tries` lines, one end
// moved at a time (to turn the line as well as shift it) by log-uniform scales from a twentieth of the
// segment's length (at least `width_m`, at most 0.25 m) down to 1e-4 of `width_m`, where `a_ok` and `b_ok`
// accept the moved end (empty: anywhere). Deterministic for a seed. An oblique line through a wide opening
// may itself be narrow: the search turns it towards the opening's middle.
bool opening_at_least(const RayScene& scene, glm::vec3 a, glm::vec3 b, float width_m, uint32_t tries,
                      uint64_t seed, const std::function<bool(glm::vec3)>& a_ok = {},
                      const std::function<bool(glm::vec3)>& b_ok = {});

}  // namespace pvs
