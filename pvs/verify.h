// pvsbake pvs: verification of a PVS by Embree ray sampling (ALGORITHMS.md section 5).
//
// Independent of how the PVS was made: eye points in each cell's eye region (cells/eyes.h), rays over
// the whole sphere, each traced through see-through surfaces to its first opaque hit. An object a ray
// touches that the cell's PVS does not list is a MISS: a bug in a conservative bake. The objects the
// rays touched form the sampled visible set, a lower bound of the truth; |PVS| / |sampled set| is the
// overestimation to drive down.
//
// Two kinds of rays per cell, after guided visibility sampling (Wonka, Wimmer, Zhou, Maierhofer, Hesina,
// Reshetov: "Guided visibility sampling", SIGGRAPH 2006):
// - UNIFORM rays: eyes_per_cell eye points, stratified directions over the sphere. With a budget of
//   100 rays per eye a uniform ray touches an object in proportion to its solid angle, so a small or far
//   object (a few millisteradians through a gap) is almost never touched: both its miss and its
//   visibility go unnoticed, and the overestimation figure mostly measures undersampling.
// - AIMED rays (VerifyConfig::aimed_share of the budget): from fresh eye points of the same eye region
//   (another random stream), one ray at a random point ON every object the uniform rays did not touch
//   (a triangle picked by area, a uniform point in it). Such a ray reaches its object unless something
//   opaque is in the way, so the chance to see a visible object no longer shrinks with its solid angle.
//   Unlisted untouched objects are the only place a miss can hide; listed untouched ones are aimed at
//   too, to tighten the sampled set. Every object an aimed ray touches counts as seen (and as a miss
//   when unlisted), whether or not it is the one aimed at. Objects every PVS lists (pvs_always_visible,
//   or bounds meeting the cell) are not aimed at when the PVS lists them.
//   Per cell (budget B = aimed_share x ray_budget / cells rays, K candidates): A = floor(B / K) eye
//   points each aim one ray at every candidate, and the B mod K rays left go from one more eye point to a
//   seeded random subset of B mod K candidates, so a cell spends its share and no more (when B < K only
//   that subset is aimed at: aimed_targets < aimed_candidates). With no ray budget, A = eyes_per_cell.
// Rays and eye points depend only on (seed, cell, eye): the result is the same for any thread count.
// aimed_share = 0 traces exactly the uniform rays of before (same seed, same rays, same figures).
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/pvs_set.h"
#include "core/world.h"
#include "io/bake_file.h"
#include "pvs/embree_scene.h"

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
    uint64_t aimed_rays_per_cell = 0;  // the budget's share per cell; 0 = no budget (eyes_per_cell eyes)
    uint64_t aimed_candidates = 0;     // (cell, object) pairs the uniform rays left untouched, to aim at
    uint64_t aimed_targets = 0;        // of those, the pairs aimed at within the budget
    uint64_t aimed_new_pairs = 0;      // (cell, object) pairs seen by aimed rays only
    uint64_t aimed_missed_pairs = 0;   // missed pairs found by aimed rays only (part of missed_pairs)
    std::vector<Miss> misses;  // the first ray of each missed pair, cell order, at most max_misses_reported
    std::vector<uint32_t> cell_sampled_visible;  // per cell: objects the rays touched
    PvsSet sampled;                              // per cell: which objects the rays touched

    // Figures over cells whose sampled set is not empty.
    double overestimation_mean = 0, overestimation_median = 0, overestimation_max = 0;
    double overestimation_tri_mean = 0, overestimation_tri_median = 0, overestimation_tri_max = 0;
    double pvs_triangle_share_mean = 0;      // share of the world's triangles the PVS lets through
    double sampled_triangle_share_mean = 0;  // share of the world's triangles the rays saw
    uint32_t cells_with_empty_sample = 0;

    NamedValues figures() const;
};

VerifyResult verify_pvs(Context& ctx, const VerifyConfig& config, const World& world, const RayScene& scene,
                        const CellSet& cells, const PvsSet& pvs);

// Prints the summary lines of a verification.
void log_verify_summary(Context& ctx, const VerifyResult& result, const World& world);

}  // namespace pvs
