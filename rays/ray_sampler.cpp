// SPDX-License-Identifier: MIT
// Ray sampling per cell and the sampled (aggressive) PVS.
#include "rays/ray_sampler.h"

#include "cells/eyes.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace pvs {

uint32_t rays_per_eye_within_budget(const SampleConfig& config, size_t cells) {
    uint32_t rays = config.rays_per_eye;
    if (config.ray_budget > 0 && cells > 0) {
        const uint64_t per_eye = config.ray_budget / (uint64_t(cells) * config.eyes_per_cell);
        rays = uint32_t(std::min<uint64_t>(rays, std::max<uint64_t>(per_eye, kMinRaysPerEye)));
    }
    return std::max(rays, std::min(config.rays_per_eye, kMinRaysPerEye));
}

void trace_region(const RayScene& scene, const CellSet& cells, const Aabb& box, uint64_t stream_id,
                  const SampleConfig& config, uint32_t rays_per_eye, CellRays& out) {
    out.rays_per_eye = rays_per_eye;
    out.eyes.clear();
    out.directions.clear();
    out.touches.clear();
    sample_eye_points_in(cells, box, stream_id, config.eyes_per_cell, config.seed, out.eyes);
    for (uint32_t e = 0; e < out.eyes.size(); ++e) {
        const uint64_t stream = (stream_id << 20) ^ e;
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
                hi[a] = std::min(cells.dims[a] - 1,
                                 int(std::floor((obj.bounds.max[a] - cells.origin[a]) / s)) + 1);
            }
            for (int z = lo.z; z <= hi.z; ++z)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int x = lo.x; x <= hi.x; ++x) {
                        const int32_t c =
                            cells
                                .grid_to_cell[size_t(x) + size_t(cells.dims.x) *
                                                              (size_t(y) + size_t(cells.dims.y) * size_t(z))];
                        if (c >= 0 && cells.cells[c].bounds.overlaps(obj.bounds)) pvs.set(uint32_t(c), o);
                    }
        } else {
            for (uint32_t c = 0; c < cells.size(); ++c)
                if (cells.cells[c].bounds.overlaps(obj.bounds)) pvs.set(c, o);
        }
    }
}

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kTwoPi = 2.0f * kPi;

// Direction bins: rows by cos(polar) = y (equal area), columns by azimuth atan2(z, x); each bin lists its
// rays, so a cone query only looks at the rays near its axis.
struct DirectionBins {
    int rows = 1, cols = 2;
    std::vector<uint32_t> first;  // rows * cols + 1 offsets into ray_of
    std::vector<uint32_t> ray_of;

    void build(const glm::vec3* dirs, uint32_t count) {
        rows = std::max(1, int(std::sqrt(double(count) / 4.0)));
        cols = 2 * rows;
        const size_t bins = size_t(rows) * size_t(cols);
        first.assign(bins + 1, 0);
        std::vector<uint32_t> bin(count);
        for (uint32_t r = 0; r < count; ++r) {
            bin[r] = uint32_t(bin_of(dirs[r]));
            ++first[bin[r] + 1];
        }
        for (size_t b = 0; b < bins; ++b) first[b + 1] += first[b];
        ray_of.resize(count);
        std::vector<uint32_t> fill(first.begin(), first.end() - 1);
        for (uint32_t r = 0; r < count; ++r) ray_of[fill[bin[r]]++] = r;
    }
    int row_of(float y) const { return std::clamp(int((1.0f - y) * 0.5f * float(rows)), 0, rows - 1); }
    int col_of(float phi) const {
        float u = phi / kTwoPi;
        u -= std::floor(u);
        return std::clamp(int(u * float(cols)), 0, cols - 1);
    }
    size_t bin_of(glm::vec3 d) const {
        return size_t(row_of(d.y)) * size_t(cols) + size_t(col_of(std::atan2(d.z, d.x)));
    }
};

// Does the ray (eye, dir) come within angle atan(tan_band) of the box before `reach`? Tested as: the ray
// segment [0, reach] meets the box grown by reach * tan_band (a cylinder around the ray holds the cone).
bool ray_passes_near(glm::vec3 eye, glm::vec3 dir, float reach, const Aabb& box, float tan_band) {
    const float grow = std::isfinite(reach) ? reach * tan_band : 0.0f;
    const float limit = std::isfinite(reach) ? reach : std::numeric_limits<float>::max();
    float t0, t1;
    return ray_box_interval(eye, dir, Aabb::of(box.min - grow, box.max + grow), limit, t0, t1);
}

// True when a ray within `half` of `axis` (the candidates) passes near the box before it stops.
bool cone_reaches(const DirectionBins& bins, const glm::vec3* dirs, const float* reach, glm::vec3 axis,
                  float half, float near, glm::vec3 eye, const Aabb& box, float tan_band) {
    const float polar = std::acos(std::clamp(axis.y, -1.0f, 1.0f));
    const float lo = std::max(0.0f, polar - half), hi = std::min(kPi, polar + half);
    const int r0 = bins.row_of(std::cos(lo)), r1 = bins.row_of(std::cos(hi));
    int c0 = 0, c1 = bins.cols - 1;
    if (polar - half > 0.0f && polar + half < kPi) {
        const float dphi = std::asin(std::min(1.0f, std::sin(half) / std::sin(polar)));
        const float phi = std::atan2(axis.z, axis.x);
        if (2.0f * dphi < kTwoPi) {
            c0 = bins.col_of(phi - dphi);
            c1 = bins.col_of(phi + dphi);
        }
    }
    const float cos_half = std::cos(half);
    for (int r = r0; r <= r1; ++r) {
        for (int c = c0;; c = (c + 1) % bins.cols) {
            const size_t b = size_t(r) * size_t(bins.cols) + size_t(c);
            for (uint32_t k = bins.first[b]; k < bins.first[b + 1]; ++k) {
                const uint32_t ray = bins.ray_of[k];
                if (reach[ray] >= near && glm::dot(dirs[ray], axis) >= cos_half &&
                    ray_passes_near(eye, dirs[ray], reach[ray], box, tan_band)) {
                    return true;
                }
            }
            if (c == c1) break;
        }
    }
    return false;
}

}  // namespace

