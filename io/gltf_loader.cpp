// SPDX-License-Identifier: MIT
// pvsbake io: load_world, a glTF 2.0 file (.gltf or .glb) flattened into a World of world-space triangles.
//
// tinygltf parses the JSON and the buffers; everything it hands back is then treated as untrusted: every
// index, count, offset and stride is checked here before a byte is read, so a corrupt or hostile file
// gives a one-line pvs::Error (kBadInput), never a crash. The GLB container is validated here too before
// tinygltf sees it (tinygltf 2.7.0 reads up to 8 bytes past a BIN chunk whose length field overruns
// the file by less than its 8-byte chunk header).
#include "io/gltf_loader.h"

#include "core/error.h"
#include "io/gltf_references.h"

#include <fmt/format.h>
#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <unordered_map>
#include <vector>

namespace pvs {
namespace {

static_assert(std::endian::native == std::endian::little, "glTF buffers are little-endian");

constexpr uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"
constexpr size_t kGlbHeaderBytes = 12;
constexpr size_t kGlbChunkHeaderBytes = 8;

constexpr int kComponentByte = 5120;
constexpr int kComponentUnsignedByte = 5121;
constexpr int kComponentShort = 5122;
constexpr int kComponentUnsignedShort = 5123;
constexpr int kComponentUnsignedInt = 5125;
constexpr int kComponentFloat = 5126;

// A triangle is degenerate when |e1 x e2|^2 <= kDegenerateSin2 * |e1|^2 * |e2|^2, i.e. the sine of its
// angle at the first corner is below 1e-6: zero area up to float rounding of positions in metres.
constexpr double kDegenerateSin2 = 1e-12;
// An accessor with no bufferView is all zeros plus its sparse values; nothing in the file backs its count,
// so it may exceed its sparse count only up to this, which keeps a corrupt count from allocating gigabytes.
constexpr uint64_t kMaxUnbackedElements = uint64_t(1) << 20;
// tinygltf's messages can quote a whole data: URI; keep ours to one readable line.
constexpr size_t kMaxQuotedChars = 300;

constexpr uint32_t kUnmapped = std::numeric_limits<uint32_t>::max();

// Squashes a multi-line message to one line and caps its length.
std::string one_line(const std::string& text) {
    std::string out;
    out.reserve(std::min(text.size(), kMaxQuotedChars + 3));
    bool space = false;
    for (char c : text) {
        const bool blank = c == '\n' || c == '\r' || c == '\t' || c == ' ';
        if (blank) {
            space = !out.empty();
            continue;
        }
        if (space) out.push_back(' ');
        space = false;
        out.push_back(std::isprint(static_cast<unsigned char>(c)) ? c : '?');
        if (out.size() >= kMaxQuotedChars) {
            out += "...";
            break;
        }
    }
    return out;
}

// Image decoding is never needed: a no-op loader keeps textures (present, missing or corrupt) out of it.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
    return true;
}

std::string read_input_file(const std::string& path) {
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status)) throw bad_input(fmt::format("{}: file not found", path));
    if (std::filesystem::is_directory(status)) {
        throw bad_input(fmt::format("{}: is a folder, not a glTF file", path));
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw bad_input(fmt::format("{}: cannot open the file for reading (permissions?)", path));
    std::string bytes;
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    if (size < 0) throw bad_input(fmt::format("{}: cannot read the file", path));
    bytes.resize(size_t(size));
    in.seekg(0, std::ios::beg);
    if (!bytes.empty() && !in.read(bytes.data(), std::streamsize(bytes.size()))) {
        throw bad_input(fmt::format("{}: cannot read the file", path));
    }
    return bytes;
}

uint32_t read_u32(const std::string& bytes, size_t offset) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + offset, 4);
    return v;
}

// Checks the GLB header and chunk layout (what tinygltf trusts too much). Returns the length to parse.
size_t check_glb_container(const std::string& path, const std::string& bytes) {
    const size_t size = bytes.size();
    if (size < kGlbHeaderBytes + kGlbChunkHeaderBytes) {
        throw bad_input(
            fmt::format("{}: truncated .glb: {} bytes, shorter than the GLB headers", path, size));
    }
    const uint32_t version = read_u32(bytes, 4);
    const uint32_t length = read_u32(bytes, 8);
    if (version != 2) {
        throw bad_input(
            fmt::format("{}: unsupported GLB container version {} (glTF 2.0 needs 2)", path, version));
    }
    if (length > size) {
        throw bad_input(
            fmt::format("{}: truncated .glb: its header says {} bytes, the file has {}", path, length, size));
    }
    if (length < kGlbHeaderBytes + kGlbChunkHeaderBytes) {
        throw bad_input(fmt::format("{}: corrupt .glb: header length {} is too small", path, length));
    }
    const uint64_t json_length = read_u32(bytes, 12);
    const uint32_t json_type = read_u32(bytes, 16);
    if (json_type != kGlbChunkJson) {
        throw bad_input(fmt::format("{}: corrupt .glb: the first chunk is not JSON", path));
    }
    const uint64_t json_end = kGlbHeaderBytes + kGlbChunkHeaderBytes + json_length;
    if (json_length == 0 || json_end > length) {
        throw bad_input(
            fmt::format("{}: truncated or corrupt .glb: JSON chunk of {} bytes does not fit in "
                        "{} bytes",
                        path, json_length, length));
    }
    if (json_end < length) {
        if (json_end + kGlbChunkHeaderBytes > length) {
            throw bad_input(fmt::format("{}: truncated .glb: incomplete BIN chunk header", path));
        }
        const uint64_t bin_length = read_u32(bytes, size_t(json_end));
        const uint32_t bin_type = read_u32(bytes, size_t(json_end) + 4);
        if (bin_type != kGlbChunkBin) {
            throw bad_input(fmt::format("{}: corrupt .glb: the second chunk is not BIN", path));
        }
        if (json_end + kGlbChunkHeaderBytes + bin_length > length) {
            throw bad_input(
                fmt::format("{}: truncated .glb: BIN chunk of {} bytes runs past the end ({} bytes)", path,
                            bin_length, length));
        }
        if (bin_length < 4 || bin_length % 4 != 0) {
            throw bad_input(fmt::format(
                "{}: corrupt .glb: BIN chunk length {} is not a positive multiple of 4", path, bin_length));
        }
    }
    return length;
}

