// Verification of a PVS against Embree rays: misses, sampled visible sets, overestimation.
#include "pvs/verify.h"

#include "pvs/ray_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

namespace pvs {

namespace {

struct Stats {
    double mean = 0, median = 0, max = 0;
};

Stats stats_of(std::vector<double> v) {
    Stats s;
    if (v.empty()) return s;
    double sum = 0;
    for (double x : v) {
        sum += x;
        s.max = std::max(s.max, x);
    }
    s.mean = sum / double(v.size());
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    return s;
}

uint64_t row_triangles(const World& world, const PvsSet& set, uint32_t cell) {
    uint64_t tris = 0;
    const uint64_t* row = set.row(cell);
    for (uint32_t w = 0; w < set.words_per_row; ++w) {
        uint64_t bits = row[w];
        while (bits) {
            const uint32_t o = w * 64 + uint32_t(__builtin_ctzll(bits));
            bits &= bits - 1;
            tris += world.objects[o].triangle_count;
        }
    }
    return tris;
}

}  // namespace

NamedValues VerifyResult::figures() const {
    return {
        {"rays", double(rays)},
        {"rays_per_eye", double(rays_per_eye)},
        {"seconds", seconds},
        {"rays_per_second", seconds > 0 ? double(rays) / seconds : 0.0},
        {"missed_pairs", double(missed_pairs)},
        {"missed_rays", double(missed_rays)},
        {"cells_with_misses", double(cells_with_misses)},
        {"overestimation_mean", overestimation_mean},
        {"overestimation_median", overestimation_median},
        {"overestimation_max", overestimation_max},
        {"overestimation_triangles_mean", overestimation_tri_mean},
        {"overestimation_triangles_median", overestimation_tri_median},
        {"overestimation_triangles_max", overestimation_tri_max},
        {"pvs_triangle_share_mean", pvs_triangle_share_mean},
        {"sampled_triangle_share_mean", sampled_triangle_share_mean},
        {"cells_with_empty_sample", double(cells_with_empty_sample)},
    };
}

VerifyResult verify_pvs(Context& ctx, const VerifyConfig& config, const World& world, const RayScene& scene,
                        const CellSet& cells, const PvsSet& pvs) {
    ScopedTimer timer(ctx, "verify");
    const auto start = std::chrono::steady_clock::now();
    VerifyResult result;
    const uint32_t n_cells = uint32_t(cells.size());
    result.sampled = PvsSet::make(n_cells, uint32_t(world.objects.size()));
    result.rays_per_eye = rays_per_eye_within_budget(config.rays, n_cells);
    const uint64_t rays_per_cell = uint64_t(config.rays.eyes_per_cell) * result.rays_per_eye;
    ctx.info(fmt::format("verify: {} cells x {} eyes x {} rays = {:.1f} M rays (seed {})", n_cells,
                         config.rays.eyes_per_cell, result.rays_per_eye,
                         double(rays_per_cell) * double(n_cells) * 1e-6, config.rays.seed));

    std::vector<std::vector<Miss>> cell_misses(n_cells);
    std::vector<uint64_t> cell_missed_rays(n_cells, 0);
    uint64_t rays_traced = 0;
    ctx.progress_begin("verify", n_cells, "cells");
#pragma omp parallel reduction(+ : rays_traced)
    {
        CellRays rays;
        std::vector<uint8_t> reported;
#pragma omp for schedule(dynamic, 4)
        for (int64_t ci = 0; ci < int64_t(n_cells); ++ci) {
            const uint32_t c = uint32_t(ci);
            trace_cell(scene, cells, c, config.rays, result.rays_per_eye, rays);
            rays_traced += uint64_t(rays.eyes.size()) * rays.rays_per_eye;
            // Touches come in ray order, so the first touch of a missed object is its first ray.
            reported.assign(world.objects.size(), 0);
            for (const RayTouch& t : rays.touches) {
                result.sampled.set(c, t.object);
                if (pvs.test(c, t.object)) continue;
                ++cell_missed_rays[c];
                if (reported[t.object]) continue;
                reported[t.object] = 1;
                const uint32_t eye = t.ray / rays.rays_per_eye;
                cell_misses[c].push_back(Miss{c, t.object, rays.eyes[eye], rays.directions[t.ray], t.t});
            }
            std::sort(cell_misses[c].begin(), cell_misses[c].end(),
                      [](const Miss& a, const Miss& b) { return a.object < b.object; });
            ctx.progress_advance();
        }
    }
    ctx.progress_end();

    result.rays = rays_traced;
    result.cell_sampled_visible.resize(n_cells);
    std::vector<double> over, over_tri, pvs_share, sampled_share;
    const double world_tris = std::max<double>(1.0, double(world.triangles.size()));
    for (uint32_t c = 0; c < n_cells; ++c) {
        result.missed_rays += cell_missed_rays[c];
        result.missed_pairs += cell_misses[c].size();
        result.cells_with_misses += !cell_misses[c].empty();
        for (const Miss& m : cell_misses[c]) {
            if (result.misses.size() >= config.max_misses_reported) break;
            result.misses.push_back(m);
        }
        const uint32_t seen = result.sampled.count(c);
        result.cell_sampled_visible[c] = seen;
        const uint64_t pvs_tris = row_triangles(world, pvs, c);
        pvs_share.push_back(double(pvs_tris) / world_tris);
        if (seen == 0) {
            ++result.cells_with_empty_sample;
            sampled_share.push_back(0.0);
            continue;
        }
        const uint64_t seen_tris = row_triangles(world, result.sampled, c);
        sampled_share.push_back(double(seen_tris) / world_tris);
        over.push_back(double(pvs.count(c)) / double(seen));
        over_tri.push_back(seen_tris ? double(pvs_tris) / double(seen_tris) : 1.0);
    }
    const Stats o = stats_of(over), ot = stats_of(over_tri);
    result.overestimation_mean = o.mean;
    result.overestimation_median = o.median;
    result.overestimation_max = o.max;
    result.overestimation_tri_mean = ot.mean;
    result.overestimation_tri_median = ot.median;
    result.overestimation_tri_max = ot.max;
    result.pvs_triangle_share_mean = stats_of(pvs_share).mean;
    result.sampled_triangle_share_mean = stats_of(sampled_share).mean;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

void log_verify_summary(Context& ctx, const VerifyResult& r, const World& world) {
    ctx.info(fmt::format("verify: {:.1f} M rays in {:.1f} s ({:.2f} M rays/s)", double(r.rays) * 1e-6,
                         r.seconds, r.seconds > 0 ? double(r.rays) * 1e-6 / r.seconds : 0.0));
    ctx.info(
        fmt::format("verify: overestimation |PVS|/|sampled| mean {:.2f}, median {:.2f}, max {:.2f}; "
                    "by triangles mean {:.2f}, median {:.2f}, max {:.2f}",
                    r.overestimation_mean, r.overestimation_median, r.overestimation_max,
                    r.overestimation_tri_mean, r.overestimation_tri_median, r.overestimation_tri_max));
    ctx.info(
        fmt::format("verify: the PVS lets through {:.1f}% of the triangles on average; the rays saw {:.1f}%",
                    100.0 * r.pvs_triangle_share_mean, 100.0 * r.sampled_triangle_share_mean));
    if (r.missed_pairs == 0) {
        ctx.info("verify: no misses");
        return;
    }
    ctx.warn(
        fmt::format("verify: {} MISSES: {} (cell, object) pairs in {} cells, {} rays saw an unlisted object",
                    r.missed_pairs, r.missed_pairs, r.cells_with_misses, r.missed_rays));
    const size_t show = std::min<size_t>(r.misses.size(), 10);
    for (size_t i = 0; i < show; ++i) {
        const Miss& m = r.misses[i];
        ctx.warn(
            fmt::format("  miss: cell {} object {} '{}' from eye ({:.3f}, {:.3f}, {:.3f}) direction "
                        "({:.4f}, {:.4f}, {:.4f}) at {:.3f} m",
                        m.cell, m.object, world.objects[m.object].name, m.eye.x, m.eye.y, m.eye.z,
                        m.direction.x, m.direction.y, m.direction.z, m.distance_m));
    }
    if (r.missed_pairs > show)
        ctx.warn(fmt::format("  ... and {} more (see the report)", r.missed_pairs - show));
}

}  // namespace pvs
