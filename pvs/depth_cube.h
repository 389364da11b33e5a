// SPDX-License-Identifier: MIT
// pvsbake solver: a conservative from-point occlusion test on a depth cube map around an eye point s.
//
// This is the from-point test of occluder shrinking (Wonka, Wimmer, Schmalstieg 2000; the caller passes the
// ε-shrunk occluders). Why each rule below is safe: docs/ALGORITHMS.md#depth-cube. Occluders are axis-aligned
// boxes, flat rectangles (panels) and convex polygons in other planes (slanted panels); occludees are boxes.
// Pure CPU, no Embree. DepthCube is the fast kernel; is_hidden_reference() is the plain reference of the SAME
// rules, and tests/test_depth_cube.cpp and tests/test_depth_cube_slanted.cpp run both on fixed seeds and
// assert identical answers.
//
// Conventions (read these before touching the code; Masked Occlusion Culling style):
// - Axes: glTF world axes (right-handed, +Y up, metres). Everything is relative to the eye:
//   Δ = p - eye.
// - Faces, in this order: 0 = +X, 1 = -X, 2 = +Y, 3 = -Y, 4 = +Z, 5 = -Z. Face f has axis a = f / 2 and
//   sign s = +1 for even f, -1 for odd f. Its other axes are ua = (a + 1) % 3 and va = (a + 2) % 3.
// - Depth of a point on face f: d = s * Δ[a], the z-buffer distance along the face normal (not the
//   Euclidean distance). Larger depth = farther. Along any ray of the face, depth grows with distance,
//   so "nearer in depth" means "earlier on the ray".
// - Face coordinates: u = Δ[ua] / d, v = Δ[va] / d. No per-face mirroring (this is NOT the OpenGL cube map
//   layout; nothing here cares about handedness). A direction belongs to face f when
//   s * Δ[a] >= max(|Δ[ua]|, |Δ[va]|), i.e. its largest |component|. The cones are CLOSED: a direction on a
//   cube edge or corner belongs to every tied face, and both faces are checked (no tie breaking is needed,
//   because every rule below is conservative on each face separately).
// - Pixels: R = resolution pixels per face edge. Pixel (i, j) of a face is the closed square
//   u in [g(i), g(i + 1)], v in [g(j), g(j + 1)], with g(k) = -1 + 2k / R evaluated in double (the
//   definition of the grid, used by both the kernel and the reference). Neighbouring pixels share edges.
//   Storage index: face * R * R + j * R + i.
// - Near plane: d = kCubeNearPlane_m on every face. An empty pixel holds +infinity.
// - Occluder pixel rule (writing less is always safe): an occluder box writes pixel P of face f when each
//   of P's four corner rays, taken over depths t in [kCubeNearPlane_m, +inf), passes through the box with
//   room to spare (exit >= entry * (1 + kCubeDepthSlack)). The depth written is
//   max over the four corners of entry * (1 + kCubeDepthSlack), rounded UP to float. The pixel keeps the
//   minimum over occluders. Boxes containing the eye (closed) write nothing. A box crossing the near plane
//   is clipped to d >= near (a sub-box), not dropped. Every ray through a written pixel meets the box at a
//   depth no larger than the pixel's: the max of the four corner entry depths is exact, not only safe
//   (docs/ALGORITHMS.md#depth-cube); the slack covers rounding (doubles err by ~1e-16 relative).
// - Occludee rule (touching more is always safe): a box is visible (is_hidden returns false) when it is
//   empty, not finite, or meets the closed cube [eye - near, eye + near] (this covers "contains the eye"
//   and "reaches the near plane of a face inside that face's cone"). Otherwise, on each face f, let
//   L_f = max(d_min, dist(0, [Δu_lo, Δu_hi]), dist(0, [Δv_lo, Δv_hi]), near): exactly the smallest depth of
//   the box's part inside face f's cone (the part is empty when L_f > d_max: the face is skipped). The
//   touched pixels are those whose closed square meets the bounding rectangle of the projection of
//   box ∩ {L_f <= d <= d_max}, widened by 1e-9 (relative) and clamped to [-1, 1]^2.
// - The conservative comparison: the box is hidden only if, on every face and at every touched pixel,
//   stored_depth < L_f * (1 - kCubeDepthSlack) (STRICTLY nearer). Equal depths count as visible; an empty
//   pixel (+inf) is visible.
// - "Conservative" here: if is_hidden(box) is true, then every segment from the eye to any point x of the
//   box meets some single occluder (box, or panel as drawn) at a depth strictly smaller than x's depth, i.e.
//   before x (proof: docs/ALGORITHMS.md#depth-cube). Fusion of occluders happens on the depth buffer:
//   different occluders may cover different pixels of the same occludee.
// - Depth bands (set_panel_bands(true); docs/ALGORITHMS.md#depth-bands): besides its depth D, a pixel may
//   keep one band (N, F], depths where every point is hidden too (near a panel's plane, where only a share
//   of its inset is needed). Then a pixel passes the comparison also when N < L_f * (1 - kCubeDepthSlack) and either
//   d_max * (1 + kCubeDepthSlack) <= F or D <= F (the band and the depth together hide all beyond N).
#pragma once

