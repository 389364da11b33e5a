// SPDX-License-Identifier: MIT
// Ranking occluder boxes for a view cell: exact solid angles, shadow frusta and the score (ranking.h).
// After Hudson et al., "Accelerated Occlusion Culling using Shadow Frusta" (SoCG 1997), and Van Oosterom and
// Strackee, "The Solid Angle of a Plane Triangle" (IEEE Trans. Biomed. Eng. 1983).
#include "occluders/ranking.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

namespace pvs {

namespace {

// Does the eye see face (axis, side) of the box: is it strictly on the outer side of the face's plane?
bool faces_eye(const Aabb& b, glm::dvec3 p, int axis, int side) {
    return side == 0 ? p[axis] < double(b.min[axis]) : p[axis] > double(b.max[axis]);
}

// The cap bound: no box inside a sphere of radius r whose centre is d away subtends more than this.
double cap_solid_angle_sr(double r, double d) {
    if (d <= r) return kFourPi;
    return 2.0 * 3.14159265358979323846 * (1.0 - std::sqrt(1.0 - (r * r) / (d * d)));
}

}  // namespace

double triangle_solid_angle_sr(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num = std::fabs(glm::dot(a, glm::cross(b, c)));
    const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
    return 2.0 * std::atan2(num, den);
}

double box_solid_angle_sr(const Aabb& box, glm::vec3 eye) {
    if (box.is_empty()) return 0.0;
    if (box.contains(eye)) return kFourPi;
    const glm::dvec3 p(eye);
    double sum = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            if (!faces_eye(box, p, axis, side)) continue;
            // The face's four corners in order around it: the other two axes u, v.
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            glm::dvec3 q[4];
            for (int k = 0; k < 4; ++k) {
                q[k][axis] = side ? box.max[axis] : box.min[axis];
                q[k][u] = (k == 1 || k == 2) ? box.max[u] : box.min[u];
                q[k][v] = (k >= 2) ? box.max[v] : box.min[v];
                q[k] -= p;
            }
            sum += triangle_solid_angle_sr(q[0], q[1], q[2]) + triangle_solid_angle_sr(q[0], q[2], q[3]);
        }
    }
    return sum;
}

bool segment_meets_box(glm::vec3 eye, glm::vec3 q, const Aabb& box) {
    if (box.is_empty()) return false;
    double t0 = 0.0, t1 = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double o = eye[a], d = double(q[a]) - double(eye[a]);
        if (d == 0.0) {
            if (o < box.min[a] || o > box.max[a]) return false;
            continue;
        }
        double ta = (double(box.min[a]) - o) / d, tb = (double(box.max[a]) - o) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

ShadowFrustum shadow_frustum(const Aabb& box, glm::vec3 eye) {
    ShadowFrustum f;
    if (box.is_empty() || !is_finite(eye) || box.contains(eye)) return f;
    const glm::dvec3 p(eye);
    const glm::dvec3 centre = 0.5 * (glm::dvec3(box.min) + glm::dvec3(box.max));
    const double scale = glm::length(glm::dvec3(box.max) - glm::dvec3(box.min)) + glm::length(centre - p);
    // The planes of the faces the eye sees: q must lie on their far side.
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            if (!faces_eye(box, p, axis, side)) continue;
            glm::dvec4 plane(0.0);
            plane[axis] = side == 0 ? 1.0 : -1.0;
            plane.w = side == 0 ? -double(box.min[axis]) : double(box.max[axis]);
            f.planes[f.count++] = plane;
        }
    }
    // The silhouette edges: between a face the eye sees and one it does not. Edge along axis a at sides
    // (sb, sc) of the other two axes b, c; its faces are (b, sb) and (c, sc).
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        for (int sb = 0; sb < 2; ++sb) {
            for (int sc = 0; sc < 2; ++sc) {
                if (faces_eye(box, p, b, sb) == faces_eye(box, p, c, sc)) continue;
                glm::dvec3 e0, e1;
                e0[a] = box.min[a];
                e1[a] = box.max[a];
                e0[b] = e1[b] = sb ? box.max[b] : box.min[b];
                e0[c] = e1[c] = sc ? box.max[c] : box.min[c];
                glm::dvec3 n = glm::cross(e0 - p, e1 - p);
                const double len = glm::length(n);
                if (!(len > 1e-9 * scale * scale)) return ShadowFrustum{};  // the eye on the edge's line
                n /= len;
                double w = -glm::dot(n, p);
                if (glm::dot(n, centre) + w < 0.0) {
                    n = -n;
                    w = -w;
                }
                f.planes[f.count++] = glm::dvec4(n, w);
            }
        }
    }
    for (int i = 0; i < f.count; ++i) f.fast[i] = glm::vec4(f.planes[i]);
    f.valid = true;
    return f;
}

bool ShadowFrustum::contains(glm::vec3 q) const {
    if (!valid) return false;
    const glm::dvec3 x(q);
    for (int i = 0; i < count; ++i)
        if (glm::dot(glm::dvec3(planes[i]), x) + planes[i].w < 0.0) return false;
    return true;
}

