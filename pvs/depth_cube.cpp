// SPDX-License-Identifier: MIT
// Conservative depth cube map: occluder boxes written where they cover whole pixels, occludee boxes tested
// against every pixel they touch. Conventions: depth_cube.h; the safety argument:
// docs/ALGORITHMS.md#depth-cube and docs/ALGORITHMS.md#panel-inset.
//
// After: P. Wonka, M. Wimmer, D. Schmalstieg. Visibility Preprocessing with Occluder Fusion for Urban
// Walkthroughs. EGWR 2000 (the from-point test on shrunk occluders); H. Zhang et al. Visibility Culling
// using Hierarchical Occlusion Maps, SIGGRAPH 1997 (conservative depth comparisons on an occlusion map).
#include "pvs/depth_cube.h"

#include "core/error.h"
#include "occluders/panels.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define PVS_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PVS_AVX2_CLONES
#endif

namespace pvs {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr float kInfF = std::numeric_limits<float>::infinity();
// Widening of the occludee's projected rectangle, relative to max(1, |u|): covers rounding of Δu / d.
constexpr double kRectPad = 1e-9;

// The pixel grid: edge k of R along u or v. THE definition, shared by kernel and reference.
inline double grid(int k, int r) {
    return -1.0 + 2.0 * double(k) / double(r);
}

// Round a non-negative finite double up to a float (larger stored depth is the safe side). The next float up
// of a positive finite float is the one whose bits are one more (IEEE 754 orders positive floats as their
// bit patterns); much cheaper than std::nextafter.
inline float float_up(double x) {
    const float f = float(x);
    return std::bit_cast<float>(std::bit_cast<uint32_t>(f) + uint32_t(double(f) < x));
}

// The box relative to the eye, in face f's axes (double; differences of floats are exact in practice).
struct FaceBox {
    double d_min, d_max;  // depth range along the face axis
    double u_lo, u_hi;    // Δ[ua] range
    double v_lo, v_hi;    // Δ[va] range
};

// A box relative to the eye, per world axis (the differences computed once for all six faces).
struct EyeBox {
    double lo[3], hi[3];
};

inline EyeBox eye_box(const Aabb& box, glm::vec3 eye) {
    EyeBox e;
    for (int k = 0; k < 3; ++k) {
        e.lo[k] = double(box.min[k]) - double(eye[k]);
        e.hi[k] = double(box.max[k]) - double(eye[k]);
    }
    return e;
}

inline FaceBox face_box(const EyeBox& e, int face) {
    const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    FaceBox fb;
    if (face % 2 == 0) {
        fb.d_min = e.lo[a];
        fb.d_max = e.hi[a];
    } else {
        fb.d_min = -e.hi[a];
        fb.d_max = -e.lo[a];
    }
    fb.u_lo = e.lo[ua];
    fb.u_hi = e.hi[ua];
    fb.v_lo = e.lo[va];
    fb.v_hi = e.hi[va];
    return fb;
}

FaceBox face_box(const Aabb& box, glm::vec3 eye, int face) {
    return face_box(eye_box(box, eye), face);
}

// Distance from 0 to the interval [lo, hi].
inline double dist_to_zero(double lo, double hi) {
    return std::max({0.0, lo, -hi});
}

// Interval of ray depths t with lo <= t * c <= hi (c is the ray direction's component); empty as [inf, -inf].
inline void slab(double lo, double hi, double c, double& enter, double& exit) {
    if (c > 0.0) {
        enter = lo / c;
        exit = hi / c;
    } else if (c < 0.0) {
        enter = hi / c;
        exit = lo / c;
    } else if (lo <= 0.0 && 0.0 <= hi) {
        enter = -kInf;
        exit = kInf;
    } else {
        enter = kInf;
        exit = -kInf;
    }
}

// slab() for the grid values g(k), k = k0..k1, branch-free so that it vectorizes (the same divisions, so
// the same values; the quotients of a lane with g = 0 are computed and not used).
inline void slabs(double lo, double hi, int k0, int k1, int r, double* __restrict enter,
                  double* __restrict exit) {
    const bool inside = lo <= 0.0 && 0.0 <= hi;
    const double zero_enter = inside ? -kInf : kInf, zero_exit = inside ? kInf : -kInf;
    for (int k = k0; k <= k1; ++k) {
        const double c = grid(k, r);
        const double a = lo / c, b = hi / c;
        enter[k] = c > 0.0 ? a : (c < 0.0 ? b : zero_enter);
        exit[k] = c > 0.0 ? b : (c < 0.0 ? a : zero_exit);
    }
}

inline bool box_usable(const Aabb& box) {
    return !box.is_empty() && is_finite(box.min) && is_finite(box.max);
}

// Candidate grid vertices along one face axis for a shape whose projection spans [x0, x1] there: those of
// the region's pixels reg_lo..reg_hi within it, one vertex of slack each side (the test at the vertices
// decides, so extra candidates change nothing, and the slack absorbs rounding). False when fewer than two
// vertices remain (no whole pixel).
inline bool candidate_vertices(double x0, double x1, int reg_lo, int reg_hi, int r, int& v0, int& v1) {
    if (x0 > 1.0 || x1 < -1.0) return false;
    v0 = std::max(std::max(0, int(std::floor((std::max(x0, -1.0) + 1.0) * 0.5 * r)) - 1), reg_lo);
    v1 = std::min(std::min(r, int(std::ceil((std::min(x1, 1.0) + 1.0) * 0.5 * r)) + 1), reg_hi + 1);
    return v1 - v0 >= 1;
}

// The bounding rectangle, in face coordinates, of the projection of a box's part at depths [d_lo, d_max]
// (a product set, so each extreme is reached at a corner: the depth that pushes u outward).
inline void projected_rect(const FaceBox& fb, double d_lo, double& u0, double& u1, double& v0, double& v1) {
    u0 = fb.u_lo >= 0.0 ? fb.u_lo / fb.d_max : fb.u_lo / d_lo;
    u1 = fb.u_hi >= 0.0 ? fb.u_hi / d_lo : fb.u_hi / fb.d_max;
    v0 = fb.v_lo >= 0.0 ? fb.v_lo / fb.d_max : fb.v_lo / d_lo;
    v1 = fb.v_hi >= 0.0 ? fb.v_hi / d_lo : fb.v_hi / fb.d_max;
}

// A box's candidate vertices on one face: the bounding rectangle of the projection of its part beyond the
// near plane (box ∩ {d >= d_lo}, clipping being safe: a sub-box), as vertices of the region's pixels
// (candidate_vertices()). False when no whole pixel can be written.
struct FaceCandidates {
    FaceBox fb;
    double d_lo = 0.0;
    int iv0 = 0, iv1 = -1, jv0 = 0, jv1 = -1;
};

inline bool face_candidates(const Aabb& box, glm::vec3 eye, int face, const std::array<int, 4>& reg, int r,
                            FaceCandidates& out) {
    out.fb = face_box(box, eye, face);
    out.d_lo = std::max(out.fb.d_min, kCubeNearPlane_m);
    if (out.d_lo > out.fb.d_max) return false;
    double u0, u1, v0, v1;
    projected_rect(out.fb, out.d_lo, u0, u1, v0, v1);
    return candidate_vertices(u0, u1, reg[0], reg[1], r, out.iv0, out.iv1) &&
           candidate_vertices(v0, v1, reg[2], reg[3], r, out.jv0, out.jv1);
}

inline bool meets_near_cube(const Aabb& box, glm::vec3 eye) {
    for (int k = 0; k < 3; ++k) {
        if (double(box.max[k]) - double(eye[k]) < -kCubeNearPlane_m) return false;
        if (double(box.min[k]) - double(eye[k]) > kCubeNearPlane_m) return false;
    }
    return true;
}

// The occludee's per-face rule (depth_cube.h): lower depth bound and the touched pixel range on the face.
struct OccludeeFace {
    bool touched = false;
    double limit = 0.0;  // stored depth must be < limit
    double far = 0.0;    // or a band must hold the depths from limit to far (depth bands)
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
};

// Smallest pixel index i in [0, r - 1] whose closed span [g(i), g(i + 1)] reaches up to lo (g(i + 1) >= lo).
// g is the table of grid(k, r), k = 0..r.
inline int first_pixel_reaching(double lo, int r, const double* g) {
    int i = std::clamp(int(std::floor((lo + 1.0) * 0.5 * r)), 0, r - 1);
    while (i > 0 && g[i] >= lo) --i;
    while (i < r - 1 && g[i + 1] < lo) ++i;
    return i;
}

// Largest pixel index i in [0, r - 1] with g(i) <= hi.
inline int last_pixel_reaching(double hi, int r, const double* g) {
    int i = std::clamp(int(std::floor((hi + 1.0) * 0.5 * r)), 0, r - 1);
    while (i < r - 1 && g[i + 1] <= hi) ++i;
    while (i > 0 && g[i] > hi) --i;
    return i;
}

inline double pad_low(double x) {
    return std::clamp(x - kRectPad * std::max(1.0, std::abs(x)), -1.0, 1.0);
}
inline double pad_high(double x) {
    return std::clamp(x + kRectPad * std::max(1.0, std::abs(x)), -1.0, 1.0);
}

OccludeeFace occludee_face(const EyeBox& e, int face, int r, const double* g) {
    OccludeeFace of;
    const FaceBox fb = face_box(e, face);
    const double lower = std::max(
        {fb.d_min, dist_to_zero(fb.u_lo, fb.u_hi), dist_to_zero(fb.v_lo, fb.v_hi), kCubeNearPlane_m});
    if (lower > fb.d_max) return of;  // no part of the box in this face's cone
    // Bounding rectangle of the projection of the box restricted to depths [lower, d_max] (a product set,
    // so each extreme is reached at a corner: pick the depth that pushes u outward).
    const double u0 = fb.u_lo >= 0.0 ? fb.u_lo / fb.d_max : fb.u_lo / lower;
    const double u1 = fb.u_hi >= 0.0 ? fb.u_hi / lower : fb.u_hi / fb.d_max;
    const double v0 = fb.v_lo >= 0.0 ? fb.v_lo / fb.d_max : fb.v_lo / lower;
    const double v1 = fb.v_hi >= 0.0 ? fb.v_hi / lower : fb.v_hi / fb.d_max;
    of.i0 = first_pixel_reaching(pad_low(u0), r, g);
    of.i1 = last_pixel_reaching(pad_high(u1), r, g);
    of.j0 = first_pixel_reaching(pad_low(v0), r, g);
    of.j1 = last_pixel_reaching(pad_high(v1), r, g);
    of.touched = of.i0 <= of.i1 && of.j0 <= of.j1;
    of.limit = lower * (1.0 - kCubeDepthSlack);
    of.far = fb.d_max * (1.0 + kCubeDepthSlack);
    return of;
}

}  // namespace

