// SPDX-License-Identifier: MIT
// The shaft pass: piece pairs of a region and an object, each covered in one plane by panels and the solid.
#include "pvs/shaft_hiding.h"

#include "cells/eyes.h"
#include "core/convex_clip.h"
#include "core/random.h"
#include "occluders/panels.h"
#include "pvs/region_hiding.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>

namespace pvs {

namespace {

using Poly = std::vector<glm::dvec2>;

// More pieces than this left of a plane's cover: given up (not covered).
constexpr size_t kMaxPieces = 64;
// Voxel coordinates within this of a voxel's side count as on it (both voxels are then tested).
constexpr double kVoxelSlack = 1e-6;
// Random sight lines tried before the cover search: one that meets no occluder settles the pair.
constexpr int kProbeLines = 32;
// Halving: a side across an open strip (narrower than this share of the crossing, relative to the other
// side's share) counts this many times its length.
constexpr double kNarrowStrip = 0.5;
constexpr double kAcrossStripWeight = 4.0;
// A piece pair halved 10 + log2(budget) times from the whole region and object is not halved again: the
// pair is given up (listed). Pairs that need deeper pieces are mostly seams between occluders of different
// planes, which no depth closes, and they spent most of the budget; a larger budget buys some depth too.
constexpr int kBaseHalvings = 10;

double cross(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// The convex hull of the n <= 64 points `pts` (sorted in place; Andrew's monotone chain) into `out`,
// counter-clockwise, without collinear corners; fewer than 3 corners when it has no area.
void convex_hull(glm::dvec2* pts, size_t n, Poly& out) {
    std::sort(pts, pts + n,
              [](const glm::dvec2& a, const glm::dvec2& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    std::array<glm::dvec2, 130> h;
    if (n < 3 || n > 64) {
        out.assign(pts, pts + std::min<size_t>(n, 2));
        return;
    }
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0.0) --k;
        h[k++] = pts[i];
    }
    for (size_t i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0.0) --k;
        h[k++] = pts[i];
    }
    out.assign(h.begin(), h.begin() + std::ptrdiff_t(k - 1));
}

// A piece with no area: fewer than three corners, or no extent on an axis (a piece cut to a rectangle's
// side). The uncovered part of a convex polygon of positive area, less closed sets, is open in it, so it
// has positive area when it is not empty: pieces without area are covered.
bool degenerate(const Poly& p) {
    if (p.size() < 3) return true;
    glm::dvec2 lo = p[0], hi = p[0];
    for (const glm::dvec2& q : p) {
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    return !(hi.x > lo.x && hi.y > lo.y);
}

// The corners of the part of triangle (a, b, c) inside the closed box, in double; empty if none.
void clip_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const Aabb& box,
                   std::vector<glm::dvec3>& poly, std::vector<glm::dvec3>& tmp) {
    poly = {a, b, c};
    for (int k = 0; k < 3 && !poly.empty(); ++k)
        for (int side = 0; side < 2 && !poly.empty(); ++side) {
            clip(poly, k, side ? double(box.max[k]) : double(box.min[k]), side == 1, tmp);
            poly.swap(tmp);
        }
}

// Calls visit(voxel, solid) for the voxels of `mask` the segment from -> to passes, in order, until visit
// returns true (Amanatides and Woo).
template <class Visit>
void walk_voxels(const VoxelMask& mask, glm::vec3 from, glm::vec3 to, Visit&& visit) {
    if (mask.empty()) return;
    const double h = mask.voxel_size_m;
    const glm::dvec3 o(mask.origin);
    const glm::dvec3 p0 = (glm::dvec3(from) - o) / h, p1 = (glm::dvec3(to) - o) / h;
    const glm::dvec3 dd = p1 - p0;
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        if (dd[k] == 0.0) {
            if (p0[k] < 0.0 || p0[k] >= mask.dims[k]) return;
            continue;
        }
        double a = (0.0 - p0[k]) / dd[k], b = (double(mask.dims[k]) - p0[k]) / dd[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
    }
    if (!(t0 < t1)) return;
    glm::ivec3 cell, step;
    glm::dvec3 t_max, t_delta;
    const glm::dvec3 start = p0 + (t0 + 1e-9) * dd;
    for (int k = 0; k < 3; ++k) {
        cell[k] = std::clamp(int(std::floor(start[k])), 0, mask.dims[k] - 1);
        step[k] = dd[k] > 0.0 ? 1 : -1;
        t_delta[k] = dd[k] != 0.0 ? 1.0 / std::abs(dd[k]) : INFINITY;
        const double next = dd[k] > 0.0 ? double(cell[k] + 1) : double(cell[k]);
        t_max[k] = dd[k] != 0.0 ? (next - p0[k]) / dd[k] : INFINITY;
    }
    for (int guard = 0; guard < mask.dims.x + mask.dims.y + mask.dims.z + 3; ++guard) {
        const uint64_t idx =
            uint64_t(cell.x) +
            uint64_t(mask.dims.x) * (uint64_t(cell.y) + uint64_t(mask.dims.y) * uint64_t(cell.z));
        if (visit(cell, mask.get(idx))) return;
        const int k = t_max.x < t_max.y ? (t_max.x < t_max.z ? 0 : 2) : (t_max.y < t_max.z ? 1 : 2);
        if (t_max[k] > t1) return;
        cell[k] += step[k];
        if (cell[k] < 0 || cell[k] >= mask.dims[k]) return;
        t_max[k] += t_delta[k];
    }
}

// More umbrae than this per plane tried: the rest of the plane's crossing is left open.
constexpr size_t kMaxUmbrae = 16;
// Rounds of umbra search through the open pieces of a crossing, after the search through its open corners.
constexpr int kUmbraRounds = 2;
// Planes of a piece pair tried again with umbrae when none covers it alone: the first ones the line met.
constexpr size_t kFusedPlanes = 4;
// The convex caps of this many of the first panels a line meets are tried.
constexpr size_t kCapTouches = 4;
// Open corner crossings the umbra search traces lines through (the first and the farthest from it).
constexpr size_t kUmbraProbes = 2;
// Pieces narrower than this (metres) count as covered: the rounding of double computations where two
// covers meet along one line (docs/ALGORITHMS.md#cross-plane-fusion).
constexpr double kSliverM = 1e-9;
// A cup's piece lies this many tolerances inside each face (so the hull of a face's corner crossings holds
// every crossing, docs/ALGORITHMS.md#cups); the outer piece as far outside the cup.
constexpr double kCupMarginTolerances = 4.0;
// Lines to find a cup's faces run to the corners of the other piece pulled this share towards its centre.
constexpr float kCupCornerPull = 0.01f;
// Rounds of a cup search: each moves every face left open to the next plane out.
constexpr int kCupRounds = 4;
// A piece pair tries a cup when it has been halved a multiple of this many times: most of what cups at
// every depth prove, for a fraction of their cost (docs/RESULTS.md, "Tightness levers").
constexpr int kCupDepthStep = 4;
// The flood (pvs/shaft_flood.h) is tried on the same pieces as cups, and on pieces at the depth cap.
constexpr int kFloodDepthStep = kCupDepthStep;

// How wide convex `p` is: the least, over its sides, of its farthest corner's distance from the side's line.
double width(const Poly& p) {
    if (p.size() < 3) return 0.0;
    double w = INFINITY;
    for (size_t i = 0; i < p.size(); ++i) {
        const glm::dvec2 a = p[i], d = p[(i + 1) % p.size()] - a;
        const double len = glm::length(d);
        if (!(len > 0.0)) continue;
        double far = 0.0;
        for (const glm::dvec2& q : p)
            far = std::max(far, std::abs(d.x * (q.y - a.y) - d.y * (q.x - a.x)) / len);
        w = std::min(w, far);
    }
    return w == INFINITY ? 0.0 : w;
}

bool sliver(const Poly& p) {
    if (p.size() < 3) return true;
    // The width is at least the area over the diameter, which the bounds' diagonal exceeds.
    double area = 0.0;
    glm::dvec2 lo = p[0], hi = p[0];
    for (size_t i = 0; i < p.size(); ++i) {
        const glm::dvec2 a = p[i], b = p[(i + 1) % p.size()];
        area += a.x * b.y - a.y * b.x;
        lo = glm::min(lo, a);
        hi = glm::max(hi, a);
    }
    if (0.5 * std::abs(area) > 2.0 * kSliverM * glm::length(hi - lo)) return false;
    return width(p) <= kSliverM;
}

// Is p in the closed convex counter-clockwise polygon `poly`?
bool inside(const Poly& poly, glm::dvec2 p) {
    if (poly.size() < 3) return false;
    for (size_t i = 0; i < poly.size(); ++i)
        if (cross(poly[i], poly[(i + 1) % poly.size()], p) < 0.0) return false;
    return true;
}

}  // namespace

// Per thread: the pieces of a plane's cover, and the umbrae found for it.
struct ShaftProver::PlaneScratch {
    std::vector<Poly> pieces, next;
    Poly rest, part, band;
    std::vector<uint32_t> near_rects;  // the plane's panels meeting the crossing's bounds
    std::vector<glm::dvec2> open;      // corner crossings no panel or solid voxel of the plane covers
    std::vector<Poly> umbrae;
    std::vector<uint32_t> tried;  // occluders of umbra_scene_ whose umbrae were computed
    std::vector<RayTouch> touches;
    std::vector<glm::dvec3> corners;
    Poly shadow, clipped, other;
    std::array<glm::dvec2, 64> pts;
};

bool umbra_on_plane(const std::array<glm::dvec3, 8>& eyes, const glm::dvec3* corners, size_t n, int axis,
                    double c, int side, Poly& out) {
    const int a = axis, u = (a + 1) % 3, v = (a + 2) % 3;
    if (n == 0 || n > 64) return false;
    double h_max = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double h = (corners[i][a] - c) * side;
        if (!(h >= 0.0)) return false;
        h_max = std::max(h_max, h);
    }
    thread_local Poly shadow, next;
    std::array<glm::dvec2, 64> pts;
    bool first = true;
    for (const glm::dvec3& q : eyes) {
        const double hq = (q[a] - c) * side;
        if (!(hq > h_max)) return false;
        // The central projection from q onto the plane: y = p + (p - q) h_p / (h_q - h_p). A corner on the
        // plane (h_p = 0) is its own projection, exactly, so covers meeting along such a corner's line meet
        // exactly.
        for (size_t i = 0; i < n; ++i) {
            const glm::dvec3& p = corners[i];
            const double s = (p[a] - c) * side / (hq - (p[a] - c) * side);
            pts[i] = glm::dvec2(p[u] + (p[u] - q[u]) * s, p[v] + (p[v] - q[v]) * s);
        }
        convex_hull(pts.data(), n, shadow);
        if (shadow.size() < 3) return false;
        if (first) {
            out = shadow;
            first = false;
            continue;
        }
        for (size_t i = 0; i < shadow.size() && out.size() >= 3; ++i) {
            clip_line(out, shadow[i], shadow[(i + 1) % shadow.size()], false, next);
            out.swap(next);
        }
        if (sliver(out)) return false;
    }
    return !sliver(out);
}

