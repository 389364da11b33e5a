// Verification of a PVS against Embree rays: misses, sampled visible sets, overestimation.
// Aimed rays after Wonka et al., "Guided visibility sampling" (SIGGRAPH 2006): rays from random eye points
// to random points on the objects uniform sampling did not touch.
#include "pvs/verify.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "pvs/ray_sampler.h"
#include "pvs/surface_points.h"

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
constexpr uint64_t kAimedEyeStream = uint64_t(0x41494d) << 40;     // | cell (no budget), ^ (cell, batch)
constexpr uint64_t kAimedSubsetStream = uint64_t(0x535542) << 40;  // ^ (cell, round): which candidates
constexpr uint64_t kAimedPointStream = uint64_t(0x505453) << 40;   // ^ (cell << 20) ^ eye: target points
constexpr float kMinAimDistanceM = 1e-4f;                          // closer targets give no direction
// The eye points of the aimed rounds of a cell come in batches of 16, stratified over the cell's eye region
// and taken in bit-reversed order, so the first 2, 4, 8 rounds of a batch already spread over the region.
constexpr uint32_t kRoundEyesPerBatch = 16;
constexpr uint8_t kRoundEyeOrder[kRoundEyesPerBatch] = {0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15};

// A stream of (cell, index), one per pair, for a purpose tagged by `tag`.
uint64_t cell_stream(uint64_t tag, uint32_t cell, uint32_t index) {
    return tag ^ mix64((uint64_t(cell) << 32) | index);
}

// The aimed rays of one cell. Without a budget eye e's rays are [first[e], first[e + 1]) in `directions`;
// with one, a round has one eye and its rays are all of `directions`.
struct AimedRays {
    std::vector<uint32_t> listed;    // candidates the PVS lists, increasing
    std::vector<uint32_t> left_out;  // candidates the PVS leaves out, increasing
    std::vector<uint32_t> targets;   // of a round (or every candidate without a budget), increasing
    std::vector<uint8_t> aimed_at;   // per object: aimed at by a round of this cell
    std::vector<glm::vec3> eyes;
    std::vector<uint32_t> first;
    std::vector<glm::vec3> directions;
    std::vector<RayTouch> touches;      // ray = index into directions
    std::vector<glm::vec3> batch_eyes;  // the eye points of batch `batch` of the rounds
    uint32_t batch = UINT32_MAX;
};

// Appends one ray per object of `targets` from `eye` at a random point on the object (none for an object
// closer than kMinAimDistanceM).
void aim_from(const World& world, const std::vector<double>& cum_area, const glm::vec3& eye,
              const std::vector<uint32_t>& targets, Rng& rng, std::vector<glm::vec3>& directions) {
    for (uint32_t o : targets) {
        const glm::vec3 d = random_point_on(world, cum_area, o, rng) - eye;
        const float len = glm::length(d);
        if (len < kMinAimDistanceM) continue;
        directions.push_back(d / len);
    }
}

// Without a budget: `eye_count` eye points each aim one ray at a random point on every object of `targets`.
void trace_aimed(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                 const CellSet& cells, uint32_t c, uint32_t eye_count, uint64_t seed, AimedRays& out) {
    out.eyes.clear();
    out.first.assign(1, 0);
    out.directions.clear();
    out.touches.clear();
    sample_eye_points_in(cells, cells.cells[c].bounds, kAimedEyeStream | c, eye_count, seed, out.eyes);
    for (uint32_t e = 0; e < out.eyes.size(); ++e) {
        Rng rng(seed, kAimedPointStream ^ (uint64_t(c) << 20) ^ e);
        const uint32_t begin = uint32_t(out.directions.size());
        aim_from(world, cum_area, out.eyes[e], out.targets, rng, out.directions);
        const uint32_t count = uint32_t(out.directions.size()) - begin;
        out.first.push_back(begin + count);
        const size_t t0 = out.touches.size();
        scene.trace(out.eyes[e], out.directions.data() + begin, count, out.touches);
        for (size_t i = t0; i < out.touches.size(); ++i) out.touches[i].ray += begin;
    }
}

