// SPDX-License-Identifier: MIT
// pvsbake core: BakeConfig, every knob of a bake in one place (after Recast's rcConfig).
//
// Every field states its units, limits and default. Each stage takes its own part. The options are
// declared once, in visit_options(): the same declaration drives the command line, --help, validation,
// and the resolved parameters written into the bake file and the report, so a bake can be repeated.
#pragma once

#include "core/math.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pvs {

enum class BakeMode { kSampled, kConservative };

const char* to_string(BakeMode mode);

struct RunConfig {
    int threads = 0;  // [Limit: >= 0] worker threads; 0 = every core
    // [Limit: 0..1e6] [Units: s] seconds between checkpoint chunks within a pass of the conservative solver
    // (each pass's end writes one too); 0 = no checkpoint (docs/ALGORITHMS.md#resume)
    double checkpoint_interval_s = 300.0;
    double max_memory_mib = 0.0;  // [Limit: >= 0] [Units: MiB] refuse a bake whose plan needs more
                                  // (driver/memory_plan.h); 0 = the machine's memory less a tenth
};

// The gap tolerance: the conservative promise covers every object seen through an opening at least this
// wide (docs/ALGORITHMS.md#openings); a miss through a narrower one is reported apart and does not fail.
constexpr double kDefaultGapToleranceM = 0.001;
struct GapConfig {
    double tolerance_m = kDefaultGapToleranceM;  // [Limit: 1e-6..10] [Units: m]
};

enum class CellKind { kGrid, kOctree };

struct CellConfig {
    CellKind kind = CellKind::kGrid;
    double cell_size_m = 2.0;       // [Limit: > 0] [Units: m] grid: edge of a cell
    double min_cell_size_m = 2.0;   // [Limit: > 0] [Units: m] octree: never split below this edge (the
                                    // grid's cell: the octree is never finer than the default grid)
    double root_cell_size_m = 8.0;  // [Limit: >= min] [Units: m] octree: edge of the root cells (rounded to
                                    // min_cell_size_m times a power of two)
    double split_threshold = 0.2;  // [Limit: 0..1] octree: split when a child's PVS differs from its parent's
                                   // by more than this share of the parent's PVS size
    uint32_t max_cells = 0;        // [Limit: >= 0] octree: stop splitting at this many cells; 0 = no limit
};

const char* to_string(CellKind kind);

// The edge of the largest cell the partition can make: the grid's cell, or the octree's root cell
// (min_cell_size_m times the power of two nearest root / min, as build_octree() rounds it) [m].
double largest_cell_edge_m(const CellConfig& config);

// Where eyes can be (cells/view_volume.h): explicit boxes, the flood of free space from view seeds, and a
// play height above floors, combined by intersection; none given = the world bounds.
struct ViewVolumeConfig {
    double voxel_size_m = 0.0;          // [Limit: >= 0] [Units: m] 0 = automatic (kDefaultVoxelSizeM, coarser
                                        // when the grid would pass max_voxels)
    uint64_t max_voxels = 200'000'000;  // [Limit: >= 1000] the voxels the automatic size aims at: it grows to
                                        // stay within them up to max_voxel_size_m; past that the grid keeps
                                        // voxels of that edge, more of them (up to kMaxVoxels), and the memory
                                        // plan (driver/memory_plan.h) decides whether they fit
    double max_voxel_size_m = 0.25;     // [Limit: > 0] [Units: m] the automatic size grows at most to this
                                        // edge (and never past the cells'); a world that would need coarser
                                        // voxels to stay within max_voxels is refused when an object stands
                                        // apart from the rest, naming it (cells/world_extent.h)
    bool allow_coarse_voxels = false;   // past max_voxel_size_m, take the coarser voxels that fit max_voxels
                                        // instead (a world with an object standing apart, or one too large
                                        // for the grid at max_voxel_size_m, then bakes)
    bool eyes_anywhere = false;         // with no seeds, boxes or play height: eyes anywhere in the world's
                                        // bounds (the conservative mode refuses such a bake otherwise)
    double play_height_m = 0.0;         // [Limit: >= 0] [Units: m] keep only space up to this height above
                                        // upward-facing opaque surfaces; 0 = off
    bool use_world_seeds = true;        // flood from the world's pvs_view_seed nodes
    bool use_world_boxes = true;        // limit to the world's pvs_view_volume boxes
    std::vector<Aabb> boxes;            // --view-box, metres
    std::vector<glm::vec3> seeds;       // --view-seed, metres
    double auto_voxel_size_m = 0.25;  // [Units: m] what "automatic" aims at; not an option: the bake sets it
                                      // to conservative_voxel_size_m(epsilon) in conservative mode
    // Not options: the bake sets them (driver/bake.cpp view_volume_config).
    double cell_edge_m = 0.0;         // [Units: m] the partition's smallest cell edge: automatic voxels are
                                      // never coarser (0 = no such limit)
    bool need_sources = false;        // refuse a view volume with no source unless eyes_anywhere (the
                                      // conservative mode: its promise is about where eyes can be)
};
constexpr double kDefaultVoxelSizeM = 0.25;

// The automatic voxel edge of a conservative bake: epsilon / 2, at most kDefaultVoxelSizeM. Walls thicker
// than about 2 epsilon + 2 voxels keep a shrunk occluder (the voxels their surfaces touch are not solid,
// and the rest erodes by epsilon on each side), so half-epsilon voxels let thinner walls occlude than
// epsilon voxels do, for 8x the voxels (still capped by max_voxels; docs/RESULTS.md has the trade).
inline double conservative_voxel_size_m(double epsilon_m) {
    return std::min(kDefaultVoxelSizeM, 0.5 * epsilon_m);
}

