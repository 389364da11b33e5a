// SPDX-License-Identifier: MIT
// Space hidden from an eye region, grown front to back through the space already hidden.
#include "pvs/umbra_volume.h"

#include "occluders/panels.h"
#include "pvs/region_hiding.h"
#include "voxels/voxels.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <set>
#include <tuple>

namespace pvs {
namespace {

// A node is halved no further once its edge is below this share of its distance from the region's centre
// along the blocker's axis: far nodes are settled coarsely (stopping early only leaves space unmarked).
const double kDescentSlope = getenv("PVS_UMBRA_SLOPE") ? atof(getenv("PVS_UMBRA_SLOPE")) : 1.0 / 32.0;  // XXX
// A blocker grows by one layer of voxels at a time, at most this many layers a side, and not across a layer
// of more voxels than this (cost bounds: growing less only makes a blocker smaller).
constexpr int kMaxGrowLayers = 512;
constexpr int64_t kMaxLayerVoxels = int64_t(1) << 16;

// The float box holding the double box [lo, hi] (rounded outward).
Aabb outward(const glm::dvec3& lo, const glm::dvec3& hi) {
    Aabb b;
    for (int k = 0; k < 3; ++k) {
        float l = float(lo[k]), h = float(hi[k]);
        if (double(l) > lo[k]) l = std::nextafter(l, -INFINITY);
        if (double(h) < hi[k]) h = std::nextafter(h, INFINITY);
        b.min[k] = l;
        b.max[k] = h;
    }
    return b;
}

double chebyshev_gap(const glm::dvec3& alo, const glm::dvec3& ahi, const glm::dvec3& blo,
                     const glm::dvec3& bhi) {
    double g = 0.0;
    for (int k = 0; k < 3; ++k) g = std::max({g, blo[k] - ahi[k], alo[k] - bhi[k]});
    return g;
}

// The shadow of a box K from a point q, by the slopes along an axis a on which q lies outside K: every
// point x whose segment from q meets K lies at a depth s (x_a - q_a) >= near with its slopes
// (x_b - q_b) / depth within K's.
struct Shadow {
    glm::dvec3 q{0.0};
    int a = 0, sgn = 1;
    double near = 0.0;
    double smin[3] = {0, 0, 0}, smax[3] = {0, 0, 0};

    // May the box [lo, hi] meet the shadow? `dd0`: its least depth in the shadow's range of depths.
    bool may_meet(const glm::dvec3& lo, const glm::dvec3& hi, double& dd0) const {
        const double d0 = sgn > 0 ? lo[a] - q[a] : q[a] - hi[a];
        const double d1 = sgn > 0 ? hi[a] - q[a] : q[a] - lo[a];
        if (d1 <= near) return false;
        dd0 = std::max(d0, near);
        for (int k = 1; k <= 2; ++k) {
            const int b = (a + k) % 3;
            const double u0 = lo[b] - q[b], u1 = hi[b] - q[b];
            const double lo_s = u0 >= 0.0 ? u0 / d1 : u0 / dd0;
            const double hi_s = u1 >= 0.0 ? u1 / dd0 : u1 / d1;
            if (hi_s < smin[b] || lo_s > smax[b]) return false;
        }
        return true;
    }
};

// The shadow of [klo, khi] from q, along the axis q lies farthest outside it on; false when q is inside.
bool shadow_of(const glm::dvec3& q, const glm::dvec3& klo, const glm::dvec3& khi, Shadow& out) {
    out.q = q;
    int a = -1;
    double near = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double g1 = klo[k] - q[k], g2 = q[k] - khi[k];
        if (g1 > near) {
            a = k;
            out.sgn = 1;
            near = g1;
        }
        if (g2 > near) {
            a = k;
            out.sgn = -1;
            near = g2;
        }
    }
    if (a < 0) return false;
    out.a = a;
    out.near = near;
    const double kd0 = near, kd1 = out.sgn > 0 ? khi[a] - q[a] : q[a] - klo[a];
    for (int k = 1; k <= 2; ++k) {
        const int b = (a + k) % 3;
        const double u0 = klo[b] - q[b], u1 = khi[b] - q[b];
        out.smin[b] = u0 >= 0.0 ? u0 / kd1 : u0 / kd0;
        out.smax[b] = u1 >= 0.0 ? u1 / kd0 : u1 / kd1;
    }
    return true;
}

}  // namespace

