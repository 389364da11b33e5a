// SPDX-License-Identifier: MIT
#include "pvs/convex_cap.h"

#include "core/convex_clip.h"
#include "occluders/panels.h"
#include "pvs/region_hiding.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace pvs {

namespace {

// A cap holds at most this many polygons and corners (its hull is found by trying every plane through three
// corners).
constexpr size_t kMaxCapPolygons = 8;
constexpr size_t kMaxCapCorners = 32;
// Corners this close are one; a corner this near a plane lies on it (the hull's faces and the polygons'
// planes). Far below kHideToleranceM, by which every test keeps away from the hull's surface.
constexpr double kSameM = 1e-9;
constexpr double kOnPlaneM = 1e-7;
// Two polygons are edge neighbours when an edge of each lies on the same line over at least this length.
constexpr double kSharedEdgeM = 1e-4;
// A neighbour bends away when one of its corners lies at least this far behind the polygon's plane.
constexpr double kBendM = 1e-6;

double side_of(const CapPolygon& p, const glm::dvec3& x) { return glm::dot(p.normal, x) - p.offset; }

// Is x (on the polygon's plane) inside the convex polygon, within kSameM?
bool inside(const CapPolygon& p, const glm::dvec3& x) {
    const size_t n = p.corners.size();
    glm::dvec3 area(0.0);
    for (size_t i = 0; i < n; ++i) area += glm::cross(p.corners[i], p.corners[(i + 1) % n]);
    const double turn = glm::dot(area, p.normal) >= 0.0 ? 1.0 : -1.0;
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 a = p.corners[i], b = p.corners[(i + 1) % n];
        const double len = glm::length(b - a);
        if (!(len > 0.0)) continue;
        if (turn * glm::dot(glm::cross(b - a, x - a), p.normal) / len < -kSameM) return false;
    }
    return true;
}

// Do an edge of a and an edge of b lie on one line over at least kSharedEdgeM?
bool share_edge(const CapPolygon& a, const CapPolygon& b) {
    const size_t na = a.corners.size(), nb = b.corners.size();
    for (size_t i = 0; i < na; ++i) {
        const glm::dvec3 p = a.corners[i], q = a.corners[(i + 1) % na];
        const double len = glm::length(q - p);
        if (!(len > kSharedEdgeM)) continue;
        const glm::dvec3 d = (q - p) / len;
        for (size_t j = 0; j < nb; ++j) {
            const glm::dvec3 r = b.corners[j], s = b.corners[(j + 1) % nb];
            if (glm::length(glm::cross(r - p, d)) > kOnPlaneM || glm::length(glm::cross(s - p, d)) > kOnPlaneM)
                continue;
            const double r0 = glm::dot(r - p, d), s0 = glm::dot(s - p, d);
            if (std::min(len, std::max(r0, s0)) - std::max(0.0, std::min(r0, s0)) >= kSharedEdgeM) return true;
        }
    }
    return false;
}

// The polygon seen from the side `sign` (+1: the side its normal points to): every corner of `other` lies
// behind its plane or on it.
bool behind(const CapPolygon& p, double sign, const CapPolygon& other) {
    for (const glm::dvec3& x : other.corners)
        if (sign * side_of(p, x) > kOnPlaneM) return false;
    return true;
}

bool bends_away(const CapPolygon& p, double sign, const CapPolygon& other) {
    for (const glm::dvec3& x : other.corners)
        if (sign * side_of(p, x) < -kBendM) return true;
    return false;
}

}  // namespace

std::vector<CapPolygon> cap_polygons(const std::vector<Aabb>& panels, const std::vector<SlantedPanel>& slanted) {
    std::vector<CapPolygon> out;
    out.reserve(panels.size() + slanted.size());
    for (const Aabb& b : panels) {
        CapPolygon p;
        const int a = panel_axis(b);
        if (a >= 0) {
            const int u = (a + 1) % 3, v = (a + 2) % 3;
            for (int k = 0; k < 4; ++k) {
                glm::dvec3 x(b.min);
                x[u] = (k == 1 || k == 2) ? b.max[u] : b.min[u];
                x[v] = k >= 2 ? b.max[v] : b.min[v];
                p.corners.push_back(x);
            }
            p.normal[a] = 1.0;
            p.offset = b.min[a];
        }
        out.push_back(std::move(p));
    }
    for (const SlantedPanel& sp : slanted) {
        CapPolygon p;
        if (sp.thickness == 0.0) p = CapPolygon{sp.corners, sp.normal, sp.offset};
        out.push_back(std::move(p));
    }
    return out;
}

