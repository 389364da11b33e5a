// Occluder synthesis: solid voxels, greedy boxes, and the ray check of every box against the triangles.
#include "pvs/occluder_synthesis.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "occluders/boxes.h"
#include "occluders/panels.h"
#include "occluders/solid.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

// Distance at which the ray leaves the box (the box holds the origin).
float exit_distance(glm::vec3 o, glm::vec3 d, const Aabb& b) {
    float t0, t1;
    return ray_box_interval(o, d, b, std::numeric_limits<float>::max(), t0, t1) ? t1 : 0.0f;
}

// Eye points for the check, spread over the eye space (or, with none, over free voxels of the grid).
std::vector<glm::vec3> check_eyes(const ViewVolume& view, const VoxelGrid& grid, const BitVolume& blocked,
                                  uint32_t count, uint64_t seed) {
    std::vector<uint64_t> candidates;
    for (uint64_t i = 0; i < grid.count(); ++i) {
        const bool ok = !view.eyes.empty() ? view.eyes.get(i) : !blocked.get(i);
        if (ok) candidates.push_back(i);
    }
    std::vector<glm::vec3> eyes;
    if (candidates.empty()) return eyes;
    Rng rng(seed, 0x434845434bULL);
    const uint64_t n = candidates.size();
    for (uint32_t k = 0; k < count; ++k) {
        const uint64_t a = uint64_t(k) * n / count, b = std::max(a + 1, uint64_t(k + 1) * n / count);
        const uint64_t i = candidates[std::min<uint64_t>(n - 1, a + uint64_t(rng.uniform() * float(b - a)))];
        eyes.push_back(grid.voxel_center(grid.coords(i)) +
                       (glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f) * grid.voxel_size_m);
    }
    return eyes;
}

// The sight probe: rays over the sphere from eye points; solid voxels a ray passes before it stops are
// seen (through a crack): carve them and their neighbours out of the solid.
void carve_seen_solid(Context& ctx, const OccluderConfig& config, const VoxelGrid& grid,
                      const BitVolume& touched, const ViewVolume& view, const RayScene& scene, Solid& solid,
                      OccluderFigures& figures) {
    ScopedTimer timer(ctx, "sight_probe");
    const std::vector<glm::vec3> eyes =
        check_eyes(view, grid, touched, config.probe_eyes, config.check_seed ^ 0x5052);
    std::vector<uint8_t> seen(grid.count(), 0);
    uint64_t into_solid = 0, escaped = 0;
    const float step = grid.voxel_size_m;  // a corner a step skips is covered by the 26-neighbour carving
    const Aabb gb = grid.bounds();
#pragma omp parallel reduction(+ : into_solid, escaped)
    {
        std::vector<glm::vec3> dirs;
        std::vector<RayTouch> touches;
        std::vector<float> stop;
#pragma omp for schedule(dynamic, 4)
        for (int64_t e = 0; e < int64_t(eyes.size()); ++e) {
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
                    if (solid.solid.get(i)) {
                        seen[i] = 1;  // a benign race: every writer writes 1
                        hit_solid = true;
                    }
                }
                into_solid += hit_solid;
            }
        }
    }
    uint64_t carved = 0;
    for (uint64_t i = 0; i < grid.count(); ++i) {
        if (!seen[i]) continue;
        const glm::ivec3 c = grid.coords(i);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const glm::ivec3 n = c + glm::ivec3(dx, dy, dz);
                    if (!grid.inside(n)) continue;
                    const uint64_t j = grid.index(n.x, n.y, n.z);
                    if (solid.solid.get(j)) {
                        solid.solid.clear(j);
                        ++carved;
                    }
                }
    }
    figures.probe_rays = uint64_t(eyes.size()) * config.probe_rays_per_eye;
    figures.probe_rays_into_solid = into_solid;
    figures.probe_rays_escaped = escaped;
    figures.probe_carved_voxels = carved;
    solid.solid_voxels -= carved;
    ctx.info(fmt::format(
        "sight probe: {:.1f} M rays from {} eyes; {} reached solid voxels through cracks ({} left the "
        "world); {} voxels carved out of the solid",
        double(figures.probe_rays) * 1e-6, eyes.size(), into_solid, escaped, carved));
}

}  // namespace

