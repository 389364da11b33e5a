// The bake driver: wires the stages and gathers the figures of a bake.
#include "pvs/bake.h"

#include "cells/grid.h"
#include "cells/octree.h"
#include "cells/view_volume.h"
#include "core/error.h"
#include "pvs/conservative.h"
#include "pvs/embree_scene.h"
#include "pvs/occluder_ranking.h"
#include "pvs/occluder_synthesis.h"
#include "pvs/ray_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
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

void store_verification(const VerifyResult& result, VerificationRecord& record) {
    record.ran = true;
    record.figures = result.figures();
    record.cell_sampled_visible = result.cell_sampled_visible;
    record.misses = result.misses;
}

std::vector<Occluder> solver_occluders(Context& ctx, const BakeConfig& config, const World& world,
                                       const ViewVolume& view, const RayScene& scene,
                                       OccluderFigures& figures, BlockFigures& blocks,
                                       ShrunkOccluders& shrunk) {
    const bool conservative = config.mode == BakeMode::kConservative;
    // The epsilon ladder only as high as the cells' faces can use (conservative_levels_used()).
    const double largest_cell = largest_cell_edge_m(config.cells);
    std::vector<Occluder> boxes = synthesize_occluders(
        ctx, config.occluders, world, view, scene, figures, config.conservative.epsilon_m,
        conservative_levels_used(config.conservative, largest_cell), conservative ? &shrunk : nullptr);
    if (conservative && config.occluders.block_m > 0.0) {
        // Blocks of whole cells from the cells' origin (the view bounds' corner, for the grid and the
        // octree's roots), so that every cell lies in one block.
        const double block =
            largest_cell * std::max(1.0, std::round(config.occluders.block_m / largest_cell));
        blocks = synthesize_block_occluders(ctx, config.occluders, world, view, scene, view.view_bounds.min,
                                            float(block), shrunk);
    }
    return boxes;
}

