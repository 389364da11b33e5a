// SPDX-License-Identifier: MIT
// pvsbake solver: the conservative PVS with occluder fusion, by occluder shrinking (after P. Wonka,
// M. Wimmer, D. Schmalstieg, "Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs",
// EGWR 2000).
//
// Conventions: glTF axes (right-handed, +Y up), metres. Epsilons and patch radii are in the Chebyshev metric
// (|d|_inf = max_k |d_k|). A box's EYE REGION is the bounds of the eye voxels in it, clipped to it
// (cells/eyes.h, eye_region). "Conservative": a row leaves an object out only if no sight line from an eye
// of the region reaches it, given that no sight line from the eye space meets the proven solid (the one
// sampled step: docs/ALGORITHMS.md#sampled-step). Every bake is verified by rays (driver/verify.h).
//
// How a row is made; the argument, step by step, is docs/ALGORITHMS.md#conservative-pvs:
// - always listed: pvs_always_visible objects and objects whose bounds meet the region
//   (docs/ALGORITHMS.md#eye-region);
// - the region's faces are cut into patches; a patch of Chebyshev radius r is tested from its centre s on a
//   depth cube (pvs/depth_cube.h) of the boxes shrunk by the smallest epsilon >= r
//   (docs/ALGORITHMS.md#shrunk-occluders, docs/ALGORITHMS.md#chebyshev, docs/ALGORITHMS.md#patches,
//   docs/ALGORITHMS.md#depth-cube); a patch wholly in the proven solid, or whose s lies in a shrunk box, is
//   skipped;
// - what a patch does not prove goes to its halves, down to the floor epsilon_0, where it is listed; a test
//   skips what the row already lists (docs/ALGORITHMS.md#refinement); objects are tested through a
//   hierarchy and by parts (docs/ALGORITHMS.md#object-bvh); what a sight ray from s reaches is listed at
//   once (docs/ALGORITHMS.md#sight-rays);
// - panels (occluders/panels.h) are drawn inset per ray for the patch's box (docs/ALGORITHMS.md#panel-inset),
//   with --panel-bands also where the inset leaves a pixel out, for the depths near the plane that need only
//   a share of it (docs/ALGORITHMS.md#depth-bands); with --corner-pairs, two panels meeting along a line are
//   drawn as one occluder too (docs/ALGORITHMS.md#corner-pairs);
// - with --single-occluder-pass, what one panel or one box hides from the whole region (or patch) is left
//   out first, proven exactly (pvs/region_hiding.h, docs/ALGORITHMS.md#single-occluder);
// - with --shaft-budget, what the faces listed and no sight ray saw is tried once more against the whole
//   region, in piece pairs each covered in one plane by panels and the proven solid (pvs/shaft_hiding.h,
//   docs/ALGORITHMS.md#shaft-pass), after rays from eye points of the cell settle what they reach
//   (docs/ALGORITHMS.md#shaft-probe); with --shaft-block on a grid, blocks of cells and their halves
//   share proofs, down to single cells (docs/ALGORITHMS.md#shaft-hierarchy);
// - a region whose eyes lie in one block uses that block's occluders, ShrunkOccluders::set_for (opt-in
//   --occluder-block, unproven: docs/ALGORITHMS.md#block-occluders);
// - an octree box tests only what its parent's row lists (docs/ALGORITHMS.md#octree-parent-bound).
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/pvs_set.h"
#include "core/row_journal.h"
#include "core/work_share.h"
#include "core/world.h"
#include "rays/ray_scene.h"
#include "pvs/region_hiding.h"
#include "pvs/reuse.h"
#include "pvs/shaft_hiding.h"

#include <vector>

namespace pvs {

struct ConservativeFigures {
    uint64_t samples = 0;           // patch centres a depth cube was drawn from
    uint64_t samples_skipped = 0;   // patch centres inside a shrunk occluder (nothing passes the patch)
    uint64_t patches_in_solid = 0;  // patches wholly in the proven solid
    uint64_t object_tests = 0;      // box tests on a depth cube (hierarchy nodes, objects and parts)
    uint64_t rays = 0;              // sight rays from patch centres (objects seen need no refinement)
    uint64_t fine_samples = 0;      // floor samples that took a second look on the fine cube
    uint64_t panel_splits = 0;      // patches at the floor epsilon halved once more for the panels' sake
    uint64_t known_listed = 0;      // (face side, object) pairs not tested: the cell already listed them
    uint64_t region_hidden = 0;     // (cell, object) pairs the single-occluder pass proved hidden
    double region_seconds = 0.0;    // its time (grid; on boxes it is part of `seconds`)
    uint64_t patch_hidden = 0;      // (patch, object) pairs it proved hidden, of what a patch's cubes left
    uint64_t parent_hidden = 0;     // (octree box, object) pairs left out untested: its parent left them out
    ShaftFigures shaft;             // the shaft pass (pvs/shaft_hiding.h)
    int shaft_pair_budget = 0;      // the largest piece-pair budget a (region, object) of it was given
    // The fewest objects a pass that ran was given (docs/ALGORITHMS.md#shaft-cap), the share of the
    // leavable objects' triangles they hold, and shaft_objects_digest() of them (0: every object); 0, 0, 0
    // when no pass ran.
    uint64_t shaft_objects = 0;
    double shaft_objects_triangle_share = 0.0;
    double shaft_objects_digest = 0.0;
    std::vector<uint64_t> samples_per_level;  // samples at each epsilon of the ladder
    double seconds = 0.0;
};

// The conservative rows of arbitrary boxes (cells, or octree nodes being considered): rows has boxes.size()
// rows. Each box is first clipped to its eye region (the bounds of the `eyes` voxels in it; the whole box
// when `eyes` is empty). Lists pvs_always_visible objects and objects whose bounds meet the region, then
// every object some patch of the region's boundary cannot prove hidden. Parallel over boxes.
// With `bounds` (one per box, null for none): bounds[i] is this function's row for a box that holds box i
// (an octree node's parent). Its eye region holds box i's, so what that row leaves out is hidden from every
// eye of box i too: it is left out without a test (docs/ALGORITHMS.md#octree-parent-bound).
// `hiders` and `provers` (of these occluders), when given, are used instead of building them per call.
// With `journal` and `keys` (one per box, the same box the same key in every run): a box's row the journal
// holds (table "box") is taken from it, and every row computed is recorded there
// (docs/ALGORITHMS.md#resume). With `share`, the boxes are dealt between the processes of the bake and every
// process gets every row (docs/ALGORITHMS.md#processes); without, this process computes them all.
void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const VoxelMask& eyes,
                           const ShrunkOccluders& occluders, const RayScene& scene, PvsSet& rows,
                           ConservativeFigures& figures, const RegionHiders* hiders = nullptr,
                           const std::vector<const uint64_t*>* bounds = nullptr,
                           const ShaftProvers* provers = nullptr, RowJournal* journal = nullptr,
                           const std::vector<uint64_t>* keys = nullptr, WorkShare* share = nullptr);

