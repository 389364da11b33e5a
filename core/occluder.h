// SPDX-License-Identifier: MIT
// pvsbake core: a synthesized occluder, an axis-aligned box inside the opaque solid.
//
// Conventions: glTF axes, metres. `proven`: the box passed the ray check against the real triangles
// (occluders/synthesis.h); only proven boxes may ever be used by a conservative bake.
#pragma once

#include "core/cell_set.h"
#include "core/math.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs {

struct Occluder {
    Aabb box;
    float voxel_size_m = 0.0f;  // the voxels it was found at
    bool proven = false;
    std::vector<uint32_t> objects;  // opaque objects whose bounds meet the box grown by one voxel
};

// One ranked occluder of a cell (occluders/ranking.h defines the score and the measures).
struct RankedOccluder {
    uint32_t box = 0;                    // index into the bake's occluders (always a proven one), or, from
                                         // their count B on, polygon box - B of the bake's polygons
    float score = 0.0f;                  // higher is better (occluders/ranking.h)
    float solid_angle_sr = 0.0f;         // largest exact solid angle from the cell's sampled eyes
    float hidden_objects = 0.0f;         // mean over the sampled eyes: objects wholly in its shadow
    float hidden_triangle_share = 0.0f;  // mean over the sampled eyes: share of the world's triangles
                                         // in objects wholly in its shadow
};

// A slanted panel (occluders/slanted_panels.h): a convex polygon in a plane that is not an axis plane, tiled
// exactly by opaque triangles sharing whole edges, all within `thickness` of the plane
// (docs/ALGORITHMS.md#slanted-panels).
struct SlantedPanel {
    glm::dvec3 normal{0.0};           // unit
    double offset = 0.0;              // the plane: dot(normal, x) = offset
    double thickness = 0.0;           // the largest distance of a corner of its triangles from the plane
    std::vector<glm::dvec3> corners;  // convex, counter-clockwise seen from the side normal points to
    // Per edge i, from corners[i] to corners[i + 1]: its inward unit normal m in the plane and the line
    // m.x = edge_offset[i] through it. The polygon's prism is where m.x >= offset for every edge.
    std::vector<glm::dvec3> edge_normal;
    std::vector<double> edge_offset;
    double area_m2 = 0.0;
    uint32_t triangles = 0;
    Aabb bounds;
};

// A POLYGON OCCLUDER for the run-time culler (docs/ALGORITHMS.md#runtime-polygons): a slanted panel made
// smaller and rounded to floats so that its promise holds as written: every segment that crosses the slab
// |dot(normal, x) - offset| <= thickness from one side to the other, entering and leaving it inside the prism
// over the corners (along the normal), meets an opaque triangle.
struct OccluderPolygon {
    glm::vec3 normal{0.0f};  // unit, to float rounding
    float offset = 0.0f;
    float thickness = 0.0f;
    std::vector<glm::vec3> corners;  // convex, counter-clockwise seen from the side normal points to; 3 to 8
                                     // (to 32 for a tile)
    Aabb bounds;                     // of the corners
    // A TILE: its corners, in order, bound a disk of opaque surface lying within its slab (a slanted panel
    // kept whole; docs/ALGORITHMS.md#runtime-horizon), so tiles sharing corners fuse exactly.
    bool tile = false;
};

// The ranked occluders of every cell: cell c has entries[offsets[c] .. offsets[c + 1]), best first.
// Empty offsets = no ranking (a bake made without it, or read from a file older than format 1.2).
struct RankedOccluders {
    std::vector<uint32_t> offsets;  // cells + 1 entries, from 0, never decreasing; or empty
    std::vector<RankedOccluder> entries;

    bool empty() const { return offsets.empty(); }
    uint32_t count(uint32_t cell) const {
        return cell + 1 < offsets.size() ? offsets[cell + 1] - offsets[cell] : 0;
    }
};

