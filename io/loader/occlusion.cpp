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

// ---- Exact fusion of the occluders' faces (docs/ALGORITHMS.md#runtime-faces): the box is cut into
// fragments, each a sub-box with a convex polygon of directions, until every fragment lies beyond a face in
// directions the face covers (hidden) or one fragment has passed every face (visible). Directions are
// central projections along one axis p on which the whole box lies ahead of the eye: u = x[U] / d,
// v = x[V] / d with d = sign * x[p] > 0 (everything relative to the eye). The same arithmetic as the C99
// runtime's (runtime/pvsr.c), so that both give the same answers.
constexpr int kFuseMaxVerts = 16;  // of a fragment's polygon; more: give up (visible)
constexpr int kFuseMaxFaces = 96;  // faces a box is tested against (the nearest first), polygons among them
constexpr int kFuseMaxFragments = 32;  // fragments pending; more: give up (visible)
constexpr double kFuseEps = 1e-12;     // relative: a covered region shrunk, a box's directions widened
constexpr double kFuseGrowRel = 1e-9;  // a face grows by this times (1 + the largest |coordinate|), metres
constexpr int kFuseProjVerts = OcclusionCuller::kMaxPolygonCorners + 1;  // a cross-section clipped at near
constexpr int kFusePolyVerts = 2 * kFuseProjVerts;                       // two such projections intersected
constexpr int kFusePool = 6 * kFuseMaxFaces + kFusePolyVerts * int(OcclusionCuller::kMaxPolygons);

struct FusePoly {
    int n = 0;
    double x[kFuseMaxVerts], y[kFuseMaxVerts];
};

// A face or polygon occluder in the test's frame. The part of a box beyond it is, along `axis`, where the
// coordinate is at least (`above`) or at most its cut: a face's plane moved away by delta, or, for a
// polygon, the least coordinate there at which every point of the box's cross-section has n.x >= w.
struct FuseFace {
    const double *x, *y;  // its projection (counter-clockwise), in the test's vertex pool
    double lo[2], hi[2];  // that polygon's bounds
    double plane, delta;  // a face
    double n[3], w;       // a polygon: n.x >= w (relative) lies beyond its slab and margin
    int count, axis;
    bool above, poly;
};

struct FuseFragment {
    double b[6];  // relative to the eye
    FusePoly r;
    int next;  // the first face not yet applied
};

struct FuseFrame {
    int p, u, v;
    double sign;
};

inline double widen(double x, bool up) {
    const double m = kFuseEps * (1.0 + std::abs(x));
    return up ? x + m : x - m;
}

// Keeps the part of the polygon (ix, iy, n) where a * x + b * y <= w, into (ox, oy); its vertex count, or -1
// when it would have more than cap.
int clip_arrays(const double* ix, const double* iy, int n, double a, double b, double w, double* ox,
                double* oy, int cap) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        const double si = a * ix[i] + b * iy[i] - w, sj = a * ix[j] + b * iy[j] - w;
        if (si <= 0.0) {
            if (m == cap) return -1;
            ox[m] = ix[i];
            oy[m++] = iy[i];
        }
        if ((si < 0.0 && sj > 0.0) || (si > 0.0 && sj < 0.0)) {
            const double t = si / (si - sj);
            if (m == cap) return -1;
            ox[m] = ix[i] + t * (ix[j] - ix[i]);
            oy[m++] = iy[i] + t * (iy[j] - iy[i]);
        }
    }
    return m;
}

// Keeps the part of `in` where a * x + b * y <= w; false when the result would have too many vertices.
bool clip_poly(const FusePoly& in, double a, double b, double w, FusePoly& out) {
    out.n = clip_arrays(in.x, in.y, in.n, a, b, w, out.x, out.y, kFuseMaxVerts);
    if (out.n >= 0) return true;
    out.n = 0;
    return false;
}