DepthCube::DepthCube(int resolution) : resolution_(resolution) {
    if (resolution < kMinCubeResolution || resolution > kMaxCubeResolution) {
        throw bad_input("DepthCube: resolution " + std::to_string(resolution) + " is outside [" +
                        std::to_string(kMinCubeResolution) + ", " + std::to_string(kMaxCubeResolution) +
                        "] pixels per face edge");
    }
    depth_.assign(size_t(6) * resolution_ * resolution_, kInfF);
    for (auto* v : {&col_enter_, &col_exit_, &row_enter_, &row_exit_, &corner_prev_, &corner_cur_}) {
        v->resize(size_t(resolution_) + 1);
    }
    side_first_.resize(size_t(resolution_) + 1);
    grid_.resize(size_t(resolution_) + 1);
    for (int k = 0; k <= resolution_; ++k) grid_[size_t(k)] = grid(k, resolution_);
    side_last_.resize(size_t(resolution_) + 1);
    band_major_share_.resize(size_t(resolution_) + 1);
    band_first_.resize(size_t(resolution_) + 1);
    band_last_.resize(size_t(resolution_) + 1);
}

void DepthCube::set_panel_bands(bool on) {
    panel_bands_ = on;
    if (on && band_near_.size() != depth_.size()) {
        band_near_.assign(depth_.size(), kInfF);
        band_far_.assign(depth_.size(), 0.0f);
    }
}

void DepthCube::clear(glm::vec3 eye) {
    eye_ = eye;
    std::fill(depth_.begin(), depth_.end(), kInfF);
    if (panel_bands_) {
        std::fill(band_near_.begin(), band_near_.end(), kInfF);
        std::fill(band_far_.begin(), band_far_.end(), 0.0f);
    }
    for (auto& r : region_) r = {0, resolution_ - 1, 0, resolution_ - 1};
}

void DepthCube::clear_for(glm::vec3 eye, const std::vector<Aabb>& boxes) {
    eye_ = eye;
    limit_to(boxes);
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        const auto& reg = region_[size_t(face)];
        for (int j = reg[2]; j <= reg[3]; ++j) {
            const size_t row = (size_t(face) * r + size_t(j)) * r;
            std::fill(depth_.data() + row + reg[0], depth_.data() + row + reg[1] + 1, kInfF);
            if (panel_bands_) {
                std::fill(band_near_.data() + row + reg[0], band_near_.data() + row + reg[1] + 1, kInfF);
                std::fill(band_far_.data() + row + reg[0], band_far_.data() + row + reg[1] + 1, 0.0f);
            }
        }
    }
}

void DepthCube::limit_to(const std::vector<Aabb>& boxes) {
    const int r = resolution_;
    for (auto& reg : region_) reg = {r, -1, r, -1};
    for (const Aabb& box : boxes) {
        if (!box_usable(box) || meets_near_cube(box, eye_)) {
            for (auto& reg : region_) reg = {0, r - 1, 0, r - 1};  // tested as visible anyway; stay simple
            return;
        }
        const EyeBox rel = eye_box(box, eye_);
        for (int face = 0; face < 6; ++face) {
            const OccludeeFace of = occludee_face(rel, face, r, grid_.data());
            if (!of.touched) continue;
            auto& reg = region_[size_t(face)];
            reg = {std::min(reg[0], of.i0), std::max(reg[1], of.i1), std::min(reg[2], of.j0),
                   std::max(reg[3], of.j1)};
        }
    }
}

size_t DepthCube::covered_pixel_count() const {
    return size_t(std::count_if(depth_.begin(), depth_.end(), [](float d) { return d < kInfF; }));
}

// Built twice, for AVX2 and for plain x86-64, and chosen when the program loads (GCC target_clones): the
// pixel loops vectorize four doubles wide with AVX2. Same arithmetic, same results.
PVS_AVX2_CLONES void DepthCube::add_occluder(const Aabb& box) {
    if (!box_usable(box) || box.contains(eye_)) return;
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        // Candidate vertices: a pixel whose four corners hit lies in the projection of box ∩ {d >= d_lo},
        // only the region's pixels (limit_to()).
        FaceCandidates fc;
        if (!face_candidates(box, eye_, face, region_[size_t(face)], r, fc)) continue;
        const FaceBox& fb = fc.fb;
        const double d_lo = fc.d_lo;
        const int iv0 = fc.iv0, iv1 = fc.iv1, jv0 = fc.jv0, jv1 = fc.jv1;

        // Separable slab test: a corner ray (u, v, 1) (depth-parameterized) enters at
        // max(d_lo, enter_u(u), enter_v(v)) and leaves at min(d_max, exit_u(u), exit_v(v)).
        slabs(fb.u_lo, fb.u_hi, iv0, iv1, r, col_enter_.data(), col_exit_.data());
        slabs(fb.v_lo, fb.v_hi, jv0, jv1, r, row_enter_.data(), row_exit_.data());

        float* const face_depth = depth_.data() + size_t(face) * r * r;
        // Corner depths of vertex row jv (+inf where the corner ray does not certainly hit).
        const auto vertex_row = [&](int jv, double* __restrict out) {
            const double re = std::max(d_lo, row_enter_[jv]), rx = std::min(fb.d_max, row_exit_[jv]);
            for (int iv = iv0; iv <= iv1; ++iv) {
                const double enter = std::max(re, col_enter_[iv]);
                const double exit = std::min(rx, col_exit_[iv]);
                const double hit_depth = enter * (1.0 + kCubeDepthSlack);
                out[iv] = exit >= hit_depth ? hit_depth : kInf;
            }
        };
        bool prev_ready = false;  // corner_prev_ holds vertex row j
        for (int j = jv0; j < jv1; ++j) {
            float* __restrict const row = face_depth + size_t(j) * r;
            // Every corner depth of pixel row j is at least `least` (entries are >= each vertex row's
            // max(d_lo, row_enter_)), and so is what it could write (float_up rounds up). A row already
            // as near everywhere keeps its depths: skip it (the same depths, less work behind walls).
            const double least = std::min(std::max(d_lo, row_enter_[j]), std::max(d_lo, row_enter_[j + 1]));
            uint32_t farthest = 0;  // positive floats and +inf order as their bits
            for (int i = iv0; i < iv1; ++i) farthest = std::max(farthest, std::bit_cast<uint32_t>(row[i]));
            if (double(std::bit_cast<float>(farthest)) <= least) {
                prev_ready = false;
                continue;
            }
            if (!prev_ready) vertex_row(j, corner_prev_.data());
            vertex_row(j + 1, corner_cur_.data());
            // Branch-free, so that it vectorizes: min with float_up(d) keeps the pixel when d >= it
            // (float_up(d) >= d) and lowers it to float_up(d) otherwise.
            const double* __restrict const cp = corner_prev_.data();
            const double* __restrict const cc = corner_cur_.data();
            for (int i = iv0; i < iv1; ++i) {
                const float f = float_up(std::max(std::max(cp[i], cp[i + 1]), std::max(cc[i], cc[i + 1])));
                row[i] = f < row[i] ? f : row[i];
            }
            std::swap(corner_prev_, corner_cur_);
            prev_ready = true;
        }
    }
}

