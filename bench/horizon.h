// SPDX-License-Identifier: MIT
// A measurement of bench_frame (--horizon-cell-eyes, --horizon-faces), not a culler a game gets: the
// occlusion horizon of the C99 runtime (pvsr_horizon, docs/ALGORITHMS.md#runtime-horizon) in plain C++, which
// also tells which occluders each proof used and takes the world's slanted panels exactly as found (the
// runtime takes polygon occluders in their float form), so that the bench can choose the occluders a list per
// cell would hold. Built from every proven box of the bake (their faces towards the eye), panels (rectangles
// covered by opaque triangles) and slanted panels (convex polygons whose prism across a thin slab stops every
// segment that crosses the slab inside it).
//
// Four side frames (+x, -x, +z, -z; y is up): a point x (less the eye) with depth d = s x_p > 0 has the
// direction (u, v) = (x_h / d, x_y / d). Each frame's u in [-1, 1] is cut into N columns. A face (a convex
// polygon that stops every ray crossing it) covers a column over [lo, hi] when every direction of the
// column with v in [lo, hi] crosses it: its projection is convex, so its lower boundary is a convex function
// of u and its upper one concave, and that v range is [the larger lower, the smaller upper] at the column's
// two sides. The column keeps every such PIECE with the face's deepest point over it (a corner: 1 / linear
// is convex). A box is hidden when each of its points lies in some frame's wedge (d >= |x_h|) in columns
// where the pieces lying wholly before the box cover its v range: an exact union in v, so faces meeting
// along a line (a wall on a floor, terrain polygons sharing an edge) fuse, at any distance. Every segment
// from the eye to the box then meets an occluder before its end.
//
// Tolerance: pieces are shrunk by 1e-12 relative for double rounding, and two pieces whose ends are within
// 1e-9 (1 + |v|) of each other count as touching, so "hidden" means: every segment meets an occluder or
// passes within about 1e-9 of the scale of one (the convention of docs/ALGORITHMS.md#runtime-faces).
#pragma once

#include "core/math.h"
#include "core/occluder.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs::bench {

class OcclusionHorizon {
public:
    // columns: per side frame; max_faces: only the nearest so many faces (0: all).
    OcclusionHorizon(int columns, size_t max_faces) : columns_(columns), max_faces_(max_faces) {}

