// SPDX-License-Identifier: MIT
// Separation in the shaft: a flood over an exact grid of the occluders that meet the hull of two boxes.
#include "pvs/shaft_flood.h"

#include "occluders/panels.h"
#include "pvs/region_hiding.h"

#include <algorithm>
#include <cmath>

namespace pvs {

namespace {

// The grid's planes per axis: the domain's two sides, kFloodSplits - 1 even cuts (they tighten what the
// hull leaves out of big cells), and the occluders' sides, at most kMaxFloodPlanes in all. At most
// kMaxFloodCandidates occluders, the nearest the line between the boxes' centres, are offered to the grid.
constexpr int kFloodSplits = 4;
constexpr size_t kMaxFloodPlanes = 48;
constexpr size_t kMaxFloodCandidates = 1024;

// a * l <= b, for l in [l0, l1]: narrows the interval; false when it empties.
bool narrow(double a, double b, double& l0, double& l1) {
    if (a > 0.0) {
        l1 = std::min(l1, b / a);
    } else if (a < 0.0) {
        l0 = std::max(l0, b / a);
    } else if (b < 0.0) {
        return false;
    }
    return l0 <= l1;
}

// The hull of two boxes q and x: the union over l in [0, 1] of the boxes l q + (1 - l) x.
struct Hull {
    glm::dvec3 qlo, qhi, xlo, xhi;
    // The l in [l0, l1] for which the box l q + (1 - l) x meets [lo, hi] grown by `margin` on axis k:
    // narrows the interval; false when it empties.
    bool narrow_axis(int k, double lo, double hi, double margin, double& l0, double& l1) const {
        // The box reaches down to x_lo + l (q_lo - x_lo) <= hi + margin ...
        if (!narrow(qlo[k] - xlo[k], hi + margin - xlo[k], l0, l1)) return false;
        // ... and up to x_hi + l (q_hi - x_hi) >= lo - margin.
        return narrow(xhi[k] - qhi[k], xhi[k] - lo + margin, l0, l1);
    }
    // Does the closed box [lo, hi] grown by `margin` meet the hull? False only when they are disjoint.
    bool meets(const glm::dvec3& lo, const glm::dvec3& hi, double margin) const {
        double l0 = 0.0, l1 = 1.0;
        for (int k = 0; k < 3; ++k)
            if (!narrow_axis(k, lo[k], hi[k], margin, l0, l1)) return false;
        return true;
    }
};

bool boxes_meet(const glm::dvec3& alo, const glm::dvec3& ahi, const glm::dvec3& blo, const glm::dvec3& bhi) {
    return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y && alo.z <= bhi.z &&
           blo.z <= ahi.z;
}

// The squared distance from p to the segment a -> b.
double distance2_to_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
    const glm::dvec3 d = b - a;
    const double len2 = glm::dot(d, d);
    const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
    const glm::dvec3 e = a + t * d - p;
    return glm::dot(e, e);
}

struct FloodScratch {
    std::array<std::vector<double>, 3> planes;
    std::vector<std::pair<double, uint32_t>> order;
    std::vector<uint32_t> used;
    std::vector<uint8_t> state;  // per cell: kSolid, kSeen
    std::vector<uint8_t> cover;  // per cell: bit a when its face towards +a lies in a panel
    std::vector<uint32_t> queue;
    // Per axis and cell index along it, the l of the hull's boxes l q + (1 - l) x meeting the cells there.
    std::array<std::vector<glm::dvec2>, 3> span;
};
constexpr uint8_t kSolid = 1, kSeen = 2;

}  // namespace

