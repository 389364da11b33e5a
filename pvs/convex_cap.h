// SPDX-License-Identifier: MIT
// pvsbake solver: convex caps, the shaft pass's occluders that fuse panels of different planes meeting at an
// edge (a roof ridge, the outer corner of a pillar, a bevel). A cap is the convex hull P of a few opaque
// convex polygons that are faces of P. A segment from a point outside P that meets P enters it through a
// face the point sees; when every face that a piece of eyes sees is one of the opaque polygons, every
// segment from the piece that meets P is stopped. And every segment between two boxes meets the convex P
// when the 64 segments between their corners do. The argument: docs/ALGORITHMS.md#convex-caps.
//
// Contract: cap_hides(cap, from, to) is true only if every segment from a point of box `from` to a point of
// box `to` meets an opaque polygon of the cap (both boxes grown by kHideToleranceM, P shrunk by it). Any
// segment from a box the cap guards (cap_guards) that reaches a point of P's interior has met one before.
#pragma once

#include "core/math.h"
#include "core/occluder.h"

#include <cstdint>
#include <vector>

namespace pvs {

// An opaque convex polygon: every point of it lies on an opaque triangle of the world.
struct CapPolygon {
    std::vector<glm::dvec3> corners;  // convex, in order (either way round)
    glm::dvec3 normal{0.0};           // unit
    double offset = 0.0;              // the plane: dot(normal, x) = offset
};

// The hull P of a cap's polygons, as faces dot(normal[k], x) <= offset[k], each face opaque when it lies
// inside one of the polygons. Empty (no faces) when the polygons bound no volume.
struct ConvexCap {
    std::vector<glm::dvec3> normal;
    std::vector<double> offset;
    std::vector<uint8_t> opaque;
    uint32_t polygons = 0;  // how many polygons it was made of
    Aabb bounds;            // of the polygons' corners
    bool empty() const { return normal.empty(); }
};

// The opaque polygons of a set of occluders, indexed as the shaft pass indexes them: each panel (a flat
// box; none for a box flat along no axis), then each slanted panel of no thickness (none for a slab with
// thickness).
std::vector<CapPolygon> cap_polygons(const std::vector<Aabb>& panels, const std::vector<SlantedPanel>& slanted);

// The hull of `polygons`, its faces found among the planes through three of their corners (the polygons are
// few: a cap has at most kMaxCapPolygons). Empty when the corners are too many or span no volume.
ConvexCap make_cap(const std::vector<const CapPolygon*>& polygons);

// For every polygon and each of its two sides (2 * i for the side its normal points to, 2 * i + 1 for the
// other): the cap of the polygon with those of its edge neighbours (polygons sharing a piece of an edge,
// not coplanar) that bend away from that side, so that all of them are faces of their hull seen from it.
// Empty where no neighbour bends away. Deterministic: neighbours in index order.
std::vector<ConvexCap> build_caps(const std::vector<CapPolygon>& polygons);

// See the contract above. The test: cap_guards(cap, from), and each of the 64 segments between the grown
// boxes' corners meets P shrunk by the tolerance.
bool cap_hides(const ConvexCap& cap, const Aabb& from, const Aabb& to);

// Does every segment from a point of box `from` (grown by kHideToleranceM) that meets P meet an opaque polygon
// of the cap first? True when `from` lies strictly outside one face of P and every face that one of its
// corners sees, or lies on, is opaque (docs/ALGORITHMS.md#convex-caps).
bool cap_guards(const ConvexCap& cap, const Aabb& from);

// The cross-section of P shrunk by kHideToleranceM with the plane x[axis] = c, in the plane's coordinates
// (axis + 1, axis + 2), clipped to the rectangle [lo, hi]: convex, counter-clockwise; empty when none. A
// segment from a box the cap guards that crosses the plane there has met an opaque polygon of the cap.
void cap_slice(const ConvexCap& cap, int axis, double c, glm::dvec2 lo, glm::dvec2 hi,
               std::vector<glm::dvec2>& out, std::vector<glm::dvec2>& scratch);

}  // namespace pvs