namespace {

// The panel's plane relative to the eye: the face along its normal that looks at it, and its depth there;
// false when the panel is unusable (not flat along exactly one axis, not finite) or its plane is within
// the near plane or within the eye box (its half-extent along the normal, times 1 + 1e-6) of the eye.
bool panel_face(const Aabb& panel, glm::vec3 eye, glm::dvec3 spread, int& face, double& depth) {
    if (!is_finite(panel.min) || !is_finite(panel.max)) return false;
    int axis = -1;
    for (int a = 0; a < 3; ++a) {
        if (!(panel.min[a] <= panel.max[a])) return false;
        if (panel.min[a] == panel.max[a]) {
            if (axis >= 0) return false;
            axis = a;
        }
    }
    if (axis < 0) return false;
    const double h = double(panel.min[axis]) - double(eye[axis]);
    if (!(std::abs(h) > std::max(kCubeNearPlane_m, spread[axis] * (1.0 + 1e-6)))) return false;
    face = 2 * axis + (h > 0.0 ? 0 : 1);
    depth = std::abs(h);
    return true;
}

// The tangents p (of a ray from the eye, relative to a panel's normal, along one in-plane axis k) whose ray
// crosses the panel's plane, at signed height h from the eye on the normal axis, at h p, inside [lo, hi]
// (relative to the eye, on axis k) inset by the eye box's per-ray bound (docs/ALGORITHMS.md#panel-inset):
//     lo + b_k + b_n |p| <= h p <= hi - b_k - b_n |p|,   b = spread (1 + 1e-9) + 1e-9 |h|,
// b_k and b_n the box's half-extents along k and along the normal, the second term of b covering rounding
// (of p, and of this test). Both sides are concave in p, so the set is an interval; each end solves a
// linear equation on one side of p = 0 (the plane is beyond the box, |h| > b_n, so h p -+ b_n |p| is
// monotone). The computed ends are then moved inward until the test holds there as written, so every p in
// [lo, hi] passes it in exact arithmetic (concavity), with the rounding margin of b to spare. Empty
// (lo > hi) when no ray crosses inside the inset rectangle.
struct TangentRange {
    double lo = 1.0, hi = 0.0;
    bool contains(double p) const { return lo <= p && p <= hi; }
};

TangentRange panel_tangent_range(double h, double lo, double hi, double spread_k, double spread_n) {
    const double bk = spread_k * (1.0 + 1e-9) + 1e-9 * std::abs(h);
    const double bn = spread_n * (1.0 + 1e-9) + 1e-9 * std::abs(h);
    const auto passes = [&](double p) {
        const double inset = bk + bn * std::abs(p);
        return h * p - lo >= inset && hi - h * p >= inset;
    };
    // With H = |h| > bn, in q = p sign(h) (the crossing is at H q): the ends solve H q - bn |q| = lo + bk
    // and H q + bn |q| = hi - bk, both sides increasing in q.
    const double big_h = std::abs(h);
    const auto lower_end = [&](double c) { return c >= 0.0 ? c / (big_h - bn) : c / (big_h + bn); };
    const auto upper_end = [&](double d) { return d >= 0.0 ? d / (big_h + bn) : d / (big_h - bn); };
    TangentRange t;
    if (h > 0.0) {
        t.lo = lower_end(lo + bk);
        t.hi = upper_end(hi - bk);
    } else {
        t.lo = -upper_end(hi - bk);
        t.hi = -lower_end(lo + bk);
    }
    if (!(big_h > bn) || !(t.lo <= t.hi) || !std::isfinite(t.lo) || !std::isfinite(t.hi))
        return TangentRange{};
    for (double step = 1e-15 * std::max(1.0, std::abs(t.lo)); !passes(t.lo); step *= 2.0) {
        t.lo += step;
        if (!(t.lo <= t.hi)) return TangentRange{};
    }
    for (double step = 1e-15 * std::max(1.0, std::abs(t.hi)); !passes(t.hi); step *= 2.0) {
        t.hi -= step;
        if (!(t.lo <= t.hi)) return TangentRange{};
    }
    return t;
}

// Depth bands (depth_cube.h, set_panel_bands(); docs/ALGORITHMS.md#depth-bands). THE share of a corner ray
// of tangent p along one in-plane axis k that fails the panel's rule there, shared by kernel and reference:
// the largest f with lo + f w + m <= h p <= hi - f w - m (w and m as in the header), below kBandMaxShare.
constexpr double kBandMaxShare = 1.0 - 1e-6;

inline double inset_share(double h, double p, double lo, double hi, double spread_k, double spread_n) {
    const double dist = std::min(h * p - lo, hi - h * p) - 4e-9 * std::abs(h) * (1.0 + std::abs(p));
    if (!(dist > 0.0)) return 0.0;
    const double w = (spread_k + spread_n * std::abs(p)) * (1.0 + 1e-9);
    if (!(w > 0.0)) return kBandMaxShare;
    return std::min(dist / w * (1.0 - 1e-9), kBandMaxShare);
}

// The far end of a band of share f in (0, 1): the depth, on a face where the largest |tangent along the
// normal| of the pixel's vertices is g, up to which a point is at most (|h| - b_n) f / (1 - f) beyond the
// plane, with margins, rounded down to float (a smaller far end is the safe side).
inline float band_far(double big_h, double spread_n, double f, double g) {
    const double beyond = f * (big_h - spread_n * (1.0 + 1e-9)) / (1.0 - f);
    const double far = (big_h + beyond) / g * (1.0 - 1e-6);
    const float x = float(far);
    return double(x) > far ? std::nextafter(x, 0.0f) : x;
}

// A pixel's band (kept_near, kept_far] after band (near, far] is drawn on it: their union when they overlap
// or touch (near <= kept_far and kept_near <= far), else the one of larger far end (then of smaller near
// end). Either way every depth of the result lies in one of the two.
inline void merge_band(float near, float far, float& kept_near, float& kept_far) {
    if (!(far > near)) return;
    if (near <= kept_far && kept_near <= far) {
        kept_near = std::min(kept_near, near);
        kept_far = std::max(kept_far, far);
    } else if (far > kept_far || (far == kept_far && near < kept_near)) {
        kept_near = near;
        kept_far = far;
    }
}

// The run of grid vertices k in [k0, k1] with lo <= g[k] <= hi, g growing with k: [first, last], empty when
// first > last. Found from an estimate and walked to its exact ends with that very test.
inline void vertex_run(const double* g, double lo, double hi, int k0, int k1, int r, int& first, int& last) {
    if (!(lo <= hi)) {
        first = 1;
        last = 0;
        return;
    }
    const auto index = [&](double x) {
        return std::clamp(int(std::floor((std::clamp(x, -2.0, 2.0) + 1.0) * 0.5 * r)), k0, k1);
    };
    first = index(lo);
    while (first > k0 && g[first - 1] >= lo) --first;
    while (first <= k1 && g[first] < lo) ++first;
    last = std::max(first - 1, index(hi));
    while (last < k1 && g[last + 1] <= hi) ++last;
    while (last >= first && g[last] > hi) --last;
}

// A panel's ranges of tangents on its two in-plane axes (for a box around the eye), computed once for the
// four side faces of the cube.
struct PanelTangents {
    int axis = 0;           // the panel's normal axis
    double h = 0.0;         // signed height of its plane above the eye, on that axis
    TangentRange range[3];  // per in-plane axis (range[axis] unused)
};

// False when the panel is unusable or its plane is within the near plane or the eye box (panel_face()).
bool panel_tangents(const Aabb& panel, glm::vec3 eye, glm::dvec3 spread, PanelTangents& out) {
    int normal_face = 0;
    double t = 0.0;
    if (!panel_face(panel, eye, spread, normal_face, t)) return false;
    out.axis = normal_face / 2;
    out.h = double(panel.min[out.axis]) - double(eye[out.axis]);
    for (int k = 0; k < 3; ++k) {
        if (k != out.axis) {
            out.range[k] =
                panel_tangent_range(out.h, double(panel.min[k]) - double(eye[k]),
                                    double(panel.max[k]) - double(eye[k]), spread[k], spread[out.axis]);
        }
    }
    return true;
}

// The panel on SIDE face `face` of the cube (one whose axis f lies in the panel's plane; depth_cube.h,
// add_panel_sides()). There the panel's normal axis is one face coordinate, the "major" one (g_m), and its
// other in-plane axis c the other, the "minor" one (g_n). A corner ray (+-1 on f, g_m, g_n) reaches the plane
// at ray parameter h / g_m, which is also its depth on this face, with tangents +-1 / g_m along f and
// g_n / g_m along c.
struct PanelSide {
    bool major_is_u = true;  // the major coordinate is u (columns); else v (rows)
    double h = 0.0;          // signed height of the plane above the eye, on the panel's normal axis
    double face_sign = 1.0;  // the f component of the face's rays
    TangentRange along_face_axis, along_minor;
};

// THE rule of a panel on a side face, shared by the kernel and the reference: false when the face is along
// the panel's normal or no ray of the face crosses the panel inside its inset rectangle.
bool panel_side(const PanelTangents& pt, int face, PanelSide& out) {
    const int f = face / 2;
    if (f == pt.axis) return false;
    out.major_is_u = (f + 1) % 3 == pt.axis;
    out.h = pt.h;
    out.face_sign = face % 2 == 0 ? 1.0 : -1.0;
    out.along_face_axis = pt.range[f];
    out.along_minor = pt.range[3 - pt.axis - f];
    return out.along_face_axis.lo <= out.along_face_axis.hi && out.along_minor.lo <= out.along_minor.hi;
}

// Does the major grid value g_m pass (its rays reach the plane ahead, with a tangent along the face axis in
// range)? Its crossing depth is h / g_m.
inline bool panel_side_major(const PanelSide& ps, double g_m) {
    return ps.h * g_m > 0.0 && ps.along_face_axis.contains(ps.face_sign / g_m);
}

// The minors that pass with major g_m: g_n / g_m in the minor range, tested as g_n between the products of
// the range's ends with g_m (no division; the products' rounding, relative 1e-16, is far inside the margin
// of panel_tangent_range()). Returns the interval [lo, hi] of g_n.
inline void panel_side_minor_span(const PanelSide& ps, double g_m, double& lo, double& hi) {
    const double a = ps.along_minor.lo * g_m, b = ps.along_minor.hi * g_m;
    lo = g_m > 0.0 ? a : b;
    hi = g_m > 0.0 ? b : a;
}

// The share of a side face's grid vertex (major g_m, minor g_n) for the depth bands: 1 where it passes the
// panel's rule on that axis, else inset_share() of its tangent there (face_sign / g_m along the face axis,
// g_n / g_m along the minor), the least of the two; 0 when its ray does not reach the plane ahead.
// SideShareInputs holds the panel's extent relative to the eye along the face axis (f_lo, f_hi) and the
// minor axis (c_lo, c_hi), and the eye box's half-extents along them and along the normal.
struct SideShareInputs {
    double f_lo, f_hi, c_lo, c_hi;
    double spread_f, spread_c, spread_n;
};

inline double side_major_share(const PanelSide& ps, const SideShareInputs& in, double g_m) {
    if (!(ps.h * g_m > 0.0)) return 0.0;
    if (panel_side_major(ps, g_m)) return 1.0;
    return inset_share(ps.h, ps.face_sign / g_m, in.f_lo, in.f_hi, in.spread_f, in.spread_n);
}

inline double side_minor_share(const PanelSide& ps, const SideShareInputs& in, double g_m, double g_n) {
    double lo, hi;
    panel_side_minor_span(ps, g_m, lo, hi);
    if (lo <= g_n && g_n <= hi) return 1.0;
    return inset_share(ps.h, g_n / g_m, in.c_lo, in.c_hi, in.spread_c, in.spread_n);
}

inline SideShareInputs side_share_inputs(const Aabb& panel, glm::vec3 eye, glm::dvec3 spread, int axis,
                                         int face) {
    const int f = face / 2, c = 3 - axis - f;
    return {double(panel.min[f]) - double(eye[f]),
            double(panel.max[f]) - double(eye[f]),
            double(panel.min[c]) - double(eye[c]),
            double(panel.max[c]) - double(eye[c]),
            spread[f],
            spread[c],
            spread[axis]};
}

// A panel's rule on one face, read along a chosen MAJOR face coordinate (u or v): a grid vertex passes when
// its major value passes and its minor value lies in that major's minor interval, and its crossing depth is
// a function of the major alone. add_panel()'s rule on the face along the panel's normal that looks at it
// (either coordinate may be the major; the depth is t), add_panel_sides()'s on a side face whose major
// coordinate is the panel's normal's (the depth is h / g_m). Made from the panel's tangent ranges
// (PanelTangents): on the face along the normal a face coordinate is the tangent times the sign of h, so
// that rule's ranges are the tangent ranges, negated and swapped when h < 0 (the same inequalities as
// add_panel()'s).
struct PanelLines {
    bool front = false;
    double t = 0.0;                         // front: the plane's depth
    TangentRange major_range, minor_range;  // front
    PanelSide side;                         // side
};

// False when the panel has no such rule on the face (it looks away from the panel, or lies along its plane
// with another major) or no ray of it passes.
bool panel_lines(const PanelTangents& pt, int face, bool major_is_u, PanelLines& out) {
    const int f = face / 2;
    out.front = f == pt.axis;
    if (out.front) {
        if (face != 2 * f + (pt.h > 0.0 ? 0 : 1)) return false;
        out.t = std::abs(pt.h);
        const auto facing = [&](const TangentRange& p) {
            return pt.h > 0.0 ? p : TangentRange{-p.hi, -p.lo};
        };
        out.major_range = facing(pt.range[major_is_u ? (f + 1) % 3 : (f + 2) % 3]);
        out.minor_range = facing(pt.range[major_is_u ? (f + 2) % 3 : (f + 1) % 3]);
        return out.major_range.lo <= out.major_range.hi && out.minor_range.lo <= out.minor_range.hi;
    }
    return panel_side(pt, face, out.side) && out.side.major_is_u == major_is_u;
}

inline bool lines_major(const PanelLines& pl, double g) {
    return pl.front ? pl.major_range.contains(g) : panel_side_major(pl.side, g);
}

inline void lines_minor(const PanelLines& pl, double g, double& lo, double& hi) {
    if (pl.front) {
        lo = pl.minor_range.lo;
        hi = pl.minor_range.hi;
    } else {
        panel_side_minor_span(pl.side, g, lo, hi);
    }
}

inline double lines_depth(const PanelLines& pl, double g) {
    return pl.front ? pl.t : pl.side.h / g;
}

// The major values a panel's rule passes, as an interval of g (the front rule's range; on a side face the
// g of the same sign as h whose face_sign / g lies in the range along the face axis, 1 / g being monotone
// there). Ends may be infinite.
TangentRange lines_major_interval(const PanelLines& pl) {
    if (pl.front) return pl.major_range;
    const TangentRange& p = pl.side.along_face_axis;
    const double want = pl.side.h > 0.0 ? pl.side.face_sign : -pl.side.face_sign;  // the sign p must have
    double p0 = p.lo, p1 = p.hi;
    if (want > 0.0) {
        p0 = std::max(p0, 0.0);
    } else {
        p1 = std::min(p1, 0.0);
    }
    if (!(p0 <= p1)) return TangentRange{};
    const double g0 = p0 == 0.0 ? want * pl.side.face_sign * kInf : pl.side.face_sign / p0;
    const double g1 = p1 == 0.0 ? want * pl.side.face_sign * kInf : pl.side.face_sign / p1;
    return TangentRange{std::min(g0, g1), std::max(g0, g1)};
}

// A corner pair prepared for one eye box (depth_cube.h, add_corner()): each panel's tangent ranges as it is
// and cut and extended across the line. Extended without end: its range along the other normal loses its
// end on that side, for the other inequality alone holds there for every tangent beyond it (its left side
// is monotone; docs/ALGORITHMS.md#corner-pairs).
struct CornerRule {
    std::array<PanelTangents, 2> own, extended;
    // Per panel p, on the face along its normal that looks at it (face[p]): the line's major value there
    // (g_line), the band of rows drawn, |g - g_line| <= band, and the face coordinates of the panel's
    // extent along the line (minor_lo, minor_hi; every pixel drawn lies within them).
    std::array<int, 2> face{};
    std::array<double, 2> g_line{}, band{}, minor_lo{}, minor_hi{};
};

// Is the row of pixels between the major values g0 < g1 in the band of panel p's face?
inline bool corner_in_band(const CornerRule& rule, size_t p, double g0, double g1) {
    return g1 >= rule.g_line[p] - rule.band[p] && g0 <= rule.g_line[p] + rule.band[p];
}

// THE rule of a corner pair, shared by the kernel and the reference; false when the panels do not meet so,
// the eye box reaches a plane, neither corner applies, or a panel's own rule passes no ray
// (docs/ALGORITHMS.md#corner-pairs).
bool corner_rule(const Aabb& a, const Aabb& b, glm::vec3 eye, glm::dvec3 spread, int r, CornerRule& out,
                 const std::array<std::array<int, 4>, 6>* region = nullptr) {
    if (!box_usable(a) || !box_usable(b)) return false;
    const int na = panel_axis(a), nb = panel_axis(b);
    if (na < 0 || nb < 0 || na == nb) return false;
    const int k = 3 - na - nb;
    const float ca = a.min[na], cb = b.min[nb];
    if (!(a.min[nb] <= cb && cb <= a.max[nb] && b.min[na] <= ca && ca <= b.max[na])) return false;
    if (!(std::max(a.min[k], b.min[k]) < std::min(a.max[k], b.max[k]))) return false;
    const double ha = double(ca) - double(eye[na]), hb = double(cb) - double(eye[nb]);
    // The eye box strictly off both planes (as panel_face() asks).
    const auto beyond_box = [&](double h, int axis) {
        return std::abs(h) > std::max(kCubeNearPlane_m, spread[axis] * (1.0 + 1e-6));
    };
    if (!beyond_box(ha, na) || !beyond_box(hb, nb)) return false;
    // The eye lies above a's plane when ha < 0. Concave: a's part on the eye's side of b's plane and b's
    // part on the eye's side of a's; convex: both parts beyond. Each part must have some extent.
    const bool above_a = ha < 0.0, above_b = hb < 0.0;
    const auto has_part = [](const Aabb& p, int axis, float c, bool up) {
        return up ? p.max[axis] > c : p.min[axis] < c;
    };
    bool a_up = above_b, b_up = above_a;  // the concave corner's parts: a at x[nb] >= cb when a_up
    if (!has_part(a, nb, cb, a_up) || !has_part(b, na, ca, b_up)) {
        a_up = !above_b;
        b_up = !above_a;
        if (!has_part(a, nb, cb, a_up) || !has_part(b, na, ca, b_up)) return false;
    }
    // The faces along the normals, the line's major value there, the band of rows about it: the parts'
    // insets for the eye box there are about (b_other + b_normal |g|) / depth, a few times that, and two
    // pixels. With the cube's drawn region: false when neither face's band and extent meet it.
    bool any = region == nullptr;
    for (size_t p = 0; p < 2; ++p) {
        const Aabb& panel = p == 0 ? a : b;
        const int n = p == 0 ? na : nb, other = p == 0 ? nb : na;
        const double h = p == 0 ? ha : hb, h_other = p == 0 ? hb : ha;
        out.face[p] = 2 * n + (h > 0.0 ? 0 : 1);
        out.g_line[p] = h_other / std::abs(h);
        out.band[p] =
            3.0 * (spread[na] + spread[nb]) * (1.0 + std::abs(out.g_line[p])) / std::abs(h) + 4.0 / r;
        out.minor_lo[p] = (double(panel.min[k]) - double(eye[k])) / std::abs(h);
        out.minor_hi[p] = (double(panel.max[k]) - double(eye[k])) / std::abs(h);
        if (!any) {
            const bool major_is_u = (n + 1) % 3 == other;
            const auto& reg = (*region)[size_t(out.face[p])];
            const double g_lo = out.g_line[p] - out.band[p], g_hi = out.g_line[p] + out.band[p];
            const int rm0 = major_is_u ? reg[0] : reg[2], rm1 = major_is_u ? reg[1] : reg[3];
            const int rn0 = major_is_u ? reg[2] : reg[0], rn1 = major_is_u ? reg[3] : reg[1];
            any = rm0 <= rm1 && rn0 <= rn1 && grid(rm1 + 1, r) >= g_lo && grid(rm0, r) <= g_hi &&
                  grid(rn1 + 1, r) >= out.minor_lo[p] && grid(rn0, r) <= out.minor_hi[p];
        }
    }
    if (!any) return false;
    Aabb part_a = a, part_b = b;  // the parts kept
    (a_up ? part_a.min[nb] : part_a.max[nb]) = cb;
    (b_up ? part_b.min[na] : part_b.max[na]) = ca;
    if (!panel_tangents(part_a, eye, spread, out.own[0]) || !panel_tangents(part_b, eye, spread, out.own[1]))
        return false;
    for (size_t p = 0; p < 2; ++p) {
        const PanelTangents& own = out.own[p];
        for (int axis = 0; axis < 3; ++axis)
            if (axis != own.axis && !(own.range[axis].lo <= own.range[axis].hi)) return false;
        // The extension runs to lower coordinates along the other normal when the part is up; a tangent
        // there is that offset over h.
        const int other = p == 0 ? nb : na;
        const bool down = p == 0 ? a_up : b_up;
        out.extended[p] = own;
        if (down == (own.h > 0.0)) {
            out.extended[p].range[other].lo = -kInf;
        } else {
            out.extended[p].range[other].hi = kInf;
        }
    }
    return true;
}

// The corner on one face along either panel's normal, read along the other panel's normal's coordinate
// (there the line projects to a line of constant major value): the four rules.
struct CornerFace {
    bool major_is_u = true;
    std::array<PanelLines, 2> extended, own;
};

// False on the faces along the line, or when a rule is missing on the face.
bool corner_face(const CornerRule& rule, int face, CornerFace& out) {
    const int f = face / 2, a0 = rule.own[0].axis, a1 = rule.own[1].axis;
    if (face != rule.face[0] && face != rule.face[1]) return false;
    out.major_is_u = (f + 1) % 3 == (f == a0 ? a1 : a0);
    for (size_t p = 0; p < 2; ++p)
        if (!panel_lines(rule.extended[p], face, out.major_is_u, out.extended[p]) ||
            !panel_lines(rule.own[p], face, out.major_is_u, out.own[p]))
            return false;
    return true;
}

// A row of pixels between the major values g0 and g1: drawn when both pass both extended panels and, for
// each panel, one fails its own rule (where both pass it, that part alone covers the row's pixels, the
// minors being the same, at no greater depth). Then a pixel is written when its two minors lie in
// [lo, hi], with `depth` (the largest crossing depth of its four vertices).
inline bool corner_row(const CornerFace& cf, double g0, double g1, double& lo, double& hi, double& depth) {
    lo = -kInf;
    hi = kInf;
    depth = 0.0;
    for (size_t p = 0; p < 2; ++p) {
        const PanelLines& ext = cf.extended[p];
        if (!lines_major(ext, g0) || !lines_major(ext, g1)) return false;
        if (lines_major(cf.own[p], g0) && lines_major(cf.own[p], g1)) return false;
        for (const double g : {g0, g1}) {
            double l = 0.0, h = 0.0;
            lines_minor(ext, g, l, h);
            lo = std::max(lo, l);
            hi = std::min(hi, h);
            depth = std::max(depth, lines_depth(ext, g));
        }
    }
    return lo <= hi;
}

// The rows corner_row() can draw lie between the two parts' own ends on their extensions' sides: a row needs
// a vertex beyond each. [g_lo, g_hi], or the whole face when the extensions run the same way.
void corner_window(const CornerFace& cf, double& g_lo, double& g_hi) {
    g_lo = -kInf;
    g_hi = kInf;
    double end[2];
    int dir[2];
    for (size_t p = 0; p < 2; ++p) {
        const TangentRange own = lines_major_interval(cf.own[p]), ext = lines_major_interval(cf.extended[p]);
        dir[p] = ext.lo < own.lo ? -1 : (ext.hi > own.hi ? 1 : 0);
        end[p] = dir[p] < 0 ? own.lo : own.hi;
        if (dir[p] == 0 || !std::isfinite(end[p])) return;
    }
    if (dir[0] == dir[1]) return;
    g_lo = std::min(end[0], end[1]);
    g_hi = std::max(end[0], end[1]);
}

}  // namespace