bool looks_like_json(const std::string& bytes) {
    size_t i = 0;
    if (bytes.size() >= 3 && std::memcmp(bytes.data(), "\xEF\xBB\xBF", 3) == 0) i = 3;  // UTF-8 BOM
    while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
    return i < bytes.size() && bytes[i] == '{';
}

bool no_file_exists(const std::string&, void*) {
    return false;
}

std::string path_as_is(const std::string& path, void*) {
    return path;
}

bool no_file_read(std::vector<unsigned char>*, std::string* err, const std::string& path, void*) {
    if (err) *err += fmt::format("external file '{}' is not read: the world was given as bytes", path);
    return false;
}

bool no_file_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing files is not allowed";
    return false;
}

tinygltf::Model parse_gltf(Context& ctx, const std::string& path, const std::string& bytes, bool files) {
    if (bytes.size() > std::numeric_limits<uint32_t>::max()) {
        throw bad_input(fmt::format("{}: file too large for glTF (4 GiB or more)", path));
    }
    const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
    size_t length = bytes.size();
    if (binary) {
        length = check_glb_container(path, bytes);
    } else if (!looks_like_json(bytes)) {
        throw bad_input(fmt::format("{}: not a glTF file (neither a GLB header nor a JSON object)", path));
    }

    std::string base_dir = std::filesystem::path(path).parent_path().string();
    if (base_dir.empty()) base_dir = ".";

    // The numbers tinygltf reads as "absent" when they do not fit its ints (io/gltf_references.h).
    if (binary) {
        const size_t json_end = kGlbHeaderBytes + kGlbChunkHeaderBytes + read_u32(bytes, 12);
        const int64_t bin = json_end < length ? int64_t(read_u32(bytes, json_end)) : kNoBinChunk;
        check_gltf_references(path, bytes.substr(kGlbHeaderBytes + kGlbChunkHeaderBytes, read_u32(bytes, 12)), bin);
    } else {
        check_gltf_references(path, bytes.substr(0, length), kNotGlb);
    }

    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(&skip_image, nullptr);
    if (!files) gltf.SetFsCallbacks({&no_file_exists, &path_as_is, &no_file_read, &no_file_write, nullptr});
    tinygltf::Model model;
    std::string err;
    std::string warn;
    bool ok = false;
    try {
        const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
        if (binary) {
            ok = gltf.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(length), base_dir);
        } else {
            ok = gltf.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(length), base_dir);
        }
    } catch (const std::bad_alloc&) {
        throw bad_input(fmt::format("{}: invalid glTF: out of memory while parsing (corrupt sizes?)", path));
    } catch (const std::exception& e) {
        // tinygltf 2.7.0 throws std::out_of_range on a GLB buffer with byteLength 0, for one.
        throw bad_input(
            fmt::format("{}: invalid glTF: tinygltf failed on it ({})", path, one_line(e.what())));
    }
    if (!ok) {
        const std::string why = one_line(err.empty() ? warn : err);
        throw bad_input(fmt::format("{}: invalid {}: {}", path, binary ? "glTF binary (.glb)" : "glTF",
                                    why.empty() ? "tinygltf gave no reason" : why));
    }
    if (!err.empty()) ctx.debug(fmt::format("{}: tinygltf: {}", path, one_line(err)));
    if (!warn.empty()) ctx.debug(fmt::format("{}: tinygltf: {}", path, one_line(warn)));
    return model;
}

int component_size(int component_type) {
    switch (component_type) {
        case kComponentByte:
        case kComponentUnsignedByte:
            return 1;
        case kComponentShort:
        case kComponentUnsignedShort:
            return 2;
        case kComponentUnsignedInt:
        case kComponentFloat:
            return 4;
        default:
            return 0;  // INT and DOUBLE are not valid glTF accessor types here
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return 1;
        case TINYGLTF_TYPE_VEC2:
            return 2;
        case TINYGLTF_TYPE_VEC3:
            return 3;
        case TINYGLTF_TYPE_VEC4:
            return 4;
        case TINYGLTF_TYPE_MAT2:
            return 4;
        case TINYGLTF_TYPE_MAT3:
            return 9;
        case TINYGLTF_TYPE_MAT4:
            return 16;
        default:
            return 0;
    }
}

// One component; normalized integers map to [0, 1] (unsigned) or [-1, 1] (signed) as glTF 2.0 says.
double read_component(const unsigned char* p, int component_type, bool normalized) {
    switch (component_type) {
        case kComponentByte: {
            int8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? std::max(double(v) / 127.0, -1.0) : double(v);
        }
        case kComponentUnsignedByte: {
            uint8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? double(v) / 255.0 : double(v);
        }
        case kComponentShort: {
            int16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? std::max(double(v) / 32767.0, -1.0) : double(v);
        }
        case kComponentUnsignedShort: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? double(v) / 65535.0 : double(v);
        }
        case kComponentUnsignedInt: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        case kComponentFloat: {
            float v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        default:
            return 0.0;
    }
}

const char* component_name(int component_type) {
    switch (component_type) {
        case kComponentByte:
            return "BYTE";
        case kComponentUnsignedByte:
            return "UNSIGNED_BYTE";
        case kComponentShort:
            return "SHORT";
        case kComponentUnsignedShort:
            return "UNSIGNED_SHORT";
        case 5124:
            return "INT";
        case kComponentUnsignedInt:
            return "UNSIGNED_INT";
        case kComponentFloat:
            return "FLOAT";
        case 5130:
            return "DOUBLE";
        default:
            return "unknown";
    }
}

