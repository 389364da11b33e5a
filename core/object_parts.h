// SPDX-License-Identifier: MIT
// Part boxes of objects: each object's surface cut by axis planes into a few pieces, each piece's bounds a
// box, so that the run-time tests of an object whose bounds are not hidden can try its parts
// (docs/ALGORITHMS.md#object-parts).
//
// Contract: for every object o, every point of every triangle of o lies in one of the boxes of its parts
// (closed boxes), and each part box lies inside o's bounds; so when every part box of o is hidden from an
// eye, every point of o is. An object keeps parts only when there are at least two and they hold less of the
// volume than its bounds (object_parts() below).
#pragma once

#include "core/math.h"
#include "core/world.h"

#include <cstdint>
#include <vector>

namespace pvs {

// Per object, its part boxes: object o's are boxes[offsets[o] .. offsets[o + 1]) (none, or 2 to max_parts).
struct ObjectParts {
    std::vector<uint32_t> offsets;  // objects + 1 (empty: no parts at all)
    std::vector<Aabb> boxes;
    uint32_t count(uint32_t o) const { return offsets.empty() ? 0 : offsets[o + 1] - offsets[o]; }
};

// The part boxes of one object, at most `max_parts` (at least one when it has a triangle): its triangles as
// polygons, cut greedily, each time the part whose best cut saves the most, by the cut that saves the most of
// the parts' cost (the area of their boxes grown by kPartSlackM), among the planes at each
// 1 / kPartCutsPerAxis of the part's box on each axis; a part is the bounds of its polygons' corners rounded
// outward to floats, met with the object's bounds. Cutting stops when no cut saves any cost.
std::vector<Aabb> object_part_boxes(const World& world, uint32_t object, uint32_t max_parts);

// The parts of every object (none when max_parts < 2): object_part_boxes(), kept when there are at least two
// whose boxes, each grown by kPartSlackM on every side, hold less than kPartVolumeShare of the volume of the
// object's bounds grown alike, and the object is not flagged always visible.
ObjectParts object_parts(const World& world, uint32_t max_parts);

constexpr double kPartSlackM = 0.01;
constexpr double kPartVolumeShare = 0.9;
constexpr uint32_t kMaxObjectParts = 64;
constexpr int kPartCutsPerAxis = 8;

}  // namespace pvs
