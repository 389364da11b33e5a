// SPDX-License-Identifier: MIT
// Occluder synthesis: solid voxels, greedy boxes, and the ray check of every box against the triangles.
#include "occluders/synthesis.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "occluders/boxes.h"
#include "occluders/gap_probe.h"
#include "occluders/panels.h"
#include "occluders/seal_probe.h"
#include "occluders/slanted_panels.h"
#include "occluders/solid.h"
#include "rays/clearance.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <sstream>

namespace pvs {

namespace {

// Distance at which the ray leaves the box (the box holds the origin).
float exit_distance(glm::vec3 o, glm::vec3 d, const Aabb& b) {
    float t0, t1;
    return ray_box_interval(o, d, b, std::numeric_limits<float>::max(), t0, t1) ? t1 : 0.0f;
}

// Eye points for the check, spread over the eye mask's voxels (or, with none, over free voxels of the grid).
std::vector<glm::vec3> check_eyes(const VoxelMask& eye_mask, const VoxelGrid& grid, const BitVolume& blocked,
                                  uint32_t count, uint64_t seed) {
    // The candidates are the set bits of the eye mask (or the free voxels), in index order: counted per
    // word, and the k-th found by a binary search over the running counts and a select in its word.
    const uint64_t count_voxels = grid.count();
    const size_t words = size_t((count_voxels + 63) / 64);
    const auto word = [&](size_t w) {
        uint64_t bits = !eye_mask.empty() ? eye_mask.bits[w] : ~blocked.words[w];
        if (w + 1 == words && count_voxels % 64) bits &= (uint64_t(1) << (count_voxels % 64)) - 1;
        return bits;
    };
    std::vector<uint64_t> before(words + 1, 0);  // candidates in the words before each
    for (size_t w = 0; w < words; ++w) before[w + 1] = before[w] + uint64_t(__builtin_popcountll(word(w)));
    const auto candidate = [&](uint64_t r) {
        const size_t w = size_t(std::upper_bound(before.begin(), before.end(), r) - before.begin()) - 1;
        uint64_t bits = word(w);
        for (uint64_t k = before[w]; k < r; ++k) bits &= bits - 1;
        return uint64_t(w) * 64 + uint64_t(__builtin_ctzll(bits));
    };
    std::vector<glm::vec3> eyes;
    const uint64_t n = before[words];
    if (n == 0) return eyes;
    Rng rng(seed, 0x434845434bULL);
    for (uint32_t k = 0; k < count; ++k) {
        const uint64_t a = uint64_t(k) * n / count, b = std::max(a + 1, uint64_t(k + 1) * n / count);
        const uint64_t i = candidate(std::min<uint64_t>(n - 1, a + uint64_t(rng.uniform() * float(b - a))));
        eyes.push_back(grid.voxel_center(grid.coords(i)) +
                       (glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f) * grid.voxel_size_m);
    }
    return eyes;
}

// The least width of a line the probes count: kGapWidthShare of the gap tolerance
// (docs/ALGORITHMS.md#gap-tolerance). The ray check counts every line.
double least_width_m(const OccluderConfig& config) {
    return kGapWidthShare * config.gap_tolerance_m;
}

// The sight probe: rays over the sphere from eye points; solid voxels a ray passes before it stops are
// seen (through a crack): carve them and their neighbours out of the solid.
void carve_seen_solid(Context& ctx, const OccluderConfig& config, uint32_t probe_eyes, const VoxelGrid& grid,
                      const BitVolume& touched, const VoxelMask& eye_mask, const RayScene& scene,
                      Solid& solid, OccluderFigures& figures, WorkShare& share) {
    ScopedTimer timer(ctx, "sight_probe");
    const std::vector<glm::vec3> eyes =
        check_eyes(eye_mask, grid, touched, probe_eyes, config.check_seed ^ 0x5052);
    BitVolume seen;  // solid voxels a probe ray passed
    seen.reset(grid.count());
    uint64_t into_solid = 0, escaped = 0, narrow = 0;
    const float min_width_m = float(least_width_m(config));
    const float step = grid.voxel_size_m;  // a corner a step skips is covered by the 26-neighbour carving
    const Aabb gb = grid.bounds();
    ctx.progress_begin("sight probe", eyes.size(), "eyes");
    share.begin(eyes.size());
#pragma omp parallel reduction(+ : into_solid, escaped, narrow)
    {
        std::vector<glm::vec3> dirs;
        std::vector<RayTouch> touches;
        std::vector<float> stop;
        for_each_dealt(share, ctx, 4, [&](uint64_t e) {
            dirs.clear();
            touches.clear();
            sample_sphere_directions(config.probe_rays_per_eye, config.check_seed, uint64_t(e), dirs);
            scene.trace(eyes[size_t(e)], dirs.data(), uint32_t(dirs.size()), touches);
            stop.assign(dirs.size(), std::numeric_limits<float>::infinity());
            for (const RayTouch& t : touches)
                if (t.stops) stop[t.ray] = t.t;
            for (size_t r = 0; r < dirs.size(); ++r) {
                // March to the stop (or out of the grid), looking for solid voxels.
                const float exit = exit_distance(eyes[size_t(e)], dirs[r], gb);
                // The last voxel before the stop is not looked at: the surface that stops the ray may lie on
                // a voxel face with solid right behind it, and rounding must not count that as a crack.
                const float end = std::min(stop[r] - grid.voxel_size_m, exit);
                escaped += !std::isfinite(stop[r]);
                bool hit_solid = false;
                for (float t = 0.0f; t < end; t += step) {
                    const glm::vec3 p = eyes[size_t(e)] + t * dirs[r];
                    const glm::ivec3 c = grid.voxel_of(p);
                    const uint64_t i = grid.index(c.x, c.y, c.z);
                    if (!solid.solid.get(i)) continue;
                    // Sight through an opening narrower than the tolerance carves nothing.
                    if (!hit_solid && min_width_m > 0.0f &&
                        !sight_line_at_least(scene, eyes[size_t(e)], p, kNoObject, min_width_m)) {
                        ++narrow;
                        break;
                    }
                    seen.set_atomic(i);
                    hit_solid = true;
                }
                into_solid += hit_solid;
            }
        });
    }
    ctx.progress_end();
    // The processes' seen voxels and counts together (docs/ALGORITHMS.md#processes).
    share.unite(seen.words.data(), seen.words.size());
    uint64_t counts[3] = {into_solid, escaped, narrow};
    share.add(counts, 3);
    into_solid = counts[0];
    escaped = counts[1];
    narrow = counts[2];
    // Carve each seen voxel and its 26 neighbours: the seen set dilated by one voxel, a word at a time.
    const BitVolume carve = dilate(grid, seen, 1);
    uint64_t carved = 0;
    const int64_t words = int64_t(carve.words.size());
#pragma omp parallel for schedule(static) reduction(+ : carved)
    for (int64_t w = 0; w < words; ++w) {
        const uint64_t gone = solid.solid.words[size_t(w)] & carve.words[size_t(w)];
        carved += uint64_t(__builtin_popcountll(gone));
        solid.solid.words[size_t(w)] &= ~gone;
    }
    figures.probe_rays = uint64_t(eyes.size()) * config.probe_rays_per_eye;
    figures.probe_rays_into_solid = into_solid;
    figures.probe_rays_escaped = escaped;
    figures.probe_rays_narrow = narrow;
    figures.probe_carved_voxels = carved;
    solid.solid_voxels -= carved;
    ctx.info(fmt::format(
        "sight probe: {:.1f} M rays from {} eyes; {} reached solid voxels through cracks ({} left the "
        "world); {} voxels carved out of the solid",
        double(figures.probe_rays) * 1e-6, eyes.size(), into_solid, escaped, carved));
}

// The ray check: every box against sight lines from `eyes` to random points of it; returns 1 per rejected
// box (a segment reached a point of it before an opaque triangle, or an eye is inside it).
// With `near_eyes`, each box is also checked from config.check_near_eyes eye points of that mask within
// kNearCheckReachM of it, kNearCheckRays rays each: eyes spread over the whole eye space put few rays
// where a crack narrower than a voxel lets sight into the solid near them, and most of those are stopped
// far away. Still sampling: it finds such a crack often, not always (tests/test_occluders.cpp;
// docs/ALGORITHMS.md#ray-check).
constexpr uint32_t kNearCheckRays = 16;
constexpr float kNearCheckReachM = 4.0f;
std::vector<uint8_t> check_boxes(Context& ctx, const OccluderConfig& config, const std::vector<Aabb>& boxes,
                                 const std::vector<glm::vec3>& eyes, uint32_t rays_per_eye, uint64_t stream,
                                 const RayScene& scene, uint64_t& rays, WorkShare& share,
                                 const VoxelMask* near_eyes = nullptr) {
    std::vector<uint8_t> rejected(boxes.size(), 0);
    uint64_t rays_total = 0;
    ctx.progress_begin("occluder check", boxes.size(), "boxes");
    share.begin(boxes.size());
#pragma omp parallel reduction(+ : rays_total)
    {
        std::vector<glm::vec3> origins, dirs, near;
        std::vector<float> tfar;
        std::vector<uint8_t> blocked;
        for_each_dealt(share, ctx, 1, [&](uint64_t b) {
            const Aabb& box = boxes[size_t(b)];
            Rng rng(config.check_seed, stream + uint64_t(b));
            origins.clear();
            dirs.clear();
            tfar.clear();
            near.clear();
            if (near_eyes && !near_eyes->empty()) {
                // Uniform points of the box grown by the reach, kept where they are eye space (rejection
                // sampling: no walk over the voxels of a large box).
                const Aabb around = Aabb::of(box.min - kNearCheckReachM, box.max + kNearCheckReachM);
                Rng near_rng(config.check_seed, (stream + uint64_t(b)) ^ 0x4e454152ULL);
                const uint32_t want = config.check_near_eyes;
                for (uint32_t tries = 0; tries < 16 * want && near.size() < want; ++tries) {
                    const glm::vec3 u(near_rng.uniform(), near_rng.uniform(), near_rng.uniform());
                    const glm::vec3 p = around.min + around.size() * u;
                    if (near_eyes->contains(p)) near.push_back(p);
                }
            }
            const size_t n_far = eyes.size();
            for (size_t ei = 0; ei < n_far + near.size(); ++ei) {
                const glm::vec3& e = ei < n_far ? eyes[ei] : near[ei - n_far];
                if (box.contains(e)) {
                    rejected[size_t(b)] = 1;  // an eye inside: not solid at all
                    break;
                }
                const uint32_t n_rays = ei < n_far ? rays_per_eye : kNearCheckRays;
                for (uint32_t k = 0; k < n_rays; ++k) {
                    const glm::vec3 target =
                        box.min + box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
                    const glm::vec3 d = glm::normalize(target - e);
                    // The segment to the target point itself: a box whose face lies on the blocking surface
                    // (internal faces are solid) is blocked at its face, before any point inside it.
                    const float t = glm::length(target - e);
                    if (t <= 0.0f) continue;
                    origins.push_back(e);
                    dirs.push_back(d);
                    tfar.push_back(t);
                }
            }
            if (!rejected[size_t(b)] && !origins.empty()) {
                blocked.resize(origins.size());
                scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                                      blocked.data());
                rays_total += origins.size();
                for (uint8_t x : blocked)
                    if (!x) {
                        rejected[size_t(b)] = 1;
                        break;
                    }
            }
        });
    }
    ctx.progress_end();
    // The processes' verdicts and rays together (docs/ALGORITHMS.md#processes).
    if (share.processes() > 1) {
        std::vector<uint64_t> bits((boxes.size() + 63) / 64, 0);
        for (size_t b = 0; b < boxes.size(); ++b) bits[b / 64] |= uint64_t(rejected[b]) << (b % 64);
        share.unite(bits.data(), bits.size());
        for (size_t b = 0; b < boxes.size(); ++b) rejected[b] = uint8_t((bits[b / 64] >> (b % 64)) & 1);
        share.add(&rays_total, 1);
    }
    rays += rays_total;
    return rejected;
}

std::vector<Aabb> bounds_of(const VoxelGrid& grid, const std::vector<VoxelBox>& boxes) {
    std::vector<Aabb> out;
    out.reserve(boxes.size());
    for (const VoxelBox& b : boxes) out.push_back(box_bounds(grid, b));
    return out;
}

// Sets (value true) or clears the voxels of every box whose flag in `rejected` equals `which`, a row of
// each box at a time, whole words between its ends.
void mark_boxes(const VoxelGrid& grid, const std::vector<VoxelBox>& boxes,
                const std::vector<uint8_t>& rejected, uint8_t which, bool value, BitVolume& out) {
    const auto mark = [&](uint64_t w, uint64_t mask) {
        value ? out.words[w] |= mask : out.words[w] &= ~mask;
    };
    for (size_t b = 0; b < boxes.size(); ++b) {
        if (rejected[b] != which) continue;
        const VoxelBox& vb = boxes[b];
        for (int z = vb.lo.z; z <= vb.hi.z; ++z)
            for (int y = vb.lo.y; y <= vb.hi.y; ++y) {
                const uint64_t lo = grid.index(vb.lo.x, y, z), hi = grid.index(vb.hi.x, y, z);
                const uint64_t w0 = lo >> 6, w1 = hi >> 6;
                const uint64_t m0 = ~uint64_t(0) << (lo & 63), m1 = ~uint64_t(0) >> (63 - (hi & 63));
                if (w0 == w1) {
                    mark(w0, m0 & m1);
                    continue;
                }
                mark(w0, m0);
                for (uint64_t w = w0 + 1; w < w1; ++w) mark(w, ~uint64_t(0));
                mark(w1, m1);
            }
    }
}

// Boxes of the proven solid eroded by each epsilon of the ladder: a voxel stays when every voxel within k
// (Chebyshev) is proven solid; voxels within k of the grid's border go (outside the grid is unknown).
// The levels run one after another, each on all threads (dilate() and grow_boxes() are parallel), so the
// stage holds one level's table and seed cubes whatever the thread count; the boxes do not depend on it.
std::vector<std::vector<Aabb>> shrunk_boxes(Context& ctx, const VoxelGrid& grid, const BitVolume& proven,
                                            const BoxConfig& bc, const std::vector<double>& epsilon_m,
                                            WorkShare& share) {
    const double voxel_m3 = double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    BitVolume not_proven;
    not_proven.words.resize(proven.words.size());
    for_each_word(not_proven.words.size(), [&](size_t w) { not_proven.words[w] = ~proven.words[w]; });
    BoxConfig sc = bc;
    sc.min_box_volume_m3 = 0.0;  // every shrunk box helps fusion
    sc.max_boxes = std::max<uint32_t>(bc.max_boxes, 1024);
    std::vector<std::vector<Aabb>> out(epsilon_m.size());
    std::vector<uint64_t> eroded_voxels(epsilon_m.size(), 0);
    const auto k_of = [&](size_t level) {
        return std::max(1, int(std::ceil(epsilon_m[level] / double(grid.voxel_size_m) - 1e-9)));
    };
    // Under MPI each process grows the levels dealt to it (level mod processes), one after another, each
    // on all its threads; then every process takes each level's boxes from the one that grew them.
    const auto owner = [&](size_t level) { return int(level % size_t(share.processes())); };
    // grow_boxes()'s own progress and timer would repeat per level: they go to a quiet context.
    Context quiet(Context::Options{LogLevel::kWarning, true, nullptr});
    for (size_t level = 0; level < epsilon_m.size(); ++level) {
        if (owner(level) != share.rank()) continue;
        const int k = k_of(level);
        BitVolume eroded = dilate(grid, not_proven, k);
        for_each_word(eroded.words.size(),
                      [&](size_t w) { eroded.words[w] = proven.words[w] & ~eroded.words[w]; });
        clear_border(grid, eroded, k);
        for (const VoxelBox& vb : grow_boxes(quiet, grid, eroded, sc, nullptr))
            out[level].push_back(box_bounds(grid, vb));
        eroded_voxels[level] = eroded.count();
    }
    if (share.processes() > 1) {
        // A level as words: its eroded voxels, then each box's six floats, two to a word.
        for (size_t level = 0; level < epsilon_m.size(); ++level) {
            std::vector<uint64_t> packed;
            if (owner(level) == share.rank()) {
                packed.assign(1 + 3 * out[level].size(), 0);
                packed[0] = eroded_voxels[level];
                for (size_t b = 0; b < out[level].size(); ++b) {
                    const Aabb& a = out[level][b];
                    const float f[6] = {a.min.x, a.min.y, a.min.z, a.max.x, a.max.y, a.max.z};
                    std::memcpy(&packed[1 + 3 * b], f, sizeof f);
                }
            }
            take_from(share, owner(level), packed);
            eroded_voxels[level] = packed.at(0);
            out[level].resize((packed.size() - 1) / 3);
            for (size_t b = 0; b < out[level].size(); ++b) {
                float f[6];
                std::memcpy(f, &packed[1 + 3 * b], sizeof f);
                out[level][b] = Aabb::of(glm::vec3(f[0], f[1], f[2]), glm::vec3(f[3], f[4], f[5]));
            }
        }
    }
    for (size_t level = 0; level < epsilon_m.size(); ++level) {
        ctx.info(fmt::format("occluders shrunk by {} m ({} voxels): {} boxes of {:.0f} m3 of solid",
                             epsilon_m[level], k_of(level), out[level].size(),
                             double(eroded_voxels[level]) * voxel_m3));
    }
    return out;
}

VoxelMask mask_of(const VoxelGrid& grid, std::vector<uint64_t> bits) {
    VoxelMask m;
    m.origin = grid.origin;
    m.voxel_size_m = grid.voxel_size_m;
    m.dims = grid.dims;
    m.bits = std::move(bits);
    return m;
}

BoxConfig box_config(const OccluderConfig& config) {
    BoxConfig bc;
    bc.max_boxes = config.max_occluders;
    bc.min_box_volume_m3 = config.min_occluder_volume_m3;
    bc.min_added_share = config.min_added_share;
    return bc;
}

// The voxels of `grid` from `lo` over `window`'s dims, as a volume on `window` (the same voxel size).
BitVolume crop(const VoxelGrid& grid, const std::vector<uint64_t>& bits, glm::ivec3 lo,
               const VoxelGrid& window) {
    BitVolume out;
    out.reset(window.count());
    for (int z = 0; z < window.dims.z; ++z)
        for (int y = 0; y < window.dims.y; ++y)
            for (int x = 0; x < window.dims.x; ++x) {
                const uint64_t i = grid.index(lo.x + x, lo.y + y, lo.z + z);
                if ((bits[i >> 6] >> (i & 63)) & 1u) out.set(window.index(x, y, z));
            }
    return out;
}

}  // namespace