std::vector<FloodBox> solid_tiles(const VoxelMask& m) {
    std::vector<FloodBox> out;
    if (m.empty()) return out;
    const glm::ivec3 n = m.dims;
    const int e = kSolidTileChunk;
    const glm::ivec3 chunks = (n + e - 1) / e;
    const auto at = [&](int axis, int k) {
        return double(m.origin[axis]) + double(k) * double(m.voxel_size_m);
    };
    std::vector<std::vector<FloodBox>> per_chunk(size_t(chunks.x) * size_t(chunks.y) * size_t(chunks.z));
#pragma omp parallel for schedule(dynamic, 16)
    for (size_t c = 0; c < per_chunk.size(); ++c) {
        const glm::ivec3 ci(int(c % size_t(chunks.x)), int((c / size_t(chunks.x)) % size_t(chunks.y)),
                            int(c / (size_t(chunks.x) * size_t(chunks.y))));
        const glm::ivec3 lo = ci * e, hi = glm::min(lo + e, n);
        // Per slice z, rectangles [x0, x1) x [y0, y1): runs along x merged over y when equal; then
        // rectangles merged over z when equal.
        struct Box {
            int x0, x1, y0, y1, z0, z1;
        };
        std::vector<Box> boxes;
        std::vector<size_t> open, next, rects;  // boxes reaching the slice before; rectangles of this slice
        std::vector<size_t> row_open, row_next;
        for (int z = lo.z; z < hi.z; ++z) {
            rects.clear();
            row_open.clear();
            for (int y = lo.y; y < hi.y; ++y) {
                row_next.clear();
                const uint64_t row = (uint64_t(z) * uint64_t(n.y) + uint64_t(y)) * uint64_t(n.x);
                size_t r = 0;  // into row_open, ordered by x0
                for (int x = lo.x; x < hi.x;) {
                    if (!m.get(row + uint64_t(x))) {
                        ++x;
                        continue;
                    }
                    int end = x;
                    while (end < hi.x && m.get(row + uint64_t(end))) ++end;
                    while (r < row_open.size() && boxes[row_open[r]].x0 < x) ++r;
                    if (r < row_open.size() && boxes[row_open[r]].x0 == x && boxes[row_open[r]].x1 == end) {
                        boxes[row_open[r]].y1 = y + 1;
                        row_next.push_back(row_open[r]);
                    } else {
                        row_next.push_back(boxes.size());
                        rects.push_back(boxes.size());
                        boxes.push_back(Box{x, end, y, y + 1, z, z + 1});
                    }
                    x = end;
                }
                std::swap(row_open, row_next);
            }
            // This slice's new rectangles: each continues a box of the slice before when equal to it.
            next.clear();
            for (const size_t i : rects) {
                Box& b = boxes[i];
                const auto same = std::find_if(open.begin(), open.end(), [&](size_t j) {
                    const Box& o = boxes[j];
                    return o.x0 == b.x0 && o.x1 == b.x1 && o.y0 == b.y0 && o.y1 == b.y1;
                });
                if (same != open.end()) {
                    boxes[*same].z1 = z + 1;
                    b.x1 = b.x0;  // merged: dropped below
                    next.push_back(*same);
                } else {
                    next.push_back(i);
                }
            }
            std::swap(open, next);
        }
        std::vector<FloodBox>& mine = per_chunk[c];
        for (const Box& b : boxes)
            if (b.x1 > b.x0)
                mine.push_back(FloodBox{{at(0, b.x0), at(1, b.y0), at(2, b.z0)},
                                        {at(0, b.x1), at(1, b.y1), at(2, b.z1)}});
    }
    for (const std::vector<FloodBox>& v : per_chunk) out.insert(out.end(), v.begin(), v.end());
    return out;
}

ShaftFlood::ShaftFlood(const std::vector<Aabb>& panels, const VoxelMask& solid) {
    for (const Aabb& p : panels) {
        const int a = panel_axis(p);
        if (a < 0) continue;
        boxes_.push_back(FloodBox{glm::dvec3(p.min), glm::dvec3(p.max)});
        flat_.push_back(int8_t(a));
    }
    for (const FloodBox& t : solid_tiles(solid)) {
        boxes_.push_back(t);
        flat_.push_back(-1);
    }
    bounds_.reserve(boxes_.size());
    for (const FloodBox& b : boxes_) {
        bounds_.push_back(Aabb::of({float_at_most(b.lo.x), float_at_most(b.lo.y), float_at_most(b.lo.z)},
                                   {float_at_least(b.hi.x), float_at_least(b.hi.y), float_at_least(b.hi.z)}));
    }
    tree_ = BoxTree::build(bounds_);
}