void ShaftProver::add_umbrae(const Aabb& region, const Aabb& target, int axis, double c, glm::dvec2 y,
                             PlaneScratch& ps) const {
    const int a = axis, u = (a + 1) % 3, v = (a + 2) % 3;
    const double tol = kHideToleranceM;
    const int region_side = double(region.min[a]) > c ? 1 : -1;
    glm::dvec3 p;
    p[a] = c;
    p[u] = y.x;
    p[v] = y.y;
    const uint32_t n_boxes = uint32_t(boxes_.size()), n_flat = n_boxes + uint32_t(panels_.size());
    // A box (a panel: flat along `flat`) clipped to one side of the plane and shrunk by tol on every side
    // but its face on the plane; its umbra from the box with corners `eyes` on that side.
    const auto box_umbra = [&](const Aabb& b, int flat, int part_side,
                               const std::array<glm::dvec3, 8>& eyes) {
        // Clipped to the slab between the plane and the eyes' box (grown by tol, so strictly nearer).
        double near = part_side > 0 ? INFINITY : -INFINITY;
        for (const glm::dvec3& q : eyes) near = part_side > 0 ? std::min(near, q[a]) : std::max(near, q[a]);
        glm::dvec3 lo(b.min), hi(b.max);
        if (part_side > 0) {
            lo[a] = std::max(lo[a], c);
            hi[a] = std::min(hi[a], near - tol);
        } else {
            hi[a] = std::min(hi[a], c);
            lo[a] = std::max(lo[a], near + tol);
        }
        if (!(lo[a] <= hi[a])) return;
        for (int k = 0; k < 3; ++k) {
            if (k == flat) continue;
            if (!(k == a && lo[a] == c)) lo[k] += tol;
            if (!(k == a && hi[a] == c)) hi[k] -= tol;
            if (!(lo[k] <= hi[k])) return;
        }
        if (!(lo[a] <= hi[a])) return;
        // Only an occluder that hides the probed point from every eye corner is worth its umbra here.
        for (const glm::dvec3& q : eyes) {
            double t0 = 0.0, t1 = 1.0;
            for (int k = 0; k < 3 && t0 <= t1; ++k) {
                const double d = p[k] - q[k];
                if (d == 0.0) {
                    if (q[k] < lo[k] || q[k] > hi[k]) t1 = -1.0;
                    continue;
                }
                double e0 = (lo[k] - q[k]) / d, e1 = (hi[k] - q[k]) / d;
                if (e0 > e1) std::swap(e0, e1);
                t0 = std::max(t0, e0);
                t1 = std::min(t1, e1);
            }
            if (!(t0 <= t1)) return;
        }
        ps.corners.clear();
        for (int i = 0; i < 8; ++i)
            ps.corners.push_back(glm::dvec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
        if (umbra_on_plane(eyes, ps.corners.data(), 8, a, c, part_side, ps.shadow))
            ps.umbrae.push_back(ps.shadow);
    };
    const std::array<glm::dvec3, 8> rc = box_corners(region, tol), tc = box_corners(target, tol);
    // The lines stay in the bounds of the two boxes (which hold p): what the pass reads for a pair lies
    // there (pvs/reuse.h).
    Aabb both = region;
    both.extend(target);
    for (int from_region = 0; from_region < 2; ++from_region) {
        // The line from one box's centre through p, on until it leaves the bounds.
        const glm::dvec3 o(from_region ? region.center() : target.center());
        const glm::dvec3 step = p - o;
        double t_end = INFINITY;
        for (int k = 0; k < 3; ++k)
            if (step[k] != 0.0)
                t_end = std::min(
                    t_end, ((step[k] > 0.0 ? double(both.max[k]) : double(both.min[k])) - o[k]) / step[k]);
        if (!(t_end >= 1.0 && t_end < INFINITY)) continue;
        const glm::dvec3 d = step * t_end;
        const float len = float(glm::length(d));
        if (!(len > 0.0f)) continue;
        const glm::vec3 dir(d / double(len));
        ps.touches.clear();
        umbra_scene_->trace_until(glm::vec3(o), &dir, &len, 1, ps.touches);
        // Nearest first, ties by index: the occluders tried, and so the answer, do not depend on the order
        // Embree reports them in.
        std::sort(ps.touches.begin(), ps.touches.end(), [](const RayTouch& x, const RayTouch& y) {
            return x.t != y.t ? x.t < y.t : x.object < y.object;
        });
        for (const RayTouch& t : ps.touches) {
            const uint32_t k = t.object;
            if (ps.tried.size() >= kMaxUmbrae) return;
            if (std::find(ps.tried.begin(), ps.tried.end(), k) != ps.tried.end()) continue;
            ps.tried.push_back(k);
            if (k >= n_boxes) add_cap_slices(k - n_boxes, region, target, a, c, ps);
            if (k < n_flat) {
                const Aabb& b = k < n_boxes ? boxes_[k] : panels_[k - n_boxes];
                const int flat = k < n_boxes ? -1 : panel_axis_[k - n_boxes];
                if (flat == a && double(b.min[a]) == c) continue;  // in the plane: a cover of its own
                box_umbra(b, flat, region_side, rc);
                box_umbra(b, flat, -region_side, tc);
                continue;
            }
            // A slanted panel: segments crossing both faces of its slab inside the polygon (shrunk towards
            // its centroid so that every edge moves in by at least tol) meet its triangles.
            const SlantedPanel& sp = slanted_[k - n_flat];
            const size_t n = sp.corners.size();
            if (n < 3 || 2 * n > 64 || sp.edge_normal.size() != n || sp.edge_offset.size() != n) continue;
            glm::dvec3 g(0.0);
            for (const glm::dvec3& q : sp.corners) g += q;
            g /= double(n);
            double inner = INFINITY;
            for (size_t i = 0; i < n; ++i)
                inner = std::min(inner, glm::dot(sp.edge_normal[i], g) - sp.edge_offset[i]);
            if (!(inner > 2.0 * tol)) continue;
            const double shrink = tol / inner;
            ps.corners.clear();
            for (int f = -1; f <= 1; f += 2)
                for (const glm::dvec3& q : sp.corners) {
                    const glm::dvec3 in_plane = g + (q - g) * (1.0 - shrink);
                    const double height =
                        double(f) * sp.thickness - (glm::dot(sp.normal, in_plane) - sp.offset);
                    ps.corners.push_back(in_plane + sp.normal * height);
                }
            int part_side = 0;
            bool straddles = false;
            for (const glm::dvec3& q : ps.corners) {
                const int s = q[a] > c ? 1 : (q[a] < c ? -1 : 0);
                if (s == 0 || (part_side != 0 && s != part_side)) straddles = true;
                part_side = s;
            }
            if (straddles) continue;
            const std::array<glm::dvec3, 8>& eyes = part_side == region_side ? rc : tc;
            if (!umbra_on_plane(eyes, ps.corners.data(), n, a, c, part_side, ps.shadow)) continue;
            if (!umbra_on_plane(eyes, ps.corners.data() + n, n, a, c, part_side, ps.other)) continue;
            for (size_t i = 0; i < ps.other.size() && ps.shadow.size() >= 3; ++i) {
                clip_line(ps.shadow, ps.other[i], ps.other[(i + 1) % ps.other.size()], false, ps.clipped);
                ps.shadow.swap(ps.clipped);
            }
            if (!sliver(ps.shadow)) ps.umbrae.push_back(ps.shadow);
        }
    }
}

// A piece of the region (the bounds of its eye voxels' parts in a box, with an eye point) and a piece of
// the object (the bounds of its triangles' parts in a box, with a point on one of them). Voxel and triangle
// lists live in the scratch arenas.
struct ShaftProver::Pair {
    Aabb region;
    glm::ivec3 eyes_lo{0}, eyes_hi{0};  // the eye voxels of the piece: local indices of the ShaftRegion
    glm::vec3 from{0.0f};
    Aabb target;
    uint32_t tris_first = 0, tris_count = 0;
    glm::vec3 point{0.0f};
    int depth = 0;  // halvings from the whole region and object
};

struct ShaftProver::Scratch {
    std::vector<uint32_t> tri_arena;
    std::vector<Pair> stack;
    std::vector<glm::dvec3> poly, tmp;
    std::vector<RayTouch> touches;
    std::vector<glm::ivec3> run;
    // Per side (region, object), axis and direction, the planes of a cup's candidate faces.
    std::array<std::array<std::vector<float>, 6>, 2> cup_faces;
};

ShaftProver::ShaftProver(Context& ctx, const ShrunkOccluders& set, bool fusion, bool caps, bool cups,
                         bool flood)
    : panels_(set.panels), slanted_(set.slanted), solid_(set.solid), fusion_(fusion), cups_(cups) {
    if (flood) flood_ = std::make_unique<ShaftFlood>(set.panels, set.solid);
    std::array<std::vector<std::pair<float, uint32_t>>, 3> by_plane;
    for (uint32_t i = 0; i < panels_.size(); ++i) {
        const int a = panel_axis(panels_[i]);
        panel_axis_.push_back(a);
        if (a >= 0) by_plane[size_t(a)].emplace_back(panels_[i].min[a], i);
    }
    for (int a = 0; a < 3; ++a) {
        std::vector<std::pair<float, uint32_t>>& v = by_plane[size_t(a)];
        std::sort(v.begin(), v.end());
        const int u = (a + 1) % 3, w = (a + 2) % 3;
        for (size_t i = 0; i < v.size();) {
            Plane p{v[i].first, uint32_t(rects_.size()), 0, glm::dvec2(INFINITY), glm::dvec2(-INFINITY)};
            for (; i < v.size() && v[i].first == p.c; ++i) {
                const Aabb& b = panels_[v[i].second];
                rects_.push_back(Rect{b.min[u], b.max[u], b.min[w], b.max[w]});
                p.lo = glm::min(p.lo, glm::dvec2(b.min[u], b.min[w]));
                p.hi = glm::max(p.hi, glm::dvec2(b.max[u], b.max[w]));
                ++p.count;
            }
            planes_[a].push_back(p);
        }
    }
    if (!solid_.empty()) {
        // Each layer's bounds, row by row along x on all threads: a row adds its x range to its y and z
        // layers, and each of its voxels its y, z square to its x layer. Min and max merge in any order.
        const glm::ivec3 n = solid_.dims;
        const double h = solid_.voxel_size_m;
        const glm::dvec3 o(solid_.origin);
        for (int a = 0; a < 3; ++a) {
            layer_lo_[a].assign(size_t(n[a]), glm::dvec2(INFINITY));
            layer_hi_[a].assign(size_t(n[a]), glm::dvec2(-INFINITY));
        }
        const auto at = [&](int axis, int k) { return o[axis] + double(k) * h; };
#pragma omp parallel
        {
            std::array<std::vector<glm::dvec2>, 3> lo, hi;
            for (int a = 0; a < 3; ++a) {
                lo[size_t(a)].assign(size_t(n[a]), glm::dvec2(INFINITY));
                hi[size_t(a)].assign(size_t(n[a]), glm::dvec2(-INFINITY));
            }
#pragma omp for schedule(static)
            for (int z = 0; z < n.z; ++z) {
                for (int y = 0; y < n.y; ++y) {
                    const uint64_t first = (uint64_t(z) * uint64_t(n.y) + uint64_t(y)) * uint64_t(n.x);
                    const uint64_t end = first + uint64_t(n.x);
                    int x_min = -1, x_max = -1;
                    for (uint64_t w = first >> 6; w <= (end - 1) >> 6; ++w) {
                        uint64_t bits = solid_.bits[w];
                        if (w == first >> 6) bits &= ~uint64_t(0) << (first & 63);
                        if (w == (end - 1) >> 6) bits &= ~uint64_t(0) >> (63 - ((end - 1) & 63));
                        for (; bits != 0; bits &= bits - 1) {
                            const int x = int(w * 64 + uint64_t(std::countr_zero(bits)) - first);
                            if (x_min < 0) x_min = x;
                            x_max = x;
                            lo[0][size_t(x)] = glm::min(lo[0][size_t(x)], glm::dvec2(at(1, y), at(2, z)));
                            hi[0][size_t(x)] = glm::max(hi[0][size_t(x)], glm::dvec2(at(1, y + 1), at(2, z + 1)));
                        }
                    }
                    if (x_min < 0) continue;
                    // Layer y: (z, x); layer z: (x, y).
                    lo[1][size_t(y)] = glm::min(lo[1][size_t(y)], glm::dvec2(at(2, z), at(0, x_min)));
                    hi[1][size_t(y)] = glm::max(hi[1][size_t(y)], glm::dvec2(at(2, z + 1), at(0, x_max + 1)));
                    lo[2][size_t(z)] = glm::min(lo[2][size_t(z)], glm::dvec2(at(0, x_min), at(1, y)));
                    hi[2][size_t(z)] = glm::max(hi[2][size_t(z)], glm::dvec2(at(0, x_max + 1), at(1, y + 1)));
                }
            }
#pragma omp critical(shaft_layers)
            for (int a = 0; a < 3; ++a)
                for (size_t k = 0; k < size_t(n[a]); ++k) {
                    layer_lo_[a][k] = glm::min(layer_lo_[a][k], lo[size_t(a)][k]);
                    layer_hi_[a][k] = glm::max(layer_hi_[a][k], hi[size_t(a)][k]);
                }
        }
    }
    Context quiet(Context::Options{LogLevel::kWarning, true, nullptr});
    scene_ =
        std::make_unique<RayScene>(quiet, box_world({}, panels_, false, slanted_), BuildQuality::kMedium, 1);
    if (fusion_) {
        if (!set.boxes.empty()) boxes_ = set.boxes.front();
        umbra_scene_ = std::make_unique<RayScene>(quiet, box_world(boxes_, panels_, false, slanted_),
                                                  BuildQuality::kMedium, 1);
    }
    if (caps) {
        // Every panel and every slanted panel of no thickness is an opaque polygon (its triangles tile it).
        cap_polygons_ = cap_polygons(panels_, slanted_);
        caps_ = build_caps(cap_polygons_);
    }
    size_t n_caps = 0;
    for (const ConvexCap& c : caps_) n_caps += c.empty() ? 0 : 1;
    ctx.debug(
        fmt::format("shaft pass: {} panels in {} planes, {} slanted panels, {} convex caps, {} occluders "
                    "of the flood",
                    panels_.size(), planes_[0].size() + planes_[1].size() + planes_[2].size(),
                    slanted_.size(), n_caps, flood_ ? flood_->occluders() : 0));
}

ShaftProver::~ShaftProver() = default;

bool ShaftProver::plane_covers(const Aabb& region, const Aabb& target, int axis, float c, PlaneMiss* miss,
                               uint64_t* umbrae) const {
    return cover(region, target, axis, c, fusion_, miss, umbrae);
}

bool ShaftProver::cover(const Aabb& region, const Aabb& target, int axis, float c, bool fuse, PlaneMiss* miss,
                        uint64_t* umbrae, const Window* window) const {
    const int a = axis, u = (a + 1) % 3, v = (a + 2) % 3;
    const double cd = c, tol = kHideToleranceM;
    // In a window (a face of a cup), the target may reach the plane: the region lies farther from it, so the
    // hull of the corner crossings still holds every crossing (docs/ALGORITHMS.md#cups).
    const double near = window ? kCupMarginTolerances * tol : tol, far = window ? 0.0 : tol;
    const bool below = double(region.max[a]) < cd - near && double(target.min[a]) >= cd + far &&
                       (window || double(target.min[a]) > cd + far);
    const bool above = double(region.min[a]) > cd + near && double(target.max[a]) <= cd - far &&
                       (window || double(target.max[a]) < cd - far);
    if (!below && !above) return false;
    // Where the 64 corner segments of the boxes grown by tol cross the plane: their hull holds where every
    // segment from region to target crosses it (docs/ALGORITHMS.md#single-occluder) grown by tol on both
    // axes (a segment moved by e in the plane, |e| <= tol, runs between the grown boxes).
    thread_local PlaneScratch ps;
    ps.umbrae.clear();
    ps.tried.clear();
    struct Count {
        const PlaneScratch& ps;
        uint64_t* to;
        ~Count() {
            if (to) *to += ps.umbrae.size();
        }
    } count{ps, umbrae};
    std::array<glm::dvec2, 64> pts;
    const std::array<glm::dvec3, 8> rc = box_corners(region, tol), tc = box_corners(target, tol);
    size_t n_pts = 0;
    for (const glm::dvec3& q : rc)
        for (const glm::dvec3& x : tc) {
            const double t = (cd - q[a]) / (x[a] - q[a]);
            pts[n_pts++] = glm::dvec2(q[u] + t * (x[u] - q[u]), q[v] + t * (x[v] - q[v]));
        }
    glm::dvec2 lo = pts[0], hi = pts[0];
    for (size_t i = 1; i < n_pts; ++i) {
        lo = glm::min(lo, pts[i]);
        hi = glm::max(hi, pts[i]);
    }
    // Only the crossings inside the window count; none there: no segment leaves the cup by this face.
    const auto in_window = [&](glm::dvec2 p) {
        return !window ||
               (p.x >= window->lo.x && p.y >= window->lo.y && p.x <= window->hi.x && p.y <= window->hi.y);
    };
    if (window) {
        lo = glm::max(lo, window->lo);
        hi = glm::min(hi, window->hi);
        if (!(lo.x < hi.x && lo.y < hi.y)) return true;
    }
    // The voxel layers holding the plane (both, on a voxel side), or none outside the grid.
    int l0 = -1, l1 = -2;
    if (!solid_.empty()) {
        const double rel = (cd - double(solid_.origin[a])) / double(solid_.voxel_size_m);
        const double fl = std::floor(rel);
        l0 = l1 = int(fl);
        if (rel - fl < kVoxelSlack) l0 = l1 - 1;
        if (fl + 1.0 - rel < kVoxelSlack) l1 = l0 + 1;
        if (l0 < 0 || l1 >= solid_.dims[a]) l0 = -1, l1 = -2;
    }
    // A crossing beyond the bounds of the plane's panels and of its layers' solid is not covered.
    const std::vector<Plane>& planes = planes_[a];
    const auto it = std::lower_bound(planes.begin(), planes.end(), c,
                                     [](const Plane& p, float value) { return p.c < value; });
    const bool has_panels = it != planes.end() && it->c == c;
    if (!fuse) {
        glm::dvec2 reach_lo(INFINITY), reach_hi(-INFINITY);
        if (has_panels) {
            reach_lo = it->lo;
            reach_hi = it->hi;
        }
        glm::dvec2 solid_lo(-INFINITY), solid_hi(INFINITY);  // what every layer holds
        for (int l = l0; l <= l1; ++l) {
            solid_lo = glm::max(solid_lo, layer_lo_[a][size_t(l)]);
            solid_hi = glm::min(solid_hi, layer_hi_[a][size_t(l)]);
        }
        if (l0 <= l1 && solid_lo.x <= solid_hi.x && solid_lo.y <= solid_hi.y) {
            reach_lo = glm::min(reach_lo, solid_lo);
            reach_hi = glm::max(reach_hi, solid_hi);
        }
        if (!(lo.x >= reach_lo.x && lo.y >= reach_lo.y && hi.x <= reach_hi.x && hi.y <= reach_hi.y)) {
            if (miss) *miss = PlaneMiss{a, c, lo, hi, lo, hi};
            return false;
        }
    }
    // Every corner crossing is a point of the crossing: one left open settles it (cheaper than the cover).
    {
        ps.near_rects.clear();
        ps.open.clear();
        if (has_panels)
            for (uint32_t r = it->first; r < it->first + it->count; ++r) {
                const Rect& rect = rects_[r];
                if (!(rect.u0 > hi.x || rect.u1 < lo.x || rect.v0 > hi.y || rect.v1 < lo.y))
                    ps.near_rects.push_back(r);
            }
        const double h = solid_.voxel_size_m;
        const glm::dvec3 o(solid_.origin);
        glm::dvec2 open_lo(INFINITY), open_hi(-INFINITY);
        for (size_t i = 0; i < n_pts; ++i) {
            const glm::dvec2 p = pts[i];
            bool in = !in_window(p);
            for (uint32_t r : ps.near_rects) {
                if (in) break;
                const Rect& rect = rects_[r];
                if (p.x >= rect.u0 && p.x <= rect.u1 && p.y >= rect.v0 && p.y <= rect.v1) {
                    in = true;
                    break;
                }
            }
            if (!in && l0 <= l1) {
                const int64_t iu = int64_t(std::floor((p.x - o[u]) / h)),
                              iv = int64_t(std::floor((p.y - o[v]) / h));
                if (iu >= 0 && iv >= 0 && iu < solid_.dims[u] && iv < solid_.dims[v]) {
                    in = true;
                    for (int l = l0; l <= l1 && in; ++l) {
                        glm::i64vec3 idx;
                        idx[a] = l;
                        idx[u] = iu;
                        idx[v] = iv;
                        in = solid_.get(uint64_t(idx.x) +
                                        uint64_t(solid_.dims.x) *
                                            (uint64_t(idx.y) + uint64_t(solid_.dims.y) * uint64_t(idx.z)));
                    }
                }
            }
            if (!in) {
                open_lo = glm::min(open_lo, p);
                open_hi = glm::max(open_hi, p);
                if (fuse) ps.open.push_back(p);
            }
        }
        // With fusion, an open corner crossing may lie in the umbra of an occluder of another plane: search
        // through the first open crossing and the one farthest from it, then every open one must be in one.
        if (fuse && !ps.open.empty()) {
            size_t far = 0;
            double far_d = -1.0;
            for (size_t i = 0; i < ps.open.size(); ++i) {
                const double d = glm::length(ps.open[i] - ps.open[0]);
                if (d > far_d) far_d = d, far = i;
            }
            const size_t probes[kUmbraProbes] = {0, far};
            for (size_t i = 0; i < kUmbraProbes && (i == 0 || probes[i] != probes[0]); ++i)
                add_umbrae(region, target, a, cd, ps.open[probes[i]], ps);
            open_lo = glm::dvec2(INFINITY);
            open_hi = glm::dvec2(-INFINITY);
            for (const glm::dvec2& p : ps.open) {
                bool in = false;
                for (const Poly& um : ps.umbrae)
                    if (inside(um, p)) {
                        in = true;
                        break;
                    }
                if (!in) {
                    open_lo = glm::min(open_lo, p);
                    open_hi = glm::max(open_hi, p);
                }
            }
        }
        if (open_lo.x <= open_hi.x) {
            if (miss) *miss = PlaneMiss{a, c, lo, hi, open_lo, open_hi};
            return false;
        }
    }
    if (ps.pieces.empty()) ps.pieces.resize(1);
    convex_hull(pts.data(), n_pts, ps.pieces[0]);
    // Pieces without area are dropped as covered below (6.11.1): that needs a crossing with area.
    if (ps.pieces[0].size() < 3) return false;
    if (window) {
        // The crossing less what lies outside the window; a window with no area of it is not crossed.
        for (int k = 0; k < 2; ++k) {
            clip(ps.pieces[0], k, window->lo[k], false, ps.part);
            clip(ps.part, k, window->hi[k], true, ps.pieces[0]);
        }
        if (degenerate(ps.pieces[0])) return true;
    }
    size_t n_pieces = 1;
    // Less the panels of the plane.
    if (has_panels) {
        for (size_t nr = 0; nr < ps.near_rects.size() && n_pieces > 0; ++nr) {
            const Rect& rect = rects_[ps.near_rects[nr]];
            size_t n_next = 0;
            for (size_t i = 0; i < n_pieces; ++i) {
                // The piece outside the rectangle, as up to four convex parts: left, right, below, above.
                ps.rest = ps.pieces[i];
                const std::array<std::pair<int, double>, 4> sides{
                    {{0, rect.u0}, {0, rect.u1}, {1, rect.v0}, {1, rect.v1}}};
                for (size_t s = 0; s < 4 && !ps.rest.empty(); ++s) {
                    const bool low_side = s % 2 == 0;
                    clip(ps.rest, sides[s].first, sides[s].second, low_side, ps.part);
                    if (!degenerate(ps.part)) {
                        if (ps.next.size() <= n_next) ps.next.resize(n_next + 1);
                        ps.next[n_next++] = ps.part;
                    }
                    clip(ps.rest, sides[s].first, sides[s].second, !low_side, ps.part);
                    ps.rest.swap(ps.part);
                }
            }
            ps.pieces.swap(ps.next);
            n_pieces = n_next;
            if (n_pieces > kMaxPieces) break;
        }
    }
    // Less the umbrae of other planes' occluders: those found through the open corners, then those through
    // the middle of what is left.
    if (fuse && n_pieces > 0) {
        const auto subtract = [&](const Poly& um) {
            size_t n_next = 0;
            for (size_t i = 0; i < n_pieces; ++i) {
                ps.rest = ps.pieces[i];
                for (size_t e = 0; e < um.size() && ps.rest.size() >= 3; ++e) {
                    const glm::dvec2 e0 = um[e], e1 = um[(e + 1) % um.size()];
                    clip_line(ps.rest, e0, e1, true, ps.part);
                    if (!sliver(ps.part)) {
                        if (ps.next.size() <= n_next) ps.next.resize(n_next + 1);
                        ps.next[n_next++] = ps.part;
                    }
                    clip_line(ps.rest, e0, e1, false, ps.part);
                    ps.rest.swap(ps.part);
                }
            }
            ps.pieces.swap(ps.next);
            n_pieces = n_next;
        };
        size_t done = 0;
        for (int round = 0; round <= kUmbraRounds && n_pieces > 0 && n_pieces <= kMaxPieces; ++round) {
            if (round > 0) {
                glm::dvec2 mid(0.0);
                for (const glm::dvec2& q : ps.pieces[0]) mid += q;
                add_umbrae(region, target, a, cd, mid / double(ps.pieces[0].size()), ps);
            }
            if (done == ps.umbrae.size()) {
                if (round > 0) break;
                continue;
            }
            for (; done < ps.umbrae.size() && n_pieces > 0 && n_pieces <= kMaxPieces; ++done)
                subtract(ps.umbrae[done]);
        }
    }
    if (n_pieces == 0) return true;
    if (miss) {
        *miss = PlaneMiss{a, c, lo, hi, ps.pieces[0][0], ps.pieces[0][0]};
        for (size_t i = 0; i < n_pieces; ++i)
            for (const glm::dvec2& p : ps.pieces[i]) {
                miss->open_lo = glm::min(miss->open_lo, p);
                miss->open_hi = glm::max(miss->open_hi, p);
            }
    }
    if (n_pieces > kMaxPieces) return false;
    // The rest must lie in the interior of the proven solid: every voxel of the layer (both layers, on a
    // voxel side) whose closed square meets a piece is solid.
    if (l0 > l1) return false;
    const double h = solid_.voxel_size_m;
    const glm::dvec3 o(solid_.origin);
    Poly& band = ps.band;
    Poly& part = ps.part;
    for (size_t pi = 0; pi < n_pieces; ++pi) {
        const Poly& piece = ps.pieces[pi];
        glm::dvec2 plo = piece[0], phi = piece[0];
        for (const glm::dvec2& p : piece) {
            plo = glm::min(plo, p);
            phi = glm::max(phi, p);
        }
        const int64_t j0 = int64_t(std::floor((plo.y - o[v]) / h - kVoxelSlack));
        const int64_t j1 = int64_t(std::floor((phi.y - o[v]) / h + kVoxelSlack));
        if (j0 < 0 || j1 >= solid_.dims[v]) return false;
        for (int64_t j = j0; j <= j1; ++j) {
            clip(piece, 1, o[v] + double(j) * h - kVoxelSlack * h, false, part);
            clip(part, 1, o[v] + double(j + 1) * h + kVoxelSlack * h, true, band);
            if (band.empty()) continue;
            double umin = band[0].x, umax = band[0].x;
            for (const glm::dvec2& p : band) {
                umin = std::min(umin, p.x);
                umax = std::max(umax, p.x);
            }
            const int64_t i0 = int64_t(std::floor((umin - o[u]) / h - kVoxelSlack));
            const int64_t i1 = int64_t(std::floor((umax - o[u]) / h + kVoxelSlack));
            if (i0 < 0 || i1 >= solid_.dims[u]) return false;
            for (int64_t i = i0; i <= i1; ++i)
                for (int l = l0; l <= l1; ++l) {
                    glm::i64vec3 idx;
                    idx[a] = l;
                    idx[u] = i;
                    idx[v] = j;
                    if (!solid_.get(uint64_t(idx.x) +
                                    uint64_t(solid_.dims.x) *
                                        (uint64_t(idx.y) + uint64_t(solid_.dims.y) * uint64_t(idx.z))))
                        return false;
                }
        }
    }
    return true;
}

bool ShaftProver::cap_covers(uint32_t polygon, const Aabb& region, const Aabb& target) const {
    if (caps_.empty()) return false;
    const CapPolygon& p = cap_polygons_[polygon];
    if (p.corners.empty()) return false;
    // Seen from the region: the cap on the region's side; seen from the target: the cap on the target's.
    const auto cap_seen_from = [&](const Aabb& box) -> const ConvexCap& {
        const double s = glm::dot(p.normal, glm::dvec3(box.center())) - p.offset;
        return caps_[2 * size_t(polygon) + (s >= 0.0 ? 0 : 1)];
    };
    return cap_hides(cap_seen_from(region), region, target) || cap_hides(cap_seen_from(target), target, region);
}

bool ShaftProver::try_pair(const Pair& pair, glm::vec3 from, glm::vec3 to, bool& line_blocked,
                           PlaneMiss& miss, Scratch& sc, ShaftFigures& figures) const {
    line_blocked = false;
    miss = PlaneMiss{};
    double best = INFINITY;
    const glm::vec3 d = to - from;
    const float len = glm::length(d);
    if (!(len > 0.0f)) return false;
    std::array<std::pair<int, float>, 16> tried;
    size_t n_tried = 0;
    const auto try_plane = [&](int a, float c) {
        for (size_t i = 0; i < n_tried; ++i)
            if (tried[i].first == a && tried[i].second == c) return false;
        if (n_tried < tried.size()) tried[n_tried++] = {a, c};
        PlaneMiss m;
        if (cover(pair.region, pair.target, a, c, false, &m)) return true;
        if (m.axis >= 0) {
            const glm::dvec2 extent = glm::max(m.hi - m.lo, 1e-12), open = m.open_hi - m.open_lo;
            const double narrow = std::min(open.x / extent.x, open.y / extent.y);
            if (narrow < best) {
                best = narrow;
                miss = m;
            }
        }
        return false;
    };
    // The panels and slanted panels the line crosses.
    const glm::vec3 dir = d / len;
    sc.touches.clear();
    scene_->trace_until(from, &dir, &len, 1, sc.touches);
    std::sort(sc.touches.begin(), sc.touches.end(),
              [](const RayTouch& x, const RayTouch& y) { return x.t < y.t; });
    const uint32_t n_panels = uint32_t(panels_.size());
    for (const RayTouch& t : sc.touches) {
        line_blocked = true;
        if (t.object < n_panels) {
            const int a = panel_axis_[t.object];
            if (a >= 0 && try_plane(a, panels_[t.object].min[a])) return true;
        } else if (slanted_hides(pair.region, pair.target, slanted_[t.object - n_panels])) {
            return true;
        }
    }
    // The runs of proven solid the line crosses: a plane across the middle voxel of each, on the axes the
    // line runs along most first.
    std::array<int, 3> axes{0, 1, 2};
    std::sort(axes.begin(), axes.end(), [&](int x, int y) { return std::abs(d[x]) > std::abs(d[y]); });
    const double h = solid_.voxel_size_m;
    const glm::dvec3 o(solid_.origin);
    sc.run.clear();
    const auto end_run = [&]() {
        if (sc.run.empty()) return false;
        const glm::ivec3 mid = sc.run[sc.run.size() / 2];
        sc.run.clear();
        for (int a : axes)
            if (d[a] != 0.0f && try_plane(a, float(o[a] + (double(mid[a]) + 0.5) * h))) return true;
        return false;
    };
    bool covered = false;
    walk_voxels(solid_, from, to, [&](const glm::ivec3& cell, bool in_solid) {
        if (in_solid) {
            line_blocked = true;
            sc.run.push_back(cell);
            return false;
        }
        covered = end_run();
        return covered;
    });
    if (covered || end_run()) return true;
    // The convex caps of the first panels the line met (docs/ALGORITHMS.md#convex-caps).
    if (!caps_.empty()) {
        uint32_t last = UINT32_MAX;
        size_t tried_caps = 0;
        for (const RayTouch& t : sc.touches) {
            if (t.object == last) continue;
            last = t.object;
            if (tried_caps++ >= kCapTouches) break;
            if (cap_covers(t.object, pair.region, pair.target)) {
                ++figures.capped;
                return true;
            }
        }
    }
    // No plane's own occluders cover the pair: the first planes the line met, with the umbrae of the
    // occluders of other planes (cheap planes first: most pairs need no umbra).
    if (fusion_)
        for (size_t i = 0; i < std::min(n_tried, kFusedPlanes); ++i)
            if (cover(pair.region, pair.target, tried[i].first, tried[i].second, true, nullptr, &figures.umbrae))
                return true;
    return false;
}

bool ShaftProver::cup_covers(const Pair& pair, Scratch& sc, ShaftFigures& figures) const {
    const double tol = kHideToleranceM, margin = kCupMarginTolerances * tol;
    // The candidate faces of a cup around each piece (side 0: the region piece, 1: the object piece): the
    // first occluder each of a few lines between the pieces meets from that piece's end, by axis and
    // direction (the side of the piece the face bounds).
    std::array<std::array<std::vector<float>, 6>, 2>& faces = sc.cup_faces;
    for (auto& side_faces : faces)
        for (auto& f : side_faces) f.clear();
    const auto add_face = [&](int side, int a, float c) {
        const Aabb& inner = side == 0 ? pair.region : pair.target;
        const double cd = c;
        int dir;
        if (double(inner.max[a]) < cd - margin) {
            dir = 1;
        } else if (double(inner.min[a]) > cd + margin) {
            dir = 0;
        } else {
            return;
        }
        std::vector<float>& f = faces[size_t(side)][size_t(2 * a + dir)];
        if (std::find(f.begin(), f.end(), c) == f.end()) f.push_back(c);
    };
    const double h = solid_.voxel_size_m;
    const glm::dvec3 o(solid_.origin);
    // The first run of proven solid from `from` towards `to`, within `reach` metres: a plane across the
    // middle of its first voxel, on the axis the line entered it by.
    const auto first_solid = [&](int side, glm::vec3 from, glm::vec3 to, float reach) {
        const float len = glm::length(to - from);
        if (!(len > 0.0f)) return;
        const glm::vec3 end = reach < len ? from + (to - from) * (reach / len) : to;
        glm::ivec3 prev(0);
        bool have_prev = false;
        walk_voxels(solid_, from, end, [&](const glm::ivec3& cell, bool in_solid) {
            if (in_solid) {
                if (have_prev)
                    for (int a = 0; a < 3; ++a)
                        if (cell[a] != prev[a]) add_face(side, a, float(o[a] + (double(cell[a]) + 0.5) * h));
                return true;
            }
            prev = cell;
            have_prev = true;
            return false;
        });
    };
    // Each line from a point of the region piece to a point of the object piece: its first axis panel from
    // either end, and the first solid from either end, looked for no farther than that panel and two voxels.
    const auto line = [&](glm::vec3 from, glm::vec3 to) {
        const glm::vec3 d = to - from;
        const float len = glm::length(d);
        if (!(len > 0.0f)) return;
        const glm::vec3 dir = d / len;
        sc.touches.clear();
        scene_->trace_until(from, &dir, &len, 1, sc.touches);
        const RayTouch *first = nullptr, *last = nullptr;
        for (const RayTouch& t : sc.touches)
            if (t.object < panels_.size() && panel_axis_[t.object] >= 0) {
                if (!first || t.t < first->t) first = &t;
                if (!last || t.t > last->t) last = &t;
            }
        const float slack = float(2.0 * h);
        if (first)
            add_face(0, panel_axis_[first->object], panels_[first->object].min[panel_axis_[first->object]]);
        if (last)
            add_face(1, panel_axis_[last->object], panels_[last->object].min[panel_axis_[last->object]]);
        first_solid(0, from, to, first ? first->t + slack : len);
        first_solid(1, to, from, last ? len - last->t + slack : len);
    };
    line(pair.from, pair.point);
    for (const glm::dvec3& x : box_corners(pair.target, 0.0))
        line(pair.from, glm::mix(glm::vec3(x), pair.target.center(), kCupCornerPull));
    for (const glm::dvec3& q : box_corners(pair.region, 0.0))
        line(glm::mix(glm::vec3(q), pair.region.center(), kCupCornerPull), pair.point);

    for (int side = 0; side < 2; ++side) {
        // The cup holds `inner`; the segments leave it towards `outer`.
        const Aabb& inner = side == 0 ? pair.region : pair.target;
        const Aabb& outer = side == 0 ? pair.target : pair.region;
        std::array<std::vector<float>, 6>& cand = faces[size_t(side)];
        for (int g = 0; g < 6; ++g) {
            const double base = g % 2 ? double(inner.max[g / 2]) : double(inner.min[g / 2]);
            std::sort(cand[size_t(g)].begin(), cand[size_t(g)].end(),
                      [&](float x, float y) { return std::abs(x - base) < std::abs(y - base); });
        }
        // Nearest faces first; the first face whose window is not covered gives way to the next one out (an
        // occluder in front of a wall), or to none.
        std::array<size_t, 6> choice{};
        for (int round = 0; round < kCupRounds; ++round) {
            glm::dvec3 lo(-INFINITY), hi(INFINITY);
            for (int g = 0; g < 6; ++g)
                if (choice[size_t(g)] < cand[size_t(g)].size()) {
                    const double c = cand[size_t(g)][choice[size_t(g)]];
                    (g % 2 ? hi : lo)[g / 2] = c;
                }
            // The outer piece must lie outside the cup, clear of it.
            bool outside = false;
            for (int a = 0; a < 3; ++a)
                outside =
                    outside || double(outer.max[a]) < lo[a] - margin || double(outer.min[a]) > hi[a] + margin;
            if (!outside) break;
            // Each face the outer piece reaches beyond: the plane's own covers first (cheap), then with the
            // umbrae of other planes' occluders where those fall short.
            bool all = true;
            std::array<bool, 6> open{};
            for (int fuse = 0; fuse < (fusion_ ? 2 : 1); ++fuse)
                for (int g = 0; g < 6; ++g) {
                    if (choice[size_t(g)] >= cand[size_t(g)].size() || (fuse == 1 && !open[size_t(g)]))
                        continue;
                    const int a = g / 2, u = (a + 1) % 3, v = (a + 2) % 3;
                    const float c = cand[size_t(g)][choice[size_t(g)]];
                    // The segments leaving by this face end in the part of the outer piece beyond its plane.
                    Aabb beyond = outer;
                    if (g % 2) {
                        if (double(outer.max[a]) < double(c)) continue;
                        beyond.min[a] = std::max(beyond.min[a], c);
                    } else {
                        if (double(outer.min[a]) > double(c)) continue;
                        beyond.max[a] = std::min(beyond.max[a], c);
                    }
                    const Window w{glm::dvec2(lo[u], lo[v]), glm::dvec2(hi[u], hi[v])};
                    open[size_t(g)] = !cover(inner, beyond, a, c, fuse == 1, nullptr, &figures.umbrae, &w);
                }
            bool moved = false;
            for (int g = 0; g < 6; ++g)
                if (open[size_t(g)]) {
                    all = false;
                    ++choice[size_t(g)];
                    moved = true;
                }
            if (all) return true;
            if (!moved) break;
        }
    }
    return false;
}

void ShaftProver::add_cap_slices(uint32_t polygon, const Aabb& region, const Aabb& target, int axis, double c,
                                 PlaneScratch& ps) const {
    if (caps_.empty()) return;
    const CapPolygon& p = cap_polygons_[polygon];
    if (p.corners.empty()) return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Aabb both = region;
    both.extend(target);
    const glm::dvec2 lo(both.min[u], both.min[v]), hi(both.max[u], both.max[v]);
    for (const Aabb* box : {&region, &target}) {
        // The cap on the side of the box's centre, if it guards the whole box (docs/ALGORITHMS.md#convex-caps).
        const double s = glm::dot(p.normal, glm::dvec3(box->center())) - p.offset;
        const ConvexCap& cap = caps_[2 * size_t(polygon) + (s >= 0.0 ? 0 : 1)];
        if (cap.empty() || !cap_guards(cap, *box)) continue;
        cap_slice(cap, axis, c, lo, hi, ps.shadow, ps.clipped);
        if (!ps.shadow.empty() && !sliver(ps.shadow)) ps.umbrae.push_back(ps.shadow);
    }
}

ShaftRegion shaft_region(const VoxelMask& eyes, const Aabb& region) {
    ShaftRegion out;
    out.box = region;
    if (eyes.empty() || region.is_empty()) return out;
    const float h = eyes.voxel_size_m;
    glm::ivec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::clamp(int(std::floor((region.min[a] - eyes.origin[a]) / h)), 0, eyes.dims[a]);
        hi[a] = std::clamp(int(std::ceil((region.max[a] - eyes.origin[a]) / h)), lo[a], eyes.dims[a]);
    }
    out.base = lo;
    out.n = hi - lo;
    const glm::ivec3 n = out.n;
    out.sum.assign(size_t(n.x + 1) * size_t(n.y + 1) * size_t(n.z + 1), 0);
    const auto at = [&](int x, int y, int z) -> uint32_t& {
        return out.sum[size_t(x) + size_t(n.x + 1) * (size_t(y) + size_t(n.y + 1) * size_t(z))];
    };
    for (int z = 1; z <= n.z; ++z)
        for (int y = 1; y <= n.y; ++y)
            for (int x = 1; x <= n.x; ++x) {
                const glm::ivec3 g = lo + glm::ivec3(x - 1, y - 1, z - 1);
                const uint64_t i =
                    uint64_t(g.x) +
                    uint64_t(eyes.dims.x) * (uint64_t(g.y) + uint64_t(eyes.dims.y) * uint64_t(g.z));
                at(x, y, z) = (eyes.get(i) ? 1u : 0u) + at(x - 1, y, z) + at(x, y - 1, z) + at(x, y, z - 1) -
                              at(x - 1, y - 1, z) - at(x - 1, y, z - 1) - at(x, y - 1, z - 1) +
                              at(x - 1, y - 1, z - 1);
            }
    return out;
}