#include "core/math.h"
#include "core/occluder.h"

#include <array>
#include <utility>
#include <vector>

namespace pvs {

// Near plane of every face, metres along the face axis.
inline constexpr double kCubeNearPlane_m = 1e-4;
// Relative safety margin on depths and on "the ray passes through the box" (covers rounding).
inline constexpr double kCubeDepthSlack = 1e-6;
// A slanted panel's slab is grown, and its polygon's edges moved inward, by this much (metres) before it is
// drawn: covers the rounding of its corners and of the tests.
inline constexpr double kSlantedPanelMarginM = 1e-4;
// Resolution limits (pixels per face edge).
inline constexpr int kMinCubeResolution = 1;
inline constexpr int kMaxCubeResolution = 4096;

// A depth cube map around one eye point. Owns its buffers; reuse one per thread across eye samples
// (clear() keeps the allocation). Not thread-safe for writes; is_hidden() is const and may be called from
// several threads once the occluders are in.
class DepthCube {
public:
    // resolution: pixels per face edge [Limit: kMinCubeResolution..kMaxCubeResolution], e.g. 32..256.
    // Throws pvs::Error (kBadInput) outside the limits.
    explicit DepthCube(int resolution);

    // Moves the eye and resets every pixel to "no occluder" (+infinity); occluders will be drawn on all
    // pixels.
    void clear(glm::vec3 eye);
    // Occluders will only be drawn on the pixels that these boxes touch (the bounding pixel rectangle per
    // face of the occludee rule's touched pixels), until the next clear(). Pixels left out stay +infinity,
    // which is always the safe side; use it when only these boxes will be tested (adaptive refinement
    // tests few objects on fine patches).
    void limit_to(const std::vector<Aabb>& boxes);
    // clear() then limit_to(), resetting only the pixels of the limited region: the cost of a clear grows
    // with the region, not with 6 R^2, so a fine cube (R = 256 and more) tested on a few boxes stays cheap.
    // Pixels outside the region keep stale depths, which is_hidden() never reads: a box touching a pixel
    // outside the region is visible (as after limit_to(), where they are +infinity).
    void clear_for(glm::vec3 eye, const std::vector<Aabb>& boxes);
    // Rasterizes one occluder box (see the pixel rule above). Empty or non-finite boxes are ignored.
    void add_occluder(const Aabb& box);
    // Rasterizes one PANEL (occluders/panels.h: a rectangle flat along exactly one axis, else ignored) for
    // every eye in the EYE BOX around the cube's eye s: the points q with |q_k - s_k| <= spread[k] on each
    // axis k (metres, >= 0; a zero spread is s alone). Only on the face along its normal that looks at it,
    // where its plane has the constant depth t = |plane - s|: a pixel whose four corner rays cross the
    // plane inside the rectangle inset per corner ray gets t (1 + slack), rounded up to float. The inset of
    // a corner ray of face coordinates (u, v) is b_u + b_n |u| on the u axis and b_v + b_n |v| on the v axis,
    // with b = spread (1 + 1e-9) + 1e-9 t per axis (the margin covers rounding) and n the normal's axis: a
    // column passes when lo_u + b_u + b_n |u| <= t u <= hi_u - b_u - b_n |u|, an interval of u solved once
    // per panel (its ends checked with this very test), so the passing columns and rows are two runs. Panels
    // whose plane is within the near plane, or within the eye box (spread[n] (1 + 1e-6)), are ignored.
    // Guarantee: if x lies beyond the plane (depth > t) in the direction of a written pixel, then for every
    // q in the eye box the segment q -> x crosses the (uninset) rectangle. The inset bound, and why testing
    // the pixel's corners is exact: docs/ALGORITHMS.md#panel-inset.
    void add_panel(const Aabb& panel, glm::dvec3 spread = glm::dvec3(0.0));
    void add_panels(const std::vector<Aabb>& panels, glm::dvec3 spread = glm::dvec3(0.0));
    // The same panel on the four SIDE faces, those whose axis lies in its plane (rays more than 45 degrees
    // from its normal), by the same per-ray bound with the ray's TANGENTS relative to the normal in place
    // of the face coordinates: along the face axis +-1 / g_m, along the other in-plane axis g_n / g_m, where
    // g_m is the face coordinate along the panel's normal and g_n the other one (both > 1 in size towards
    // grazing rays, so the inset grows there). A vertex passes when its ray reaches the plane ahead (at
    // parameter, and depth, h / g_m, h the plane's signed height above the eye) and each tangent p along an
    // in-plane axis k lies in the interval where lo + b_k + b_n |p| <= h p <= hi - b_k - b_n |p| (b the
    // spread plus rounding margins; both sides concave in p). A pixel whose four vertices pass gets the
    // larger crossing depth of its two majors times (1 + slack), rounded up. The vertices decide
    // (docs/ALGORITHMS.md#panel-inset); separable: per major value a contiguous range of minors.
    void add_panel_sides(const Aabb& panel, glm::dvec3 spread);
    void add_panels_sides(const std::vector<Aabb>& panels, glm::dvec3 spread);
    // DEPTH BANDS of add_panel() and add_panel_sides() (off until set; docs/ALGORITHMS.md#depth-bands): for
    // a point x beyond the plane at height h_x past it, what a segment from the eye box to x may stray from
    // the eye's own crossing is the inset times the SHARE h_x / (h_x + |h| - b_n) < 1 (|h| the plane's height
    // above the eye, b_n the box's half-extent along the normal). A vertex whose corner ray fails a panel's
    // rule has, per in-plane axis k with tangent p, the share (dist - m) / w (1 - 1e-9), where dist is how
    // far inside [lo, hi] the ray crosses, w = (spread_k + spread_n |p|) (1 + 1e-9) and m = 4e-9 |h| (1 +
    // |p|); 0 when dist <= m; 1 on an axis whose rule it passes; its share is the least over both axes, held
    // below 1 - 1e-6. A pixel that the panel does not write and whose four vertices have shares f > 0 (f the
    // least) keeps the band (N, F] with N its depth as the rule would write it and
    // F = (|h| + f (|h| - b_n) / (1 - f)) / g (1 - 1e-6), rounded down to float, g the largest |tangent along
    // the normal| of its vertices (1 on the face along the normal), when F > N; a pixel keeps one band: the
    // union of the two when a new band overlaps or touches it, else the one of larger F (then of smaller N),
    // so what it keeps depends on the order panels are drawn in. Guarantee: if x lies in the direction of
    // such a pixel at a depth in (N, F], every segment from the eye box to x crosses the panel.
    void set_panel_bands(bool on);
    // Rasterizes one CORNER PAIR: two panels `a` and `b` (flat along different axes n_a and n_b, planes at
    // c_a and c_b) that meet along the line x[n_a] = c_a, x[n_b] = c_b: a's extent along n_b holds c_b, b's
    // extent along n_a holds c_a, and their extents along the third axis overlap. With the EYE BOX strictly
    // on one side of each plane (as add_panel()), each panel is cut at the line to its part on the eye box's
    // side of the other's plane (the CONCAVE corner; failing that, to its part beyond it, the CONVEX corner)
    // and extended across the line without end; a ray from the box that crosses both extended rectangles
    // crosses one of the cut panels (docs/ALGORITHMS.md#corner-pairs). Drawn on the two faces along the
    // panels' normals, where each extended panel has add_panel()'s rule on one and add_panel_sides()'s on the
    // other, read per line of constant value of the other normal's face coordinate (the MAJOR): a row of
    // pixels between two majors is drawn when both majors pass both extended panels and, for each panel, one
    // fails the panel's own rule (where both pass it, that panel alone covers the row's pixels at no greater
    // depth); a pixel of it whose two minors pass both panels at both majors gets the larger crossing depth
    // of its four vertices, times (1 + slack), rounded up. Ignored when the panels do not meet so, or
    // neither corner applies.
    void add_corner(const Aabb& a, const Aabb& b, glm::dvec3 spread);
    // Rasterizes one SLANTED PANEL (core/occluder.h: a convex polygon tiled by opaque triangles within a slab
    // |n.x - offset| <= thickness) for every eye in the EYE BOX around s (as add_panel()), on every face. Let
    // N be the unit normal towards s, and h_near < h_far the heights of s above the slab's two faces, the
    // slab grown by kSlantedPanelMarginM. A grid vertex with ray direction d (+-1 on the face axis) passes
    // when w = -N.d > 0 and, for each edge i of the polygon (inward unit normal m_i in the plane, line
    // m_i.x = k_i moved inward by kSlantedPanelMarginM), at both heights h:
    //     (m_i.s - k_i - a_i) w + h (m_i.d) - b_n |m_i.d| >= 0,
    // a_i = sum_k |m_ik| spread_k and b_n = sum_k |n_k| spread_k (each times 1 + 1e-9): the ray crosses both
    // faces inside the polygon inset by the eye box's per-ray bound. A pixel whose four vertices pass gets
    // the largest of their far-face crossing depths h_far / w, times (1 + slack), rounded up. Ignored when
    // the eye box reaches the grown slab (h_near <= b_n (1 + 1e-6)). Guarantee: if x lies beyond that depth
    // in the direction of a written pixel, then for every q in the eye box the segment q -> x crosses the
    // slab over the polygon, so meets an opaque triangle before x. Why, and why the vertices decide:
    // docs/ALGORITHMS.md#slanted-inset.
    void add_slanted_panel(const SlantedPanel& panel, glm::dvec3 spread);
    // All of them, nearest first, skipping each panel whose bounds the occluders drawn so far already hide
    // (drawing fewer is always safe).
    void add_slanted_panels(const std::vector<SlantedPanel>& panels, glm::dvec3 spread);
    // The same for panels[i], i in `which`.
    void add_slanted_panels(const std::vector<SlantedPanel>& panels, const std::vector<uint32_t>& which,
                            glm::dvec3 spread);
    // Rasterizes all the boxes, nearest first, skipping each box the ones before already hide (it could not
    // lower any pixel). Same depths as add_occluder() on every box, in far less time behind walls.
    void add_occluders(const std::vector<Aabb>& boxes);
    // True only if the box is certainly hidden from the eye by the occluders added so far (with the bands,
    // when they are on).
    bool is_hidden(const Aabb& box) const;

