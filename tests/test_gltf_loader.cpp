// SPDX-License-Identifier: MIT
// Tests of load_world on hand-built glTF files (tests/gltf_fixtures.h): transforms, primitive modes,
// accessor layouts, names, materials, extras, degenerate triangles, bad inputs, and the real worlds.
#include "io/gltf_loader.h"

#include "core/error.h"
#include "tests/gltf_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>

namespace pvs {
namespace {

using test::GltfBuilder;
using test::kGlFloat;
using test::kGlShort;
using test::kGlUnsignedByte;
using test::kGlUnsignedInt;
using test::kGlUnsignedShort;
using test::TempDir;

Context quiet_context() {
    return Context(Context::Options{.sink = nullptr});
}

World load(const std::string& path) {
    Context ctx = quiet_context();
    return load_world(ctx, path);
}

glm::vec3 corner(const World& w, size_t triangle, int k) {
    return w.positions[w.triangles[triangle].v[k]];
}

glm::vec3 normal_of(const World& w, size_t t) {
    return glm::cross(corner(w, t, 1) - corner(w, t, 0), corner(w, t, 2) - corner(w, t, 0));
}

void expect_near(glm::vec3 got, glm::vec3 want, float tol = 1e-5f) {
    EXPECT_NEAR(got.x, want.x, tol) << "x";
    EXPECT_NEAR(got.y, want.y, tol) << "y";
    EXPECT_NEAR(got.z, want.z, tol) << "z";
}

// Loading must throw pvs::Error (kBadInput) with one line naming the file and containing `word`.
void expect_bad_input(const std::string& path, const std::string& word) {
    SCOPED_TRACE(path);
    try {
        load(path);
        ADD_FAILURE() << "no error; expected one containing '" << word << "'";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << msg;
        const std::string file = std::filesystem::path(path).filename().string();
        EXPECT_TRUE(msg.find(file) != std::string::npos) << "message does not name " << file << ": " << msg;
        EXPECT_TRUE(msg.find(word) != std::string::npos) << "message lacks '" << word << "': " << msg;
        EXPECT_TRUE(msg.find('\n') == std::string::npos) << "message is not one line: " << msg;
    }
}

const std::vector<glm::vec3> kTriangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

// One node with one triangle; returns the builder so a test can edit the node.
GltfBuilder one_triangle(nlohmann::json node_fields = nlohmann::json::object()) {
    GltfBuilder b;
    const int pos = b.add_positions(kTriangle);
    const int idx = b.add_indices({0, 1, 2});
    const int mesh = b.add_mesh({GltfBuilder::primitive(pos, idx)});
    b.set_scene({b.add_node("tri", mesh, std::move(node_fields))});
    return b;
}

TEST(GltfLoader, TrsTransformIsTranslateRotateScale) {
    TempDir dir;
    const double h = std::sqrt(0.5);
    GltfBuilder b =
        one_triangle({{"translation", {1, 2, 3}}, {"rotation", {0, h, 0, h}}, {"scale", {2, 2, 2}}});
    const World w = load(b.write_gltf(dir, "trs"));
    ASSERT_EQ(w.triangle_count(), 1u);
    // Scaled by 2, turned 90 degrees about +Y (x -> -z), then moved by (1, 2, 3).
    expect_near(corner(w, 0, 0), {1, 2, 3});
    expect_near(corner(w, 0, 1), {1, 2, 1});
    expect_near(corner(w, 0, 2), {1, 4, 3});
    expect_near(w.bounds.min, {1, 2, 1});
    expect_near(w.bounds.max, {1, 4, 3});
    EXPECT_EQ(w.source_path, dir.file("trs.gltf"));
}

TEST(GltfLoader, MatrixTransformIsColumnMajor) {
    TempDir dir;
    GltfBuilder b = one_triangle({{"matrix", {2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1}}});
    const World w = load(b.write_gltf(dir, "matrix"));
    ASSERT_EQ(w.triangle_count(), 1u);
    expect_near(corner(w, 0, 0), {5, 6, 7});
    expect_near(corner(w, 0, 1), {7, 6, 7});
    expect_near(corner(w, 0, 2), {5, 7, 7});
}

TEST(GltfLoader, HierarchyComposesParentTimesChild) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.add_positions(kTriangle);
    const int mesh = b.add_mesh({GltfBuilder::primitive(pos)});
    const int leaf = b.add_node("leaf", mesh, {{"translation", {0, 0, 1}}});
    const int child = b.add_node("child", -1, {{"translation", {0, 1, 0}}, {"children", {leaf}}});
    const int root =
        b.add_node("root", -1, {{"translation", {10, 0, 0}}, {"scale", {2, 2, 2}}, {"children", {child}}});
    b.set_scene({root});
    const World w = load(b.write_gltf(dir, "tree"));
    ASSERT_EQ(w.object_count(), 1u);
    EXPECT_EQ(w.objects[0].name, "leaf");
    EXPECT_EQ(w.objects[0].node_path, "root/child/leaf");
    EXPECT_EQ(w.objects[0].node_index, leaf);
    EXPECT_EQ(w.stats.nodes_visited, 3u);
    // world = T(10,0,0) S(2) T(0,1,0) T(0,0,1) p = 2 (p + (0,1,1)) + (10,0,0)
    expect_near(corner(w, 0, 0), {10, 2, 2});
    expect_near(corner(w, 0, 1), {12, 2, 2});
    expect_near(corner(w, 0, 2), {10, 4, 2});
}

TEST(GltfLoader, TriangleStripAndFanAreConvertedWithConsistentWinding) {
    TempDir dir;
    GltfBuilder b;
    const int strip_pos = b.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 2, 0}, {1, 2, 0}});
    const int fan_pos = b.add_positions({{0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}, {-1, 1, 5}});
    const int strip = b.add_mesh({GltfBuilder::primitive(strip_pos, -1, 5)});
    const int fan =
        b.add_mesh({GltfBuilder::primitive(fan_pos, b.add_indices({0, 1, 2, 3, 4}, kGlUnsignedShort), 6)});
    b.set_scene({b.add_node("strip", strip), b.add_node("fan", fan)});
    const World w = load(b.write_gltf(dir, "modes"));
    ASSERT_EQ(w.object_count(), 2u);
    EXPECT_EQ(w.objects[0].triangle_count, 4u);  // n - 2 for a strip of 6
    EXPECT_EQ(w.objects[1].triangle_count, 3u);  // n - 2 for a fan of 5
    for (size_t t = 0; t < w.triangle_count(); ++t) {
        const glm::vec3 n = normal_of(w, t);
        EXPECT_GT(n.z, 0.0f) << "triangle " << t << " is wound the other way";
        EXPECT_NEAR(n.x, 0.0f, 1e-6f);
        EXPECT_NEAR(n.y, 0.0f, 1e-6f);
    }
    // Every fan triangle uses the centre.
    for (uint32_t t = w.objects[1].first_triangle; t < w.objects[1].first_triangle + 3; ++t) {
        bool uses_centre = false;
        for (int k = 0; k < 3; ++k) uses_centre |= corner(w, t, k) == glm::vec3(0, 0, 5);
        EXPECT_TRUE(uses_centre) << t;
    }
}

