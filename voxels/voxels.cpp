// SPDX-License-Identifier: MIT
// Conservative voxelization: Akenine-Möller's triangle-box separating-axis test, applied hierarchically
// (a box of voxels the triangle misses is skipped whole; one it overlaps is halved until single voxels).
#include "voxels/voxels.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace pvs {

VoxelGrid make_voxel_grid(const Aabb& bounds, double voxel_size_m, int pad_voxels) {
    if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) {
        throw bad_input(fmt::format("make_voxel_grid: --voxel-size must be > 0 m (got {})", voxel_size_m));
    }
    if (bounds.is_empty()) throw bad_input("make_voxel_grid: the world has no extent");
    VoxelGrid g;
    g.voxel_size_m = float(voxel_size_m);
    g.origin = bounds.min - glm::vec3(float(pad_voxels) * g.voxel_size_m);
    uint64_t total = 1;
    for (int a = 0; a < 3; ++a) {
        const double n = std::ceil(double(bounds.max[a] - bounds.min[a]) / voxel_size_m) + 2.0 * pad_voxels;
        g.dims[a] = int(std::clamp(n, 1.0, 2e9));
        total *= uint64_t(g.dims[a]);
        if (total > kMaxVoxels) {
            const glm::vec3 e = bounds.size();
            throw bad_input(
                fmt::format("make_voxel_grid: {} m voxels over {:.1f} x {:.1f} x {:.1f} m need more than {} "
                            "voxels; use a larger --voxel-size",
                            voxel_size_m, e.x, e.y, e.z, kMaxVoxels));
        }
    }
    return g;
}

double voxel_grid_count(const Aabb& bounds, double voxel_size_m, int pad_voxels) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a)
        total *=
            std::max(1.0, std::ceil(double(bounds.max[a] - bounds.min[a]) / voxel_size_m) + 2.0 * pad_voxels);
    return total;
}

int void_pad_voxels(double voxel_size_m) {
    return std::max(2, int(std::min(1e6, std::ceil(kVoidPadM / voxel_size_m))));
}

double default_voxel_size(const Aabb& bounds, double preferred_m, uint64_t max_voxels) {
    const auto fits = [&](double size) {
        return voxel_grid_count(bounds, size, void_pad_voxels(size)) <= double(max_voxels);
    };
    if (fits(preferred_m)) return preferred_m;
    // The volume's estimate is a lower bound (padding and rounding only add voxels); then grow by 1% until
    // the padded grid fits. The count falls as the size grows, so this ends: within a few hundred steps
    // once the size passes the bounds' longest edge divided by the cap.
    const glm::dvec3 e = glm::dvec3(bounds.size()) + 4.0 * preferred_m;
    double size = std::max(preferred_m, std::cbrt(e.x * e.y * e.z / double(max_voxels)));
    while (!fits(size) && size < 1e12) size *= 1.01;
    return size;
}

namespace {

bool axis_separates(glm::vec3 axis, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2, glm::vec3 half) {
    const float p0 = glm::dot(axis, v0), p1 = glm::dot(axis, v1), p2 = glm::dot(axis, v2);
    const float r = half.x * std::fabs(axis.x) + half.y * std::fabs(axis.y) + half.z * std::fabs(axis.z);
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

}  // namespace

bool triangle_box_overlap(glm::vec3 center, glm::vec3 half, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 v0 = a - center, v1 = b - center, v2 = c - center;
    // 1. The box's three face normals (the triangle's bounds against the box).
    for (int i = 0; i < 3; ++i) {
        if (std::min({v0[i], v1[i], v2[i]}) > half[i] || std::max({v0[i], v1[i], v2[i]}) < -half[i])
            return false;
    }
    // 2. The triangle's normal.
    const glm::vec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
    const glm::vec3 n = glm::cross(e0, e1);
    if (axis_separates(n, v0, v1, v2, half)) return false;
    // 3. The nine cross products of box axes and triangle edges.
    const glm::vec3 edges[3] = {e0, e1, e2};
    for (const glm::vec3& e : edges) {
        if (axis_separates(glm::vec3(0, -e.z, e.y), v0, v1, v2, half)) return false;
        if (axis_separates(glm::vec3(e.z, 0, -e.x), v0, v1, v2, half)) return false;
        if (axis_separates(glm::vec3(-e.y, e.x, 0), v0, v1, v2, half)) return false;
    }
    return true;
}

namespace {

struct Voxelizer {
    const VoxelGrid& grid;
    glm::vec3 a, b, c;
    float grow;  // added to every box half size: rounding can only add voxels
    BitVolume& touched;
    BitVolume* upward;