// Rounds of the seal probe: each probes the frontier the leaks of the one before opened.
constexpr int kSealRounds = 8;

// Slanted panels: their triangles within 0.1 mm of the plane (the slab the single-occluder test checks both
// faces of: any thickness is safe, a thin one keeps the test tight), and polygons of at least 0.25 m2 (the
// smaller ones, a third of them on ctf_inyard, hold little of the area and cost candidate tests).
constexpr double kSlantedThicknessM = 1e-4;
constexpr double kSlantedMinAreaM2 = 0.25;

std::vector<Occluder> synthesize_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                           const ViewVolume& view, const RayScene& scene,
                                           OccluderFigures& figures, double epsilon_m, int levels,
                                           ShrunkOccluders* shrunk, WorkShare* share) {
    ScopedTimer timer(ctx, "occluders");
    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    const auto start = std::chrono::steady_clock::now();
    // The voxels: the view volume's; without a view volume, its grid of the world (build_view_volume).
    const VoxelGrid& grid = view.grid;
    BitVolume touched_local;
    const BitVolume* touched = &view.touched;
    if (!view.voxelized) {
        voxelize_opaque(ctx, world, grid, touched_local);
        touched = &touched_local;
    }
    Solid solid = classify_solid(ctx, grid, *touched, view.eyes);
    add_closed_boxes(ctx, closed_box_objects(world), view.eyes, solid);
    figures.solid_m3 = solid.solid_m3;
    if (config.probe_eyes > 0)
        carve_seen_solid(ctx, config, config.probe_eyes, grid, *touched, view.eyes, scene, solid, figures,
                         deal);
    if (config.gap_lines > 0) {
        const GapProbeFigures gf = probe_gaps(ctx, *touched, view.eyes, scene, config.gap_tolerance_m,
                                              config.gap_lines, solid, share);
        figures.gap_voxels = gf.voxels;
        figures.gap_gaps = gf.gaps;
        figures.gap_lines = gf.lines;
        figures.gap_leaks = gf.leaks;
        figures.gap_removed_voxels = gf.removed_voxels;
    }
    if (config.seal_rays > 0) {
        const SealProbeFigures sf =
            probe_seals(ctx, *touched, view.eyes, scene, config.seal_rays, config.seal_reach_m, kSealRounds,
                        config.check_seed, least_width_m(config), solid, share);
        figures.seal_frontier_voxels = sf.frontier_voxels;
        figures.seal_narrow = sf.narrow;
        figures.seal_rays = sf.rays;
        figures.seal_leaks = sf.leaks;
        figures.seal_removed_voxels = sf.removed_voxels;
    }

    const BoxConfig bc = box_config(config);
    BoxStats stats;
    std::vector<VoxelBox> boxes = grow_boxes(ctx, grid, solid.solid, bc, &stats);
    figures.grown = stats.grown;
    figures.kept = uint32_t(boxes.size());
    const double voxel_m3 = double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    figures.covered_m3 = double(stats.covered_voxels) * voxel_m3;

    // The ray check: every box against sight lines from eyes spread over the eye space.
    const std::vector<glm::vec3> eyes =
        check_eyes(view.eyes, grid, *touched, config.check_eyes, config.check_seed);
    std::vector<uint8_t> rejected =
        check_boxes(ctx, config, bounds_of(grid, boxes), eyes, config.check_rays_per_eye, 0, scene,
                    figures.check_rays, deal, &view.eyes);
    for (uint8_t r : rejected) figures.rejected_by_rays += r;
    // The proven solid, for the solver: the carved solid less every rejected box (as the ray check left the
    // boxes, before the kept ones are trimmed off them).
    BitVolume proven;
    if (shrunk != nullptr) {
        proven = solid.solid;
        mark_boxes(grid, boxes, rejected, 1, false, proven);
    }
    const TrimFigures trim =
        trim_off_rejected(boxes, rejected, uint64_t(std::ceil(bc.min_box_volume_m3 / voxel_m3)));
    figures.trimmed = trim.trimmed;
    figures.trimmed_away = trim.trimmed_away;

    if (shrunk != nullptr) {
        // The proven solid eroded per epsilon.
        ScopedTimer t(ctx, "shrink");
        *shrunk = ShrunkOccluders{};
        for (int level = 0; level <= levels; ++level)
            shrunk->epsilon_m.push_back(epsilon_m * std::ldexp(1.0, level));
        PanelFigures pf;
        shrunk->panels = find_panels(world, &pf);
        ctx.info(
            fmt::format("panels: {} opaque triangles lie in {} axis planes, covering {} cells of their "
                        "vertex grids; {} maximal covered rectangles",
                        pf.flat_triangles, pf.planes, pf.covered_cells, pf.panels));
        SlantedPanelFigures sf;
        shrunk->slanted = find_slanted_panels(world, kSlantedThicknessM, kSlantedMinAreaM2, &sf);
        ctx.info(fmt::format(
            "slanted panels: {} opaque triangles off the axis planes ({:.0f} m2) give {} convex "
            "polygons of at least {} m2 ({:.0f} m2)",
            sf.slanted_triangles, sf.slanted_area_m2, sf.panels, kSlantedMinAreaM2, sf.panel_area_m2));
        shrunk->boxes = shrunk_boxes(ctx, grid, proven, bc, shrunk->epsilon_m, deal);
        std::vector<uint64_t> free_bits(proven.words.size());
        for_each_word(free_bits.size(),
                      [&](size_t w) { free_bits[w] = ~(proven.words[w] | touched->words[w]); });
        shrunk->free = mask_of(grid, std::move(free_bits));
        shrunk->solid = mask_of(grid, std::move(proven.words));
    }

    std::vector<Occluder> out;
    for (size_t b = 0; b < boxes.size(); ++b) {
        Occluder o;
        o.box = box_bounds(grid, boxes[b]);
        o.voxel_size_m = grid.voxel_size_m;
        o.proven = !rejected[b];
        Aabb grown = o.box;
        grown.min -= grid.voxel_size_m;
        grown.max += grid.voxel_size_m;
        for (uint32_t i = 0; i < world.objects.size(); ++i) {
            if ((world.objects[i].flags & kObjectHasOpaque) && world.objects[i].bounds.overlaps(grown))
                o.objects.push_back(i);
        }
        out.push_back(std::move(o));
    }
    // Coverage of the solid near the view region by the proven boxes.
    {
        BitVolume covered;
        covered.reset(grid.count());
        mark_boxes(grid, boxes, rejected, 0, true, covered);
        BitVolume near;
        if (!view.view.empty()) {
            BitVolume region;
            region.words = view.view.bits;
            near = dilate(grid, region, int(std::ceil(kNearViewM / grid.voxel_size_m)));
        }
        const auto s_near = [&](size_t w) {
            return solid.solid.words[w] & (near.words.empty() ? ~uint64_t(0) : near.words[w]);
        };
        const uint64_t n = sum_words(solid.solid.words.size(),
                                     [&](size_t w) { return uint64_t(__builtin_popcountll(s_near(w))); });
        const uint64_t c = sum_words(solid.solid.words.size(), [&](size_t w) {
            return uint64_t(__builtin_popcountll(s_near(w) & covered.words[w]));
        });
        figures.near_m3 = double(n) * voxel_m3;
        figures.near_covered_m3 = double(c) * voxel_m3;
    }
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "occluders: {} boxes cover {:.0f} of {:.0f} m3 of solid ({:.1f}%), {:.1f}% of the {:.0f} m3 "
        "within {} m of the view region; the ray check ({:.1f} M rays) rejected {}, and {} kept boxes "
        "were cut off them ({} too small then); {:.2f} s",
        figures.kept, figures.covered_m3, figures.solid_m3,
        figures.solid_m3 > 0 ? 100.0 * figures.covered_m3 / figures.solid_m3 : 0.0,
        figures.near_m3 > 0 ? 100.0 * figures.near_covered_m3 / figures.near_m3 : 0.0, figures.near_m3,
        kNearViewM, double(figures.check_rays) * 1e-6, figures.rejected_by_rays, figures.trimmed,
        figures.trimmed_away, figures.seconds));
    return out;
}