ConvexCap make_cap(const std::vector<const CapPolygon*>& polygons) {
    ConvexCap cap;
    if (polygons.size() < 2 || polygons.size() > kMaxCapPolygons) return cap;
    std::vector<glm::dvec3> pts;
    for (const CapPolygon* p : polygons)
        for (const glm::dvec3& x : p->corners) {
            bool known = false;
            for (const glm::dvec3& y : pts) known = known || glm::length(x - y) <= kSameM;
            if (!known) pts.push_back(x);
        }
    if (pts.size() < 4 || pts.size() > kMaxCapCorners) return cap;
    // A volume: some corner off the first polygon's plane.
    bool solid = false;
    for (const glm::dvec3& x : pts) solid = solid || std::abs(side_of(*polygons[0], x)) > kBendM;
    if (!solid) return cap;
    const size_t n = pts.size();
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j)
            for (size_t k = j + 1; k < n; ++k) {
                glm::dvec3 m = glm::cross(pts[j] - pts[i], pts[k] - pts[i]);
                const double len = glm::length(m);
                if (!(len > 1e-12)) continue;
                m /= len;
                const double d = glm::dot(m, pts[i]);
                double lo = 0.0, hi = 0.0;
                for (const glm::dvec3& x : pts) {
                    const double s = glm::dot(m, x) - d;
                    lo = std::min(lo, s);
                    hi = std::max(hi, s);
                }
                if (hi > kOnPlaneM && lo < -kOnPlaneM) continue;  // corners on both sides: no face
                const glm::dvec3 out = hi <= kOnPlaneM ? m : -m;
                const double off = hi <= kOnPlaneM ? d : -d;
                bool known = false;
                for (size_t f = 0; f < cap.normal.size() && !known; ++f)
                    known = glm::dot(cap.normal[f], out) > 1.0 - 1e-12 && std::abs(cap.offset[f] - off) <= kOnPlaneM;
                if (known) continue;
                cap.normal.push_back(out);
                cap.offset.push_back(off);
            }
    if (cap.normal.size() < 4) return ConvexCap{};
    // A face is opaque when its corners all lie in one polygon of its plane.
    cap.opaque.assign(cap.normal.size(), 0);
    for (size_t f = 0; f < cap.normal.size(); ++f) {
        for (const CapPolygon* p : polygons) {
            if (std::abs(std::abs(glm::dot(p->normal, cap.normal[f])) - 1.0) > 1e-12) continue;
            bool all = true;
            for (const glm::dvec3& x : pts) {
                if (std::abs(glm::dot(cap.normal[f], x) - cap.offset[f]) > kOnPlaneM) continue;
                all = all && std::abs(side_of(*p, x)) <= kOnPlaneM && inside(*p, x);
            }
            if (all) {
                cap.opaque[f] = 1;
                break;
            }
        }
    }
    cap.polygons = uint32_t(polygons.size());
    for (const glm::dvec3& x : pts) cap.bounds.extend(glm::vec3(x));
    return cap;
}

std::vector<ConvexCap> build_caps(const std::vector<CapPolygon>& polygons) {
    const size_t n = polygons.size();
    std::vector<ConvexCap> caps(2 * n);
    // Edge neighbours, by a sweep over the polygons' bounds along x.
    std::vector<Aabb> bounds(n);
    for (size_t i = 0; i < n; ++i)
        for (const glm::dvec3& x : polygons[i].corners) bounds[i].extend(glm::vec3(x));
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return bounds[a].min.x < bounds[b].min.x || (bounds[a].min.x == bounds[b].min.x && a < b);
    });
    std::vector<std::vector<uint32_t>> neighbours(n);
    const float slack = float(kSharedEdgeM);
    for (size_t oi = 0; oi < n; ++oi) {
        const uint32_t a = order[oi];
        if (polygons[a].corners.size() < 3) continue;
        const Aabb grown = Aabb::of(bounds[a].min - slack, bounds[a].max + slack);
        for (size_t oj = oi + 1; oj < n; ++oj) {
            const uint32_t b = order[oj];
            if (bounds[b].min.x > grown.max.x) break;
            if (polygons[b].corners.size() < 3) continue;
            if (!grown.overlaps(bounds[b])) continue;
            if (std::abs(glm::dot(polygons[a].normal, polygons[b].normal)) > 1.0 - 1e-12) continue;  // parallel
            if (!share_edge(polygons[a], polygons[b])) continue;
            neighbours[a].push_back(b);
            neighbours[b].push_back(a);
        }
    }
    for (size_t i = 0; i < n; ++i) std::sort(neighbours[i].begin(), neighbours[i].end());
    for (size_t i = 0; i < n; ++i) {
        for (int s = 0; s < 2; ++s) {
            // Grown outwards from the polygon, neighbours of the chosen ones first, each with the side it is
            // seen from: the one all the chosen polygons lie behind.
            std::vector<std::pair<uint32_t, double>> chosen{{uint32_t(i), s == 0 ? 1.0 : -1.0}};
            std::vector<glm::dvec3> corners = polygons[i].corners;
            for (size_t next = 0; next < chosen.size() && chosen.size() < kMaxCapPolygons; ++next) {
                const auto [c, sc] = chosen[next];
                for (const uint32_t b : neighbours[c]) {
                    if (chosen.size() >= kMaxCapPolygons) break;
                    if (std::any_of(chosen.begin(), chosen.end(), [&](const auto& x) { return x.first == b; }))
                        continue;
                    const CapPolygon& pb = polygons[b];
                    if (!behind(polygons[c], sc, pb) || !bends_away(polygons[c], sc, pb)) continue;
                    double sb = 0.0;
                    for (const double t : {1.0, -1.0}) {
                        bool all = bends_away(pb, t, polygons[c]);
                        for (const auto& [d, sd] : chosen) all = all && behind(pb, t, polygons[d]);
                        if (all) sb = t;
                    }
                    if (sb == 0.0) continue;
                    bool fits = true;
                    for (const auto& [d, sd] : chosen) fits = fits && behind(polygons[d], sd, pb);
                    if (!fits) continue;
                    size_t added = 0;
                    for (const glm::dvec3& x : pb.corners)
                        added += std::none_of(corners.begin(), corners.end(),
                                              [&](const glm::dvec3& y) { return glm::length(x - y) <= kSameM; });
                    if (corners.size() + added > kMaxCapCorners) continue;
                    for (const glm::dvec3& x : pb.corners)
                        if (std::none_of(corners.begin(), corners.end(),
                                         [&](const glm::dvec3& y) { return glm::length(x - y) <= kSameM; }))
                            corners.push_back(x);
                    chosen.emplace_back(b, sb);
                }
            }
            if (chosen.size() < 2) continue;
            std::vector<const CapPolygon*> ps;
            for (const auto& c : chosen) ps.push_back(&polygons[c.first]);
            caps[2 * i + size_t(s)] = make_cap(ps);
        }
    }
    return caps;
}

