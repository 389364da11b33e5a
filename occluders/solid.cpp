// Solid classification: a flood of sight from the eye space through untouched voxels; the rest, less the
// touched voxels, is solid.
#include "occluders/solid.h"

#include "core/error.h"

#include <fmt/format.h>

namespace pvs {

Solid classify_solid(Context& ctx, const VoxelGrid& grid, const BitVolume& touched, const VoxelMask& eyes) {
    ScopedTimer timer(ctx, "solid");
    Solid out;
    out.grid = grid;
    BitVolume reached;
    reached.reset(grid.count());
    std::vector<uint64_t> frontier, next;
    if (!eyes.empty()) {
        if (eyes.dims != grid.dims || eyes.origin != grid.origin || eyes.voxel_size_m != grid.voxel_size_m) {
            throw internal_error("classify_solid: the eye mask is not on the voxel grid");
        }
        out.from_eye_space = true;
        for (uint64_t i = 0; i < grid.count(); ++i) {
            if (eyes.get(i) && !touched.get(i)) {
                reached.set(i);
                frontier.push_back(i);
            }
        }
    } else {
        for (uint64_t i = 0; i < grid.count(); ++i) {
            const glm::ivec3 c = grid.coords(i);
            const bool border = c.x == 0 || c.y == 0 || c.z == 0 || c.x == grid.dims.x - 1 ||
                                c.y == grid.dims.y - 1 || c.z == grid.dims.z - 1;
            if (border && !touched.get(i)) {
                reached.set(i);
                frontier.push_back(i);
            }
        }
    }
    static const glm::ivec3 kSteps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    while (!frontier.empty()) {
        next.clear();
        for (uint64_t i : frontier) {
            const glm::ivec3 c = grid.coords(i);
            for (const glm::ivec3& s : kSteps) {
                const glm::ivec3 n = c + s;
                if (!grid.inside(n)) continue;
                const uint64_t j = grid.index(n.x, n.y, n.z);
                if (reached.get(j) || touched.get(j)) continue;
                reached.set(j);
                next.push_back(j);
            }
        }
        std::swap(frontier, next);
    }
    out.solid.reset(grid.count());
    for (size_t w = 0; w < out.solid.words.size(); ++w)
        out.solid.words[w] = ~(reached.words[w] | touched.words[w]);
    const uint64_t tail = grid.count() % 64;
    if (tail) out.solid.words.back() &= (uint64_t(1) << tail) - 1;
    out.solid_voxels = out.solid.count();
    out.solid_m3 =
        double(out.solid_voxels) * double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    ctx.info(fmt::format("solid: {:.0f} m3 in {} voxels ({})", out.solid_m3, out.solid_voxels,
                         out.from_eye_space ? "sealed off from the eyes" : "inside closed meshes"));
    return out;
}

}  // namespace pvs
