// SPDX-License-Identifier: MIT
// Run-time culling of moving objects: shadow frusta of single occluder boxes, then a conservative float
// depth cube that fuses them. Conventions: include/pvsbake/occlusion.h; the safety argument:
// docs/ALGORITHMS.md#runtime-culler.
//
// After: T. Hudson et al. Accelerated Occlusion Culling using Shadow Frusta. SoCG 1997; H. Zhang et al.
// Visibility Culling using Hierarchical Occlusion Maps. SIGGRAPH 1997; P. Wonka, M. Wimmer, D. Schmalstieg.
// Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs. EGWR 2000 (pvs/depth_cube.h, the
// baker's double-precision version of the same rules).
#include <pvsbake/occlusion.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace pvsbake {
namespace {

constexpr float kInfF = std::numeric_limits<float>::infinity();
constexpr double kInfD = std::numeric_limits<double>::infinity();

inline bool usable_box(const Box& b) {
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a]) || b.min[a] > b.max[a]) return false;
    }
    return true;
}

// The one axis along which b is flat (a panel), -1 for a solid box, -2 when flat along two or three axes.
inline int flat_axis(const Box& b) {
    int flat = -1;
    for (int a = 0; a < 3; ++a) {
        if (b.min[a] != b.max[a]) continue;
        if (flat != -1) return -2;
        flat = a;
    }
    return flat;
}

// x + delta rounded up to a float (or x - delta rounded down, for delta < 0): a float bound moved inward by
// at least |delta|.
inline float moved_in(float x, double delta) {
    const double want = double(x) + delta;
    float f = float(want);
    if (delta > 0.0 && double(f) < want) f = std::nextafter(f, kInfF);
    if (delta < 0.0 && double(f) > want) f = std::nextafter(f, -kInfF);
    return f;
}

// Largest |coordinate| of the eye and the box: the scale of the margins.
inline double scale_of(const double eye[3], const Box& b) {
    double m = 0.0;
    for (int a = 0; a < 3; ++a) {
        m = std::max({m, std::abs(eye[a]), std::abs(double(b.min[a])), std::abs(double(b.max[a]))});
    }
    return m;
}

// The box relative to the eye in face f's axes, float.
struct FaceBox {
    float d_min, d_max;  // depth range along the face axis
    float u_lo, u_hi;    // Δ[ua] range
    float v_lo, v_hi;    // Δ[va] range
};

inline FaceBox face_box(const Box& b, const float eye[3], int face) {
    const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const float lo = b.min[a] - eye[a], hi = b.max[a] - eye[a];
    FaceBox fb;
    if (face % 2 == 0) {
        fb.d_min = lo;
        fb.d_max = hi;
    } else {
        fb.d_min = -hi;
        fb.d_max = -lo;
    }
    fb.u_lo = b.min[ua] - eye[ua];
    fb.u_hi = b.max[ua] - eye[ua];
    fb.v_lo = b.min[va] - eye[va];
    fb.v_hi = b.max[va] - eye[va];
    return fb;
}

inline bool finite_face_box(const FaceBox& fb) {
    return std::isfinite(fb.d_min) && std::isfinite(fb.d_max) && std::isfinite(fb.u_lo) &&
           std::isfinite(fb.u_hi) && std::isfinite(fb.v_lo) && std::isfinite(fb.v_hi);
}

// Distance from 0 to the interval [lo, hi].
inline float dist_to_zero(float lo, float hi) {
    return std::max({0.0f, lo, -hi});
}

// Interval of ray depths t with lo <= t * c <= hi (c: the corner ray's side component); empty: [inf, -inf].
inline void slab(float lo, float hi, float c, float& enter, float& exit) {
    if (c > 0.0f) {
        enter = lo / c;
        exit = hi / c;
    } else if (c < 0.0f) {
        enter = hi / c;
        exit = lo / c;
    } else if (lo <= 0.0f && 0.0f <= hi) {
        enter = -kInfF;
        exit = kInfF;
    } else {
        enter = kInfF;
        exit = -kInfF;
    }
}

// Smallest pixel i in [0, r - 1] whose closed span [g(i), g(i + 1)] reaches down to lo (g(i + 1) >= lo).
inline int first_pixel_reaching(const float* g, float lo, int r) {
    int i = std::clamp(int(std::floor((lo + 1.0f) * 0.5f * float(r))), 0, r - 1);
    while (i > 0 && g[i] >= lo) --i;
    while (i < r - 1 && g[i + 1] < lo) ++i;
    return i;
}

