// Verification of a PVS against Embree rays: misses, sampled visible sets, overestimation.
// Aimed rays after Wonka et al., "Guided visibility sampling" (SIGGRAPH 2006): rays from random eye points
// to random points on the objects uniform sampling did not touch.
#include "pvs/verify.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "pvs/ray_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

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

// Random streams of the aimed rays, apart from the uniform ones (whose eye stream is the cell index and
// whose direction stream is (cell << 20) ^ eye).
constexpr uint64_t kAimedEyeStream = uint64_t(0x41494d) << 40;     // | cell: eye points
constexpr uint64_t kAimedSubsetStream = uint64_t(0x535542) << 40;  // | cell: which candidates, when few rays
constexpr uint64_t kAimedPointStream = uint64_t(0x505453) << 40;   // ^ (cell << 20) ^ eye: target points
constexpr float kMinAimDistanceM = 1e-4f;                          // closer targets give no direction

// Per triangle: the running sum of triangle areas within its object (m2), to pick a triangle of an object
// with probability proportional to its area.
std::vector<double> cumulative_areas(const World& world) {
    std::vector<double> out(world.triangles.size(), 0.0);
    for (const WorldObject& obj : world.objects) {
        double sum = 0.0;
        for (uint32_t i = obj.first_triangle; i < obj.first_triangle + obj.triangle_count; ++i) {
            const Triangle& t = world.triangles[i];
            const glm::vec3 a = world.positions[t.v[0]], b = world.positions[t.v[1]],
                            c = world.positions[t.v[2]];
            sum += 0.5 * double(glm::length(glm::cross(b - a, c - a)));
            out[i] = sum;
        }
    }
    return out;
}

// A uniform random point on the object's surface: a triangle by area, then a uniform point in it.
glm::vec3 random_point_on(const World& world, const std::vector<double>& cum_area, uint32_t object,
                          Rng& rng) {
    const WorldObject& obj = world.objects[object];
    const auto first = cum_area.begin() + obj.first_triangle;
    const auto last = first + obj.triangle_count;
    const double pick = double(rng.uniform()) * *(last - 1);
    const auto it = std::min(std::upper_bound(first, last, pick), last - 1);
    const Triangle& t = world.triangles[obj.first_triangle + uint32_t(it - first)];
    const float r = std::sqrt(rng.uniform()), v = rng.uniform();
    return (1.0f - r) * world.positions[t.v[0]] + r * (1.0f - v) * world.positions[t.v[1]] +
           r * v * world.positions[t.v[2]];
}

// The aimed rays of one cell: eye e's rays are [first[e], first[e + 1]) in `directions`.
struct AimedRays {
    std::vector<uint32_t> candidates;  // objects to aim at, increasing
    std::vector<glm::vec3> eyes;
    std::vector<uint32_t> first;
    std::vector<glm::vec3> directions;
    std::vector<RayTouch> touches;  // ray = index into directions
};

