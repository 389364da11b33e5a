// SPDX-License-Identifier: MIT
// Slanted panels: convex polygons tiled by coplanar opaque triangles. Conventions: slanted_panels.h.
#include "occluders/slanted_panels.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <tuple>

namespace pvs {

namespace {

using Key = std::tuple<float, float, float>;
Key key_of(const glm::vec3& p) {
    return {p.x, p.y, p.z};
}
using EdgeKey = std::pair<Key, Key>;
EdgeKey edge_of(const glm::vec3& a, const glm::vec3& b) {
    const Key ka = key_of(a), kb = key_of(b);
    return ka < kb ? EdgeKey{ka, kb} : EdgeKey{kb, ka};
}

bool in_axis_plane(const std::array<glm::vec3, 3>& p) {
    for (int a = 0; a < 3; ++a)
        if (p[0][a] == p[1][a] && p[1][a] == p[2][a]) return true;
    return false;
}

// Sines of angles: a new corner must lie beyond the edge by at least kBeyond (far above double rounding, so
// no triangle folds back over the polygon), and a corner may turn the wrong way by at most kStraight (a
// straight run of edges, rounded), far less than kBeyond.
constexpr double kBeyond = 1e-9;
constexpr double kStraight = 1e-12;

double cross2(const glm::dvec2& a, const glm::dvec2& b) {
    return a.x * b.y - a.y * b.x;
}

// A polygon being grown: its corners (as the float vertices they are, and in the plane's 2D frame),
// counter-clockwise.
struct Growing {
    glm::dvec3 origin, e1, e2, normal;
    double offset = 0.0;
    std::vector<glm::vec3> corners;
    std::vector<glm::dvec2> flat;
    glm::dvec2 to2d(const glm::vec3& p) const {
        const glm::dvec3 d = glm::dvec3(p) - origin;
        return {glm::dot(d, e1), glm::dot(d, e2)};
    }
};

}  // namespace

bool set_slanted_edges(SlantedPanel& panel) {
    const size_t n = panel.corners.size();
    panel.edge_normal.resize(n);
    panel.edge_offset.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 in = glm::cross(panel.normal, panel.corners[(i + 1) % n] - panel.corners[i]);
        const double len = glm::length(in);
        if (!(len > 0.0) || !std::isfinite(len)) return false;
        panel.edge_normal[i] = in / len;
        panel.edge_offset[i] = glm::dot(panel.edge_normal[i], panel.corners[i]);
    }
    return n >= 3;
}