// Largest pixel i in [0, r - 1] with g(i) <= hi.
inline int last_pixel_reaching(const float* g, float hi, int r) {
    int i = std::clamp(int(std::floor((hi + 1.0f) * 0.5f * float(r))), 0, r - 1);
    while (i < r - 1 && g[i + 1] <= hi) ++i;
    while (i > 0 && g[i] > hi) --i;
    return i;
}

// The occludee's rectangle widened, clamped to [-1, 1]; NaN (from inf - inf on huge boxes) widens fully.
inline float pad_low(float x) {
    const float y = x - OcclusionCuller::kRectPad * std::max(1.0f, std::abs(x));
    return y > -1.0f ? std::min(y, 1.0f) : -1.0f;
}
inline float pad_high(float x) {
    const float y = x + OcclusionCuller::kRectPad * std::max(1.0f, std::abs(x));
    return y < 1.0f ? std::max(y, -1.0f) : 1.0f;
}

}  // namespace

OcclusionCuller::OcclusionCuller(int resolution) noexcept {
    const int r = resolution <= 0 ? 0 : std::clamp((resolution + 1) & ~1, kMinResolution, kMaxResolution);
    for (Rect& w : written_) w = {0, -1, 0, -1};
    try {
        frusta_.resize(kMaxOccluders);
        candidates_.reserve(kMaxOccluders);
        if (r > 0) {
            grid_.resize(size_t(r) + 1);
            for (int k = 0; k <= r; ++k) grid_[size_t(k)] = float(-1.0 + 2.0 * double(k) / double(r));
            depth_.assign(size_t(6) * size_t(r) * size_t(r), kInfF);
            for (auto* v : {&col_enter_, &col_exit_, &row_enter_, &row_exit_, &corner_prev_, &corner_cur_}) {
                v->resize(size_t(r) + 1);
            }
        }
        resolution_ = r;
        ok_ = true;
    } catch (...) {  // std::bad_alloc: a culler that culls nothing
        ok_ = false;
        resolution_ = 0;
    }
}

uint32_t OcclusionCuller::begin_cell(const Bake& bake, uint32_t c, const float eye[3],
                                     size_t max_occluders) noexcept {
    Box boxes[kMaxOccluders];
    const uint32_t n = bake.occluder_boxes(c, boxes, uint32_t(std::min(max_occluders, kMaxOccluders)));
    begin_frame(eye, boxes, n);
    return n;
}

void OcclusionCuller::begin_frame(const float eye[3], const Box* occluders, size_t count,
                                  size_t stride_bytes) noexcept {
    // Clear what the last frame wrote.
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        Rect& w = written_[face];
        for (int j = w.j0; j <= w.j1; ++j) {
            float* row = depth_.data() + (size_t(face) * size_t(r) + size_t(j)) * size_t(r);
            std::fill(row + w.i0, row + w.i1 + 1, kInfF);
        }
        w = {0, -1, 0, -1};
    }
    used_ = 0;
    redundant_ = 0;
    frustum_count_ = 0;
    eye_ok_ =
        ok_ && eye != nullptr && std::isfinite(eye[0]) && std::isfinite(eye[1]) && std::isfinite(eye[2]);
    if (!eye_ok_) return;
    for (int a = 0; a < 3; ++a) {
        eye_[a] = eye[a];
        eye_d_[a] = double(eye[a]);
    }
    if (occluders == nullptr) count = 0;
    if (stride_bytes == 0) stride_bytes = sizeof(Box);
    const unsigned char* base = reinterpret_cast<const unsigned char*>(occluders);
    const double* e = eye_d_;

    // The usable boxes (the first kMaxOccluders), nearest first: a box that those before it already hide
    // (its shadow lies in theirs, and it could not lower any pixel of the cube) is redundant and skipped.
    candidates_.clear();
    for (size_t k = 0; k < count && candidates_.size() < kMaxOccluders; ++k) {
        Candidate c;
        std::memcpy(&c.box, base + k * stride_bytes, sizeof(Box));
        if (!usable_box(c.box)) continue;
        const Box& b = c.box;
        c.delta = kMargin_m + kMarginRel * scale_of(e, b);
        c.flat = flat_axis(b);
        c.raster = b;
        if (c.flat == -2) continue;  // a segment or a point: hides nothing
        if (c.flat >= 0) {           // a panel: off its plane, its rectangle shrunk by the margin
            if (!(std::abs(double(b.min[c.flat]) - e[c.flat]) > c.delta)) continue;
            bool empty = false;
            for (int a = 0; a < 3; ++a) {
                if (a == c.flat) continue;
                c.raster.min[a] = moved_in(b.min[a], c.delta);
                c.raster.max[a] = moved_in(b.max[a], -c.delta);
                empty = empty || !(c.raster.min[a] < c.raster.max[a]);
            }
            if (empty) continue;
        }
        bool touches_eye = true;
        double dist2 = 0.0;
        for (int a = 0; a < 3; ++a) {
            touches_eye =
                touches_eye && double(b.min[a]) - c.delta <= e[a] && e[a] <= double(b.max[a]) + c.delta;
            const double d = std::max({0.0, double(b.min[a]) - e[a], e[a] - double(b.max[a])});
            dist2 += d * d;
        }
        if (touches_eye) continue;
        c.dist2 = dist2;
        candidates_.push_back(c);  // no allocation: reserved for kMaxOccluders
    }
    std::sort(candidates_.begin(), candidates_.end(),
              [](const Candidate& x, const Candidate& y) { return x.dist2 < y.dist2; });
    for (const Candidate& c : candidates_) {
        if (used_ > 0 && classify(c.box) != Path::kVisible) {
            ++redundant_;
            continue;
        }
        ++used_;
        if (r > 0) rasterize(c.raster, c.flat);
        build_frustum(c.box, c.delta, c.flat, frusta_[frustum_count_++]);
    }
}

