// SPDX-License-Identifier: MIT
// pvsbake io: make_box_node and write_glb, simple triangle scenes written as one glTF 2.0 binary (.glb):
// JSON built with nlohmann, one buffer of float VEC3 positions and u32 indices in the BIN chunk.
#include "io/gltf_writer.h"

#include "io/atomic_file.h"

#include "core/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cstring>

namespace pvs {
namespace {

static_assert(std::endian::native == std::endian::little, "GLB is little-endian");

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kGlbVersion = 2;
constexpr uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kComponentUnsignedInt = 5125;
constexpr int kComponentFloat = 5126;
constexpr int kTargetArrayBuffer = 34962;
constexpr int kTargetElementArrayBuffer = 34963;
constexpr int kModeTriangles = 4;

bool finite4(const glm::vec4& v) {
    return is_finite(glm::vec3(v)) && std::isfinite(v.w);
}

void append_u32(std::string& out, uint32_t v) {
    char b[4];
    std::memcpy(b, &v, 4);
    out.append(b, 4);
}

void pad_to_4(std::string& s, char fill) {
    while (s.size() % 4 != 0) s.push_back(fill);
}

// Appends raw bytes to the BIN chunk, 4-byte aligned, and returns their offset.
size_t append_bytes(std::string& bin, const void* data, size_t size) {
    pad_to_4(bin, '\0');
    const size_t offset = bin.size();
    bin.append(static_cast<const char*>(data), size);
    return offset;
}

void check_scene(const SceneDesc& scene) {
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        if (!finite4(scene.materials[m].base_color)) {
            throw bad_input(fmt::format("write_glb: material {} '{}': base color is not finite", m,
                                        scene.materials[m].name));
        }
    }
    for (size_t i = 0; i < scene.nodes.size(); ++i) {
        const SceneNode& node = scene.nodes[i];
        const std::string where = fmt::format("write_glb: node {} '{}'", i, node.name);
        if (node.material < -1 || node.material >= int(scene.materials.size())) {
            throw bad_input(fmt::format("{}: material {} out of range ({} materials)", where, node.material,
                                        scene.materials.size()));
        }
        if (node.indices.size() % 3 != 0) {
            throw bad_input(fmt::format("{}: {} indices, not a multiple of 3", where, node.indices.size()));
        }
        for (size_t k = 0; k < node.indices.size(); ++k) {
            if (node.indices[k] >= node.positions.size()) {
                throw bad_input(fmt::format("{}: index {} = {} out of range ({} positions)", where, k,
                                            node.indices[k], node.positions.size()));
            }
        }
        for (const glm::vec3& p : node.positions) {
            if (!is_finite(p)) throw bad_input(fmt::format("{}: a position is not finite", where));
        }
        if (!is_finite(node.translation)) {
            throw bad_input(fmt::format("{}: translation is not finite", where));
        }
    }
}

const char* alpha_mode(SceneMaterial::Alpha alpha) {
    switch (alpha) {
        case SceneMaterial::Alpha::kOpaque:
            return "OPAQUE";
        case SceneMaterial::Alpha::kBlend:
            return "BLEND";
        case SceneMaterial::Alpha::kMask:
            return "MASK";
    }
    return "OPAQUE";
}

}  // namespace

SceneNode make_box_node(const std::string& name, const Aabb& box, int material) {
    SceneNode node;
    node.name = name;
    node.material = material;
    // Corner k has x = max when bit 0 is set, y = max for bit 1, z = max for bit 2.
    for (int k = 0; k < 8; ++k) {
        node.positions.emplace_back((k & 1) ? box.max.x : box.min.x, (k & 2) ? box.max.y : box.min.y,
                                    (k & 4) ? box.max.z : box.min.z);
    }
    // Two triangles per face, counter-clockwise seen from outside (normals point out).
    node.indices = {
        0, 4, 6, 0, 6, 2,  // -X
        1, 3, 7, 1, 7, 5,  // +X
        0, 1, 5, 0, 5, 4,  // -Y
        2, 6, 7, 2, 7, 3,  // +Y
        0, 2, 3, 0, 3, 1,  // -Z
        4, 5, 7, 4, 7, 6,  // +Z
    };
    return node;
}