    int resolution() const { return resolution_; }
    glm::vec3 eye() const { return eye_; }
    // Stored depth of pixel (i, j) of a face (+infinity when no occluder covers it).
    float depth(int face, int i, int j) const {
        return depth_[(size_t(face) * resolution_ + j) * resolution_ + i];
    }
    // Pixels that hold an occluder (for tests and statistics).
    size_t covered_pixel_count() const;

private:
    int resolution_;
    glm::vec3 eye_{0.0f};
    std::vector<float> depth_;                    // 6 * R * R, index face * R * R + j * R + i
    bool panel_bands_ = false;
    // Per pixel as depth_: the band (near, far] of depth bands, empty when far = 0.
    std::vector<float> band_near_, band_far_;
    std::vector<double> share_u_, share_v_;  // scratch of add_panel(): per vertex, its share on u / on v
    // is_hidden() by the depths alone: the test of the occluders skipped as already hidden (a box hidden
    // only through a band could still lower a depth).
    bool is_hidden_by_depths(const Aabb& box) const;
    template <bool kBands>
    bool hidden_test(const Aabb& box) const;
    void keep_band(int face, int i, int j, float near, float far);
    std::vector<double> band_major_share_;     // scratch of add_panel_sides()'s bands: per major, its share
    std::vector<int> band_first_, band_last_;  // and its run of minors inside the panel's own span
    std::array<std::array<int, 4>, 6> region_{};  // per face: pixels i0, i1, j0, j1 occluders are drawn on
    // Scratch of add_occluder(), reused: per grid vertex of a column / row, the slab interval of the ray
    // parameter (depth) on the u / v axis; and the corner depths of two vertex rows.
    std::vector<std::pair<float, uint32_t>> order_;  // scratch of add_occluders()
    std::vector<double> col_enter_, col_exit_, row_enter_, row_exit_, corner_prev_, corner_cur_;
    std::vector<int> side_first_, side_last_;  // scratch of add_panel_sides(): per major, its minor range
    std::vector<double> grid_;                 // grid(k) for k = 0..R
    std::vector<std::pair<float, uint32_t>> slanted_order_;  // scratch of add_slanted_panels()
};

// The plain reference of the same rules: for every pixel of every face, brute force "is it touched", and
// for touched pixels the minimum over all occluders of the four-corner slab tests. Slow (O(6 R^2 * N)); for
// the differential test and the benchmark ratio only.
bool is_hidden_reference(const std::vector<Aabb>& occluders, glm::vec3 eye, const Aabb& box, int resolution);
// The same with panels (add_panel(panel, panel_spread), and add_panel_sides() too when panel_sides),
// slanted panels (add_slanted_panel(panel, panel_spread), all of them) and corner pairs
// (add_corner(pair[0], pair[1], panel_spread)) besides the boxes.
bool is_hidden_reference(const std::vector<Aabb>& occluders, const std::vector<Aabb>& panels,
                         glm::dvec3 panel_spread, glm::vec3 eye, const Aabb& box, int resolution,
                         bool panel_sides = false, const std::vector<SlantedPanel>& slanted = {},
                         const std::vector<std::array<Aabb, 2>>& corners = {}, bool panel_bands = false);

}  // namespace pvs