glm::dmat4 node_local_matrix(const tinygltf::Node& node, const std::string& where) {
    auto all_finite = [](const std::vector<double>& v) {
        return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
    };
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16 || !all_finite(node.matrix)) {
            throw bad_input(fmt::format("{}: matrix must be 16 finite numbers", where));
        }
        return glm::make_mat4(node.matrix.data());  // glTF matrices are column-major, as glm's
    }
    glm::dmat4 m(1.0);
    if (!node.translation.empty()) {
        if (node.translation.size() != 3 || !all_finite(node.translation)) {
            throw bad_input(fmt::format("{}: translation must be 3 finite numbers", where));
        }
        m = glm::translate(m, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
    }
    if (!node.rotation.empty()) {
        if (node.rotation.size() != 4 || !all_finite(node.rotation)) {
            throw bad_input(fmt::format("{}: rotation must be 4 finite numbers (a quaternion)", where));
        }
        // glTF stores x, y, z, w; glm::dquat's constructor takes w first.
        glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        const double len = glm::length(q);
        if (!(len > 1e-12)) throw bad_input(fmt::format("{}: rotation is a zero quaternion", where));
        m = m * glm::mat4_cast(q / len);
    }
    if (!node.scale.empty()) {
        if (node.scale.size() != 3 || !all_finite(node.scale)) {
            throw bad_input(fmt::format("{}: scale must be 3 finite numbers", where));
        }
        m = glm::scale(m, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
    }
    return m;
}

// The triangles of one primitive, in world space, with only the vertices they use.
struct PrimitiveTriangles {
    std::vector<glm::vec3> positions;
    std::vector<Triangle> triangles;  // indices into positions
    bool opaque = true;
    bool double_sided = false;
};

struct NodeFlags {
    bool view_seed = false;
    bool view_volume = false;
    bool occluder = true;
    bool always_visible = false;
};

class Loader {
public:
    Loader(Context& ctx, const std::string& path, const tinygltf::Model& model, World& world)
        : ctx_(ctx), path_(path), model_(model), world_(world) {}

    void run();

private:
    std::vector<int> scene_roots() const;
    std::string node_label(int n) const;
    std::string node_name(int n) const;
    NodeFlags read_flags(int n);
    std::optional<bool> extra_bool(const tinygltf::Value& extras, const char* key, int n);
    void visit_node(int n, const glm::dmat4& world_from_node, const std::string& node_path);
    // Decodes the mesh of node n into world-space triangles, appended to out (one entry per primitive).
    void decode_mesh(int n, const glm::dmat4& world_from_node, bool count_degenerate,
                     std::vector<PrimitiveTriangles>& out);
    void decode_primitive(int n, int mesh_index, int prim_index, const glm::dmat4& world_from_node,
                          bool count_degenerate, PrimitiveTriangles& out);
    // Reads an accessor as count * components numbers, sparse values applied. Fully bounds-checked.
    std::vector<double> read_accessor(int index, const std::string& what, int* components);
    const std::vector<glm::dvec3>& positions_of(int accessor_index, const std::string& what);
    // Every position finite and within the accessor's declared min/max (when declared).
    void check_declared_bounds(int accessor_index, const std::string& what,
                               const std::vector<glm::dvec3>& positions) const;
    std::vector<uint32_t> indices_of(int accessor_index, const std::string& what);
    // Checks that count elements of elem_bytes at stride fit in view bytes from offset.
    void check_range(const std::string& what, uint64_t offset, uint64_t count, uint64_t elem_bytes,
                     uint64_t stride, uint64_t view_bytes) const;
    // Index and vertex data never share bytes: a bufferView used as both (the glTF-Validator's
    // BUFFER_VIEW_TARGET_OVERRIDE), or index and vertex views that overlap in a buffer, is bad input.
    enum ViewRole : uint8_t { kVertexData = 1, kIndexData = 2 };
    void note_view_role(int accessor_index, ViewRole role);
    void check_view_overlaps() const;
    // Returns the bytes of a bufferView after checking it lies inside its buffer.
    std::pair<const unsigned char*, size_t> view_bytes(int view, const std::string& what) const;
    void check_extensions();
    void make_names_unique();
    void report();

    [[noreturn]] void fail(const std::string& what) const {
        throw bad_input(fmt::format("{}: {}", path_, what));
    }

    Context& ctx_;
    const std::string& path_;
    const tinygltf::Model& model_;
    World& world_;

    std::vector<uint8_t> node_state_;  // 0 unvisited, 1 on the current path, 2 done
    std::unordered_map<int, std::vector<glm::dvec3>> position_cache_;
    std::vector<uint32_t> remap_;  // scratch: accessor vertex -> primitive vertex, kUnmapped when unused
    std::vector<uint8_t> view_roles_;  // per bufferView: ViewRole bits
    std::vector<int> view_role_accessor_;  // per bufferView: an accessor that gave it a role

    uint64_t skipped_non_triangle_ = 0;
    uint64_t skipped_no_position_ = 0;
    uint64_t skinned_nodes_ = 0;
    uint64_t morphed_primitives_ = 0;
    uint64_t unknown_alpha_ = 0;
    uint64_t non_bool_extras_ = 0;
    std::string non_bool_example_;
    uint64_t empty_objects_ = 0;
    uint64_t ragged_lists_ = 0;  // triangle lists whose count is not a multiple of 3
    std::string ragged_example_;
};

std::string Loader::node_name(int n) const {
    const std::string& name = model_.nodes[size_t(n)].name;
    return name.empty() ? fmt::format("node{}", n) : name;
}

std::string Loader::node_label(int n) const {
    const std::string& name = model_.nodes[size_t(n)].name;
    return name.empty() ? fmt::format("node {}", n) : fmt::format("node {} '{}'", n, one_line(name));
}

std::optional<bool> Loader::extra_bool(const tinygltf::Value& extras, const char* key, int n) {
    if (!extras.IsObject() || !extras.Has(key)) return std::nullopt;
    const tinygltf::Value& v = extras.Get(key);
    if (v.IsBool()) return v.Get<bool>();
    if (non_bool_extras_++ == 0) non_bool_example_ = fmt::format("{} extras.{}", node_label(n), key);
    return std::nullopt;
}

NodeFlags Loader::read_flags(int n) {
    const tinygltf::Value& extras = model_.nodes[size_t(n)].extras;
    NodeFlags f;
    f.view_seed = extra_bool(extras, "pvs_view_seed", n).value_or(false);
    f.view_volume = extra_bool(extras, "pvs_view_volume", n).value_or(false);
    f.occluder = extra_bool(extras, "pvs_occluder", n).value_or(true);
    f.always_visible = extra_bool(extras, "pvs_always_visible", n).value_or(false);
    return f;
}

std::vector<int> Loader::scene_roots() const {
    const int node_count = int(model_.nodes.size());
    if (!model_.scenes.empty()) {
        int scene = model_.defaultScene;
        if (scene < 0) scene = 0;
        if (size_t(scene) >= model_.scenes.size()) {
            fail(fmt::format("default scene {} does not exist ({} scenes)", scene, model_.scenes.size()));
        }
        for (int n : model_.scenes[size_t(scene)].nodes) {
            if (n < 0 || n >= node_count) {
                fail(fmt::format("scene {} lists node {}, out of range ({} nodes)", scene, n, node_count));
            }
        }
        return model_.scenes[size_t(scene)].nodes;
    }
    // No scenes: every node that is no node's child is a root.
    std::vector<uint8_t> is_child(model_.nodes.size(), 0);
    for (const tinygltf::Node& node : model_.nodes) {
        for (int c : node.children) {
            if (c >= 0 && c < node_count) is_child[size_t(c)] = 1;
        }
    }
    std::vector<int> roots;
    for (int n = 0; n < node_count; ++n) {
        if (!is_child[size_t(n)]) roots.push_back(n);
    }
    return roots;
}

std::pair<const unsigned char*, size_t> Loader::view_bytes(int view, const std::string& what) const {
    if (view < 0 || size_t(view) >= model_.bufferViews.size()) {
        fail(fmt::format("{}: bufferView {} out of range ({} bufferViews)", what, view,
                         model_.bufferViews.size()));
    }
    const tinygltf::BufferView& bv = model_.bufferViews[size_t(view)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size()) {
        fail(fmt::format("{}: bufferView {} names buffer {}, out of range ({} buffers)", what, view,
                         bv.buffer, model_.buffers.size()));
    }
    const std::vector<unsigned char>& data = model_.buffers[size_t(bv.buffer)].data;
    if (bv.byteLength > data.size() || bv.byteOffset > data.size() - bv.byteLength) {
        fail(fmt::format("{}: bufferView {} (offset {}, {} bytes) runs past the end of buffer {} ({} bytes)",
                         what, view, bv.byteOffset, bv.byteLength, bv.buffer, data.size()));
    }
    return {data.data() + bv.byteOffset, bv.byteLength};
}

void Loader::check_range(const std::string& what, uint64_t offset, uint64_t count, uint64_t elem_bytes,
                         uint64_t stride, uint64_t view_bytes) const {
    if (count == 0) return;
    // Last element ends at offset + (count - 1) * stride + elem_bytes; evaluated without overflow.
    const bool fits = offset <= view_bytes && elem_bytes <= view_bytes - offset &&
                      (count - 1) <= (view_bytes - offset - elem_bytes) / stride;
    if (!fits) {
        fail(
            fmt::format("{}: {} elements of {} bytes (stride {}) from byte offset {} run past the end of its "
                        "buffer view ({} bytes)",
                        what, count, elem_bytes, stride, offset, view_bytes));
    }
}

std::vector<double> Loader::read_accessor(int index, const std::string& what_in, int* components) {
    if (index < 0 || size_t(index) >= model_.accessors.size()) {
        fail(fmt::format("{}: accessor {} out of range ({} accessors)", what_in, index,
                         model_.accessors.size()));
    }
    const std::string what = fmt::format("{} (accessor {})", what_in, index);
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    const int ncomp = component_count(a.type);
    const int csize = component_size(a.componentType);
    if (ncomp == 0 || csize == 0) {
        fail(fmt::format("{}: unsupported component type {} ({})", what, a.componentType,
                         component_name(a.componentType)));
    }
    *components = ncomp;
    const uint64_t elem_bytes = uint64_t(ncomp) * uint64_t(csize);
    const uint64_t count = a.count;

    std::vector<double> values;
    if (a.bufferView >= 0) {
        const auto [bytes, size] = view_bytes(a.bufferView, what);
        const size_t stride_field = model_.bufferViews[size_t(a.bufferView)].byteStride;
        const uint64_t stride = stride_field == 0 ? elem_bytes : stride_field;
        if (stride < elem_bytes) {
            fail(fmt::format("{}: byteStride {} is smaller than one element ({} bytes)", what, stride,
                             elem_bytes));
        }
        check_range(what, a.byteOffset, count, elem_bytes, stride, size);
        values.resize(size_t(count) * size_t(ncomp));
        const unsigned char* p = bytes + a.byteOffset;
        for (size_t i = 0; i < count; ++i, p += stride) {
            for (int c = 0; c < ncomp; ++c) {
                values[i * size_t(ncomp) + size_t(c)] =
                    read_component(p + c * csize, a.componentType, a.normalized);
            }
        }
    } else {
        if (!a.sparse.isSparse) {
            fail(fmt::format("{}: has neither a bufferView nor sparse values", what));
        }
        const uint64_t limit =
            std::max<uint64_t>(kMaxUnbackedElements, uint64_t(std::max(a.sparse.count, 0)));
        if (count > limit) {
            fail(
                fmt::format("{}: count {} is too large for an accessor with no bufferView ({} sparse values)",
                            what, count, a.sparse.count));
        }
        values.assign(size_t(count) * size_t(ncomp), 0.0);
    }

    if (a.sparse.isSparse) {
        const int scount = a.sparse.count;
        if (scount < 1 || uint64_t(scount) > count) {
            fail(fmt::format("{}: sparse count {} must be between 1 and the accessor count {}", what, scount,
                             count));
        }
        const int itype = a.sparse.indices.componentType;
        if (itype != kComponentUnsignedByte && itype != kComponentUnsignedShort &&
            itype != kComponentUnsignedInt) {
            fail(fmt::format("{}: sparse indices have component type {} ({}), not an unsigned integer", what,
                             itype, component_name(itype)));
        }
        if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0) {
            fail(fmt::format("{}: negative sparse byteOffset", what));
        }
        const std::string iwhat = what + " sparse indices";
        const auto [ibytes, isize] = view_bytes(a.sparse.indices.bufferView, iwhat);
        const uint64_t istride = uint64_t(component_size(itype));
        check_range(iwhat, uint64_t(a.sparse.indices.byteOffset), uint64_t(scount), istride, istride, isize);
        const std::string vwhat = what + " sparse values";
        const auto [vbytes, vsize] = view_bytes(a.sparse.values.bufferView, vwhat);
        check_range(vwhat, uint64_t(a.sparse.values.byteOffset), uint64_t(scount), elem_bytes, elem_bytes,
                    vsize);
        const unsigned char* ip = ibytes + a.sparse.indices.byteOffset;
        const unsigned char* vp = vbytes + a.sparse.values.byteOffset;
        double previous = -1.0;
        for (int s = 0; s < scount; ++s, ip += istride, vp += elem_bytes) {
            const double target = read_component(ip, itype, false);
            if (target >= double(count)) {
                fail(fmt::format("{}: sparse index {} = {} out of range (count {})", what, s,
                                 uint64_t(target), count));
            }
            if (target <= previous) {
                fail(fmt::format("{}: sparse index {} = {} does not increase (the one before is {})", what, s,
                                 uint64_t(target), uint64_t(previous)));
            }
            previous = target;
            for (int c = 0; c < ncomp; ++c) {
                values[size_t(target) * size_t(ncomp) + size_t(c)] =
                    read_component(vp + c * csize, a.componentType, a.normalized);
            }
        }
    }
    return values;
}

