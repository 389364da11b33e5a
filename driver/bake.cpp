// SPDX-License-Identifier: MIT
// The bake driver: wires the stages and gathers the figures of a bake.
#include "driver/bake.h"

#include "cells/grid.h"
#include "cells/octree.h"
#include "cells/view_volume.h"
#include "cells/world_extent.h"
#include "core/error.h"
#include "core/object_parts.h"
#include "driver/memory_plan.h"
#include "driver/report.h"
#include "driver/verify_boxes.h"
#include "io/runtime_file.h"
#include "occluders/cell_ranking.h"
#include "occluders/slanted_panels.h"
#include "occluders/synthesis.h"
#include "pvs/conservative.h"
#include "pvs/reuse.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>

#ifndef PVSBAKE_VERSION
#define PVSBAKE_VERSION "0.0.0"
#endif

namespace pvs {

const char* tool_version() {
    return PVSBAKE_VERSION;
}

std::vector<ObjectRecord> object_records(const World& world) {
    std::vector<ObjectRecord> out;
    out.reserve(world.objects.size());
    for (const WorldObject& o : world.objects)
        out.push_back(ObjectRecord{o.name, o.bounds, o.triangle_count, o.flags});
    return out;
}

ViewVolumeConfig view_volume_config(const BakeConfig& config) {
    ViewVolumeConfig view = config.view;
    if (config.mode == BakeMode::kConservative) {
        view.auto_voxel_size_m = conservative_voxel_size_m(config.conservative.epsilon_m);
        view.need_sources = true;
    }
    view.cell_edge_m =
        config.cells.kind == CellKind::kGrid ? config.cells.cell_size_m : config.cells.min_cell_size_m;
    return view;
}

double gap_tolerance_of(const BakeData& bake) {
    return config_from_parameters(bake.parameters).gap.tolerance_m;
}

void store_verification(const VerifyResult& result, BakeData& bake) {
    VerificationRecord& record = bake.verification;
    record.ran = true;
    record.figures = result.figures();
    // The run's timing of the verification replaces an earlier one (`pvsbake verify` writing back).
    const NamedValues timing = result.run_figures();
    std::erase_if(bake.run.figures, [&](const auto& f) {
        return std::any_of(timing.begin(), timing.end(), [&](const auto& t) { return t.first == f.first; });
    });
    bake.run.figures.insert(bake.run.figures.end(), timing.begin(), timing.end());
    record.cell_sampled_visible = result.cell_sampled_visible;
    record.misses = result.misses;
}

void verify_ranked_boxes(Context& ctx, const RayScene& scene, uint64_t seed, BakeData& bake) {
    if (bake.ranked.empty()) return;
    const RankedBoxCheck check = check_ranked_boxes(ctx, scene, bake.cells, bake.occluders, bake.ranked, seed);
    bake.verification.figures.emplace_back("ranked_boxes_checked", double(check.boxes));
    bake.verification.figures.emplace_back("ranked_box_rays", double(check.rays));
    bake.verification.figures.emplace_back("ranked_boxes_seen_into", double(check.seen_into));
}

std::vector<Occluder> solver_occluders(Context& ctx, const BakeConfig& config, const World& world,
                                       const ViewVolume& view, const RayScene& scene,
                                       OccluderFigures& figures, BlockFigures& blocks,
                                       ShrunkOccluders& shrunk, WorkShare* share) {
    const bool conservative = config.mode == BakeMode::kConservative;
    // The epsilon ladder only as high as the cells' faces can use (conservative_levels_used()).
    const double largest_cell = largest_cell_edge_m(config.cells);
    OccluderConfig occluders = config.occluders;
    occluders.gap_tolerance_m = config.gap.tolerance_m;
    std::vector<Occluder> boxes = synthesize_occluders(
        ctx, occluders, world, view, scene, figures, config.conservative.epsilon_m,
        conservative_levels_used(config.conservative, largest_cell), conservative ? &shrunk : nullptr, share);
    if (conservative && config.occluders.block_m > 0.0) {
        // Blocks of whole cells from the cells' origin (the view bounds' corner, for the grid and the
        // octree's roots), so that every cell lies in one block.
        const double block =
            largest_cell * std::max(1.0, std::round(config.occluders.block_m / largest_cell));
        blocks = synthesize_block_occluders(ctx, occluders, world, view, scene, view.view_bounds.min,
                                            float(block), shrunk);
    }
    return boxes;
}

namespace {

int worker_threads(const BakeConfig& config) {
    return config.run.threads > 0 ? config.run.threads : omp_get_max_threads();
}

// The most cells a partition of `bounds` can make: the grid's, or the octree's finest (capped by max_cells).
uint64_t most_cells(const CellConfig& cells, const Aabb& bounds) {
    const double edge = cells.kind == CellKind::kGrid ? cells.cell_size_m : cells.min_cell_size_m;
    const glm::dvec3 n = glm::ceil(glm::dvec3(bounds.size()) / edge) + 1.0;
    const double most = n.x * n.y * n.z;
    if (cells.kind == CellKind::kOctree && cells.max_cells > 0) return std::min<uint64_t>(cells.max_cells, uint64_t(most));
    return uint64_t(std::min(most, 1e18));
}

// The header of a bake: the tool, the world, the mode, the resolved parameters and the objects.
BakeData bake_header(const BakeConfig& config, const World& world, const std::string& world_path,
                     const std::string& world_hash) {
    BakeData bake;
    bake.tool_version = tool_version();
    bake.world_path = world_path;
    bake.world_hash = world_hash;
    bake.mode = to_string(config.mode);
    bake.conservative = config.mode == BakeMode::kConservative;
    for (auto& p : resolved_parameters(config))
        (is_run_parameter(p.first) ? bake.run.parameters : bake.parameters).push_back(std::move(p));
    bake.objects = object_records(world);
    return bake;
}

// The grid's cells, clipped to the view volume, then every cell's PVS in the bake's mode.
void grid_cells_and_pvs(Context& ctx, const BakeConfig& config, const World& world, const ViewVolume& view,
                        const RayScene& scene, const ShrunkOccluders& shrunk, BakeData& bake,
                        StageFigures& figures, RowJournal* journal, WorkShare* share, const BakeData* reuse) {
    bake.cells = build_uniform_grid(ctx, config.cells, view.view_bounds);
    figures.cells_dropped = clip_grid_to_view(ctx, bake.cells, view.view, view.eyes);
    {
        const MemoryPlan plan =
            plan_memory(config, world, view.grid.count(), bake.cells.size(), worker_threads(config));
        ctx.info(fmt::format("memory plan: {}", describe(plan)));
        check_memory(plan, max_memory_bytes(config.run), "the PVS");
    }
    if (config.mode == BakeMode::kConservative) {
        std::optional<ReusePlan> plan;
        if (reuse) {
            // The shaft pass's cap is decided by the cells and objects (docs/ALGORITHMS.md#shaft-cap): an old
            // bake that decided otherwise holds rows this bake would not compute, so it cannot be reused.
            // Which objects it tried too: all, or the heaviest the cap allows (a digest of their names).
            double skipped = 0.0, old_objects = -1.0, old_digest = 0.0;
            for (const auto& [name, value] : reuse->figures) {
                if (name == "conservative_shaft_skipped_candidates") skipped = value;
                if (name == "conservative_shaft_objects") old_objects = value;
                if (name == "conservative_shaft_objects_digest") old_digest = value;
            }
            // (a bake file without the objects' figure ran the pass on all of them or on none)
            const bool ran = config.conservative.shaft_budget > 0 &&
                             (old_objects >= 0.0 ? old_objects > 0.0 : skipped == 0.0);
            const uint64_t regions = grid_shaft_regions(config.conservative, bake.cells);
            const std::vector<uint32_t> chosen = shaft_objects(config.conservative, world, regions);
            const bool runs = !chosen.empty();
            if (ran != runs) {
                throw bad_input(fmt::format(
                    "--reuse: the old bake {} the shaft pass and this one would {}: {} cells "
                    "x the objects {} --shaft-max-pairs {} now; bake without --reuse",
                    ran ? "ran" : "did not run", runs ? "run it" : "not", regions,
                    runs ? "allow it within" : "are over it at", config.conservative.shaft_max_pairs));
            }
            if (runs && old_digest != shaft_objects_digest(world, chosen)) {
                throw bad_input(fmt::format(
                    "--reuse: the old bake's shaft pass tried other objects than this one would ({} of {} "
                    "now: the cap --shaft-max-pairs {} over {} cells takes those with the most triangles); "
                    "bake without --reuse",
                    chosen.size(), leavable_count(world), config.conservative.shaft_max_pairs, regions));
            }
            // A small bake's pair budget follows its cells and objects too (docs/ALGORITHMS.md#shaft-small).
            double old_budget = runs ? double(config.conservative.shaft_budget) : 0.0;
            for (const auto& [name, value] : reuse->figures)
                if (name == "conservative_shaft_pair_budget") old_budget = value;
            const int budget = runs ? shaft_pair_budget(config.conservative, world, regions) : 0;
            if (runs && old_budget != double(budget)) {
                throw bad_input(fmt::format(
                    "--reuse: the old bake's shaft pass gave each (cell, object) {} piece pairs and this one "
                    "would give {} ({} cells x the objects, --shaft-small-spend {}); bake without --reuse",
                    old_budget, budget, regions, config.conservative.shaft_small_spend));
            }
            ScopedTimer t(ctx, "reuse_plan");
            plan = plan_reuse(ctx, config.conservative, world, bake.cells, bake.print,
                              ReuseSource{reuse->cells, reuse->pvs, reuse->print});
            figures.reuse = plan->figures;
            if (!plan->whole.empty()) {
                ctx.warn(fmt::format("--reuse: nothing is kept from the old bake: {}", plan->whole));
                plan.reset();
            }
        }
        bake.pvs = bake_conservative_pvs(ctx, config.conservative, world, bake.cells, shrunk, scene,
                                         figures.conservative, journal, share, plan ? &*plan : nullptr);
    } else {
        SampledPvs sampled = bake_sampled_pvs(ctx, config.sampled, world, scene, bake.cells);
        bake.pvs = std::move(sampled.pvs);
        figures.sampled = {sampled.rays, sampled.rays_per_eye, sampled.guard_band_added, sampled.seconds};
    }
}

// The octree's cells and PVS together: the octree asks the bake's mode for the PVS of every box it
// considers, and the leaves' rows are the bake's rows (docs/ALGORITHMS.md#octree). The ray budget does not
// apply: boxes are not known in advance. Timed under the mode's name, as on the grid.
void octree_cells_and_pvs(Context& ctx, const BakeConfig& config, const World& world, const ViewVolume& view,
                          const RayScene& scene, const ShrunkOccluders& shrunk, BakeData& bake,
                          StageFigures& figures, RowJournal* journal, WorkShare* share) {
    const bool conservative = config.mode == BakeMode::kConservative;
    ScopedTimer t(ctx, conservative ? "conservative_pvs" : "sampled_pvs");
    const auto start = std::chrono::steady_clock::now();
    CellSet masks;
    masks.view = view.view;
    masks.eyes = view.eyes;
    SampledFigures& sampled = figures.sampled;
    sampled.rays_per_eye = config.sampled.rays.rays_per_eye;
    // Built once for all the boxes the octree considers (pvs/region_hiding.h, pvs/shaft_hiding.h).
    std::optional<RegionHiders> hiders;
    if (conservative && config.conservative.single_occluder_pass) hiders.emplace(ctx, shrunk);
    std::optional<ShaftProvers> provers;  // built at the first level the shaft pass runs on
    // A conservative box tests only what its parent lists (docs/ALGORITHMS.md#octree-parent-bound); the
    // sampled mode's rows prove nothing, so it samples every box afresh.
    const RegionPvsOracle oracle = [&](const std::vector<Aabb>& boxes, const std::vector<uint64_t>& streams,
                                       const std::vector<const uint64_t*>& bounds, PvsSet& rows) {
        if (conservative) {
            // The shaft pass's cap, for the cells these boxes can still split into
            // (docs/ALGORITHMS.md#shaft-cap).
            ConservativeConfig level = config.conservative;
            const uint64_t reach = octree_shaft_regions(boxes, config.cells.min_cell_size_m);
            level.shaft_budget = shaft_pair_budget(level, world, reach);  // docs/ALGORITHMS.md#shaft-small
            const size_t chosen = shaft_objects(level, world, reach).size();
            if (level.shaft_budget > 0 && chosen == 0) {
                level.shaft_budget = 0;
                const uint64_t candidates = shaft_candidates(world, reach);
                figures.conservative.shaft.skipped_candidates += candidates;
                ctx.info(fmt::format(
                    "shaft pass: not run on {} octree boxes: the {} cells they can split into "
                    "x the objects = {} candidate pairs, over --shaft-max-pairs {}, and the "
                    "objects with the most triangles that fit hold less than "
                    "--shaft-min-share {} of them",
                    boxes.size(), reach, candidates, level.shaft_max_pairs, level.shaft_min_share));
            } else if (level.shaft_budget > 0 && chosen < leavable_count(world) &&
                       level.shaft_max_pairs > 0) {
                // The heaviest objects the cap allows over those cells: the boxes' own rule then chooses
                // the same ones (floor(chosen x boxes / boxes) of them).
                level.shaft_max_pairs = uint64_t(chosen) * uint64_t(std::max<size_t>(boxes.size(), 1));
            }
            if (!provers && level.shaft_budget > 0)
                provers.emplace(ctx, shrunk, level.shaft_fusion, level.shaft_caps, level.shaft_cups,
                                level.shaft_flood);
            // A box's stream names it in every run (its node's index): the journal's key.
            conservative_box_rows(ctx, level, world, boxes, masks.eyes, shrunk, scene, rows,
                                  figures.conservative, hiders ? &*hiders : nullptr, &bounds,
                                  provers ? &*provers : nullptr, journal, &streams, share);
            if (journal) journal->flush();  // an octree level is a stage's end
            return;
        }
        sample_box_rows(config.sampled, world, scene, masks, boxes, streams, sampled.rays_per_eye, rows,
                        sampled.guard_band_added, &ctx);
        sampled.rays += uint64_t(boxes.size()) * config.sampled.rays.eyes_per_cell * sampled.rays_per_eye;
    };
    bake.cells = build_octree(ctx, config.cells, masks, view.view_bounds, uint32_t(world.objects.size()),
                              oracle, bake.pvs, figures.octree);
    add_always_listed(world, bake.cells, bake.pvs);
    if (conservative) {
        const ConservativeFigures& cons = figures.conservative;
        ctx.info(
            fmt::format("conservative PVS: {} boxes evaluated; {:.2f} M (box, object) pairs left out "
                        "untested because the box's parent left them out, {:.2f} M proven hidden "
                        "by one occluder, {:.1f} s",
                        figures.octree.evaluated, double(cons.parent_hidden) * 1e-6,
                        double(cons.region_hidden) * 1e-6, cons.seconds));
    }
    sampled.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BakeData bake_world(Context& ctx, const BakeConfig& config, const World& world, const std::string& world_path,
                    const std::string& world_hash, RowJournal* journal, WorkShare* share,
                    const BakeData* reuse) {
    validate(config);
    const bool conservative = config.mode == BakeMode::kConservative;
    if (share && !conservative) {
        // The sampled mode is not dealt: rank 0 bakes it alone.
        const bool root = share->rank() == 0;
        share->close();
        if (!root) return bake_header(config, world, world_path, world_hash);
        ctx.warn("the sampled mode runs on rank 0 alone; the other processes wait");
        share = nullptr;
    }
    BakeData bake = bake_header(config, world, world_path, world_hash);
    StageFigures figures;

    // 1. View volume: where eyes can be (docs/ALGORITHMS.md#view-volume), once the memory plan of its voxels
    //    (and of at most as many cells as the world's bounds hold) is within the limit.
    const ViewVolumeConfig view_config = view_volume_config(config);
    {
        const VoxelGrid grid = planned_view_grid(view_config, world);
        MemoryPlan plan = plan_memory(config, world, grid.count(), most_cells(config.cells, world.bounds),
                                      worker_threads(config));
        plan.cells_bound = true;
        ctx.info(fmt::format("memory plan: {}; this bake may use {:.2f} GiB", describe(plan),
                             max_memory_bytes(config.run) / double(uint64_t(1) << 30)));
        try {
            check_memory(plan, max_memory_bytes(config.run), "the view volume and occluders");
        } catch (const Error& e) {
            const std::string strays = describe_reaches(world, stray_objects(world, 3));
            if (strays.empty()) throw;
            throw Error(e.kind(), fmt::format("{}; the world's bounds are that large because {}", e.what(), strays));
        }
    }
    const ViewVolume view = build_view_volume(ctx, view_config, world);
    bake.leak_path = view.leak_path;

    // 2. The world as a ray-tracing scene, for every stage that traces rays.
    RayScene scene(ctx, world, BuildQuality::kMedium, config.run.threads);

    // 3. Occluders: the proven solid, its boxes (stored), and the solver's shrunk occluders.
    ShrunkOccluders shrunk;
    if (config.occluders.enabled || conservative) {
        bake.occluders =
            solver_occluders(ctx, config, world, view, scene, figures.occluders, figures.blocks, shrunk, share);
    }
    // What a later re-bake after an edit compares (docs/ALGORITHMS.md#reuse).
    if (conservative) {
        ScopedTimer t(ctx, "geometry_print");
        bake.print = geometry_print(config.conservative, world, shrunk, view.eyes);
    }

    // 4. Cells and their PVS (docs/ALGORITHMS.md#conservative-pvs): a grid, then each cell's row; or an
    //    octree, split where the rows of its children differ.
    if (config.cells.kind == CellKind::kGrid) {
        grid_cells_and_pvs(ctx, config, world, view, scene, shrunk, bake, figures, journal, share, reuse);
    } else {
        if (reuse) ctx.warn("--reuse: octree cells are baked in full (a reuse keeps the rows of grid cells)");
        octree_cells_and_pvs(ctx, config, world, view, scene, shrunk, bake, figures, journal, share);
    }
    // 5. Ranked occluders per cell, once the cells are final (the octree's depend on the PVS); dealt like
    //    the PVS (every process ends the stages before the PVS with the same occluders).
    //    By sight, the panels at least --ranking-panel-area large join the proven occluders (stored with
    //    them, flat along their plane: docs/ALGORITHMS.md#ranking-sight).
    if (config.ranking.sight_lines > 0 && config.ranking.occluders_per_cell > 0) {
        for (const Aabb& p : shrunk.panels) {
            const glm::vec3 s = p.size();
            const float area = s.x == 0.0f ? s.y * s.z : s.y == 0.0f ? s.x * s.z : s.x * s.y;
            if (double(area) < config.ranking.min_panel_area_m2) continue;
            Occluder o;
            o.box = p;
            o.proven = true;  // every point of the rectangle lies in an opaque triangle
            bake.occluders.push_back(o);
        }
        if (config.ranking.polygons)
            bake.polygons = runtime_polygons(shrunk.slanted, config.ranking.min_panel_area_m2);
    }
    if (!bake.occluders.empty() || !bake.polygons.empty()) {
        bake.ranked = rank_occluders(ctx, config.ranking, world, bake.cells, bake.occluders, figures.ranking,
                                     share, &bake.pvs, &bake.polygons);
    }
    // 5b. The objects' part boxes for the run-time tests (docs/ALGORITHMS.md#object-parts).
    bake.object_parts = object_parts(world, config.ranking.object_parts);
    round_parts_to_runtime_grid(world, bake.object_parts);
    // 5c. The run-time horizon's list of proven occluders per block of cells, chosen by the runtime's own
    //     horizon from seeded eyes (docs/ALGORITHMS.md#horizon-lists): the proven boxes, every panel, and the
    //     slanted panels as tiles are the candidates.
    if (config.ranking.horizon_eyes > 0 && (config.occluders.enabled || conservative)) {
        std::vector<Aabb> candidates;
        for (const Occluder& o : bake.occluders) {
            const glm::vec3 s = o.box.size();
            if (o.proven && s.x > 0.0f && s.y > 0.0f && s.z > 0.0f) candidates.push_back(o.box);
        }
        candidates.insert(candidates.end(), shrunk.panels.begin(), shrunk.panels.end());
        bake.horizon = choose_horizon_lists(ctx, config.ranking, world, bake.cells, bake.pvs, candidates,
                                            runtime_tiles(shrunk.slanted, 0.0), figures.horizon, share,
                                            &bake.object_parts);
    }
    // 6. The figures of the bake (driver/report.h).
    figures.shrunk_boxes = shrunk.boxes.empty() ? 0 : shrunk.boxes[0].size();
    figures.epsilon_levels = shrunk.epsilon_m.size();
    bake.figures = bake_figures(config, world, view, bake, figures);
    bake.run.figures = run_figures(bake, figures);

    // 7. Verification by rays (docs/ALGORITHMS.md#verification), its passes dealt like the PVS's.
    if (config.verify.enabled) {
        if (config.verify.rays.seed == config.sampled.rays.seed) {
            ctx.warn(
                "verify: the verification seed equals the bake's: it will only replay the bake's own rays");
        }
        VerifyConfig verify = config.verify;
        verify.gap_tolerance_m = config.gap.tolerance_m;
        const VerifyResult result = verify_pvs(ctx, verify, world, scene, bake.cells, bake.pvs, share);
        log_verify_summary(ctx, result, world);
        store_verification(result, bake);
        verify_ranked_boxes(ctx, scene, verify.rays.seed, bake);
    }
    // Every process holds the whole bake now; rank 0 alone writes it.
    if (share) share->close();
    return bake;
}

void check_reuse(const BakeConfig& config, const BakeData& old, const std::string& old_path) {
    if (!old.conservative)
        throw bad_input(fmt::format("--reuse {}: not a conservative bake (mode {})", old_path, old.mode));
    std::map<std::string, std::string> before(old.parameters.begin(), old.parameters.end());
    for (const auto& [name, value] : resolved_parameters(config)) {
        if (is_run_parameter(name) || is_ranking_parameter(name)) continue;
        const auto it = before.find(name);
        if (it == before.end() || it->second != value) {
            throw bad_input(
                fmt::format("--reuse {}: it was baked with {} = {}, this bake has {}: a re-bake reuses only "
                            "a bake of the "
                            "same parameters",
                            old_path, name, it == before.end() ? "(none)" : it->second, value));
        }
    }
    if (config.occluders.block_m > 0.0)
        throw bad_input("--reuse: not with --occluder-block (occluders per block are not printed)");
}

void check_bake_matches_world(Context& ctx, const BakeData& bake, const World& world,
                              const std::string& world_hash) {
    if (bake.objects.size() != world.objects.size()) {
        throw bad_input(
            fmt::format("the bake lists {} objects but the world {} has {}: not the world it was baked from",
                        bake.objects.size(), world.source_path, world.objects.size()));
    }
    for (size_t i = 0; i < world.objects.size(); ++i) {
        if (bake.objects[i].name != world.objects[i].name) {
            throw bad_input(
                fmt::format("object {} is '{}' in the bake but '{}' in the world {}: not the world it was "
                            "baked from",
                            i, bake.objects[i].name, world.objects[i].name, world.source_path));
        }
    }
    if (!bake.world_hash.empty() && bake.world_hash != world_hash) {
        ctx.warn(fmt::format(
            "the world file {} changed since the bake (hash {} then, {} now); objects still match",
            world.source_path, bake.world_hash, world_hash));
    }
}

}  // namespace pvs
