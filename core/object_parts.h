// SPDX-License-Identifier: MIT
// Part boxes of objects: each object's triangles split into a few groups, each group's bounds a box, so that
// the run-time tests of an object whose bounds are not hidden can try its parts
// (docs/ALGORITHMS.md#object-parts).
//
// Contract: for every object o, every triangle of o lies wholly inside one of the boxes of its parts, and
// each part box lies inside o's bounds; so when every part box of o is hidden from an eye, every point of o
// is. An object keeps parts only when there are at least two and they hold less of the volume than its bounds
// (object_parts() below).
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

// The parts of every object: its triangles split at the median of their centres along the longest side of
// the centres' bounds, recursively, into at most `max_parts` groups (0 or 1: no parts); an object keeps them
// when the parts' boxes, each grown by kPartSlackM on every side, hold less than kPartVolumeShare of the
// volume of its bounds grown alike.
ObjectParts object_parts(const World& world, uint32_t max_parts);

constexpr double kPartSlackM = 0.01;
constexpr double kPartVolumeShare = 0.9;
constexpr uint32_t kMaxObjectParts = 64;

}  // namespace pvs