const std::vector<glm::dvec3>& Loader::positions_of(int accessor_index, const std::string& what) {
    auto it = position_cache_.find(accessor_index);
    if (it != position_cache_.end()) return it->second;
    if (accessor_index >= 0 && size_t(accessor_index) < model_.accessors.size()) {
        const tinygltf::Accessor& a = model_.accessors[size_t(accessor_index)];
        if (a.type != TINYGLTF_TYPE_VEC3) {
            fail(fmt::format("{} (accessor {}): POSITION must be VEC3", what, accessor_index));
        }
        if (a.componentType == kComponentUnsignedInt) {
            fail(fmt::format("{} (accessor {}): POSITION component type UNSIGNED_INT is not allowed", what,
                             accessor_index));
        }
    }
    int ncomp = 0;
    const std::vector<double> values = read_accessor(accessor_index, what, &ncomp);
    std::vector<glm::dvec3> positions(values.size() / 3);
    for (size_t i = 0; i < positions.size(); ++i) {
        positions[i] = glm::dvec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    }
    check_declared_bounds(accessor_index, what, positions);
    return position_cache_.emplace(accessor_index, std::move(positions)).first->second;
}

void Loader::check_declared_bounds(int accessor_index, const std::string& what,
                                   const std::vector<glm::dvec3>& positions) const {
    const tinygltf::Accessor& a = model_.accessors[size_t(accessor_index)];
    const auto vertex = [&](size_t i) {
        const glm::dvec3 p = positions[i];
        return fmt::format("vertex {} = ({:g}, {:g}, {:g})", i, p.x, p.y, p.z);
    };
    for (size_t i = 0; i < positions.size(); ++i) {
        if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) || !std::isfinite(positions[i].z))
            fail(fmt::format("{} (accessor {}): {} is not finite", what, accessor_index, vertex(i)));
    }
    // Normalized integers declare their bounds in stored units (glTF 2.0, 3.6.2.5); only float and plain
    // integer data are compared. The declared numbers pass through float: allow that rounding.
    if (a.minValues.size() != 3 || a.maxValues.size() != 3 || a.normalized) return;
    const glm::dvec3 lo(a.minValues[0], a.minValues[1], a.minValues[2]);
    const glm::dvec3 hi(a.maxValues[0], a.maxValues[1], a.maxValues[2]);
    const double slack =
        1e-5 * std::max({1.0, std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x), std::fabs(hi.y),
                         std::fabs(hi.z)});
    for (size_t i = 0; i < positions.size(); ++i) {
        const glm::dvec3 p = positions[i];
        for (int c = 0; c < 3; ++c) {
            if (p[c] >= lo[c] - slack && p[c] <= hi[c] + slack) continue;
            fail(fmt::format("{} (accessor {}): {} lies outside the accessor's declared bounds min ({:g}, {:g}, "
                             "{:g}) max ({:g}, {:g}, {:g}): the file's vertex data or its bounds are wrong",
                             what, accessor_index, vertex(i), lo.x, lo.y, lo.z, hi.x, hi.y, hi.z));
        }
    }
}