// Per major grid value: does it pass, and which minor vertices pass (g_n in an interval, and g_n grows with
// n: a contiguous range, found from an estimate and walked to its exact ends with the reference's very
// test); a pixel is written when both its majors pass and its two minors lie in both ranges, with the larger
// crossing depth of its two majors.
void DepthCube::add_panel_sides(const Aabb& panel, glm::dvec3 spread) {
    int normal_face = 0;
    double t = 0.0;
    if (!panel_face(panel, eye_, spread, normal_face, t)) return;
    const int r = resolution_;
    PanelTangents pt;
    bool have_tangents = false;  // computed when a face first needs them (square roots)
    for (int face = 0; face < 6; ++face) {
        if (face / 2 == normal_face / 2) continue;
        // Candidate vertices: a passing vertex's ray crosses the panel at depth >= |h| > near, so it lies in
        // the projection of the panel's part beyond the near plane.
        FaceCandidates fc;
        if (!face_candidates(panel, eye_, face, region_[size_t(face)], r, fc)) continue;
        const int iv0 = fc.iv0, iv1 = fc.iv1, jv0 = fc.jv0, jv1 = fc.jv1;
        if (!have_tangents) {
            panel_tangents(panel, eye_, spread, pt);
            have_tangents = true;
        }
        PanelSide ps;
        // With no ray passing the rule (an empty range), nothing is written but the bands may be.
        if (!panel_side(pt, face, ps) && !panel_bands_) continue;
        const int mv0 = ps.major_is_u ? iv0 : jv0, mv1 = ps.major_is_u ? iv1 : jv1;
        const int nv0 = ps.major_is_u ? jv0 : iv0, nv1 = ps.major_is_u ? jv1 : iv1;
        const double* const g = grid_.data();
        for (int m = mv0; m <= mv1; ++m) {
            const double g_m = g[m];
            side_first_[size_t(m)] = 1;
            side_last_[size_t(m)] = 0;
            if (!panel_side_major(ps, g_m)) continue;
            corner_cur_[size_t(m)] = ps.h / g_m;
            double lo, hi;
            panel_side_minor_span(ps, g_m, lo, hi);
            vertex_run(g, lo, hi, nv0, nv1, r, side_first_[size_t(m)], side_last_[size_t(m)]);
        }
        float* const face_depth = depth_.data() + size_t(face) * r * r;
        const size_t step_major = ps.major_is_u ? 1 : size_t(r), step_minor = ps.major_is_u ? size_t(r) : 1;
        for (int m = mv0; m < mv1; ++m) {
            const int first = std::max(side_first_[size_t(m)], side_first_[size_t(m) + 1]);
            const int last = std::min(side_last_[size_t(m)], side_last_[size_t(m) + 1]);  // vertices
            if (first >= last) continue;  // no pixel has both minors in range
            const float depth = float_up(std::max(corner_cur_[size_t(m)], corner_cur_[size_t(m) + 1]) *
                                         (1.0 + kCubeDepthSlack));
            float* p = face_depth + size_t(m) * step_major + size_t(first) * step_minor;
            for (int n = first; n < last; ++n, p += step_minor) *p = std::min(*p, depth);
        }
        if (!panel_bands_) continue;
        // Depth bands (depth_cube.h, set_panel_bands()). A vertex has a share > 0 only where its ray crosses
        // the panel's own rectangle by a margin (of 4e-9 |h| (1 + |p|), far above the rounding of the
        // tangent), so per major only the minors in that span, widened by 1e-9, are visited (a run found as
        // above), and of those only the pixels not written above.
        const SideShareInputs in = side_share_inputs(panel, eye_, spread, pt.axis, face);
        for (int m = mv0; m <= mv1; ++m) {
            const size_t k = size_t(m);
            band_major_share_[k] = side_major_share(ps, in, g[m]);
            band_first_[k] = 1;
            band_last_[k] = 0;
            if (!(band_major_share_[k] > 0.0)) continue;
            const double a = g[m] * in.c_lo / ps.h, b = g[m] * in.c_hi / ps.h;
            const double pad = 1e-9 * std::max({1.0, std::abs(a), std::abs(b)});
            vertex_run(g, std::min(a, b) - pad, std::max(a, b) + pad, nv0, nv1, r, band_first_[k],
                       band_last_[k]);
        }
        const double big_h = std::abs(ps.h);
        for (int m = mv0; m < mv1; ++m) {
            const double major_share =
                std::min(band_major_share_[size_t(m)], band_major_share_[size_t(m) + 1]);
            if (!(major_share > 0.0)) continue;
            const int first = std::max(band_first_[size_t(m)], band_first_[size_t(m) + 1]);
            const int last = std::min(band_last_[size_t(m)], band_last_[size_t(m) + 1]);
            // The pixels add_panel_sides() wrote in this row (none when a major fails its rule).
            int written_first = 1, written_last = 0;
            if (major_share >= 1.0) {
                written_first = std::max(side_first_[size_t(m)], side_first_[size_t(m) + 1]);
                written_last = std::min(side_last_[size_t(m)], side_last_[size_t(m) + 1]);
            }
            const float near = float_up(std::max(ps.h / g[m], ps.h / g[m + 1]) * (1.0 + kCubeDepthSlack));
            const double g_big = std::max(std::abs(g[m]), std::abs(g[m + 1]));
            // The pixels before the written ones, then those after them; a vertex's minor share is carried
            // from one pixel to the next.
            const int stops[2][2] = {
                {first, std::min(last, written_first < written_last ? written_first : last)},
                {std::max(first, written_first < written_last ? written_last : last), last}};
            for (const auto& [from, to] : stops) {
                double left = 0.0;  // the least share of vertex column n at both majors, once known
                bool have_left = false;
                for (int n = from; n < to; ++n) {
                    if (!have_left)
                        left = std::min(side_minor_share(ps, in, g[m], g[n]),
                                        side_minor_share(ps, in, g[m + 1], g[n]));
                    const double right = std::min(side_minor_share(ps, in, g[m], g[n + 1]),
                                                  side_minor_share(ps, in, g[m + 1], g[n + 1]));
                    const double f = std::min({major_share, left, right});
                    left = right;
                    have_left = true;
                    if (!(f > 0.0 && f < 1.0)) continue;
                    const float far = band_far(big_h, spread[pt.axis], f, g_big);
                    if (ps.major_is_u)
                        keep_band(face, m, n, near, far);
                    else
                        keep_band(face, n, m, near, far);
                }
            }
        }
    }
}

