// Conservative depth cube map: occluder boxes written where they cover whole pixels, occludee boxes tested
// against every pixel they touch. Conventions and the safety argument: depth_cube.h.
//
// After: P. Wonka, M. Wimmer, D. Schmalstieg. Visibility Preprocessing with Occluder Fusion for Urban
// Walkthroughs. EGWR 2000 (the from-point test on shrunk occluders); H. Zhang et al. Visibility Culling
// using Hierarchical Occlusion Maps, SIGGRAPH 1997 (conservative depth comparisons on an occlusion map).
#include "pvs/depth_cube.h"

#include "core/error.h"

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
// bit patterns); much cheaper than std::nextafter, which was 9% of a bake.
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

FaceBox face_box(const Aabb& box, glm::vec3 eye, int face) {
    const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const double lo = double(box.min[a]) - double(eye[a]), hi = double(box.max[a]) - double(eye[a]);
    FaceBox fb;
    if (face % 2 == 0) {
        fb.d_min = lo;
        fb.d_max = hi;
    } else {
        fb.d_min = -hi;
        fb.d_max = -lo;
    }
    fb.u_lo = double(box.min[ua]) - double(eye[ua]);
    fb.u_hi = double(box.max[ua]) - double(eye[ua]);
    fb.v_lo = double(box.min[va]) - double(eye[va]);
    fb.v_hi = double(box.max[va]) - double(eye[va]);
    return fb;
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
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
};

// Smallest pixel index i in [0, r - 1] whose closed span [g(i), g(i + 1)] reaches up to lo (g(i + 1) >= lo).
int first_pixel_reaching(double lo, int r) {
    int i = std::clamp(int(std::floor((lo + 1.0) * 0.5 * r)), 0, r - 1);
    while (i > 0 && grid(i, r) >= lo) --i;
    while (i < r - 1 && grid(i + 1, r) < lo) ++i;
    return i;
}

// Largest pixel index i in [0, r - 1] with g(i) <= hi.
int last_pixel_reaching(double hi, int r) {
    int i = std::clamp(int(std::floor((hi + 1.0) * 0.5 * r)), 0, r - 1);
    while (i < r - 1 && grid(i + 1, r) <= hi) ++i;
    while (i > 0 && grid(i, r) > hi) --i;
    return i;
}

inline double pad_low(double x) {
    return std::clamp(x - kRectPad * std::max(1.0, std::abs(x)), -1.0, 1.0);
}
inline double pad_high(double x) {
    return std::clamp(x + kRectPad * std::max(1.0, std::abs(x)), -1.0, 1.0);
}

OccludeeFace occludee_face(const Aabb& box, glm::vec3 eye, int face, int r) {
    OccludeeFace of;
    const FaceBox fb = face_box(box, eye, face);
    const double lower = std::max(
        {fb.d_min, dist_to_zero(fb.u_lo, fb.u_hi), dist_to_zero(fb.v_lo, fb.v_hi), kCubeNearPlane_m});
    if (lower > fb.d_max) return of;  // no part of the box in this face's cone
    // Bounding rectangle of the projection of the box restricted to depths [lower, d_max] (a product set,
    // so each extreme is reached at a corner: pick the depth that pushes u outward).
    const double u0 = fb.u_lo >= 0.0 ? fb.u_lo / fb.d_max : fb.u_lo / lower;
    const double u1 = fb.u_hi >= 0.0 ? fb.u_hi / lower : fb.u_hi / fb.d_max;
    const double v0 = fb.v_lo >= 0.0 ? fb.v_lo / fb.d_max : fb.v_lo / lower;
    const double v1 = fb.v_hi >= 0.0 ? fb.v_hi / lower : fb.v_hi / fb.d_max;
    of.i0 = first_pixel_reaching(pad_low(u0), r);
    of.i1 = last_pixel_reaching(pad_high(u1), r);
    of.j0 = first_pixel_reaching(pad_low(v0), r);
    of.j1 = last_pixel_reaching(pad_high(v1), r);
    of.touched = of.i0 <= of.i1 && of.j0 <= of.j1;
    of.limit = lower * (1.0 - kCubeDepthSlack);
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
}

void DepthCube::clear(glm::vec3 eye) {
    eye_ = eye;
    std::fill(depth_.begin(), depth_.end(), kInfF);
    for (auto& r : region_) r = {0, resolution_ - 1, 0, resolution_ - 1};
}

