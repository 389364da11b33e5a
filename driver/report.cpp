// SPDX-License-Identifier: MIT
// The figures of a bake and its JSON report.
#include "driver/report.h"

#include "driver/bake.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>

namespace pvs {

NamedValues bake_figures(const BakeConfig& config, const World& world, const ViewVolume& view,
                         const BakeData& bake, const StageFigures& stages) {
    uint32_t occluders_proven = 0;
    for (const Occluder& o : bake.occluders) occluders_proven += o.proven;
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
    return {
        {"objects", double(world.objects.size())},
        {"triangles", double(world.triangles.size())},
        {"cells", double(bake.cells.size())},
        {"cells_dropped_outside_view_volume", double(stages.cells_dropped)},
        {"cells_octree", config.cells.kind == CellKind::kOctree ? 1.0 : 0.0},
        {"cell_size_mean_m", edge_mean},
        {"cell_size_max_m", edge_max},
        {"octree_splits_by_visibility", double(stages.octree.splits)},
        {"octree_depth", double(stages.octree.depth)},
        {"view_volume_m3", view.view_volume_m3},
        {"view_eye_space_m3", view.eye_volume_m3},
        {"world_bounds_m3", view.world_bounds_m3},
        {"view_volume_share_of_bounds", view.view_volume_m3 / std::max(1e-9, view.world_bounds_m3)},
        {"view_voxel_size_m", view.voxelized ? double(view.view.voxel_size_m) : 0.0},
        {"view_flooded", view.flooded ? 1.0 : 0.0},
        {"view_leaked", view.leaked ? 1.0 : 0.0},
        {"view_leak_path_points", double(view.leak_path.size())},
        {"view_seeds_used", double(view.seeds_used)},
        {"occluder_solid_m3", stages.occluders.solid_m3},
        {"occluder_boxes", double(bake.occluders.size())},
        {"occluder_boxes_proven", double(occluders_proven)},
        {"occluder_covered_share_of_solid",
         stages.occluders.solid_m3 > 0 ? stages.occluders.covered_m3 / stages.occluders.solid_m3 : 0.0},
        {"occluder_covered_share_of_solid_near_view",
         stages.occluders.near_m3 > 0 ? stages.occluders.near_covered_m3 / stages.occluders.near_m3 : 0.0},
        {"occluder_probe_rays_into_solid", double(stages.occluders.probe_rays_into_solid)},
        {"occluder_probe_rays_narrow", double(stages.occluders.probe_rays_narrow)},
        {"occluder_gap_gaps", double(stages.occluders.gap_gaps)},
        {"occluder_gap_leaks", double(stages.occluders.gap_leaks)},
        {"occluder_gap_removed_voxels", double(stages.occluders.gap_removed_voxels)},
        {"occluder_seal_leaks", double(stages.occluders.seal_leaks)},
        {"occluder_seal_narrow", double(stages.occluders.seal_narrow)},
        {"occluder_seal_removed_voxels", double(stages.occluders.seal_removed_voxels)},
        {"occluder_blocks", double(stages.blocks.blocks)},
        {"occluder_blocks_with_own_occluders", double(stages.blocks.blocks_used)},
        {"occluder_block_solid_m3", stages.blocks.solid_m3},
        {"occluder_block_global_solid_m3", stages.blocks.global_solid_m3},
        {"occluder_block_rays", double(stages.blocks.rays)},
        {"ranked_occluders_per_cell_mean",
         bake.cells.size() ? double(stages.ranking.ranked) / double(bake.cells.size()) : 0.0},
        {"ranked_occluders_cells_with_none", double(stages.ranking.cells_with_none)},
        {"ranked_occluder_score_mean", stages.ranking.score_mean},
        {"ranked_occluder_solid_angle_mean_sr", stages.ranking.solid_angle_mean_sr},
        {"ranked_occluder_hidden_triangle_share_mean", stages.ranking.hidden_triangle_share_mean},
        {"horizon_candidates", double(stages.horizon.candidates)},
        {"horizon_occluders", double(stages.horizon.kept)},
        {"horizon_lists", double(stages.horizon.lists)},
        {"horizon_lists_per_cell", stages.horizon.per_cell ? 1.0 : 0.0},
        {"horizon_list_entries_mean",
         stages.horizon.lists ? double(stages.horizon.entries) / double(stages.horizon.lists) : 0.0},
        {"horizon_list_entries_max", double(stages.horizon.largest_list)},
        // The objects a cell's frames give the horizon, on average (0: every object;
        // docs/ALGORITHMS.md#horizon-tests).
        {"horizon_tests_mean",
         bake.cells.size() ? double(stages.horizon.tests) / double(bake.cells.size()) : 0.0},
        {"horizon_eyes", double(stages.horizon.eyes)},
        {"horizon_pieces_dropped", double(stages.horizon.pieces_dropped)},
        {"conservative_shrunk_occluders", double(stages.shrunk_boxes)},
        {"conservative_epsilon_levels", double(stages.epsilon_levels)},
        // The shaft pass's cap (docs/ALGORITHMS.md#shaft-cap): regions x objects of the passes not run.
        {"conservative_shaft_skipped_candidates", double(stages.conservative.shaft.skipped_candidates)},
        // A small bake's pair budget (docs/ALGORITHMS.md#shaft-small): the largest a pass gave a pair.
        {"conservative_shaft_pair_budget", double(stages.conservative.shaft_pair_budget)},
        // The objects the pass tried (docs/ALGORITHMS.md#shaft-cap): the fewest a pass was given, the share
        // of the leavable objects' triangles they hold, and a digest of which (0: all of them).
        {"conservative_shaft_objects", double(stages.conservative.shaft_objects)},
        {"conservative_shaft_objects_triangle_share", stages.conservative.shaft_objects_triangle_share},
        {"conservative_shaft_objects_digest", stages.conservative.shaft_objects_digest},
        {"pvs_objects_mean", double(listed) / n_cells},
        {"pvs_objects_max", double(listed_max)},
        {"pvs_share_of_objects_mean",
         double(listed) / n_cells / std::max<double>(1.0, double(world.objects.size()))},
        {"sampled_rays_per_eye", double(stages.sampled.rays_per_eye)},
        {"sampled_eyes_per_cell", double(config.sampled.rays.eyes_per_cell)},
        {"degenerate_triangles_dropped", double(world.stats.degenerate_triangles_dropped)},
    };
}

NamedValues run_figures(const BakeData& bake, const StageFigures& stages) {
    const ConservativeFigures& cons = stages.conservative;
    NamedValues figures = {
        {"octree_boxes_evaluated", double(stages.octree.evaluated)},
        {"octree_merged_back", double(stages.octree.merged)},
        {"occluder_seconds", stages.occluders.seconds},
        {"occluder_block_seconds", stages.blocks.seconds},
        {"ranking_seconds", stages.ranking.seconds},
        {"horizon_list_seconds", stages.horizon.seconds},
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
        {"conservative_shaft_pairs", double(cons.shaft.pairs)},
        {"conservative_shaft_hidden", double(cons.shaft.hidden)},
        {"conservative_shaft_tests", double(cons.shaft.tests)},
        {"conservative_shaft_given_up", double(cons.shaft.certain)},
        {"conservative_shaft_out_of_budget", double(cons.shaft.out_of_budget)},
        {"conservative_shaft_stuck", double(cons.shaft.stuck)},
        {"conservative_shaft_stuck_meet", double(cons.shaft.stuck_meet)},
        {"conservative_shaft_stuck_depth", double(cons.shaft.stuck_depth)},
        {"conservative_shaft_hidden_seconds", cons.shaft.seconds_hidden},
        {"conservative_shaft_given_up_seconds", cons.shaft.seconds_certain},
        {"conservative_shaft_out_of_budget_seconds", cons.shaft.seconds_out_of_budget},
        {"conservative_shaft_stuck_seconds", cons.shaft.seconds_stuck},
        {"conservative_shaft_umbrae", double(cons.shaft.umbrae)},
        {"conservative_shaft_capped", double(cons.shaft.capped)},
        {"conservative_shaft_cupped", double(cons.shaft.cupped)},
        {"conservative_shaft_flood_tries", double(cons.shaft.flood.tries)},
        {"conservative_shaft_flooded", double(cons.shaft.flood.separated)},
        {"conservative_shaft_flood_cells", double(cons.shaft.flood.cells)},
        {"conservative_shaft_flood_dropped", double(cons.shaft.flood.dropped)},
        {"conservative_shaft_flood_seconds", cons.shaft.flood.seconds},
        {"conservative_shaft_probe_rays", double(cons.shaft.probe_rays)},
        {"conservative_shaft_probe_seen", double(cons.shaft.probe_seen)},
        {"conservative_shaft_seconds", cons.shaft.seconds},
        {"conservative_seconds", cons.seconds},
        {"reuse_pairs", double(stages.reuse.pairs)},
        {"reuse_pairs_kept", double(stages.reuse.kept)},
        {"reuse_cells_matched", double(stages.reuse.cells_matched)},
        {"reuse_cells_whole", double(stages.reuse.cells_whole)},
        {"reuse_objects_matched", double(stages.reuse.objects_matched)},
        {"reuse_changed_tiles", double(stages.reuse.changed_tiles)},
        {"reuse_seconds", stages.reuse.seconds},
        {"cells_per_second",
         cons.seconds > 0
             ? double(bake.cells.size()) / cons.seconds
             : (stages.sampled.seconds > 0 ? double(bake.cells.size()) / stages.sampled.seconds : 0.0)},
        {"sampled_rays", double(stages.sampled.rays)},
        {"sampled_rays_per_second",
         stages.sampled.seconds > 0 ? double(stages.sampled.rays) / stages.sampled.seconds : 0.0},
        {"sampled_guard_band_added", double(stages.sampled.guard_band_added)},
    };
    // The shaft pass by level of its hierarchy (docs/ALGORITHMS.md#shaft-hierarchy): 0 is a cell; and the
    // blocks' proofs before the faces (docs/ALGORITHMS.md#shaft-early).
    for (int l = 0; l <= kShaftLevels; ++l) {
        const ShaftLevel& level = l < kShaftLevels ? cons.shaft.levels[size_t(l)] : cons.shaft.early;
        const std::string at =
            l < kShaftLevels ? fmt::format("conservative_shaft_level{}_", l) : "conservative_shaft_early_";
        figures.push_back({at + "tried", double(level.tried)});
        figures.push_back({at + "proven", double(level.proven)});
        figures.push_back({at + "settled", double(level.settled)});
        figures.push_back({at + "seen", double(level.seen)});
        figures.push_back({at + "given_up", double(level.given_up)});
        figures.push_back({at + "seconds", level.seconds});
    }
    return figures;
}

std::string pvs_kind(const BakeData& bake) {
    return bake.conservative ? "conservative" : "aggressive (" + bake.mode + ": may miss visible objects)";
}

namespace {
nlohmann::ordered_json values_json(const NamedValues& values) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    for (const auto& [k, v] : values) j[k] = v;
    return j;
}
double figure(const NamedValues& values, const std::string& key, double fallback) {
    for (const auto& [k, v] : values)
        if (k == key) return v;
    return fallback;
}
}  // namespace

