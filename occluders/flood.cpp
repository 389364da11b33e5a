// Breadth-first flood of free voxels from seeds; the first border voxel reached gives the leak path.
#include "occluders/flood.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace pvs {

namespace {

const glm::ivec3 kSteps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
constexpr uint8_t kSeedMark = 6;  // came_from value of a seed voxel

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
                             const std::vector<glm::vec3>& seeds, int max_seed_move_voxels) {
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
            if (leak_voxel < 0 && on_border(grid, c)) leak_voxel = int64_t(i);
            for (int s = 0; s < 6; ++s) {
                const glm::ivec3 n = c + kSteps[s];
                if (!grid.inside(n)) continue;
                const uint64_t j = grid.index(n.x, n.y, n.z);
                if (came_from[j] != 0xff || blocked.get(j)) continue;
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

}  // namespace pvs
