// SPDX-License-Identifier: MIT
// pvsbake occluders: PANELS, flat axis-aligned rectangles wholly covered by opaque triangles: the faces of
// walls, floors and ceilings, found exactly from the triangles (no voxels). A wall thinner than about
// 2 epsilon + 2 voxels leaves no box in the solid once shrunk (occluders/boxes.h); its faces still give
// panels. Planar occluders as in the original occluder-shrinking work (P. Wonka, M. Wimmer,
// D. Schmalstieg, "Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs", EGWR 2000). How
// panels are found and why they stop sight: docs/ALGORITHMS.md#panels; how the depth cube insets a panel so
// that it stays safe for every point of a patch: docs/ALGORITHMS.md#panel-inset.
//
// Conventions: glTF axes (right-handed, +Y up, metres). A panel is an Aabb that is flat along one axis
// (min[axis] == max[axis], its PLANE); its other two extents are its rectangle. "Covered" means every point
// of the closed rectangle lies in some closed opaque triangle, so any segment that meets the rectangle
// meets an opaque triangle: sight does not pass it (from either side; rays stop at both sides of a
// triangle, as in the verification).
#pragma once

#include "core/math.h"
#include "core/world.h"

#include <array>
#include <cstdint>
#include <vector>

namespace pvs {

struct PanelFigures {
    uint64_t flat_triangles = 0;  // opaque triangles lying in an axis-aligned plane
    uint64_t planes = 0;          // distinct axis planes holding them
    uint64_t covered_cells = 0;   // cells of the planes' vertex-coordinate grids the triangles cover
    uint64_t panels = 0;          // maximal covered rectangles kept
};

// The covered rectangles of the world's opaque triangles. Per axis plane (vertices compared exactly), the
// grid of the distinct vertex coordinates cuts the plane into cells; a cell is covered when one triangle
// holds it or, failing that, the union of the triangles meeting it does (exact polygon subtraction in
// double; leftover slivers under 1e-12 m2 count as rounding along shared edges). Any triangulation is
// found: pairs of halves, fans of a brush face, T-junctions, faces of several meshes meeting. Panels are
// MAXIMAL rectangles of covered cells, grown from every cell not yet in one (u first and v first), so they
// overlap: a point deep in the covered region is deep in some panel, and the inset
// (docs/ALGORITHMS.md#panel-inset) costs only at the region's edges. Rectangles inside another are dropped.
// Deterministic.
std::vector<Aabb> find_panels(const World& world, PanelFigures* figures = nullptr);

// Axis along which a panel is flat (min == max), or -1 when it is not a panel (flat along no axis, or along
// more than one).
int panel_axis(const Aabb& panel);

// The CORNER PAIRS of a set of panels (pvs/depth_cube.h, add_corner(); docs/ALGORITHMS.md#corner-pairs):
// index pairs {i, j}, i < j, of panels flat along different axes n_i and n_j that meet along a line: panel
// i's extent along n_j holds panel j's plane, panel j's extent along n_i holds panel i's plane (both closed,
// compared exactly), and their extents along the third axis overlap by more than nothing. An L (a wall
// ending on a floor, two walls at a corner), a T (a wall standing on a floor) and a cross all qualify.
// In index order; deterministic.
std::vector<std::array<uint32_t, 2>> panel_corners(const std::vector<Aabb>& panels);

// Each panel with its rectangle shrunk by `inset_m` on all four sides; panels that vanish are dropped.
std::vector<Aabb> inset_panels(const std::vector<Aabb>& panels, double inset_m);

}  // namespace pvs