TEST(GltfLoader, PointsAndLinesAreSkippedWithOneWarning) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.add_positions(kTriangle);
    const int mesh = b.add_mesh({GltfBuilder::primitive(pos, -1, 0), GltfBuilder::primitive(pos, -1, 1),
                                 GltfBuilder::primitive(pos), GltfBuilder::primitive(pos, -1, 3),
                                 GltfBuilder::primitive(pos, -1, 2)});
    b.set_scene({b.add_node("mixed", mesh)});
    Context ctx = quiet_context();
    const World w = load_world(ctx, b.write_gltf(dir, "points"));
    EXPECT_EQ(w.triangle_count(), 1u);
    EXPECT_EQ(w.stats.primitives_skipped, 4u);
    int mentions = 0;
    for (const std::string& warning : ctx.warnings()) {
        if (warning.find("POINTS") != std::string::npos) {
            ++mentions;
            EXPECT_TRUE(warning.find('4') != std::string::npos) << warning;
        }
    }
    EXPECT_EQ(mentions, 1);
}

TEST(GltfLoader, NonIndexedTriangles) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}});
    b.set_scene({b.add_node("two", b.add_mesh({GltfBuilder::primitive(pos)}))});
    const World w = load(b.write_gltf(dir, "nonindexed"));
    ASSERT_EQ(w.triangle_count(), 2u);
    expect_near(corner(w, 1, 1), {1, 0, 1});
}

