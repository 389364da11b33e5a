// SPDX-License-Identifier: MIT
// pvsbake io: load a glTF 2.0 world (.gltf with external or embedded buffers, or .glb) into a World.
//
// Conventions: glTF axes (right-handed, +Y up), metres; every node transform (TRS or matrix) is applied,
// so the World is in world space. The default scene is loaded (scene 0 when none is set).
// - Each node that instances a mesh is one object, named by the node; repeated names are made unique
//   with the node's path in the tree ("parent/child"), then with "#<node index>" if still repeated;
//   unnamed nodes are "node<index>".
// - TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN are converted to triangles; POINTS and LINES are skipped
//   with a warning. Indexed and non-indexed; u8/u16/u32 indices; strided and sparse accessors; float,
//   and (KHR_mesh_quantization) normalized or integer positions.
// - alphaMode BLEND or MASK: not opaque (seen through, never occludes). OPAQUE or no material: opaque.
// - Node extras honoured: pvs_view_seed (node origin is a point in playable space), pvs_view_volume (the
//   node's mesh bounds are a box where eyes can be; the node is not an object), pvs_occluder: false
//   (never occludes: its triangles are see-through for visibility), pvs_always_visible (in every PVS).
// - Degenerate triangles (zero area or repeated indices) are dropped and counted in World::stats.
// Bad input throws pvs::Error (kBadInput) with a one-line message naming the file and what is wrong:
// missing or unreadable file, not glTF, truncated or corrupt binary, missing external buffer,
// out-of-range indices or accessors, NaN or infinite positions, POSITION data outside its accessor's
// declared min/max (beyond float rounding), ids, counts and offsets that break the schema
// (io/gltf_references.h), index and vertex data sharing bytes, a scene with no triangles. A triangle list
// whose count is not a multiple of 3 is drawn without its last one or two vertices, with a warning.
#pragma once

#include "core/context.h"
#include "core/world.h"

#include <string>

namespace pvs {

World load_world(Context& ctx, const std::string& path);

// The same from a file's bytes (a .glb, or a .gltf whose buffers are data: URIs): `name` stands for the path
// in messages; external files are never read (a URI naming one is bad input).
World load_world_from_memory(Context& ctx, const std::string& name, const std::string& bytes);

}  // namespace pvs
