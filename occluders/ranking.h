// SPDX-License-Identifier: MIT
// pvsbake occluders: ranking occluder boxes for a view cell (docs/ALGORITHMS.md#ranking). After Hudson,
// Manocha, Cohen, Lin, Hoff and Zhang, "Accelerated Occlusion Culling using Shadow Frusta" (SoCG 1997): for
// each cell keep the few occluders worth testing at run time (for dynamic objects, which a PVS cannot
// list), chosen by their solid angle and by how much of the world lies in their shadow frusta.
//
// Conventions: glTF axes (right-handed, +Y up), metres, boxes closed (core/math.h). Solid angles in
// steradians (a whole sphere is 4 pi).
//
// - Solid angle: EXACT for a box seen from a point (not the area-angle estimate a (N.V)/|V|^2): the sum,
//   over the faces the point sees (at most 3), of the exact solid angle of the face, each face two
//   triangles by Van Oosterom and Strackee's formula (IEEE Trans. Biomed. Eng. 1983):
//   tan(W / 2) = |a.(b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|). Exact for a box
//   (docs/ALGORITHMS.md#solid-angle). A point in the closed box: 4 pi.
// - Shadow frustum of box B from eye p: the points q such that the segment [p, q] meets B (B included):
//   the cone from p over B (one plane through p and each silhouette edge of B) cut by the planes of the
//   faces p sees (q on their far side). An object's AABB lies WHOLLY in the shadow iff, for each of those
//   at most 9 planes, the corner of the AABB farthest out of it is inside: an exact test (up to rounding;
//   docs/ALGORITHMS.md#shadow-frustum); every ray from p to any point of the AABB passes through B.
//   segment_meets_box() is the simple reference (tests compare the two). An object only partly in the
//   shadow never counts: "hidden" here is conservative for an opaque box. From an eye inside B (the closed
//   box) there is no shadow.
// - Depth complexity, sampled: for each eye of the cell, the objects (and their triangles) wholly in the
//   box's shadow frustum; averaged over the cell's eyes (an eye inside the box counts as hiding nothing).
// - Score, higher is better:  score = sqrt( (W_mean / 4 pi) * h ),  h = (O_mean / N + T_mean) / 2,
//   with W_mean the mean solid angle over the cell's eyes, O_mean the mean number of objects wholly in the
//   shadow (of the world's N), T_mean the mean share of the world's triangles in them; a share in [0, 1]
//   (why this score: docs/ALGORITHMS.md#ranking-score). Ties (for example everything scoring 0 when no
//   object is wholly hidden) break by the largest solid angle, then by the lower box index, so the order is
//   total and the bake repeatable.
// - Candidates: boxes whose solid angle from SOME sampled eye of the cell reaches min_solid_angle_sr; the
//   best occluders_per_cell of them are kept. The depth complexity (the costly part) is measured only for
//   candidates that can still make the top K (a box scores at most sqrt(W_mean / 4 pi), as h <= 1): the
//   result is the same as measuring all of them.
#pragma once

#include "core/config.h"
#include "core/math.h"
#include "core/occluder.h"
#include "core/world.h"

#include <cstdint>
#include <vector>