uint32_t add_guard_band(const World& world, const CellRays& rays, float guard_band_rad, uint64_t* row) {
    uint32_t added = 0;
    const float tan_band = std::tan(guard_band_rad);
    DirectionBins bins;
    std::vector<float> reach(rays.rays_per_eye);
    for (uint32_t e = 0; e < rays.eyes.size(); ++e) {
        const glm::vec3* dirs = rays.directions.data() + size_t(e) * rays.rays_per_eye;
        bins.build(dirs, rays.rays_per_eye);
        std::fill(reach.begin(), reach.end(), std::numeric_limits<float>::infinity());
        for (const RayTouch& t : rays.touches) {
            if (t.stops && t.ray / rays.rays_per_eye == e) reach[t.ray % rays.rays_per_eye] = t.t;
        }
        const glm::vec3 eye = rays.eyes[e];
        for (uint32_t o = 0; o < world.objects.size(); ++o) {
            if ((row[o >> 6] >> (o & 63)) & 1u) continue;
            const Aabb& box = world.objects[o].bounds;
            const glm::vec3 v = box.center() - eye;
            const float dist = glm::length(v);
            const float radius = 0.5f * glm::length(box.size());
            bool listed = dist <= radius;
            if (!listed) {
                const float half = std::min(kPi, std::asin(std::min(1.0f, radius / dist)) + guard_band_rad);
                listed =
                    cone_reaches(bins, dirs, reach.data(), v / dist, half, dist - radius, eye, box, tan_band);
            }
            if (listed) {
                row[o >> 6] |= uint64_t(1) << (o & 63);
                ++added;
            }
        }
    }
    return added;
}

void sample_box_rows(const SampledPvsConfig& config, const World& world, const RayScene& scene,
                     const CellSet& masks, const std::vector<Aabb>& boxes,
                     const std::vector<uint64_t>& streams, uint32_t rays_per_eye, PvsSet& rows,
                     uint64_t& guard_band_added, Context* progress) {
    const float guard_band_rad = float(config.guard_band_deg) * kPi / 180.0f;
    uint64_t added_total = 0;
#pragma omp parallel reduction(+ : added_total)
    {
        CellRays rays;
#pragma omp for schedule(dynamic, 4)
        for (int64_t b = 0; b < int64_t(boxes.size()); ++b) {
            trace_region(scene, masks, boxes[size_t(b)], streams[size_t(b)], config.rays, rays_per_eye, rays);
            for (const RayTouch& t : rays.touches) rows.set(uint32_t(b), t.object);
            if (guard_band_rad > 0.0f)
                added_total += add_guard_band(world, rays, guard_band_rad, rows.row(uint32_t(b)));
            if (progress) progress->progress_advance();
        }
    }
    guard_band_added += added_total;
}

SampledPvs bake_sampled_pvs(Context& ctx, const SampledPvsConfig& config, const World& world,
                            const RayScene& scene, const CellSet& cells) {
    ScopedTimer timer(ctx, "sampled_pvs");
    const auto start = std::chrono::steady_clock::now();
    SampledPvs result;
    result.pvs = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    result.rays_per_eye = rays_per_eye_within_budget(config.rays, cells.size());
    const uint64_t rays_per_cell = uint64_t(config.rays.eyes_per_cell) * result.rays_per_eye;
    ctx.info(fmt::format("sampled PVS (aggressive): {} cells x {} eyes x {} rays = {:.1f} M rays",
                         cells.size(), config.rays.eyes_per_cell, result.rays_per_eye,
                         double(rays_per_cell) * double(cells.size()) * 1e-6));
    if (config.guard_band_deg > 0.0) {
        ctx.info(fmt::format("sampled PVS: guard band {} degrees (lists objects rays passed near)",
                             config.guard_band_deg));
    }
    std::vector<Aabb> boxes;
    std::vector<uint64_t> streams;
    for (uint32_t c = 0; c < cells.size(); ++c) {
        boxes.push_back(cells.cells[c].bounds);
        streams.push_back(c);
    }
    ctx.progress_begin("sampled PVS", cells.size(), "cells");
    sample_box_rows(config, world, scene, cells, boxes, streams, result.rays_per_eye, result.pvs,
                    result.guard_band_added, &ctx);
    ctx.progress_end();
    add_always_listed(world, cells, result.pvs);
    result.rays = rays_per_cell * cells.size();
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format("sampled PVS: {:.1f} M rays in {:.1f} s ({:.2f} M rays/s)",
                         double(result.rays) * 1e-6, result.seconds,
                         double(result.rays) * 1e-6 / std::max(result.seconds, 1e-9)));
    return result;
}

}  // namespace pvs