void DepthCube::clear_for(glm::vec3 eye, const std::vector<Aabb>& boxes) {
    eye_ = eye;
    limit_to(boxes);
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        const auto& reg = region_[size_t(face)];
        for (int j = reg[2]; j <= reg[3]; ++j) {
            float* const row = depth_.data() + (size_t(face) * r + size_t(j)) * r;
            std::fill(row + reg[0], row + reg[1] + 1, kInfF);
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
        for (int face = 0; face < 6; ++face) {
            const OccludeeFace of = occludee_face(box, eye_, face, r);
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
        const FaceBox fb = face_box(box, eye_, face);
        const double d_lo = std::max(fb.d_min, kCubeNearPlane_m);  // clip to d >= near (safe: a sub-box)
        if (d_lo > fb.d_max) continue;
        // Candidate vertices: the bounding rectangle of the projection of box ∩ {d >= d_lo}; a pixel whose
        // four corners hit lies inside it. One vertex of slack each side absorbs rounding; the test at the
        // vertices decides, so extra candidates change nothing.
        const double u0 = fb.u_lo >= 0.0 ? fb.u_lo / fb.d_max : fb.u_lo / d_lo;
        const double u1 = fb.u_hi >= 0.0 ? fb.u_hi / d_lo : fb.u_hi / fb.d_max;
        const double v0 = fb.v_lo >= 0.0 ? fb.v_lo / fb.d_max : fb.v_lo / d_lo;
        const double v1 = fb.v_hi >= 0.0 ? fb.v_hi / d_lo : fb.v_hi / fb.d_max;
        if (u0 > 1.0 || u1 < -1.0 || v0 > 1.0 || v1 < -1.0) continue;
        const auto vertex_lo = [r](double x) {
            return std::max(0, int(std::floor((std::max(x, -1.0) + 1.0) * 0.5 * r)) - 1);
        };
        const auto vertex_hi = [r](double x) {
            return std::min(r, int(std::ceil((std::min(x, 1.0) + 1.0) * 0.5 * r)) + 1);
        };
        // Only the vertices of the pixels of the face's region (limit_to()).
        const auto& reg = region_[size_t(face)];
        const int iv0 = std::max(vertex_lo(u0), reg[0]), iv1 = std::min(vertex_hi(u1), reg[1] + 1);
        const int jv0 = std::max(vertex_lo(v0), reg[2]), jv1 = std::min(vertex_hi(v1), reg[3] + 1);
        if (iv1 - iv0 < 1 || jv1 - jv0 < 1) continue;  // fewer than two vertices: no whole pixel

        // Separable slab test: a corner ray (u, v, 1) (depth-parameterized) enters at
        // max(d_lo, enter_u(u), enter_v(v)) and leaves at min(d_max, exit_u(u), exit_v(v)).
        slabs(fb.u_lo, fb.u_hi, iv0, iv1, r, col_enter_.data(), col_exit_.data());
        slabs(fb.v_lo, fb.v_hi, jv0, jv1, r, row_enter_.data(), row_exit_.data());

        float* const face_depth = depth_.data() + size_t(face) * r * r;
        for (int jv = jv0; jv <= jv1; ++jv) {
            // Corner depths of this vertex row (+inf where the corner ray does not certainly hit).
            const double re = std::max(d_lo, row_enter_[jv]), rx = std::min(fb.d_max, row_exit_[jv]);
            for (int iv = iv0; iv <= iv1; ++iv) {
                const double enter = std::max(re, col_enter_[iv]);
                const double exit = std::min(rx, col_exit_[iv]);
                const double hit_depth = enter * (1.0 + kCubeDepthSlack);
                corner_cur_[iv] = exit >= hit_depth ? hit_depth : kInf;
            }
            if (jv > jv0) {
                // Branch-free, so that it vectorizes: min with float_up(d) keeps the pixel when d >= it
                // (float_up(d) >= d) and lowers it to float_up(d) otherwise.
                float* __restrict const row = face_depth + size_t(jv - 1) * r;
                const double* __restrict const cp = corner_prev_.data();
                const double* __restrict const cc = corner_cur_.data();
                for (int i = iv0; i < iv1; ++i) {
                    const float f =
                        float_up(std::max(std::max(cp[i], cp[i + 1]), std::max(cc[i], cc[i + 1])));
                    row[i] = f < row[i] ? f : row[i];
                }
            }
            std::swap(corner_prev_, corner_cur_);
        }
    }
}

namespace {

// How far inside a panel's rectangle, on one in-plane axis, the ray of grid value g on that axis must
// cross the plane so that the segment from any point of the ball of radius `ball` around the eye to any
// point beyond, along that ray, crosses the rectangle too: ball * sqrt(1 + g^2) (depth_cube.h), plus a
// hair for rounding. THE definition, shared by the kernel and the reference.
inline double panel_inset(double ball, double g) {
    return ball > 0.0 ? ball * std::sqrt(1.0 + g * g) * (1.0 + 1e-9) : 0.0;
}

// Does the corner ray of grid value g (on an in-plane axis) cross a panel's plane, at depth t, inside
// [lo, hi] on that axis, inset by panel_inset(), with room to spare? The same slab as a box's, and the same
// slack.
inline bool panel_corner_hits(double lo, double hi, double g, double t, double ball) {
    const double inset = panel_inset(ball, g);
    double enter, exit;
    slab(lo + inset, hi - inset, g, enter, exit);
    return enter * (1.0 + kCubeDepthSlack) <= t && t * (1.0 + kCubeDepthSlack) <= exit;
}

// The panel's plane relative to the eye: the face along its normal that looks at it, and its depth there;
// false when the panel is unusable (not flat along exactly one axis, not finite) or its plane is within
// the near plane or within the ball (radius * (1 + 1e-6)) of the eye.
bool panel_face(const Aabb& panel, glm::vec3 eye, double ball, int& face, double& depth) {
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
    if (!(std::abs(h) > std::max(kCubeNearPlane_m, ball * (1.0 + 1e-6)))) return false;
    face = 2 * axis + (h > 0.0 ? 0 : 1);
    depth = std::abs(h);
    return true;
}

}  // namespace

void DepthCube::add_panel(const Aabb& panel, double ball_radius) {
    int face = 0;
    double t = 0.0;
    if (!panel_face(panel, eye_, ball_radius, face, t)) return;
    const int r = resolution_, a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const double u_lo = double(panel.min[ua]) - double(eye_[ua]),
                 u_hi = double(panel.max[ua]) - double(eye_[ua]);
    const double v_lo = double(panel.min[va]) - double(eye_[va]),
                 v_hi = double(panel.max[va]) - double(eye_[va]);
    // Candidate vertices: those of the region's pixels within the projected rectangle, one vertex of slack
    // each side (the test at the vertices decides; extra candidates change nothing).
    const auto& reg = region_[size_t(face)];
    const auto vertex_lo = [r](double x) {
        return std::max(0, int(std::floor((std::max(x, -1.0) + 1.0) * 0.5 * r)) - 1);
    };
    const auto vertex_hi = [r](double x) {
        return std::min(r, int(std::ceil((std::min(x, 1.0) + 1.0) * 0.5 * r)) + 1);
    };
    if (u_lo / t > 1.0 || u_hi / t < -1.0 || v_lo / t > 1.0 || v_hi / t < -1.0) return;
    const int iv0 = std::max(vertex_lo(u_lo / t), reg[0]), iv1 = std::min(vertex_hi(u_hi / t), reg[1] + 1);
    const int jv0 = std::max(vertex_lo(v_lo / t), reg[2]), jv1 = std::min(vertex_hi(v_hi / t), reg[3] + 1);
    if (iv1 - iv0 < 1 || jv1 - jv0 < 1) return;
    // Vertices whose corner rays hit; a pixel is written when its four corners do.
    for (int iv = iv0; iv <= iv1; ++iv)
        col_enter_[iv] = panel_corner_hits(u_lo, u_hi, grid(iv, r), t, ball_radius) ? 1.0 : 0.0;
    for (int jv = jv0; jv <= jv1; ++jv)
        row_enter_[jv] = panel_corner_hits(v_lo, v_hi, grid(jv, r), t, ball_radius) ? 1.0 : 0.0;
    const float depth = float_up(t * (1.0 + kCubeDepthSlack));
    float* const face_depth = depth_.data() + size_t(face) * r * r;
    for (int j = jv0; j < jv1; ++j) {
        if (row_enter_[j] == 0.0 || row_enter_[j + 1] == 0.0) continue;
        float* const row = face_depth + size_t(j) * r;
        for (int i = iv0; i < iv1; ++i)
            if (col_enter_[i] != 0.0 && col_enter_[i + 1] != 0.0) row[i] = std::min(row[i], depth);
    }
}

void DepthCube::add_panels(const std::vector<Aabb>& panels, double ball_radius) {
    for (const Aabb& p : panels) add_panel(p, ball_radius);
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
        if (!is_hidden(boxes[b])) add_occluder(boxes[b]);
    }
}