// Occluder synthesis (occluders/, occluders/synthesis.h).
struct OccluderConfig {
    bool enabled = true;                  // synthesize occluders in a bake (--no-occluders to skip)
    uint32_t max_occluders = 512;         // [Limit: >= 1] boxes kept at most
    double min_occluder_volume_m3 = 0.5;  // [Limit: >= 0] [Units: m3] smaller boxes are dropped
    double min_added_share = 0.05;        // [Limit: 0..1] keep a box only while this share of it is new
    uint32_t probe_eyes = 2048;           // [Limit: >= 0] eye points of the sight probe (0 = off)
    uint32_t probe_rays_per_eye = 4096;   // [Limit: >= 1] directions over the sphere per probe eye
    uint32_t check_eyes = 4096;           // [Limit: >= 1] eye points of the ray check of every box
    uint32_t check_rays_per_eye = 4;      // [Limit: >= 1] rays from each eye point to each box
    uint32_t check_near_eyes = 256;       // [Limit: >= 0] and eye points within 4 m of each box, 16 rays
                                          // each (0 = off): sight through a crack near a box
    uint32_t gap_lines = 8;               // [Limit: >= 0] gap probe: lines across each gap between nearby
                                          // triangles near the solid (occluders/gap_probe.h; 0 = off)
    uint32_t seal_rays = 32;              // [Limit: >= 0] seal probe: rays from each voxel of the solid's
                                          // frontier towards the eye space (occluders/seal_probe.h; 0 = off)
    double seal_reach_m = 4.0;            // [Limit: > 0] [Units: m] seal probe: how far a ray looks for an
                                          // eye voxel
    uint64_t check_seed = 7;
    // Not an option of its own: the driver copies GapConfig::tolerance_m. The probes count a line of sight
    // only when its width is at least kGapWidthShare of it (occluders/gap_probe.h); the ray check, every
    // line.
    double gap_tolerance_m = kDefaultGapToleranceM;
    // Occluders per block of cells (conservative mode; occluders/synthesis.h synthesize_block_occluders).
    // EXPERIMENTAL, NOT PROVEN: their boxes rest on sampled ray checks at grazing shadow edges
    // (docs/ALGORITHMS.md#block-occluders).
    double block_m = 0.0;          // [Limit: >= 0] [Units: m] block edge (rounded to whole cells); 0 = off
    double block_reach_m = 64.0;   // [Limit: >= 0] [Units: m] a block's own solid is looked for this far
                                   // around it
    double block_min_gain = 0.25;  // [Limit: >= 0] a block keeps its own occluders only when its eyes leave
                                   // more than (1 + this) times the solid all eyes leave in its window
    uint32_t block_probe_eyes = 256;   // [Limit: >= 0] sight probe eyes per block (0 = off)
    uint32_t block_check_eyes = 1024;  // [Limit: >= 1] ray check eyes per block
};

// Ranked occluders per cell (occluders/ranking.h, occluders/cell_ranking.h; docs/ALGORITHMS.md#ranking).
struct RankingConfig {
    uint32_t occluders_per_cell = 16;  // [Limit: 0..1024] occluders kept per cell, best first; 0 = off
    double min_solid_angle_sr = 0.01;  // [Limit: 0..4 pi] [Units: sr] a box is a candidate for a cell when
                                       // its exact solid angle from some sampled eye of the cell passes this
    uint32_t eyes_per_cell = 8;        // [Limit: 1..1024] seeded eye points per cell (cells/eyes.h)
    uint64_t seed = 0x72616e6bULL;     // [Limit: any] the same seed gives the same ranking for any threads
    uint32_t sight_lines = 1024;  // [Limit: 0..1e6] sight lines per cell from its eyes to its PVS's objects:
                                  // the occluders (proven boxes and panels) that stop the most first are kept
                                  // (occluders/sight_ranking.h); 0 = rank proven boxes by solid angle and
                                  // depth complexity (occluders/ranking.h)
    double min_panel_area_m2 = 1.0;  // [Limit: >= 0] [Units: m2] panels this large are candidates (by sight)
    bool polygons = false;  // by sight, the slanted panels this large are candidates too, as the run-time
                            // culler's polygon occluders (docs/ALGORITHMS.md#runtime-polygons); opt-in (what
                            // they gain and cost: docs/RESULTS.md, "What a game draws per frame")
    uint32_t horizon_eyes = 32;  // [Limit: 0..4096] seeded eyes per block of cells whose run-time horizons
                                 // choose the block's list of horizon occluders (occluders/horizon_lists.h,
                                 // docs/ALGORITHMS.md#horizon-lists); 0 = no lists
    uint32_t horizon_columns = 256;  // [Limit: 4..8192] columns a side of those horizons (runtime/pvsr.h)
    uint32_t horizon_min_uses = 1;   // [Limit: 1..1e9] a list keeps the occluders that served in this many of
                                     // its eyes' proofs
    uint32_t object_parts = 8;       // [Limit: 0..64] each object's surface cut into up to this many part
                                     // boxes, stored for the run-time tests: an object whose bounds are not
                                     // hidden is culled when every part is (docs/ALGORITHMS.md#object-parts);
                                     // 0 or 1 = none
    uint32_t horizon_list_max = 0;   // [Limit: 0..1e6] and at most this many of them, the most used first;
                                     // 0 = no limit
    uint32_t horizon_cell_eyes = 16;  // [Limit: 0..4096] seeded eyes per cell whose horizons, built from the
                                      // cell's block's list, choose the cell's own list, a subset of it
                                      // (docs/ALGORITHMS.md#horizon-lists); 0 = lists per block only
    double horizon_cell_lists_max = 2e6;  // [Limit: >= 0] [Units: entries] lists per cell only when the cells
                                          // times their blocks' mean list length are at most this
    bool horizon_cell_tests = true;  // with lists per cell, each cell also keeps the objects of its PVS that
                                     // its eyes' horizons culled, and a frame's horizon tests only those
                                     // (docs/ALGORITHMS.md#horizon-tests)
};