void write_glb(const SceneDesc& scene, const std::string& path) {
    check_scene(scene);
    using nlohmann::json;

    json doc;
    doc["asset"] = {{"version", "2.0"}, {"generator", "pvsbake"}};
    std::string bin;
    json buffer_views = json::array();
    json accessors = json::array();
    json meshes = json::array();
    json nodes = json::array();
    json materials = json::array();

    for (const SceneMaterial& m : scene.materials) {
        json jm;
        if (!m.name.empty()) jm["name"] = m.name;
        jm["pbrMetallicRoughness"] = {
            {"baseColorFactor", {m.base_color.r, m.base_color.g, m.base_color.b, m.base_color.a}}};
        if (m.alpha != SceneMaterial::Alpha::kOpaque) jm["alphaMode"] = alpha_mode(m.alpha);
        if (m.double_sided) jm["doubleSided"] = true;
        materials.push_back(std::move(jm));
    }

    for (const SceneNode& node : scene.nodes) {
        json jn;
        if (!node.name.empty()) jn["name"] = node.name;
        if (node.translation != glm::vec3(0.0f)) {
            jn["translation"] = {node.translation.x, node.translation.y, node.translation.z};
        }
        if (!node.indices.empty()) {
            Aabb bounds;
            for (const glm::vec3& p : node.positions) bounds.extend(p);
            const size_t pos_bytes = node.positions.size() * sizeof(glm::vec3);
            const size_t pos_offset = append_bytes(bin, node.positions.data(), pos_bytes);
            buffer_views.push_back({{"buffer", 0},
                                    {"byteOffset", pos_offset},
                                    {"byteLength", pos_bytes},
                                    {"target", kTargetArrayBuffer}});
            accessors.push_back({{"bufferView", buffer_views.size() - 1},
                                 {"componentType", kComponentFloat},
                                 {"count", node.positions.size()},
                                 {"type", "VEC3"},
                                 {"min", {bounds.min.x, bounds.min.y, bounds.min.z}},
                                 {"max", {bounds.max.x, bounds.max.y, bounds.max.z}}});
            const size_t position_accessor = accessors.size() - 1;

            const size_t idx_bytes = node.indices.size() * sizeof(uint32_t);
            const size_t idx_offset = append_bytes(bin, node.indices.data(), idx_bytes);
            buffer_views.push_back({{"buffer", 0},
                                    {"byteOffset", idx_offset},
                                    {"byteLength", idx_bytes},
                                    {"target", kTargetElementArrayBuffer}});
            accessors.push_back({{"bufferView", buffer_views.size() - 1},
                                 {"componentType", kComponentUnsignedInt},
                                 {"count", node.indices.size()},
                                 {"type", "SCALAR"}});
            json primitive = {{"attributes", {{"POSITION", position_accessor}}},
                              {"indices", accessors.size() - 1},
                              {"mode", kModeTriangles}};
            if (node.material >= 0) primitive["material"] = node.material;
            json mesh = {{"primitives", json::array({primitive})}};
            if (!node.name.empty()) mesh["name"] = node.name;
            meshes.push_back(std::move(mesh));
            jn["mesh"] = meshes.size() - 1;
        }
        json extras = json::object();
        if (node.view_seed) extras["pvs_view_seed"] = true;
        if (node.view_volume) extras["pvs_view_volume"] = true;
        if (!node.occluder) extras["pvs_occluder"] = false;
        if (node.always_visible) extras["pvs_always_visible"] = true;
        if (!extras.empty()) jn["extras"] = std::move(extras);
        nodes.push_back(std::move(jn));
    }
    pad_to_4(bin, '\0');

    json roots = json::array();
    for (size_t i = 0; i < scene.nodes.size(); ++i) roots.push_back(i);
    doc["scene"] = 0;
    doc["scenes"] = json::array({{{"nodes", roots}}});
    if (!nodes.empty()) doc["nodes"] = std::move(nodes);
    if (!meshes.empty()) doc["meshes"] = std::move(meshes);
    if (!materials.empty()) doc["materials"] = std::move(materials);
    if (!accessors.empty()) doc["accessors"] = std::move(accessors);
    if (!buffer_views.empty()) doc["bufferViews"] = std::move(buffer_views);
    if (!bin.empty()) doc["buffers"] = json::array({{{"byteLength", bin.size()}}});

    std::string json_text = doc.dump();
    pad_to_4(json_text, ' ');

    const uint64_t total = 12 + 8 + uint64_t(json_text.size()) + (bin.empty() ? 0 : 8 + uint64_t(bin.size()));
    if (total > 0xFFFFFFFFull) {
        throw bad_input(fmt::format("write_glb: {}: scene too large for a .glb ({} bytes)", path, total));
    }
    std::string out;
    out.reserve(size_t(total));
    append_u32(out, kGlbMagic);
    append_u32(out, kGlbVersion);
    append_u32(out, uint32_t(total));
    append_u32(out, uint32_t(json_text.size()));
    append_u32(out, kGlbChunkJson);
    out += json_text;
    if (!bin.empty()) {
        append_u32(out, uint32_t(bin.size()));
        append_u32(out, kGlbChunkBin);
        out += bin;
    }
    if (out.size() != total) throw internal_error(fmt::format("write_glb: {}: size mismatch", path));
    write_file_atomically(path, out, "the glTF file");
}

}  // namespace pvs
