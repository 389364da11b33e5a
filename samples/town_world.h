// SPDX-License-Identifier: MIT
// A generated town: a big open level (a ground slab of some hundred metres, blocks of closed box buildings
// of random heights, streets between them, a view seed at every crossing). The worlds "a big world is not a
// fault" is checked on (tests/test_world_extent.cpp) and measured with (samples/make_town_world.cpp,
// docs/RESULTS.md). Deterministic: the same parameters give the same world on every machine (core/random.h).
//
// Conventions: glTF axes (+Y up), metres. The ground's top is y = 0; the town is centred on x = z = 0.
#pragma once

#include "core/world.h"

#include <cstdint>

namespace pvs {

struct TownParams {
    float size_m = 330.0f;       // the ground's edge along x and z
    float block_m = 30.0f;       // a block's edge (four buildings, 2 x 2, with 2 m lanes between them)
    float street_m = 10.0f;      // the streets between blocks
    float min_height_m = 6.0f;   // the buildings' heights, uniform in [min, max]; one building per block row
    float max_height_m = 46.0f;  // reaches the maximum, so that the town's height is max_height_m
    uint64_t seed = 1;
};

// The ground ('ground', a 1 m slab), the buildings ('building_<i>_<j>_<k>', closed boxes) and a view seed
// 1.5 m above every street crossing.
World make_town_world(const TownParams& params);

}  // namespace pvs
