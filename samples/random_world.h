// SPDX-License-Identifier: MIT
// Random closed box worlds: the property tests' worlds (tests/test_conservative.cpp), and the truth bench's
// random levels (samples/make_random_world.cpp writes one as .glb). Deterministic: the same seed and attempt
// give the same world on every machine (core/random.h).
#pragma once

#include "core/world.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

// Appends a box as one object: 12 triangles, or 10 with face `open_face` left out (0 and 1: z min and max;
// 2 and 3: y; 4 and 5: x). opaque = false: seen through (glass). Returns the object's index.
uint32_t add_box_object(World& world, const std::string& name, const Aabb& b, bool opaque = true,
                        uint32_t extra_flags = 0, int open_face = -1);

// Appends a prism standing on y0 up to y1 over the convex footprint `xz` (four corners, counterclockwise
// seen from above) as one opaque object; side k (from corner k to k + 1) is left out when open_side == k.
// Its faces are not axis-aligned rectangles, so no panel comes from it (occluders/panels.h).
uint32_t add_prism_object(World& world, const std::string& name, const std::array<glm::vec2, 4>& xz, float y0,
                          float y1, int open_side);

// A random closed room, inside [0, size] (x and z 12 to 16 m, y 3 to 4 m), shut by a floor, a roof and four
// walls 0.5 to 1 m thick, holding: one or two partitions across the room with a doorway, long thin walls (0.3
// to 0.6 m thick, along x or z, full height, low, or hanging from the roof like a lintel, some from a room
// wall), up to two walls turned off the axes (some hollow), pillars, crates (on the floor, stacked or in the
// air), see-through panes and blocks (opaque = false), and small targets (0.1 to 0.4 m, a fifth of them
// see-through) anywhere, some partly inside other boxes. Coordinates are random floats, on neither the voxel
// nor the cell grid. The view seeds are random points at least 0.2 m from every opaque box. `attempt` draws
// another world for the same seed (for one whose seeds all fell where no view volume can be built).
struct RandomWorld {
    World world;
    std::vector<Aabb> opaque;  // every opaque box (and each turned wall's bounds), to keep the seeds out of them
};
RandomWorld make_random_world(uint64_t seed, uint64_t attempt);

}  // namespace pvs
