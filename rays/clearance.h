// pvsbake rays: how wide an opening a line of sight passes, against the real opaque triangles
// (docs/ALGORITHMS.md#openings).
//
// Conventions: glTF axes, metres. Distances are Euclidean, between closed sets (a triangle with its edges,
// a segment with its ends); computed in double and returned as float. The WIDTH of a sight line from e to
// x is the largest w such that no opaque triangle comes within w / 2 of the CORE of the segment, the
// segment shortened by w / 2 at each end (so a tube of diameter w around the line is clear, except within
// w / 2 of the eye and of the point seen). An opening is at least T wide when some sight line through it
// has width >= T: the gap tolerance's promise is stated in these words.
#pragma once

#include "core/world.h"
#include "rays/ray_scene.h"

#include <vector>

namespace pvs {

// Exact distance between the segment [p, q] and the triangle (0 when they meet). Degenerate segments (p ==
// q) and degenerate triangles are handled (the distance to a point, to an edge).
double segment_triangle_distance(glm::dvec3 p, glm::dvec3 q, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

// The opaque triangles within `radius` of the segment [p, q], every one of the world tested one by one: the
// reference for RayScene::opaque_triangles_near().
std::vector<TriangleCorners> opaque_triangles_near_segment_reference(const World& world, glm::vec3 p,
                                                                     glm::vec3 q, float radius);

// The distance from the segment [p, q] to the nearest of `triangles`, at most `cap`.
double distance_to_triangles(glm::dvec3 p, glm::dvec3 q, const std::vector<TriangleCorners>& triangles,
                             double cap);

// The width of the sight line from `eye` to `seen` (definition above), at most `max_width_m` and at most
// the segment's length; found by bisection to `resolution_m` (the result is a width that holds, rounded
// down). `triangles`: the opaque triangles within max_width_m / 2 of the segment (or a superset).
float sight_line_width(glm::vec3 eye, glm::vec3 seen, const std::vector<TriangleCorners>& triangles,
                       float max_width_m, float resolution_m);

// The same, gathering the triangles near the segment from the scene.
float sight_line_width(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, float max_width_m,
                       float resolution_m);

// Does the sight line from `eye` to `seen` have width at least `width_m`? (One distance query: exact.)
bool sight_line_at_least(const RayScene& scene, glm::vec3 eye, glm::vec3 seen, float width_m);

}  // namespace pvs