// The blocks the shaft pass proves over on a grid (docs/ALGORITHMS.md#shaft-hierarchy): the cells in each block of
// k x k x k grid positions, in cell order; the blocks in the order of their first cell. k = 1: each cell
// alone.
std::vector<std::vector<uint32_t>> grid_shaft_blocks(const CellSet& cells, int k);
// The regions the shaft pass's cap counts over a grid (docs/ALGORITHMS.md#shaft-cap): its cells, with or
// without blocks (a block's proofs save tries, but what the pass costs still grows with its cells).
uint64_t grid_shaft_regions(const ConservativeConfig& config, const CellSet& cells);

// The objects the shaft pass tries over `regions` cells or boxes of `world` (docs/ALGORITHMS.md#shaft-cap),
// in index order: every object a pass may leave out (all but always-visible ones) when regions x their count
// is at most config.shaft_max_pairs (0: no limit); else the floor(shaft_max_pairs / regions) of them with the
// most triangles (ties: the lower index), where a listed object costs a frame the most, when they hold at
// least config.shaft_min_share of the leavable objects' triangles. None otherwise, and when the budget is
// off. A function of the config, the world and the count alone, so a bake chooses alike on every process
// and in every run.
std::vector<uint32_t> shaft_objects(const ConservativeConfig& config, const World& world, uint64_t regions);
// What shaft_objects() chose, for a re-bake to compare: 0 when every object a pass may leave out, else a
// 52-bit hash (FNV-1a) of the chosen objects' names in order of the names.
double shaft_objects_digest(const World& world, const std::vector<uint32_t>& chosen);
// Whether the shaft pass runs over `regions` cells or boxes of `world`: shaft_objects() chooses some.
bool shaft_pass_runs(const ConservativeConfig& config, const World& world, uint64_t regions);
// The piece pairs the shaft pass gives each (region, object) over `regions` cells or boxes
// (docs/ALGORITHMS.md#shaft-small): config.shaft_budget, doubled (at most six times, and to 4096 at most)
// while the candidates (shaft_candidates) x the budget stay within config.shaft_small_spend. A function of
// the config, the world and the count alone, as shaft_pass_runs().
int shaft_pair_budget(const ConservativeConfig& config, const World& world, uint64_t regions);
// The count that rule compares: regions x the objects a pass may leave out (all but always-visible ones).
uint64_t shaft_candidates(const World& world, uint64_t regions);
// The objects a pass may leave out: all but always-visible ones.
size_t leavable_count(const World& world);
// The regions an octree level's `boxes` stand for in that rule: the cells of `min_cell_m` each box can still
// be split into ((edge / min_cell_m)^3, the edge rounded up to min_cell_m times a power of two), so that a
// level of few big boxes is not cheaper than the leaves it decides.
uint64_t octree_shaft_regions(const std::vector<Aabb>& boxes, double min_cell_m);

// The conservative PVS of every cell. On a grid each face shared by two cells is computed once.
// With `journal` (a grid only): every finished row of a pass (tables "hidden", "face", "face_seen",
// "shaft") is taken from the journal when it holds it and recorded there when computed, and the journal is
// flushed at the end of each pass and phase; the PVS is the same (docs/ALGORITHMS.md#resume). With `share`,
// the faces and cells of each pass are dealt between the processes of the bake, and every process gets the
// whole PVS (docs/ALGORITHMS.md#processes). With `reuse` (a grid only; pvs/reuse.h), the pairs it
// settles take its bit and no pass tests them; the PVS is the same (docs/ALGORITHMS.md#reuse).
PvsSet bake_conservative_pvs(Context& ctx, const ConservativeConfig& config, const World& world,
                             const CellSet& cells, const ShrunkOccluders& occluders, const RayScene& scene,
                             ConservativeFigures& figures, RowJournal* journal = nullptr,
                             WorkShare* share = nullptr, const ReusePlan* reuse = nullptr);

}  // namespace pvs