bool ShadowFrustum::contains(const Aabb& b) const {
    if (!valid || b.is_empty()) return false;
    for (int i = 0; i < count; ++i) {
        const glm::vec4& pl = fast[i];
        // The corner that goes farthest out of the plane (least dot product).
        const float x = pl.x >= 0 ? b.min.x : b.max.x, y = pl.y >= 0 ? b.min.y : b.max.y,
                    z = pl.z >= 0 ? b.min.z : b.max.z;
        if (pl.x * x + pl.y * y + pl.z * z + pl.w < 0.0f) return false;
    }
    return true;
}

int ShadowFrustum::classify(const Aabb& b) const {
    if (!valid || b.is_empty()) return -1;
    bool inside = true;
    for (int i = 0; i < count; ++i) {
        const glm::vec4& pl = fast[i];
        const bool px = pl.x >= 0, py = pl.y >= 0, pz = pl.z >= 0;
        // The corner deepest in the plane: if even it is out, the whole box is.
        const float hi = pl.x * (px ? b.max.x : b.min.x) + pl.y * (py ? b.max.y : b.min.y) +
                         pl.z * (pz ? b.max.z : b.min.z) + pl.w;
        if (hi < 0.0f) return -1;
        if (inside) {
            const float lo = pl.x * (px ? b.min.x : b.max.x) + pl.y * (py ? b.min.y : b.max.y) +
                             pl.z * (pz ? b.min.z : b.max.z) + pl.w;
            inside = lo >= 0.0f;
        }
    }
    return inside ? 1 : 0;
}

// ---------------------------------------------------------------------------------------------------------
// Occludees.

Occludees::Occludees(const World& world) {
    bounds_.reserve(world.objects.size());
    triangles_.reserve(world.objects.size());
    for (const WorldObject& o : world.objects) {
        bounds_.push_back(o.bounds);
        triangles_.push_back(o.triangle_count);
    }
    build();
}

Occludees::Occludees(std::vector<Aabb> bounds, std::vector<uint32_t> triangles)
    : bounds_(std::move(bounds)), triangles_(std::move(triangles)) {
    triangles_.resize(bounds_.size(), 0);
    build();
}

void Occludees::build() {
    total_triangles_ = 0;
    for (uint32_t t : triangles_) total_triangles_ += t;
    order_.clear();
    for (uint32_t o = 0; o < bounds_.size(); ++o)
        if (triangles_[o] > 0 && !bounds_[o].is_empty() && is_finite(bounds_[o].min) &&
            is_finite(bounds_[o].max))
            order_.push_back(o);
    nodes_.clear();
    if (order_.empty()) return;
    nodes_.reserve(2 * order_.size());
    nodes_.emplace_back();
    build_node(0, 0, uint32_t(order_.size()));
}

// Fills node n with order_[begin, end): median split on the longest axis of the centres, leaves of at most
// 4 objects; the two children of an inner node are adjacent.
void Occludees::build_node(uint32_t n, uint32_t begin, uint32_t end) {
    Aabb bounds, centres;
    uint64_t triangles = 0;
    for (uint32_t k = begin; k < end; ++k) {
        bounds.extend(bounds_[order_[k]]);
        centres.extend(bounds_[order_[k]].center());
        triangles += triangles_[order_[k]];
    }
    nodes_[n].bounds = bounds;
    nodes_[n].objects = end - begin;
    nodes_[n].triangles = triangles;
    if (end - begin <= 4) {
        nodes_[n].first = begin;
        nodes_[n].count = end - begin;
        return;
    }
    const glm::vec3 size = centres.size();
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](uint32_t a, uint32_t b) {
                         const float ca = bounds_[a].center()[axis], cb = bounds_[b].center()[axis];
                         return ca < cb || (ca == cb && a < b);
                     });
    const uint32_t first = uint32_t(nodes_.size());
    nodes_[n].first = first;
    nodes_[n].count = 0;
    nodes_.emplace_back();
    nodes_.emplace_back();
    build_node(first, begin, mid);
    build_node(first + 1, mid, end);
}