// The conservative solver (pvs/conservative.h).
struct ConservativeConfig {
    double epsilon_m = 0.125;      // [Limit: > 0] [Units: m] occluders shrink by this; cell faces are sampled
                                   // every 2 epsilon. Smaller: tighter PVS, slower bake (samples grow
                                   // as 1 / epsilon^2); walls thinner than 2 epsilon do not occlude
    int cube_resolution = 80;      // [Limit: 8..1024] depth cube pixels per face edge (near every occluder
                                   // edge about two pixels are lost: finer is tighter and slower)
    int fine_cube_resolution = 0;  // [Limit: 0..4096] floor samples take a second look at what the
                                   // cube could not prove on a cube this fine, drawn only over those
                                   // objects' pixels; 0 = off
    int panel_refine_levels = 0;   // [Limit: 0..4] halvings of the floor patches, for what only the panels
                                   // may still prove (their inset is the patch's half-size; the boxes keep
                                   // epsilon); 0 = none
    bool corner_pairs = false;     // two panels meeting along a line (a wall on a floor, two walls at a
                                   // corner) are drawn on the depth cubes as one occluder too
                                   // (docs/ALGORITHMS.md#corner-pairs): exact, tighter on open levels,
                                   // slower
    bool panel_bands = false;      // a pixel a panel's inset leaves out still hides what lies near the
                                   // panel's plane (docs/ALGORITHMS.md#depth-bands): exact, tighter on open
                                   // levels, slower
    bool slanted_cubes = false;    // slanted panels are drawn on the depth cubes too, inset per ray
                                   // (docs/ALGORITHMS.md#slanted-inset): exact, a little tighter on levels of
                                   // slopes and roofs, slower
    int shaft_budget = 64;  // [Limit: 0..4096] the shaft pass: an object the faces listed and no sight ray
                            // saw is tried once more against the whole eye region, cut into piece pairs
                            // each covered in one plane by panels and the proven solid, at most this many
                            // pairs per (cell, object) (pvs/shaft_hiding.h); 0 = off
    uint64_t shaft_max_pairs = 4'000'000;  // [Limit: >= 0] the shaft pass tries every leavable object over a
                                           // grid's cells (an octree level's boxes) when cells x leavable
                                           // objects is at most this, else the floor(this / cells) with the
                                           // most triangles (docs/ALGORITHMS.md#shaft-cap); 0 = no limit
    double shaft_min_share = 0.5;  // [Limit: 0..1] [Units: share] over the cap, the shaft pass runs only when
                                   // the objects it may try hold at least this share of the triangles of
                                   // those it may leave out (docs/ALGORITHMS.md#shaft-cap); 0 = always
    int shaft_block = 1;  // [Limit: 1..16] the shaft pass over a grid proves over blocks of this many cells
                          // along each axis and their halves down to single cells: what a node is proven
                          // hidden from, every cell of it leaves out (docs/ALGORITHMS.md#shaft-hierarchy);
                          // 1 = every cell alone
    bool shaft_early = false;  // with shaft_block > 1, before the faces each block's whole eye region tries
                               // every object no ray from it reaches: proven, no face of its cells tests
                               // it (docs/ALGORITHMS.md#shaft-early)
    int shaft_give_up = 0;  // [Limit: 0..4] a node of the shaft hierarchy of this level or higher whose two
                            // witnesses both fail to prove an object gives it up for all its cells (they
                            // keep it listed, untried): fewer failing tries, rows never below the per-cell
                            // pass's (docs/ALGORITHMS.md#shaft-give-up); 0 = never
    int shaft_probe_rays = 256;  // [Limit: 0..4096] before the shaft pass proves a (cell, object) pair, rays from
                                // this many seeded eye points of the cell, one at a random point of each
                                // object it would try, settle what they reach as visible
                                // (docs/ALGORITHMS.md#shaft-probe); 0 = off
    double shaft_small_spend = 8388608.0;  // [Limit: 0..1e12] [Units: piece pairs] a small bake's shaft pass
                                           // doubles its budget per (cell, object), at most six times and
                                           // to 4096, while cells x objects x the budget stay within this
                                           // (docs/ALGORITHMS.md#shaft-small); 0 = off
    bool shaft_fusion = true;  // the shaft pass's plane covers take in the umbrae of occluders in other
                               // planes (docs/ALGORITHMS.md#cross-plane-fusion); false for measurement
    bool shaft_caps = true;  // the shaft pass also covers piece pairs with the convex caps of panels meeting
                             // at edges (docs/ALGORITHMS.md#convex-caps); false for measurement
    bool shaft_cups = true;  // the shaft pass also covers piece pairs with cups, boxes around one piece whose
                             // faces are covered where sight leaves them (docs/ALGORITHMS.md#cups); false
                             // for measurement
    bool shaft_flood = true;  // the shaft pass also covers piece pairs the axis panels and the proven solid
                              // separate in the hull of their boxes, whatever planes they lie in
                              // (docs/ALGORITHMS.md#shaft-flood); false for measurement
    bool single_occluder_pass = true;  // first, what ONE occluder hides from a cell's whole eye region is
                                       // proven exactly (pvs/region_hiding.h); the faces skip it
    int refine_levels = 4;  // [Limit: 0..8] adaptive refinement: patches of a face are first tested
                            // with occluders shrunk by epsilon * 2^levels (few samples), and only the
                            // objects not yet proven hidden go to patches half the size, down to epsilon;
                            // at most: a bake stops at the level its largest cell can use
                            // (conservative_levels_used())
};

// The refinement levels a conservative bake of cells no larger than `cell_edge_m` can use: a cell face is
// solved from top patches of half-side at most edge / 2, which the level epsilon * 2^L >= edge / 2 already
// holds, so the levels above it would never be sampled, yet each costs a shrink of the whole solid. At most
// config.refine_levels; a patch larger than the top level is split before it is sampled, so fewer levels
// are always safe.
int conservative_levels_used(const ConservativeConfig& config, double cell_edge_m);

