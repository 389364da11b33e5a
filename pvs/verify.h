// pvsbake pvs: verification of a PVS by Embree ray sampling (ALGORITHMS.md section 5).
//
// Independent of how the PVS was made: eye points in each cell's eye region (cells/eyes.h), rays over
// the whole sphere, each traced through see-through surfaces to its first opaque hit. An object a ray
// touches that the cell's PVS does not list is a MISS: a bug in a conservative bake. The objects the
// rays touched form the sampled visible set, a lower bound of the truth; |PVS| / |sampled set| is the
// overestimation to drive down.
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