TEST(GltfLoader, IndexComponentTypes) {
    TempDir dir;
    // 300 vertices so u16 and u32 indices go past 255; the quad uses the last four.
    std::vector<glm::vec3> p(300, glm::vec3(0.0f));
    for (size_t i = 0; i < p.size(); ++i) p[i] = glm::vec3(float(i), 0, 0);
    p[296] = {0, 0, 0};
    p[297] = {1, 0, 0};
    p[298] = {1, 1, 0};
    p[299] = {0, 1, 0};
    const std::vector<uint32_t> far = {296, 297, 298, 296, 298, 299};
    for (int type : {kGlUnsignedByte, kGlUnsignedShort, kGlUnsignedInt}) {
        SCOPED_TRACE(type);
        GltfBuilder b;
        std::vector<uint32_t> idx = far;
        std::vector<glm::vec3> pos = p;
        if (type == kGlUnsignedByte) {  // u8 cannot reach 296: use a 4-vertex copy
            pos.assign(p.begin() + 296, p.end());
            for (uint32_t& v : idx) v -= 296;
        }
        const int pa = b.add_positions(pos);
        b.set_scene({b.add_node("quad", b.add_mesh({GltfBuilder::primitive(pa, b.add_indices(idx, type))}))});
        const World w = load(b.write_gltf(dir, "indices" + std::to_string(type)));
        ASSERT_EQ(w.triangle_count(), 2u);
        expect_near(corner(w, 0, 1), {1, 0, 0});
        expect_near(corner(w, 1, 2), {0, 1, 0});
        EXPECT_EQ(w.positions.size(), 4u) << "only the used vertices are kept";
    }
}

TEST(GltfLoader, StridedPositions) {
    TempDir dir;
    const std::vector<glm::vec3> quad = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}};
    for (size_t stride : {16u, 20u}) {
        SCOPED_TRACE(stride);
        GltfBuilder b;
        const int pa = b.add_strided_positions(quad, stride);
        b.set_scene({b.add_node(
            "quad", b.add_mesh({GltfBuilder::primitive(pa, b.add_indices({0, 1, 2, 0, 2, 3}))}))});
        const World w = load(b.write_gltf(dir, "stride" + std::to_string(stride)));
        ASSERT_EQ(w.triangle_count(), 2u);
        expect_near(corner(w, 0, 2), {2, 3, 0});
        expect_near(corner(w, 1, 2), {0, 3, 0});
        expect_near(w.bounds.max, {2, 3, 0});
    }
}

TEST(GltfLoader, SparseAccessorOverridesPositions) {
    TempDir dir;
    GltfBuilder b;
    const int pa = b.add_positions({{0, 0, 0}, {9, 9, 9}, {0, 1, 0}, {7, 7, 7}});
    const std::vector<uint16_t> sparse_idx = {1, 3};
    const std::vector<float> sparse_val = {1, 0, 0, 1, 1, 0};
    const int iv = b.add_view(std::string(reinterpret_cast<const char*>(sparse_idx.data()), 4));
    const int vv = b.add_view(std::string(reinterpret_cast<const char*>(sparse_val.data()), 24));
    b.json["accessors"][size_t(pa)]["sparse"] = {
        {"count", 2},
        {"indices", {{"bufferView", iv}, {"componentType", kGlUnsignedShort}}},
        {"values", {{"bufferView", vv}}}};
    // A second accessor with no bufferView: zeros, then its sparse values (vertex 0 stays at the origin).
    const std::vector<uint8_t> zidx = {1, 2};
    const std::vector<float> zval = {0, 0, 4, 4, 0, 0};
    const int ziv = b.add_view(std::string(reinterpret_cast<const char*>(zidx.data()), 2));
    const int zvv = b.add_view(std::string(reinterpret_cast<const char*>(zval.data()), 24));
    const int za = b.add_accessor(-1, kGlFloat, 3, "VEC3");
    b.json["accessors"][size_t(za)]["sparse"] = {
        {"count", 2},
        {"indices", {{"bufferView", ziv}, {"componentType", kGlUnsignedByte}}},
        {"values", {{"bufferView", zvv}}}};
    b.set_scene(
        {b.add_node("quad", b.add_mesh({GltfBuilder::primitive(pa, b.add_indices({0, 1, 3, 0, 3, 2}))})),
         b.add_node("zeros", b.add_mesh({GltfBuilder::primitive(za)}))});
    const World w = load(b.write_gltf(dir, "sparse"));
    ASSERT_EQ(w.object_count(), 2u);
    ASSERT_EQ(w.triangle_count(), 3u);
    expect_near(corner(w, 0, 1), {1, 0, 0});
    expect_near(corner(w, 0, 2), {1, 1, 0});
    expect_near(w.objects[0].bounds.max, {1, 1, 0});
    expect_near(corner(w, 2, 0), {0, 0, 0});
    expect_near(corner(w, 2, 1), {0, 0, 4});
    expect_near(corner(w, 2, 2), {4, 0, 0});
}