    // Occluder k is boxes[k], then panels[k - boxes], then slanted[k - boxes - panels]; with `only`, just
    // those k with only[k] != 0.
    void build(const glm::dvec3& eye, const std::vector<Aabb>& boxes, const std::vector<Aabb>& panels,
               const std::vector<SlantedPanel>& slanted, const std::vector<uint8_t>* only = nullptr) {
        eye_ = eye;
        faces_.clear();
        const double scale = 1.0 + std::max({std::abs(eye.x), std::abs(eye.y), std::abs(eye.z)});
        const double delta = 1e-5 + 1e-6 * scale, grow = 1e-9 * scale;
        uint32_t source = 0;
        n_sources_ = boxes.size() + panels.size() + slanted.size();
        const auto rect = [&](int axis, double plane, const glm::dvec3& lo, const glm::dvec3& hi) {
            const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            Face f;
            glm::dvec3 c(0.0);
            c[axis] = plane;
            const double l1 = lo[a1] - grow, h1 = hi[a1] + grow, l2 = lo[a2] - grow, h2 = hi[a2] + grow;
            const double q[4][2] = {{l1, l2}, {h1, l2}, {h1, h2}, {l1, h2}};
            for (const auto& k : q) {
                c[a1] = k[0];
                c[a2] = k[1];
                f.a.push_back(c - eye_);
            }
            f.n = glm::dvec3(0.0);
            f.n[axis] = 1.0;
            f.c = plane - eye_[axis];
            f.key = dist_key(lo, hi);
            f.source = source;
            faces_.push_back(std::move(f));
        };
        for (size_t i = 0; i < panels.size(); ++i) {
            const Aabb& p = panels[i];
            source = uint32_t(boxes.size() + i);
            if (only && !(*only)[source]) continue;
            int axis = -1;
            for (int k = 0; k < 3; ++k)
                if (p.min[k] == p.max[k]) axis = axis < 0 ? k : 3;
            if (axis < 0 || axis > 2) continue;
            if (std::abs(eye[axis] - double(p.min[axis])) <= delta) continue;
            rect(axis, p.min[axis], glm::dvec3(p.min), glm::dvec3(p.max));
        }
        for (size_t i = 0; i < boxes.size(); ++i) {
            const Aabb& b = boxes[i];
            source = uint32_t(i);
            if (only && !(*only)[source]) continue;
            for (int axis = 0; axis < 3; ++axis) {
                if (!(b.min[axis] < b.max[axis])) continue;
                if (eye[axis] < double(b.min[axis]) - delta)
                    rect(axis, b.min[axis], glm::dvec3(b.min), glm::dvec3(b.max));
                else if (eye[axis] > double(b.max[axis]) + delta)
                    rect(axis, b.max[axis], glm::dvec3(b.min), glm::dvec3(b.max));
            }
        }
        for (size_t i = 0; i < slanted.size(); ++i) {
            const SlantedPanel& sp = slanted[i];
            source = uint32_t(boxes.size() + panels.size() + i);
            if (only && !(*only)[source]) continue;
            const double s = glm::dot(sp.normal, eye) - sp.offset;
            if (std::abs(s) <= sp.thickness + delta) continue;
            const double side = s > 0.0 ? 1.0 : -1.0;
            Face f;
            for (const glm::dvec3& c : sp.corners) {
                f.a.push_back(c + sp.normal * (side * sp.thickness) - eye_);  // the near cross-section
                f.b.push_back(c - sp.normal * (side * sp.thickness) - eye_);  // the far one
            }
            f.n = sp.normal;
            f.c = sp.offset - side * sp.thickness - glm::dot(sp.normal, eye_);
            f.key = dist_key(glm::dvec3(sp.bounds.min), glm::dvec3(sp.bounds.max));
            f.source = source;
            faces_.push_back(std::move(f));
        }
        std::sort(faces_.begin(), faces_.end(), [](const Face& x, const Face& y) { return x.key < y.key; });
        if (max_faces_ > 0 && faces_.size() > max_faces_) faces_.resize(max_faces_);
        for (int fr = 0; fr < 4; ++fr) {
            build_frame(fr);
            for (Column& c : frames_[fr])
                std::sort(c.pieces.begin(), c.pieces.end(),
                          [](const Piece& x, const Piece& y) { return x.lo < y.lo; });
        }
    }

    // The occluders (as `only` counts them) of the faces the last build() took.
    std::vector<uint8_t> sources() const {
        std::vector<uint8_t> out(n_sources_, 0);
        for (const Face& f : faces_) out[f.source] = 1;
        return out;
    }

