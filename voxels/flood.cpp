// SPDX-License-Identifier: MIT
// Flood of free voxels from seeds: on all threads for the reached set; breadth first on one thread when it
// leaks, up to the first border voxel reached, for the path to it.
#include "voxels/flood.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <limits>

namespace pvs {

namespace {

const glm::ivec3 kSteps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
constexpr uint8_t kSeedMark = 6;  // came_from value of a seed voxel
constexpr int kStepUp = 2;        // kSteps[2] is +y
constexpr int kStepDown = 3;      // kSteps[3] is -y

bool on_border(const VoxelGrid& g, glm::ivec3 c) {
    return c.x == 0 || c.y == 0 || c.z == 0 || c.x == g.dims.x - 1 || c.y == g.dims.y - 1 ||
           c.z == g.dims.z - 1;
}

// The free voxel nearest to c within `radius` voxels (Chebyshev shells), or -1.
int64_t nearest_free(const VoxelGrid& g, const BitVolume& blocked, glm::ivec3 c, int radius) {
    for (int r = 1; r <= radius; ++r) {
        int64_t best = -1;
        int best_d = std::numeric_limits<int>::max();
        for (int z = -r; z <= r; ++z)
            for (int y = -r; y <= r; ++y)
                for (int x = -r; x <= r; ++x) {
                    if (std::max({std::abs(x), std::abs(y), std::abs(z)}) != r) continue;
                    const glm::ivec3 p = c + glm::ivec3(x, y, z);
                    if (!g.inside(p) || blocked.get(g.index(p.x, p.y, p.z))) continue;
                    const int d = x * x + y * y + z * z;
                    if (d < best_d) best_d = d, best = int64_t(g.index(p.x, p.y, p.z));
                }
        if (best >= 0) return best;
    }
    return -1;
}

// May the flood step from voxel i to its free neighbour j by step s? Walking: into the band from anywhere;
// out of it only sideways off a ledge or down; from the air outside it only down (falling).
bool may_step(const WalkRules* walk, int s, uint64_t i, uint64_t j) {
    return !(walk && s != kStepDown &&
             ((!walk->band.get(j) && (s == kStepUp || !walk->band.get(i))) || walk->glass.get(j)));
}

// What the flood reaches from `frontier` (its voxels already set in `reached`), without the order: level
// by level, a big level's voxels expanded on all threads, each voxel joining the next level once (the
// thread whose atomic OR sets its bit). The set is the breadth-first search's, for any thread count.
void reach_in_parallel(const VoxelGrid& grid, const BitVolume& blocked, const WalkRules* walk,
                       std::vector<uint64_t> frontier, BitVolume& reached) {
    std::vector<uint64_t> next;
    while (!frontier.empty()) {
        next.clear();
        const int64_t n = int64_t(frontier.size());
#pragma omp parallel if (n >= 4096)
        {
            std::vector<uint64_t> mine;
#pragma omp for schedule(static) nowait
            for (int64_t k = 0; k < n; ++k) {
                const uint64_t i = frontier[size_t(k)];
                const glm::ivec3 c = grid.coords(i);
                for (int s = 0; s < 6; ++s) {
                    const glm::ivec3 nb = c + kSteps[s];
                    if (!grid.inside(nb)) continue;
                    const uint64_t j = grid.index(nb.x, nb.y, nb.z);
                    const uint64_t bit = uint64_t(1) << (j & 63);
                    std::atomic_ref<uint64_t> word(reached.words[j >> 6]);
                    if ((word.load(std::memory_order_relaxed) & bit) || blocked.get(j) || !may_step(walk, s, i, j))
                        continue;
                    if (word.fetch_or(bit, std::memory_order_relaxed) & bit) continue;  // another thread's
                    mine.push_back(j);
                }
            }
#pragma omp critical(flood_next)
            next.insert(next.end(), mine.begin(), mine.end());
        }
        std::swap(frontier, next);
    }
}

// Does the reached set touch the grid's border layer? (Walking, the band may reach the grid's top above the
// highest floor: that is no way out, so the top layer does not count.)
bool reaches_border(const VoxelGrid& g, const BitVolume& reached, bool walking) {
    for (int z = 0; z < g.dims.z; ++z)
        for (int y = 0; y < g.dims.y; ++y) {
            if (walking && y == g.dims.y - 1) continue;
            if (z == 0 || z == g.dims.z - 1 || y == 0 || y == g.dims.y - 1) {
                for (int x = 0; x < g.dims.x; ++x)
                    if (reached.get(g.index(x, y, z))) return true;
            } else if (reached.get(g.index(0, y, z)) || reached.get(g.index(g.dims.x - 1, y, z))) {
                return true;
            }
        }
    return false;
}

}  // namespace

FloodResult flood_free_space(Context& ctx, const VoxelGrid& grid, const BitVolume& blocked,
                             const std::vector<glm::vec3>& seeds, int max_seed_move_voxels,
                             const WalkRules* walk) {
    ScopedTimer timer(ctx, "flood");
    FloodResult r;
    r.reached.reset(grid.count());
    std::vector<uint64_t> frontier, next;
    for (const glm::vec3& s : seeds) {
        if (!is_finite(s) || !grid.bounds().contains(s)) {
            ++r.seeds_dropped;
            ctx.warn(fmt::format("flood: view seed ({:.2f}, {:.2f}, {:.2f}) is outside the world; ignored",
                                 s.x, s.y, s.z));
            continue;
        }
        const glm::ivec3 c = grid.voxel_of(s);
        int64_t i = int64_t(grid.index(c.x, c.y, c.z));
        if (blocked.get(uint64_t(i))) {
            i = nearest_free(grid, blocked, c, max_seed_move_voxels);
            if (i < 0) {
                ++r.seeds_dropped;
                ctx.warn(fmt::format(
                    "flood: view seed ({:.2f}, {:.2f}, {:.2f}) is inside solid with no free voxel "
                    "within {} voxels; ignored",
                    s.x, s.y, s.z, max_seed_move_voxels));
                continue;
            }
            ++r.seeds_moved;
        }
        ++r.seeds_used;
        if (r.reached.get(uint64_t(i))) continue;
        r.reached.set(uint64_t(i));
        frontier.push_back(uint64_t(i));
    }
    // The reached set, on all threads. A leaking level is searched again breadth first on one thread, for
    // the leak path (the first border voxel in that order and the steps back to a seed), up to that voxel.
    reach_in_parallel(grid, blocked, walk, frontier, r.reached);
    if (!reaches_border(grid, r.reached, walk != nullptr)) {
        r.reached_count = r.reached.count();
        ctx.debug(fmt::format("flood: {} seeds, {} voxels reached, sealed", r.seeds_used, r.reached_count));
        return r;
    }
    // came_from[i]: the step index that entered voxel i (0..5), kSeedMark for seeds; 0xff = not reached.
    // The search stops at the first border voxel it takes: the reached set is the parallel flood's (the
    // same set), and the path needs only the voxels taken before it.
    std::vector<uint8_t> came_from(grid.count(), 0xff);
    for (const uint64_t i : frontier) came_from[i] = kSeedMark;
    int64_t leak_voxel = -1;
    while (!frontier.empty() && leak_voxel < 0) {
        next.clear();
        for (uint64_t i : frontier) {
            const glm::ivec3 c = grid.coords(i);
            // (Walking, the band may reach the grid's top above the highest floor: that is no way out.)
            if (on_border(grid, c) && !(walk && c.y == grid.dims.y - 1)) {
                leak_voxel = int64_t(i);
                break;
            }
            for (int s = 0; s < 6; ++s) {
                const glm::ivec3 n = c + kSteps[s];
                if (!grid.inside(n)) continue;
                const uint64_t j = grid.index(n.x, n.y, n.z);
                if (came_from[j] != 0xff || blocked.get(j) || !may_step(walk, s, i, j)) continue;
                came_from[j] = uint8_t(s);
                next.push_back(j);
            }
        }
        std::swap(frontier, next);
    }
    r.reached_count = r.reached.count();
    if (leak_voxel >= 0) {
        r.leaked = true;
        // Walk back to the seed; keep the points where the path turns.
        std::vector<glm::ivec3> path;
        uint64_t i = uint64_t(leak_voxel);
        while (true) {
            const glm::ivec3 c = grid.coords(i);
            path.push_back(c);
            const uint8_t s = came_from[i];
            if (s == kSeedMark) break;
            const glm::ivec3 p = c - kSteps[s];
            i = grid.index(p.x, p.y, p.z);
        }
        std::reverse(path.begin(), path.end());
        for (size_t k = 0; k < path.size(); ++k) {
            const bool turn =
                k == 0 || k + 1 == path.size() || (path[k] - path[k - 1]) != (path[k + 1] - path[k]);
            if (turn) r.leak_path.push_back(grid.voxel_center(path[k]));
        }
    }
    ctx.debug(fmt::format("flood: {} seeds, {} voxels reached, {}", r.seeds_used, r.reached_count,
                          r.leaked ? "LEAKS" : "sealed"));
    return r;
}

namespace {

// Voxels as rows of whole words (row (y, z) at ((z * dims.y + y) * words_per_row)), so rows can be
// combined a word at a time.
struct RowBits {
    int words_per_row = 0;
    std::vector<uint64_t> w;
    uint64_t* row(const VoxelGrid& g, int y, int z) {
        return w.data() + (size_t(z) * size_t(g.dims.y) + size_t(y)) * size_t(words_per_row);
    }
    const uint64_t* row(const VoxelGrid& g, int y, int z) const {
        return w.data() + (size_t(z) * size_t(g.dims.y) + size_t(y)) * size_t(words_per_row);
    }
};

// The 64 bits of `v` from bit `pos` on (bits past the end read 0).
uint64_t bits_at(const BitVolume& v, uint64_t pos) {
    const uint64_t w = pos >> 6, r = pos & 63;
    const uint64_t lo = w < v.words.size() ? v.words[w] : 0;
    if (r == 0) return lo;
    const uint64_t hi = w + 1 < v.words.size() ? v.words[w + 1] : 0;
    return (lo >> r) | (hi << (64 - r));
}

// Each row a word at a time; rows are independent, so they run in parallel.
RowBits to_rows(const VoxelGrid& g, const BitVolume& v, bool invert) {
    RowBits r;
    const int W = (g.dims.x + 63) / 64;
    r.words_per_row = W;
    r.w.resize(size_t(g.dims.y) * size_t(g.dims.z) * size_t(W));
    const int tail = g.dims.x % 64;
    const int64_t rows = int64_t(g.dims.y) * g.dims.z;
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < rows; ++k) {
        const int y = int(k % g.dims.y), z = int(k / g.dims.y);
        uint64_t* out = r.row(g, y, z);
        const uint64_t base = g.index(0, y, z);
        for (int w = 0; w < W; ++w) {
            const uint64_t bits = bits_at(v, base + uint64_t(w) * 64);
            out[w] = invert ? ~bits : bits;
        }
        if (tail) out[W - 1] &= (uint64_t(1) << tail) - 1;
    }
    return r;
}

// ORs `bits` into `v` at bit `pos` (within v's words), atomically: a row's first and last words may be
// another row's too.
void or_bits_at(BitVolume& v, uint64_t pos, uint64_t bits) {
    if (!bits) return;
    const uint64_t w = pos >> 6, r = pos & 63;
    std::atomic_ref<uint64_t>(v.words[w]).fetch_or(bits << r, std::memory_order_relaxed);
    if (r && (bits >> (64 - r)))
        std::atomic_ref<uint64_t>(v.words[w + 1]).fetch_or(bits >> (64 - r), std::memory_order_relaxed);
}

// Bits of `seed` (within `open`) spread along x through runs of `open`, upwards (x increasing) when
// `up`: the Kogge-Stone occluded fill, carried from word to word.
void fill_row(const uint64_t* seed, const uint64_t* open, uint64_t* out, int words, bool up) {
    uint64_t carry = 0;
    for (int k = 0; k < words; ++k) {
        const int w = up ? k : words - 1 - k;
        const uint64_t f = open[w];
        uint64_t gen = (seed[w] | (up ? carry : carry << 63)) & f, pro = f;
        if (up) {
            gen |= pro & (gen << 1), pro &= pro << 1;
            gen |= pro & (gen << 2), pro &= pro << 2;
            gen |= pro & (gen << 4), pro &= pro << 4;
            gen |= pro & (gen << 8), pro &= pro << 8;
            gen |= pro & (gen << 16), pro &= pro << 16;
            gen |= pro & (gen << 32);
            carry = gen >> 63;
        } else {
            gen |= pro & (gen >> 1), pro &= pro >> 1;
            gen |= pro & (gen >> 2), pro &= pro >> 2;
            gen |= pro & (gen >> 4), pro &= pro >> 4;
            gen |= pro & (gen >> 8), pro &= pro >> 8;
            gen |= pro & (gen >> 16), pro &= pro >> 16;
            gen |= pro & (gen >> 32);
            carry = gen & 1;
        }
        out[w] = gen;
    }
}

}  // namespace