struct UmbraHider::Scratch {
    std::vector<uint64_t> flags;
    std::vector<uint32_t> order;
    std::vector<double> key;
    struct Node {
        int level;
        glm::ivec3 n;
    };
    std::vector<Node> stack;
};

void UmbraHider::block_box(glm::ivec3 b, glm::dvec3& lo, glm::dvec3& hi) const {
    for (int k = 0; k < 3; ++k) {
        lo[k] = origin_[k] + double(b[k] * b_) * h_;
        hi[k] = origin_[k] + double(std::min((b[k] + 1) * b_, vdims_[k])) * h_;
    }
}

bool UmbraHider::block_hidden(const Scratch& s, glm::ivec3 b) const {
    for (size_t l = 0; l < ldims_.size(); ++l) {
        const glm::ivec3 n = b >> int(l);
        const glm::ivec3& d = ldims_[l];
        const size_t i = loffset_[l] + size_t(n.x) + size_t(d.x) * (size_t(n.y) + size_t(d.y) * size_t(n.z));
        if ((s.flags[i >> 6] >> (i & 63)) & 1u) return true;
    }
    return false;
}

bool UmbraHider::voxel_blocked(const Scratch& s, glm::ivec3 v) const {
    if (v.x < 0 || v.y < 0 || v.z < 0 || v.x >= vdims_.x || v.y >= vdims_.y || v.z >= vdims_.z) return false;
    const uint64_t i =
        uint64_t(v.x) + uint64_t(vdims_.x) * (uint64_t(v.y) + uint64_t(vdims_.y) * uint64_t(v.z));
    if (set_.solid.get(i)) return true;
    return block_hidden(s, v / b_);
}

// Grows the voxel box [lo, hi) along `axis` on `side` (+1 / -1) one layer at a time while every voxel of the
// next layer is solid (or, with `through_hidden`, solid or in a hidden block).
void UmbraHider::grow(const Scratch& s, glm::ivec3& lo, glm::ivec3& hi, int axis, int side,
                      bool through_hidden) const {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    if (int64_t(hi[u] - lo[u]) * int64_t(hi[v] - lo[v]) > kMaxLayerVoxels) return;
    for (int step = 0; step < kMaxGrowLayers; ++step) {
        const int x = side > 0 ? hi[axis] : lo[axis] - 1;
        if (x < 0 || x >= vdims_[axis]) return;
        glm::ivec3 p;
        p[axis] = x;
        for (p[v] = lo[v]; p[v] < hi[v]; ++p[v])
            for (p[u] = lo[u]; p[u] < hi[u]; ++p[u]) {
                if (through_hidden ? !voxel_blocked(s, p)
                                   : !set_.solid.get(uint64_t(p.x) + uint64_t(vdims_.x) *
                                                                         (uint64_t(p.y) + uint64_t(vdims_.y) *
                                                                                              uint64_t(p.z))))
                    return;
            }
        if (side > 0)
            ++hi[axis];
        else
            --lo[axis];
    }
}

