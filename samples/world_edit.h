// SPDX-License-Identifier: MIT
// pvsbake samples: a world written again with edits of the kind a level designer makes between two bakes
// (an object moved or removed, the objects in a box removed, a hole cut, a crate added): the input of the
// incremental re-bake's tests and measures (samples/edit_world.cpp, docs/ALGORITHMS.md#reuse).
#pragma once

#include "core/world.h"
#include "io/gltf_writer.h"

#include <string>
#include <vector>

namespace pvs {

struct WorldEdit {
    enum class Kind { kMove, kRemove, kRemoveIn, kCut, kAddBox, kTile };
    Kind kind = Kind::kMove;
    std::string name;        // kMove, kRemove: the object; kAddBox: the new object's name
    Aabb box;                // kRemoveIn: objects wholly inside go; kCut: what lies inside goes (triangles
                             // are clipped, the hole's sides left open); kAddBox: the closed opaque box added
    glm::vec3 offset{0.0f};  // kMove; kTile: the step between copies (x and z)
    glm::ivec2 copies{1, 1};  // kTile: the whole edited world, copies.x x copies.y times along x and z,
                              // applied after every other edit; names get "@i,j"
};

// Four closed walls `thickness` metres thick around `bounds` (a world's), `thickness` metres outside it in x
// and z, from `thickness` below its bottom up to its top: sight leaving a leaking level stops at them, and
// no eye can stand above them. `outer` holds the world and its walls (the step of a tiling). Named
// enclosure_west, _east, _south, _north.
struct Enclosure {
    std::vector<WorldEdit> walls;  // kAddBox edits
    Aabb outer;
};
Enclosure enclosure(const Aabb& bounds, float thickness);

// The world as a scene to write (io/gltf_writer.h): every object as loaded (world-space triangles, one node
// per object and kind of triangle: opaque or see-through, one- or two-sided, so an object of one kind keeps
// its name), with its flags, the view seeds and the view-volume boxes; the edits applied in order. Throws
// pvs::Error (bad input) when an edit names no object or tiles no copy. Deterministic.
SceneDesc edited_world(const World& world, const std::vector<WorldEdit>& edits);

}  // namespace pvs
