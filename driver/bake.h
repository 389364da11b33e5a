// SPDX-License-Identifier: MIT
// pvsbake driver: the bake pipeline, from a loaded World to the BakeData written to the bake file:
//   view volume (cells/view_volume.h) -> ray scene (rays/ray_scene.h) -> occluders (occluders/synthesis.h)
//   -> cells and PVS (cells/grid.h or cells/octree.h; pvs/conservative.h, or rays/ray_sampler.h in the
//   sampled mode) -> ranked occluders (occluders/cell_ranking.h) -> figures (driver/report.h)
//   -> verification (driver/verify.h).
// Each stage is a function over plain data; bake_world only calls them in order
// (docs/ALGORITHMS.md#pipeline).
#pragma once

#include "cells/view_volume.h"
#include "core/config.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/row_journal.h"
#include "core/work_share.h"
#include "core/world.h"
#include "driver/verify.h"
#include "io/bake_file.h"
#include "occluders/synthesis.h"
#include "rays/ray_scene.h"

#include <string>

namespace pvs {

const char* tool_version();

// Object records for the bake file.
std::vector<ObjectRecord> object_records(const World& world);

// The occluder stage of a bake: the synthesized boxes (returned, as stored in the bake file) and, in
// conservative mode, the solver's occluders (`shrunk`; per block too when config.occluders.block_m > 0,
// blocks of whole cells). Deterministic: the same config and world give the same occluders, so tools can
// rebuild a bake's occluders from its stored parameters (core/config.h config_from_parameters).
// With `share`, the work is dealt between the processes of an MPI bake (occluders/synthesis.h); the
// occluders per block are computed by every process.
std::vector<Occluder> solver_occluders(Context& ctx, const BakeConfig& config, const World& world,
                                       const ViewVolume& view, const RayScene& scene,
                                       OccluderFigures& figures, BlockFigures& blocks,
                                       ShrunkOccluders& shrunk, WorkShare* share = nullptr);

// Runs the bake of `world` (already loaded from world_path, whose content hash is world_hash).
// With `journal`, the conservative PVS (grid or octree) takes the rows it holds and records those it
// computes (docs/ALGORITHMS.md#resume); the bake is the same. With `share` (several processes,
// driver/processes.h), the costly parts of the stages before the PVS, its passes, the occluder ranking and
// the verification are dealt between the processes, and every process returns the same bake (rank 0 writes
// it); the sampled mode runs on rank 0 alone.
// With `reuse` (an older conservative bake of the same parameters, check_reuse()), a grid's PVS keeps the
// bits of that bake an edit of the world cannot change and computes the rest (pvs/reuse.h); the bake is
// the same as without it (docs/ALGORITHMS.md#reuse). An octree is baked in full.
BakeData bake_world(Context& ctx, const BakeConfig& config, const World& world, const std::string& world_path,
                    const std::string& world_hash, RowJournal* journal = nullptr, WorkShare* share = nullptr,
                    const BakeData* reuse = nullptr);

// Checks that `old` (read from `old_path`) can serve a re-bake with `config` (--reuse): a conservative
// bake made with the same parameters (outside run.*). Throws pvs::Error (bad input) naming the first
// difference.
void check_reuse(const BakeConfig& config, const BakeData& old, const std::string& old_path);

// The view volume's config of a bake: the conservative mode's automatic voxel follows epsilon.
ViewVolumeConfig view_volume_config(const BakeConfig& config);

// The gap tolerance a bake was made with (its parameter gap.tolerance_m; the default for bakes made before
// it was recorded). Throws pvs::Error (bad input) when the stored parameters do not parse.
double gap_tolerance_of(const BakeData& bake);

// Copies a verification's figures, per-cell sampled counts and misses into the bake's record, and its
// timing into the bake's run record.
void store_verification(const VerifyResult& result, BakeData& bake);

// The ray check of the bake's ranked occluder boxes (driver/verify_boxes.h), its figures added to the
// verification's: ranked_boxes_checked, ranked_box_rays, ranked_boxes_seen_into (a bug when not 0).
void verify_ranked_boxes(Context& ctx, const RayScene& scene, uint64_t seed, BakeData& bake);

// Checks that a bake was made from this world (same objects, in the same order). Throws pvs::Error
// (bad input) naming the first difference. A different content hash only warns.
void check_bake_matches_world(Context& ctx, const BakeData& bake, const World& world,
                              const std::string& world_hash);

}  // namespace pvs