void Loader::note_view_role(int accessor_index, ViewRole role) {
    if (accessor_index < 0 || size_t(accessor_index) >= model_.accessors.size()) return;
    const int view = model_.accessors[size_t(accessor_index)].bufferView;
    if (view < 0 || size_t(view) >= model_.bufferViews.size()) return;
    if (view_roles_.empty()) {
        view_roles_.assign(model_.bufferViews.size(), 0);
        view_role_accessor_.assign(model_.bufferViews.size(), -1);
    }
    uint8_t& roles = view_roles_[size_t(view)];
    if ((roles | role) == (kVertexData | kIndexData)) {
        const int other = view_role_accessor_[size_t(view)];
        fail(fmt::format("bufferView {} holds both vertex data and indices (accessors {} and {})", view,
                         role == kIndexData ? other : accessor_index, role == kIndexData ? accessor_index : other));
    }
    roles |= role;
    view_role_accessor_[size_t(view)] = accessor_index;
}

void Loader::check_view_overlaps() const {
    struct Span {
        int buffer;
        size_t begin, end;
        uint8_t role;
        int view;
    };
    std::vector<Span> spans;
    for (size_t v = 0; v < view_roles_.size(); ++v) {
        if (!view_roles_[v]) continue;
        const tinygltf::BufferView& bv = model_.bufferViews[v];
        spans.push_back({bv.buffer, bv.byteOffset, bv.byteOffset + bv.byteLength, view_roles_[v], int(v)});
    }
    std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) {
        return a.buffer != b.buffer ? a.buffer < b.buffer : a.begin < b.begin;
    });
    // A sweep per buffer: the view of each role reaching farthest so far; one that starts before the other
    // role's reach overlaps it.
    const Span* reach[2] = {nullptr, nullptr};
    for (size_t i = 0; i < spans.size(); ++i) {
        const Span& s = spans[i];
        if (i > 0 && spans[i - 1].buffer != s.buffer) reach[0] = reach[1] = nullptr;
        const int mine = s.role == kVertexData ? 0 : 1;
        const Span* other = reach[1 - mine];
        if (other && s.begin < other->end) {
            const Span& vertex = mine == 0 ? s : *other;
            const Span& index = mine == 0 ? *other : s;
            fail(fmt::format("bufferView {} (vertex data, bytes {} to {}) and bufferView {} (indices, bytes {} to "
                             "{}) overlap in buffer {}",
                             vertex.view, vertex.begin, vertex.end, index.view, index.begin, index.end, s.buffer));
        }
        if (!reach[mine] || s.end > reach[mine]->end) reach[mine] = &s;
    }
}