BakeData bake_world(Context& ctx, const BakeConfig& config, const World& world, const std::string& world_path,
                    const std::string& world_hash) {
    validate(config);
    BakeData bake;
    bake.tool_version = tool_version();
    bake.world_path = world_path;
    bake.world_hash = world_hash;
    bake.mode = to_string(config.mode);
    bake.conservative = config.mode == BakeMode::kConservative;
    bake.parameters = resolved_parameters(config);
    bake.objects = object_records(world);

    ViewVolumeConfig view_config = config.view;
    if (config.mode == BakeMode::kConservative)
        view_config.auto_voxel_size_m = conservative_voxel_size_m(config.conservative.epsilon_m);
    const ViewVolume view = build_view_volume(ctx, view_config, world);
    RayScene scene(ctx, world, BuildQuality::kMedium, config.run.threads);
    bake.leak_path = view.leak_path;
    OccluderFigures occ;
    const bool conservative = config.mode == BakeMode::kConservative;
    ShrunkOccluders shrunk;
    BlockFigures blocks;
    if (config.occluders.enabled || conservative)
        bake.occluders = solver_occluders(ctx, config, world, view, scene, occ, blocks, shrunk);
    ConservativeFigures cons;
    uint32_t occluders_proven = 0;
    for (const Occluder& o : bake.occluders) occluders_proven += o.proven;
    uint64_t cells_dropped = 0;
    OctreeStats octree;
    SampledPvs sampled;
    if (config.cells.kind == CellKind::kGrid) {
        bake.cells = build_uniform_grid(ctx, config.cells, view.view_bounds);
        cells_dropped = clip_grid_to_view(ctx, bake.cells, view.view, view.eyes);
        if (conservative) {
            sampled.pvs =
                bake_conservative_pvs(ctx, config.conservative, world, bake.cells, shrunk, scene, cons);
        } else {
            sampled = bake_sampled_pvs(ctx, config.sampled, world, scene, bake.cells);
        }
    } else {
        // The octree asks the bake's mode for the PVS of every box it considers; the leaves' rows are
        // the bake's rows. The ray budget does not apply: boxes are not known in advance. The stage is
        // timed under the mode's name, as on the grid.
        ScopedTimer t(ctx, conservative ? "conservative_pvs" : "sampled_pvs");
        const auto start = std::chrono::steady_clock::now();
        CellSet masks;
        masks.view = view.view;
        masks.eyes = view.eyes;
        sampled.rays_per_eye = config.sampled.rays.rays_per_eye;
        // Built once for all the boxes the octree considers (pvs/region_hiding.h).
        std::optional<RegionHiders> hiders;
        if (conservative && config.conservative.single_occluder_pass) hiders.emplace(ctx, shrunk);
        // A conservative box tests only what its parent lists (RegionPvsOracle); the sampled mode's rows
        // prove nothing, so it samples every box afresh.
        const RegionPvsOracle oracle = [&](const std::vector<Aabb>& boxes,
                                           const std::vector<uint64_t>& streams,
                                           const std::vector<const uint64_t*>& bounds, PvsSet& rows) {
            if (conservative) {
                conservative_box_rows(ctx, config.conservative, world, boxes, masks.eyes, shrunk, scene, rows,
                                      cons, hiders ? &*hiders : nullptr, &bounds);
                return;
            }
            sample_box_rows(config.sampled, world, scene, masks, boxes, streams, sampled.rays_per_eye, rows,
                            sampled.guard_band_added, &ctx);
            sampled.rays += uint64_t(boxes.size()) * config.sampled.rays.eyes_per_cell * sampled.rays_per_eye;
        };
        bake.cells = build_octree(ctx, config.cells, masks, view.view_bounds, uint32_t(world.objects.size()),
                                  oracle, sampled.pvs, octree);
        add_always_listed(world, bake.cells, sampled.pvs);
        if (conservative) {
            ctx.info(
                fmt::format("conservative PVS: {} boxes evaluated; {:.2f} M (box, object) pairs left out "
                            "untested because the box's parent left them out, {:.2f} M proven hidden "
                            "by one occluder, {:.1f} s",
                            octree.evaluated, double(cons.parent_hidden) * 1e-6,
                            double(cons.region_hidden) * 1e-6, cons.seconds));
        }
        sampled.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    bake.pvs = std::move(sampled.pvs);
    // Ranked occluders per cell (issue 9): once the cells are final (the octree's depend on the PVS).
    RankingFigures ranking;
    if (!bake.occluders.empty()) {
        bake.ranked = rank_occluders(ctx, config.ranking, world, bake.cells, bake.occluders, ranking);
    }
    double edge_sum = 0.0, edge_max = 0.0;
    for (const Cell& c : bake.cells.cells) {
        edge_sum += c.bounds.size().x;
        edge_max = std::max(edge_max, double(c.bounds.size().x));
    }
    const double edge_mean = bake.cells.size() ? edge_sum / double(bake.cells.size()) : 0.0;

    uint64_t listed = 0, listed_max = 0;
    for (uint32_t c = 0; c < bake.cells.size(); ++c) {
        const uint64_t n = bake.pvs.count(c);
        listed += n;
        listed_max = std::max(listed_max, n);
    }
    const double n_cells = std::max<double>(1.0, double(bake.cells.size()));
    bake.figures = {
        {"objects", double(world.objects.size())},
        {"triangles", double(world.triangles.size())},
        {"cells", double(bake.cells.size())},
        {"cells_dropped_outside_view_volume", double(cells_dropped)},
        {"cells_octree", config.cells.kind == CellKind::kOctree ? 1.0 : 0.0},
        {"cell_size_mean_m", edge_mean},
        {"cell_size_max_m", edge_max},
        {"octree_splits_by_visibility", double(octree.splits)},
        {"octree_merged_back", double(octree.merged)},
        {"octree_boxes_evaluated", double(octree.evaluated)},
        {"octree_depth", double(octree.depth)},
        {"view_volume_m3", view.view_volume_m3},
        {"view_eye_space_m3", view.eye_volume_m3},
        {"world_bounds_m3", view.world_bounds_m3},
        {"view_volume_share_of_bounds", view.view_volume_m3 / std::max(1e-9, view.world_bounds_m3)},
        {"view_voxel_size_m", view.voxelized ? double(view.view.voxel_size_m) : 0.0},
        {"view_flooded", view.flooded ? 1.0 : 0.0},
        {"view_leaked", view.leaked ? 1.0 : 0.0},
        {"view_leak_path_points", double(view.leak_path.size())},
        {"view_seeds_used", double(view.seeds_used)},
        {"occluder_solid_m3", occ.solid_m3},
        {"occluder_boxes", double(bake.occluders.size())},
        {"occluder_boxes_proven", double(occluders_proven)},
        {"occluder_covered_share_of_solid", occ.solid_m3 > 0 ? occ.covered_m3 / occ.solid_m3 : 0.0},
        {"occluder_covered_share_of_solid_near_view",
         occ.near_m3 > 0 ? occ.near_covered_m3 / occ.near_m3 : 0.0},
        {"occluder_probe_rays_into_solid", double(occ.probe_rays_into_solid)},
        {"occluder_seal_leaks", double(occ.seal_leaks)},
        {"occluder_seal_removed_voxels", double(occ.seal_removed_voxels)},
        {"occluder_seconds", occ.seconds},
        {"occluder_blocks", double(blocks.blocks)},
        {"occluder_blocks_with_own_occluders", double(blocks.blocks_used)},
        {"occluder_block_solid_m3", blocks.solid_m3},
        {"occluder_block_global_solid_m3", blocks.global_solid_m3},
        {"occluder_block_rays", double(blocks.rays)},
        {"occluder_block_seconds", blocks.seconds},
        {"ranked_occluders_per_cell_mean",
         bake.cells.size() ? double(ranking.ranked) / double(bake.cells.size()) : 0.0},
        {"ranked_occluders_cells_with_none", double(ranking.cells_with_none)},
        {"ranked_occluder_score_mean", ranking.score_mean},
        {"ranked_occluder_solid_angle_mean_sr", ranking.solid_angle_mean_sr},
        {"ranked_occluder_hidden_triangle_share_mean", ranking.hidden_triangle_share_mean},
        {"ranking_seconds", ranking.seconds},
        {"conservative_shrunk_occluders", shrunk.boxes.empty() ? 0.0 : double(shrunk.boxes[0].size())},
        {"conservative_epsilon_levels", double(shrunk.epsilon_m.size())},
        {"conservative_samples", double(cons.samples)},
        {"conservative_samples_in_occluders", double(cons.samples_skipped)},
        {"conservative_patches_in_solid", double(cons.patches_in_solid)},
        {"conservative_object_tests", double(cons.object_tests)},
        {"conservative_fine_samples", double(cons.fine_samples)},
        {"conservative_panel_splits", double(cons.panel_splits)},
        {"conservative_known_listed", double(cons.known_listed)},
        {"conservative_region_hidden", double(cons.region_hidden)},
        {"conservative_parent_hidden", double(cons.parent_hidden)},
        {"conservative_region_seconds", cons.region_seconds},
        {"conservative_patch_hidden", double(cons.patch_hidden)},
        {"conservative_seconds", cons.seconds},
        {"cells_per_second", cons.seconds > 0
                                 ? double(bake.cells.size()) / cons.seconds
                                 : (sampled.seconds > 0 ? double(bake.cells.size()) / sampled.seconds : 0.0)},
        {"pvs_objects_mean", double(listed) / n_cells},
        {"pvs_objects_max", double(listed_max)},
        {"pvs_share_of_objects_mean",
         double(listed) / n_cells / std::max<double>(1.0, double(world.objects.size()))},
        {"sampled_rays", double(sampled.rays)},
        {"sampled_rays_per_eye", double(sampled.rays_per_eye)},
        {"sampled_eyes_per_cell", double(config.sampled.rays.eyes_per_cell)},
        {"sampled_rays_per_second", sampled.seconds > 0 ? double(sampled.rays) / sampled.seconds : 0.0},
        {"sampled_guard_band_added", double(sampled.guard_band_added)},
        {"degenerate_triangles_dropped", double(world.stats.degenerate_triangles_dropped)},
    };

    if (config.verify.enabled) {
        if (config.verify.rays.seed == config.sampled.rays.seed) {
            ctx.warn(
                "verify: the verification seed equals the bake's: it will only replay the bake's own rays");
        }
        const VerifyResult result = verify_pvs(ctx, config.verify, world, scene, bake.cells, bake.pvs);
        log_verify_summary(ctx, result, world);
        store_verification(result, bake.verification);
    }
    return bake;
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