TEST(GltfLoader, QuantizedPositions) {
    TempDir dir;
    GltfBuilder b;
    b.json["extensionsUsed"] = {"KHR_mesh_quantization"};
    b.json["extensionsRequired"] = {"KHR_mesh_quantization"};
    // Normalized SHORT, stride 8 (4-byte aligned elements): 32767 -> 1, -32767 and -32768 -> -1.
    const std::vector<int16_t> s = {0, 0, 0, 0, 32767, 0, 0, 0, -32768, -32767, 16384, 0};
    const int sv = b.add_view(std::string(reinterpret_cast<const char*>(s.data()), s.size() * 2), 8);
    const int sa = b.add_accessor(sv, kGlShort, 3, "VEC3", 0, true);
    // Plain UNSIGNED_BYTE integers, stride 4.
    const std::vector<uint8_t> u = {0, 0, 0, 0, 10, 0, 0, 0, 0, 20, 3, 0};
    const int uv = b.add_view(std::string(reinterpret_cast<const char*>(u.data()), u.size()), 4);
    const int ua = b.add_accessor(uv, kGlUnsignedByte, 3, "VEC3");
    b.set_scene({b.add_node("short", b.add_mesh({GltfBuilder::primitive(sa)})),
                 b.add_node("ubyte", b.add_mesh({GltfBuilder::primitive(ua)}))});
    const World w = load(b.write_gltf(dir, "quantized"));
    ASSERT_EQ(w.triangle_count(), 2u);
    expect_near(corner(w, 0, 0), {0, 0, 0});
    expect_near(corner(w, 0, 1), {1, 0, 0});
    expect_near(corner(w, 0, 2), {-1, -1, 16384.0f / 32767.0f});
    expect_near(corner(w, 1, 1), {10, 0, 0});
    expect_near(corner(w, 1, 2), {0, 20, 3});
}

TEST(GltfLoader, RepeatedNamesAreMadeUnique) {
    TempDir dir;
    GltfBuilder b;
    const int mesh = b.add_mesh({GltfBuilder::primitive(b.add_positions(kTriangle))});
    const int crate_a = b.add_node("crate", mesh);
    const int crate_b = b.add_node("crate", mesh);
    const int room_a = b.add_node("roomA", -1, {{"children", {crate_a}}});
    const int room_b = b.add_node("roomB", -1, {{"children", {crate_b}}});
    const int wall_1 = b.add_node("wall", mesh);
    const int wall_2 = b.add_node("wall", mesh);
    const int unnamed = b.add_node("", mesh);
    const int lone = b.add_node("lone", mesh);
    b.set_scene({room_a, room_b, wall_1, wall_2, unnamed, lone});
    const World w = load(b.write_gltf(dir, "names"));
    ASSERT_EQ(w.object_count(), 6u);
    std::set<std::string> names;
    for (const WorldObject& o : w.objects) names.insert(o.name);
    EXPECT_EQ(names.size(), 6u);
    const std::set<std::string> want = {"roomA/crate",
                                        "roomB/crate",
                                        "wall#" + std::to_string(wall_1),
                                        "wall#" + std::to_string(wall_2),
                                        "node" + std::to_string(unnamed),
                                        "lone"};
    EXPECT_EQ(names, want);
}

TEST(GltfLoader, DegenerateTrianglesAreDroppedAndCounted) {
    TempDir dir;
    GltfBuilder b;
    const int pa = b.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {5, 5, 5}, {5, 5, 5}});
    // good, repeated index, collinear (0,1,3), two vertices at one place (4,5)
    const int ia = b.add_indices({0, 1, 2, 0, 0, 2, 0, 1, 3, 4, 5, 0});
    const int all_bad = b.add_indices({0, 1, 3, 2, 2, 2});
    b.set_scene({b.add_node("some", b.add_mesh({GltfBuilder::primitive(pa, ia)})),
                 b.add_node("none", b.add_mesh({GltfBuilder::primitive(pa, all_bad)}))});
    Context ctx = quiet_context();
    const World w = load_world(ctx, b.write_gltf(dir, "degenerate"));
    ASSERT_EQ(w.object_count(), 1u) << "a node with no triangles left is not an object";
    EXPECT_EQ(w.objects[0].name, "some");
    EXPECT_EQ(w.triangle_count(), 1u);
    EXPECT_EQ(w.stats.degenerate_triangles_dropped, 5u);
    EXPECT_EQ(w.positions.size(), 3u);
}