void poly_bounds(const double* x, const double* y, int n, double lo[2], double hi[2]) {
    lo[0] = hi[0] = x[0];
    lo[1] = hi[1] = y[0];
    for (int i = 1; i < n; ++i) {
        lo[0] = x[i] < lo[0] ? x[i] : lo[0];
        hi[0] = x[i] > hi[0] ? x[i] : hi[0];
        lo[1] = y[i] < lo[1] ? y[i] : lo[1];
        hi[1] = y[i] > hi[1] ? y[i] : hi[1];
    }
}

// The bounds of the directions of box b (relative, all of it at d >= its near side > 0), widened.
void box_directions(const FuseFrame& f, const double b[6], double lo[2], double hi[2]) {
    const double d0 = f.sign > 0.0 ? b[f.p] : -b[3 + f.p], d1 = f.sign > 0.0 ? b[3 + f.p] : -b[f.p];
    const int ax[2] = {f.u, f.v};
    for (int k = 0; k < 2; ++k) {
        const double l = b[ax[k]], h = b[3 + ax[k]];
        lo[k] = widen(l >= 0.0 ? l / d1 : l / d0, false);
        hi[k] = widen(h >= 0.0 ? h / d0 : h / d1, true);
    }
}

// r clipped to the rectangle [lo, hi]: 1, 0 when empty, -1 when a polygon would have too many vertices.
int clip_to_rect(FusePoly& r, const double lo[2], const double hi[2]) {
    const double a[4] = {-1.0, 1.0, 0.0, 0.0}, b[4] = {0.0, 0.0, -1.0, 1.0};
    const double w[4] = {-lo[0], hi[0], -lo[1], hi[1]};
    double plo[2], phi[2];
    poly_bounds(r.x, r.y, r.n, plo, phi);
    for (int k = 0; k < 4 && r.n >= 3; ++k) {
        const bool cuts = k == 0   ? plo[0] < lo[0]
                          : k == 1 ? phi[0] > hi[0]
                          : k == 2 ? plo[1] < lo[1]
                                   : phi[1] > hi[1];
        if (!cuts) continue;
        FusePoly t;
        if (!clip_poly(r, a[k], b[k], w[k], t)) return -1;
        r = t;
    }
    return r.n >= 3 ? 1 : 0;
}

bool push_fragment(FuseFragment* stack, int& top, const double b[6], const FusePoly& r, int next) {
    if (top == kFuseMaxFragments) return false;
    std::memcpy(stack[top].b, b, sizeof stack[top].b);
    stack[top].r = r;
    stack[top++].next = next;
    return true;
}

// Pushes the parts of r outside the face's polygon, shrunk by kFuseEps (their union covers r less the
// shrunk polygon); false when the stack or a polygon overflows.
bool push_outside(FuseFragment* stack, int& top, const double b[6], const FusePoly& r, const FuseFace& q,
                  int next) {
    FusePoly cur = r, piece, rest;
    for (int k = 0; k < q.count; ++k) {
        const int k1 = (k + 1) % q.count;
        const double nx = -(q.y[k1] - q.y[k]), ny = q.x[k1] - q.x[k];  // inward: left of the edge
        const double w = nx * q.x[k] + ny * q.y[k];
        const double eps =
            kFuseEps * (std::abs(nx) + std::abs(ny)) * (1.0 + std::abs(q.x[k]) + std::abs(q.y[k]));
        bool any_out = false, any_in = false;
        for (int i = 0; i < cur.n; ++i) {
            const double s = nx * cur.x[i] + ny * cur.y[i] - w;
            any_out = any_out || !(s >= eps);  // a NaN counts as outside: kept, never hidden
            any_in = any_in || s > eps;
        }
        if (!any_out) continue;
        if (!any_in) return push_fragment(stack, top, b, cur, next);
        if (!clip_poly(cur, nx, ny, w + eps, piece) || !clip_poly(cur, -nx, -ny, -(w + eps), rest))
            return false;
        if (piece.n >= 3 && !push_fragment(stack, top, b, piece, next)) return false;
        if (rest.n < 3) return true;
        cur = rest;
    }
    return true;
}