    void visit(glm::ivec3 lo, glm::ivec3 hi) {  // voxels lo..hi inclusive
        const glm::vec3 box_lo = grid.origin + glm::vec3(lo) * grid.voxel_size_m;
        const glm::vec3 box_hi = grid.origin + glm::vec3(hi + 1) * grid.voxel_size_m;
        const glm::vec3 half = 0.5f * (box_hi - box_lo) + grow;
        if (!triangle_box_overlap(0.5f * (box_lo + box_hi), half, a, b, c)) return;
        const glm::ivec3 n = hi - lo + 1;
        if (n.x == 1 && n.y == 1 && n.z == 1) {
            const uint64_t i = grid.index(lo.x, lo.y, lo.z);
            touched.set_atomic(i);
            if (upward) upward->set_atomic(i);
            return;
        }
        const int axis = n.x >= n.y && n.x >= n.z ? 0 : (n.y >= n.z ? 1 : 2);
        const int mid = lo[axis] + n[axis] / 2;
        glm::ivec3 hi0 = hi, lo1 = lo;
        hi0[axis] = mid - 1;
        lo1[axis] = mid;
        visit(lo, hi0);
        visit(lo1, hi);
    }
};

}  // namespace

namespace {

// Word w of `in` shifted by `by` bits along the linear index (positive: to higher indices), bits shifted
// past either end dropped: the bits of word w come from words w - q and w - q - 1 (or w + q, w + q + 1).
uint64_t shifted_word(const uint64_t* src, int64_t n, int64_t w, int64_t by) {
    const int64_t q = (by >= 0 ? by : -by) >> 6;
    const int r = int((by >= 0 ? by : -by) & 63);
    if (by >= 0) {
        if (w < q) return 0;
        const uint64_t lo = src[w - q], below = w - q - 1 >= 0 ? src[w - q - 1] : 0;
        return r == 0 ? lo : (lo << r) | (below >> (64 - r));
    }
    if (w + q >= n) return 0;
    const uint64_t hi = src[w + q], above = w + q + 1 < n ? src[w + q + 1] : 0;
    return r == 0 ? hi : (hi >> r) | (above << (64 - r));
}

// The bits of word w whose index i satisfies lo <= i mod period < hi (0 <= lo <= hi <= period).
uint64_t periodic_mask(uint64_t w, uint64_t period, uint64_t lo, uint64_t hi) {
    const uint64_t first = w * 64, end = first + 64;
    uint64_t mask = 0;
    for (uint64_t base = first - first % period; base < end; base += period) {
        const uint64_t a = std::max(first, base + lo), b = std::min(end, base + hi);
        if (a >= b) continue;
        const uint64_t bits = b - a;  // 1..64
        mask |= (bits == 64 ? ~uint64_t(0) : ((uint64_t(1) << bits) - 1)) << (a - first);
    }
    return mask;
}

}  // namespace

// Per axis, by doubling: a set grown by `reach` voxels along the axis, ORed with itself moved by up to
// `reach` + 1 more voxels either way, is grown by twice that plus one (at most `radius`). A move along the
// axis is a shift of the linear index by a multiple of the axis's stride; the bits that would cross the end
// of their line (into the next row or plane) are masked off, so the result is exact. Each word of a move
// depends only on the volume before it (double-buffered), so the words run in parallel and the result does
// not depend on the thread count.
BitVolume dilate(const VoxelGrid& g, const BitVolume& in, int radius) {
    BitVolume a = in;
    if (radius <= 0) return a;
    const uint64_t count = g.count();
    const int64_t words = int64_t(a.words.size());
    const int64_t stride[3] = {1, int64_t(g.dims.x), int64_t(g.dims.x) * int64_t(g.dims.y)};
    BitVolume b;
    b.words.resize(a.words.size());
    for (int axis = 0; axis < 3; ++axis) {
        const int64_t n = g.dims[axis];
        const uint64_t period = uint64_t(stride[axis] * n);  // a block of whole lines along the axis
        int reach = 0;
        while (reach < radius) {
            const int step = std::min(reach + 1, radius - reach);
            for (const int dir : {1, -1}) {
                // Moved up, keep the voxels whose coordinate on the axis is >= step; moved down, those
                // <= n - 1 - step: the rest came from another line. Along z nothing wraps.
                const uint64_t s = uint64_t(stride[axis]), kept = uint64_t(std::max<int64_t>(0, n - step));
                const uint64_t lo = dir > 0 ? s * uint64_t(step) : 0, hi = lo + s * kept;
                const int64_t by = dir * step * stride[axis];
                const uint64_t* src = a.words.data();
                uint64_t* dst = b.words.data();
                for_each_word(size_t(words), [&](size_t w) {
                    uint64_t moved = shifted_word(src, words, int64_t(w), by);
                    if (axis < 2) moved &= periodic_mask(uint64_t(w), period, lo, hi);
                    dst[w] = src[w] | moved;
                });
                std::swap(a.words, b.words);
            }
            reach += step;
        }
    }
    if (count & 63) a.words.back() &= (uint64_t(1) << (count & 63)) - 1;  // moves along z past the end
    return a;
}

void clear_border(const VoxelGrid& g, BitVolume& v, int k) {
    if (k <= 0) return;
    // Per axis, the kept coordinates [k, dims - k) as a range of the index modulo the axis's period.
    uint64_t period[3], lo[3], hi[3];
    uint64_t stride = 1;
    for (int axis = 0; axis < 3; ++axis) {
        const int64_t n = g.dims[axis];
        period[axis] = stride * uint64_t(std::max<int64_t>(n, 1));
        lo[axis] = stride * uint64_t(std::min<int64_t>(k, n));
        hi[axis] = std::max(lo[axis], stride * uint64_t(std::max<int64_t>(0, n - k)));
        stride = period[axis];
    }
    for_each_word(v.words.size(), [&](size_t w) {
        uint64_t keep = ~uint64_t(0);
        for (int axis = 0; axis < 3; ++axis)
            keep &= periodic_mask(uint64_t(w), period[axis], lo[axis], hi[axis]);
        v.words[w] &= keep;
    });
}

void voxelize_opaque(Context& ctx, const World& world, const VoxelGrid& grid, BitVolume& touched,
                     BitVolume* upward, float min_up_cos, BitVolume* see_through) {
    ScopedTimer timer(ctx, "voxelize");
    touched.reset(grid.count());
    if (upward) upward->reset(grid.count());
    if (see_through) see_through->reset(grid.count());
    const float grow = grid.voxel_size_m * 1e-4f;
    const int64_t n = int64_t(world.triangles.size());
#pragma omp parallel for schedule(dynamic, 256)
    for (int64_t t = 0; t < n; ++t) {
        const bool opaque = world.triangle_opaque[size_t(t)];
        if (!opaque && !see_through) continue;
        const Triangle& tri = world.triangles[size_t(t)];
        const glm::vec3 a = world.positions[tri.v[0]], b = world.positions[tri.v[1]],
                        c = world.positions[tri.v[2]];
        Aabb tb;
        tb.extend(a);
        tb.extend(b);
        tb.extend(c);
        const glm::ivec3 lo = grid.voxel_of(tb.min - grow), hi = grid.voxel_of(tb.max + grow);
        const glm::vec3 normal = glm::cross(b - a, c - a);
        const float len = glm::length(normal);
        const bool up = opaque && upward && len > 0.0f && normal.y / len >= min_up_cos;
        Voxelizer v{grid, a, b, c, grow, opaque ? touched : *see_through, up ? upward : nullptr};
        v.visit(lo, hi);
    }
    ctx.debug(fmt::format("voxelize: {} of {} voxels touched", touched.count(), grid.count()));
}

}  // namespace pvs
