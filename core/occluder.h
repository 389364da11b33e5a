// pvsbake core: a synthesized occluder, an axis-aligned box inside the opaque solid.
//
// Conventions: glTF axes, metres. `proven`: the box passed the ray check against the real triangles
// (pvs/occluder_synthesis.h); only proven boxes may ever be used by a conservative bake.
#pragma once

#include "core/math.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct Occluder {
    Aabb box;
    float voxel_size_m = 0.0f;  // the voxels it was found at
    bool proven = false;
    std::vector<uint32_t> objects;  // opaque objects whose bounds meet the box grown by one voxel
};

}  // namespace pvs