void Occludees::count_hidden(const ShadowFrustum& f, uint32_t& objects, uint64_t& triangles) const {
    objects = 0;
    triangles = 0;
    if (!f.valid || nodes_.empty()) return;
    // Iterative walk; a node wholly inside adds its totals without visiting its objects.
    uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        const int c = f.classify(node.bounds);
        if (c < 0) continue;
        if (c > 0) {
            objects += node.objects;
            triangles += node.triangles;
            continue;
        }
        if (node.count == 0) {
            stack[top++] = node.first;
            stack[top++] = node.first + 1;
            continue;
        }
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
            const uint32_t o = order_[k];
            if (f.contains(bounds_[o])) {
                ++objects;
                triangles += triangles_[o];
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Ranking.

double ranking_score(const BoxMeasures& m, size_t object_count) {
    const double objects = object_count > 0 ? m.hidden_objects_mean / double(object_count) : 0.0;
    const double hidden = 0.5 * (objects + m.hidden_triangle_share_mean);
    return std::sqrt(std::max(0.0, m.solid_angle_mean_sr / kFourPi * hidden));
}

void measure_hidden(const Aabb& box, const Occludees& occludees, const std::vector<glm::vec3>& eyes,
                    BoxMeasures& m) {
    const double total_triangles = double(std::max<uint64_t>(1, occludees.total_triangles()));
    m.hidden_objects_mean = 0.0;
    m.hidden_triangle_share_mean = 0.0;
    if (eyes.empty()) return;
    for (const glm::vec3& e : eyes) {
        uint32_t hidden = 0;
        uint64_t triangles = 0;
        occludees.count_hidden(shadow_frustum(box, e), hidden, triangles);
        m.hidden_objects_mean += double(hidden);
        m.hidden_triangle_share_mean += double(triangles) / total_triangles;
    }
    m.hidden_objects_mean /= double(eyes.size());
    m.hidden_triangle_share_mean /= double(eyes.size());
}

void rank_cell_occluders(const RankingConfig& config, const std::vector<Aabb>& boxes,
                         const std::vector<uint32_t>& usable, const Occludees& occludees,
                         const std::vector<glm::vec3>& eyes, std::vector<RankedOccluder>& out) {
    if (eyes.empty() || config.occluders_per_cell == 0 || usable.empty()) return;
    Aabb eye_box;
    for (const glm::vec3& e : eyes) eye_box.extend(e);
    const double n_eyes = double(eyes.size());
    struct Candidate {
        uint32_t box;
        BoxMeasures m;
        double score;
    };
    // Solid angles first (cheap); the depth complexity (the costly part) only for boxes that can still
    // make the top K: with h <= 1 a box scores at most sqrt(W_mean / 4 pi), so once K boxes are measured,
    // a box whose bound is below the K-th best score cannot enter (the result is the same as measuring all).
    std::vector<Candidate> candidates, measured;
    for (uint32_t i : usable) {
        const Aabb& box = boxes[i];
        if (box.is_empty()) continue;
        // Quick reject: the cap around the box's bounding sphere, from the nearest point of the eyes' box.
        const glm::vec3 centre = box.center();
        const glm::vec3 nearest = glm::clamp(centre, eye_box.min, eye_box.max);
        const double r = 0.5 * double(glm::length(box.size()));
        if (cap_solid_angle_sr(r, double(glm::length(centre - nearest))) < config.min_solid_angle_sr)
            continue;
        BoxMeasures m;
        for (const glm::vec3& e : eyes) {
            const double w = box_solid_angle_sr(box, e);
            if (w >= kFourPi) continue;  // the eye is in the box: no shadow, no solid angle to count
            m.solid_angle_max_sr = std::max(m.solid_angle_max_sr, w);
            m.solid_angle_mean_sr += w;
        }
        if (!(m.solid_angle_max_sr >= config.min_solid_angle_sr) || m.solid_angle_max_sr <= 0.0) continue;
        m.solid_angle_mean_sr /= n_eyes;
        // The bound (a hair above it: the hidden share may round a hair above 1).
        candidates.push_back(Candidate{i, m, std::sqrt(m.solid_angle_mean_sr / kFourPi) * (1.0 + 1e-9)});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
        return a.score > b.score || (a.score == b.score && a.box < b.box);
    });
    const size_t k_best = config.occluders_per_cell;
    std::vector<double> best;  // the K best scores so far, a min-heap
    for (Candidate& c : candidates) {
        if (best.size() == k_best && c.score < best.front()) break;  // sorted by bound: no later one enters
        measure_hidden(boxes[c.box], occludees, eyes, c.m);
        c.score = ranking_score(c.m, occludees.object_count());
        measured.push_back(c);
        best.push_back(c.score);
        std::push_heap(best.begin(), best.end(), std::greater<>());
        if (best.size() > k_best) {
            std::pop_heap(best.begin(), best.end(), std::greater<>());
            best.pop_back();
        }
    }
    candidates.swap(measured);
    const size_t keep = std::min<size_t>(config.occluders_per_cell, candidates.size());
    std::partial_sort(candidates.begin(), candidates.begin() + keep, candidates.end(),
                      [](const Candidate& a, const Candidate& b) {
                          if (a.score != b.score) return a.score > b.score;
                          if (a.m.solid_angle_max_sr != b.m.solid_angle_max_sr)
                              return a.m.solid_angle_max_sr > b.m.solid_angle_max_sr;
                          return a.box < b.box;
                      });
    for (size_t k = 0; k < keep; ++k) {
        const Candidate& c = candidates[k];
        out.push_back(RankedOccluder{c.box, float(c.score), float(c.m.solid_angle_max_sr),
                                     float(c.m.hidden_objects_mean), float(c.m.hidden_triangle_share_mean)});
    }
}

}  // namespace pvs