    // Is every point of the box behind the horizon (see above)? With `used`, counts (to 255) for the
    // occluders whose pieces the proof took (when it holds).
    bool hides(const Aabb& box, std::vector<uint8_t>* used = nullptr) const {
        taken_.clear();
        const glm::dvec3 lo = glm::dvec3(box.min) - eye_, hi = glm::dvec3(box.max) - eye_;
        for (int fr = 0; fr < 4; ++fr) {
            const int p = fr < 2 ? 0 : 2, hax = fr < 2 ? 2 : 0;
            const double s = (fr & 1) ? -1.0 : 1.0;
            const double d_box_lo = s > 0 ? lo[p] : -hi[p], d_hi = s > 0 ? hi[p] : -lo[p];
            const double h_lo = lo[hax], h_hi = hi[hax];
            const double min_abs_h =
                (h_lo <= 0.0 && h_hi >= 0.0) ? 0.0 : std::min(std::abs(h_lo), std::abs(h_hi));
            const double d_lo = std::max(d_box_lo, min_abs_h);
            if (d_lo > d_hi) continue;  // no point of the box in this frame's wedge
            if (d_lo <= kNear) return false;
            const double u_min = std::max(-1.0, std::min(h_lo / d_lo, h_lo / d_hi));
            const double u_max = std::min(1.0, std::max(h_hi / d_lo, h_hi / d_hi));
            const double v_max = std::max(hi.y / d_lo, hi.y / d_hi),
                         v_min = std::min(lo.y / d_lo, lo.y / d_hi);
            const int k0 = std::clamp(int(std::floor((u_min + 1.0) * 0.5 * columns_)), 0, columns_ - 1);
            const int k1 = std::clamp(int(std::floor((u_max + 1.0) * 0.5 * columns_)), 0, columns_ - 1);
            for (int k = k0; k <= k1; ++k) {
                // [v_min, v_max] covered by the pieces that lie wholly before the box (pieces by lo).
                double cur = v_min;
                bool covered = false;
                for (const Piece& pc : frames_[fr][size_t(k)].pieces) {
                    if (!(d_lo > pc.depth * (1.0 + 1e-9) + 1e-9)) continue;
                    if (pc.lo > cur + 1e-9 * (1.0 + std::abs(cur))) break;  // a gap at cur
                    if (pc.hi > cur) {
                        cur = pc.hi;
                        if (used) taken_.push_back(pc.source);
                    }
                    if (cur > v_max + 1e-12 * (1.0 + std::abs(v_max))) {
                        covered = true;
                        break;
                    }
                }
                if (!covered) return false;
            }
        }
        if (used)
            for (const uint32_t k : taken_) (*used)[k] = uint8_t(std::min(255, (*used)[k] + 1));
        return true;
    }

private:
    static constexpr double kNear = 1e-3;
    struct Face {
        std::vector<glm::dvec3> a,
            b;  // corners less the eye; b: a second polygon whose directions must hold too
        glm::dvec3 n{0.0};
        double c = 0.0;  // the plane of depth: n . x = c (x less the eye)
        double key = 0.0;
        uint32_t source = 0;
    };
    struct Piece {
        double lo, hi, depth;  // every direction of the column with v in [lo, hi] meets a face by depth
        uint32_t source;
    };
    struct Column {
        std::vector<Piece> pieces;  // by lo
    };

    double dist_key(const glm::dvec3& lo, const glm::dvec3& hi) const {
        const glm::dvec3 q = glm::clamp(eye_, lo, hi) - eye_;
        return glm::dot(q, q);
    }

    // The directions (u, v) of the polygon's part at depth >= kNear in frame fr; empty when none.
    std::vector<glm::dvec2> project(int fr, const std::vector<glm::dvec3>& poly) const {
        const int p = fr < 2 ? 0 : 2, hax = fr < 2 ? 2 : 0;
        const double s = (fr & 1) ? -1.0 : 1.0;
        std::vector<glm::dvec2> out;
        const size_t n = poly.size();
        for (size_t i = 0; i < n; ++i) {
            const glm::dvec3 &a = poly[i], &b = poly[(i + 1) % n];
            const double da = s * a[p], db = s * b[p];
            if (da >= kNear) out.push_back({a[hax] / da, a.y / da});
            if ((da >= kNear) != (db >= kNear)) {
                const double t = (kNear - da) / (db - da);
                const glm::dvec3 m = a + (b - a) * t;
                out.push_back({m[hax] / kNear, m.y / kNear});
            }
        }
        return out;
    }

    // The convex polygon a clipped by the convex polygon b (Sutherland-Hodgman; either orientation).
    static std::vector<glm::dvec2> clip(std::vector<glm::dvec2> a, const std::vector<glm::dvec2>& b) {
        double area = 0.0;
        for (size_t i = 0; i < b.size(); ++i) {
            const glm::dvec2 &p = b[i], &q = b[(i + 1) % b.size()];
            area += p.x * q.y - q.x * p.y;
        }
        const double orient = area >= 0.0 ? 1.0 : -1.0;
        for (size_t i = 0; i < b.size() && !a.empty(); ++i) {
            const glm::dvec2 &p = b[i], &q = b[(i + 1) % b.size()];
            const auto side = [&](const glm::dvec2& x) {
                return orient * ((q.x - p.x) * (x.y - p.y) - (q.y - p.y) * (x.x - p.x));
            };
            std::vector<glm::dvec2> out;
            for (size_t j = 0; j < a.size(); ++j) {
                const glm::dvec2 &c = a[j], &d = a[(j + 1) % a.size()];
                const double sc = side(c), sd = side(d);
                if (sc >= 0.0) out.push_back(c);
                if ((sc >= 0.0) != (sd >= 0.0)) out.push_back(c + (d - c) * (sc / (sc - sd)));
            }
            a = std::move(out);
        }
        return a;
    }

