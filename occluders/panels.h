// pvsbake occluders: PANELS, flat axis-aligned rectangles wholly covered by opaque triangles: the faces of
// walls, floors and ceilings, found exactly from the triangles (no voxels). A wall thinner than about
// 2 epsilon + 2 voxels leaves no box in the solid once shrunk (occluders/boxes.h); its faces still give
// panels. Planar occluders as in the original occluder-shrinking work (P. Wonka, M. Wimmer,
// D. Schmalstieg, "Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs", EGWR 2000);
// how a panel is shrunk so that it stays safe for every point of a sample's ball is argued in
// pvs/conservative.h, point 8.
//
// Conventions: glTF axes (right-handed, +Y up, metres). A panel is an Aabb that is flat along one axis
// (min[axis] == max[axis], its PLANE); its other two extents are its rectangle. "Covered" means every point
// of the closed rectangle lies in some closed opaque triangle, so any segment that meets the rectangle
// meets an opaque triangle: sight does not pass it (from either side; rays stop at both sides of a
// triangle, as in the verification).
#pragma once

#include "core/math.h"
#include "core/world.h"

#include <vector>

namespace pvs {

struct PanelFigures {
    uint64_t flat_triangles = 0;  // opaque triangles lying in an axis-aligned plane
    uint64_t rectangles = 0;      // rectangles covered by a pair of them (two halves of a rectangle)
    uint64_t panels = 0;          // after merging rectangles that share a whole edge in the same plane
};

// The covered rectangles of the world's opaque triangles: each is two triangles that are the halves of an
// axis-aligned rectangle (cut along a diagonal), compared exactly; then rectangles of one plane that share
// a whole edge are merged while any do. Deterministic; rectangles covered only by other triangulations are
// not found (fewer panels is the safe side).
std::vector<Aabb> find_panels(const World& world, PanelFigures* figures = nullptr);

// Axis along which a panel is flat (min == max), or -1 when it is not a panel (flat along no axis, or along
// more than one).
int panel_axis(const Aabb& panel);

// Each panel with its rectangle shrunk by `inset_m` on all four sides; panels that vanish are dropped.
std::vector<Aabb> inset_panels(const std::vector<Aabb>& panels, double inset_m);

}  // namespace pvs