UmbraHider::UmbraHider(Context& ctx, const World& world, const ShrunkOccluders& set, int block_voxels)
    : set_(set) {
    ScopedTimer t(ctx, "umbra_setup");
    if (set.solid.empty()) return;
    b_ = std::max(1, getenv("PVS_UMBRA_BLOCK") ? atoi(getenv("PVS_UMBRA_BLOCK")) : block_voxels);  // XXX
    origin_ = glm::dvec3(set.solid.origin);
    h_ = double(set.solid.voxel_size_m);
    vdims_ = set.solid.dims;
    bdims_ = (vdims_ + (b_ - 1)) / b_;
    ldims_.push_back(bdims_);
    while (ldims_.back().x > 1 || ldims_.back().y > 1 || ldims_.back().z > 1)
        ldims_.push_back((ldims_.back() + 1) / 2);
    for (const glm::ivec3& d : ldims_) {
        loffset_.push_back(flags_);
        flags_ += size_t(d.x) * size_t(d.y) * size_t(d.z);
    }

    // Seeds: each floor-epsilon box, as the box of solid voxels grown from the voxel at its centre.
    const Scratch none;
    std::set<std::tuple<int, int, int, int, int, int>> seen;
    if (!set.boxes.empty()) {
        for (const Aabb& box : set.boxes[0]) {
            if (box.is_empty()) continue;
            const glm::dvec3 c = (glm::dvec3(box.min) + glm::dvec3(box.max)) * 0.5;
            const glm::ivec3 v = glm::ivec3(glm::floor((c - origin_) / h_));
            if (v.x < 0 || v.y < 0 || v.z < 0 || v.x >= vdims_.x || v.y >= vdims_.y || v.z >= vdims_.z)
                continue;
            if (!set.solid.get(uint64_t(v.x) +
                               uint64_t(vdims_.x) * (uint64_t(v.y) + uint64_t(vdims_.y) * uint64_t(v.z))))
                continue;
            glm::ivec3 lo = v, hi = v + 1;
            for (int round = 0; round < 2; ++round)
                for (int axis = 0; axis < 3; ++axis)
                    for (int side : {-1, 1}) grow(none, lo, hi, axis, side, false);
            if (!seen.emplace(lo.x, lo.y, lo.z, hi.x, hi.y, hi.z).second) continue;
            Seed s;
            s.kind = 0;
            s.vlo = lo;
            s.vhi = hi;
            s.lo = origin_ + glm::dvec3(lo) * h_;
            s.hi = origin_ + glm::dvec3(hi) * h_;
            seeds_.push_back(s);
        }
    }
    for (const Aabb& p : set.panels) {
        const int axis = panel_axis(p);
        if (axis < 0) continue;
        Seed s;
        s.kind = 1;
        s.index = int(panels_.size());
        s.axis = axis;
        s.lo = glm::dvec3(p.min);
        s.hi = glm::dvec3(p.max);
        panels_.push_back(p);
        seeds_.push_back(s);
    }
    for (size_t i = 0; i < set.slanted.size(); ++i) {
        Seed s;
        s.kind = 2;
        s.index = int(i);
        s.lo = glm::dvec3(set.slanted[i].bounds.min);
        s.hi = glm::dvec3(set.slanted[i].bounds.max);
        seeds_.push_back(s);
    }

    // The blocks each object's triangles touch (a block grown by a relative 1e-5, so rounding only adds).
    const size_t n = world.objects.size();
    std::vector<std::vector<uint32_t>> lists(n);
    const double bh = double(b_) * h_;
#pragma omp parallel for schedule(dynamic, 16)
    for (int64_t oi = 0; oi < int64_t(n); ++oi) {
        const WorldObject& o = world.objects[size_t(oi)];
        std::vector<uint32_t>& out = lists[size_t(oi)];
        for (uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t) {
            const glm::vec3 a = world.positions[world.triangles[t].v[0]],
                            b = world.positions[world.triangles[t].v[1]],
                            c = world.positions[world.triangles[t].v[2]];
            const glm::dvec3 lo = glm::min(glm::dvec3(a), glm::min(glm::dvec3(b), glm::dvec3(c)));
            const glm::dvec3 hi = glm::max(glm::dvec3(a), glm::max(glm::dvec3(b), glm::dvec3(c)));
            glm::ivec3 b0, b1;
            for (int k = 0; k < 3; ++k) {
                b0[k] = std::clamp(int(std::floor((lo[k] - origin_[k]) / bh - 1e-6)), 0, bdims_[k] - 1);
                b1[k] = std::clamp(int(std::floor((hi[k] - origin_[k]) / bh + 1e-6)), 0, bdims_[k] - 1);
            }
            const bool degenerate = glm::length(glm::cross(b - a, c - a)) <= 1e-12f;
            for (int z = b0.z; z <= b1.z; ++z)
                for (int y = b0.y; y <= b1.y; ++y)
                    for (int x = b0.x; x <= b1.x; ++x) {
                        glm::dvec3 blo, bhi;
                        block_box({x, y, z}, blo, bhi);
                        const glm::dvec3 half = (bhi - blo) * 0.5 * (1.0 + 1e-5) + 1e-6;
                        if (degenerate ||
                            triangle_box_overlap(glm::vec3((blo + bhi) * 0.5), glm::vec3(half), a, b, c))
                            out.push_back(uint32_t(x + bdims_.x * (y + bdims_.y * z)));
                    }
        }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }
    object_offset_.assign(n + 1, 0);
    for (size_t o = 0; o < n; ++o) object_offset_[o + 1] = object_offset_[o] + uint32_t(lists[o].size());
    object_blocks_.reserve(object_offset_[n]);
    for (const auto& l : lists) object_blocks_.insert(object_blocks_.end(), l.begin(), l.end());
    // Where marks matter: blocks some object's triangles touch, and blocks holding both solid and other
    // voxels (where a blocker may grow through hidden space); and every node above one of them.
    relevant_.assign((flags_ + 63) / 64, 0);
    auto set_relevant = [&](glm::ivec3 b) {
        for (size_t l = 0; l < ldims_.size(); ++l) {
            const size_t i = flag_index(int(l), b >> int(l));
            relevant_[i >> 6] |= uint64_t(1) << (i & 63);
        }
    };
    for (uint32_t bi : object_blocks_)
        set_relevant({int(bi % uint32_t(bdims_.x)), int((bi / uint32_t(bdims_.x)) % uint32_t(bdims_.y)),
                      int(bi / (uint32_t(bdims_.x) * uint32_t(bdims_.y)))});
    // Per block: 1 holds a solid voxel, 2 holds another.
    std::vector<uint8_t> kind(size_t(bdims_.x) * size_t(bdims_.y) * size_t(bdims_.z), 0);
    auto bindex = [&](int x, int y, int z) {
        return size_t(x) + size_t(bdims_.x) * (size_t(y) + size_t(bdims_.y) * size_t(z));
    };
    for (int vz = 0; vz < vdims_.z; ++vz)
        for (int vy = 0; vy < vdims_.y; ++vy)
            for (int vx = 0; vx < vdims_.x; ++vx)
                kind[bindex(vx / b_, vy / b_, vz / b_)] |=
                    set.solid.get(uint64_t(vx) +
                                  uint64_t(vdims_.x) * (uint64_t(vy) + uint64_t(vdims_.y) * uint64_t(vz)))
                        ? 1
                        : 2;
    for (int z = 0; z < bdims_.z; ++z)
        for (int y = 0; y < bdims_.y; ++y)
            for (int x = 0; x < bdims_.x; ++x) {
                if (!(kind[bindex(x, y, z)] & 2)) continue;
                bool near_solid = kind[bindex(x, y, z)] & 1;
                for (int k = 0; k < 3 && !near_solid; ++k)
                    for (int side : {-1, 1}) {
                        glm::ivec3 n(x, y, z);
                        n[k] += side;
                        if (n[k] >= 0 && n[k] < bdims_[k] && (kind[bindex(n.x, n.y, n.z)] & 1))
                            near_solid = true;
                    }
                if (near_solid) set_relevant({x, y, z});
            }
    ctx.debug(fmt::format("umbra: {} seeds, {} x {} x {} blocks of {} voxels, {} object blocks",
                          seeds_.size(), bdims_.x, bdims_.y, bdims_.z, b_, object_blocks_.size()));
}