// Boxes grown over the solid only a block's eyes leave, each ray-checked before its voxels count as proven.
constexpr uint32_t kBlockCheckBoxes = 4096;

BlockFigures synthesize_block_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                        const ViewVolume& view, const RayScene& scene, glm::vec3 origin,
                                        float block_m, ShrunkOccluders& shrunk) {
    ScopedTimer timer(ctx, "block_occluders");
    const auto start = std::chrono::steady_clock::now();
    WorkShare alone;  // each block's own probes, on this process
    BlockFigures figures;
    if (!view.voxelized || view.eyes.empty() || !(block_m > 0.0f) || shrunk.epsilon_m.empty() ||
        shrunk.solid.empty()) {
        return figures;
    }
    const VoxelGrid& grid = view.grid;
    const float vs = grid.voxel_size_m;
    const Aabb& vb = view.view_bounds;
    const glm::ivec2 dims(std::max(1, int(std::ceil((vb.max.x - origin.x) / block_m))),
                          std::max(1, int(std::ceil((vb.max.z - origin.z) / block_m))));
    shrunk.block_size_m = block_m;
    shrunk.block_origin = origin;
    shrunk.block_dims = dims;
    shrunk.block_tolerance_m = 0.5f * vs;
    shrunk.block_set.assign(size_t(dims.x) * size_t(dims.y), -1);
    shrunk.block_sets.clear();
    const BoxConfig bc = box_config(config);
    const std::vector<Aabb> closed = closed_box_objects(world);
    const double voxel_m3 = double(vs) * vs * vs;
    // The stages' own logs and timers would repeat once per block: they go to a quiet context.
    Context quiet(Context::Options{LogLevel::kWarning, true, nullptr});
    const auto voxel_lo = [&](float p, int a) {
        return std::clamp(int(std::floor((p - grid.origin[a]) / vs)), 0, grid.dims[a]);
    };
    ctx.progress_begin("block occluders", shrunk.block_set.size(), "blocks");
    for (int bz = 0; bz < dims.y; ++bz)
        for (int bx = 0; bx < dims.x; ++bx) {
            ctx.progress_advance();
            const float x0 = origin.x + float(bx) * block_m, z0 = origin.z + float(bz) * block_m;
            const float x1 = x0 + block_m, z1 = z0 + block_m;
            // The window: the block's square grown by the reach, every height.
            const float reach = float(config.block_reach_m);
            const glm::ivec3 lo(voxel_lo(x0 - reach, 0), 0, voxel_lo(z0 - reach, 2));
            const glm::ivec3 hi(std::min(grid.dims.x, voxel_lo(x1 + reach, 0) + 1), grid.dims.y,
                                std::min(grid.dims.z, voxel_lo(z1 + reach, 2) + 1));
            if (glm::any(glm::lessThanEqual(hi, lo))) continue;
            VoxelGrid window;
            window.origin = grid.origin + glm::vec3(lo) * vs;
            window.voxel_size_m = vs;
            window.dims = hi - lo;
            // The sources: every eye voxel meeting the square grown by a voxel (a cell of the block, and so
            // its eye region, lies in the square; more sources only mean less solid).
            BitVolume sources;
            sources.reset(window.count());
            const int sx0 = std::max(lo.x, voxel_lo(x0 - vs, 0)),
                      sx1 = std::min(hi.x, voxel_lo(x1 + vs, 0) + 1);
            const int sz0 = std::max(lo.z, voxel_lo(z0 - vs, 2)),
                      sz1 = std::min(hi.z, voxel_lo(z1 + vs, 2) + 1);
            uint64_t n_sources = 0;
            for (int z = sz0; z < sz1; ++z)
                for (int y = 0; y < grid.dims.y; ++y)
                    for (int x = sx0; x < sx1; ++x)
                        if (view.eyes.get(grid.index(x, y, z))) {
                            sources.set(window.index(x - lo.x, y, z - lo.z));
                            ++n_sources;
                        }
            if (n_sources == 0) continue;
            ++figures.blocks;
            const BitVolume touched = crop(grid, view.touched.words, lo, window);
            const VoxelMask eyes = mask_of(window, std::move(sources.words));
            Solid solid = classify_solid(quiet, window, touched, eyes);
            add_closed_boxes(quiet, closed, eyes, solid);
            // Worth it only when the block's eyes leave clearly more solid than all eyes do.
            const BitVolume global = crop(grid, shrunk.solid.bits, lo, window);
            const uint64_t n_global = global.count(), n_block = solid.solid.count();
            if (double(n_block) <= (1.0 + config.block_min_gain) * double(n_global)) continue;
            OccluderFigures f;
            if (config.block_probe_eyes > 0)
                carve_seen_solid(quiet, config, config.block_probe_eyes, window, touched, eyes, scene, solid,
                                 f, alone);
            // What only the block's eyes leave is proven box by box: boxes grown to cover it (up to
            // kBlockCheckBoxes, however small), each checked with segments from the block's own eyes; the
            // block's proven solid is the accepted boxes, with the global proven solid (proven for every
            // eye). (Voxels no checked box covers are dropped: unlike the global solid, which is mostly
            // sealed space, a block's is mostly shadow, whose edges are grazing lines.)
            BoxConfig cover = bc;
            cover.max_boxes = kBlockCheckBoxes;
            cover.min_box_volume_m3 = 0.0;
            const std::vector<VoxelBox> boxes = grow_boxes(quiet, window, solid.solid, cover, nullptr);
            const uint64_t block_index = uint64_t(bx) + uint64_t(dims.x) * uint64_t(bz);
            const std::vector<glm::vec3> check = check_eyes(eyes, window, touched, config.block_check_eyes,
                                                            config.check_seed ^ (block_index << 8));
            const std::vector<uint8_t> rejected =
                check_boxes(quiet, config, bounds_of(window, boxes), check, config.check_rays_per_eye, 0,
                            scene, f.check_rays, alone);
            BitVolume proven = global;
            mark_boxes(window, boxes, rejected, 0, true, proven);
            ShrunkOccluders set;
            set.epsilon_m = shrunk.epsilon_m;
            set.boxes = shrunk_boxes(quiet, window, proven, bc, shrunk.epsilon_m, alone);
            // The boxes the solver will draw are checked once more, from the same eyes at fresh points: a
            // box any segment reaches is dropped (drawing fewer occluders is always safe).
            for (size_t k = 0; k < set.boxes.size(); ++k) {
                const std::vector<uint8_t> seen =
                    check_boxes(quiet, config, set.boxes[k], check, config.check_rays_per_eye,
                                uint64_t(k + 1) << 32, scene, f.check_rays, alone);
                std::vector<Aabb> kept;
                for (size_t i = 0; i < seen.size(); ++i)
                    if (!seen[i]) kept.push_back(set.boxes[k][i]);
                figures.boxes_dropped += seen.size() - kept.size();
                set.boxes[k] = std::move(kept);
            }
            figures.boxes += set.boxes.front().size();
            // The global boxes still serve beyond the window; those inside one of the block's are dropped.
            for (size_t k = 0; k < set.boxes.size(); ++k) {
                const size_t own = set.boxes[k].size();
                for (const Aabb& g : shrunk.boxes[k]) {
                    bool inside = false;
                    for (size_t i = 0; i < own && !inside; ++i) {
                        const Aabb& b = set.boxes[k][i];
                        inside = glm::all(glm::lessThanEqual(b.min, g.min)) &&
                                 glm::all(glm::lessThanEqual(g.max, b.max));
                    }
                    if (!inside) set.boxes[k].push_back(g);
                }
            }
            set.panels = shrunk.panels;
            set.slanted = shrunk.slanted;
            figures.solid_m3 += double(proven.count()) * voxel_m3;
            figures.global_solid_m3 += double(n_global) * voxel_m3;
            figures.rays += f.probe_rays + f.check_rays;
            set.solid = mask_of(window, std::move(proven.words));  // `free` stays the global one
            shrunk.block_set[block_index] = int32_t(shrunk.block_sets.size());
            shrunk.block_sets.push_back(std::move(set));
        }
    ctx.progress_end();
    figures.blocks_used = uint32_t(shrunk.block_sets.size());
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "block occluders: {} m blocks (sight from the block's own eyes, {} m around it): {} of {} blocks "
        "leave more solid and have their own occluders ({:.0f} m3 of proven solid where all eyes leave "
        "{:.0f} m3; {} own boxes at the floor epsilon, {} shrunk boxes dropped by the second check); {:.1f} "
        "s",
        block_m, config.block_reach_m, figures.blocks_used, figures.blocks, figures.solid_m3,
        figures.global_solid_m3, figures.boxes, figures.boxes_dropped, figures.seconds));
    return figures;
}