TEST(GltfLoader, MaterialsAndExtras) {
    TempDir dir;
    GltfBuilder b;
    const int opaque = b.add_material("OPAQUE");
    const int blend = b.add_material("BLEND", true);
    const int mask = b.add_material("MASK");
    const int pa = b.add_positions(kTriangle);
    auto mesh_with = [&](int material) { return b.add_mesh({GltfBuilder::primitive(pa, -1, 4, material)}); };
    const int two =
        b.add_mesh({GltfBuilder::primitive(pa, -1, 4, opaque), GltfBuilder::primitive(pa, -1, 4, blend)});
    std::vector<int> roots = {
        b.add_node("plain", mesh_with(-1)),
        b.add_node("glass", mesh_with(blend)),
        b.add_node("fence", mesh_with(mask)),
        b.add_node("mixed", two),
        b.add_node("ghost", mesh_with(opaque), {{"extras", {{"pvs_occluder", false}}}}),
        b.add_node("beacon", mesh_with(opaque), {{"extras", {{"pvs_always_visible", true}}}}),
        b.add_node("odd", mesh_with(opaque),
                   {{"extras", {{"pvs_occluder", "no"}, {"pvs_always_visible", 1}}}}),
        b.add_node("spawn", -1, {{"translation", {1, 2, 3}}, {"extras", {{"pvs_view_seed", true}}}}),
        b.add_node("seeded", mesh_with(opaque),
                   {{"translation", {4, 5, 6}}, {"extras", {{"pvs_view_seed", true}}}}),
        b.add_node("volume", mesh_with(opaque),
                   {{"scale", {10, 20, 1}}, {"extras", {{"pvs_view_volume", true}}}}),
    };
    b.set_scene(roots);
    Context ctx = quiet_context();
    const World w = load_world(ctx, b.write_glb(dir, "materials"));
    ASSERT_EQ(w.object_count(), 8u);
    auto find = [&](const std::string& name) -> const WorldObject& {
        for (const WorldObject& o : w.objects) {
            if (o.name == name) return o;
        }
        ADD_FAILURE() << "no object " << name;
        return w.objects[0];
    };
    auto opaque_of = [&](const WorldObject& o, uint32_t k) {
        return w.triangle_opaque[o.first_triangle + k];
    };
    EXPECT_EQ(find("plain").flags, uint32_t(kObjectHasOpaque));
    EXPECT_EQ(opaque_of(find("plain"), 0), 1);
    EXPECT_EQ(find("glass").flags, uint32_t(kObjectHasSeeThrough));
    EXPECT_EQ(opaque_of(find("glass"), 0), 0);
    EXPECT_EQ(w.triangle_double_sided[find("glass").first_triangle], 1);
    EXPECT_EQ(w.triangle_double_sided[find("plain").first_triangle], 0);
    EXPECT_EQ(find("fence").flags, uint32_t(kObjectHasSeeThrough));
    EXPECT_EQ(find("mixed").flags, uint32_t(kObjectHasOpaque | kObjectHasSeeThrough));
    EXPECT_EQ(find("mixed").triangle_count, 2u);
    EXPECT_EQ(find("ghost").flags, uint32_t(kObjectHasSeeThrough | kObjectNeverOccludes));
    EXPECT_EQ(opaque_of(find("ghost"), 0), 0);
    EXPECT_EQ(find("beacon").flags, uint32_t(kObjectHasOpaque | kObjectAlwaysVisible));
    EXPECT_EQ(find("odd").flags, uint32_t(kObjectHasOpaque)) << "non-boolean extras are ignored";
    bool warned = false;
    for (const std::string& warning : ctx.warnings()) {
        warned |= warning.find("not booleans") != std::string::npos;
    }
    EXPECT_TRUE(warned);
    EXPECT_EQ(find("seeded").flags, uint32_t(kObjectHasOpaque))
        << "a view seed with a mesh is still an object";
    ASSERT_EQ(w.view_seeds.size(), 2u);
    expect_near(w.view_seeds[0], {1, 2, 3});
    expect_near(w.view_seeds[1], {4, 5, 6});
    ASSERT_EQ(w.view_volume_boxes.size(), 1u);
    expect_near(w.view_volume_boxes[0].min, {0, 0, 0});
    expect_near(w.view_volume_boxes[0].max, {10, 20, 0});
    // Triangles are stored object by object.
    uint32_t next = 0;
    for (const WorldObject& o : w.objects) {
        EXPECT_EQ(o.first_triangle, next);
        next += o.triangle_count;
    }
    EXPECT_EQ(next, w.triangle_count());
    EXPECT_EQ(w.triangle_opaque.size(), w.triangle_count());
    EXPECT_EQ(w.triangle_double_sided.size(), w.triangle_count());
}