// Projects a convex polygon of n <= kMaxPolygonCorners points (relative to the eye) in frame f: its part at
// d >= the near plane, counter-clockwise, into x, y (kFuseProjVerts room); its vertex count, or 0 when
// nothing or a degenerate polygon is left.
int project_points(const FuseFrame& f, const double (*c)[3], int n, double* x, double* y) {
    const double near_d = double(OcclusionCuller::kNearPlane_m);
    double d[kFuseProjVerts], u[kFuseProjVerts], v[kFuseProjVerts], area = 0.0;
    int m = 0;
    for (int i = 0; i < n; ++i) {  // clipped to d >= near
        const int j = (i + 1) % n;
        const double di = f.sign * c[i][f.p], dj = f.sign * c[j][f.p];
        if (di >= near_d) {
            d[m] = di;
            u[m] = c[i][f.u];
            v[m++] = c[i][f.v];
        }
        if ((di < near_d && dj > near_d) || (di > near_d && dj < near_d)) {
            const double t = (near_d - di) / (dj - di);
            d[m] = near_d;
            u[m] = c[i][f.u] + t * (c[j][f.u] - c[i][f.u]);
            v[m++] = c[i][f.v] + t * (c[j][f.v] - c[i][f.v]);
        }
    }
    if (m < 3) return 0;
    for (int i = 0; i < m; ++i) {
        const double inv = 1.0 / d[i];
        x[i] = u[i] * inv;
        y[i] = v[i] * inv;
    }
    for (int i = 0; i < m; ++i) {
        const int j = (i + 1) % m;
        area += x[i] * y[j] - x[j] * y[i];
    }
    if (!(area != 0.0) || !std::isfinite(area)) return 0;
    if (area < 0.0) {
        std::reverse(x, x + m);
        std::reverse(y, y + m);
    }
    return m;
}

// The part of box b beyond face t: along *ax the coordinates at least *cut (t.above) or at most it; false
// when no part of b lies beyond.
bool beyond_part(const FuseFace& t, const double b[6], int& ax, double& cut) {
    const int a = t.axis;
    ax = a;
    if (!t.poly) {
        cut = t.above ? t.plane + t.delta : t.plane - t.delta;
    } else {  // n.x >= w over the cross-section: n[a] x[a] >= w - (the least of the other two terms)
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        const double m1 = t.n[a1] > 0.0 ? t.n[a1] * b[a1] : t.n[a1] * b[3 + a1];
        const double m2 = t.n[a2] > 0.0 ? t.n[a2] * b[a2] : t.n[a2] * b[3 + a2];
        cut = widen((t.w - m1 - m2) / t.n[a], t.above);
    }
    return t.above ? b[3 + a] > cut : b[a] < cut;
}

// Projects a face (x[axis] = plane, the rectangle lo..hi on the other two axes; absolute) in frame f into the
// pool at x, y: its part at d >= the near plane, counter-clockwise.
bool project_face(const FuseFrame& f, int a, double plane, const double lo[2], const double hi[2],
                  const double e[3], double* x, double* y, FuseFace& out) {
    const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
    double c[4][3];
    for (int i = 0; i < 4; ++i) {
        c[i][a] = plane - e[a];
        c[i][a1] = (i == 1 || i == 2 ? hi[0] : lo[0]) - e[a1];
        c[i][a2] = (i >= 2 ? hi[1] : lo[1]) - e[a2];
    }
    out.count = project_points(f, c, 4, x, y);
    if (out.count == 0) return false;
    out.x = x;
    out.y = y;
    poly_bounds(x, y, out.count, out.lo, out.hi);
    return true;
}