// The run-time horizon's occluders and the list each block of cells gives it (occluders/horizon_lists.h,
// docs/ALGORITHMS.md#horizon-lists). List l is entries[offsets[l] .. offsets[l + 1]), ascending; an entry
// below boxes.size() names a box (solid, or a panel flat along one axis), entry boxes.size() + t the tile
// tiles[t]. Every occluder is proven; cell c's list is cell_list[c]. Empty offsets: no lists.
struct HorizonLists {
    std::vector<Aabb> boxes;
    std::vector<OccluderPolygon> tiles;  // each with tile = true
    std::vector<uint32_t> cell_list;     // per cell
    std::vector<uint32_t> offsets;       // lists + 1, from 0, never decreasing
    std::vector<uint32_t> entries;
    // With lists per cell, optionally: cell c's frames give the horizon only the objects
    // tests[test_offsets[c] .. test_offsets[c + 1]) (ascending; the culler tests every object:
    // docs/ALGORITHMS.md#horizon-tests); both empty: the horizon tests every object.
    std::vector<uint32_t> test_offsets;  // cells + 1, from 0, never decreasing
    std::vector<uint32_t> tests;

    bool empty() const { return offsets.empty(); }
    size_t lists() const { return offsets.empty() ? 0 : offsets.size() - 1; }
    size_t occluders() const { return boxes.size() + tiles.size(); }
};

// The occluders of the conservative solver (pvs/conservative.h): the proven solid, and boxes of it shrunk
// by each epsilon of a ladder (every point of a box of level k has its whole epsilon_m[k]-cube, the ball in
// the Chebyshev metric, inside the proven solid: docs/ALGORITHMS.md#shrunk-occluders).
struct ShrunkOccluders {
    std::vector<double> epsilon_m;         // ascending, epsilon_m[0] is the floor (--epsilon)
    std::vector<std::vector<Aabb>> boxes;  // boxes[k]: shrunk by epsilon_m[k]
    // Flat rectangles covered by opaque triangles (occluders/panels.h), as found: the depth cube insets them
    // per ray for each patch's box (docs/ALGORITHMS.md#panel-inset).
    std::vector<Aabb> panels;
    // Convex polygons in other planes (occluders/slanted_panels.h), as found: the depth cube insets them per
    // ray for each patch's box (docs/ALGORITHMS.md#slanted-inset), and the single-occluder test
    // (pvs/region_hiding.h) uses them whole.
    std::vector<SlantedPanel> slanted;
    VoxelMask solid;  // the proven solid (sealed off from the eyes, untouched, passed the sight probe and the
                      // ray check): no sight line from the eye space enters it
                      // (docs/ALGORITHMS.md#sampled-step)
    VoxelMask free;   // voxels no opaque triangle touches, outside the proven solid: where sight from the eye
                      // space can be, and a ray started there sees as an eye would

    // Occluders per block of cells (occluders/synthesis.h, synthesize_block_occluders): squares of
    // block_size_m in x and z from block_origin; block_set[bx + block_dims.x * bz] indexes block_sets, or is
    // -1 where the block uses these occluders. A block set has the same epsilon ladder, its own boxes, panels
    // and solid, and an empty `free` (use this one's).
    float block_size_m = 0.0f;  // 0: no blocks
    glm::vec3 block_origin{0.0f};
    glm::ivec2 block_dims{0};
    float block_tolerance_m = 0.0f;  // a region may pass its block's square by this much (half a voxel:
                                     // the block's eye sources reach a whole voxel beyond it)
    std::vector<int32_t> block_set;
    std::vector<ShrunkOccluders> block_sets;

    // The set serving every eye of `region`: the block set whose square holds it, or -1 (these).
    int32_t set_for(const Aabb& region) const {
        if (block_size_m <= 0.0f || region.is_empty()) return -1;
        const float bx = std::floor((0.5f * (region.min.x + region.max.x) - block_origin.x) / block_size_m);
        const float bz = std::floor((0.5f * (region.min.z + region.max.z) - block_origin.z) / block_size_m);
        if (!(bx >= 0.0f && bz >= 0.0f && bx < float(block_dims.x) && bz < float(block_dims.y))) return -1;
        const float x0 = block_origin.x + bx * block_size_m, z0 = block_origin.z + bz * block_size_m;
        const float t = block_tolerance_m;
        if (region.min.x < x0 - t || region.max.x > x0 + block_size_m + t || region.min.z < z0 - t ||
            region.max.z > z0 + block_size_m + t) {
            return -1;
        }
        return block_set[size_t(bx) + size_t(block_dims.x) * size_t(bz)];
    }
    const ShrunkOccluders& set(int32_t i) const { return i < 0 ? *this : block_sets[size_t(i)]; }
};

}  // namespace pvs