TEST(GltfLoader, EmbeddedBufferAndGlbLoadAlike) {
    TempDir dir;
    GltfBuilder b = one_triangle({{"translation", {0, 0, -3}}});
    const World a = load(b.write_embedded(dir, "embedded"));
    const World g = load(b.write_glb(dir, "binary"));
    const World e = load(b.write_gltf(dir, "external"));
    for (const World* w : {&a, &g, &e}) {
        ASSERT_EQ(w->triangle_count(), 1u);
        expect_near(w->positions[w->triangles[0].v[2]], {0, 1, -3});
    }
}

TEST(GltfLoader, FormatIsChosenByContentNotExtension) {
    TempDir dir;
    GltfBuilder b = one_triangle();
    test::write_file(dir.file("really_binary.gltf"), b.glb_bytes());
    test::write_file(dir.file("really_text.glb"), b.json_text("data:application/octet-stream;base64," +
                                                              test::base64_encode(b.padded_bin())));
    test::write_file(dir.file("bom.gltf"),
                     "\xEF\xBB\xBF\n  " + b.json_text("data:application/octet-stream;base64," +
                                                      test::base64_encode(b.padded_bin())));
    EXPECT_EQ(load(dir.file("really_binary.gltf")).triangle_count(), 1u);
    EXPECT_EQ(load(dir.file("really_text.glb")).triangle_count(), 1u);
    EXPECT_EQ(load(dir.file("bom.gltf")).triangle_count(), 1u) << "a UTF-8 byte order mark is allowed";
}

TEST(GltfLoader, NoScenesMeansEveryRootNode) {
    TempDir dir;
    GltfBuilder b;
    const int mesh = b.add_mesh({GltfBuilder::primitive(b.add_positions(kTriangle))});
    const int child = b.add_node("child", mesh);
    b.add_node("parent", mesh, {{"children", {child}}, {"translation", {0, 10, 0}}});
    b.add_node("other", mesh);
    const World w = load(b.write_gltf(dir, "noscene"));
    ASSERT_EQ(w.object_count(), 3u);
    EXPECT_EQ(w.objects[0].name, "parent");
    EXPECT_EQ(w.objects[1].node_path, "parent/child");
    expect_near(w.objects[1].bounds.min, {0, 10, 0});
    EXPECT_EQ(w.objects[2].name, "other");
}

TEST(GltfLoader, DefaultSceneIsHonoured) {
    TempDir dir;
    GltfBuilder b;
    const int mesh = b.add_mesh({GltfBuilder::primitive(b.add_positions(kTriangle))});
    const int first = b.add_node("first", mesh);
    const int second = b.add_node("second", mesh);
    b.json["scenes"] = {{{"nodes", {first}}}, {{"nodes", {second}}}};
    b.json["scene"] = 1;
    const World w = load(b.write_gltf(dir, "scenes"));
    ASSERT_EQ(w.object_count(), 1u);
    EXPECT_EQ(w.objects[0].name, "second");
}

// ---- Bad inputs ----

TEST(GltfLoaderBadInput, MissingFile) {
    TempDir dir;
    expect_bad_input(dir.file("nowhere.glb"), "not found");
}

TEST(GltfLoaderBadInput, NotGltf) {
    TempDir dir;
    test::write_file(dir.file("random.gltf"), "Lorem ipsum dolor sit amet, 12345\n\x01\x02 not json at all");
    expect_bad_input(dir.file("random.gltf"), "not a glTF");
    test::write_file(dir.file("brace.gltf"), "{ \"asset\": {\"version\": \"2.0\"}, ");
    expect_bad_input(dir.file("brace.gltf"), "invalid glTF");
    test::write_file(dir.file("empty.glb"), "");
    expect_bad_input(dir.file("empty.glb"), "not a glTF");
}

TEST(GltfLoaderBadInput, TruncatedGlb) {
    TempDir dir;
    const std::string bytes = one_triangle().glb_bytes();
    for (size_t keep :
         {size_t(4), size_t(16), size_t(40), bytes.size() / 2, bytes.size() - 8, bytes.size() - 1}) {
        const std::string path = dir.file("cut" + std::to_string(keep) + ".glb");
        test::write_file(path, bytes.substr(0, keep));
        expect_bad_input(path, "truncated");
    }
}

uint32_t u32_at(const std::string& bytes, size_t offset) {
    uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, 4);
    return v;
}

void set_u32(std::string& bytes, size_t offset, uint32_t v) {
    std::memcpy(bytes.data() + offset, &v, 4);
}

