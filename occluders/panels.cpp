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

// Merges rectangles of one plane that share a whole edge (or overlap with the same extent across): along u
// for equal v ranges, then along v for equal u ranges, while any merge happens. The union of two such
// rectangles is their bounding rectangle, so covered stays covered.
void merge_plane(std::vector<Rect>& rects) {
    const auto merge_along = [&](bool along_u) {
        std::sort(rects.begin(), rects.end(), [&](const Rect& a, const Rect& b) {
            return along_u ? std::tie(a.v0, a.v1, a.u0, a.u1) < std::tie(b.v0, b.v1, b.u0, b.u1)
                           : std::tie(a.u0, a.u1, a.v0, a.v1) < std::tie(b.u0, b.u1, b.v0, b.v1);
        });
        std::vector<Rect> out;
        for (const Rect& r : rects) {
            if (!out.empty()) {
                Rect& last = out.back();
                const bool same_across =
                    along_u ? (last.v0 == r.v0 && last.v1 == r.v1) : (last.u0 == r.u0 && last.u1 == r.u1);
                if (same_across && along_u && r.u0 <= last.u1) {
                    last.u1 = std::max(last.u1, r.u1);
                    continue;
                }
                if (same_across && !along_u && r.v0 <= last.v1) {
                    last.v1 = std::max(last.v1, r.v1);
                    continue;
                }
            }
            out.push_back(r);
        }
        const bool merged = out.size() < rects.size();
        rects = std::move(out);
        return merged;
    };
    bool merged = true;
    while (merged) {
        const bool a = merge_along(true);
        const bool b = merge_along(false);
        merged = a || b;
    }
}

// Rounds x toward `toward` when the float conversion moved it away (insets must never grow a panel).
float float_inward(double x, bool up) {
    float f = float(x);
    if (up && double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    if (!up && double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
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

std::vector<Aabb> find_panels(const World& world, PanelFigures* figures) {
    PanelFigures fig;
    // Per rectangle, the corners missing from its half-triangles seen so far (bit c: corner c missing, with
    // corner c = (u == u1) + 2 (v == v1)). A rectangle is covered when both halves of one diagonal are in:
    // the halves along a diagonal miss opposite corners (c and c ^ 3).
    std::map<Rect, uint8_t> halves;
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
        Rect r{axis,
               p[0][axis],
               std::min({p[0][ua], p[1][ua], p[2][ua]}),
               std::max({p[0][ua], p[1][ua], p[2][ua]}),
               std::min({p[0][va], p[1][va], p[2][va]}),
               std::max({p[0][va], p[1][va], p[2][va]})};
        if (!(r.u0 < r.u1 && r.v0 < r.v1)) continue;
        uint8_t present = 0;
        bool corners = true;
        for (const glm::vec3& q : p) {
            const bool at_u0 = q[ua] == r.u0, at_u1 = q[ua] == r.u1;
            const bool at_v0 = q[va] == r.v0, at_v1 = q[va] == r.v1;
            if (!(at_u0 || at_u1) || !(at_v0 || at_v1)) corners = false;
            present |= uint8_t(1u << (int(at_u1) + 2 * int(at_v1)));
        }
        if (!corners || std::popcount(present) != 3) continue;  // not half of its bounding rectangle
        halves[r] |= uint8_t(~present & 0xFu);
    }
    std::map<std::pair<int, float>, std::vector<Rect>> planes;
    for (const auto& [r, missing] : halves) {
        if ((missing & 0x9u) == 0x9u || (missing & 0x6u) == 0x6u) {
            ++fig.rectangles;
            planes[{r.axis, r.plane}].push_back(r);
        }
    }
    std::vector<Aabb> out;
    for (auto& [plane, rects] : planes) {
        merge_plane(rects);
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
            q.min[a] = float_inward(double(p.min[a]) + inset_m, true);
            q.max[a] = float_inward(double(p.max[a]) - inset_m, false);
            empty = empty || !(q.min[a] < q.max[a]);
        }
        if (!empty) out.push_back(q);
    }
    return out;
}

}  // namespace pvs
