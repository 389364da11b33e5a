// SPDX-License-Identifier: MIT
// pvsbake occluders: ranking by SIGHT (docs/ALGORITHMS.md#ranking-sight): for a view cell, the occluders
// (proven boxes and panels) that stop first the most sampled sight lines from the cell's eyes to the objects
// of its PVS, so that the run-time culler, given the cell's best few, hides what the cell's eyes do not see
// of its PVS (docs/ALGORITHMS.md#runtime-faces).
//
// Conventions: glTF axes, metres. A sight line runs from one of the cell's sampled eyes to a uniform random
// point of an object of the cell's PVS, the object drawn with probability proportional to its triangles
// (the run-time figure is a share of triangles). Its FIRST occluder is the nearest candidate it meets before
// it comes within kSightEndMargin_m of its point (a panel under the point, or the box holding it, is not
// what hides it). Counts are exact for the sampled lines and depend only on (seed, cell): the same input
// gives the same ranking for any thread count.
#pragma once

#include "core/math.h"
#include "core/occluder.h"
#include "core/random.h"
#include "core/world.h"
#include "rays/ray_scene.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace pvs {

constexpr float kSightEndMargin_m = 0.01f;

// The candidate occluders as an opaque ray scene: candidate k is object k (a box as its 12 triangles; a
// panel, flat along one axis, as its rectangle), then the polygons, polygon j as candidate boxes.size() + j
// (its corners as a fan of triangles).
class OccluderSightScene {
public:
    OccluderSightScene(Context& ctx, const std::vector<Aabb>& candidates,
                       const std::vector<OccluderPolygon>& polygons = {});
    // For each segment eye[i] -> point[i]: the candidate it meets first, or UINT32_MAX.
    void first_hits(const glm::vec3* eyes, const glm::vec3* points, uint32_t count, uint32_t* first) const;
    const World& world() const { return world_; }

private:
    World world_;
    std::unique_ptr<RayScene> scene_;
};

// Counts, for one cell, how many of `lines` sight lines each candidate stops first: out[k] for candidate k
// (resized to the candidate count). `pvs_row` is the cell's PVS (bit i: object i); `cum_area` is
// cumulative_areas(world). No PVS object with triangles, or no eyes: all counts 0.
void count_first_hits(const OccluderSightScene& scene, const World& world,
                      const std::vector<double>& cum_area, const uint64_t* pvs_row,
                      const std::vector<glm::vec3>& eyes, uint32_t lines, Rng& rng,
                      std::vector<uint32_t>& out);

}  // namespace pvs