namespace pvs {

constexpr double kFourPi = 12.566370614359172;

// Exact solid angle (sr) of the triangle (a, b, c) seen from the origin (vertices relative to the eye).
double triangle_solid_angle_sr(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

// Exact solid angle (sr) of the closed box seen from `eye`; 4 pi when the eye is in the closed box.
double box_solid_angle_sr(const Aabb& box, glm::vec3 eye);

// The shadow frustum of a box from an eye (see the conventions above): inside = every plane's
// dot(normal, q) + offset >= 0. Invalid (hides nothing) when the eye is in the closed box or so close to
// an edge's line that a plane is undefined.
struct ShadowFrustum {
    glm::dvec4 planes[9];  // xyz normal (unit), w offset
    glm::vec4 fast[9];     // the same in float, for the box tests (their rounding: micrometres at 100 m)
    int count = 0;
    bool valid = false;

    bool contains(glm::vec3 q) const;
    // Is the whole (non-empty) box in the shadow? False for an empty box or an invalid frustum.
    bool contains(const Aabb& b) const;
    // -1: the box is wholly outside some plane (nothing in it can be in the shadow), 1: wholly inside,
    // 0: neither.
    int classify(const Aabb& b) const;
};
ShadowFrustum shadow_frustum(const Aabb& box, glm::vec3 eye);

// The reference: does the closed segment [eye, q] meet the closed box? (Slab test in double.)
bool segment_meets_box(glm::vec3 eye, glm::vec3 q, const Aabb& box);

// The world's objects as occludees: bounds and triangle counts, with a small bounding volume hierarchy
// so that counting what a shadow frustum holds costs about the log of the objects, not their number.
// Objects with no triangles or an empty box are left out (nothing to hide).
class Occludees {
public:
    explicit Occludees(const World& world);
    Occludees(std::vector<Aabb> bounds, std::vector<uint32_t> triangles);

    size_t object_count() const { return bounds_.size(); }  // all objects, the empty ones included
    uint64_t total_triangles() const { return total_triangles_; }

    // Objects wholly in the frustum: their number and their triangles.
    void count_hidden(const ShadowFrustum& f, uint32_t& objects, uint64_t& triangles) const;
    // Calls hidden(object) for each object wholly in the frustum (any order).
    template <class F>
    void for_each_hidden(const ShadowFrustum& f, F&& hidden) const {
        if (!f.valid || nodes_.empty()) return;
        visit(f, 0, false, hidden);
    }

private:
    struct Node {
        Aabb bounds;
        uint32_t first = 0;  // leaf: first index into order_; inner: first child (the second follows)
        uint32_t count = 0;  // leaf: objects; 0: inner node
        uint32_t objects = 0;
        uint64_t triangles = 0;
    };
    void build();
    void build_node(uint32_t n, uint32_t begin, uint32_t end);
    template <class F>
    void visit(const ShadowFrustum& f, uint32_t n, bool inside, F& hidden) const {
        const Node& node = nodes_[n];
        if (!inside) {
            const int c = f.classify(node.bounds);
            if (c < 0) return;
            inside = c > 0;
        }
        if (node.count == 0) {
            visit(f, node.first, inside, hidden);
            visit(f, node.first + 1, inside, hidden);
            return;
        }
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
            const uint32_t o = order_[k];
            if (inside || f.contains(bounds_[o])) hidden(o);
        }
    }

    std::vector<Aabb> bounds_;
    std::vector<uint32_t> triangles_;
    uint64_t total_triangles_ = 0;
    std::vector<uint32_t> order_;  // the non-empty objects, grouped by leaf
    std::vector<Node> nodes_;      // nodes_[0] is the root
};

// One candidate box seen from one cell's eyes: its measures before ranking.
struct BoxMeasures {
    double solid_angle_max_sr = 0.0;
    double solid_angle_mean_sr = 0.0;
    double hidden_objects_mean = 0.0;
    double hidden_triangle_share_mean = 0.0;
};

// The sampled depth complexity of `box` from `eyes` (see above): m.hidden_objects_mean and
// m.hidden_triangle_share_mean, means over the eyes (0 with no eyes).
void measure_hidden(const Aabb& box, const Occludees& occludees, const std::vector<glm::vec3>& eyes,
                    BoxMeasures& m);

// The documented score (see above) of a box's measures, for a world of `object_count` objects.
double ranking_score(const BoxMeasures& m, size_t object_count);

// Ranks the boxes for one cell seen from `eyes`: `boxes[i]` for each i in `usable` (the proven occluders);
// appends the best config.occluders_per_cell candidates to `out`, best first (RankedOccluder::box = i).
// No eyes, or occluders_per_cell 0: appends nothing.
void rank_cell_occluders(const RankingConfig& config, const std::vector<Aabb>& boxes,
                         const std::vector<uint32_t>& usable, const Occludees& occludees,
                         const std::vector<glm::vec3>& eyes, std::vector<RankedOccluder>& out);

}  // namespace pvs
