// pvsbake cells: where eyes can be. The ONE place that decides it: the sampled PVS, the verifier and
// (later) occluder ranking all draw their eye points here.
//
// Today an eye may be anywhere in its cell's box (there is no view volume yet). The view-cell issue
// replaces eye_region() with cell ∩ view volume, never inside solid, and every user follows.
//
// Sampling is stratified: the region is split into about `count` strata along its axes (a k x k x k
// grid, shuffled) and one jittered point is drawn in each. The points depend only on (seed, cell).
#pragma once

#include "core/cell_set.h"

#include <cstdint>
#include <vector>

namespace pvs {

// The box eye points of a cell are drawn from.
Aabb eye_region(const CellSet& cells, uint32_t cell);

// Appends `count` stratified random eye points of the cell to `out`.
void sample_eye_points(const CellSet& cells, uint32_t cell, uint32_t count, uint64_t seed,
                       std::vector<glm::vec3>& out);

// Appends `count` directions stratified over the whole sphere (equal-area strata in (cos theta, phi),
// one jittered direction per stratum). Unit length.
void sample_sphere_directions(uint32_t count, uint64_t seed, uint64_t stream, std::vector<glm::vec3>& out);

}  // namespace pvs
