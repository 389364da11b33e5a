// SPDX-License-Identifier: MIT
// pvsbake driver: verification of a PVS by Embree ray sampling (docs/ALGORITHMS.md#verification).
//
// Independent of how the PVS was made: eye points in each cell's eye region (cells/eyes.h), rays each
// traced through see-through surfaces to its first opaque hit. An object a ray touches that the cell's PVS
// does not list is a MISS: a bug in a conservative bake. The objects the rays touched form the sampled
// visible set, a lower bound of the truth; |PVS| / |sampled set| is the overestimation to drive down.
//
// Three passes of rays per cell, after guided visibility sampling (Wonka, Wimmer, Zhou, Maierhofer, Hesina,
// Reshetov: "Guided visibility sampling", SIGGRAPH 2006); why each: docs/ALGORITHMS.md#uniform-rays,
// docs/ALGORITHMS.md#aimed-rays, docs/ALGORITHMS.md#neighbour-rays.
// - UNIFORM rays: eyes_per_cell eye points, stratified directions over the sphere.
// - AIMED rays (VerifyConfig::aimed_share of the budget): from fresh eye points of the same eye region
//   (another random stream), one ray at a random point ON every object the uniform rays did not touch
//   (a triangle picked by area, a uniform point in it). Every object an aimed ray touches counts as seen
//   (and as a miss when unlisted), whether or not it is the one aimed at. Objects every PVS lists
//   (pvs_always_visible, or bounds meeting the cell) are not aimed at when the PVS lists them.
//   The untouched objects ("candidates") of a cell fall in two groups: LEFT-OUT ones (the PVS leaves them
//   out; a ray at them can only find a miss) and LISTED ones (a ray at them can only tighten the sampled
//   set). Per cell (budget B = aimed_share x ray_budget / cells rays) the listed group gets
//   floor(aimed_listed_share x B) rays and the left-out group the rest; a group that runs out of objects
//   to aim at (all seen) gives what it did not spend to the other (listed first, then left-out, then
//   listed again), so the cell spends B and no more unless every candidate has been seen. A group spends
//   its rays in ROUNDS: round r draws one fresh eye point of the cell (in batches of 16 stratified over
//   the eye region, taken in bit-reversed order) and aims one ray at every object of the group not SEEN
//   yet (seen = touched by any ray of this cell so far, uniform or aimed); the last round, short of rays,
//   aims at a seeded random subset. A left-out object leaves its group only when a miss touches it.
//   aimed_listed_share < 1 keeps rays on the left-out objects.
//   With no ray budget: eyes_per_cell eye points aim at every candidate of both groups (no rounds).
// - NEIGHBOUR rays (VerifyConfig::neighbour_share of each cell's aimed rays; the first pass above gets the
//   rest): every ray that first touches an object in a cell leaves a WITNESS: its eye and the point it
//   touched. A neighbour pass then aims, from each cell, one ray at each witness of the cells around (boxes
//   meeting by a face, an edge or a corner) whose object the cell's rays have not touched yet, listed or
//   left out: round k takes the k-th witness of every such object. The ray starts at the point of the cell
//   nearest the witness's eye (a millimetre inside the cell, when that is eye space; else the nearest of 16
//   eye points of the cell). What a pass finds leaves witnesses for the next one; passes stop when one
//   finds nothing new, or after 8. A cell spends at most its share on them and puts what is left into more
//   aimed rounds.
// Rays and eye points depend only on (seed, cell, eye or round), and a neighbour pass reads only what the
// pass before it wrote: the result is the same for any thread count.
// aimed_share = 0 traces the uniform rays alone, with the whole budget (same seed, same rays).
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/pvs_set.h"
#include "core/work_share.h"
#include "core/world.h"
#include "io/bake_file.h"
#include "rays/ray_scene.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct VerifyResult {
    uint64_t rays = 0;
    uint32_t rays_per_eye = 0;
    double seconds = 0.0;
    uint64_t missed_pairs = 0;  // distinct (cell, object) pairs seen but not listed
    uint64_t missed_rays = 0;   // rays that touched an unlisted object
    uint32_t cells_with_misses = 0;
    // Aimed rays (counted in `rays` too).
    uint64_t aimed_rays = 0;
    uint64_t aimed_listed_rays = 0;        // of those, aimed at listed candidates (0 without a budget)
    uint64_t aimed_rays_per_cell = 0;      // the budget's share per cell; 0 = no budget (eyes_per_cell eyes)
    uint64_t aimed_candidates = 0;         // (cell, object) pairs the uniform rays left untouched, to aim at
    uint64_t aimed_listed_candidates = 0;  // of those, the pairs the PVS lists
    uint64_t aimed_targets = 0;            // of those, the pairs aimed at (at least once) within the budget
    uint64_t aimed_rounds = 0;             // aimed eye points over all cells (one per round)
    uint64_t aimed_new_pairs = 0;          // (cell, object) pairs seen by aimed rays only
    uint64_t aimed_listed_new_pairs = 0;   // of those, the pairs the PVS lists (they tighten the figure)
    uint64_t aimed_missed_pairs = 0;       // missed pairs found by aimed rays only (part of missed_pairs)
    // The neighbour pass (counted in `rays` too; its spare rays count as aimed).
    uint32_t neighbour_passes = 0;
    uint64_t neighbour_rays = 0;
    uint64_t neighbour_targets = 0;           // witness points aimed at (one ray each, unless no eye point)
    uint64_t neighbour_new_pairs = 0;         // (cell, object) pairs seen by neighbour-pass rays only
    uint64_t neighbour_listed_new_pairs = 0;  // of those, the pairs the PVS lists
    uint64_t neighbour_missed_pairs = 0;      // missed pairs found by neighbour-pass rays only
    // Misses by the width of the opening they pass (docs/ALGORITHMS.md#miss-widths): the first ray of each
    // reported pair is measured; a pair whose widest line found is narrower than the gap tolerance is NARROW
    // (reported apart, does not fail), every other pair WIDE (unmeasured pairs count as wide).
    double gap_tolerance_m = 0.0;  // the tolerance the misses were measured against
    uint64_t narrow_missed_pairs = 0;
    uint64_t wide_missed_pairs = 0;
    float narrow_width_max_m = 0.0f;  // the widest line found through a narrow miss's opening
    double width_seconds = 0.0;       // spent measuring
    std::vector<Miss> misses;  // the first ray of each missed pair, cell order, at most max_misses_reported
    // A measured miss through an opening narrower than the tolerance.
    bool is_narrow(const Miss& m) const { return is_narrow_miss(m, gap_tolerance_m); }
    std::vector<uint32_t> cell_sampled_visible;  // per cell: objects the rays touched
    PvsSet sampled;                              // per cell: which objects the rays touched

    // Figures over cells whose sampled set is not empty.
    double overestimation_mean = 0, overestimation_median = 0, overestimation_max = 0;
    double overestimation_tri_mean = 0, overestimation_tri_median = 0, overestimation_tri_max = 0;
    double pvs_triangle_share_mean = 0;      // share of the world's triangles the PVS lets through
    double sampled_triangle_share_mean = 0;  // share of the world's triangles the rays saw
    uint32_t cells_with_empty_sample = 0;

    // What the rays found (/verification/figures): a function of the bake and the verification's options.
    NamedValues figures() const;
    // How long it took (the run's own record, /run/figures): verify_seconds, verify_rays_per_second,
    // verify_width_seconds.
    NamedValues run_figures() const;
};

// With `share` (the processes of an MPI job), each pass's cells are dealt between the processes and what they
// found is passed to every process after the pass (docs/ALGORITHMS.md#dealt-verification): every process
// returns the same result, the one process alone would. Collective then.
VerifyResult verify_pvs(Context& ctx, const VerifyConfig& config, const World& world, const RayScene& scene,
                        const CellSet& cells, const PvsSet& pvs, WorkShare* share = nullptr);

// Prints the summary lines of a verification.
void log_verify_summary(Context& ctx, const VerifyResult& result, const World& world);

}  // namespace pvs
