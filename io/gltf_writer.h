// SPDX-License-Identifier: MIT
// pvsbake io: write simple triangle scenes as glTF 2.0 binary (.glb): the sample world generator, test
// worlds and (later) the synthesized occluder boxes use it.
//
// Conventions: glTF axes (right-handed, +Y up), metres. Positions are written in world space; each
// SceneNode becomes one node with its own mesh (one primitive, TRIANGLES, u32 indices) or, with no
// triangles, an empty node at `translation` (a view seed, say). The file is written whole or not at all.
#pragma once

#include "core/math.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

struct SceneMaterial {
    enum class Alpha { kOpaque, kBlend, kMask };
    std::string name;
    glm::vec4 base_color{0.8f, 0.8f, 0.8f, 1.0f};
    Alpha alpha = Alpha::kOpaque;
    bool double_sided = false;
};

struct SceneNode {
    std::string name;
    std::vector<glm::vec3> positions;  // world space when translation is zero
    std::vector<uint32_t> indices;     // triangles; empty with empty positions = an empty node
    int material = -1;                 // index into SceneDesc::materials, -1 = none (opaque default)
    glm::vec3 translation{0.0f};
    // Extras the baker honours (written only when they differ from the default).
    bool view_seed = false;
    bool view_volume = false;
    bool occluder = true;
    bool always_visible = false;
};

struct SceneDesc {
    std::vector<SceneMaterial> materials;
    std::vector<SceneNode> nodes;  // all roots of scene 0
};

// A closed box (12 triangles, outward facing) as a node.
SceneNode make_box_node(const std::string& name, const Aabb& box, int material = -1);

// Writes the scene as .glb. Throws pvs::Error on failure and leaves no file behind.
void write_glb(const SceneDesc& scene, const std::string& path);

}  // namespace pvs
