// SPDX-License-Identifier: MIT
// pvsbake occluders: SLANTED PANELS, convex polygons in planes that are not axis planes, tiled exactly by
// opaque triangles that share whole edges: the slopes, ramps and roofs that axis-aligned boxes and panels
// (occluders/panels.h) cannot cover. docs/ALGORITHMS.md#slanted-panels says how they are grown and what
// they promise; the solver's single-occluder test uses them (pvs/region_hiding.h). The struct is
// core/occluder.h's SlantedPanel.
//
// Conventions: glTF axes (right-handed, +Y up, metres). A slanted panel's triangles all lie within
// `thickness` of its plane dot(normal, x) = offset, and their union is exactly its polygon (each triangle
// added across an edge of the polygon so far, on the far side of that edge): a segment from one side of the
// slab |dot(normal, x) - offset| <= thickness to the other whose slab part stays over the polygon meets an
// opaque triangle.
#pragma once

#include "core/math.h"
#include "core/occluder.h"
#include "core/world.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct SlantedPanelFigures {
    uint64_t slanted_triangles = 0;  // opaque triangles not in an axis plane
    double slanted_area_m2 = 0.0;
    uint64_t panels = 0;  // polygons kept (at least min_area_m2)
    uint64_t triangles_in_panels = 0;
    double panel_area_m2 = 0.0;
};

// Sets the panel's edge lines from its normal and corners; false when an edge is degenerate or it has fewer
// than three corners.
bool set_slanted_edges(SlantedPanel& panel);

// The slanted panels of the world's opaque triangles, largest triangle first as seed: a polygon grows by
// a triangle that shares one of its edges (vertex positions compared exactly), whose third corner lies
// beyond that edge and within max_thickness_m of the seed's plane, and that keeps it convex. Each triangle
// joins at most one polygon. Polygons under min_area_m2 are dropped. T-junctions stop the growth (an
// edge must be shared whole). Deterministic.
std::vector<SlantedPanel> find_slanted_panels(const World& world, double max_thickness_m, double min_area_m2,
                                              SlantedPanelFigures* figures = nullptr);

// The run-time culler's polygon occluders (docs/ALGORITHMS.md#runtime-polygons) of the panels of at least
// min_area_m2: each reduced to at most 8 corners by dropping corners (a convex polygon's corners span a part
// of it), shrunk towards its centre by kPolygonInsetM, rounded to floats with its slab grown by
// kPolygonSlabGrowM, and kept only when the float form is checked (in double, at the corners of its prism's
// part in its slab) to lie inside the panel's prism and to cross the panel's slab from side to side: then the
// float form's promise (core/occluder.h) follows from the panel's. Deterministic.
constexpr double kPolygonInsetM = 1e-3;
constexpr double kPolygonSlabGrowM = 1e-3;
constexpr size_t kPolygonMaxCorners = 8;
std::vector<OccluderPolygon> runtime_polygons(const std::vector<SlantedPanel>& panels, double min_area_m2);

// The run-time horizon's TILES (docs/ALGORITHMS.md#runtime-horizon) of the panels of at least min_area_m2
// and at most kTileMaxCorners corners: each panel whole, its corners the float vertices they are (so
// neighbouring panels share them exactly), its plane rounded to floats and its slab the corners' largest
// distance from that plane as the runtime reads it (in double), grown by kTileSlabGrowM and rounded up. A
// panel's triangles are the hulls of some of its corners, so they lie in that slab and bound, with the
// corners, a disk: the tile's promise. Kept only when its corners turn one way about the float normal.
constexpr double kTileSlabGrowM = 1e-6;
constexpr size_t kTileMaxCorners = 32;
std::vector<OccluderPolygon> runtime_tiles(const std::vector<SlantedPanel>& panels, double min_area_m2);

}  // namespace pvs