std::vector<SlantedPanel> find_slanted_panels(const World& world, double max_thickness_m, double min_area_m2,
                                              SlantedPanelFigures* figures) {
    SlantedPanelFigures fig;
    std::vector<uint32_t> slanted;
    std::vector<double> area;
    std::map<EdgeKey, std::vector<uint32_t>> by_edge;
    auto corners_of = [&](uint32_t t) {
        const Triangle& tri = world.triangles[t];
        return std::array<glm::vec3, 3>{world.positions[tri.v[0]], world.positions[tri.v[1]],
                                        world.positions[tri.v[2]]};
    };
    for (uint32_t t = 0; t < world.triangles.size(); ++t) {
        if (!world.triangle_opaque[t]) continue;
        const std::array<glm::vec3, 3> p = corners_of(t);
        if (in_axis_plane(p)) continue;
        const double a = 0.5 * glm::length(glm::cross(glm::dvec3(p[1]) - glm::dvec3(p[0]),
                                                      glm::dvec3(p[2]) - glm::dvec3(p[0])));
        if (!(a > 0.0)) continue;
        ++fig.slanted_triangles;
        fig.slanted_area_m2 += a;
        slanted.push_back(t);
        area.push_back(a);
        for (int i = 0; i < 3; ++i) by_edge[edge_of(p[i], p[(i + 1) % 3])].push_back(t);
    }
    std::vector<size_t> order(slanted.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return area[a] > area[b]; });
    std::vector<uint8_t> used(world.triangles.size(), 1);  // only slanted triangles may join
    for (uint32_t t : slanted) used[t] = 0;

    std::vector<SlantedPanel> out;
    for (size_t s : order) {
        const uint32_t seed = slanted[s];
        if (used[seed]) continue;
        used[seed] = 1;
        const std::array<glm::vec3, 3> p = corners_of(seed);
        Growing g;
        g.origin = glm::dvec3(p[0]);
        g.normal = glm::normalize(glm::cross(glm::dvec3(p[1]) - g.origin, glm::dvec3(p[2]) - g.origin));
        g.offset = glm::dot(g.normal, g.origin);
        g.e1 = glm::normalize(glm::dvec3(p[1]) - g.origin);
        g.e2 = glm::cross(g.normal, g.e1);
        g.corners.assign(p.begin(), p.end());  // counter-clockwise about normal by construction
        for (const glm::vec3& c : g.corners) g.flat.push_back(g.to2d(c));
        uint32_t members = 1;
        double thickness = 0.0;
        for (bool grew = true; grew;) {
            grew = false;
            for (size_t i = 0; i < g.corners.size() && !grew; ++i) {
                const size_t j = (i + 1) % g.corners.size();
                const auto it = by_edge.find(edge_of(g.corners[i], g.corners[j]));
                if (it == by_edge.end()) continue;
                for (uint32_t u : it->second) {
                    if (used[u]) continue;
                    const std::array<glm::vec3, 3> q = corners_of(u);
                    int third = -1;
                    for (int k = 0; k < 3; ++k)
                        if (key_of(q[k]) != key_of(g.corners[i]) && key_of(q[k]) != key_of(g.corners[j]))
                            third = k;
                    if (third < 0) continue;
                    const glm::vec3 c = q[size_t(third)];
                    const double off = std::abs(glm::dot(g.normal, glm::dvec3(c)) - g.offset);
                    if (!(off <= max_thickness_m)) continue;
                    const glm::dvec2 a2 = g.flat[i], b2 = g.flat[j], c2 = g.to2d(c);
                    // Beyond the edge by more than rounding (so the triangle cannot fold back over the
                    // polygon), and convex at both ends of it, up to rounding
                    // (docs/ALGORITHMS.md#slanted-panels).
                    if (!(cross2(b2 - a2, c2 - a2) < -kBeyond * glm::length(b2 - a2) * glm::length(c2 - a2)))
                        continue;
                    const size_t n = g.corners.size();
                    const glm::dvec2 before_a = g.flat[(i + n - 1) % n], after_b = g.flat[(j + 1) % n];
                    if (cross2(a2 - before_a, c2 - a2) <
                        -kStraight * glm::length(a2 - before_a) * glm::length(c2 - a2))
                        continue;
                    if (cross2(b2 - c2, after_b - b2) <
                        -kStraight * glm::length(b2 - c2) * glm::length(after_b - b2))
                        continue;
                    g.corners.insert(g.corners.begin() + ptrdiff_t(j == 0 ? n : j), c);
                    g.flat.insert(g.flat.begin() + ptrdiff_t(j == 0 ? n : j), c2);
                    used[u] = 1;
                    ++members;
                    thickness = std::max(thickness, off);
                    grew = true;
                    break;
                }
            }
        }
        double a = 0.0;
        for (size_t i = 0; i < g.flat.size(); ++i) a += cross2(g.flat[i], g.flat[(i + 1) % g.flat.size()]);
        a *= 0.5;
        if (a < min_area_m2) continue;
        SlantedPanel panel;
        panel.normal = g.normal;
        panel.offset = g.offset;
        panel.thickness = thickness;
        panel.area_m2 = a;
        panel.triangles = members;
        for (const glm::vec3& c : g.corners) {
            panel.corners.emplace_back(c);
            panel.bounds.extend(c);
        }
        if (!set_slanted_edges(panel)) continue;
        fig.triangles_in_panels += members;
        fig.panel_area_m2 += a;
        out.push_back(std::move(panel));
    }
    fig.panels = out.size();
    if (figures) *figures = fig;
    return out;
}

namespace {

// The polygon occluder of one panel, or nothing when its float form fails the checks.
std::optional<OccluderPolygon> runtime_polygon(const SlantedPanel& panel) {
    std::vector<glm::dvec3> c = panel.corners;
    const auto corner_area = [&](size_t i) {  // what dropping corner i loses
        const glm::dvec3& a = c[(i + c.size() - 1) % c.size()];
        const glm::dvec3& b = c[(i + 1) % c.size()];
        return 0.5 * glm::length(glm::cross(c[i] - a, b - a));
    };
    while (c.size() > kPolygonMaxCorners) {
        size_t drop = 0;
        for (size_t i = 1; i < c.size(); ++i)
            if (corner_area(i) < corner_area(drop)) drop = i;
        c.erase(c.begin() + std::ptrdiff_t(drop));
    }
    // Shrunk towards the mean of the corners g by 1 - d / h, h the least distance from g to an edge line of
    // the panel: each edge moves in by at least d (the corners kept lie in the panel, so its prism holds
    // them).
    glm::dvec3 g(0.0);
    for (const glm::dvec3& p : c) g += p;
    g /= double(c.size());
    double h = INFINITY;
    for (size_t i = 0; i < panel.corners.size(); ++i)
        h = std::min(h, glm::dot(panel.edge_normal[i], g) - panel.edge_offset[i]);
    if (!(h > 4.0 * kPolygonInsetM)) return std::nullopt;
    const double s = 1.0 - kPolygonInsetM / h;
    OccluderPolygon out;
    out.normal = glm::vec3(panel.normal);
    out.offset = float(panel.offset);
    out.thickness = float(panel.thickness + kPolygonSlabGrowM);
    for (const glm::dvec3& p : c) {
        out.corners.push_back(glm::vec3(g + s * (p - g)));
        out.bounds.extend(out.corners.back());
    }
    // The float form as the culler reads it (in double), checked at the corners of its prism's part in its
    // slab: each inside the panel's prism, the near ones on the near side of the panel's slab, the far ones
    // on the far side, and the corners convex and counter-clockwise about its normal.
    const glm::dvec3 nf(out.normal);
    const double len = glm::length(nf);
    const glm::dvec3 n = nf / len;
    const double o = double(out.offset) / len, t = double(out.thickness) / len;
    const size_t k = out.corners.size();
    const double margin = 1e-6;
    for (size_t i = 0; i < k; ++i) {
        const glm::dvec3 p0(out.corners[i]), p1(out.corners[(i + 1) % k]);
        const glm::dvec3 m = glm::cross(n, p1 - p0);
        for (size_t j = 0; j < k; ++j)
            if (!(glm::dot(m, glm::dvec3(out.corners[j]) - p0) >= 0.0)) return std::nullopt;
        for (const double side : {-1.0, 1.0}) {
            const glm::dvec3 v = p0 + (o + side * t - glm::dot(n, p0)) * n;
            for (size_t e = 0; e < panel.corners.size(); ++e)
                if (!(glm::dot(panel.edge_normal[e], v) >= panel.edge_offset[e] + margin))
                    return std::nullopt;
            const double above = glm::dot(panel.normal, v) - panel.offset;
            if (!(side * above >= panel.thickness + margin)) return std::nullopt;
        }
    }
    return out;
}

}  // namespace