// Draws and traces the aimed rays of cell c: `full_eyes` eye points each aim one ray at a random point on
// every object of `targets`, then, when `partial` is not empty, one more eye point aims at those objects.
void trace_aimed(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                 const CellSet& cells, uint32_t c, const std::vector<uint32_t>& targets, uint32_t full_eyes,
                 const std::vector<uint32_t>& partial, uint64_t seed, AimedRays& out) {
    out.eyes.clear();
    out.first.assign(1, 0);
    out.directions.clear();
    out.touches.clear();
    const uint32_t eye_count = full_eyes + (partial.empty() ? 0 : 1);
    sample_eye_points_in(cells, cells.cells[c].bounds, kAimedEyeStream | c, eye_count, seed, out.eyes);
    for (uint32_t e = 0; e < out.eyes.size(); ++e) {
        Rng rng(seed, kAimedPointStream ^ (uint64_t(c) << 20) ^ e);
        const glm::vec3 eye = out.eyes[e];
        const uint32_t begin = uint32_t(out.directions.size());
        for (uint32_t o : e < full_eyes ? targets : partial) {
            const glm::vec3 d = random_point_on(world, cum_area, o, rng) - eye;
            const float len = glm::length(d);
            if (len < kMinAimDistanceM) continue;
            out.directions.push_back(d / len);
        }
        const uint32_t count = uint32_t(out.directions.size()) - begin;
        out.first.push_back(begin + count);
        const size_t t0 = out.touches.size();
        scene.trace(eye, out.directions.data() + begin, count, out.touches);
        for (size_t i = t0; i < out.touches.size(); ++i) out.touches[i].ray += begin;
    }
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
        {"aimed_rays", double(aimed_rays)},
        {"aimed_rays_per_cell", double(aimed_rays_per_cell)},
        {"aimed_candidates", double(aimed_candidates)},
        {"aimed_targets", double(aimed_targets)},
        {"aimed_new_pairs", double(aimed_new_pairs)},
        {"aimed_missed_pairs", double(aimed_missed_pairs)},
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
    const uint32_t n_objects = uint32_t(world.objects.size());
    result.sampled = PvsSet::make(n_cells, n_objects);
    // The uniform rays fit in what the aimed ones leave of the budget (all of it when aimed_share = 0, so
    // the uniform rays are those of before).
    const bool aim = config.aimed_share > 0.0;
    const uint64_t aimed_budget =
        aim ? std::min(config.rays.ray_budget, uint64_t(double(config.rays.ray_budget) * config.aimed_share))
            : 0;
    SampleConfig uniform = config.rays;
    uniform.ray_budget -= aimed_budget;
    result.rays_per_eye = rays_per_eye_within_budget(uniform, n_cells);
    result.aimed_rays_per_cell = n_cells > 0 ? aimed_budget / n_cells : 0;
    const bool aim_capped = config.rays.ray_budget > 0;
    const uint64_t rays_per_cell = uint64_t(config.rays.eyes_per_cell) * result.rays_per_eye;
    ctx.info(fmt::format("verify: {} cells x {} eyes x {} rays = {:.1f} M uniform rays (seed {})", n_cells,
                         config.rays.eyes_per_cell, result.rays_per_eye,
                         double(rays_per_cell) * double(n_cells) * 1e-6, config.rays.seed));
    if (aim && aim_capped) {
        ctx.info(
            fmt::format("verify: aimed rays: {} per cell ({:.1f} M, {:.0f}% of the budget) at the objects "
                        "the uniform rays did not touch",
                        result.aimed_rays_per_cell, double(result.aimed_rays_per_cell * n_cells) * 1e-6,
                        100.0 * config.aimed_share));
    } else if (aim) {
        ctx.info(
            fmt::format("verify: aimed rays: from {} eye points per cell at every object the uniform rays "
                        "did not touch (no ray budget)",
                        config.rays.eyes_per_cell));
    }
    const std::vector<double> cum_area = aim ? cumulative_areas(world) : std::vector<double>();

    std::vector<std::vector<Miss>> cell_misses(n_cells);
    std::vector<uint64_t> cell_missed_rays(n_cells, 0);
    uint64_t rays_traced = 0, aimed_rays = 0, aimed_candidates = 0, aimed_targets = 0, aimed_new = 0,
             aimed_missed = 0;
    ctx.progress_begin("verify", n_cells, "cells");
#pragma omp parallel reduction(+ : rays_traced, aimed_rays, aimed_candidates, aimed_targets, aimed_new, \
                                   aimed_missed)
    {
        CellRays rays;
        AimedRays aimed;
        std::vector<uint32_t> partial;
        std::vector<uint8_t> reported;
#pragma omp for schedule(dynamic, 4)
        for (int64_t ci = 0; ci < int64_t(n_cells); ++ci) {
            const uint32_t c = uint32_t(ci);
            trace_cell(scene, cells, c, config.rays, result.rays_per_eye, rays);
            rays_traced += uint64_t(rays.eyes.size()) * rays.rays_per_eye;
            // Touches come in ray order, so the first touch of a missed object is its first ray.
            reported.assign(n_objects, 0);
            auto record = [&](uint32_t object, const glm::vec3& eye, const glm::vec3& direction, float t) {
                ++cell_missed_rays[c];
                if (reported[object]) return false;
                reported[object] = 1;
                cell_misses[c].push_back(Miss{c, object, eye, direction, t});
                return true;
            };
            for (const RayTouch& t : rays.touches) {
                result.sampled.set(c, t.object);
                if (pvs.test(c, t.object)) continue;
                record(t.object, rays.eyes[t.ray / rays.rays_per_eye], rays.directions[t.ray], t.t);
            }
            if (aim) {
                // Candidates: what the uniform rays did not touch, but for listed objects every PVS lists.
                aimed.candidates.clear();
                const Aabb& cell_box = cells.cells[c].bounds;
                for (uint32_t o = 0; o < n_objects; ++o) {
                    const WorldObject& obj = world.objects[o];
                    if (result.sampled.test(c, o) || obj.triangle_count == 0) continue;
                    if (cum_area[obj.first_triangle + obj.triangle_count - 1] <= 0.0) continue;
                    if (pvs.test(c, o) &&
                        ((obj.flags & kObjectAlwaysVisible) || cell_box.overlaps(obj.bounds)))
                        continue;
                    aimed.candidates.push_back(o);
                }
                // A eye points aim at every candidate, A = aimed rays per cell / candidates (eyes_per_cell
                // without a budget); the rest of the cell's rays, fewer than the candidates, go from one
                // more eye point to a seeded random subset of them.
                const uint64_t k = aimed.candidates.size();
                aimed_candidates += k;
                uint32_t full_eyes = k > 0 ? config.rays.eyes_per_cell : 0;
                partial.clear();
                if (aim_capped && k > 0) {
                    const uint64_t per_cell = result.aimed_rays_per_cell;
                    full_eyes = uint32_t(std::min<uint64_t>(per_cell / k, UINT32_MAX - 1));
                    const uint64_t rest = per_cell % k;
                    if (rest > 0 && full_eyes < UINT32_MAX - 1) {
                        partial = aimed.candidates;
                        Rng rng(config.rays.seed, kAimedSubsetStream | c);
                        for (uint64_t i = 0; i < rest; ++i)
                            std::swap(partial[i], partial[i + rng.below(uint32_t(k - i))]);
                        partial.resize(rest);
                        std::sort(partial.begin(), partial.end());
                    }
                }
                if (full_eyes > 0 || !partial.empty()) {
                    trace_aimed(scene, world, cum_area, cells, c, aimed.candidates, full_eyes, partial,
                                config.rays.seed, aimed);
                    if (!aimed.eyes.empty()) aimed_targets += full_eyes > 0 ? k : partial.size();
                    aimed_rays += aimed.directions.size();
                    rays_traced += aimed.directions.size();
                    for (const RayTouch& t : aimed.touches) {
                        if (!result.sampled.test(c, t.object)) {
                            result.sampled.set(c, t.object);
                            ++aimed_new;
                        }
                        if (pvs.test(c, t.object)) continue;
                        const uint32_t eye =
                            uint32_t(std::upper_bound(aimed.first.begin(), aimed.first.end(), t.ray) -
                                     aimed.first.begin() - 1);
                        if (record(t.object, aimed.eyes[eye], aimed.directions[t.ray], t.t)) ++aimed_missed;
                    }
                }
            }
            std::sort(cell_misses[c].begin(), cell_misses[c].end(),
                      [](const Miss& a, const Miss& b) { return a.object < b.object; });
            ctx.progress_advance();
        }
    }
    ctx.progress_end();

    result.aimed_rays = aimed_rays;
    result.aimed_candidates = aimed_candidates;
    result.aimed_targets = aimed_targets;
    result.aimed_new_pairs = aimed_new;
    result.aimed_missed_pairs = aimed_missed;
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
    if (r.aimed_rays > 0 || r.aimed_candidates > 0) {
        ctx.info(fmt::format(
            "verify: aimed rays {:.1f} M at {} of {} untouched (cell, object) pairs: {} pairs seen only by "
            "them, {} missed pairs found only by them",
            double(r.aimed_rays) * 1e-6, r.aimed_targets, r.aimed_candidates, r.aimed_new_pairs,
            r.aimed_missed_pairs));
    }
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
