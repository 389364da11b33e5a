// SPDX-License-Identifier: MIT
// pvsbake samples: the crack test set, worlds of openings of known kind and width
// (docs/ALGORITHMS.md#crack-test-set).
//
// Conventions: glTF axes, metres. Every CASE is a compartment of two sealed rooms (closed boxes all round)
// divided by one wall of thickness `wall_m` that has one opening of `width_m`; a spawn point (view seed) in
// room A, a target box in room B, the opening between them, the whole compartment turned by a random
// rotation and placed on a grid. Room B holds no eye: if the opening stays closed, room B is solid and
// hides the target; if it is found, the target is seen, from the WITNESS eye in room A along a line through
// the middle of the opening square to the wall (a line exactly `width_m` wide). So a conservative bake with
// gap tolerance T must list the target in the witness eye's cell whenever width_m >= T.
// Deterministic: the same spec gives the same scene.
#pragma once

#include "core/math.h"
#include "io/gltf_writer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

enum class CrackKind {
    kSlit,       // a straight slit through the wall, 1 m tall, walled above and below
    kLSlit,      // an L-shaped slit (a vertical arm and a horizontal one, both of the width)
    kSeam,       // a seam from floor to ceiling between two closed box meshes with matching vertices
    kTJunction,  // the same seam, one side cut into three boxes: its vertices fall mid-edge on the other's
    kHole,       // a hollow wall of two sheets (one mesh each, shared vertices), each missing one triangle: a
                 // right triangle whose inscribed circle is the opening, the two holes in line
};
inline constexpr CrackKind kCrackKinds[] = {CrackKind::kSlit, CrackKind::kLSlit, CrackKind::kSeam,
                                            CrackKind::kTJunction, CrackKind::kHole};
const char* to_string(CrackKind kind);

struct CrackCase {
    CrackKind kind = CrackKind::kSlit;
    float width_m = 0.0f;
    float wall_m = 0.0f;
    glm::vec3 witness_eye{0.0f};   // in room A, on the line through the middle of the opening
    glm::vec3 room_b_point{0.0f};  // in room B on that line, halfway from the wall to the target: in the
                                   // solid exactly when the opening stayed closed
    std::string target;            // the target object's name (node name) in room B
};

struct CrackSetSpec {
    std::vector<float> widths_m;                       // one batch of cases per width
    std::vector<float> walls_m = {0.02f, 0.1f, 0.3f};  // wall thicknesses, taken in turn
    std::vector<CrackKind> kinds = {std::begin(kCrackKinds), std::end(kCrackKinds)};  // taken in turn
    uint32_t cases_per_width = 8;  // per width, all kinds together
    uint64_t seed = 1;
};

struct CrackSet {
    SceneDesc scene;
    std::vector<CrackCase> cases;
};

// The cases of `spec`, all in one scene (compartments 6 m apart on a grid).
CrackSet make_crack_set(const CrackSetSpec& spec);

}  // namespace pvs