size_t UmbraHider::flag_index(int level, glm::ivec3 n) const {
    const glm::ivec3& d = ldims_[size_t(level)];
    return loffset_[size_t(level)] + size_t(n.x) + size_t(d.x) * (size_t(n.y) + size_t(d.y) * size_t(n.z));
}

// Flags node n of `level`, and each ancestor all of whose children are then flagged.
void UmbraHider::mark(Scratch& s, int level, glm::ivec3 n) const {
    for (;;) {
        const size_t i = flag_index(level, n);
        s.flags[i >> 6] |= uint64_t(1) << (i & 63);
        if (size_t(level) + 1 >= ldims_.size()) return;
        const glm::ivec3 p = n >> 1;
        const glm::ivec3& d = ldims_[size_t(level)];
        for (int z = 0; z < 2; ++z)
            for (int y = 0; y < 2; ++y)
                for (int x = 0; x < 2; ++x) {
                    const glm::ivec3 ch = p * 2 + glm::ivec3(x, y, z);
                    if (ch.x >= d.x || ch.y >= d.y || ch.z >= d.z) continue;
                    const size_t ci = flag_index(level, ch);
                    if (!((s.flags[ci >> 6] >> (ci & 63)) & 1u)) return;
                }
        ++level;
        n = p;
    }
}

