// SPDX-License-Identifier: MIT
// pvsbake io: the glTF document's numbers that name or size things (ids, counts, offsets, enums), checked
// against the glTF 2.0 schema before the loader trusts them: an integer, within its minimum and enum, an
// id that names an existing element (the Khronos glTF-Validator's TYPE_MISMATCH, VALUE_NOT_IN_RANGE,
// INVALID_VALUE and UNRESOLVED_REFERENCE). A parser that reads such a property as "absent" when it does
// not fit an int would otherwise drop a mesh or a primitive's indices without a word.
//
// Conventions: JSON pointers in messages ("meshes[0].primitives[1].indices"); only the properties a world
// load reads (scenes, nodes, meshes, accessors, bufferViews, buffers, materials by id).
#pragma once

#include <cstdint>
#include <string>

namespace pvs {

// Throws pvs::Error (bad input) "PATH: meshes[0].primitives[0].indices is 1.8e+19, not an index of
// accessors (4 of them)" on the first property that breaks its rule; nothing on a document that is not
// JSON (the parser reports that). `json_text` is the whole JSON (the .gltf, or a .glb's JSON chunk);
// `bin_bytes` the length of a .glb's BIN chunk, which buffer 0 without a uri must fit
// (BUFFER_BYTE_LENGTH_MISMATCH), or kNoBinChunk, or kNotGlb for a .gltf.
constexpr int64_t kNoBinChunk = -1;
constexpr int64_t kNotGlb = -2;
void check_gltf_references(const std::string& path, const std::string& json_text, int64_t bin_bytes);

}  // namespace pvs