std::vector<Occluder> synthesize_occluders(Context& ctx, const OccluderConfig& config, const World& world,
                                           const ViewVolume& view, const RayScene& scene,
                                           OccluderFigures& figures, double epsilon_m, int levels,
                                           ShrunkOccluders* shrunk) {
    ScopedTimer timer(ctx, "occluders");
    const auto start = std::chrono::steady_clock::now();
    // The voxels: the view volume's, or the world's at the default size when there is no view volume.
    VoxelGrid grid = view.grid;
    BitVolume touched_local;
    const BitVolume* touched = &view.touched;
    if (!view.voxelized) {
        grid = make_voxel_grid(world.bounds,
                               default_voxel_size(world.bounds, kDefaultVoxelSizeM, 200'000'000), 2);
        voxelize_opaque(ctx, world, grid, touched_local);
        touched = &touched_local;
    }
    Solid solid = classify_solid(ctx, grid, *touched, view.eyes);
    add_closed_boxes(ctx, closed_box_objects(world), view.eyes, solid);
    figures.solid_m3 = solid.solid_m3;
    if (config.probe_eyes > 0) carve_seen_solid(ctx, config, grid, *touched, view, scene, solid, figures);

    BoxConfig bc;
    bc.max_boxes = config.max_occluders;
    bc.min_box_volume_m3 = config.min_occluder_volume_m3;
    bc.min_added_share = config.min_added_share;
    BoxStats stats;
    const std::vector<VoxelBox> boxes = grow_boxes(ctx, grid, solid.solid, bc, &stats);
    figures.grown = stats.grown;
    figures.kept = uint32_t(boxes.size());
    const double voxel_m3 = double(grid.voxel_size_m) * grid.voxel_size_m * grid.voxel_size_m;
    figures.covered_m3 = double(stats.covered_voxels) * voxel_m3;

    // The ray check: every box against sight lines from eyes spread over the eye space.
    const std::vector<glm::vec3> eyes =
        check_eyes(view, grid, *touched, config.check_eyes, config.check_seed);
    std::vector<uint8_t> rejected(boxes.size(), 0);
    uint64_t rays_total = 0;
    ctx.progress_begin("occluder check", boxes.size(), "boxes");
#pragma omp parallel reduction(+ : rays_total)
    {
        std::vector<glm::vec3> origins, dirs;
        std::vector<float> tfar;
        std::vector<uint8_t> blocked;
#pragma omp for schedule(dynamic, 1)
        for (int64_t b = 0; b < int64_t(boxes.size()); ++b) {
            const Aabb box = box_bounds(grid, boxes[size_t(b)]);
            Rng rng(config.check_seed, uint64_t(b));
            origins.clear();
            dirs.clear();
            tfar.clear();
            for (const glm::vec3& e : eyes) {
                if (box.contains(e)) {
                    rejected[size_t(b)] = 1;  // an eye inside: not solid at all
                    break;
                }
                for (uint32_t k = 0; k < config.check_rays_per_eye; ++k) {
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
            ctx.progress_advance();
        }
    }
    ctx.progress_end();
    figures.check_rays = rays_total;

    if (shrunk != nullptr) {
        // The proven solid: the carved solid less every rejected box, then eroded: a voxel stays when every
        // voxel within k (Chebyshev) is proven solid; voxels within k of the grid's border go (outside the
        // grid is unknown).
        ScopedTimer t(ctx, "shrink");
        BitVolume proven = solid.solid;
        for (size_t b = 0; b < boxes.size(); ++b) {
            if (!rejected[b]) continue;
            const VoxelBox& vb = boxes[b];
            for (int z = vb.lo.z; z <= vb.hi.z; ++z)
                for (int y = vb.lo.y; y <= vb.hi.y; ++y)
                    for (int x = vb.lo.x; x <= vb.hi.x; ++x) proven.clear(grid.index(x, y, z));
        }
        BitVolume not_proven;
        not_proven.reset(grid.count());
        for (size_t w = 0; w < proven.words.size(); ++w) not_proven.words[w] = ~proven.words[w];
        BoxConfig sc = bc;
        sc.min_box_volume_m3 = 0.0;  // every shrunk box helps fusion
        sc.max_boxes = std::max<uint32_t>(bc.max_boxes, 1024);
        shrunk->epsilon_m.clear();
        shrunk->boxes.clear();
        shrunk->panels.clear();
        PanelFigures pf;
        const std::vector<Aabb> panels = find_panels(world, &pf);
        ctx.info(
            fmt::format("panels: {} opaque triangles lie in axis planes, {} rectangles are covered by pairs "
                        "of them, merged into {} panels",
                        pf.flat_triangles, pf.rectangles, pf.panels));
        for (int level = 0; level <= levels; ++level) {
            const double eps = epsilon_m * std::ldexp(1.0, level);
            const int k = std::max(1, int(std::ceil(eps / double(grid.voxel_size_m) - 1e-9)));
            const BitVolume near_not = dilate(grid, not_proven, k);
            BitVolume eroded;
            eroded.reset(grid.count());
            for (size_t w = 0; w < proven.words.size(); ++w)
                eroded.words[w] = proven.words[w] & ~near_not.words[w];
            for (uint64_t i = 0; i < grid.count(); ++i) {
                if (!eroded.get(i)) continue;
                const glm::ivec3 c = grid.coords(i);
                if (glm::any(glm::lessThan(c, glm::ivec3(k))) ||
                    glm::any(glm::greaterThanEqual(c, grid.dims - k))) {
                    eroded.clear(i);
                }
            }
            const std::vector<VoxelBox> shrunk_boxes = grow_boxes(ctx, grid, eroded, sc, nullptr);
            std::vector<Aabb> level_boxes;
            for (const VoxelBox& vb : shrunk_boxes) level_boxes.push_back(box_bounds(grid, vb));
            ctx.info(fmt::format("occluders shrunk by {} m ({} voxels): {} boxes of {:.0f} m3 of solid", eps,
                                 k, level_boxes.size(), double(eroded.count()) * voxel_m3));
            shrunk->epsilon_m.push_back(eps);
            shrunk->boxes.push_back(std::move(level_boxes));
            shrunk->panels.push_back(inset_panels(panels, kPanelInset * eps));
        }
        shrunk->free.origin = grid.origin;
        shrunk->free.voxel_size_m = grid.voxel_size_m;
        shrunk->free.dims = grid.dims;
        shrunk->free.bits.resize(proven.words.size());
        for (size_t w = 0; w < proven.words.size(); ++w)
            shrunk->free.bits[w] = ~(proven.words[w] | touched->words[w]);
        shrunk->solid.origin = grid.origin;
        shrunk->solid.voxel_size_m = grid.voxel_size_m;
        shrunk->solid.dims = grid.dims;
        shrunk->solid.bits = std::move(proven.words);
    }

    std::vector<Occluder> out;
    for (size_t b = 0; b < boxes.size(); ++b) {
        Occluder o;
        o.box = box_bounds(grid, boxes[b]);
        o.voxel_size_m = grid.voxel_size_m;
        o.proven = !rejected[b];
        figures.rejected_by_rays += rejected[b];
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
        for (size_t b = 0; b < boxes.size(); ++b) {
            if (rejected[b]) continue;
            const VoxelBox& vb = boxes[b];
            for (int z = vb.lo.z; z <= vb.hi.z; ++z)
                for (int y = vb.lo.y; y <= vb.hi.y; ++y)
                    for (int x = vb.lo.x; x <= vb.hi.x; ++x) covered.set(grid.index(x, y, z));
        }
        BitVolume near;
        if (!view.view.empty()) {
            BitVolume region;
            region.words = view.view.bits;
            near = dilate(grid, region, int(std::ceil(kNearViewM / grid.voxel_size_m)));
        }
        uint64_t n = 0, c = 0;
        for (size_t w = 0; w < solid.solid.words.size(); ++w) {
            const uint64_t s_near =
                solid.solid.words[w] & (near.words.empty() ? ~uint64_t(0) : near.words[w]);
            n += uint64_t(__builtin_popcountll(s_near));
            c += uint64_t(__builtin_popcountll(s_near & covered.words[w]));
        }
        figures.near_m3 = double(n) * voxel_m3;
        figures.near_covered_m3 = double(c) * voxel_m3;
    }
    figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.info(fmt::format(
        "occluders: {} boxes cover {:.0f} of {:.0f} m3 of solid ({:.1f}%), {:.1f}% of the {:.0f} m3 "
        "within {} m of the view region; the ray check ({:.1f} M rays) rejected {}; {:.2f} s",
        figures.kept, figures.covered_m3, figures.solid_m3,
        figures.solid_m3 > 0 ? 100.0 * figures.covered_m3 / figures.solid_m3 : 0.0,
        figures.near_m3 > 0 ? 100.0 * figures.near_covered_m3 / figures.near_m3 : 0.0, figures.near_m3,
        kNearViewM, double(figures.check_rays) * 1e-6, figures.rejected_by_rays, figures.seconds));
    return out;
}

}  // namespace pvs