    // [lowest, highest] v of the convex polygon on the line u = x; false when the line misses it.
    static bool span_at(const std::vector<glm::dvec2>& poly, double x, double& vlo, double& vhi) {
        vlo = HUGE_VAL;
        vhi = -HUGE_VAL;
        for (size_t i = 0; i < poly.size(); ++i) {
            const glm::dvec2 &a = poly[i], &b = poly[(i + 1) % poly.size()];
            if ((a.x - x) * (b.x - x) > 0.0) continue;
            double v;
            if (a.x == b.x) {
                vlo = std::min({vlo, a.y, b.y});
                vhi = std::max({vhi, a.y, b.y});
                continue;
            }
            v = a.y + (b.y - a.y) * ((x - a.x) / (b.x - a.x));
            vlo = std::min(vlo, v);
            vhi = std::max(vhi, v);
        }
        return vlo <= vhi;
    }

    void build_frame(int fr) {
        std::vector<Column>& cols = frames_[fr];
        cols.assign(size_t(columns_), Column{});
        const int p = fr < 2 ? 0 : 2, hax = fr < 2 ? 2 : 0;
        const double s = (fr & 1) ? -1.0 : 1.0;
        for (const Face& f : faces_) {
            std::vector<glm::dvec2> poly = project(fr, f.a);
            if (poly.size() < 3) continue;
            if (!f.b.empty()) {
                const std::vector<glm::dvec2> pb = project(fr, f.b);
                if (pb.size() < 3) continue;
                poly = clip(poly, pb);
                if (poly.size() < 3) continue;
            }
            double umin = HUGE_VAL, umax = -HUGE_VAL;
            for (const glm::dvec2& q : poly) {
                umin = std::min(umin, q.x);
                umax = std::max(umax, q.x);
            }
            // Columns wholly inside [umin, umax], shrunk by a rounding margin.
            const double m = 1e-12 * (1.0 + std::max(std::abs(umin), std::abs(umax)));
            const int k0 = std::max(0, int(std::ceil((umin + m + 1.0) * 0.5 * columns_)));
            const int k1 = std::min(columns_ - 1, int(std::floor((umax - m + 1.0) * 0.5 * columns_)) - 1);
            for (int k = k0; k <= k1; ++k) {
                Column& c = cols[size_t(k)];
                const double u0 = -1.0 + 2.0 * k / columns_, u1 = -1.0 + 2.0 * (k + 1) / columns_;
                double lo0, hi0, lo1, hi1;
                if (!span_at(poly, u0, lo0, hi0) || !span_at(poly, u1, lo1, hi1)) continue;
                const double lo = std::max(lo0, lo1), hi = std::min(hi0, hi1);
                const double r = 1e-12 * (1.0 + std::abs(lo) + std::abs(hi));  // double rounding
                if (!(hi - r > lo + r)) continue;
                // The deepest point of the face over the column's [lo, hi]: a corner (1 / linear is convex).
                double deepest = 0.0;
                bool ok = true;
                for (const double u : {u0, u1})
                    for (const double v : {lo, hi}) {
                        glm::dvec3 dir(0.0);
                        dir[p] = s;
                        dir[hax] = u;
                        dir.y = v;
                        const double den = glm::dot(f.n, dir);
                        if (std::abs(den) < 1e-300) {
                            ok = false;
                            continue;
                        }
                        const double t = f.c / den;
                        if (!(t > 0.0)) ok = false;
                        deepest = std::max(deepest, t);
                    }
                if (!ok) continue;
                c.pieces.push_back({lo + r, hi - r, deepest * (1.0 + 1e-9), f.source});
            }
        }
    }

    mutable std::vector<uint32_t> taken_;
    size_t n_sources_ = 0;
    int columns_;
    size_t max_faces_;
    glm::dvec3 eye_{0.0};
    std::vector<Face> faces_;
    std::vector<Column> frames_[4];
};

}  // namespace pvs::bench