// Projects a polygon occluder (relative to the eye: unit normal n away from the eye, its slab's planes
// n.x = near_w and far_w, `count` corners) in frame f into the pool at x, y (kFusePolyVerts room): the
// directions whose segments cross both planes of its slab inside its prism, the projections of the two
// cross-sections intersected (docs/ALGORITHMS.md#runtime-polygons).
bool project_polygon(const FuseFrame& f, const double n[3], double near_w, double far_w, const double (*c)[3],
                     int count, double* x, double* y, FuseFace& out) {
    double s[2][OcclusionCuller::kMaxPolygonCorners][3], px[2][kFuseProjVerts], py[2][kFuseProjVerts];
    int m[2];
    for (int h = 0; h < 2; ++h) {
        const double w = h == 0 ? near_w : far_w;
        for (int i = 0; i < count; ++i) {
            const double up = w - (n[0] * c[i][0] + n[1] * c[i][1] + n[2] * c[i][2]);
            for (int a = 0; a < 3; ++a) s[h][i][a] = c[i][a] + up * n[a];
        }
        m[h] = project_points(f, s[h], count, px[h], py[h]);
        if (m[h] == 0) return false;
    }
    double cx[2][kFusePolyVerts], cy[2][kFusePolyVerts];
    int cn = m[0], cur = 0;
    std::copy(px[0], px[0] + cn, cx[0]);
    std::copy(py[0], py[0] + cn, cy[0]);
    for (int k = 0; k < m[1] && cn >= 3; ++k) {  // left of every edge of the far projection
        const int k1 = (k + 1) % m[1];
        const double dx = px[1][k1] - px[1][k], dy = py[1][k1] - py[1][k];
        cn = clip_arrays(cx[cur], cy[cur], cn, dy, -dx, dy * px[1][k] - dx * py[1][k], cx[1 - cur],
                         cy[1 - cur], kFusePolyVerts);
        cur = 1 - cur;
    }
    if (cn < 3) return false;
    std::copy(cx[cur], cx[cur] + cn, x);
    std::copy(cy[cur], cy[cur] + cn, y);
    out.x = x;
    out.y = y;
    out.count = cn;
    poly_bounds(x, y, cn, out.lo, out.hi);
    return true;
}

}  // namespace