namespace {

// A slanted panel prepared for one eye box (depth_cube.h, add_slanted_panel()): THE rule of a grid vertex,
// shared by the kernel and the reference.
struct SlantedRule {
    glm::dvec3 toward{0.0};         // N: the unit normal on the eye's side
    double h_near = 0.0;            // height of s above the grown slab's near face (> b_n)
    double h_far = 0.0;             // and above its far face
    double b_n = 0.0;               // the eye box's support along the normal
    const glm::dvec3* m = nullptr;  // per edge: inward unit normal in the plane (the panel's edge_normal)
    size_t edges = 0;
    std::vector<double> slack;  // per edge: m_i.s - k_i - a_i (the sample's room inside the inset edge)
};

// False when the panel is unusable (fewer than 3 corners, no edge lines, not finite) or the eye box reaches
// its grown slab.
bool slanted_rule(const SlantedPanel& panel, glm::vec3 eye, glm::dvec3 spread, SlantedRule& out) {
    const size_t n = panel.corners.size();
    if (n < 3 || !std::isfinite(panel.offset) || !std::isfinite(panel.thickness)) return false;
    const glm::dvec3 s(eye);
    const double h0 = glm::dot(panel.normal, s) - panel.offset;
    const double sign = h0 > 0.0 ? 1.0 : -1.0;
    out.toward = sign * panel.normal;
    out.b_n = 0.0;
    for (int k = 0; k < 3; ++k) out.b_n += std::abs(panel.normal[k]) * spread[k] * (1.0 + 1e-9);
    const double grown = panel.thickness + kSlantedPanelMarginM;
    out.h_near = std::abs(h0) - grown;
    out.h_far = std::abs(h0) + grown;
    // Beyond the eye box, and far enough from s that every crossing lies beyond the near plane (|d| <= sqrt
    // 3, so a crossing's depth is at least h_near / sqrt 3): there a passing vertex lies in the projection of
    // slanted_reach() clipped to the near plane, which the kernel's candidate vertices cover.
    if (!(out.h_near > std::max(out.b_n * (1.0 + 1e-6), 2.0 * kCubeNearPlane_m)) || !std::isfinite(out.h_far))
        return false;
    if (panel.edge_normal.size() != n || panel.edge_offset.size() != n) return false;
    out.m = panel.edge_normal.data();
    out.edges = n;
    out.slack.resize(n);
    for (size_t i = 0; i < n; ++i) {
        double a = 0.0;
        for (int k = 0; k < 3; ++k) a += std::abs(out.m[i][k]) * spread[k] * (1.0 + 1e-9);
        out.slack[i] = glm::dot(out.m[i], s) - (panel.edge_offset[i] + kSlantedPanelMarginM) - a;
    }
    return true;
}

// The far-face crossing depth of a passing vertex with ray direction d (+-1 on the face axis, so the ray
// parameter is the depth), or +infinity when it does not pass.
inline double slanted_vertex_depth(const SlantedRule& rule, const glm::dvec3& d) {
    const double w = -glm::dot(rule.toward, d);
    if (!(w > 0.0)) return kInf;
    for (size_t i = 0; i < rule.edges; ++i) {
        const double md = glm::dot(rule.m[i], d);
        // Linear in h: both faces pass when the one with the smaller h * md does.
        const double hm = md >= 0.0 ? rule.h_near * md : rule.h_far * md;
        if (!(rule.slack[i] * w + hm - rule.b_n * std::abs(md) >= 0.0)) return kInf;
    }
    return rule.h_far / w;
}

// The slanted panel's bounds grown to hold every point of its slab over the polygon, where a passing
// vertex's ray crosses (for the candidate vertices; a vertex left out counts as failing, which is safe).
Aabb slanted_reach(const SlantedPanel& panel) {
    const float g = float(2.0 * (panel.thickness + kSlantedPanelMarginM)) + 1e-3f;
    return Aabb::of(panel.bounds.min - g, panel.bounds.max + g);
}

// face_candidates() for a slanted panel's reach, false also when its projection is narrower than a pixel
// on either axis: a written pixel's four corner rays cross the near face inside the reach, beyond the near
// plane, so the pixel lies in that projection. (Most far panels are; the answer is the same, only faster.)
bool slanted_face_candidates(const Aabb& reach, glm::vec3 eye, int face, const std::array<int, 4>& reg, int r,
                             FaceCandidates& fc) {
    if (!face_candidates(reach, eye, face, reg, r, fc)) return false;
    double u0, u1, v0, v1;
    projected_rect(fc.fb, fc.d_lo, u0, u1, v0, v1);
    const double pixel = 2.0 / double(r) * (1.0 - 1e-9);
    return std::min(u1, 1.0) - std::max(u0, -1.0) >= pixel && std::min(v1, 1.0) - std::max(v0, -1.0) >= pixel;
}

// The direction of the ray of face coordinates (u, v) on a face: +-1 on its axis, so its parameter is depth.
inline glm::dvec3 face_direction(int face, double u, double v) {
    const int a = face / 2;
    glm::dvec3 dir(0.0);
    dir[a] = face % 2 == 0 ? 1.0 : -1.0;
    dir[(a + 1) % 3] = u;
    dir[(a + 2) % 3] = v;
    return dir;
}

}  // namespace