bool ShaftFlood::separates(const Aabb& region, const Aabb& target, FloodFigures& figures) const {
    ++figures.tries;
    thread_local FloodScratch sc;
    const double tol = kHideToleranceM;
    const Hull hull{glm::dvec3(region.min) - tol, glm::dvec3(region.max) + tol, glm::dvec3(target.min) - tol,
                    glm::dvec3(target.max) + tol};
    if (boxes_meet(hull.qlo, hull.qhi, hull.xlo, hull.xhi)) return false;
    const glm::dvec3 dlo = glm::min(hull.qlo, hull.xlo), dhi = glm::max(hull.qhi, hull.xhi);
    const glm::dvec3 qc = 0.5 * (hull.qlo + hull.qhi), xc = 0.5 * (hull.xlo + hull.xhi);

    // The occluders that meet the hull, nearest the line between the boxes' centres first (panels before
    // the solid's tiles at equal distance).
    sc.order.clear();
    const Aabb query = Aabb::of({float_at_most(dlo.x), float_at_most(dlo.y), float_at_most(dlo.z)},
                                {float_at_least(dhi.x), float_at_least(dhi.y), float_at_least(dhi.z)});
    tree_.walk(
        [&](const Aabb& b) {
            return b.overlaps(query) && hull.meets(glm::dvec3(b.min), glm::dvec3(b.max), 0.0);
        },
        [&](uint32_t i) {
            const FloodBox& b = boxes_[i];
            if (!boxes_meet(b.lo, b.hi, dlo, dhi) || !hull.meets(b.lo, b.hi, 0.0)) return;
            const glm::dvec3 c = 0.5 * (glm::max(b.lo, dlo) + glm::min(b.hi, dhi));
            sc.order.emplace_back(distance2_to_segment(c, qc, xc), i);
        });
    if (sc.order.empty()) return false;
    if (sc.order.size() > kMaxFloodCandidates) {
        figures.dropped += sc.order.size() - kMaxFloodCandidates;
        std::nth_element(sc.order.begin(), sc.order.begin() + kMaxFloodCandidates, sc.order.end());
        sc.order.resize(kMaxFloodCandidates);
    }
    std::sort(sc.order.begin(), sc.order.end());

    for (int a = 0; a < 3; ++a) {
        std::vector<double>& p = sc.planes[size_t(a)];
        p.clear();
        for (int k = 0; k <= kFloodSplits; ++k)
            p.push_back(k == kFloodSplits ? dhi[a] : dlo[a] + (dhi[a] - dlo[a]) * double(k) / kFloodSplits);
        std::sort(p.begin(), p.end());
        p.erase(std::unique(p.begin(), p.end()), p.end());
    }
    // Takes an occluder when its sides inside the domain fit the budget of planes.
    sc.used.clear();
    std::array<double, 6> add;
    for (const auto& [d, i] : sc.order) {
        const FloodBox& b = boxes_[i];
        std::array<size_t, 3> extra{};
        size_t n_add = 0;
        bool fits = true;
        for (int a = 0; a < 3 && fits; ++a) {
            const std::vector<double>& p = sc.planes[size_t(a)];
            for (const double v : {b.lo[a], b.hi[a]}) {
                if (!(v > dlo[a] && v < dhi[a]) || std::binary_search(p.begin(), p.end(), v)) continue;
                if (n_add > 0 && add[n_add - 1] == v && extra[size_t(a)] > 0) continue;  // a panel's plane
                add[n_add++] = v;
                ++extra[size_t(a)];
            }
            fits = p.size() + extra[size_t(a)] <= kMaxFloodPlanes;
        }
        if (!fits) {
            ++figures.dropped;
            continue;
        }
        size_t k = 0;
        for (int a = 0; a < 3; ++a) {
            std::vector<double>& p = sc.planes[size_t(a)];
            for (size_t e = 0; e < extra[size_t(a)]; ++e, ++k)
                p.insert(std::upper_bound(p.begin(), p.end(), add[k]), add[k]);
        }
        sc.used.push_back(i);
    }

    const std::array<std::vector<double>, 3>& planes = sc.planes;
    const glm::ivec3 n(int(planes[0].size()) - 1, int(planes[1].size()) - 1, int(planes[2].size()) - 1);
    const size_t cells = size_t(n.x) * size_t(n.y) * size_t(n.z);
    figures.cells += cells;
    sc.state.assign(cells, 0);
    sc.cover.assign(cells, 0);
    const auto cell = [&](int x, int y, int z) {
        return size_t(x) + size_t(n.x) * (size_t(y) + size_t(n.y) * size_t(z));
    };
    // The cells within [lo, hi] on axis a (their sides are planes of the grid): [first, end).
    const auto inside = [&](int a, double lo, double hi, int& first, int& end) {
        const std::vector<double>& p = planes[size_t(a)];
        first = int(std::lower_bound(p.begin(), p.end(), std::max(lo, dlo[a])) - p.begin());
        end = int(std::lower_bound(p.begin(), p.end(), std::min(hi, dhi[a])) - p.begin());
    };
    // The cells whose closed boxes meet [lo, hi] on axis a: [first, end).
    const auto meeting = [&](int a, double lo, double hi, int& first, int& end) {
        const std::vector<double>& p = planes[size_t(a)];
        first = std::max(int(std::lower_bound(p.begin() + 1, p.end(), lo) - p.begin()) - 1, 0);
        end = int(std::upper_bound(p.begin(), p.end() - 1, hi) - p.begin());
    };
    for (const uint32_t i : sc.used) {
        const FloodBox& b = boxes_[i];
        const int flat = flat_[i];
        glm::ivec3 first, end;
        for (int a = 0; a < 3; ++a) {
            if (a == flat) continue;
            inside(a, b.lo[a], b.hi[a], first[a], end[a]);
        }
        if (flat < 0) {
            for (int z = first.z; z < end.z; ++z)
                for (int y = first.y; y < end.y; ++y)
                    for (int x = first.x; x < end.x; ++x) sc.state[cell(x, y, z)] = kSolid;
            continue;
        }
        // A panel on a plane inside the domain covers the faces between the cells on either side of it.
        if (!(b.lo[flat] > dlo[flat] && b.lo[flat] < dhi[flat])) continue;
        const std::vector<double>& p = planes[size_t(flat)];
        const int k = int(std::lower_bound(p.begin(), p.end(), b.lo[flat]) - p.begin());
        first[flat] = k - 1;
        end[flat] = k;
        for (int z = first.z; z < end.z; ++z)
            for (int y = first.y; y < end.y; ++y)
                for (int x = first.x; x < end.x; ++x) sc.cover[cell(x, y, z)] |= uint8_t(1u << flat);
    }

    const auto box_of = [&](int x, int y, int z, glm::dvec3& lo, glm::dvec3& hi) {
        lo = glm::dvec3(planes[0][size_t(x)], planes[1][size_t(y)], planes[2][size_t(z)]);
        hi = glm::dvec3(planes[0][size_t(x) + 1], planes[1][size_t(y) + 1], planes[2][size_t(z) + 1]);
    };
    // A cell meets the hull when the spans of l of its three indices overlap (Hull::meets, axis by axis).
    for (int a = 0; a < 3; ++a) {
        std::vector<glm::dvec2>& span = sc.span[size_t(a)];
        span.resize(size_t(n[a]));
        for (int i = 0; i < n[a]; ++i) {
            double l0 = 0.0, l1 = 1.0;
            if (!hull.narrow_axis(a, planes[size_t(a)][size_t(i)], planes[size_t(a)][size_t(i) + 1], tol, l0,
                                  l1))
                l0 = 2.0, l1 = -1.0;
            span[size_t(i)] = glm::dvec2(l0, l1);
        }
    }
    const auto meets_hull = [&](const glm::ivec3& at) {
        const glm::dvec2 &x = sc.span[0][size_t(at.x)], &y = sc.span[1][size_t(at.y)],
                         &z = sc.span[2][size_t(at.z)];
        return std::max({x[0], y[0], z[0]}) <= std::min({x[1], y[1], z[1]});
    };
    // Every segment from the region to the target moves one way along each axis: along an axis where the
    // two boxes are apart, towards the target; along another, either way, the same all along. So the flood
    // runs once per choice of ways on the axes where they overlap, each stepping only those ways.
    std::array<int, 3> forced{};
    int free_axes = 0;
    for (int a = 0; a < 3; ++a) {
        forced[size_t(a)] = hull.qhi[a] < hull.xlo[a] ? 1 : (hull.xhi[a] < hull.qlo[a] ? -1 : 0);
        free_axes += forced[size_t(a)] == 0 ? 1 : 0;
    }
    glm::ivec3 first, end;
    for (int a = 0; a < 3; ++a) meeting(a, hull.qlo[a], hull.qhi[a], first[a], end[a]);
    for (int way = 0; way < (1 << free_axes); ++way) {
        std::array<int, 3> step{};
        for (int a = 0, f = 0; a < 3; ++a)
            step[size_t(a)] = forced[size_t(a)] != 0 ? forced[size_t(a)] : ((way >> f++) & 1 ? 1 : -1);
        if (way > 0)
            for (uint8_t& st : sc.state) st &= kSolid;
        // Seeds: the open cells meeting the region; none may meet the target.
        sc.queue.clear();
        for (int z = first.z; z < end.z; ++z)
            for (int y = first.y; y < end.y; ++y)
                for (int x = first.x; x < end.x; ++x) {
                    const size_t c = cell(x, y, z);
                    if (sc.state[c] != 0) continue;
                    glm::dvec3 lo, hi;
                    box_of(x, y, z, lo, hi);
                    if (boxes_meet(lo, hi, hull.xlo, hull.xhi)) return false;
                    sc.state[c] = kSeen;
                    sc.queue.push_back(uint32_t(c));
                }
        // The flood, the chosen way on each axis, through faces no panel covers, into cells not solid that
        // meet the hull.
        for (size_t head = 0; head < sc.queue.size(); ++head) {
            const size_t c = sc.queue[head];
            const int x = int(c % size_t(n.x)), y = int((c / size_t(n.x)) % size_t(n.y)),
                      z = int(c / (size_t(n.x) * size_t(n.y)));
            const glm::ivec3 at(x, y, z);
            for (int a = 0; a < 3; ++a) {
                const int dir = step[size_t(a)];
                glm::ivec3 to = at;
                to[a] += dir;
                if (to[a] < 0 || to[a] >= n[a]) continue;
                const size_t t = cell(to.x, to.y, to.z);
                if (sc.state[t] != 0) continue;
                if (sc.cover[dir > 0 ? c : t] & (1u << a)) continue;
                sc.state[t] = kSeen;
                if (!meets_hull(to)) continue;
                glm::dvec3 lo, hi;
                box_of(to.x, to.y, to.z, lo, hi);
                if (boxes_meet(lo, hi, hull.xlo, hull.xhi)) return false;
                sc.queue.push_back(uint32_t(t));
            }
        }
    }
    ++figures.separated;
    return true;
}

}  // namespace pvs
