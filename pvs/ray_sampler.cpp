// Ray sampling per cell and the sampled (aggressive) PVS.
#include "pvs/ray_sampler.h"

#include "cells/eyes.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>

namespace pvs {

uint32_t rays_per_eye_within_budget(const SampleConfig& config, size_t cells) {
    uint32_t rays = config.rays_per_eye;
    if (config.ray_budget > 0 && cells > 0) {
        const uint64_t per_eye = config.ray_budget / (uint64_t(cells) * config.eyes_per_cell);
        rays = uint32_t(std::min<uint64_t>(rays, std::max<uint64_t>(per_eye, kMinRaysPerEye)));
    }
    return std::max(rays, std::min(config.rays_per_eye, kMinRaysPerEye));
}

void trace_cell(const RayScene& scene, const CellSet& cells, uint32_t cell, const SampleConfig& config,
                uint32_t rays_per_eye, CellRays& out) {
    out.rays_per_eye = rays_per_eye;
    out.eyes.clear();
    out.directions.clear();
    out.touches.clear();
    sample_eye_points(cells, cell, config.eyes_per_cell, config.seed, out.eyes);
    for (uint32_t e = 0; e < out.eyes.size(); ++e) {
        const uint64_t stream = (uint64_t(cell) << 20) ^ e;
        sample_sphere_directions(rays_per_eye, config.seed, stream, out.directions);
        const size_t first = out.touches.size();
        scene.trace(out.eyes[e], out.directions.data() + size_t(e) * rays_per_eye, rays_per_eye, out.touches);
        for (size_t i = first; i < out.touches.size(); ++i) out.touches[i].ray += e * rays_per_eye;
    }
}

void add_always_listed(const World& world, const CellSet& cells, PvsSet& pvs) {
    for (uint32_t o = 0; o < world.objects.size(); ++o) {
        const WorldObject& obj = world.objects[o];
        if (obj.flags & kObjectAlwaysVisible) {
            for (uint32_t c = 0; c < cells.size(); ++c) pvs.set(c, o);
            continue;
        }
        // Objects are few next to cells on a grid: visit the grid cells their bounds cover.
        if (cells.kind == CellSet::Kind::kGrid && cells.cell_size_m > 0.0f) {
            glm::ivec3 lo, hi;
            for (int a = 0; a < 3; ++a) {
                const float s = cells.cell_size_m;
                lo[a] = std::max(0, int(std::floor((obj.bounds.min[a] - cells.origin[a]) / s)) - 1);
                hi[a] = std::min(cells.dims[a] - 1, int(std::floor((obj.bounds.max[a] - cells.origin[a]) / s)) + 1);
            }
            for (int z = lo.z; z <= hi.z; ++z)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int x = lo.x; x <= hi.x; ++x) {
                        const int32_t c = cells.grid_to_cell[size_t(x) + size_t(cells.dims.x) *
                                                                        (size_t(y) + size_t(cells.dims.y) * size_t(z))];
                        if (c >= 0 && cells.cells[c].bounds.overlaps(obj.bounds)) pvs.set(uint32_t(c), o);
                    }
        } else {
            for (uint32_t c = 0; c < cells.size(); ++c)
                if (cells.cells[c].bounds.overlaps(obj.bounds)) pvs.set(c, o);
        }
    }
}

SampledPvs bake_sampled_pvs(Context& ctx, const SampledPvsConfig& config, const World& world,
                            const RayScene& scene, const CellSet& cells) {
    ScopedTimer timer(ctx, "sampled_pvs");
    const auto start = std::chrono::steady_clock::now();
    SampledPvs result;
    result.pvs = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    result.rays_per_eye = rays_per_eye_within_budget(config.rays, cells.size());
    const uint64_t rays_per_cell = uint64_t(config.rays.eyes_per_cell) * result.rays_per_eye;
    ctx.info(fmt::format("sampled PVS (aggressive): {} cells x {} eyes x {} rays = {:.1f} M rays", cells.size(),
                         config.rays.eyes_per_cell, result.rays_per_eye,
                         double(rays_per_cell) * double(cells.size()) * 1e-6));
    ctx.progress_begin("sampled PVS", cells.size(), "cells");
#pragma omp parallel
    {
        CellRays rays;
#pragma omp for schedule(dynamic, 4)
        for (int64_t c = 0; c < int64_t(cells.size()); ++c) {
            trace_cell(scene, cells, uint32_t(c), config.rays, result.rays_per_eye, rays);
            for (const RayTouch& t : rays.touches) result.pvs.set(uint32_t(c), t.object);
            ctx.progress_advance();
        }
    }
    ctx.progress_end();
    add_always_listed(world, cells, result.pvs);
    result.rays = rays_per_cell * cells.size();
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format("sampled PVS: {:.1f} M rays in {:.1f} s ({:.2f} M rays/s)", double(result.rays) * 1e-6,
                         result.seconds, double(result.rays) * 1e-6 / std::max(result.seconds, 1e-9)));
    return result;
}

}  // namespace pvs