// Is every block meeting the blocks [b0, b1] hidden?
bool UmbraHider::range_hidden(Scratch& s, glm::ivec3 b0, glm::ivec3 b1) const {
    s.stack.clear();
    s.stack.push_back({int(ldims_.size()) - 1, glm::ivec3(0)});
    while (!s.stack.empty()) {
        const Scratch::Node node = s.stack.back();
        s.stack.pop_back();
        const glm::ivec3 n0 = node.n << node.level, n1 = ((node.n + 1) << node.level) - 1;
        if (n1.x < b0.x || n1.y < b0.y || n1.z < b0.z || n0.x > b1.x || n0.y > b1.y || n0.z > b1.z) continue;
        const size_t i = flag_index(node.level, node.n);
        if ((s.flags[i >> 6] >> (i & 63)) & 1u) continue;
        if (node.level == 0) return false;
        const glm::ivec3& cd = ldims_[size_t(node.level - 1)];
        for (int z = 0; z < 2; ++z)
            for (int y = 0; y < 2; ++y)
                for (int x = 0; x < 2; ++x) {
                    const glm::ivec3 ch = node.n * 2 + glm::ivec3(x, y, z);
                    if (ch.x < cd.x && ch.y < cd.y && ch.z < cd.z) s.stack.push_back({node.level - 1, ch});
                }
    }
    return true;
}

void UmbraHider::run(const Aabb& region, Scratch& s, UmbraFigures& f) const {
    s.flags.assign((flags_ + 63) / 64, 0);
    const glm::dvec3 rlo(region.min), rhi(region.max);
    const glm::dvec3 c = (rlo + rhi) * 0.5;
    // Front to back: the seeds by their distance from the region.
    s.order.resize(seeds_.size());
    s.key.resize(seeds_.size());
    std::iota(s.order.begin(), s.order.end(), 0u);
    for (size_t i = 0; i < seeds_.size(); ++i) s.key[i] = chebyshev_gap(rlo, rhi, seeds_[i].lo, seeds_[i].hi);
    std::sort(s.order.begin(), s.order.end(),
              [&](uint32_t a, uint32_t b) { return s.key[a] < s.key[b] || (s.key[a] == s.key[b] && a < b); });
    const size_t top = ldims_.size() - 1;
    for (uint32_t si : s.order) {
        const Seed& seed = seeds_[si];
        glm::dvec3 klo = seed.lo, khi = seed.hi;
        // The axis along which the centre is farthest outside the blocker's bounds.
        auto pick_axis = [&](int& a, int& sgn, double& near) {
            a = -1;
            near = 0.0;
            for (int k = 0; k < 3; ++k) {
                const double g1 = klo[k] - c[k], g2 = c[k] - khi[k];
                if (g1 > near) {
                    a = k;
                    sgn = 1;
                    near = g1;
                }
                if (g2 > near) {
                    a = k;
                    sgn = -1;
                    near = g2;
                }
            }
        };
        int a, sgn = 1;
        double near;
        pick_axis(a, sgn, near);
        if (a < 0) continue;
        {
            // A blocker wholly in hidden space casts no umbra that is not hidden already.
            glm::ivec3 b0, b1;
            for (int k = 0; k < 3; ++k) {
                b0[k] =
                    std::clamp(int(std::floor((klo[k] - origin_[k]) / (double(b_) * h_))), 0, bdims_[k] - 1);
                b1[k] =
                    std::clamp(int(std::floor((khi[k] - origin_[k]) / (double(b_) * h_))), 0, bdims_[k] - 1);
            }
            if (range_hidden(s, b0, b1)) continue;
        }
        if (seed.kind == 0) {
            // Grow across the line of sight through the solid and the space hidden so far, then away.
            glm::ivec3 lo = seed.vlo, hi = seed.vhi;
            for (int round = 0; round < 2; ++round) {
                for (int k = 1; k <= 2; ++k)
                    for (int side : {-1, 1}) grow(s, lo, hi, (a + k) % 3, side, true);
                grow(s, lo, hi, a, sgn, true);
            }
            klo = origin_ + glm::dvec3(lo) * h_;
            khi = origin_ + glm::dvec3(hi) * h_;
            pick_axis(a, sgn, near);
            if (a < 0) continue;
        }
        // The blocker's shadows from the centre and from each corner of the region: the umbra lies in each,
        // so a node that misses one holds no point of it.
        Shadow shadows[9];
        int n_shadows = 0;
        if (!shadow_of(c, klo, khi, shadows[n_shadows])) continue;
        ++n_shadows;
        for (int i = 0; i < 8; ++i) {
            const glm::dvec3 q(i & 1 ? rhi.x : rlo.x, i & 2 ? rhi.y : rlo.y, i & 4 ? rhi.z : rlo.z);
            if (shadow_of(q, klo, khi, shadows[n_shadows])) ++n_shadows;
        }
        const Aabb region_f = region;
        bool cast_any = false;
        s.stack.clear();
        s.stack.push_back({int(top), glm::ivec3(0)});
        while (!s.stack.empty()) {
            const Scratch::Node node = s.stack.back();
            s.stack.pop_back();
            const size_t fi = flag_index(node.level, node.n);
            if ((s.flags[fi >> 6] >> (fi & 63)) & 1u) continue;
            const glm::ivec3 b0 = node.n << node.level;
            const glm::ivec3 b1 = glm::min((node.n + 1) << node.level, bdims_);
            glm::dvec3 nlo, nhi, tmp;
            block_box(b0, nlo, tmp);
            block_box(b1 - 1, tmp, nhi);
            double dd0 = 0.0;
            bool outside = false;
            for (int i = 0; i < n_shadows && !outside; ++i) {
                double d = 0.0;
                outside = !shadows[i].may_meet(nlo, nhi, d);
                if (i == 0) dd0 = d;
            }
            if (outside) continue;
            ++f.node_tests;
            cast_any = true;
            bool hides = false;
            if (seed.kind == 0) {
                hides = box_hides(rlo, rhi, nlo, nhi, klo, khi);
            } else {
                const Aabb nb = outward(nlo, nhi);
                hides = seed.kind == 1 ? panel_hides(region_f, nb, panels_[size_t(seed.index)], seed.axis)
                                       : slanted_hides(region_f, nb, set_.slanted[size_t(seed.index)]);
            }
            if (hides) {
                mark(s, node.level, node.n);
                ++f.nodes_hidden;
                continue;
            }
            if (node.level == 0) continue;
            if (!((relevant_[fi >> 6] >> (fi & 63)) & 1u)) continue;
            const glm::dvec3 size = nhi - nlo;
            if (std::max({size.x, size.y, size.z}) < kDescentSlope * dd0) continue;
            const glm::ivec3& cd = ldims_[size_t(node.level - 1)];
            for (int z = 0; z < 2; ++z)
                for (int y = 0; y < 2; ++y)
                    for (int x = 0; x < 2; ++x) {
                        const glm::ivec3 ch = node.n * 2 + glm::ivec3(x, y, z);
                        if (ch.x < cd.x && ch.y < cd.y && ch.z < cd.z)
                            s.stack.push_back({node.level - 1, ch});
                    }
        }
        if (cast_any) ++f.blockers;
    }
}