// On a row of grid vertices (v fixed) the rule is a set of linear conditions in u: w > 0, and per edge, as
// the left side is concave and piecewise linear with its break at m_i.d = 0, the two lines it is the minimum
// of, (m_i.s - k_i - a_i) w + (h_near - b_n) m_i.d >= 0 and (m_i.s - k_i - a_i) w + (h_far + b_n) m_i.d >= 0.
// So the passing vertices of a row are a run, found from the interval those lines leave and walked to its
// exact ends with slanted_vertex_depth() (in exact arithmetic every vertex between two passing ones passes:
// the set is convex; the rule's margins dwarf rounding). A pixel is written when its four vertices lie in
// the runs of its two rows, with the largest of their far-face depths.
void DepthCube::add_slanted_panel(const SlantedPanel& panel, glm::dvec3 spread) {
    thread_local SlantedRule rule;  // keeps its edge arrays from panel to panel
    if (!slanted_rule(panel, eye_, spread, rule)) return;
    const Aabb reach = slanted_reach(panel);
    const int r = resolution_;
    const double* const g = grid_.data();
    for (int face = 0; face < 6; ++face) {
        FaceCandidates fc;
        if (!slanted_face_candidates(reach, eye_, face, region_[size_t(face)], r, fc)) continue;
        const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
        const double sg = face % 2 == 0 ? 1.0 : -1.0;
        // x.d = x0 + u x1 on the row of v, for the direction d = (sg on a, u, v).
        const auto on_row = [&](const glm::dvec3& x, double v, double& x0, double& x1) {
            x0 = sg * x[a] + v * x[va];
            x1 = x[ua];
        };
        // Passing vertices of row jv, [first, last], and their far-face depths in out[].
        const auto row_run = [&](int jv, int& first, int& last, double* out) {
            const double v = g[jv];
            double lo = -kInf, hi = kInf;
            const auto keep = [&](double alpha, double beta) {  // alpha + beta u >= 0
                if (beta > 0.0) {
                    lo = std::max(lo, -alpha / beta);
                } else if (beta < 0.0) {
                    hi = std::min(hi, -alpha / beta);
                } else if (!(alpha >= 0.0)) {
                    lo = kInf;
                }
            };
            double w0, w1;
            on_row(-rule.toward, v, w0, w1);
            keep(w0, w1);
            const double near_k = rule.h_near - rule.b_n, far_k = rule.h_far + rule.b_n;
            for (size_t i = 0; i < rule.edges && lo <= hi; ++i) {
                double m0, m1;
                on_row(rule.m[i], v, m0, m1);
                const double c = rule.slack[i];
                keep(c * w0 + near_k * m0, c * w1 + near_k * m1);
                keep(c * w0 + far_k * m0, c * w1 + far_k * m1);
            }
            vertex_run(g, lo, hi, fc.iv0, fc.iv1, r, first, last);
            const auto depth_at = [&](int iv) {
                return slanted_vertex_depth(rule, face_direction(face, g[iv], v));
            };
            while (first <= last && !(depth_at(first) < kInf)) ++first;
            while (last >= first && !(depth_at(last) < kInf)) --last;
            for (int iv = first; iv <= last; ++iv)  // slanted_vertex_depth()'s very value
                out[iv] = rule.h_far / -glm::dot(rule.toward, face_direction(face, g[iv], v));
        };
        float* const face_depth = depth_.data() + size_t(face) * r * r;
        int prev_first, prev_last;
        row_run(fc.jv0, prev_first, prev_last, corner_prev_.data());
        for (int j = fc.jv0; j < fc.jv1; ++j) {
            int first, last;
            row_run(j + 1, first, last, corner_cur_.data());
            const double* const cp = corner_prev_.data();
            const double* const cc = corner_cur_.data();
            float* const row = face_depth + size_t(j) * r;
            for (int i = std::max(first, prev_first); i < std::min(last, prev_last); ++i) {
                const double d = std::max(std::max(cp[i], cp[i + 1]), std::max(cc[i], cc[i + 1]));
                row[i] = std::min(row[i], float_up(d * (1.0 + kCubeDepthSlack)));
            }
            std::swap(corner_prev_, corner_cur_);
            prev_first = first;
            prev_last = last;
        }
    }
}

void DepthCube::add_slanted_panels(const std::vector<SlantedPanel>& panels, glm::dvec3 spread) {
    std::vector<uint32_t> all(panels.size());
    for (uint32_t p = 0; p < all.size(); ++p) all[p] = p;
    add_slanted_panels(panels, all, spread);
}

void DepthCube::add_slanted_panels(const std::vector<SlantedPanel>& panels,
                                   const std::vector<uint32_t>& which, glm::dvec3 spread) {
    slanted_order_.clear();
    for (const uint32_t p : which) {
        const Aabb& b = panels[p].bounds;
        const glm::vec3 q = glm::clamp(eye_, b.min, b.max);
        slanted_order_.push_back({glm::dot(q - eye_, q - eye_), p});
    }
    std::sort(slanted_order_.begin(), slanted_order_.end());
    for (const auto& [dist2, p] : slanted_order_) {
        const Aabb reach = slanted_reach(panels[p]);
        bool wide = false;  // can it write a pixel anywhere?
        for (int face = 0; face < 6 && !wide; ++face) {
            FaceCandidates fc;
            wide = slanted_face_candidates(reach, eye_, face, region_[size_t(face)], resolution_, fc);
        }
        if (wide && !is_hidden_by_depths(reach)) add_slanted_panel(panels[p], spread);
    }
}