TEST(GltfLoaderBadInput, GlbChunkLengthsAreCheckedBeforeTinygltf) {
    TempDir dir;
    const std::string good = one_triangle().glb_bytes();
    const size_t bin_header = 20 + u32_at(good, 12);
    // A BIN chunk length 4 bytes too long: tinygltf 2.7.0 alone would read past the end of the file.
    std::string bin_long = good;
    set_u32(bin_long, bin_header, u32_at(good, bin_header) + 4);
    test::write_file(dir.file("binlong.glb"), bin_long);
    expect_bad_input(dir.file("binlong.glb"), "BIN chunk");
    std::string json_long = good;
    set_u32(json_long, 12, u32_at(good, 12) + 1000);
    test::write_file(dir.file("jsonlong.glb"), json_long);
    expect_bad_input(dir.file("jsonlong.glb"), "JSON chunk");
    std::string version = good;
    set_u32(version, 4, 1);
    test::write_file(dir.file("version1.glb"), version);
    expect_bad_input(dir.file("version1.glb"), "version 1");
    std::string not_bin = good;
    set_u32(not_bin, bin_header + 4, 0x12345678);
    test::write_file(dir.file("notbin.glb"), not_bin);
    expect_bad_input(dir.file("notbin.glb"), "not BIN");
}

TEST(GltfLoaderBadInput, TinygltfExceptionBecomesBadInput) {
    TempDir dir;
    // tinygltf 2.7.0 throws std::out_of_range for a GLB buffer of byteLength 0.
    GltfBuilder b = one_triangle();
    std::string text = b.json_text("");
    const std::string key = "\"byteLength\": " + std::to_string(b.padded_bin().size());
    const size_t at = text.rfind(key);
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, key.size(), "\"byteLength\": 0");
    test::write_file(dir.file("zero.glb"), test::make_glb_bytes(text, b.padded_bin()));
    expect_bad_input(dir.file("zero.glb"), "");  // any bad-input message: the point is no std::out_of_range
}

TEST(GltfLoaderBadInput, MissingExternalBuffer) {
    TempDir dir;
    const std::string path = one_triangle().write_gltf(dir, "lonely");
    std::filesystem::remove(dir.file("lonely.bin"));
    expect_bad_input(path, "lonely.bin");
}

TEST(GltfLoaderBadInput, IndexOutOfRange) {
    TempDir dir;
    GltfBuilder b;
    const int pa = b.add_positions(kTriangle);
    b.set_scene({b.add_node("bad", b.add_mesh({GltfBuilder::primitive(pa, b.add_indices({0, 1, 3}))}))});
    expect_bad_input(b.write_gltf(dir, "badindex"), "out of range");
    expect_bad_input(dir.file("badindex.gltf"), "mesh 0 primitive 0");
}

TEST(GltfLoaderBadInput, AccessorPastEndOfBufferView) {
    TempDir dir;
    GltfBuilder b = one_triangle();
    b.json["accessors"][0]["count"] = 4;  // 48 bytes from a 36-byte view
    expect_bad_input(b.write_gltf(dir, "pastend"), "past the end");
    GltfBuilder c = one_triangle();
    c.json["accessors"][0]["byteOffset"] = 4;
    expect_bad_input(c.write_gltf(dir, "offset"), "past the end");
    GltfBuilder d = one_triangle();
    d.json["bufferViews"][0]["byteLength"] = 1000;  // the view itself overruns the buffer
    expect_bad_input(d.write_gltf(dir, "bigview"), "past the end");
}

TEST(GltfLoaderBadInput, NonFinitePosition) {
    TempDir dir;
    GltfBuilder b;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const int pa = b.add_positions({{0, 0, 0}, {1, 0, 0}, {0, nan, 0}});
    b.set_scene({b.add_node("nan", b.add_mesh({GltfBuilder::primitive(pa)}))});
    expect_bad_input(b.write_gltf(dir, "nan"), "not finite");
    // Finite in the file, infinite in world space.
    GltfBuilder c = one_triangle({{"scale", {1e38, 1e38, 1e38}}, {"translation", {3e38, 0, 0}}});
    expect_bad_input(c.write_gltf(dir, "huge"), "not finite");
}

TEST(GltfLoaderBadInput, NoTriangles) {
    TempDir dir;
    GltfBuilder b;
    const int pa = b.add_positions(kTriangle);
    b.set_scene({b.add_node("dots", b.add_mesh({GltfBuilder::primitive(pa, -1, 0)}))});
    expect_bad_input(b.write_gltf(dir, "points"), "no triangles");
}