BitVolume sight_reach(const VoxelGrid& g, const BitVolume& blocked, const BitVolume& sources) {
    const RowBits open = to_rows(g, blocked, true), src = to_rows(g, sources, false);
    const int W = open.words_per_row;
    const size_t plane_words = size_t(g.dims.y) * size_t(W);
    // What any octant reaches, ORed in as each row is done (atomically: octants run on several threads).
    RowBits seen;
    seen.words_per_row = W;
    seen.w.assign(open.w.size(), 0);
#pragma omp parallel
    {
        // A sweep reads only the plane before the current one: two planes a thread.
        std::vector<uint64_t> planes(2 * plane_words);
        std::vector<uint64_t> in(static_cast<size_t>(W)), pred(static_cast<size_t>(W));
#pragma omp for schedule(dynamic, 1)
        for (int octant = 0; octant < 8; ++octant) {
            const int sx = octant & 1 ? -1 : 1, sy = octant & 2 ? -1 : 1, sz = octant & 4 ? -1 : 1;
            for (int kz = 0; kz < g.dims.z; ++kz) {
                const int z = sz > 0 ? kz : g.dims.z - 1 - kz;
                uint64_t* current = planes.data() + size_t(kz & 1) * plane_words;
                const uint64_t* previous = planes.data() + size_t((kz + 1) & 1) * plane_words;
                const auto row_of = [&](const uint64_t* plane, int y) { return plane + size_t(y) * size_t(W); };
                for (int ky = 0; ky < g.dims.y; ++ky) {
                    const int y = sy > 0 ? ky : g.dims.y - 1 - ky;
                    // Steps into (x, y, z) from the previous row and plane: (y - sy), (z - sz) or both.
                    std::fill(pred.begin(), pred.end(), 0);
                    const bool has_y = ky > 0, has_z = kz > 0;
                    auto add = [&](const uint64_t* r) {
                        for (int w = 0; w < W; ++w) pred[size_t(w)] |= r[w];
                    };
                    if (has_y) add(row_of(current, y - sy));
                    if (has_z) add(row_of(previous, y));
                    if (has_y && has_z) add(row_of(previous, y - sy));
                    // ... with or without a step along x (edge and corner steps), then along x in the row.
                    const uint64_t* s = src.row(g, y, z);
                    for (int w = 0; w < W; ++w) {
                        const uint64_t p = pred[size_t(w)];
                        const uint64_t shifted = sx > 0
                                                     ? (p << 1) | (w > 0 ? pred[size_t(w - 1)] >> 63 : 0)
                                                     : (p >> 1) | (w + 1 < W ? pred[size_t(w + 1)] << 63 : 0);
                        in[size_t(w)] = s[w] | p | shifted;
                    }
                    uint64_t* out = current + size_t(y) * size_t(W);
                    fill_row(in.data(), open.row(g, y, z), out, W, sx > 0);
                    uint64_t* m = seen.row(g, y, z);
                    for (int w = 0; w < W; ++w) {
                        std::atomic_ref<uint64_t> word(m[w]);
                        if (out[w] & ~word.load(std::memory_order_relaxed))
                            word.fetch_or(out[w], std::memory_order_relaxed);
                    }
                }
            }
        }
    }
    BitVolume out;
    out.reset(g.count());
    const int64_t rows = int64_t(g.dims.y) * g.dims.z;
    const int tail = g.dims.x % 64;
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < rows; ++k) {
        const int y = int(k % g.dims.y), z = int(k / g.dims.y);
        const uint64_t* r = seen.row(g, y, z);
        const uint64_t base = g.index(0, y, z);
        for (int w = 0; w < W; ++w) {
            const uint64_t bits = w + 1 == W && tail ? r[w] & ((uint64_t(1) << tail) - 1) : r[w];
            or_bits_at(out, base + uint64_t(w) * 64, bits);
        }
    }
    return out;
}

}  // namespace pvs