void OcclusionCuller::build_frustum(const Box& b, double delta, int flat, Frustum& fr) const noexcept {
    const double* e = eye_d_;
    // The shadow frustum of B shrunk by delta (a panel: in its plane only), relative to the eye.
    fr.planes = 0;
    fr.usable = true;
    double lo[3], hi[3];
    bool below[3], above[3];
    for (int a = 0; a < 3; ++a) {
        const double shrink = a == flat ? 0.0 : delta;
        lo[a] = double(b.min[a]) + shrink - e[a];
        hi[a] = double(b.max[a]) - shrink - e[a];
        fr.usable = fr.usable && (a == flat ? lo[a] == hi[a] && lo[a] != 0.0 : lo[a] < hi[a]);
        below[a] = 0.0 < lo[a];  // the eye is below the box on axis a: face min[a] faces it
        above[a] = hi[a] < 0.0;
        fr.lo[a] = below[a] ? lo[a] : -kInfD;
        fr.hi[a] = above[a] ? hi[a] : kInfD;
    }
    if (!fr.usable) return;
    // Silhouette edges: an edge along axis k at sides (si, sj) of axes i, j is on the silhouette when
    // exactly one of its two faces faces the eye. Its plane through the eye has normal ⊥ k.
    for (int k3 = 0; k3 < 3 && fr.usable; ++k3) {
        const int i = (k3 + 1) % 3, j = (k3 + 2) % 3;
        for (int si = 0; si < 2; ++si) {
            for (int sj = 0; sj < 2; ++sj) {
                const bool front_i = si == 0 ? below[i] : above[i];
                const bool front_j = sj == 0 ? below[j] : above[j];
                if (front_i == front_j) continue;
                const double pi = si == 0 ? lo[i] : hi[i], pj = sj == 0 ? lo[j] : hi[j];
                double ni = -pj, nj = pi;  // ⊥ (pi, pj) in the (i, j) plane
                const double side = ni * 0.5 * (lo[i] + hi[i]) + nj * 0.5 * (lo[j] + hi[j]);
                if (!(side != 0.0) || fr.planes == 6) {  // degenerate: do not trust this frustum
                    fr.usable = false;
                    break;
                }
                if (side < 0.0) {
                    ni = -ni;
                    nj = -nj;
                }
                double* n = fr.n[fr.planes];
                n[k3] = 0.0;
                n[i] = ni;
                n[j] = nj;
                fr.w[fr.planes] = 0.0;
                ++fr.planes;
            }
            if (!fr.usable) break;
        }
    }
}