namespace {

// The tile of one panel, or nothing when it has too many corners or its float form does not turn one way.
std::optional<OccluderPolygon> runtime_tile(const SlantedPanel& panel) {
    if (panel.corners.size() < 3 || panel.corners.size() > kTileMaxCorners) return std::nullopt;
    OccluderPolygon out;
    out.tile = true;
    out.normal = glm::vec3(panel.normal);
    out.offset = float(panel.offset);
    for (const glm::dvec3& c : panel.corners) {
        out.corners.push_back(glm::vec3(c));  // the float vertices the panel was grown from, exactly
        out.bounds.extend(out.corners.back());
    }
    // The plane as the runtime reads it: normal and offset divided by the float normal's length.
    const glm::dvec3 nf(out.normal);
    const double len = glm::length(nf);
    if (!(len > 0.0) || !std::isfinite(len)) return std::nullopt;
    const glm::dvec3 n = nf / len;
    const double o = double(out.offset) / len;
    double t = 0.0, scale = 0.0;
    for (const glm::vec3& c : out.corners) {
        t = std::max(t, std::abs(glm::dot(n, glm::dvec3(c)) - o));
        scale = std::max({scale, double(std::abs(c.x)), double(std::abs(c.y)), double(std::abs(c.z))});
    }
    // Grown past double rounding (1e-12 of the scale) and rounded up, so that t' / len >= t.
    const double want = (t + kTileSlabGrowM + 1e-12 * (1.0 + scale)) * len;
    float tf = float(want);
    if (double(tf) < want) tf = std::nextafter(tf, std::numeric_limits<float>::infinity());
    out.thickness = tf;
    // Every corner on the inner side of every edge about the float normal, up to a tenth of what the runtime
    // allows (a straight run of edges turns either way by rounding).
    const size_t k = out.corners.size();
    const double allow = 1e-10 * (1.0 + scale);
    for (size_t i = 0; i < k; ++i) {
        const glm::dvec3 p0(out.corners[i]), p1(out.corners[(i + 1) % k]);
        const glm::dvec3 m = glm::cross(n, p1 - p0);
        const double ml = glm::length(m);
        if (!(ml > 0.0)) return std::nullopt;
        for (size_t j = 0; j < k; ++j)
            if (!(glm::dot(m, glm::dvec3(out.corners[j]) - p0) / ml >= -allow)) return std::nullopt;
    }
    return out;
}

}  // namespace

namespace {

// The runtime forms `form` gives of the panels of at least min_area_m2, where it gives one.
template <typename Form>
std::vector<OccluderPolygon> runtime_forms(const std::vector<SlantedPanel>& panels, double min_area_m2,
                                           Form form) {
    std::vector<OccluderPolygon> out;
    for (const SlantedPanel& p : panels) {
        if (p.area_m2 < min_area_m2) continue;
        if (std::optional<OccluderPolygon> q = form(p)) out.push_back(std::move(*q));
    }
    return out;
}

}  // namespace

std::vector<OccluderPolygon> runtime_tiles(const std::vector<SlantedPanel>& panels, double min_area_m2) {
    return runtime_forms(panels, min_area_m2, runtime_tile);
}

std::vector<OccluderPolygon> runtime_polygons(const std::vector<SlantedPanel>& panels, double min_area_m2) {
    return runtime_forms(panels, min_area_m2, runtime_polygon);
}

}  // namespace pvs
