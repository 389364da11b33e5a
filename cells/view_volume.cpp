// SPDX-License-Identifier: MIT
// The view volume: voxelize, flood (or walk, with a play height) from the seeds, intersect with boxes and
// the play height band, grow by one voxel.
#include "cells/view_volume.h"

#include "cells/world_extent.h"
#include "core/error.h"
#include "voxels/flood.h"
#include "voxels/voxels.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace pvs {

namespace {

VoxelMask to_mask(const VoxelGrid& grid, BitVolume&& bits) {
    VoxelMask m;
    m.origin = grid.origin;
    m.voxel_size_m = grid.voxel_size_m;
    m.dims = grid.dims;
    m.bits = std::move(bits.words);
    return m;
}

}  // namespace

std::string leak_path_obj(const std::vector<glm::vec3>& path) {
    std::string out = "# pvsbake leak path: from a view seed to outside the world (metres, +Y up)\n";
    for (const glm::vec3& p : path) out += fmt::format("v {} {} {}\n", p.x, p.y, p.z);
    if (path.size() >= 2) {
        out += "l";
        for (size_t i = 1; i <= path.size(); ++i) out += fmt::format(" {}", i);
        out += "\n";
    }
    return out;
}

namespace {

std::vector<Aabb> view_boxes(const ViewVolumeConfig& config, const World& world) {
    std::vector<Aabb> boxes = config.boxes;
    if (config.use_world_boxes)
        boxes.insert(boxes.end(), world.view_volume_boxes.begin(), world.view_volume_boxes.end());
    return boxes;
}

std::vector<glm::vec3> view_seeds(const ViewVolumeConfig& config, const World& world) {
    std::vector<glm::vec3> seeds = config.seeds;
    if (config.use_world_seeds) seeds.insert(seeds.end(), world.view_seeds.begin(), world.view_seeds.end());
    return seeds;
}

bool has_sources(const ViewVolumeConfig& config, const World& world) {
    return !view_boxes(config, world).empty() || !view_seeds(config, world).empty() || config.play_height_m > 0.0;
}

}  // namespace

VoxelGrid planned_view_grid(const ViewVolumeConfig& config, const World& world) {
    // Without a source, the grid occluder synthesis voxelizes the world on: the default size, 2 voxels of pad.
    return has_sources(config, world) ? view_voxel_grid(config, world, config.auto_voxel_size_m, 0)
                                      : view_voxel_grid(config, world, kDefaultVoxelSizeM, 2);
}