void OcclusionCuller::rasterize(const Box& b, int flat) noexcept {
    const int r = resolution_;
    const float* g = grid_.data();
    for (int face = 0; face < 6; ++face) {
        const FaceBox fb = face_box(b, eye_, face);
        if (!finite_face_box(fb)) return;
        const float d_lo = std::max(fb.d_min, kNearPlane_m);  // clip to d >= near (safe: a sub-box)
        if (flat == face / 2 ? !(d_lo <= fb.d_max) : !(d_lo < fb.d_max)) continue;
        // Candidate vertices: the bounding rectangle of the projection of B ∩ {d >= d_lo}, one vertex of
        // slack each side; the corner tests decide, so extra candidates change nothing.
        const float u0 = fb.u_lo >= 0.0f ? fb.u_lo / fb.d_max : fb.u_lo / d_lo;
        const float u1 = fb.u_hi >= 0.0f ? fb.u_hi / d_lo : fb.u_hi / fb.d_max;
        const float v0 = fb.v_lo >= 0.0f ? fb.v_lo / fb.d_max : fb.v_lo / d_lo;
        const float v1 = fb.v_hi >= 0.0f ? fb.v_hi / d_lo : fb.v_hi / fb.d_max;
        if (u0 > 1.0f || u1 < -1.0f || v0 > 1.0f || v1 < -1.0f) continue;
        const auto vertex_lo = [r](float x) {
            return std::max(0, int(std::floor((std::max(x, -1.0f) + 1.0f) * 0.5f * float(r))) - 1);
        };
        const auto vertex_hi = [r](float x) {
            return std::min(r, int(std::ceil((std::min(x, 1.0f) + 1.0f) * 0.5f * float(r))) + 1);
        };
        const int iv0 = vertex_lo(u0), iv1 = vertex_hi(u1), jv0 = vertex_lo(v0), jv1 = vertex_hi(v1);
        if (iv1 - iv0 < 1 || jv1 - jv0 < 1) continue;  // fewer than two vertices: no whole pixel

        // Separable slab test: the corner ray (u, v, 1), parameterized by depth, enters B at
        // max(d_lo, enter_u(u), enter_v(v)) and leaves at min(d_max, exit_u(u), exit_v(v)). A solid box needs
        // room to spare (exit >= entry * (1 + slack)); a panel's plane is one depth, so entry = exit there,
        // and the margin its rectangle was shrunk by stands in for the room.
        const float room = flat >= 0 ? 1.0f : 1.0f + kDepthSlack;
        for (int iv = iv0; iv <= iv1; ++iv) slab(fb.u_lo, fb.u_hi, g[iv], col_enter_[iv], col_exit_[iv]);
        for (int jv = jv0; jv <= jv1; ++jv) slab(fb.v_lo, fb.v_hi, g[jv], row_enter_[jv], row_exit_[jv]);

        float* const face_depth = depth_.data() + size_t(face) * size_t(r) * size_t(r);
        Rect& w = written_[face];
        for (int jv = jv0; jv <= jv1; ++jv) {
            const float re = std::max(d_lo, row_enter_[jv]), rx = std::min(fb.d_max, row_exit_[jv]);
            for (int iv = iv0; iv <= iv1; ++iv) {
                const float enter = std::max(re, col_enter_[iv]);
                const float exit = std::min(rx, col_exit_[iv]);
                const float hit_depth = enter * (1.0f + kDepthSlack);
                corner_cur_[iv] = exit >= enter * room ? hit_depth : kInfF;
            }
            if (jv > jv0) {
                // The pixel's depth: the farthest of its four corners (+inf when one misses). Branch-free, so
                // that the compiler vectorizes it; then the row's written range from both ends.
                float* const row = face_depth + size_t(jv - 1) * size_t(r);
                const float* const p = corner_prev_.data();
                const float* const c = corner_cur_.data();
                const auto pixel = [p, c](int i) {
                    const float a = p[i] > p[i + 1] ? p[i] : p[i + 1];
                    const float b = c[i] > c[i + 1] ? c[i] : c[i + 1];
                    return a > b ? a : b;
                };
                for (int i = iv0; i < iv1; ++i) {
                    const float d = pixel(i);
                    row[i] = d < row[i] ? d : row[i];
                }
                int first = iv0, last = iv1 - 1;
                while (first <= last && !(pixel(first) < kInfF)) ++first;
                while (last >= first && !(pixel(last) < kInfF)) --last;
                if (first <= last) {
                    if (w.i0 > w.i1) {
                        w = {first, last, jv - 1, jv - 1};
                    } else {
                        w = {std::min(w.i0, first), std::max(w.i1, last), std::min(w.j0, jv - 1),
                             std::max(w.j1, jv - 1)};
                    }
                }
            }
            std::swap(corner_prev_, corner_cur_);
        }
    }
}

bool OcclusionCuller::inside_shadow(const Frustum& fr, const double q_min[3],
                                    const double q_max[3]) const noexcept {
    for (int a = 0; a < 3; ++a) {
        if (!(q_min[a] >= fr.lo[a] && q_max[a] <= fr.hi[a])) return false;
    }
    for (int p = 0; p < fr.planes; ++p) {
        const double* n = fr.n[p];
        double s = 0.0;  // the least n . x over the box: its corner on the far side of the plane
        for (int a = 0; a < 3; ++a) s += n[a] * (n[a] >= 0.0 ? q_min[a] : q_max[a]);
        if (!(s > fr.w[p])) return false;
    }
    return true;
}