OcclusionCuller::OcclusionCuller(int resolution) noexcept {
    const int r = resolution <= 0 ? 0 : std::clamp((resolution + 1) & ~1, kMinResolution, kMaxResolution);
    for (Rect& w : written_) w = {0, -1, 0, -1};
    try {
        frusta_.resize(kMaxOccluders);
        faces_.resize(3 * kMaxOccluders);
        face_directions_.resize(3 * kMaxOccluders * 24);
        polygons_.resize(kMaxPolygons);
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
    const uint32_t limit = uint32_t(std::min(max_occluders, kMaxOccluders));
    const uint32_t polygons = bake.occluder_polygon_count(c);
    uint32_t first = 0;  // the cell's polygons at places below the limit
    RankedPolygon p;
    while (first < polygons && bake.occluder_polygon(c, first, p) && p.place < limit) ++first;
    uint32_t n = bake.occluder_boxes(c, boxes, limit - first);
    begin_frame(eye, boxes, n);
    for (uint32_t k = 0; k < first; ++k)
        if (bake.occluder_polygon(c, k, p)) n += add_polygon(p.plane, p.corners, p.count) ? 1 : 0;
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
    face_count_ = 0;
    polygon_count_ = 0;
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
    // Nearest first, ties in their given order (insertion, as the C99 runtime: std::stable_sort may
    // allocate).
    for (size_t k = 1; k < candidates_.size(); ++k) {
        const Candidate c = candidates_[k];
        size_t n = k;
        for (; n > 0 && candidates_[n - 1].dist2 > c.dist2; --n) candidates_[n] = candidates_[n - 1];
        candidates_[n] = c;
    }
    for (const Candidate& c : candidates_) {
        if (used_ > 0 && (hidden_by_shadow_frusta(c.box) || hidden_by_depth_cube(c.box))) {
            ++redundant_;
            continue;
        }
        ++used_;
        if (r > 0) rasterize(c.raster, c.flat);
        build_frustum(c.box, c.delta, c.flat, frusta_[frustum_count_++]);
        add_faces(c);
    }
    face_directions();
}

namespace {

float float_down(double x) {
    float f = float(x);
    if (double(f) > x) f = std::nextafter(f, -kInfF);
    return f;
}
float float_up(double x) {
    float f = float(x);
    if (double(f) < x) f = std::nextafter(f, kInfF);
    return f;
}

}  // namespace

// Each face's projection bounds in the six frames of the faces test, once a frame: the test then projects a
// face only for the boxes whose directions its bounds meet (the same faces as projecting each for every box).
void OcclusionCuller::face_directions() noexcept {
    double x[kFuseProjVerts], y[kFuseProjVerts];
    for (size_t k = 0; k < face_count_; ++k) {
        const Face& face = faces_[k];
        for (int frame = 0; frame < 6; ++frame) {
            FuseFrame f{frame / 2, (frame / 2 + 1) % 3, (frame / 2 + 2) % 3, frame % 2 == 0 ? 1.0 : -1.0};
            FuseFace ff;
            float* b = &face_directions_[24 * k + 4 * size_t(frame)];
            if (!project_face(f, face.axis, face.plane, face.lo, face.hi, eye_d_, x, y, ff)) {
                b[0] = b[1] = kInfF;
                b[2] = b[3] = -kInfF;
                continue;
            }
            b[0] = float_down(ff.lo[0]);
            b[1] = float_down(ff.lo[1]);
            b[2] = float_up(ff.hi[0]);
            b[3] = float_up(ff.hi[1]);
        }
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

// A panel's rectangle, or a box's faces toward the eye, each GROWN in its plane by kFuseGrowRel of its scale
// (far below the float precision of its corners), so that faces meeting at a junction close it
// (docs/ALGORITHMS.md#runtime-faces).
void OcclusionCuller::add_faces(const Candidate& c) noexcept {
    const double grow = kFuseGrowRel * (1.0 + scale_of(eye_d_, c.box));
    for (int a = 0; a < 3; ++a) {
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        if (c.flat >= 0 && a != c.flat) continue;
        if (c.flat < 0 && !(eye_d_[a] < double(c.box.min[a]) - c.delta) &&
            !(eye_d_[a] > double(c.box.max[a]) + c.delta))
            continue;
        Face& f = faces_[face_count_++];
        f.axis = a;
        f.above = eye_d_[a] < double(c.box.min[a]);
        f.plane = f.above ? double(c.box.min[a]) : double(c.box.max[a]);
        f.delta = c.delta;
        f.lo[0] = double(c.box.min[a1]) - grow;
        f.hi[0] = double(c.box.max[a1]) + grow;
        f.lo[1] = double(c.box.min[a2]) - grow;
        f.hi[1] = double(c.box.max[a2]) + grow;
        f.axis1 = a1;
        f.axis2 = a2;
        f.rel_plane = f.plane - eye_d_[a];
        f.rel_lo[0] = f.lo[0] - eye_d_[a1];
        f.rel_hi[0] = f.hi[0] - eye_d_[a1];
        f.rel_lo[1] = f.lo[1] - eye_d_[a2];
        f.rel_hi[1] = f.hi[1] - eye_d_[a2];
    }
}

bool OcclusionCuller::add_polygon(const float plane[5], const float* corners, uint32_t count) noexcept {
    if (!eye_ok_ || plane == nullptr || corners == nullptr || count < 3 || count > kMaxPolygonCorners ||
        polygon_count_ >= kMaxPolygons)
        return false;
    for (int i = 0; i < 5; ++i)
        if (!std::isfinite(plane[i])) return false;
    for (uint32_t i = 0; i < 3 * count; ++i)
        if (!std::isfinite(corners[i])) return false;
    const double len =
        std::sqrt(double(plane[0]) * plane[0] + double(plane[1]) * plane[1] + double(plane[2]) * plane[2]);
    if (!(len > 0.0) || !std::isfinite(len) || !(plane[4] >= 0.0f)) return false;
    double n[3], scale = 0.0;
    for (int a = 0; a < 3; ++a) {
        n[a] = double(plane[a]) / len;
        scale = std::max(scale, std::abs(eye_d_[a]));
    }
    const double o = double(plane[3]) / len, t = double(plane[4]) / len;
    for (uint32_t i = 0; i < 3 * count; ++i) scale = std::max(scale, std::abs(double(corners[i])));
    Polygon& pg = polygons_[polygon_count_];
    pg.delta = kMargin_m + kMarginRel * scale;
    const double grow = kFuseGrowRel * (1.0 + scale);
    const double s_e = n[0] * eye_d_[0] + n[1] * eye_d_[1] + n[2] * eye_d_[2] - o;
    double sign;
    if (s_e < -(t + pg.delta))
        sign = 1.0;
    else if (s_e > t + pg.delta)
        sign = -1.0;
    else
        return false;             // the eye within the slab and its margin
    pg.near_w = -sign * s_e - t;  // > delta
    pg.far_w = -sign * s_e + t;
    pg.axis = 0;
    for (int a = 0; a < 3; ++a) {
        pg.n[a] = sign * n[a];
        if (std::abs(n[a]) > std::abs(n[pg.axis])) pg.axis = a;
    }
    for (uint32_t i = 0; i < count; ++i)
        for (int a = 0; a < 3; ++a) pg.c[i][a] = double(corners[3 * i + uint32_t(a)]) - eye_d_[a];
    double area = 0.0;
    for (uint32_t i = 0; i < count;
         ++i) {  // edge planes, inward for a counter-clockwise polygon seen from +n
        const double* p0 = pg.c[i];
        const double* p1 = pg.c[(i + 1) % count];
        const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double* m = pg.m[i];
        m[0] = n[1] * d[2] - n[2] * d[1];
        m[1] = n[2] * d[0] - n[0] * d[2];
        m[2] = n[0] * d[1] - n[1] * d[0];
        const double ml = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(ml > 0.0) || !std::isfinite(ml)) return false;
        for (int a = 0; a < 3; ++a) m[a] /= ml;
        pg.k[i] = m[0] * p0[0] + m[1] * p0[1] + m[2] * p0[2];
        for (uint32_t j = 0; j < count; ++j)  // convex and counter-clockwise: every corner inside every edge
            if (!(m[0] * pg.c[j][0] + m[1] * pg.c[j][1] + m[2] * pg.c[j][2] >= pg.k[i] - grow)) return false;
        pg.k[i] -= grow;
        area += n[0] * (p0[1] * p1[2] - p0[2] * p1[1]) + n[1] * (p0[2] * p1[0] - p0[0] * p1[2]) +
                n[2] * (p0[0] * p1[1] - p0[1] * p1[0]);
    }
    if (!(area > 0.0)) return false;
    pg.count = int(count);
    ++polygon_count_;
    return true;
}

// Whether the segment from the eye to point x (relative) crosses a face (beyond its plane, inside its
// rectangle) or a polygon (its slab, entering and leaving inside its prism): a point nothing hides proves
// the box it belongs to visible, before any projection.
bool OcclusionCuller::point_behind_a_face(const double x[3]) const noexcept {
    for (size_t k = 0; k < face_count_; ++k) {  // the crossing p x[a1] / x[a], p x[a2] / x[a], times |x[a]|
        const Face& f = faces_[k];
        const double p = f.rel_plane, xa = x[f.axis];
        if (f.above ? !(xa > p) : !(xa < p)) continue;
        const double m =
            f.above ? xa : -xa;  // p and x[a] have one sign: the eye is off the plane, x beyond it
        const double u1 = (f.above ? p : -p) * x[f.axis1];
        const double u2 = (f.above ? p : -p) * x[f.axis2];
        if (u1 >= f.rel_lo[0] * m && u1 <= f.rel_hi[0] * m && u2 >= f.rel_lo[1] * m && u2 <= f.rel_hi[1] * m)
            return true;
    }
    for (size_t k = 0; k < polygon_count_; ++k) {
        const Polygon& pg = polygons_[k];
        const double s = pg.n[0] * x[0] + pg.n[1] * x[1] + pg.n[2] * x[2];
        if (!(s > pg.far_w)) continue;
        const double t0 = pg.near_w / s, t1 = pg.far_w / s;  // the segment t * x meets the slab's planes
        int i = 0;
        for (; i < pg.count; ++i) {
            const double mx = pg.m[i][0] * x[0] + pg.m[i][1] * x[1] + pg.m[i][2] * x[2];
            if (!(t0 * mx >= pg.k[i]) || !(t1 * mx >= pg.k[i])) break;
        }
        if (i == pg.count) return true;
    }
    return false;
}

bool OcclusionCuller::hidden_by_faces(const Box& box) const noexcept {
    const double near_d = double(kNearPlane_m);
    if (!eye_ok_ || face_count_ + polygon_count_ == 0 || !usable_box(box)) return false;
    const double delta = kMargin_m + kMarginRel * scale_of(eye_d_, box);
    double q[6], best = near_d, lo[2], hi[2], cut;
    int ax;
    FuseFrame f{-1, 0, 0, 1.0};
    for (int a = 0; a < 3; ++a) {
        q[a] = double(box.min[a]) - delta - eye_d_[a];
        q[3 + a] = double(box.max[a]) + delta - eye_d_[a];
    }
    for (int a = 0; a < 3; ++a) {  // the axis along which the box lies farthest ahead of the eye
        if (q[a] > best) {
            best = q[a];
            f.p = a;
            f.sign = 1.0;
        }
        if (-q[3 + a] > best) {
            best = -q[3 + a];
            f.p = a;
            f.sign = -1.0;
        }
    }
    if (f.p < 0) return false;
    for (int k = 0; k < 8; ++k) {  // the corners (classify tried the centre): one nothing hides shows the box
        double x[3];
        for (int b = 0; b < 3; ++b) x[b] = (k >> b & 1) ? q[3 + b] : q[b];
        if (!point_behind_a_face(x)) return false;
    }
    f.u = (f.p + 1) % 3;
    f.v = (f.p + 2) % 3;
    box_directions(f, q, lo, hi);
    FuseFace faces[kFuseMaxFaces];
    double pool_x[kFusePool], pool_y[kFusePool];
    int nf = 0, used = 0;
    for (size_t k = 0; k < face_count_ + polygon_count_ && nf < kFuseMaxFaces; ++k) {
        FuseFace& ff = faces[nf];
        if (k < face_count_) {
            const Face& face = faces_[k];
            const float* db = &face_directions_[24 * k + 4 * size_t(2 * f.p + (f.sign < 0.0 ? 1 : 0))];
            if (double(db[2]) < lo[0] || double(db[0]) > hi[0] || double(db[3]) < lo[1] ||
                double(db[1]) > hi[1])
                continue;  // its projection misses the box's directions: the check below would skip it
            ff.poly = false;
            ff.axis = face.axis;
            ff.above = face.above;
            ff.plane = face.plane - eye_d_[face.axis];
            ff.delta = face.delta;
            if (!beyond_part(ff, q, ax, cut)) continue;  // nothing of the box lies beyond it
            if (!project_face(f, face.axis, face.plane, face.lo, face.hi, eye_d_, pool_x + used,
                              pool_y + used, ff))
                continue;
        } else {
            const Polygon& pg = polygons_[k - face_count_];
            ff.poly = true;
            ff.axis = pg.axis;
            ff.above = pg.n[pg.axis] > 0.0;
            std::copy(pg.n, pg.n + 3, ff.n);
            ff.w = pg.far_w + pg.delta;
            if (!beyond_part(ff, q, ax, cut)) continue;
            if (kFusePool - used < kFusePolyVerts) break;
            if (!project_polygon(f, pg.n, pg.near_w, pg.far_w, pg.c, pg.count, pool_x + used, pool_y + used,
                                 ff))
                continue;
        }
        if (ff.hi[0] < lo[0] || ff.lo[0] > hi[0] || ff.hi[1] < lo[1] || ff.lo[1] > hi[1]) continue;
        used += ff.count;
        ++nf;
    }
    if (nf == 0) return false;
    FuseFragment stack[kFuseMaxFragments];
    int top = 0;
    FusePoly r;
    r.n = 4;
    r.x[0] = lo[0];
    r.y[0] = lo[1];
    r.x[1] = hi[0];
    r.y[1] = lo[1];
    r.x[2] = hi[0];
    r.y[2] = hi[1];
    r.x[3] = lo[0];
    r.y[3] = hi[1];
    push_fragment(stack, top, q, r, 0);
    while (top > 0) {
        const FuseFragment g = stack[--top];
        double plo[2], phi[2], near_part[6], far_part[6], blo[2], bhi[2];
        const FuseFace* ff = nullptr;
        int i = g.next;
        poly_bounds(g.r.x, g.r.y, g.r.n, plo, phi);
        for (; i < nf; ++i) {  // the next face that could hide part of this fragment
            const FuseFace& t = faces[i];
            if (t.hi[0] < plo[0] || t.lo[0] > phi[0] || t.hi[1] < plo[1] || t.lo[1] > phi[1]) continue;
            if (!beyond_part(t, g.b, ax, cut)) continue;
            ff = &t;
            break;
        }
        if (ff == nullptr) return false;  // a fragment nothing hides: visible
        std::memcpy(near_part, g.b, sizeof near_part);
        std::memcpy(far_part, g.b, sizeof far_part);
        if (ff->above) {
            near_part[3 + ax] = near_part[3 + ax] < cut ? near_part[3 + ax] : cut;
            far_part[ax] = far_part[ax] > cut ? far_part[ax] : cut;
        } else {
            near_part[ax] = near_part[ax] > cut ? near_part[ax] : cut;
            far_part[3 + ax] = far_part[3 + ax] < cut ? far_part[3 + ax] : cut;
        }
        if (near_part[ax] <= near_part[3 + ax]) {  // the part on the eye's side keeps its directions
            FusePoly rn = g.r;
            box_directions(f, near_part, blo, bhi);
            const int ok = clip_to_rect(rn, blo, bhi);
            if (ok < 0 || (ok > 0 && !push_fragment(stack, top, near_part, rn, i + 1))) return false;
        }
        FusePoly rf = g.r;
        box_directions(f, far_part, blo, bhi);
        const int ok = clip_to_rect(rf, blo, bhi);
        if (ok < 0) return false;
        if (ok == 0) continue;
        if (!push_outside(stack, top, far_part, rf, *ff, i + 1)) return false;
    }
    return true;
}

OcclusionCuller::Path OcclusionCuller::classify(const Box& box) const noexcept {
    if (!eye_ok_ || (used_ == 0 && polygon_count_ == 0) || !usable_box(box)) return Path::kVisible;
    // The centre of the box (grown by its margin) behind no face: no test can hide the box (each hides only
    // boxes every point of which some face hides), so most visible boxes end here.
    const double delta = kMargin_m + kMarginRel * scale_of(eye_d_, box);
    double centre[3];
    for (int a = 0; a < 3; ++a)
        centre[a] =
            0.5 * ((double(box.min[a]) - delta - eye_d_[a]) + (double(box.max[a]) + delta - eye_d_[a]));
    if (!point_behind_a_face(centre)) return Path::kVisible;
    if (hidden_by_shadow_frusta(box)) return Path::kShadowFrustum;
    if (hidden_by_depth_cube(box)) return Path::kDepthBuffer;
    if (hidden_by_faces(box)) return Path::kFaces;
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