std::vector<uint32_t> Loader::indices_of(int accessor_index, const std::string& what) {
    if (accessor_index >= 0 && size_t(accessor_index) < model_.accessors.size()) {
        const tinygltf::Accessor& a = model_.accessors[size_t(accessor_index)];
        if (a.type != TINYGLTF_TYPE_SCALAR) {
            fail(fmt::format("{} (accessor {}): indices must be SCALAR", what, accessor_index));
        }
        if (a.componentType != kComponentUnsignedByte && a.componentType != kComponentUnsignedShort &&
            a.componentType != kComponentUnsignedInt) {
            fail(fmt::format(
                "{} (accessor {}): indices must be UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT, "
                "not {}",
                what, accessor_index, component_name(a.componentType)));
        }
    }
    int ncomp = 0;
    const std::vector<double> values = read_accessor(accessor_index, what, &ncomp);
    std::vector<uint32_t> indices(values.size());
    for (size_t i = 0; i < values.size(); ++i) indices[i] = uint32_t(values[i]);
    return indices;
}

void Loader::decode_primitive(int n, int mesh_index, int prim_index, const glm::dmat4& world_from_node,
                              bool count_degenerate, PrimitiveTriangles& out) {
    const tinygltf::Primitive& prim = model_.meshes[size_t(mesh_index)].primitives[size_t(prim_index)];
    const std::string where = fmt::format("{}: mesh {} primitive {}", node_label(n), mesh_index, prim_index);

    // Material.
    if (prim.material >= 0) {
        if (size_t(prim.material) >= model_.materials.size()) {
            fail(fmt::format("{}: material {} out of range ({} materials)", where, prim.material,
                             model_.materials.size()));
        }
        const tinygltf::Material& m = model_.materials[size_t(prim.material)];
        out.double_sided = m.doubleSided;
        if (m.alphaMode == "BLEND" || m.alphaMode == "MASK") {
            out.opaque = false;
        } else if (m.alphaMode != "OPAQUE" && !m.alphaMode.empty()) {
            // Unknown mode: see-through is the safe reading (it can only make a PVS larger).
            ++unknown_alpha_;
            out.opaque = false;
        }
    } else if (prim.material < -1) {
        fail(fmt::format("{}: material {} out of range", where, prim.material));
    }
    if (!prim.targets.empty()) ++morphed_primitives_;

    const auto pos_it = prim.attributes.find("POSITION");
    note_view_role(pos_it->second, kVertexData);
    if (prim.indices >= 0) note_view_role(prim.indices, kIndexData);
    const std::vector<glm::dvec3>& local = positions_of(pos_it->second, where + " POSITION");
    const size_t vertex_count = local.size();
    if (vertex_count >= kUnmapped) fail(fmt::format("{}: too many vertices ({})", where, vertex_count));

    std::vector<uint32_t> indices;
    if (prim.indices >= 0) {
        indices = indices_of(prim.indices, where + " indices");
        for (size_t i = 0; i < indices.size(); ++i) {
            if (indices[i] >= vertex_count) {
                fail(fmt::format("{} indices (accessor {}): index {} = {} out of range ({} vertices)", where,
                                 prim.indices, i, indices[i], vertex_count));
            }
        }
    } else if (prim.indices < -1) {
        fail(fmt::format("{}: indices accessor {} out of range", where, prim.indices));
    } else {
        indices.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) indices[i] = uint32_t(i);
    }

    // Triangles in accessor vertex indices (glTF 2.0, section 3.7.2.1 for strips and fans).
    std::vector<Triangle> local_tris;
    const size_t count = indices.size();
    if (prim.mode == TINYGLTF_MODE_TRIANGLES) {
        // The glTF-Validator's MESH_PRIMITIVE_INCOMPATIBLE_MODE is a warning: the rest are drawn, as GPUs do.
        if (count % 3 != 0 && ragged_lists_++ == 0) {
            ragged_example_ = fmt::format("{}: {} {}", where, count, prim.indices >= 0 ? "indices" : "vertices");
        }
        local_tris.reserve(count / 3);
        for (size_t i = 0; i + 2 < count; i += 3) {
            local_tris.push_back({{indices[i], indices[i + 1], indices[i + 2]}});
        }
    } else if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < count; ++i) {
            if (i % 2 == 0) {
                local_tris.push_back({{indices[i], indices[i + 1], indices[i + 2]}});
            } else {
                local_tris.push_back({{indices[i], indices[i + 2], indices[i + 1]}});
            }
        }
    } else {  // TINYGLTF_MODE_TRIANGLE_FAN
        for (size_t i = 0; i + 2 < count; ++i) {
            local_tris.push_back({{indices[i + 1], indices[i + 2], indices[0]}});
        }
    }

    // World positions of the used vertices, checked finite.
    if (remap_.size() < vertex_count) remap_.resize(vertex_count, kUnmapped);
    std::vector<uint32_t> touched;
    std::vector<glm::vec3> world_pos;
    auto map_vertex = [&](uint32_t v) {
        if (remap_[v] == kUnmapped) {
            const glm::dvec3 p = glm::dvec3(world_from_node * glm::dvec4(local[v], 1.0));
            const glm::vec3 pf(p);
            if (!is_finite(pf)) {
                fail(fmt::format("{}: vertex {} is not finite in world space ({}, {}, {})", where, v, p.x,
                                 p.y, p.z));
            }
            remap_[v] = uint32_t(world_pos.size());
            world_pos.push_back(pf);
            touched.push_back(v);
        }
        return remap_[v];
    };
    std::vector<Triangle> kept;
    kept.reserve(local_tris.size());
    uint64_t degenerate = 0;
    for (const Triangle& t : local_tris) {
        const Triangle w{{map_vertex(t.v[0]), map_vertex(t.v[1]), map_vertex(t.v[2])}};
        if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2]) {
            ++degenerate;
            continue;
        }
        const glm::dvec3 a(world_pos[w.v[0]]);
        const glm::dvec3 e1 = glm::dvec3(world_pos[w.v[1]]) - a;
        const glm::dvec3 e2 = glm::dvec3(world_pos[w.v[2]]) - a;
        const glm::dvec3 c = glm::cross(e1, e2);
        if (glm::dot(c, c) <= kDegenerateSin2 * glm::dot(e1, e1) * glm::dot(e2, e2)) {
            ++degenerate;
            continue;
        }
        kept.push_back(w);
    }
    for (uint32_t v : touched) remap_[v] = kUnmapped;
    if (count_degenerate) world_.stats.degenerate_triangles_dropped += degenerate;

    // Keep only the vertices the kept triangles use.
    std::vector<uint32_t> compact(world_pos.size(), kUnmapped);
    out.triangles.reserve(kept.size());
    for (const Triangle& t : kept) {
        Triangle c{};
        for (int k = 0; k < 3; ++k) {
            uint32_t& slot = compact[t.v[k]];
            if (slot == kUnmapped) {
                slot = uint32_t(out.positions.size());
                out.positions.push_back(world_pos[t.v[k]]);
            }
            c.v[k] = slot;
        }
        out.triangles.push_back(c);
    }
}