void DepthCube::add_corner(const Aabb& a, const Aabb& b, glm::dvec3 spread) {
    CornerRule rule;
    const int r = resolution_;
    if (!corner_rule(a, b, eye_, spread, r, rule, &region_)) return;
    const double* const g = grid_.data();
    for (size_t fp = 0; fp < 2; ++fp) {
        const int face = rule.face[fp];
        CornerFace cf;
        if (!corner_face(rule, face, cf)) continue;
        const auto& reg = region_[size_t(face)];
        int m0 = cf.major_is_u ? reg[0] : reg[2], m1 = cf.major_is_u ? reg[1] : reg[3];
        const int n0 = cf.major_is_u ? reg[2] : reg[0], n1 = cf.major_is_u ? reg[3] : reg[1];
        // Only the rows about the window (a row outside it cannot pass; two rows of slack for rounding).
        double g_lo, g_hi;
        corner_window(cf, g_lo, g_hi);
        if (std::isfinite(g_lo) && std::isfinite(g_hi)) {
            if (g_lo > 1.0 || g_hi < -1.0) continue;
            m0 = std::max(m0, int(std::floor((std::max(g_lo, -1.0) + 1.0) * 0.5 * r)) - 2);
            m1 = std::min(m1, int(std::ceil((std::min(g_hi, 1.0) + 1.0) * 0.5 * r)) + 1);
        }
        float* const face_depth = depth_.data() + size_t(face) * r * r;
        const size_t step_major = cf.major_is_u ? 1 : size_t(r), step_minor = cf.major_is_u ? size_t(r) : 1;
        m0 = std::max(m0, int(std::floor((rule.g_line[fp] - rule.band[fp] + 1.0) * 0.5 * r)) - 1);
        m1 = std::min(m1, int(std::ceil((rule.g_line[fp] + rule.band[fp] + 1.0) * 0.5 * r)) + 1);
        for (int m = m0; m <= m1; ++m) {
            double lo, hi, depth;
            if (!corner_in_band(rule, fp, g[m], g[m + 1]) || !corner_row(cf, g[m], g[m + 1], lo, hi, depth))
                continue;
            int first, last;
            vertex_run(g, lo, hi, n0, n1 + 1, r, first, last);
            const float d = float_up(depth * (1.0 + kCubeDepthSlack));
            float* p = face_depth + size_t(m) * step_major + size_t(first) * step_minor;
            for (int n = first; n < last; ++n, p += step_minor) *p = std::min(*p, d);
        }
    }
}

void DepthCube::add_panel(const Aabb& panel, glm::dvec3 spread) {
    int face = 0;
    double t = 0.0;
    if (!panel_face(panel, eye_, spread, face, t)) return;
    const int r = resolution_, a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const double u_lo = double(panel.min[ua]) - double(eye_[ua]),
                 u_hi = double(panel.max[ua]) - double(eye_[ua]);
    const double v_lo = double(panel.min[va]) - double(eye_[va]),
                 v_hi = double(panel.max[va]) - double(eye_[va]);
    // Candidate vertices: those of the region's pixels within the projected rectangle.
    const auto& reg = region_[size_t(face)];
    int iv0, iv1, jv0, jv1;
    if (!candidate_vertices(u_lo / t, u_hi / t, reg[0], reg[1], r, iv0, iv1) ||
        !candidate_vertices(v_lo / t, v_hi / t, reg[2], reg[3], r, jv0, jv1))
        return;
    // The vertices whose corner rays cross inside the rectangle inset per ray: a run of columns and a run
    // of rows (the tangent ranges of panel_tangent_range(), with the plane at height t along the face axis,
    // where the tangents are the face coordinates); a pixel is written when its four corners pass.
    const TangentRange range_u = panel_tangent_range(t, u_lo, u_hi, spread[ua], spread[a]);
    const TangentRange range_v = panel_tangent_range(t, v_lo, v_hi, spread[va], spread[a]);
    int i_first, i_last, j_first, j_last;
    vertex_run(grid_.data(), range_u.lo, range_u.hi, iv0, iv1, r, i_first, i_last);
    vertex_run(grid_.data(), range_v.lo, range_v.hi, jv0, jv1, r, j_first, j_last);
    const float depth = float_up(t * (1.0 + kCubeDepthSlack));
    float* const face_depth = depth_.data() + size_t(face) * r * r;
    for (int j = j_first; j < j_last; ++j) {
        float* __restrict const row = face_depth + size_t(j) * r;
        for (int i = i_first; i < i_last; ++i) row[i] = std::min(row[i], depth);
    }
    if (!panel_bands_) return;
    // Depth bands: the shares are separable (per column on u, per row on v), 1 inside the runs above, so a
    // pixel's share is the least of its two columns' and its two rows'; only pixels outside the written
    // rectangle are visited.
    const double spread_n = spread[a];
    const auto shares = [&](std::vector<double>& out, int k0, int k1, const TangentRange& range, double lo,
                            double hi, double spread_k) {
        out.resize(size_t(k1 - k0 + 1));
        for (int k = k0; k <= k1; ++k) {
            const double g = grid_[size_t(k)];
            out[size_t(k - k0)] = range.contains(g) ? 1.0 : inset_share(t, g, lo, hi, spread_k, spread_n);
        }
    };
    shares(share_u_, iv0, iv1, range_u, u_lo, u_hi, spread[ua]);
    shares(share_v_, jv0, jv1, range_v, v_lo, v_hi, spread[va]);
    for (int j = jv0; j < jv1; ++j) {
        const double row_share = std::min(share_v_[size_t(j - jv0)], share_v_[size_t(j + 1 - jv0)]);
        if (!(row_share > 0.0)) continue;
        const bool row_written = j >= j_first && j < j_last;
        for (int i = iv0; i < iv1; ++i) {
            if (row_written && i == i_first && i_first < i_last) i = i_last;  // skip the written pixels
            if (i >= iv1) break;
            const double f = std::min({row_share, share_u_[size_t(i - iv0)], share_u_[size_t(i + 1 - iv0)]});
            if (f > 0.0 && f < 1.0) keep_band(face, i, j, depth, band_far(t, spread_n, f, 1.0));
        }
    }
}

void DepthCube::keep_band(int face, int i, int j, float near, float far) {
    const size_t k = (size_t(face) * resolution_ + size_t(j)) * resolution_ + size_t(i);
    merge_band(near, far, band_near_[k], band_far_[k]);
}

void DepthCube::add_panels(const std::vector<Aabb>& panels, glm::dvec3 spread) {
    for (const Aabb& p : panels) add_panel(p, spread);
}

void DepthCube::add_panels_sides(const std::vector<Aabb>& panels, glm::dvec3 spread) {
    for (const Aabb& p : panels) add_panel_sides(p, spread);
}

void DepthCube::add_occluders(const std::vector<Aabb>& boxes) {
    order_.clear();
    for (uint32_t b = 0; b < boxes.size(); ++b) {
        const Aabb& box = boxes[b];
        const glm::vec3 q = glm::clamp(eye_, box.min, box.max);
        order_.push_back({glm::dot(q - eye_, q - eye_), b});
    }
    std::sort(order_.begin(), order_.end());
    for (const auto& [dist2, b] : order_) {
        if (!is_hidden_by_depths(boxes[b])) add_occluder(boxes[b]);
    }
}

bool DepthCube::is_hidden(const Aabb& box) const {
    return panel_bands_ ? hidden_test<true>(box) : hidden_test<false>(box);
}

bool DepthCube::is_hidden_by_depths(const Aabb& box) const {
    return hidden_test<false>(box);
}

template <bool kBands>
PVS_AVX2_CLONES bool DepthCube::hidden_test(const Aabb& box) const {
    if (!box_usable(box) || meets_near_cube(box, eye_)) return false;
    const int r = resolution_;
    const EyeBox rel = eye_box(box, eye_);
    for (int face = 0; face < 6; ++face) {
        const OccludeeFace of = occludee_face(rel, face, r, grid_.data());
        if (!of.touched) continue;
        // Pixels outside the drawn region hold no occluder (or, after clear_for(), stale depths): visible.
        const auto& reg = region_[size_t(face)];
        if (of.i0 < reg[0] || of.i1 > reg[1] || of.j0 < reg[2] || of.j1 > reg[3]) return false;
        // double(x) < limit exactly when x < float_up(limit), for every float x; and stored depths are
        // positive or +infinity, which order as their bit patterns. So the test is, a row at a time, an
        // unsigned max that vectorizes.
        const uint32_t limit = std::bit_cast<uint32_t>(float_up(of.limit));
        const size_t face_base = size_t(face) * r * r;
        const float* const face_depth = depth_.data() + face_base;
        for (int j = of.j0; j <= of.j1; ++j) {
            const float* __restrict const row = face_depth + size_t(j) * r;
            uint32_t farthest = 0;
            for (int i = of.i0; i <= of.i1; ++i)
                farthest = std::max(farthest, std::bit_cast<uint32_t>(row[i]));
            if (farthest < limit) continue;
            if constexpr (!kBands) {
                return false;
            } else {
                // The row fails on its depths alone: each pixel may still pass by its band.
                const float* const near = band_near_.data() + face_base + size_t(j) * r;
                const float* const far = band_far_.data() + face_base + size_t(j) * r;
                for (int i = of.i0; i <= of.i1; ++i) {
                    const double d = row[i];
                    if (d < of.limit) continue;
                    if (!(near[i] < of.limit && (of.far <= far[i] || d <= far[i]))) return false;
                }
            }
        }
    }
    return true;
}

// ---------------------------------------------------------------------------------------------------------
// Reference: every pixel of every face, every occluder, four corner rays with a textbook slab test.

namespace {

// Textbook ray-box slab test over the ray eye + t * dir, t in [near, inf). Returns the entry t, or +inf
// when the ray does not certainly pass through the box (exit < entry * (1 + slack)). With |dir[a]| = 1 on
// the face axis, t is the depth.
double reference_corner_depth(const Aabb& box, glm::vec3 eye, glm::dvec3 dir) {
    double t_enter = kCubeNearPlane_m, t_exit = kInf;
    for (int k = 0; k < 3; ++k) {
        const double lo = double(box.min[k]) - double(eye[k]), hi = double(box.max[k]) - double(eye[k]);
        if (dir[k] == 0.0) {
            if (lo > 0.0 || hi < 0.0) return kInf;
            continue;
        }
        const double t1 = lo / dir[k], t2 = hi / dir[k];
        t_enter = std::max(t_enter, std::min(t1, t2));
        t_exit = std::min(t_exit, std::max(t1, t2));
    }
    const double hit_depth = t_enter * (1.0 + kCubeDepthSlack);
    return t_exit >= hit_depth ? hit_depth : kInf;
}

}  // namespace