// Round `round` of cell c: one eye point (from its batch) aims one ray at every object of `out.targets`.
// False when the cell has no eye point (no eye voxel in it): nothing traced.
bool trace_round(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                 const CellSet& cells, uint32_t c, uint32_t round, uint64_t seed, AimedRays& out) {
    const uint32_t batch = round / kRoundEyesPerBatch, slot = kRoundEyeOrder[round % kRoundEyesPerBatch];
    if (batch != out.batch) {
        out.batch = batch;
        out.batch_eyes.clear();
        sample_eye_points_in(cells, cells.cells[c].bounds, cell_stream(kAimedEyeStream, c, batch),
                             kRoundEyesPerBatch, seed, out.batch_eyes);
    }
    out.eyes.clear();
    out.directions.clear();
    out.touches.clear();
    if (slot >= out.batch_eyes.size()) return false;
    out.eyes.push_back(out.batch_eyes[slot]);
    Rng rng(seed, cell_stream(kAimedPointStream, c, round));
    aim_from(world, cum_area, out.eyes[0], out.targets, rng, out.directions);
    scene.trace(out.eyes[0], out.directions.data(), uint32_t(out.directions.size()), out.touches);
    return true;
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
        {"aimed_listed_rays", double(aimed_listed_rays)},
        {"aimed_rays_per_cell", double(aimed_rays_per_cell)},
        {"aimed_candidates", double(aimed_candidates)},
        {"aimed_listed_candidates", double(aimed_listed_candidates)},
        {"aimed_targets", double(aimed_targets)},
        {"aimed_rounds", double(aimed_rounds)},
        {"aimed_rounds_mean",
         cell_sampled_visible.empty() ? 0.0 : double(aimed_rounds) / double(cell_sampled_visible.size())},
        {"aimed_new_pairs", double(aimed_new_pairs)},
        {"aimed_listed_new_pairs", double(aimed_listed_new_pairs)},
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
                        "the uniform rays did not touch, {:.0f}% of them at those the PVS lists",
                        result.aimed_rays_per_cell, double(result.aimed_rays_per_cell * n_cells) * 1e-6,
                        100.0 * config.aimed_share, 100.0 * config.aimed_listed_share));
    } else if (aim) {
        ctx.info(
            fmt::format("verify: aimed rays: from {} eye points per cell at every object the uniform rays "
                        "did not touch (no ray budget)",
                        config.rays.eyes_per_cell));
    }
    const std::vector<double> cum_area = aim ? cumulative_areas(world) : std::vector<double>();

    std::vector<std::vector<Miss>> cell_misses(n_cells);
    std::vector<uint64_t> cell_missed_rays(n_cells, 0);
    uint64_t rays_traced = 0, aimed_rays = 0, aimed_listed_rays = 0, aimed_candidates = 0,
             aimed_listed_candidates = 0, aimed_targets = 0, aimed_new = 0, aimed_listed_new = 0,
             aimed_missed = 0, aimed_rounds = 0;
    ctx.progress_begin("verify", n_cells, "cells");
