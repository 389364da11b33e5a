// SPDX-License-Identifier: MIT
// pvsbake core: the World, a glTF scene flattened into world-space triangles grouped into objects.
//
// Conventions: glTF axes (right-handed, +Y up), metres, world space (every node transform applied).
// An object is one glTF node that instances a mesh: the unit a game draws and a PVS lists. Its
// triangles are the contiguous range [first_triangle, first_triangle + triangle_count).
// "Opaque" is per triangle: the material's alphaMode is OPAQUE (or absent) and the object may occlude
// (it is not marked pvs_occluder: false). Only opaque triangles may ever stop sight; everything else is
// seen through but its object is still an occludee (it can be seen).
#pragma once

#include "core/math.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

enum ObjectFlags : uint32_t {
    kObjectHasOpaque = 1u << 0,      // at least one triangle stops sight
    kObjectHasSeeThrough = 1u << 1,  // at least one triangle is BLEND or MASK (or never occludes)
    kObjectAlwaysVisible = 1u << 2,  // extras.pvs_always_visible: listed in every PVS
    kObjectNeverOccludes = 1u << 3,  // extras.pvs_occluder == false
};

struct Triangle {
    uint32_t v[3];
};

struct WorldObject {
    std::string name;       // unique in the world (node name, made unique with its path when repeated)
    std::string node_path;  // names from the scene root down, joined by '/'
    int32_t node_index = -1;
    Aabb bounds;
    uint32_t first_triangle = 0;
    uint32_t triangle_count = 0;
    uint32_t flags = 0;  // ObjectFlags
};

struct LoadStats {
    uint64_t degenerate_triangles_dropped = 0;
    uint64_t primitives_skipped = 0;  // POINTS and LINES
    uint64_t nodes_visited = 0;
};

struct World {
    std::string source_path;
    std::vector<glm::vec3> positions;      // world space, metres
    std::vector<Triangle> triangles;       // grouped by object
    std::vector<uint8_t> triangle_opaque;  // 1 if the triangle stops sight
    std::vector<uint8_t> triangle_double_sided;
    std::vector<WorldObject> objects;
    std::vector<glm::vec3> view_seeds;    // extras.pvs_view_seed nodes: points in playable space
    std::vector<Aabb> view_volume_boxes;  // extras.pvs_view_volume nodes: boxes where eyes can be
    Aabb bounds;                          // of all triangles
    LoadStats stats;

    size_t triangle_count() const { return triangles.size(); }
    size_t object_count() const { return objects.size(); }
};

}  // namespace pvs