void Loader::decode_mesh(int n, const glm::dmat4& world_from_node, bool count_degenerate,
                         std::vector<PrimitiveTriangles>& out) {
    const int mesh_index = model_.nodes[size_t(n)].mesh;
    if (size_t(mesh_index) >= model_.meshes.size()) {
        fail(fmt::format("{}: mesh {} out of range ({} meshes)", node_label(n), mesh_index,
                         model_.meshes.size()));
    }
    const tinygltf::Mesh& mesh = model_.meshes[size_t(mesh_index)];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const tinygltf::Primitive& prim = mesh.primitives[p];
        if (prim.mode >= TINYGLTF_MODE_POINTS && prim.mode <= TINYGLTF_MODE_LINE_STRIP) {
            ++skipped_non_triangle_;
            ++world_.stats.primitives_skipped;
            continue;
        }
        if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            prim.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            fail(fmt::format("{}: mesh {} primitive {}: unknown mode {}", node_label(n), mesh_index, p,
                             prim.mode));
        }
        if (prim.attributes.find("POSITION") == prim.attributes.end()) {
            ++skipped_no_position_;
            continue;
        }
        PrimitiveTriangles tris;
        decode_primitive(n, mesh_index, int(p), world_from_node, count_degenerate, tris);
        if (!tris.triangles.empty()) out.push_back(std::move(tris));
    }
}

void Loader::visit_node(int n, const glm::dmat4& world_from_node, const std::string& node_path) {
    const tinygltf::Node& node = model_.nodes[size_t(n)];
    ++world_.stats.nodes_visited;
    if (node.skin >= 0) ++skinned_nodes_;
    const NodeFlags flags = read_flags(n);

    if (flags.view_seed) {
        const glm::vec3 origin = glm::vec3(glm::dvec3(world_from_node[3]));
        if (!is_finite(origin)) fail(fmt::format("{}: view seed position is not finite", node_label(n)));
        world_.view_seeds.push_back(origin);
    }
    if (node.mesh < 0) {
        if (flags.view_volume) {
            ctx_.warn(fmt::format("{}: {} is a view volume without a mesh; ignored", path_, node_label(n)));
        }
        return;
    }

    std::vector<PrimitiveTriangles> prims;
    decode_mesh(n, world_from_node, !flags.view_volume, prims);

    if (flags.view_volume) {
        Aabb box;
        for (const PrimitiveTriangles& p : prims) {
            for (const glm::vec3& v : p.positions) box.extend(v);
        }
        if (box.is_empty()) {
            ctx_.warn(fmt::format("{}: {}: view volume has no triangles; ignored", path_, node_label(n)));
        } else {
            world_.view_volume_boxes.push_back(box);
        }
        return;
    }

    size_t triangle_total = 0;
    for (const PrimitiveTriangles& p : prims) triangle_total += p.triangles.size();
    if (triangle_total == 0) {
        ++empty_objects_;
        ctx_.debug(fmt::format("{}: {} has no triangles left; not an object", path_, node_label(n)));
        return;
    }
    if (world_.triangles.size() + triangle_total > std::numeric_limits<uint32_t>::max()) {
        fail("too many triangles (more than 2^32)");
    }

    WorldObject obj;
    obj.name = node_name(n);
    obj.node_path = node_path;
    obj.node_index = n;
    obj.first_triangle = uint32_t(world_.triangles.size());
    obj.triangle_count = uint32_t(triangle_total);
    if (!flags.occluder) obj.flags |= kObjectNeverOccludes;
    if (flags.always_visible) obj.flags |= kObjectAlwaysVisible;
    for (const PrimitiveTriangles& p : prims) {
        if (world_.positions.size() + p.positions.size() >= kUnmapped) {
            fail("too many vertices (2^32 or more)");
        }
        const uint32_t base = uint32_t(world_.positions.size());
        world_.positions.insert(world_.positions.end(), p.positions.begin(), p.positions.end());
        for (const glm::vec3& v : p.positions) obj.bounds.extend(v);
        const bool opaque = p.opaque && flags.occluder;
        obj.flags |= opaque ? kObjectHasOpaque : kObjectHasSeeThrough;
        for (const Triangle& t : p.triangles) {
            world_.triangles.push_back({{t.v[0] + base, t.v[1] + base, t.v[2] + base}});
        }
        world_.triangle_opaque.insert(world_.triangle_opaque.end(), p.triangles.size(), opaque ? 1 : 0);
        world_.triangle_double_sided.insert(world_.triangle_double_sided.end(), p.triangles.size(),
                                            p.double_sided ? 1 : 0);
    }
    world_.bounds.extend(obj.bounds);
    world_.objects.push_back(std::move(obj));
}