bool cap_guards(const ConvexCap& cap, const Aabb& from) {
    if (cap.empty() || from.is_empty()) return false;
    const double tol = kHideToleranceM;
    const std::array<glm::dvec3, 8> fc = box_corners(from, tol);
    bool apart = false;
    for (size_t f = 0; f < cap.normal.size(); ++f) {
        bool all_out = true, any_sees = false;
        for (const glm::dvec3& r : fc) {
            const double s = glm::dot(cap.normal[f], r) - cap.offset[f];
            all_out = all_out && s > tol;
            any_sees = any_sees || s > -tol;
        }
        if (any_sees && !cap.opaque[f]) return false;
        apart = apart || all_out;
    }
    return apart;
}

void cap_slice(const ConvexCap& cap, int axis, double c, glm::dvec2 lo, glm::dvec2 hi,
               std::vector<glm::dvec2>& out, std::vector<glm::dvec2>& scratch) {
    const int a = axis, u = (a + 1) % 3, v = (a + 2) % 3;
    out = {lo, {hi.x, lo.y}, hi, {lo.x, hi.y}};
    for (size_t f = 0; f < cap.normal.size() && out.size() >= 3; ++f) {
        // The face's half-space on the plane: n.x * y.x + n.y * y.y <= r.
        const glm::dvec2 n(cap.normal[f][u], cap.normal[f][v]);
        const double r = cap.offset[f] - kHideToleranceM - cap.normal[f][a] * c;
        const double len2 = glm::dot(n, n);
        if (!(len2 > 1e-24)) {
            if (!(0.0 <= r)) out.clear();  // parallel to the plane, which lies outside it
            continue;
        }
        // Left of the line through p0 along (-n.y, n.x) is where n.y <= r.
        const glm::dvec2 p0 = n * (r / len2), p1 = p0 + glm::dvec2(-n.y, n.x);
        clip_line(out, p0, p1, false, scratch);
        out.swap(scratch);
    }
    if (out.size() < 3) out.clear();
}

bool cap_hides(const ConvexCap& cap, const Aabb& from, const Aabb& to) {
    if (!cap_guards(cap, from) || to.is_empty()) return false;
    const double tol = kHideToleranceM;
    const std::array<glm::dvec3, 8> fc = box_corners(from, tol), tc = box_corners(to, tol);
    const size_t nf = cap.normal.size();
    for (const glm::dvec3& r : fc)
        for (const glm::dvec3& t : tc) {
            double lo = 0.0, hi = 1.0;
            for (size_t f = 0; f < nf; ++f) {
                const double a = glm::dot(cap.normal[f], r) - (cap.offset[f] - tol);
                const double b = glm::dot(cap.normal[f], t) - (cap.offset[f] - tol);
                if (a <= 0.0 && b <= 0.0) continue;
                if (a > 0.0 && b > 0.0) return false;
                const double s = a / (a - b);
                if (a > 0.0) {
                    lo = std::max(lo, s);
                } else {
                    hi = std::min(hi, s);
                }
                if (lo > hi) return false;
            }
        }
    return true;
}

}  // namespace pvs