bool ShaftProver::meets_occluder(glm::vec3 from, glm::vec3 to, Scratch& sc) const {
    const glm::vec3 d = to - from;
    const float len = glm::length(d);
    if (!(len > 0.0f)) return true;
    const glm::vec3 dir = d / len;
    uint8_t touched = 0;
    scene_->touches_any(
        from, &dir, &len, 1, [](void*, uint32_t, uint32_t) { return true; }, nullptr, &touched);
    if (touched) return true;
    bool solid = false;
    walk_voxels(solid_, from, to, [&](const glm::ivec3&, bool in_solid) {
        solid = in_solid;
        return in_solid;
    });
    return solid;
}

bool ShaftProver::hides(const World& world, const VoxelMask& eyes, const ShaftRegion& region, uint32_t object,
                        int budget, ShaftFigures& figures) const {
    ++figures.pairs;
    const WorldObject& obj = world.objects[object];
    if (region.box.is_empty() || obj.bounds.is_empty() || obj.triangle_count == 0 || budget <= 0)
        return false;
    thread_local Scratch sc;
    sc.tri_arena.clear();
    sc.stack.clear();
    const bool voxels = !region.sum.empty();
    const float h = eyes.voxel_size_m;
    // The box of voxel local index i.
    const auto voxel_box = [&](glm::ivec3 i) {
        const glm::vec3 c(region.base + i);
        return Aabb::of(eyes.origin + c * h, eyes.origin + (c + 1.0f) * h);
    };
    // A piece of the region: the eye voxels of [lo, hi) meeting `box` with volume, their index box tightened
    // to them, the bounds of their parts in the box and an eye point (in the part of the eye voxel found by
    // halving towards the box's centre).
    const auto eyes_in = [&](glm::ivec3 lo, glm::ivec3 hi, const Aabb& box, Pair& out) {
        for (int k = 0; k < 3; ++k) {
            const double o = double(eyes.origin[k]) + double(region.base[k]) * h;
            lo[k] = std::max(lo[k], int(std::floor((double(box.min[k]) - o) / h - kVoxelSlack)));
            hi[k] = std::min(hi[k], int(std::ceil((double(box.max[k]) - o) / h + kVoxelSlack)));
        }
        if (region.count(lo, hi) == 0) return false;
        for (int k = 0; k < 3; ++k) {
            glm::ivec3 slab_hi = hi;
            for (;;) {
                slab_hi[k] = lo[k] + 1;
                if (region.count(lo, slab_hi) > 0) break;
                ++lo[k];
            }
            glm::ivec3 slab_lo = lo;
            for (;;) {
                slab_lo[k] = hi[k] - 1;
                if (region.count(slab_lo, hi) > 0) break;
                --hi[k];
            }
        }
        out.eyes_lo = lo;
        out.eyes_hi = hi;
        out.region = Aabb::of(glm::max(voxel_box(lo).min, box.min), glm::min(voxel_box(hi - 1).max, box.max));
        const glm::vec3 centre = out.region.center();
        glm::ivec3 a = lo, b = hi;
        while (b.x - a.x > 1 || b.y - a.y > 1 || b.z - a.z > 1) {
            const glm::ivec3 s = b - a;
            const int k = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
            const int mid = (a[k] + b[k]) / 2;
            glm::ivec3 lo_hi = b, hi_lo = a;
            lo_hi[k] = mid;
            hi_lo[k] = mid;
            const bool centre_low = centre[k] < voxel_box(hi_lo).min[k];
            const bool low_has = region.count(a, lo_hi) > 0;
            if (centre_low ? low_has : region.count(hi_lo, b) == 0) {
                b = lo_hi;
            } else {
                a = hi_lo;
            }
        }
        const Aabb vb = voxel_box(a);
        out.from = Aabb::of(glm::max(vb.min, out.region.min), glm::min(vb.max, out.region.max)).center();
        return true;
    };
    // A random eye voxel of the piece: halving, each half chosen by its share of the eye voxels.
    const auto random_eye_voxel = [&](const Pair& p, Rng& rng) {
        glm::ivec3 a = p.eyes_lo, b = p.eyes_hi;
        uint32_t pick = rng.below(region.count(a, b));
        while (b.x - a.x > 1 || b.y - a.y > 1 || b.z - a.z > 1) {
            const glm::ivec3 s = b - a;
            const int k = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
            glm::ivec3 lo_hi = b, hi_lo = a;
            lo_hi[k] = hi_lo[k] = (a[k] + b[k]) / 2;
            const uint32_t low = region.count(a, lo_hi);
            if (pick < low) {
                b = lo_hi;
            } else {
                pick -= low;
                a = hi_lo;
            }
        }
        return voxel_box(a);
    };
    // The part of the object in `box`: its triangles with a part there (appended to the arena), their parts'
    // bounds (rounded out to float, then clipped to the box) and a point on the first part.
    const auto tris_in = [&](uint32_t first, uint32_t count, const Aabb& box, Pair& out) {
        out.tris_first = uint32_t(sc.tri_arena.size());
        out.target = Aabb{};
        for (uint32_t k = first; k < first + count; ++k) {
            const uint32_t t = sc.tri_arena[k];
            const Triangle& tri = world.triangles[t];
            clip_triangle(glm::dvec3(world.positions[tri.v[0]]), glm::dvec3(world.positions[tri.v[1]]),
                          glm::dvec3(world.positions[tri.v[2]]), box, sc.poly, sc.tmp);
            if (sc.poly.empty()) continue;
            glm::dvec3 lo = sc.poly[0], hi = sc.poly[0], sum(0.0);
            for (const glm::dvec3& p : sc.poly) {
                lo = glm::min(lo, p);
                hi = glm::max(hi, p);
                sum += p;
            }
            if (uint32_t(sc.tri_arena.size()) == out.tris_first)
                out.point = glm::vec3(sum / double(sc.poly.size()));
            sc.tri_arena.push_back(t);
            out.target.extend(
                Aabb::of(glm::vec3(float_at_most(lo.x), float_at_most(lo.y), float_at_most(lo.z)),
                         glm::vec3(float_at_least(hi.x), float_at_least(hi.y), float_at_least(hi.z))));
        }
        out.target.min = glm::max(out.target.min, box.min);
        out.target.max = glm::min(out.target.max, box.max);
        out.tris_count = uint32_t(sc.tri_arena.size()) - out.tris_first;
        return out.tris_count > 0;
    };
    Pair root;
    for (uint32_t t = 0; t < obj.triangle_count; ++t) sc.tri_arena.push_back(obj.first_triangle + t);
    if (!tris_in(0, obj.triangle_count, obj.bounds, root)) return false;
    if (voxels) {
        if (!eyes_in(glm::ivec3(0), region.n, region.box, root)) return false;
    } else {
        root.region = region.box;
        root.from = region.box.center();
    }
    // A few sight lines first, from eyes to points of the object: one that meets no occluder settles the
    // pair at once (no cover can hold it).
    // Seeded by the object and the region, so the answer does not depend on threads or order.
    const glm::vec3 m = region.box.min;
    Rng rng(object, (uint64_t(std::bit_cast<uint32_t>(m.x)) << 32 | std::bit_cast<uint32_t>(m.z)) ^
                        (uint64_t(std::bit_cast<uint32_t>(m.y)) << 16));
    for (int k = 0; k < kProbeLines; ++k) {
        glm::vec3 from = root.region.center();
        if (voxels) {
            const Aabb vb = random_eye_voxel(root, rng);
            const Aabb part = Aabb::of(glm::max(vb.min, root.region.min), glm::min(vb.max, root.region.max));
            from = part.min + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * part.size();
        } else {
            from =
                root.region.min + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * root.region.size();
        }
        const Triangle& tri = world.triangles[obj.first_triangle + rng.below(obj.triangle_count)];
        float b1 = rng.uniform(), b2 = rng.uniform();
        if (b1 + b2 > 1.0f) {
            b1 = 1.0f - b1;
            b2 = 1.0f - b2;
        }
        const glm::vec3 to = world.positions[tri.v[0]] +
                             b1 * (world.positions[tri.v[1]] - world.positions[tri.v[0]]) +
                             b2 * (world.positions[tri.v[2]] - world.positions[tri.v[0]]);
        if (!meets_occluder(from, to, sc)) {
            ++figures.certain;
            return false;
        }
    }
    sc.stack.push_back(root);
    const int max_halvings = kBaseHalvings + std::bit_width(unsigned(budget)) - 1;
    int tests = 0;
    while (!sc.stack.empty()) {
        const Pair pair = sc.stack.back();
        sc.stack.pop_back();
        if (tests >= budget) {
            ++figures.out_of_budget;
            return false;
        }
        ++tests;
        ++figures.tests;
        if (pair.region.overlaps(pair.target)) {
            ++figures.stuck;
            ++figures.stuck_meet;
            return false;
        }
        bool blocked = false;
        PlaneMiss miss;
        if (try_pair(pair, pair.from, pair.point, blocked, miss, sc, figures)) continue;
        // A cup, on pieces halved a multiple of kCupDepthStep times.
        if (blocked && cups_ && pair.depth % kCupDepthStep == 0 && cup_covers(pair, sc, figures)) {
            ++figures.cupped;
            continue;
        }
        // Separation in the shaft, on the same pieces as cups and on pieces at the depth cap.
        if (blocked && flood_ && (pair.depth % kFloodDepthStep == 0 || pair.depth >= max_halvings)) {
            const auto start = std::chrono::steady_clock::now();
            const bool separated = flood_->separates(pair.region, pair.target, figures.flood);
            figures.flood.seconds +=
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (separated) continue;
        }
        // A line from an eye to a point of the object that meets no occluder: every cover has a piece pair
        // holding it, and no plane covers that pair.
        if (!blocked) {
            ++figures.certain;
            return false;
        }
        if (pair.depth >= max_halvings) {  // a seam no one plane covers: deeper pieces rarely close it
            ++figures.stuck;
            ++figures.stuck_depth;
            return false;
        }
        // What to halve: the longest side of the two pieces, where a side across a narrow strip left open by
        // the best plane (along an occluder's edge: halving across it cuts the strip off) counts
        // kAcrossStripWeight times its length.
        const glm::vec3 rs = pair.region.size(), ts = pair.target.size();
        bool split_region;
        int k;
        if (miss.axis >= 0) {
            const int u = (miss.axis + 1) % 3, v = (miss.axis + 2) % 3;
            const glm::dvec2 extent = glm::max(miss.hi - miss.lo, 1e-12), open = miss.open_hi - miss.open_lo;
            const glm::dvec2 ratio = open / extent;
            double best = 0.0;
            k = -1;
            for (int side = 0; side < 2; ++side)
                for (int kk = 0; kk < 3; ++kk) {
                    double length = side == 0 ? rs[kk] : ts[kk];
                    const int i = kk == u ? 0 : (kk == v ? 1 : -1);
                    if (i >= 0 && ratio[i] < kNarrowStrip * ratio[1 - i]) length *= kAcrossStripWeight;
                    if (length > best) {
                        best = length;
                        k = kk;
                        split_region = side == 0;
                    }
                }
        } else {
            k = -1;
        }
        if (k < 0) {
            const float rl = std::max({rs.x, rs.y, rs.z}), tl = std::max({ts.x, ts.y, ts.z});
            split_region = rl >= tl;
            const glm::vec3 bs = split_region ? rs : ts;
            k = bs.x >= bs.y && bs.x >= bs.z ? 0 : (bs.y >= bs.z ? 1 : 2);
        }
        const Aabb& box = split_region ? pair.region : pair.target;
        const float mid = 0.5f * (box.min[k] + box.max[k]);
        if (!(mid > box.min[k] && mid < box.max[k])) {  // too small to halve
            ++figures.stuck;
            return false;
        }
        for (int side = 0; side < 2; ++side) {
            Aabb half = box;
            (side ? half.min[k] : half.max[k]) = mid;
            Pair child = pair;
            ++child.depth;
            if (split_region) {
                if (voxels) {
                    if (!eyes_in(pair.eyes_lo, pair.eyes_hi, half, child)) continue;  // no eye there
                } else {
                    child.region = half;
                    child.from = half.center();
                }
            } else if (!tris_in(pair.tris_first, pair.tris_count, half, child)) {
                continue;  // no triangle there
            }
            sc.stack.push_back(child);
        }
    }
    ++figures.hidden;
    return true;
}

ShaftProvers::ShaftProvers(Context& ctx, const ShrunkOccluders& occluders, bool fusion, bool caps, bool cups,
                           bool flood) {
    ScopedTimer timer(ctx, "shaft_provers");
    provers_.push_back(std::make_unique<ShaftProver>(ctx, occluders, fusion, caps, cups, flood));
    for (const ShrunkOccluders& set : occluders.block_sets)
        provers_.push_back(std::make_unique<ShaftProver>(ctx, set, fusion, caps, cups, flood));
}

}  // namespace pvs