bool OcclusionCuller::hidden_by_shadow_frusta(const Box& box) const noexcept {
    if (!eye_ok_ || frustum_count_ == 0 || !usable_box(box)) return false;
    // Q grown by its margin, relative to the eye.
    const double delta = kMargin_m + kMarginRel * scale_of(eye_d_, box);
    double q_min[3], q_max[3];
    for (int a = 0; a < 3; ++a) {
        q_min[a] = double(box.min[a]) - delta - eye_d_[a];
        q_max[a] = double(box.max[a]) + delta - eye_d_[a];
    }
    // (A Q holding the eye fails every front-face test below: the eye is in front of each front face.)
    for (size_t k = 0; k < frustum_count_; ++k) {
        const Frustum& fr = frusta_[k];
        if (fr.usable && inside_shadow(fr, q_min, q_max)) return true;
    }
    return false;
}

bool OcclusionCuller::hidden_by_depth_cube(const Box& box) const noexcept {
    const int r = resolution_;
    if (!eye_ok_ || r == 0 || used_ == 0 || !usable_box(box)) return false;
    // Visible when the box meets the closed near cube around the eye (this covers "contains the eye").
    bool near = true;
    for (int a = 0; a < 3; ++a) {
        near = near && box.min[a] - eye_[a] <= kNearPlane_m && box.max[a] - eye_[a] >= -kNearPlane_m;
    }
    if (near) return false;
    const float* g = grid_.data();
    bool any_face = false;
    for (int face = 0; face < 6; ++face) {
        const FaceBox fb = face_box(box, eye_, face);
        if (!finite_face_box(fb)) return false;
        float lower = std::max(
            {fb.d_min, dist_to_zero(fb.u_lo, fb.u_hi), dist_to_zero(fb.v_lo, fb.v_hi), kNearPlane_m});
        if (lower > fb.d_max * (1.0f + kDepthSlack)) continue;  // no part of the box in this face's cone
        lower = std::min(lower, fb.d_max);
        any_face = true;
        // Bounding rectangle of the projection of box ∩ {lower <= d <= d_max}: each extreme at a corner.
        const float u0 = fb.u_lo >= 0.0f ? fb.u_lo / fb.d_max : fb.u_lo / lower;
        const float u1 = fb.u_hi >= 0.0f ? fb.u_hi / lower : fb.u_hi / fb.d_max;
        const float v0 = fb.v_lo >= 0.0f ? fb.v_lo / fb.d_max : fb.v_lo / lower;
        const float v1 = fb.v_hi >= 0.0f ? fb.v_hi / lower : fb.v_hi / fb.d_max;
        const int i0 = first_pixel_reaching(g, pad_low(u0), r), i1 = last_pixel_reaching(g, pad_high(u1), r);
        const int j0 = first_pixel_reaching(g, pad_low(v0), r), j1 = last_pixel_reaching(g, pad_high(v1), r);
        if (i0 > i1 || j0 > j1) continue;
        const Rect& w = written_[face];  // a touched pixel nobody wrote is +infinity: visible
        if (i0 < w.i0 || i1 > w.i1 || j0 < w.j0 || j1 > w.j1) return false;
        const float limit = lower * (1.0f - kDepthSlack);
        const float* const face_depth = depth_.data() + size_t(face) * size_t(r) * size_t(r);
        for (int j = j0; j <= j1; ++j) {
            const float* const row = face_depth + size_t(j) * size_t(r);
            for (int i = i0; i <= i1; ++i) {
                if (!(row[i] < limit)) return false;
            }
        }
    }
    return any_face;
}

OcclusionCuller::Path OcclusionCuller::classify(const Box& box) const noexcept {
    if (!eye_ok_ || used_ == 0 || !usable_box(box)) return Path::kVisible;
    if (hidden_by_shadow_frusta(box)) return Path::kShadowFrustum;
    if (hidden_by_depth_cube(box)) return Path::kDepthBuffer;
    return Path::kVisible;
}

size_t OcclusionCuller::covered_pixels() const noexcept {
    size_t n = 0;
    const int r = resolution_;
    for (int face = 0; face < 6; ++face) {
        const Rect& w = written_[face];
        for (int j = w.j0; j <= w.j1; ++j) {
            const float* row = depth_.data() + (size_t(face) * size_t(r) + size_t(j)) * size_t(r);
            for (int i = w.i0; i <= w.i1; ++i) n += row[i] < kInfF;
        }
    }
    return n;
}

}  // namespace pvsbake
