// SPDX-License-Identifier: MIT
// pvsbake rays: ray sampling from eye points of each cell, and the sampled PVS
// (docs/ALGORITHMS.md#sampled-pvs).
//
// The sampled PVS is AGGRESSIVE: the union of what the rays saw. It is tight and fast but can miss
// small or grazing objects that no ray happened to touch. Files and reports label it so.
// Determinism: eye points and directions depend only on (seed, cell, eye), so the result is the same
// for any thread count.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/pvs_set.h"
#include "core/world.h"
#include "rays/ray_scene.h"

#include <cstdint>
#include <vector>

namespace pvs {

// The rays of one cell and what they touched. Ray r of eye e has index e * rays_per_eye + r.
struct CellRays {
    uint32_t rays_per_eye = 0;
    std::vector<glm::vec3> eyes;
    std::vector<glm::vec3> directions;  // eyes.size() * rays_per_eye
    std::vector<RayTouch> touches;
};

// Rays per eye after fitting `cells` cells into the config's ray budget (never below kMinRaysPerEye,
// never above config.rays_per_eye).
constexpr uint32_t kMinRaysPerEye = 16;
uint32_t rays_per_eye_within_budget(const SampleConfig& config, size_t cells);

// Draws the eye points of `box` (under the view volume masks of `cells`) and their directions, and traces
// them; `stream` is a number unique to the box (the cell index for cells).
void trace_region(const RayScene& scene, const CellSet& cells, const Aabb& box, uint64_t stream,
                  const SampleConfig& config, uint32_t rays_per_eye, CellRays& out);

inline void trace_cell(const RayScene& scene, const CellSet& cells, uint32_t cell, const SampleConfig& config,
                       uint32_t rays_per_eye, CellRays& out) {
    trace_region(scene, cells, cells.cells[cell].bounds, cell, config, rays_per_eye, out);
}

// Objects every PVS lists whatever the rays say: those marked pvs_always_visible, and those whose
// bounds meet the cell's eye region (an eye may stand inside them).
void add_always_listed(const World& world, const CellSet& cells, PvsSet& pvs);

// The guard band (SampledPvsConfig::guard_band_deg): lists, in the cell's row, every object whose bounding
// sphere comes within `guard_band_rad` of a ray of the cell before the ray stops. Rays are binned per eye
// by direction (equal-area bins in (cos polar, azimuth), about two rays per bin) keeping the farthest
// reach per bin; an object is listed when a bin its widened cone covers reaches its sphere. Returns how
// many objects it added.
uint32_t add_guard_band(const World& world, const CellRays& rays, float guard_band_rad, uint64_t* row);

struct SampledPvs {
    PvsSet pvs;
    uint64_t guard_band_added = 0;  // (cell, object) pairs listed by the guard band alone
    uint64_t rays = 0;
    uint32_t rays_per_eye = 0;
    double seconds = 0.0;
};

// The sampled rows of arbitrary boxes (cells, or octree nodes being considered): every object a ray from
// the box touched, plus the guard band. rows: boxes.size() rows. Parallel over boxes.
void sample_box_rows(const SampledPvsConfig& config, const World& world, const RayScene& scene,
                     const CellSet& masks, const std::vector<Aabb>& boxes,
                     const std::vector<uint64_t>& streams, uint32_t rays_per_eye, PvsSet& rows,
                     uint64_t& guard_band_added, Context* progress);

// The sampled (aggressive) PVS: for every cell, every object a ray touched, plus add_always_listed().
SampledPvs bake_sampled_pvs(Context& ctx, const SampledPvsConfig& config, const World& world,
                            const RayScene& scene, const CellSet& cells);

}  // namespace pvs