#pragma omp parallel reduction(+ : rays_traced, aimed_rays, aimed_listed_rays, aimed_candidates, \
                                   aimed_listed_candidates, aimed_targets, aimed_new, aimed_listed_new, \
                                   aimed_missed, aimed_rounds)
    {
        CellRays rays;
        AimedRays aimed;
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
                // Candidates: what the uniform rays did not touch, but for listed objects every PVS lists;
                // split into those the PVS lists and those it leaves out.
                aimed.listed.clear();
                aimed.left_out.clear();
                const Aabb& cell_box = cells.cells[c].bounds;
                for (uint32_t o = 0; o < n_objects; ++o) {
                    const WorldObject& obj = world.objects[o];
                    if (result.sampled.test(c, o) || obj.triangle_count == 0) continue;
                    if (cum_area[obj.first_triangle + obj.triangle_count - 1] <= 0.0) continue;
                    if (!pvs.test(c, o)) {
                        aimed.left_out.push_back(o);
                    } else if (!(obj.flags & kObjectAlwaysVisible) && !cell_box.overlaps(obj.bounds)) {
                        aimed.listed.push_back(o);
                    }
                }
                aimed_candidates += aimed.listed.size() + aimed.left_out.size();
                aimed_listed_candidates += aimed.listed.size();
                // Every object an aimed ray touches counts as seen, and as a miss when unlisted.
                auto take = [&](const RayTouch& t, const glm::vec3& eye) {
                    if (!result.sampled.test(c, t.object)) {
                        result.sampled.set(c, t.object);
                        ++aimed_new;
                        if (pvs.test(c, t.object)) ++aimed_listed_new;
                    }
                    if (pvs.test(c, t.object)) return;
                    if (record(t.object, eye, aimed.directions[t.ray], t.t)) ++aimed_missed;
                };
                if (!aim_capped) {
                    // No budget: eyes_per_cell eye points aim at every candidate.
                    aimed.targets.resize(aimed.listed.size() + aimed.left_out.size());
                    std::merge(aimed.listed.begin(), aimed.listed.end(), aimed.left_out.begin(),
                               aimed.left_out.end(), aimed.targets.begin());
                    if (!aimed.targets.empty()) {
                        trace_aimed(scene, world, cum_area, cells, c, config.rays.eyes_per_cell,
                                    config.rays.seed, aimed);
                        if (!aimed.eyes.empty()) aimed_targets += aimed.targets.size();
                        aimed_rounds += aimed.eyes.size();
                        aimed_rays += aimed.directions.size();
                        rays_traced += aimed.directions.size();
                        for (const RayTouch& t : aimed.touches) {
                            const uint32_t eye =
                                uint32_t(std::upper_bound(aimed.first.begin(), aimed.first.end(), t.ray) -
                                         aimed.first.begin() - 1);
                            take(t, aimed.eyes[eye]);
                        }
                    }
                } else {
                    // Rounds: one fresh eye point aims at every object of the group not seen yet (the last
                    // round, short of rays, at a seeded random subset). Each round charges the group one ray
                    // per target. Returns the rays charged: 0 when nothing of the group is left unseen.
                    uint32_t round = 0;
                    aimed.batch = UINT32_MAX;
                    aimed.aimed_at.assign(n_objects, 0);
                    auto aim_round = [&](const std::vector<uint32_t>& group, bool listed,
                                         uint64_t rays_left) -> uint64_t {
                        aimed.targets.clear();
                        for (uint32_t o : group)
                            if (!result.sampled.test(c, o)) aimed.targets.push_back(o);
                        const uint64_t k = aimed.targets.size();
                        if (k == 0 || rays_left == 0) return 0;
                        if (k > rays_left) {
                            Rng rng(config.rays.seed, cell_stream(kAimedSubsetStream, c, round));
                            for (uint64_t i = 0; i < rays_left; ++i)
                                std::swap(aimed.targets[i], aimed.targets[i + rng.below(uint32_t(k - i))]);
                            aimed.targets.resize(rays_left);
                            std::sort(aimed.targets.begin(), aimed.targets.end());
                        }
                        if (!trace_round(scene, world, cum_area, cells, c, round, config.rays.seed, aimed))
                            return 0;
                        ++round;
                        for (uint32_t o : aimed.targets) {
                            aimed_targets += !aimed.aimed_at[o];
                            aimed.aimed_at[o] = 1;
                        }
                        aimed_rays += aimed.directions.size();
                        rays_traced += aimed.directions.size();
                        if (listed) aimed_listed_rays += aimed.directions.size();
                        for (const RayTouch& t : aimed.touches) take(t, aimed.eyes[0]);
                        return aimed.targets.size();
                    };
                    auto aim_group = [&](const std::vector<uint32_t>& group, bool listed, uint64_t budget) {
                        uint64_t spent = 0;
                        while (spent < budget) {
                            const uint64_t rays = aim_round(group, listed, budget - spent);
                            if (rays == 0) break;
                            spent += rays;
                        }
                        return spent;
                    };
                    // The listed group's share first, then the left-out group gets the rest, then the listed
                    // group what the left-out one could not use (its objects all seen: misses).
                    const uint64_t budget = result.aimed_rays_per_cell;
                    const uint64_t listed_budget =
                        aimed.left_out.empty()
                            ? budget
                            : std::min(budget, uint64_t(double(budget) * config.aimed_listed_share));
                    uint64_t spent = aim_group(aimed.listed, true, listed_budget);
                    spent += aim_group(aimed.left_out, false, budget - spent);
                    spent += aim_group(aimed.listed, true, budget - spent);
                    aimed_rounds += round;
                }
            }
            std::sort(cell_misses[c].begin(), cell_misses[c].end(),
                      [](const Miss& a, const Miss& b) { return a.object < b.object; });
            ctx.progress_advance();
        }
    }
    ctx.progress_end();

    result.aimed_rays = aimed_rays;
    result.aimed_listed_rays = aimed_listed_rays;
    result.aimed_candidates = aimed_candidates;
    result.aimed_listed_candidates = aimed_listed_candidates;
    result.aimed_listed_new_pairs = aimed_listed_new;
    result.aimed_rounds = aimed_rounds;
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
            "verify: aimed rays {:.1f} M ({:.1f} M at listed objects, {:.1f} eye points per cell) at {} of "
            "{} "
            "untouched (cell, object) pairs ({} listed): {} pairs seen only by them ({} listed), {} missed "
            "pairs found only by them",
            double(r.aimed_rays) * 1e-6, double(r.aimed_listed_rays) * 1e-6,
            r.cell_sampled_visible.empty() ? 0.0
                                           : double(r.aimed_rounds) / double(r.cell_sampled_visible.size()),
            r.aimed_targets, r.aimed_candidates, r.aimed_listed_candidates, r.aimed_new_pairs,
            r.aimed_listed_new_pairs, r.aimed_missed_pairs));
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