PVS_AVX2_CLONES bool DepthCube::is_hidden(const Aabb& box) const {
    if (!box_usable(box) || meets_near_cube(box, eye_)) return false;
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        const OccludeeFace of = occludee_face(box, eye_, face, r);
        if (!of.touched) continue;
        // Pixels outside the drawn region hold no occluder (or, after clear_for(), stale depths): visible.
        const auto& reg = region_[size_t(face)];
        if (of.i0 < reg[0] || of.i1 > reg[1] || of.j0 < reg[2] || of.j1 > reg[3]) return false;
        // double(x) < limit exactly when x < float_up(limit), for every float x; and stored depths are
        // positive or +infinity, which order as their bit patterns. So the test is, a row at a time, an
        // unsigned max that vectorizes.
        const uint32_t limit = std::bit_cast<uint32_t>(float_up(of.limit));
        const float* const face_depth = depth_.data() + size_t(face) * r * r;
        for (int j = of.j0; j <= of.j1; ++j) {
            const float* __restrict const row = face_depth + size_t(j) * r;
            uint32_t farthest = 0;
            for (int i = of.i0; i <= of.i1; ++i)
                farthest = std::max(farthest, std::bit_cast<uint32_t>(row[i]));
            if (!(farthest < limit)) return false;
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

glm::dvec3 reference_direction(int face, double u, double v) {
    const int a = face / 2;
    glm::dvec3 dir(0.0);
    dir[a] = face % 2 == 0 ? 1.0 : -1.0;
    dir[(a + 1) % 3] = u;
    dir[(a + 2) % 3] = v;
    return dir;
}

}  // namespace

bool is_hidden_reference(const std::vector<Aabb>& occluders, glm::vec3 eye, const Aabb& box, int resolution) {
    return is_hidden_reference(occluders, {}, 0.0, eye, box, resolution);
}

bool is_hidden_reference(const std::vector<Aabb>& occluders, const std::vector<Aabb>& panels,
                         double panel_ball_radius, glm::vec3 eye, const Aabb& box, int resolution) {
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

        for (int j = 0; j < r; ++j) {
            for (int i = 0; i < r; ++i) {
                const bool touched =
                    grid(i, r) <= u1 && grid(i + 1, r) >= u0 && grid(j, r) <= v1 && grid(j + 1, r) >= v0;
                if (!touched) continue;
                float pixel = kInfF;
                for (const Aabb& occ : occluders) {
                    if (!box_usable(occ) || occ.contains(eye)) continue;
                    double d = 0.0;
                    for (int cj = j; cj <= j + 1; ++cj) {
                        for (int ci = i; ci <= i + 1; ++ci) {
                            d = std::max(d,
                                         reference_corner_depth(
                                             occ, eye, reference_direction(face, grid(ci, r), grid(cj, r))));
                        }
                    }
                    if (d < kInf) pixel = std::min(pixel, float_up(d));
                }
                for (const Aabb& panel : panels) {
                    int panel_f = 0;
                    double t = 0.0;
                    if (!panel_face(panel, eye, panel_ball_radius, panel_f, t) || panel_f != face) continue;
                    // The four corner rays cross the plane at depth t: inside the rectangle with room to
                    // spare?
                    bool hits = true;
                    for (int cj = j; cj <= j + 1; ++cj) {
                        for (int ci = i; ci <= i + 1; ++ci) {
                            const glm::dvec3 dir = reference_direction(face, grid(ci, r), grid(cj, r));
                            for (const int k : {ua, va}) {
                                // The rectangle inset for this corner ray, relative to the eye.
                                const double inset = panel_inset(panel_ball_radius, dir[k]);
                                const double lo_k = double(panel.min[k]) - double(eye[k]) + inset;
                                const double hi_k = double(panel.max[k]) - double(eye[k]) - inset;
                                double lo = lo_k / dir[k];
                                double hi = hi_k / dir[k];
                                if (dir[k] < 0.0) std::swap(lo, hi);
                                if (dir[k] == 0.0) {
                                    const bool in = lo_k <= 0.0 && hi_k >= 0.0;
                                    lo = in ? -kInf : kInf;
                                    hi = in ? kInf : -kInf;
                                }
                                hits = hits && lo * (1.0 + kCubeDepthSlack) <= t &&
                                       t * (1.0 + kCubeDepthSlack) <= hi;
                            }
                        }
                    }
                    if (hits) pixel = std::min(pixel, float_up(t * (1.0 + kCubeDepthSlack)));
                }
                if (!(double(pixel) < limit)) return false;
            }
        }
    }
    return true;
}

}  // namespace pvs