ViewVolume build_view_volume(Context& ctx, const ViewVolumeConfig& config, const World& world) {
    ScopedTimer timer(ctx, "view_volume");
    ViewVolume vv;
    vv.world_bounds_m3 = world.bounds.volume();
    const std::vector<Aabb> boxes = view_boxes(config, world);
    const std::vector<glm::vec3> seeds = view_seeds(config, world);
    const bool play = config.play_height_m > 0.0;
    if (!has_sources(config, world)) {
        if (config.need_sources && !config.eyes_anywhere) {
            throw bad_input(
                "view volume: a conservative bake needs to know where eyes can be, and there are no view "
                "seeds, view boxes or play height: add pvs_view_seed nodes in the playable space (or "
                "--view-seed x,y,z), pvs_view_volume boxes (or --view-box), or --play-height; "
                "--eyes-anywhere bakes with eyes anywhere in the world's bounds (larger, slower, looser)");
        }
        const std::string what =
            "view volume: no view seeds, view boxes or play height: eyes may be anywhere in the world's bounds";
        if (config.eyes_anywhere) {
            ctx.info(what + " (--eyes-anywhere)");
        } else {
            ctx.warn(what + ", so the bake is larger and slower than it needs to be (add pvs_view_seed nodes or "
                            "--view-seed)");
        }
        vv.sources = {"world_bounds"};
        vv.view_bounds = world.bounds;
        vv.eye_volume_m3 = vv.view_volume_m3 = vv.world_bounds_m3;
        vv.grid = planned_view_grid(config, world);
        return vv;
    }
    for (const Aabb& b : boxes) {
        if (b.is_empty() || !is_finite(b.min) || !is_finite(b.max)) {
            throw bad_input(
                "view volume: a view box is empty or not finite (--view-box wants min x,y,z then max x,y,z)");
        }
    }
    vv.voxelized = true;
    // Pad by a metre (at least 2 voxels, void_pad_voxels()): around a sealed level the padding is solid the
    // flood never reaches, thick enough to stay an occluder after shrinking, so thin floors and walls of the
    // shell still occlude with the void behind them.
    const VoxelGrid grid = planned_view_grid(config, world);
    ctx.info(fmt::format("view volume: {} m voxels, {} x {} x {} = {:.1f} M voxels", grid.voxel_size_m,
                         grid.dims.x, grid.dims.y, grid.dims.z, double(grid.count()) * 1e-6));
    BitVolume touched, upward;
    BitVolume glass;
    voxelize_opaque(ctx, world, grid, touched, play ? &upward : nullptr, 0.5f, play ? &glass : nullptr);

    // The play-height band: per column, walking up, an upward-facing voxel is a floor; any other touched
    // voxel is solid in between; a free voxel is in the band while it is within the play height above the
    // last floor.
    BitVolume band;
    if (play) {
        band.reset(grid.count());
        const int reach = int(std::floor(config.play_height_m / grid.voxel_size_m));
        // Columns are independent; two slices may share a word of the band, so bits are set atomically.
#pragma omp parallel for schedule(static)
        for (int z = 0; z < grid.dims.z; ++z)
            for (int x = 0; x < grid.dims.x; ++x) {
                int last_floor = -1 << 30;
                for (int y = 0; y < grid.dims.y; ++y) {
                    const uint64_t i = grid.index(x, y, z);
                    if (upward.get(i)) {
                        last_floor = y;
                    } else if (touched.get(i)) {
                        last_floor = -1 << 30;
                    } else if (y - last_floor <= reach) {
                        band.set_atomic(i);
                    }
                }
            }
    }

    // Start from every free voxel, then intersect.
    BitVolume eyes;
    eyes.reset(grid.count());
    for (size_t w = 0; w < eyes.words.size(); ++w) eyes.words[w] = ~touched.words[w];
    const uint64_t tail = grid.count() % 64;
    if (tail) eyes.words.back() &= (uint64_t(1) << tail) - 1;

    if (!seeds.empty()) {
        vv.sources.push_back("flood");
        // With a play height the flood walks (stays in the band, or falls): eyes never get to where only
        // flight would take them, over walls or out through the sky and back in.
        const WalkRules walk{band, glass};
        const FloodResult flood = flood_free_space(ctx, grid, touched, seeds, 4, play ? &walk : nullptr);
        vv.flooded = true;
        vv.leaked = flood.leaked;
        vv.leak_path = flood.leak_path;
        vv.seeds_used = flood.seeds_used;
        vv.seeds_moved = flood.seeds_moved;
        vv.seeds_dropped = flood.seeds_dropped;
        for (size_t w = 0; w < eyes.words.size(); ++w) eyes.words[w] &= flood.reached.words[w];
        if (flood.seeds_used == 0) {
            throw bad_input("view volume: none of the view seeds is in free space inside the world");
        }
        if (flood.leaked) {
            const glm::vec3 a = flood.leak_path.front(), b = flood.leak_path.back();
            ctx.warn(fmt::format(
                "view volume: the level LEAKS: free space connects a view seed at ({:.2f}, {:.2f}, "
                "{:.2f}) to outside the world at ({:.2f}, {:.2f}, {:.2f}) ({} turns); the view "
                "volume includes the outside it reached",
                a.x, a.y, a.z, b.x, b.y, b.z, flood.leak_path.size()));
        }
    }
    if (!boxes.empty()) {
        vv.sources.push_back("boxes");
        BitVolume in_box;
        in_box.reset(grid.count());
        for (const Aabb& b : boxes) {
            const glm::ivec3 lo = grid.voxel_of(b.min), hi = grid.voxel_of(b.max);
            for (int z = lo.z; z <= hi.z; ++z)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int x = lo.x; x <= hi.x; ++x)
                        if (b.contains(grid.voxel_center({x, y, z}))) in_box.set(grid.index(x, y, z));
        }
        for (size_t w = 0; w < eyes.words.size(); ++w) eyes.words[w] &= in_box.words[w];
    }
    if (play) {
        vv.sources.push_back("play_height");
        for (size_t w = 0; w < eyes.words.size(); ++w) eyes.words[w] &= band.words[w];
    }
    BitVolume view = dilate(grid, eyes, 1);
    const double voxel_m3 = double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    const uint64_t n_eyes = eyes.count(), n_view = view.count();
    if (n_eyes == 0) {
        throw bad_input("view volume: empty (the view boxes, seeds and play height leave no free space)");
    }
    vv.eye_volume_m3 = double(n_eyes) * voxel_m3;
    vv.view_volume_m3 = double(n_view) * voxel_m3;
    // The view's bounds: the least and greatest voxel coordinates of its set bits, a word at a time over
    // all threads (min and max do not depend on the order).
    {
        glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
        const int64_t words = int64_t(view.words.size());
#pragma omp parallel
        {
            glm::ivec3 my_lo = lo, my_hi = hi;
#pragma omp for schedule(static)
            for (int64_t w = 0; w < words; ++w) {
                for (uint64_t bits = view.words[size_t(w)]; bits; bits &= bits - 1) {
                    const glm::ivec3 c = grid.coords(uint64_t(w) * 64 + uint64_t(__builtin_ctzll(bits)));
                    my_lo = glm::min(my_lo, c);
                    my_hi = glm::max(my_hi, c);
                }
            }
#pragma omp critical(view_bounds)
            {
                lo = glm::min(lo, my_lo);
                hi = glm::max(hi, my_hi);
            }
        }
        if (lo.x <= hi.x) {  // not empty (n_view > 0 here, so always)
            vv.view_bounds.extend(grid.voxel_box(lo));
            vv.view_bounds.extend(grid.voxel_box(hi));
        }
    }
    vv.eyes = to_mask(grid, std::move(eyes));
    vv.view = to_mask(grid, std::move(view));
    vv.grid = grid;
    vv.touched = std::move(touched);
    ctx.info(fmt::format(
        "view volume ({}): {:.0f} m3 of eye space, {:.0f} m3 with the walls, {:.1f}% of the world's "
        "bounds ({:.0f} m3){}",
        fmt::join(vv.sources, " & "), vv.eye_volume_m3, vv.view_volume_m3,
        100.0 * vv.view_volume_m3 / std::max(1e-9, vv.world_bounds_m3), vv.world_bounds_m3,
        vv.leaked ? "; LEAKS" : (vv.flooded ? "; sealed" : "")));
    return vv;
}

}  // namespace pvs
