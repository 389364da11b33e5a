// SPDX-License-Identifier: MIT
// pvsbake driver: the figures of a bake (what its stages measured, stored in the bake file's /figures) and
// the JSON report of a bake (and of `pvsbake info --json`).
//
// Keys: tool, version, world, world_hash, mode, pvs_kind ("conservative" or "aggressive"), objects,
// triangles, cells, parameters{}, figures{}, verification{ran, figures..., misses[]},
// run{parameters{}, figures{}, timings_s{}, utilisation{}}, warnings[]. utilisation: per stage, its CPU
// seconds (run figure cpu_seconds_<stage>) over its wall seconds and the run's threads (run figure threads). Numbers are plain JSON numbers; misses carry the
// object's name.
#pragma once

#include "cells/octree.h"
#include "cells/view_volume.h"
#include "core/config.h"
#include "core/world.h"
#include "io/bake_file.h"
#include "occluders/cell_ranking.h"
#include "occluders/horizon_lists.h"
#include "occluders/synthesis.h"
#include "pvs/conservative.h"

#include <string>
#include <vector>

namespace pvs {

// What the sampled mode's rays did (zero in the conservative mode, except rays_per_eye on the octree).
struct SampledFigures {
    uint64_t rays = 0;
    uint32_t rays_per_eye = 0;
    uint64_t guard_band_added = 0;  // (cell, object) pairs listed by the guard band alone
    double seconds = 0.0;           // the PVS stage (the octree's whole build on the octree)
};

// What the stages of one bake measured: the inputs of its figures table besides the bake itself.
struct StageFigures {
    uint64_t cells_dropped = 0;  // grid cells with no view volume in them
    OctreeStats octree;
    OccluderFigures occluders;
    BlockFigures blocks;
    size_t shrunk_boxes = 0;    // the solver's occluders at the smallest epsilon
    size_t epsilon_levels = 0;  // epsilons of the refinement ladder
    ConservativeFigures conservative;
    SampledFigures sampled;
    RankingFigures ranking;
    HorizonListFigures horizon;
    ReuseFigures reuse;  // an incremental re-bake (pvs/reuse.h); zero without --reuse
};

// The figures of a bake's result, as stored in /figures and the report's figures{}: named numbers in a
// fixed order, functions of the world and the parameters alone.
NamedValues bake_figures(const BakeConfig& config, const World& world, const ViewVolume& view,
                         const BakeData& bake, const StageFigures& stages);

// The figures of the work one run did (/run/figures, the report's run{figures{}}): seconds, rates and
// counts of tests and samples, which depend on the schedule and, in a resumed run, cover only what it
// computed itself.
NamedValues run_figures(const BakeData& bake, const StageFigures& stages);

std::string bake_report_json(const BakeData& bake, const std::vector<std::string>& warnings);

// "conservative" or "aggressive (sampled: may miss visible objects)".
std::string pvs_kind(const BakeData& bake);

}  // namespace pvs