bool is_hidden_reference(const std::vector<Aabb>& occluders, glm::vec3 eye, const Aabb& box, int resolution) {
    return is_hidden_reference(occluders, {}, glm::dvec3(0.0), eye, box, resolution);
}

bool is_hidden_reference(const std::vector<Aabb>& occluders, const std::vector<Aabb>& panels,
                         glm::dvec3 panel_spread, glm::vec3 eye, const Aabb& box, int resolution,
                         bool panel_sides, const std::vector<SlantedPanel>& slanted,
                         const std::vector<std::array<Aabb, 2>>& corners, bool panel_bands) {
    const int r = resolution;
    if (!box_usable(box)) return false;
    // Visible when the box meets the closed near cube around the eye.
    bool near = true;
    for (int k = 0; k < 3; ++k) {
        near = near && box.min[k] - double(eye[k]) <= kCubeNearPlane_m &&
               box.max[k] - double(eye[k]) >= -kCubeNearPlane_m;
    }
    if (near) return false;

    for (int face = 0; face < 6; ++face) {
        const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
        const double s = face % 2 == 0 ? 1.0 : -1.0;
        // Depth range and side ranges, straight from the definitions.
        const double da = s * (double(box.min[a]) - double(eye[a])),
                     db = s * (double(box.max[a]) - double(eye[a]));
        const double d_min = std::min(da, db), d_max = std::max(da, db);
        const double ulo = double(box.min[ua]) - double(eye[ua]), uhi = double(box.max[ua]) - double(eye[ua]);
        const double vlo = double(box.min[va]) - double(eye[va]), vhi = double(box.max[va]) - double(eye[va]);
        // Nearest depth of the box's part inside the face's cone |Δu| <= d, |Δv| <= d.
        double lower = std::max(d_min, kCubeNearPlane_m);
        if (ulo > 0.0) lower = std::max(lower, ulo);
        if (uhi < 0.0) lower = std::max(lower, -uhi);
        if (vlo > 0.0) lower = std::max(lower, vlo);
        if (vhi < 0.0) lower = std::max(lower, -vhi);
        if (lower > d_max) continue;
        // Projected rectangle: extremes over the four (side, depth) corner combinations.
        const double us[4] = {ulo / lower, ulo / d_max, uhi / lower, uhi / d_max};
        const double vs[4] = {vlo / lower, vlo / d_max, vhi / lower, vhi / d_max};
        const double u0 = pad_low(*std::min_element(us, us + 4)),
                     u1 = pad_high(*std::max_element(us, us + 4));
        const double v0 = pad_low(*std::min_element(vs, vs + 4)),
                     v1 = pad_high(*std::max_element(vs, vs + 4));
        const double limit = lower * (1.0 - kCubeDepthSlack);
        // The corner pairs with a rule on this face.
        std::vector<std::pair<CornerRule, CornerFace>> face_corners;
        for (const std::array<Aabb, 2>& pair : corners) {
            CornerRule rule;
            CornerFace cf;
            if (corner_rule(pair[0], pair[1], eye, panel_spread, r, rule) && corner_face(rule, face, cf))
                face_corners.push_back({rule, cf});
        }

        for (int j = 0; j < r; ++j) {
            for (int i = 0; i < r; ++i) {
                const bool touched =
                    grid(i, r) <= u1 && grid(i + 1, r) >= u0 && grid(j, r) <= v1 && grid(j + 1, r) >= v0;
                if (!touched) continue;
                float pixel = kInfF;
                float band_near = kInfF, band_far_end = 0.0f;  // the band kept (depth bands)
                const auto keep = [&](float n, float f) { merge_band(n, f, band_near, band_far_end); };
                for (const Aabb& occ : occluders) {
                    if (!box_usable(occ) || occ.contains(eye)) continue;
                    double d = 0.0;
                    for (int cj = j; cj <= j + 1; ++cj) {
                        for (int ci = i; ci <= i + 1; ++ci) {
                            d = std::max(d, reference_corner_depth(
                                                occ, eye, face_direction(face, grid(ci, r), grid(cj, r))));
                        }
                    }
                    if (d < kInf) pixel = std::min(pixel, float_up(d));
                }
                // Every panel on the face along its normal first, then on the side faces, in the order of the
                // list: the order in which the kernel's callers draw them (which a pixel's band depends on).
                for (int pass = 0; pass < 2; ++pass)
                    for (const Aabb& panel : panels) {
                        int panel_f = 0;
                        double t = 0.0;
                        if (!panel_face(panel, eye, panel_spread, panel_f, t)) continue;
                        if ((pass == 0) != (face / 2 == panel_f / 2)) continue;
                        PanelTangents pt;
                        PanelSide ps;
                        if (panel_sides && panel_tangents(panel, eye, panel_spread, pt) &&
                            face / 2 != pt.axis && (panel_side(pt, face, ps) || panel_bands)) {
                            // A side face: every corner's major passes and its minor is in that major's span.
                            bool all = true;
                            double d = 0.0;
                            for (int cj = j; cj <= j + 1; ++cj) {
                                for (int ci = i; ci <= i + 1; ++ci) {
                                    const double g_m = grid(ps.major_is_u ? ci : cj, r);
                                    const double g_n = grid(ps.major_is_u ? cj : ci, r);
                                    double lo = 0.0, hi = 0.0;
                                    panel_side_minor_span(ps, g_m, lo, hi);
                                    all = all && panel_side_major(ps, g_m) && lo <= g_n && g_n <= hi;
                                    if (all) d = std::max(d, ps.h / g_m);
                                }
                            }
                            if (all) pixel = std::min(pixel, float_up(d * (1.0 + kCubeDepthSlack)));
                            if (all || !panel_bands) continue;
                            // Its band: the least share of the four corners (each the least of its two
                            // axes').
                            const SideShareInputs in =
                                side_share_inputs(panel, eye, panel_spread, pt.axis, face);
                            double f = 1.0, near_d = 0.0, g_big = 0.0;
                            for (int cj = j; cj <= j + 1; ++cj) {
                                for (int ci = i; ci <= i + 1; ++ci) {
                                    const double g_m = grid(ps.major_is_u ? ci : cj, r);
                                    const double g_n = grid(ps.major_is_u ? cj : ci, r);
                                    f = std::min({f, side_major_share(ps, in, g_m),
                                                  side_minor_share(ps, in, g_m, g_n)});
                                    if (ps.h * g_m > 0.0) near_d = std::max(near_d, ps.h / g_m);
                                    g_big = std::max(g_big, std::abs(g_m));
                                }
                            }
                            if (f > 0.0 && f < 1.0)
                                keep(float_up(near_d * (1.0 + kCubeDepthSlack)),
                                     band_far(std::abs(ps.h), panel_spread[pt.axis], f, g_big));
                            continue;
                        }
                        if (panel_f != face) continue;
                        // The four corner rays cross the plane, at depth t, inside the rectangle inset per
                        // ray: their face coordinates in the tangent ranges?
                        const TangentRange range_u = panel_tangent_range(
                            t, double(panel.min[ua]) - double(eye[ua]),
                            double(panel.max[ua]) - double(eye[ua]), panel_spread[ua], panel_spread[a]);
                        const TangentRange range_v = panel_tangent_range(
                            t, double(panel.min[va]) - double(eye[va]),
                            double(panel.max[va]) - double(eye[va]), panel_spread[va], panel_spread[a]);
                        const bool hits = range_u.contains(grid(i, r)) && range_u.contains(grid(i + 1, r)) &&
                                          range_v.contains(grid(j, r)) && range_v.contains(grid(j + 1, r));
                        if (hits) pixel = std::min(pixel, float_up(t * (1.0 + kCubeDepthSlack)));
                        if (hits || !panel_bands) continue;
                        double f = 1.0;
                        for (int c = 0; c <= 1; ++c) {
                            const double gu = grid(i + c, r), gv = grid(j + c, r);
                            if (!range_u.contains(gu))
                                f = std::min(f, inset_share(t, gu, double(panel.min[ua]) - double(eye[ua]),
                                                            double(panel.max[ua]) - double(eye[ua]),
                                                            panel_spread[ua], panel_spread[a]));
                            if (!range_v.contains(gv))
                                f = std::min(f, inset_share(t, gv, double(panel.min[va]) - double(eye[va]),
                                                            double(panel.max[va]) - double(eye[va]),
                                                            panel_spread[va], panel_spread[a]));
                        }
                        if (f > 0.0 && f < 1.0)
                            keep(float_up(t * (1.0 + kCubeDepthSlack)), band_far(t, panel_spread[a], f, 1.0));
                    }
                for (const SlantedPanel& sp : slanted) {
                    SlantedRule rule;
                    if (!slanted_rule(sp, eye, panel_spread, rule)) continue;
                    double d = 0.0;
                    for (int cj = j; cj <= j + 1; ++cj)
                        for (int ci = i; ci <= i + 1; ++ci)
                            d = std::max(d, slanted_vertex_depth(
                                                rule, face_direction(face, grid(ci, r), grid(cj, r))));
                    if (d < kInf) pixel = std::min(pixel, float_up(d * (1.0 + kCubeDepthSlack)));
                }
                for (const auto& [rule, cf] : face_corners) {
                    const int m = cf.major_is_u ? i : j, n = cf.major_is_u ? j : i;
                    const size_t fp = face == rule.face[0] ? 0 : 1;
                    double lo, hi, d;
                    if (corner_in_band(rule, fp, grid(m, r), grid(m + 1, r)) &&
                        corner_row(cf, grid(m, r), grid(m + 1, r), lo, hi, d) && lo <= grid(n, r) &&
                        grid(n + 1, r) <= hi)
                        pixel = std::min(pixel, float_up(d * (1.0 + kCubeDepthSlack)));
                }
                if (double(pixel) < limit) continue;
                const double box_far = d_max * (1.0 + kCubeDepthSlack);
                if (panel_bands && double(band_near) < limit &&
                    (box_far <= double(band_far_end) || pixel <= band_far_end))
                    continue;
                return false;
            }
        }
    }
    return true;
}

}  // namespace pvs
