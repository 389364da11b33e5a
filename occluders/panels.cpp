// SPDX-License-Identifier: MIT
// Panels: rectangles wholly covered by opaque triangles, found exactly. Conventions: panels.h.
#include "occluders/panels.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

namespace pvs {

namespace {

// A rectangle in a plane: flat along `axis` at `plane`; [u0, u1] x [v0, v1] on axes (axis + 1) % 3 and
// (axis + 2) % 3.
struct Rect {
    int axis;
    float plane, u0, u1, v0, v1;
    auto key() const { return std::tie(axis, plane, u0, u1, v0, v1); }
    bool operator<(const Rect& o) const { return key() < o.key(); }
};

Aabb to_aabb(const Rect& r) {
    const int ua = (r.axis + 1) % 3, va = (r.axis + 2) % 3;
    Aabb b;
    b.min[r.axis] = b.max[r.axis] = r.plane;
    b.min[ua] = r.u0;
    b.max[ua] = r.u1;
    b.min[va] = r.v0;
    b.max[va] = r.v1;
    return b;
}

// A triangle of one plane in 2D (u, v), counter-clockwise, with its float corners for the cell grid.
struct Tri2 {
    std::array<std::array<double, 2>, 3> p;
    std::array<float, 3> u, v;
};

using Point2 = std::array<double, 2>;
using Poly2 = std::vector<Point2>;

Point2 sub(const Point2& a, const Point2& b) {
    return {a[0] - b[0], a[1] - b[1]};
}
double cross(const Point2& a, const Point2& b) {
    return a[0] * b[1] - a[1] * b[0];
}

double area(const Poly2& poly) {
    double s = 0.0;
    for (size_t i = 0; i < poly.size(); ++i) s += cross(poly[i], poly[(i + 1) % poly.size()]);
    return 0.5 * s;
}

// The part of convex `poly` on the left of a -> b (keep_left) or on its right.
Poly2 clip(const Poly2& poly, const Point2& a, const Point2& b, bool keep_left) {
    Poly2 out;
    const Point2 e = sub(b, a);
    auto side = [&](const Point2& q) {
        const double s = cross(e, sub(q, a));
        return keep_left ? s : -s;
    };
    for (size_t i = 0; i < poly.size(); ++i) {
        const Point2& p = poly[i];
        const Point2& q = poly[(i + 1) % poly.size()];
        const double sp = side(p), sq = side(q);
        if (sp >= 0.0) out.push_back(p);
        if ((sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0)) {
            const double t = sp / (sp - sq);
            out.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
        }
    }
    return out;
}

// Pieces of the leftover smaller than this (m2) are rounding slivers along shared edges, not gaps: a real
// crack that thin would be under 1e-12 m wide for a cell a metre long.
constexpr double kSliverArea = 1e-12;

// Is the rectangle [u0, u1] x [v0, v1] wholly covered by the union of `tris`? Subtracts each triangle
// from what is left (a convex piece minus a triangle is up to three convex pieces: what lies right of
// each edge in turn); covered when nothing is left.
bool union_covers(double u0, double u1, double v0, double v1, const std::vector<const Tri2*>& tris) {
    std::vector<Poly2> left = {Poly2{{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}}}, next;
    for (const Tri2* t : tris) {
        next.clear();
        for (const Poly2& piece : left) {
            Poly2 rest = piece;
            for (int e = 0; e < 3 && rest.size() >= 3; ++e) {
                const Point2& a = t->p[size_t(e)];
                const Point2& b = t->p[size_t((e + 1) % 3)];
                Poly2 outside = clip(rest, a, b, false);
                if (outside.size() >= 3 && area(outside) > kSliverArea) next.push_back(std::move(outside));
                rest = clip(rest, a, b, true);
            }
        }
        left.swap(next);
        if (left.empty()) return true;
    }
    return false;
}

// The covered rectangles of one plane. The grid of every distinct vertex coordinate (u and v) cuts the
// plane into cells; a cell is covered when one triangle holds its four corners (it is convex) or, failing
// that, when the union of the triangles meeting it covers it (union_covers). Any triangulation of a face
// (fans, T-junctions, several faces meeting) gives its covered cells. From every covered cell not yet in a
// rectangle, two MAXIMAL rectangles of covered cells are grown (u first, then v; and v first): they
// overlap, so a point deep inside the covered region lies deep inside some panel, and the inset a panel
// gets at its edges (docs/ALGORITHMS.md#panel-inset) costs only at the region's own edges, not where a
// partition would cut it.
std::vector<Rect> plane_rectangles(int axis, float plane, const std::vector<Tri2>& tris,
                                   uint64_t& covered_cells) {
    std::vector<float> us, vs;
    for (const Tri2& t : tris)
        for (int i = 0; i < 3; ++i) {
            us.push_back(t.u[size_t(i)]);
            vs.push_back(t.v[size_t(i)]);
        }
    std::sort(us.begin(), us.end());
    us.erase(std::unique(us.begin(), us.end()), us.end());
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    const size_t nu = us.size() - 1, nv = vs.size() - 1;  // cells
    if (us.size() < 2 || vs.size() < 2) return {};
    std::vector<uint8_t> covered(nu * nv, 0);
    std::map<size_t, std::vector<const Tri2*>> partial;  // cells some triangle meets but no one holds
    for (const Tri2& t : tris) {
        const float tu0 = std::min({t.u[0], t.u[1], t.u[2]}), tu1 = std::max({t.u[0], t.u[1], t.u[2]});
        const float tv0 = std::min({t.v[0], t.v[1], t.v[2]}), tv1 = std::max({t.v[0], t.v[1], t.v[2]});
        const size_t i0 = size_t(std::lower_bound(us.begin(), us.end(), tu0) - us.begin());
        const size_t i1 = size_t(std::lower_bound(us.begin(), us.end(), tu1) - us.begin());
        const size_t j0 = size_t(std::lower_bound(vs.begin(), vs.end(), tv0) - vs.begin());
        const size_t j1 = size_t(std::lower_bound(vs.begin(), vs.end(), tv1) - vs.begin());
        for (size_t j = j0; j < j1; ++j) {
            for (size_t i = i0; i < i1; ++i) {
                const size_t cell = i + nu * j;
                if (covered[cell]) continue;
                const Point2 corners[4] = {{double(us[i]), double(vs[j])},
                                           {double(us[i + 1]), double(vs[j])},
                                           {double(us[i + 1]), double(vs[j + 1])},
                                           {double(us[i]), double(vs[j + 1])}};
                bool all_in = true, apart = false;
                for (int e = 0; e < 3; ++e) {
                    const Point2& a = t.p[size_t(e)];
                    const Point2 edge = sub(t.p[size_t((e + 1) % 3)], a);
                    int in = 0;
                    for (const Point2& c : corners) in += cross(edge, sub(c, a)) >= 0.0;
                    all_in = all_in && in == 4;
                    apart = apart || in == 0;
                }
                if (all_in) {
                    covered[cell] = 1;
                } else if (!apart) {
                    partial[cell].push_back(&t);
                }
            }
        }
    }
    for (const auto& [cell, meeting] : partial) {
        if (covered[cell]) continue;
        const size_t i = cell % nu, j = cell / nu;
        covered[cell] = union_covers(us[i], us[i + 1], vs[j], vs[j + 1], meeting);
    }
    // Summed counts of covered cells, for O(1) tests of whole strips.
    std::vector<uint32_t> sum((nu + 1) * (nv + 1), 0);
    for (size_t j = 0; j < nv; ++j)
        for (size_t i = 0; i < nu; ++i)
            sum[(i + 1) + (nu + 1) * (j + 1)] = covered[i + nu * j] + sum[i + (nu + 1) * (j + 1)] +
                                                sum[(i + 1) + (nu + 1) * j] - sum[i + (nu + 1) * j];
    auto full = [&](size_t i0, size_t i1, size_t j0, size_t j1) {  // cells [i0, i1) x [j0, j1)
        const uint32_t n = sum[i1 + (nu + 1) * j1] - sum[i0 + (nu + 1) * j1] - sum[i1 + (nu + 1) * j0] +
                           sum[i0 + (nu + 1) * j0];
        return uint64_t(n) == uint64_t(i1 - i0) * uint64_t(j1 - j0);
    };
    struct Cells {
        size_t i0, i1, j0, j1;
        auto key() const { return std::tie(i0, i1, j0, j1); }
    };
    auto grow = [&](size_t i, size_t j, bool u_first) {
        Cells c{i, i + 1, j, j + 1};
        for (int pass = 0; pass < 2; ++pass) {
            if ((pass == 0) == u_first) {
                while (c.i0 > 0 && full(c.i0 - 1, c.i0, c.j0, c.j1)) --c.i0;
                while (c.i1 < nu && full(c.i1, c.i1 + 1, c.j0, c.j1)) ++c.i1;
            } else {
                while (c.j0 > 0 && full(c.i0, c.i1, c.j0 - 1, c.j0)) --c.j0;
                while (c.j1 < nv && full(c.i0, c.i1, c.j1, c.j1 + 1)) ++c.j1;
            }
        }
        return c;
    };
    std::vector<uint8_t> used(nu * nv, 0);
    std::vector<Cells> found;
    for (size_t j = 0; j < nv; ++j) {
        for (size_t i = 0; i < nu; ++i) {
            if (!covered[i + nu * j]) continue;
            ++covered_cells;
            if (used[i + nu * j]) continue;
            for (const bool u_first : {true, false}) {
                const Cells c = grow(i, j, u_first);
                if (!found.empty() && found.back().key() == c.key()) continue;
                found.push_back(c);
                for (size_t jj = c.j0; jj < c.j1; ++jj)
                    for (size_t ii = c.i0; ii < c.i1; ++ii) used[ii + nu * jj] = 1;
            }
        }
    }
    // Drop rectangles inside another.
    std::sort(found.begin(), found.end(), [](const Cells& a, const Cells& b) { return a.key() < b.key(); });
    found.erase(std::unique(found.begin(), found.end(),
                            [](const Cells& a, const Cells& b) { return a.key() == b.key(); }),
                found.end());
    std::vector<Rect> out;
    for (size_t k = 0; k < found.size(); ++k) {
        const Cells& a = found[k];
        bool inside = false;
        for (size_t m = 0; m < found.size() && !inside; ++m) {
            const Cells& b = found[m];
            inside = m != k && b.i0 <= a.i0 && a.i1 <= b.i1 && b.j0 <= a.j0 && a.j1 <= b.j1;
        }
        if (!inside) out.push_back(Rect{axis, plane, us[a.i0], us[a.i1], vs[a.j0], vs[a.j1]});
    }
    return out;
}

}  // namespace

int panel_axis(const Aabb& panel) {
    int axis = -1;
    for (int a = 0; a < 3; ++a) {
        if (!(panel.min[a] <= panel.max[a])) return -1;
        if (panel.min[a] == panel.max[a]) {
            if (axis >= 0) return -1;
            axis = a;
        }
    }
    return axis;
}

std::vector<std::array<uint32_t, 2>> panel_corners(const std::vector<Aabb>& panels) {
    // Per axis, the panels flat along it sorted by their plane: a panel's partners along axis n are those
    // whose plane lies in its extent along n, a range found by binary search.
    std::array<std::vector<std::pair<float, uint32_t>>, 3> by_plane;
    for (uint32_t i = 0; i < panels.size(); ++i) {
        const int a = panel_axis(panels[i]);
        if (a >= 0 && is_finite(panels[i].min) && is_finite(panels[i].max))
            by_plane[size_t(a)].push_back({panels[i].min[a], i});
    }
    for (auto& list : by_plane) std::sort(list.begin(), list.end());
    std::vector<std::array<uint32_t, 2>> out;
    for (uint32_t i = 0; i < panels.size(); ++i) {
        const Aabb& a = panels[i];
        const int na = panel_axis(a);
        if (na < 0 || !is_finite(a.min) || !is_finite(a.max)) continue;
        for (int nb = 0; nb < 3; ++nb) {
            if (nb == na) continue;
            const int k = 3 - na - nb;
            const auto& list = by_plane[size_t(nb)];
            auto it = std::lower_bound(list.begin(), list.end(), std::pair<float, uint32_t>{a.min[nb], 0});
            for (; it != list.end() && it->first <= a.max[nb]; ++it) {
                const uint32_t j = it->second;
                const Aabb& b = panels[j];
                if (j <= i || !(b.min[na] <= a.min[na] && a.min[na] <= b.max[na])) continue;
                if (std::max(a.min[k], b.min[k]) < std::min(a.max[k], b.max[k])) out.push_back({i, j});
            }
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<Aabb> find_panels(const World& world, PanelFigures* figures) {
    PanelFigures fig;
    // The opaque triangles of each axis plane (all three vertices on it, compared exactly), in 2D.
    std::map<std::pair<int, float>, std::vector<Tri2>> planes;
    for (size_t t = 0; t < world.triangles.size(); ++t) {
        if (!world.triangle_opaque[t]) continue;
        const Triangle& tri = world.triangles[t];
        const std::array<glm::vec3, 3> p = {world.positions[tri.v[0]], world.positions[tri.v[1]],
                                            world.positions[tri.v[2]]};
        int axis = -1;
        for (int a = 0; a < 3 && axis < 0; ++a)
            if (p[0][a] == p[1][a] && p[1][a] == p[2][a]) axis = a;
        if (axis < 0) continue;
        ++fig.flat_triangles;
        const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
        Tri2 t2;
        for (int i = 0; i < 3; ++i) t2.p[i] = {double(p[i][ua]), double(p[i][va])};
        const double area2 = cross(sub(t2.p[1], t2.p[0]), sub(t2.p[2], t2.p[0]));
        if (area2 == 0.0) continue;
        if (area2 < 0.0) std::swap(t2.p[1], t2.p[2]);  // counter-clockwise: inside is left of each edge
        for (int i = 0; i < 3; ++i) {
            t2.u[i] = float(p[i][ua]);
            t2.v[i] = float(p[i][va]);
        }
        planes[{axis, p[0][axis]}].push_back(t2);
    }
    std::vector<Aabb> out;
    for (const auto& [plane, tris] : planes) {
        ++fig.planes;
        std::vector<Rect> rects = plane_rectangles(plane.first, plane.second, tris, fig.covered_cells);
        for (const Rect& r : rects) out.push_back(to_aabb(r));
    }
    fig.panels = out.size();
    if (figures) *figures = fig;
    return out;
}

std::vector<Aabb> inset_panels(const std::vector<Aabb>& panels, double inset_m) {
    std::vector<Aabb> out;
    for (const Aabb& p : panels) {
        const int axis = panel_axis(p);
        if (axis < 0) continue;
        Aabb q = p;
        bool empty = false;
        for (int a = 0; a < 3; ++a) {
            if (a == axis) continue;
            q.min[a] =
                float_at_least(double(p.min[a]) + inset_m);  // rounded inward: an inset never grows a panel
            q.max[a] = float_at_most(double(p.max[a]) - inset_m);
            empty = empty || !(q.min[a] < q.max[a]);
        }
        if (!empty) out.push_back(q);
    }
    return out;
}

}  // namespace pvs