// Ray sampling from eye points in each cell: the sampled (aggressive) PVS and the verifier share it.
struct SampleConfig {
    uint32_t eyes_per_cell = 16;   // [Limit: >= 1] stratified random eye points per cell
    uint32_t rays_per_eye = 1024;  // [Limit: >= 1] stratified directions over the sphere per eye
    uint64_t ray_budget = 0;       // [Limit: >= 0] rays for the whole run; 0 = no cap. When the cells
                                   // would take more, rays per eye shrink evenly (never below 16)
    uint64_t seed = 1;             // [Limit: any] the same seed gives the same rays for any thread count
};

struct SampledPvsConfig {
    SampleConfig rays{16, 1024, 250'000'000, 1};  // a big world's rays per eye shrink to fit 250 M
    double guard_band_deg = 0.0;  // [Limit: 0..45] [Units: degrees] also list an object when a sampled ray
                                  // passed within this angle of its bounds; 0 = off
};

struct VerifyConfig {
    bool enabled = true;  // run verification after a bake
    // Not an option of its own: the driver copies GapConfig::tolerance_m (the bake's, when verifying a file).
    double gap_tolerance_m = kDefaultGapToleranceM;  // misses through narrower openings are reported apart
    SampleConfig rays{16, 1024, 200'000'000, 0x5eed5eedULL};
    uint32_t max_misses_reported = 1000;  // [Limit: >= 0] misses kept in the report and the file
    double aimed_share = 0.5;  // [Limit: 0..0.95] [Units: share] of the ray budget spent on rays aimed from
                               // fresh eye points at the objects the uniform rays did not touch; the
                               // uniform rays get the rest. 0 = uniform rays only (the figures before aimed
                               // rays). With no budget (0), each cell aims from eyes_per_cell eye points
    double aimed_listed_share =
        0.5;  // [Limit: 0..1] [Units: share] of a cell's aimed rays for the untouched
              // objects the PVS lists (they can only tighten the sampled set); the
              // untouched objects it leaves out (where misses hide) get the rest,
              // and either group gets what the other cannot use (docs/ALGORITHMS.md#verification)
    double neighbour_share = 0.5;  // [Limit: 0..1] [Units: share] of a cell's aimed rays kept for the
                                   // neighbour pass: rays from the cell at the points where the rays of the
                                   // cells around first touched objects its own rays did not
                                   // (docs/ALGORITHMS.md#verification). 0 = no neighbour pass
};

struct BakeConfig {
    BakeMode mode = BakeMode::kConservative;
    RunConfig run;
    GapConfig gap;
    ViewVolumeConfig view;
    CellConfig cells;
    OccluderConfig occluders;
    RankingConfig ranking;
    ConservativeConfig conservative;
    SampledPvsConfig sampled;
    VerifyConfig verify;
};

// The groups of options in `pvsbake bake --help` and docs/USAGE.md, in the order they are shown.
// kExperimental holds what is not proven or exists only to measure; its help says which.
enum class OptionGroup {
    kGeneral,
    kOutput,
    kViewVolume,
    kCells,
    kOccluders,
    kRanking,
    kConservative,
    kSampled,
    kVerification,
    kExperimental,
};
inline constexpr OptionGroup kOptionGroups[] = {
    OptionGroup::kGeneral,      OptionGroup::kOutput,      OptionGroup::kViewVolume,   OptionGroup::kCells,
    OptionGroup::kOccluders,    OptionGroup::kRanking,     OptionGroup::kConservative, OptionGroup::kSampled,
    OptionGroup::kVerification, OptionGroup::kExperimental};

// The group's title: "Cells", "Conservative solver", ...
const char* to_string(OptionGroup group);

// One declared option: its group, flag on the command line, key in the bake file, units, limits, help.
struct OptionSpec {
    OptionGroup group;
    const char* flag;   // "--cell-size"
    const char* key;    // "cells.cell_size_m"
    const char* units;  // "m", "rays", "" ...
    const char* help;
    double min = -std::numeric_limits<double>::infinity();
    double max = std::numeric_limits<double>::infinity();
};