void Loader::make_names_unique() {
    std::vector<WorldObject>& objects = world_.objects;
    auto rename_repeated = [&](auto&& new_name) {
        std::map<std::string, int> count;
        for (const WorldObject& o : objects) ++count[o.name];
        for (WorldObject& o : objects) {
            if (count[o.name] > 1) o.name = new_name(o);
        }
    };
    rename_repeated([](const WorldObject& o) { return o.node_path; });
    rename_repeated([](const WorldObject& o) { return fmt::format("{}#{}", o.name, o.node_index); });
    // Still colliding only in contrived files (a node literally named "a/b#3"): number the later ones.
    std::map<std::string, int> taken;
    for (const WorldObject& o : objects) ++taken[o.name];
    std::map<std::string, int> seen;
    for (WorldObject& o : objects) {
        if (taken[o.name] == 1 || seen[o.name]++ == 0) continue;
        std::string name;
        for (int k = 2;; ++k) {
            name = fmt::format("{}~{}", o.name, k);
            if (taken.find(name) == taken.end()) break;
        }
        taken[name] = 1;
        o.name = name;
    }
}

void Loader::report() {
    if (skipped_non_triangle_ > 0) {
        ctx_.warn(fmt::format("{}: skipped {} POINTS or LINES primitive(s): only triangles are baked", path_,
                              skipped_non_triangle_));
    }
    if (skipped_no_position_ > 0) {
        ctx_.warn(fmt::format("{}: skipped {} primitive(s) without POSITION", path_, skipped_no_position_));
    }
    if (skinned_nodes_ > 0 || morphed_primitives_ > 0) {
        ctx_.warn(
            fmt::format("{}: {} skinned node(s) and {} primitive(s) with morph targets are baked in their "
                        "static pose (skins and morph weights ignored)",
                        path_, skinned_nodes_, morphed_primitives_));
    }
    if (unknown_alpha_ > 0) {
        ctx_.warn(fmt::format("{}: {} primitive(s) with an unknown alphaMode treated as see-through", path_,
                              unknown_alpha_));
    }
    if (non_bool_extras_ > 0) {
        ctx_.warn(fmt::format("{}: {} pvs_* extras are not booleans and were ignored (first: {})", path_,
                              non_bool_extras_, non_bool_example_));
    }
    if (ragged_lists_ > 0) {
        ctx_.warn(fmt::format("{}: {} triangle list(s) whose count is not a multiple of 3 (first: {}); the last "
                              "one or two vertices of each are ignored",
                              path_, ragged_lists_, ragged_example_));
    }
    if (world_.stats.degenerate_triangles_dropped > 0) {
        ctx_.info(fmt::format("{}: dropped {} degenerate triangle(s) (repeated vertices or zero area)", path_,
                              world_.stats.degenerate_triangles_dropped));
    }
    if (empty_objects_ > 0) {
        ctx_.debug(fmt::format("{}: {} mesh node(s) had no triangles left and are not objects", path_,
                               empty_objects_));
    }
}

void Loader::check_extensions() {
    for (const std::string& ext : model_.extensionsRequired) {
        if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression") {
            fail(
                fmt::format("requires extension {} (compressed geometry), which pvsbake cannot decode; "
                            "decompress the file first (for example with gltf-transform)",
                            ext));
        }
    }
    for (const std::string& ext : model_.extensionsUsed) {
        if (ext == "EXT_mesh_gpu_instancing") {
            ctx_.warn(
                fmt::format("{}: uses EXT_mesh_gpu_instancing: only each mesh's node transform is baked, "
                            "not its GPU instances",
                            path_));
        }
    }
}

void Loader::run() {
    check_extensions();
    const std::vector<int> roots = scene_roots();
    const int node_count = int(model_.nodes.size());
    node_state_.assign(model_.nodes.size(), 0);

    // Depth-first, parents before children, without recursion (a deep hierarchy cannot overflow the stack).
    struct Frame {
        int node;
        bool leave;
        glm::dmat4 parent;
        std::string parent_path;
    };
    std::vector<Frame> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) {
        stack.push_back({*it, false, glm::dmat4(1.0), ""});
    }
    while (!stack.empty()) {
        Frame f = std::move(stack.back());
        stack.pop_back();
        uint8_t& state = node_state_[size_t(f.node)];
        if (f.leave) {
            state = 2;
            continue;
        }
        if (state == 1) fail(fmt::format("the node hierarchy has a cycle through {}", node_label(f.node)));
        if (state == 2) {
            fail(fmt::format("{} is reached twice (glTF nodes must form trees, one parent each)",
                             node_label(f.node)));
        }
        state = 1;
        const tinygltf::Node& node = model_.nodes[size_t(f.node)];
        const glm::dmat4 world_from_node =
            f.parent * node_local_matrix(node, fmt::format("{}: {}", path_, node_label(f.node)));
        const std::string path =
            f.parent_path.empty() ? node_name(f.node) : f.parent_path + "/" + node_name(f.node);
        visit_node(f.node, world_from_node, path);
        stack.push_back({f.node, true, glm::dmat4(1.0), ""});
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) {
            if (*it < 0 || *it >= node_count) {
                fail(
                    fmt::format("{}: child {} out of range ({} nodes)", node_label(f.node), *it, node_count));
            }
            stack.push_back({*it, false, world_from_node, path});
        }
    }

    if (world_.triangles.empty()) fail("no triangles in the default scene");
    check_view_overlaps();
    make_names_unique();
    report();
}

}  // namespace

namespace {

World load_world_bytes(Context& ctx, const std::string& path, const std::string& bytes, bool files) {
    World world;
    world.source_path = path;
    try {
        const tinygltf::Model model = parse_gltf(ctx, path, bytes, files);
        Loader(ctx, path, model, world).run();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw bad_input(fmt::format("{}: out of memory while loading (corrupt counts?)", path));
    } catch (const std::exception& e) {
        throw internal_error(
            fmt::format("{}: unexpected failure while loading: {}", path, one_line(e.what())));
    }
    return world;
}

}  // namespace

World load_world(Context& ctx, const std::string& path) {
    ScopedTimer timer(ctx, "load_world");
    World world = load_world_bytes(ctx, path, read_input_file(path), true);
    ctx.info(
        fmt::format("{}: {} objects, {} triangles, {} vertices, {} view seeds, {} view volumes ({:.3f} s)",
                    path, world.objects.size(), world.triangles.size(), world.positions.size(),
                    world.view_seeds.size(), world.view_volume_boxes.size(), timer.seconds()));
    return world;
}

World load_world_from_memory(Context& ctx, const std::string& name, const std::string& bytes) {
    ScopedTimer timer(ctx, "load_world");
    return load_world_bytes(ctx, name, bytes, false);
}

}  // namespace pvs