TEST(GltfLoaderBadInput, BrokenNodeGraph) {
    TempDir dir;
    GltfBuilder b = one_triangle();
    b.json["nodes"][0]["children"] = {0};
    expect_bad_input(b.write_gltf(dir, "cycle"), "cycle");
    GltfBuilder c = one_triangle();
    c.json["nodes"][0]["children"] = {7};
    expect_bad_input(c.write_gltf(dir, "child"), "nodes[0].children[0] is 7, not an index of nodes");
    GltfBuilder d = one_triangle();
    d.json["nodes"][0]["mesh"] = 5;
    expect_bad_input(d.write_gltf(dir, "mesh"), "nodes[0].mesh is 5, not an index of meshes");
    GltfBuilder e = one_triangle();
    e.json["scenes"][0]["nodes"] = {0, 0};
    expect_bad_input(e.write_gltf(dir, "twice"), "reached twice");
    GltfBuilder f = one_triangle();
    f.json["meshes"][0]["primitives"][0]["material"] = 2;
    expect_bad_input(f.write_gltf(dir, "material"), "meshes[0].primitives[0].material is 2, not an index of materials");
    GltfBuilder g = one_triangle({{"matrix", {1, 0, 0}}});
    expect_bad_input(g.write_gltf(dir, "matrix"), "matrix");
}

TEST(GltfLoaderBadInput, CompressedGeometryIsRefused) {
    TempDir dir;
    GltfBuilder b = one_triangle();
    b.json["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    b.json["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    expect_bad_input(b.write_gltf(dir, "draco"), "KHR_draco_mesh_compression");
}

// ---- The real worlds (../shared/worlds), when present ----

struct RealWorldFigures {
    size_t objects;
    size_t triangles;
    size_t seeds;
};

void check_real_world(const World& w, size_t file_objects, size_t file_triangles, size_t seeds) {
    // Every triangle in the file is either loaded or counted as dropped.
    EXPECT_EQ(w.triangle_count() + w.stats.degenerate_triangles_dropped, file_triangles);
    EXPECT_LE(w.object_count(), file_objects);
    EXPECT_EQ(w.view_seeds.size(), seeds);
    EXPECT_FALSE(w.bounds.is_empty());
    std::set<std::string> names;
    size_t see_through = 0;
    uint32_t next = 0;
    for (const WorldObject& o : w.objects) {
        names.insert(o.name);
        if (o.flags & kObjectHasSeeThrough) ++see_through;
        EXPECT_EQ(o.first_triangle, next);
        EXPECT_GT(o.triangle_count, 0u);
        next += o.triangle_count;
    }
    EXPECT_EQ(names.size(), w.object_count()) << "object names are unique";
    EXPECT_GT(see_through, 0u) << "some objects are BLEND";
    for (const Triangle& t : w.triangles) {
        for (uint32_t v : t.v) ASSERT_LT(v, w.positions.size());
    }
}

TEST(GltfLoaderRealWorld, OaDm4) {
    const std::string path = test::shared_world("oa_dm4.glb");
    if (path.empty()) GTEST_SKIP() << "../shared/worlds/oa_dm4.glb not present";
    const World w = load(path);
    check_real_world(w, 445, 4093, 7);
    // oa_dm4 has no degenerate triangles: every object and triangle of the file is loaded.
    EXPECT_EQ(w.object_count(), 445u);
    EXPECT_EQ(w.triangle_count(), 4093u);
    EXPECT_EQ(w.stats.degenerate_triangles_dropped, 0u);
}

TEST(GltfLoaderRealWorld, CtfInyard) {
    const std::string path = test::shared_world("ctf_inyard.glb");
    if (path.empty()) GTEST_SKIP() << "../shared/worlds/ctf_inyard.glb not present";
    Context ctx = quiet_context();
    const auto start = std::chrono::steady_clock::now();
    const World w = load_world(ctx, path);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[ info     ] ctf_inyard.glb: %zu objects, %zu triangles, %llu degenerate dropped, %.1f ms\n",
                w.object_count(), w.triangle_count(),
                (unsigned long long)w.stats.degenerate_triangles_dropped, seconds * 1e3);
    check_real_world(w, 2636, 44868, 48);
    // The file holds 1,470 degenerate triangles (751 with a repeated vertex, 719 of exactly zero area);
    // every object keeps some triangles: 2,636 objects and 43,398 triangles remain.
    EXPECT_EQ(w.stats.degenerate_triangles_dropped, 1470u);
    EXPECT_EQ(w.triangle_count(), 43398u);
    EXPECT_EQ(w.object_count(), 2636u);
}

}  // namespace
}  // namespace pvs