BlockAudit audit_block_occluders(const ViewVolume& view, const RayScene& scene, const ShrunkOccluders& shrunk,
                                 uint32_t eyes_per_block, uint32_t points_per_box, uint64_t seed) {
    BlockAudit out;
    CellSet masks;
    masks.eyes = view.eyes;
    Rng rng(seed, 0x415544);
    std::vector<glm::vec3> eyes, origins, dirs;
    std::vector<float> tfar;
    std::vector<uint8_t> blocked;
    for (int bz = 0; bz < shrunk.block_dims.y; ++bz)
        for (int bx = 0; bx < shrunk.block_dims.x; ++bx) {
            const size_t index = size_t(bx) + size_t(shrunk.block_dims.x) * size_t(bz);
            const int32_t set = shrunk.block_set[index];
            if (set < 0) continue;
            ++out.blocks;
            const float b = shrunk.block_size_m;
            const float x0 = shrunk.block_origin.x + float(bx) * b,
                        z0 = shrunk.block_origin.z + float(bz) * b;
            const Aabb square =
                Aabb::of({x0, view.view_bounds.min.y, z0}, {x0 + b, view.view_bounds.max.y, z0 + b});
            eyes.clear();
            sample_eye_points_in(masks, square, 7000 + index, eyes_per_block, seed, eyes);
            for (const Aabb& box : shrunk.set(set).boxes.front()) {
                origins.clear();
                dirs.clear();
                tfar.clear();
                for (const glm::vec3& e : eyes)
                    for (uint32_t k = 0; k < points_per_box; ++k) {
                        const glm::vec3 p =
                            box.min + box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
                        const float len = glm::length(p - e);
                        if (!(len > 0.0f)) continue;
                        origins.push_back(e);
                        dirs.push_back((p - e) / len);
                        tfar.push_back(len);
                    }
                blocked.resize(origins.size());
                if (origins.empty()) continue;
                scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                                      blocked.data());
                out.rays += origins.size();
                for (size_t i = 0; i < blocked.size(); ++i) {
                    if (blocked[i]) continue;
                    if (out.reached++ == 0) {
                        std::ostringstream m;
                        m << "block " << index << ": eye (" << origins[i].x << ", " << origins[i].y << ", "
                          << origins[i].z << ") reaches " << tfar[i] << " m along (" << dirs[i].x << ", "
                          << dirs[i].y << ", " << dirs[i].z << ") into box (" << box.min.x << ", "
                          << box.min.y << ", " << box.min.z << ")-(" << box.max.x << ", " << box.max.y << ", "
                          << box.max.z << ")";
                        out.first = m.str();
                    }
                }
            }
        }
    return out;
}

}  // namespace pvs
