// SPDX-License-Identifier: MIT
// Test helpers: build small glTF 2.0 files by hand (JSON with nlohmann plus one binary buffer) and write
// them as .gltf with an external .bin, .gltf with a base64 data: URI, or .glb. Header-only.
#pragma once

#include "tests/test_util.h"

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace pvs::test {

constexpr int kGlByte = 5120;
constexpr int kGlUnsignedByte = 5121;
constexpr int kGlShort = 5122;
constexpr int kGlUnsignedShort = 5123;
constexpr int kGlUnsignedInt = 5125;
constexpr int kGlFloat = 5126;

inline std::string base64_encode(const std::string& in) {
    static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const uint32_t v = (uint32_t(uint8_t(in[i])) << 16) | (uint32_t(uint8_t(in[i + 1])) << 8) |
                           uint32_t(uint8_t(in[i + 2]));
        out += kTable[(v >> 18) & 63];
        out += kTable[(v >> 12) & 63];
        out += kTable[(v >> 6) & 63];
        out += kTable[v & 63];
    }
    if (i + 1 == in.size()) {
        const uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += kTable[(v >> 18) & 63];
        out += kTable[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        const uint32_t v = (uint32_t(uint8_t(in[i])) << 16) | (uint32_t(uint8_t(in[i + 1])) << 8);
        out += kTable[(v >> 18) & 63];
        out += kTable[(v >> 12) & 63];
        out += kTable[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

// The GLB container around a JSON text and a BIN payload (both padded here).
inline std::string make_glb_bytes(std::string json_text, std::string bin) {
    while (json_text.size() % 4 != 0) json_text.push_back(' ');
    while (bin.size() % 4 != 0) bin.push_back('\0');
    auto u32 = [](uint32_t v) {
        std::string s(4, '\0');
        std::memcpy(s.data(), &v, 4);
        return s;
    };
    const uint32_t total = uint32_t(12 + 8 + json_text.size() + (bin.empty() ? 0 : 8 + bin.size()));
    std::string out =
        u32(0x46546C67) + u32(2) + u32(total) + u32(uint32_t(json_text.size())) + u32(0x4E4F534A) + json_text;
    if (!bin.empty()) out += u32(uint32_t(bin.size())) + u32(0x004E4942) + bin;
    return out;
}

// Splits a well-formed .glb into its JSON text and BIN payload (empty when absent).
inline bool split_glb(const std::string& glb, std::string* json_text, std::string* bin) {
    if (glb.size() < 20 || glb.compare(0, 4, "glTF") != 0) return false;
    uint32_t json_len = 0;
    std::memcpy(&json_len, glb.data() + 12, 4);
    if (20 + size_t(json_len) > glb.size()) return false;
    *json_text = glb.substr(20, json_len);
    bin->clear();
    const size_t bin_header = 20 + size_t(json_len);
    if (bin_header + 8 <= glb.size()) {
        uint32_t bin_len = 0;
        std::memcpy(&bin_len, glb.data() + bin_header, 4);
        if (bin_header + 8 + bin_len > glb.size()) return false;
        *bin = glb.substr(bin_header + 8, bin_len);
    }
    return true;
}

// A glTF document under construction: json is public so a test can poke any field.
class GltfBuilder {
public:
    nlohmann::json json;
    std::string bin;  // buffer 0

    GltfBuilder() {
        json = {{"asset", {{"version", "2.0"}, {"generator", "pvsbake tests"}}}};
        json["bufferViews"] = nlohmann::json::array();
        json["accessors"] = nlohmann::json::array();
        json["meshes"] = nlohmann::json::array();
        json["nodes"] = nlohmann::json::array();
    }

    // Appends bytes to the buffer (4-byte aligned) as a new bufferView; returns its index.
    int add_view(const std::string& bytes, size_t stride = 0) {
        while (bin.size() % 4 != 0) bin.push_back('\0');
        nlohmann::json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
        if (stride != 0) v["byteStride"] = stride;
        bin += bytes;
        json["bufferViews"].push_back(v);
        return int(json["bufferViews"].size()) - 1;
    }

    int add_accessor(int view, int component_type, size_t count, const std::string& type,
                     size_t byte_offset = 0, bool normalized = false) {
        nlohmann::json a = {{"componentType", component_type}, {"count", count}, {"type", type}};
        if (view >= 0) a["bufferView"] = view;
        if (byte_offset != 0) a["byteOffset"] = byte_offset;
        if (normalized) a["normalized"] = true;
        json["accessors"].push_back(a);
        return int(json["accessors"].size()) - 1;
    }

    // Tightly packed float positions with min/max.
    int add_positions(const std::vector<glm::vec3>& p) {
        std::string bytes(p.size() * 12, '\0');
        if (!p.empty()) std::memcpy(bytes.data(), p.data(), bytes.size());
        const int a = add_accessor(add_view(bytes), kGlFloat, p.size(), "VEC3");
        set_min_max(a, p);
        return a;
    }

    // Float positions interleaved at the given stride (>= 12), padding filled with 0xCD.
    int add_strided_positions(const std::vector<glm::vec3>& p, size_t stride) {
        std::string bytes(p.size() * stride, '\xCD');
        for (size_t i = 0; i < p.size(); ++i) std::memcpy(bytes.data() + i * stride, &p[i], 12);
        const int a = add_accessor(add_view(bytes, stride), kGlFloat, p.size(), "VEC3");
        set_min_max(a, p);
        return a;
    }

    // Indices as u8, u16 or u32 (component_type kGlUnsigned*).
    int add_indices(const std::vector<uint32_t>& idx, int component_type = kGlUnsignedInt) {
        std::string bytes;
        for (uint32_t v : idx) {
            if (component_type == kGlUnsignedByte) {
                bytes.push_back(char(uint8_t(v)));
            } else if (component_type == kGlUnsignedShort) {
                const uint16_t s = uint16_t(v);
                bytes.append(reinterpret_cast<const char*>(&s), 2);
            } else {
                bytes.append(reinterpret_cast<const char*>(&v), 4);
            }
        }
        return add_accessor(add_view(bytes), component_type, idx.size(), "SCALAR");
    }

    template <class T>
    int add_raw(const std::vector<T>& values, int component_type, size_t count, const std::string& type,
                bool normalized = false) {
        std::string bytes(values.size() * sizeof(T), '\0');
        if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
        return add_accessor(add_view(bytes), component_type, count, type, 0, normalized);
    }

    void set_min_max(int accessor, const std::vector<glm::vec3>& p) {
        if (p.empty()) return;
        glm::vec3 lo = p[0], hi = p[0];
        for (const glm::vec3& v : p) {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        }
        json["accessors"][size_t(accessor)]["min"] = {lo.x, lo.y, lo.z};
        json["accessors"][size_t(accessor)]["max"] = {hi.x, hi.y, hi.z};
    }

    // A primitive object; indices < 0 = non-indexed; mode 4 = TRIANGLES.
    static nlohmann::json primitive(int positions, int indices = -1, int mode = 4, int material = -1) {
        nlohmann::json p = {{"attributes", {{"POSITION", positions}}}, {"mode", mode}};
        if (indices >= 0) p["indices"] = indices;
        if (material >= 0) p["material"] = material;
        return p;
    }

    int add_mesh(const std::vector<nlohmann::json>& primitives) {
        json["meshes"].push_back({{"primitives", primitives}});
        return int(json["meshes"].size()) - 1;
    }

    // A node; extra fields (translation, children, extras...) can be given in `fields`.
    int add_node(const std::string& name, int mesh = -1, nlohmann::json fields = nlohmann::json::object()) {
        if (!name.empty()) fields["name"] = name;
        if (mesh >= 0) fields["mesh"] = mesh;
        json["nodes"].push_back(fields);
        return int(json["nodes"].size()) - 1;
    }

    int add_material(const std::string& alpha_mode, bool double_sided = false) {
        if (!json.contains("materials")) json["materials"] = nlohmann::json::array();
        nlohmann::json m = {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}}}};
        if (!alpha_mode.empty()) m["alphaMode"] = alpha_mode;
        if (double_sided) m["doubleSided"] = true;
        json["materials"].push_back(m);
        return int(json["materials"].size()) - 1;
    }

    void set_scene(const std::vector<int>& roots) {
        json["scene"] = 0;
        json["scenes"] = nlohmann::json::array({{{"nodes", roots}}});
    }

    // The document with buffer 0 pointing at uri ("" = the GLB BIN chunk).
    std::string json_text(const std::string& uri) const {
        nlohmann::json doc = json;
        if (!bin.empty()) {
            nlohmann::json buffer = {{"byteLength", padded_bin().size()}};
            if (!uri.empty()) buffer["uri"] = uri;
            doc["buffers"] = nlohmann::json::array({buffer});
        }
        return doc.dump(1);
    }

    std::string padded_bin() const {
        std::string b = bin;
        while (b.size() % 4 != 0) b.push_back('\0');
        return b;
    }

    // <dir>/<stem>.gltf + <dir>/<stem>.bin; returns the .gltf path.
    std::string write_gltf(const TempDir& dir, const std::string& stem) const {
        const std::string path = dir.file(stem + ".gltf");
        write_file(path, json_text(stem + ".bin"));
        write_file(dir.file(stem + ".bin"), padded_bin());
        return path;
    }

    std::string write_embedded(const TempDir& dir, const std::string& stem) const {
        const std::string path = dir.file(stem + ".gltf");
        write_file(path, json_text("data:application/octet-stream;base64," + base64_encode(padded_bin())));
        return path;
    }

    std::string glb_bytes() const { return make_glb_bytes(json_text(""), padded_bin()); }

    std::string write_glb(const TempDir& dir, const std::string& stem) const {
        const std::string path = dir.file(stem + ".glb");
        write_file(path, glb_bytes());
        return path;
    }
};

}  // namespace pvs::test