// Calls v(spec, field) for every numeric or boolean option of the bake; fields are double, int,
// uint32_t, uint64_t or bool. The mode is an enum and is handled by its own option.
template <class Config, class Visitor>
void visit_options(Config& c, Visitor&& v) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    v(OptionSpec{OptionGroup::kGeneral, "--threads", "run.threads", "threads",
                 "worker threads, 0 = every core", 0, 4096},
      c.run.threads);
    v(OptionSpec{OptionGroup::kGeneral, "--checkpoint-interval", "run.checkpoint_interval_s", "s",
                 "seconds between checkpoints of a conservative bake's finished rows (in OUT.checkpoint/, "
                 "removed once OUT is written; a killed bake run again resumes from them); 0 = none",
                 0, 1e6},
      c.run.checkpoint_interval_s);
    v(OptionSpec{OptionGroup::kGeneral, "--max-memory", "run.max_memory_mib", "MiB",
                 "refuse a bake whose memory plan (printed before the flood and before the PVS) needs more; "
                 "0 = the machine's memory less a tenth",
                 0, 1e9},
      c.run.max_memory_mib);
    v(OptionSpec{OptionGroup::kGeneral, "--gap-tolerance", "gap.tolerance_m", "m",
                 "the promise: every object seen through an opening at least this wide is listed (a tube of "
                 "this diameter around the sight line clear of opaque triangles, ends excepted); "
                 "verification reports misses through narrower openings apart, and they do not fail it",
                 1e-6, 10},
      c.gap.tolerance_m);
    v(OptionSpec{OptionGroup::kViewVolume, "--voxel-size", "view.voxel_size_m", "m",
                 "voxel edge for the view volume and occluders, 0 = automatic (0.25 m, or epsilon / 2 if "
                 "smaller in "
                 "conservative mode; coarser for huge worlds)",
                 0, 100},
      c.view.voxel_size_m);
    v(OptionSpec{OptionGroup::kViewVolume, "--max-voxels", "view.max_voxels", "voxels",
                 "the voxels the automatic size aims at: it grows to stay within them up to --max-voxel-size; "
                 "past that a big level keeps voxels of --max-voxel-size, more of them, and the memory plan "
                 "decides",
                 1000, 1e10},
      c.view.max_voxels);
    v(OptionSpec{OptionGroup::kViewVolume, "--max-voxel-size", "view.max_voxel_size_m", "m",
                 "the automatic voxel size grows at most to this edge (and never past the cells' edge): a world "
                 "that would need coarser voxels to stay within --max-voxels is refused when an object stands "
                 "apart from the rest (a stray vertex?), naming it",
                 1e-4, 100},
      c.view.max_voxel_size_m);
    v(OptionSpec{OptionGroup::kViewVolume, "--allow-coarse-voxels", "view.allow_coarse_voxels", "",
                 "past --max-voxel-size, take the coarser voxels that fit --max-voxels instead (a world with an "
                 "object standing apart, or one too large for the grid, then bakes)"},
      c.view.allow_coarse_voxels);
    v(OptionSpec{OptionGroup::kViewVolume, "--eyes-anywhere", "view.eyes_anywhere", "",
                 "with no view seeds, view boxes or play height, eyes may be anywhere in the world's bounds "
                 "(a conservative bake is refused without a view volume otherwise)"},
      c.view.eyes_anywhere);
    v(OptionSpec{OptionGroup::kViewVolume, "--play-height", "view.play_height_m", "m",
                 "eyes only up to this height above upward-facing floors, 0 = anywhere", 0, 1e4},
      c.view.play_height_m);
    v(OptionSpec{OptionGroup::kCells, "--cell-size", "cells.cell_size_m", "m", "grid: edge of a cell", 0.01,
                 1e4},
      c.cells.cell_size_m);
    v(OptionSpec{OptionGroup::kCells, "--min-cell-size", "cells.min_cell_size_m", "m",
                 "octree: never split below this cell edge", 0.01, 1e4},
      c.cells.min_cell_size_m);
    v(OptionSpec{OptionGroup::kCells, "--root-cell-size", "cells.root_cell_size_m", "m",
                 "octree: edge of the root cells (min cell size times a power of two)", 0.01, 1e5},
      c.cells.root_cell_size_m);
    v(OptionSpec{OptionGroup::kCells, "--split-threshold", "cells.split_threshold", "share",
                 "octree: split where a child's PVS differs from its parent's by more than this share", 0, 1},
      c.cells.split_threshold);
    v(OptionSpec{OptionGroup::kCells, "--max-cells", "cells.max_cells", "cells",
                 "octree: stop splitting at this many cells, 0 = no limit", 0, 1e9},
      c.cells.max_cells);
    v(OptionSpec{OptionGroup::kOccluders, "--max-occluders", "occluders.max_occluders", "boxes",
                 "boxes kept at most", 1, 1e7},
      c.occluders.max_occluders);
    v(OptionSpec{OptionGroup::kOccluders, "--min-occluder-volume", "occluders.min_occluder_volume_m3", "m3",
                 "drop boxes smaller than this", 0, 1e12},
      c.occluders.min_occluder_volume_m3);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-probe-eyes", "occluders.probe_eyes", "eyes",
                 "eye points whose rays over the sphere carve seen voxels out of the solid, 0 = off", 0, 1e7},
      c.occluders.probe_eyes);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-probe-rays", "occluders.probe_rays_per_eye", "rays",
                 "rays per probe eye", 1, 1e8},
      c.occluders.probe_rays_per_eye);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-check-eyes", "occluders.check_eyes", "eyes",
                 "eye points whose rays check every box against the triangles", 1, 1e7},
      c.occluders.check_eyes);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-check-near-eyes", "occluders.check_near_eyes", "eyes",
                 "eye points within 4 m of each box that check it too (16 rays each; 0 = off)", 0, 1e6},
      c.occluders.check_near_eyes);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-gap-lines", "occluders.gap_lines", "lines",
                 "lines across each gap between two triangles near the solid, looking for openings at least "
                 "the gap tolerance wide (0 = off)",
                 0, 1e4},
      c.occluders.gap_lines);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-seal-rays", "occluders.seal_rays", "rays",
                 "rays from each voxel of the solid just behind a touched layer, looking for sight "
                 "through cracks narrower than a voxel (0 = off)",
                 0, 1e5},
      c.occluders.seal_rays);
    v(OptionSpec{OptionGroup::kOccluders, "--occluder-seal-reach", "occluders.seal_reach_m", "m",
                 "how far those rays look for eye space", 0.01, 1e5},
      c.occluders.seal_reach_m);
    v(OptionSpec{OptionGroup::kExperimental, "--occluder-block", "occluders.block_m", "m",
                 "EXPERIMENTAL, NOT PROVEN (its boxes rest on sampled ray checks, and bakes with it have had "
                 "misses: docs/RESULTS.md): occluders per block of cells of this edge (rounded to whole "
                 "cells), from the sight of the block's own eyes; 0 = off, one set for all cells",
                 0, 1e5},
      c.occluders.block_m);
    v(OptionSpec{OptionGroup::kExperimental, "--occluder-block-reach", "occluders.block_reach_m", "m",
                 "with --occluder-block: a block's own occluders are looked for this far around it", 0, 1e5},
      c.occluders.block_reach_m);
    v(OptionSpec{OptionGroup::kExperimental, "--occluder-block-min-gain", "occluders.block_min_gain", "share",
                 "with --occluder-block: a block keeps its own occluders only when its eyes leave more than "
                 "(1 + this) times the solid all eyes leave around it",
                 0, 1e6},
      c.occluders.block_min_gain);
    v(OptionSpec{OptionGroup::kExperimental, "--occluder-block-probe-eyes", "occluders.block_probe_eyes",
                 "eyes", "with --occluder-block: sight probe eyes per block, 0 = off", 0, 1e7},
      c.occluders.block_probe_eyes);
    v(OptionSpec{OptionGroup::kExperimental, "--occluder-block-check-eyes", "occluders.block_check_eyes",
                 "eyes", "with --occluder-block: ray check eyes per block", 1, 1e7},
      c.occluders.block_check_eyes);
    v(OptionSpec{OptionGroup::kRanking, "--occluders-per-cell", "ranking.occluders_per_cell", "boxes",
                 "ranked occluders kept per cell for run-time culling, best first; 0 = off", 0, 1024},
      c.ranking.occluders_per_cell);
    v(OptionSpec{OptionGroup::kRanking, "--min-solid-angle", "ranking.min_solid_angle_sr", "sr",
                 "a box is a candidate for a cell when its solid angle from some sampled "
                 "eye of the cell reaches this",
                 0, 12.566370614359172},
      c.ranking.min_solid_angle_sr);
    v(OptionSpec{OptionGroup::kRanking, "--ranking-eyes", "ranking.eyes_per_cell", "eyes",
                 "seeded eye points per cell for solid angle and depth complexity", 1, 1024},
      c.ranking.eyes_per_cell);
    v(OptionSpec{OptionGroup::kRanking, "--ranking-seed", "ranking.seed", "", "random seed of the eye points",
                 0, kInf},
      c.ranking.seed);
    v(OptionSpec{OptionGroup::kRanking, "--ranking-sight-lines", "ranking.sight_lines", "lines",
                 "sight lines per cell from its eyes to its PVS's objects: the occluders (proven boxes and "
                 "panels) that stop the most of them first are kept; 0 = rank boxes by solid angle and depth "
                 "complexity",
                 0, 1e6},
      c.ranking.sight_lines);
    v(OptionSpec{OptionGroup::kRanking, "--ranking-panel-area", "ranking.min_panel_area_m2", "m2",
                 "panels at least this large are candidates when ranking by sight", 0, 1e12},
      c.ranking.min_panel_area_m2);
    v(
        OptionSpec{
            OptionGroup::kRanking, "--ranking-polygons", "ranking.polygons", "",
            "by sight, slanted panels (convex polygons off the axis planes) at least --ranking-panel-area "
            "large are candidates too, stored as polygon occluders for the run-time culler"},
        c.ranking.polygons);
    v(
        OptionSpec{
            OptionGroup::kRanking, "--horizon-eyes", "ranking.horizon_eyes", "eyes",
            "seeded eyes per block of 4 x 4 x 4 cells whose run-time horizons choose the block's list of "
            "proven occluders (boxes, panels, slanted panels) for the runtime's horizon; 0 = no lists",
            0, 4096},
        c.ranking.horizon_eyes);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-columns", "ranking.horizon_columns", "columns",
                 "columns a side of the horizons that choose the lists", 4, 8192},
      c.ranking.horizon_columns);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-min-uses", "ranking.horizon_min_uses", "proofs",
                 "a block's list keeps the occluders that served in at least this many of its eyes' proofs",
                 1, 1e9},
      c.ranking.horizon_min_uses);
    v(
        OptionSpec{
            OptionGroup::kRanking, "--object-parts", "ranking.object_parts", "parts",
            "each object's surface is cut into up to this many part boxes for the run-time tests: an "
            "object whose bounds the culler or horizon does not hide is culled when they hide every part "
            "(kept where the parts hold less than 0.9 of the bounds' volume); 0 = none",
            0, 64},
        c.ranking.object_parts);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-list-max", "ranking.horizon_list_max", "occluders",
                 "a block's list keeps at most this many occluders, the most used first (fewer: a cheaper "
                 "frame, less culled); 0 = no limit",
                 0, 1e6},
      c.ranking.horizon_list_max);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-cell-eyes", "ranking.horizon_cell_eyes", "eyes",
                 "seeded eyes per cell whose horizons, from the block's list, choose the cell's own list (a "
                 "subset: a cheaper frame, as much culled); 0 = lists per block only",
                 0, 4096},
      c.ranking.horizon_cell_eyes);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-cell-lists-max", "ranking.horizon_cell_lists_max",
                 "entries",
                 "lists per cell only when the cells times their blocks' mean list length are at most this "
                 "(larger levels keep lists per block: per-cell lists would cost the bake an eye's horizon "
                 "for every cell and the runtime file a few bits an entry)",
                 0, 1e12},
      c.ranking.horizon_cell_lists_max);
    v(OptionSpec{OptionGroup::kRanking, "--horizon-cell-tests", "ranking.horizon_cell_tests", "",
                 "with lists per cell, each cell also keeps the objects of its PVS that its eyes' horizons "
                 "culled; a frame's horizon tests only those, the culler every object (a cheaper frame, a "
                 "little more drawn)"},
      c.ranking.horizon_cell_tests);
    v(OptionSpec{OptionGroup::kConservative, "--epsilon", "conservative.epsilon_m", "m",
                 "occluders shrink by this and cell faces are sampled within it", 0.01, 100},
      c.conservative.epsilon_m);
    v(OptionSpec{OptionGroup::kConservative, "--cube-resolution", "conservative.cube_resolution", "pixels",
                 "depth cube pixels per face edge", 8, 1024},
      c.conservative.cube_resolution);
    v(OptionSpec{OptionGroup::kConservative, "--fine-cube-resolution", "conservative.fine_cube_resolution",
                 "pixels",
                 "floor samples take a second look at what the cube could not prove on a "
                 "cube this fine (only over those objects' pixels); 0 = off",
                 0, 4096},
      c.conservative.fine_cube_resolution);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--corner-pairs", "conservative.corner_pairs", "",
            "two panels meeting along a line (a wall on a floor's edge, two walls at a corner) are drawn "
            "on the depth cubes as one occluder too: exact, about 5% fewer objects on an open level for "
            "about 1.8x the PVS stage there"},
        c.conservative.corner_pairs);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--panel-bands", "conservative.panel_bands", "",
            "a pixel a panel's inset leaves out still hides what lies near the panel's plane (just under "
            "a floor near its edge, just behind a wall's end): exact, about 2.5% fewer objects on an "
            "open level for about 1.3x the PVS stage there"},
        c.conservative.panel_bands);
    v(
        OptionSpec{
            OptionGroup::kExperimental, "--single-occluder-pass", "conservative.single_occluder_pass", "",
            "FOR MEASUREMENT ONLY: false turns off the exact single-occluder pass (what one panel or box "
            "hides from a cell's whole eye region), to measure what it gives: the same safety, a looser "
            "PVS"},
        c.conservative.single_occluder_pass);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--slanted-cubes", "conservative.slanted_cubes", "",
            "slanted panels (convex polygons of opaque triangles off the axis planes) are drawn on the "
            "depth cubes too, where they fuse with the other occluders: exact, a little tighter on levels "
            "of slopes and roofs, about 1.3x the PVS stage there"},
        c.conservative.slanted_cubes);
    v(OptionSpec{OptionGroup::kConservative, "--shaft-budget", "conservative.shaft_budget", "pairs",
                 "what the faces listed and no sight ray saw is tried once more from the whole eye region, "
                 "exactly, in piece pairs each covered in one plane by panels and the proven solid: at most "
                 "this many pairs per (cell, object); 0 = off",
                 0, 4096},
      c.conservative.shaft_budget);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--shaft-max-pairs", "conservative.shaft_max_pairs", "pairs",
            "the shaft pass tries every object over a grid's cells (an octree level's boxes) when their "
            "number times the objects is at most this; over it, only the (this / cells) objects with the "
            "most triangles, so that big levels keep their bake time where a frame pays most (the pass "
            "costs about a thread-millisecond a pair it tries); 0 = no limit",
            0, 1e15},
        c.conservative.shaft_max_pairs);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--shaft-min-share", "conservative.shaft_min_share", "share",
            "over --shaft-max-pairs, the shaft pass runs on the objects with the most triangles only when "
            "they hold at least this share of the level's triangles (the pass costs about the same "
            "whatever the share, and gains with it); 0 = always",
            0, 1},
        c.conservative.shaft_min_share);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--shaft-block", "conservative.shaft_block", "cells",
            "the shaft pass over a grid proves over blocks of this many cells along each axis, halved down "
            "to single cells: an object proven hidden from a node's whole eye region leaves every cell of "
            "it, and only what a node cannot prove, or a sight ray from one of its cells saw, goes to its "
            "halves; never looser than every cell alone (1)",
            1, 16},
        c.conservative.shaft_block);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--shaft-early", "conservative.shaft_early", "",
            "with --shaft-block, before the faces each block of cells tries once to prove hidden from its "
            "whole eye region every object that no probe ray from it reaches: what it proves, no face of "
            "its cells tests (the faces spend most of their time on what the shaft pass proves)"},
        c.conservative.shaft_early);
    v(OptionSpec{OptionGroup::kConservative, "--shaft-give-up", "conservative.shaft_give_up", "level",
                 "with --shaft-block, a node of the shaft hierarchy of this level or higher (1: 2 x 2 x 2 "
                 "cells) whose first and last listing cells both fail to prove an object gives it up for "
                 "all its cells: they keep it listed without a try of their own (most failing tries are "
                 "spent on objects no cell near them can prove); 0 = never",
                 0, 4},
      c.conservative.shaft_give_up);
    v(OptionSpec{OptionGroup::kConservative, "--shaft-small-spend", "conservative.shaft_small_spend",
                 "piece pairs",
                 "a small bake's shaft pass doubles --shaft-budget, at most six times and to 4096, while its "
                 "cells x objects x the budget stay within this many piece pairs (small bakes buy a tighter "
                 "PVS with seconds); 0 = off",
                 0, 1e12},
      c.conservative.shaft_small_spend);
    v(OptionSpec{OptionGroup::kConservative, "--shaft-probe-rays", "conservative.shaft_probe_rays", "rays",
                 "before the shaft pass proves an object hidden from a cell, rays from this many seeded eye "
                 "points of the cell, one at a random point of each object it would try, settle what they "
                 "reach as visible (a proof of it could only fail); 0 = off",
                 0, 4096},
      c.conservative.shaft_probe_rays);
    v(OptionSpec{OptionGroup::kExperimental, "--shaft-fusion", "conservative.shaft_fusion", "",
                 "FOR MEASUREMENT ONLY: false keeps the shaft pass's covers to one plane's own occluders (no "
                 "umbrae of occluders in other planes), to measure what cross-plane fusion gives: the same "
                 "safety, a looser PVS"},
      c.conservative.shaft_fusion);
    v(OptionSpec{OptionGroup::kExperimental, "--shaft-caps", "conservative.shaft_caps", "",
                 "FOR MEASUREMENT ONLY: false leaves out the shaft pass's convex caps (the hull of a panel and "
                 "its neighbours across edges that bend away, a ridge or an outer corner), to measure what "
                 "they give: the same safety, a looser PVS"},
      c.conservative.shaft_caps);
    v(OptionSpec{OptionGroup::kExperimental, "--shaft-cups", "conservative.shaft_cups", "",
                 "FOR MEASUREMENT ONLY: false leaves out the shaft pass's cups (a box around one piece whose "
                 "faces, where sight leaves it, are covered: a room's corner, a floor meeting walls), to "
                 "measure what they give: the same safety, a looser PVS"},
      c.conservative.shaft_cups);
    v(
        OptionSpec{
            OptionGroup::kExperimental, "--shaft-flood", "conservative.shaft_flood", "",
            "FOR MEASUREMENT ONLY: false leaves out the shaft pass's separation in the shaft (the axis "
            "panels and the proven solid cutting the hull of two pieces apart, whatever planes they lie "
            "in: a wall on a floor, a staircase), to measure what it gives: the same safety, a looser PVS"},
        c.conservative.shaft_flood);
    v(OptionSpec{OptionGroup::kConservative, "--panel-refine-levels", "conservative.panel_refine_levels",
                 "levels",
                 "floor patches are halved this many more times for the objects only the "
                 "panels may still prove (a panel's inset is the patch's half-size; boxes keep epsilon)",
                 0, 4},
      c.conservative.panel_refine_levels);
    v(
        OptionSpec{
            OptionGroup::kConservative, "--refine-levels", "conservative.refine_levels", "levels",
            "coarsest patches use occluders shrunk by epsilon * 2^levels; "
            "objects they cannot prove hidden go to half-size patches, down to epsilon (0 = no refinement; "
            "at most: the bake stops at the level its largest cell can use)",
            0, 8},
        c.conservative.refine_levels);
    v(OptionSpec{OptionGroup::kSampled, "--eyes", "sampled.eyes_per_cell", "eyes", "eye points per cell", 1,
                 1e6},
      c.sampled.rays.eyes_per_cell);
    v(OptionSpec{OptionGroup::kSampled, "--rays", "sampled.rays_per_eye", "rays", "rays per eye point", 1,
                 1e8},
      c.sampled.rays.rays_per_eye);
    v(OptionSpec{OptionGroup::kSampled, "--ray-budget", "sampled.ray_budget", "rays",
                 "rays for the whole bake, 0 = no cap (rays per eye shrink to fit)", 0, kInf},
      c.sampled.rays.ray_budget);
    v(OptionSpec{OptionGroup::kSampled, "--seed", "sampled.seed", "", "random seed", 0, kInf},
      c.sampled.rays.seed);
    v(OptionSpec{OptionGroup::kSampled, "--guard-band", "sampled.guard_band_deg", "degrees",
                 "also list objects a ray passed within this angle of, 0 = off", 0, 45},
      c.sampled.guard_band_deg);
    v(OptionSpec{OptionGroup::kVerification, "--verify-eyes", "verify.eyes_per_cell", "eyes",
                 "eye points per cell", 1, 1e6},
      c.verify.rays.eyes_per_cell);
    v(OptionSpec{OptionGroup::kVerification, "--verify-rays-per-eye", "verify.rays_per_eye", "rays",
                 "rays per eye point", 1, 1e8},
      c.verify.rays.rays_per_eye);
    v(OptionSpec{OptionGroup::kVerification, "--verify-rays", "verify.ray_budget", "rays",
                 "rays for the whole run, 0 = no cap (rays per eye shrink to fit)", 0, kInf},
      c.verify.rays.ray_budget);
    v(OptionSpec{OptionGroup::kVerification, "--verify-seed", "verify.seed", "",
                 "random seed (differs from the bake's)", 0, kInf},
      c.verify.rays.seed);
    v(OptionSpec{OptionGroup::kVerification, "--max-misses", "verify.max_misses_reported", "misses",
                 "misses kept in the report and the file", 0, 1e7},
      c.verify.max_misses_reported);
    v(OptionSpec{OptionGroup::kVerification, "--verify-aimed-share", "verify.aimed_share", "share",
                 "share of the rays aimed at points on the objects the uniform rays missed "
                 "(the uniform rays get the rest), 0 = uniform rays only",
                 0, 0.95},
      c.verify.aimed_share);
    v(OptionSpec{OptionGroup::kVerification, "--verify-aimed-listed-share", "verify.aimed_listed_share",
                 "share",
                 "share of a cell's aimed rays for the untouched objects the PVS lists (they "
                 "tighten the overestimation figure); the objects it leaves out (where misses hide) get the "
                 "rest, and each group gets what the other cannot use",
                 0, 1},
      c.verify.aimed_listed_share);
    v(OptionSpec{OptionGroup::kVerification, "--verify-neighbour-share", "verify.neighbour_share", "share",
                 "share of a cell's aimed rays for a second pass that aims from the cell at the "
                 "points where the rays of the cells around saw objects its own rays did not, 0 = no second "
                 "pass",
                 0, 1},
      c.verify.neighbour_share);
}

// Throws pvs::Error (bad input) naming the option when a value is outside its limits.
void validate(const BakeConfig& config);

// The resolved options as (key, value) text pairs, in declaration order, mode first.
std::vector<std::pair<std::string, std::string>> resolved_parameters(const BakeConfig& config);

// Options under "run." (threads ...) decide how a bake runs, never what it writes outside the run's own
// record: the bake file keeps them apart (/run/parameters), and a checkpoint or a reused bake need not
// match them.
inline bool is_run_parameter(const std::string& key) {
    return key.rfind("run.", 0) == 0;
}

// True for the ranking's options (ranking.*): they change no PVS row, only the ranked occluders, which every
// bake computes in full after the PVS (so a re-bake with --reuse may rank otherwise).
inline bool is_ranking_parameter(const std::string& key) {
    return key.rfind("ranking.", 0) == 0;
}

// The inverse: the config a bake was made with, from its stored parameters (keys not given keep their
// defaults). Throws pvs::Error (bad input) naming a key whose value does not parse.
BakeConfig config_from_parameters(const std::vector<std::pair<std::string, std::string>>& parameters);

}  // namespace pvs
