// Breadth-first flood of free voxels from seeds; the first border voxel reached gives the leak path.
#include "voxels/flood.h"

#include <fmt/format.h>

#include <algorithm>
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

}  // namespace

FloodResult flood_free_space(Context& ctx, const VoxelGrid& grid, const BitVolume& blocked,
                             const std::vector<glm::vec3>& seeds, int max_seed_move_voxels,
                             const WalkRules* walk) {
    ScopedTimer timer(ctx, "flood");
    FloodResult r;
    r.reached.reset(grid.count());
    // came_from[i]: the step index that entered voxel i (0..5), kSeedMark for seeds; 0xff = not reached.
    std::vector<uint8_t> came_from(grid.count(), 0xff);
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
        if (came_from[uint64_t(i)] != 0xff) continue;
        came_from[uint64_t(i)] = kSeedMark;
        r.reached.set(uint64_t(i));
        frontier.push_back(uint64_t(i));
    }
    int64_t leak_voxel = -1;
    while (!frontier.empty()) {
        next.clear();
        for (uint64_t i : frontier) {
            const glm::ivec3 c = grid.coords(i);
            // (Walking, the band may reach the grid's top above the highest floor: that is no way out.)
            if (leak_voxel < 0 && on_border(grid, c) && !(walk && c.y == grid.dims.y - 1))
                leak_voxel = int64_t(i);
            for (int s = 0; s < 6; ++s) {
                const glm::ivec3 n = c + kSteps[s];
                if (!grid.inside(n)) continue;
                const uint64_t j = grid.index(n.x, n.y, n.z);
                if (came_from[j] != 0xff || blocked.get(j)) continue;
                // Walking: into the band from anywhere; out of it only sideways off a ledge or down; from the
                // air outside it only down (falling).
                if (walk && s != kStepDown &&
                    ((!walk->band.get(j) && (s == kStepUp || !walk->band.get(i))) || walk->glass.get(j)))
                    continue;
                came_from[j] = uint8_t(s);
                r.reached.set(j);
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

RowBits to_rows(const VoxelGrid& g, const BitVolume& v, bool invert) {
    RowBits r;
    r.words_per_row = (g.dims.x + 63) / 64;
    r.w.assign(size_t(g.dims.y) * size_t(g.dims.z) * size_t(r.words_per_row), 0);
    for (int z = 0; z < g.dims.z; ++z)
        for (int y = 0; y < g.dims.y; ++y) {
            uint64_t* out = r.row(g, y, z);
            const uint64_t base = g.index(0, y, z);
            for (int x = 0; x < g.dims.x; ++x)
                if (v.get(base + uint64_t(x)) != invert) out[x >> 6] |= uint64_t(1) << (x & 63);
        }
    return r;
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
    RowBits seen;
    seen.words_per_row = W;
    seen.w.assign(open.w.size(), 0);
#pragma omp parallel
    {
        RowBits reach;
        reach.words_per_row = W;
        reach.w.assign(open.w.size(), 0);
        RowBits mine;
        mine.words_per_row = W;
        mine.w.assign(open.w.size(), 0);
        std::vector<uint64_t> in(static_cast<size_t>(W)), pred(static_cast<size_t>(W));
#pragma omp for schedule(dynamic, 1)
        for (int octant = 0; octant < 8; ++octant) {
            const int sx = octant & 1 ? -1 : 1, sy = octant & 2 ? -1 : 1, sz = octant & 4 ? -1 : 1;
            for (int kz = 0; kz < g.dims.z; ++kz) {
                const int z = sz > 0 ? kz : g.dims.z - 1 - kz;
                for (int ky = 0; ky < g.dims.y; ++ky) {
                    const int y = sy > 0 ? ky : g.dims.y - 1 - ky;
                    // Steps into (x, y, z) from the previous row and plane: (y - sy), (z - sz) or both.
                    std::fill(pred.begin(), pred.end(), 0);
                    const bool has_y = ky > 0, has_z = kz > 0;
                    auto add = [&](const uint64_t* r) {
                        for (int w = 0; w < W; ++w) pred[size_t(w)] |= r[w];
                    };
                    if (has_y) add(reach.row(g, y - sy, z));
                    if (has_z) add(reach.row(g, y, z - sz));
                    if (has_y && has_z) add(reach.row(g, y - sy, z - sz));
                    // ... with or without a step along x (edge and corner steps), then along x in the row.
                    const uint64_t* s = src.row(g, y, z);
                    for (int w = 0; w < W; ++w) {
                        const uint64_t p = pred[size_t(w)];
                        const uint64_t shifted = sx > 0
                                                     ? (p << 1) | (w > 0 ? pred[size_t(w - 1)] >> 63 : 0)
                                                     : (p >> 1) | (w + 1 < W ? pred[size_t(w + 1)] << 63 : 0);
                        in[size_t(w)] = s[w] | p | shifted;
                    }
                    uint64_t* out = reach.row(g, y, z);
                    fill_row(in.data(), open.row(g, y, z), out, W, sx > 0);
                    uint64_t* m = mine.row(g, y, z);
                    for (int w = 0; w < W; ++w) m[w] |= out[w];
                }
            }
        }
#pragma omp critical
        for (size_t i = 0; i < seen.w.size(); ++i) seen.w[i] |= mine.w[i];
    }
    BitVolume out;
    out.reset(g.count());
    for (int z = 0; z < g.dims.z; ++z)
        for (int y = 0; y < g.dims.y; ++y) {
            const uint64_t* r = seen.row(g, y, z);
            const uint64_t base = g.index(0, y, z);
            for (int x = 0; x < g.dims.x; ++x)
                if ((r[x >> 6] >> (x & 63)) & 1u) out.set(base + uint64_t(x));
        }
    return out;
}

}  // namespace pvs