std::string bake_report_json(const BakeData& bake, const std::vector<std::string>& warnings) {
    nlohmann::ordered_json j;
    j["tool"] = "pvsbake";
    j["version"] = bake.tool_version;
    j["format"] = std::to_string(bake.format_major) + "." + std::to_string(bake.format_minor);
    j["world"] = bake.world_path;
    j["world_hash"] = bake.world_hash;
    j["mode"] = bake.mode;
    j["conservative"] = bake.conservative;
    j["pvs_kind"] = pvs_kind(bake);
    j["objects"] = bake.objects.size();
    j["triangles"] = uint64_t(figure(bake.figures, "triangles", 0));
    j["cells"] = bake.cells.size();
    nlohmann::ordered_json params = nlohmann::ordered_json::object();
    for (const auto& [k, v] : bake.parameters) params[k] = v;
    j["parameters"] = params;
    j["figures"] = values_json(bake.figures);
    nlohmann::ordered_json ranked;
    ranked["stored"] = !bake.ranked.empty();
    ranked["entries"] = bake.ranked.entries.size();
    ranked["per_cell_mean"] =
        bake.cells.size() ? double(bake.ranked.entries.size()) / double(bake.cells.size()) : 0.0;
    j["ranked_occluders"] = ranked;
    nlohmann::ordered_json leak = nlohmann::ordered_json::array();
    for (const glm::vec3& p : bake.leak_path) leak.push_back({p.x, p.y, p.z});
    j["leak_path"] = leak;
    nlohmann::ordered_json ver;
    ver["ran"] = bake.verification.ran;
    if (bake.verification.ran) {
        ver["figures"] = values_json(bake.verification.figures);
        nlohmann::ordered_json misses = nlohmann::ordered_json::array();
        const double tolerance = gap_tolerance_of(bake);
        for (const Miss& m : bake.verification.misses) {
            nlohmann::ordered_json mj;
            mj["cell"] = m.cell;
            mj["object"] = m.object;
            mj["object_name"] = m.object < bake.objects.size() ? bake.objects[m.object].name : "";
            mj["eye"] = {m.eye.x, m.eye.y, m.eye.z};
            mj["direction"] = {m.direction.x, m.direction.y, m.direction.z};
            mj["distance_m"] = m.distance_m;
            // The widest sight line found through the opening (-1: not measured); narrow: below the bake's
            // gap tolerance, outside its promise.
            mj["opening_width_m"] = m.opening_width_m;
            mj["narrow"] = is_narrow_miss(m, tolerance);
            misses.push_back(mj);
        }
        ver["misses"] = misses;
    }
    j["verification"] = ver;
    nlohmann::ordered_json run;
    nlohmann::ordered_json run_params = nlohmann::ordered_json::object();
    for (const auto& [k, v] : bake.run.parameters) run_params[k] = v;
    run["parameters"] = run_params;
    run["figures"] = values_json(bake.run.figures);
    run["timings_s"] = values_json(bake.run.timings_s);
    // Each stage's thread utilisation: CPU seconds / wall seconds / threads (1: every thread busy all along;
    // 1 / threads: one thread works, the others wait).
    double threads = 0.0;
    for (const auto& [k, v] : bake.run.figures)
        if (k == "threads") threads = v;
    nlohmann::ordered_json use = nlohmann::ordered_json::object();
    for (const auto& [stage, wall] : bake.run.timings_s)
        for (const auto& [k, cpu] : bake.run.figures)
            if (threads > 0.0 && wall > 0.0 && k == "cpu_seconds_" + stage) use[stage] = cpu / wall / threads;
    run["utilisation"] = use;
    j["run"] = run;
    j["warnings"] = warnings;
    return j.dump(2) + "\n";
}

}  // namespace pvs