uint32_t UmbraHider::hide(const World& world, const Aabb& region, const std::vector<uint32_t>& objects,
                          uint64_t* hidden, UmbraFigures* figures) const {
    if (flags_ == 0 || region.is_empty()) return 0;
    const auto start = std::chrono::steady_clock::now();
    UmbraFigures f;
    ++f.regions;
    Scratch s;
    run(region, s, f);
    uint32_t n = 0;
    for (uint32_t o : objects) {
        if ((hidden[o >> 6] >> (o & 63)) & 1u) continue;
        const Aabb& b = world.objects[o].bounds;
        if (b.is_empty() || b.overlaps(region) || object_offset_[o] == object_offset_[o + 1]) continue;
        bool all = true;
        for (uint32_t i = object_offset_[o]; i < object_offset_[o + 1] && all; ++i) {
            const uint32_t bi = object_blocks_[i];
            const glm::ivec3 bc(int(bi % uint32_t(bdims_.x)),
                                int((bi / uint32_t(bdims_.x)) % uint32_t(bdims_.y)),
                                int(bi / (uint32_t(bdims_.x) * uint32_t(bdims_.y))));
            all = block_hidden(s, bc);
        }
        if (all) {
            hidden[o >> 6] |= uint64_t(1) << (o & 63);
            ++n;
        }
    }
    f.hidden += n;
    f.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (figures) *figures += f;
    return n;
}

std::vector<uint8_t> UmbraHider::hidden_blocks(const Aabb& region) const {
    std::vector<uint8_t> out(size_t(bdims_.x) * size_t(bdims_.y) * size_t(bdims_.z), 0);
    if (flags_ == 0 || region.is_empty()) return out;
    Scratch s;
    UmbraFigures f;
    run(region, s, f);
    for (int z = 0; z < bdims_.z; ++z)
        for (int y = 0; y < bdims_.y; ++y)
            for (int x = 0; x < bdims_.x; ++x)
                out[size_t(x) + size_t(bdims_.x) * (size_t(y) + size_t(bdims_.y) * size_t(z))] =
                    block_hidden(s, {x, y, z}) ? 1 : 0;
    return out;
}

}  // namespace pvs
