// SPDX-License-Identifier: MIT
// Tests of write_glb and make_box_node: the GLB layout, the JSON written, errors, and a round trip through
// load_world (objects, names, triangles, bounds, materials, extras).
#include "io/gltf_writer.h"

#include "core/error.h"
#include "io/gltf_loader.h"
#include "samples/random_world.h"
#include "samples/world_edit.h"
#include "tests/gltf_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <map>

namespace pvs {
namespace {

using test::TempDir;

Context quiet_context() {
    return Context(Context::Options{.sink = nullptr});
}

uint32_t u32_at(const std::string& bytes, size_t offset) {
    uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, 4);
    return v;
}

void expect_near(glm::vec3 got, glm::vec3 want, float tol = 1e-6f) {
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}

SceneDesc sample_scene() {
    SceneDesc s;
    s.materials.push_back({"stone", {0.6f, 0.6f, 0.6f, 1.0f}, SceneMaterial::Alpha::kOpaque, false});
    s.materials.push_back({"glass", {0.6f, 0.8f, 0.9f, 0.3f}, SceneMaterial::Alpha::kBlend, true});
    s.materials.push_back({"leaves", {0.1f, 0.7f, 0.1f, 1.0f}, SceneMaterial::Alpha::kMask, false});
    s.nodes.push_back(make_box_node("wall", Aabb::of({0, 0, 0}, {4, 3, 0.25f}), 0));
    s.nodes.push_back(make_box_node("window", Aabb::of({1, 1, 2}, {2, 2, 2.05f}), 1));
    SceneNode ghost = make_box_node("ghost", Aabb::of({-3, 0, -3}, {-2, 1, -2}), 0);
    ghost.occluder = false;
    s.nodes.push_back(ghost);
    SceneNode beacon = make_box_node("beacon", Aabb::of({5, 0, 5}, {6, 4, 6}));
    beacon.always_visible = true;
    s.nodes.push_back(beacon);
    SceneNode moved = make_box_node("moved", Aabb::of({0, 0, 0}, {1, 1, 1}), 2);
    moved.translation = {10, 0, 0};
    s.nodes.push_back(moved);
    SceneNode spawn;
    spawn.name = "spawn";
    spawn.translation = {1, 1.6f, 1};
    spawn.view_seed = true;
    s.nodes.push_back(spawn);
    SceneNode volume = make_box_node("volume", Aabb::of({-10, -1, -10}, {20, 5, 20}));
    volume.view_volume = true;
    s.nodes.push_back(volume);
    return s;
}

TEST(GltfWriter, BoxNodeIsClosedAndFacesOutward) {
    const Aabb box = Aabb::of({1, 2, 3}, {4, 6, 8});
    const SceneNode node = make_box_node("b", box, 3);
    EXPECT_EQ(node.name, "b");
    EXPECT_EQ(node.material, 3);
    ASSERT_EQ(node.positions.size(), 8u);
    ASSERT_EQ(node.indices.size(), 36u);
    for (const glm::vec3& p : node.positions) {
        EXPECT_TRUE(p.x == box.min.x || p.x == box.max.x);
        EXPECT_TRUE(p.y == box.min.y || p.y == box.max.y);
        EXPECT_TRUE(p.z == box.min.z || p.z == box.max.z);
    }
    double area = 0;
    for (size_t t = 0; t < 12; ++t) {
        const glm::vec3 a = node.positions[node.indices[3 * t]];
        const glm::vec3 b = node.positions[node.indices[3 * t + 1]];
        const glm::vec3 c = node.positions[node.indices[3 * t + 2]];
        const glm::vec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(glm::dot(n, (a + b + c) / 3.0f - box.center()), 0.0f)
            << "triangle " << t << " faces inward";
        area += 0.5 * glm::length(n);
    }
    const glm::vec3 s = box.size();
    EXPECT_NEAR(area, 2.0 * (s.x * s.y + s.y * s.z + s.z * s.x), 1e-4);
    // Closed: every edge is used once in each direction.
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (size_t t = 0; t < 12; ++t) {
        for (int k = 0; k < 3; ++k) ++edges[{node.indices[3 * t + k], node.indices[3 * t + (k + 1) % 3]}];
    }
    for (const auto& [edge, uses] : edges) {
        EXPECT_EQ(uses, 1);
        EXPECT_EQ(edges.count({edge.second, edge.first}), 1u);
    }
}

TEST(GltfWriter, GlbLayoutAndJson) {
    TempDir dir;
    const std::string path = dir.file("scene.glb");
    write_glb(sample_scene(), path);
    const std::string bytes = test::read_file(path);
    ASSERT_GE(bytes.size(), 28u);
    EXPECT_EQ(u32_at(bytes, 0), 0x46546C67u);
    EXPECT_EQ(u32_at(bytes, 4), 2u);
    EXPECT_EQ(u32_at(bytes, 8), bytes.size());
    const uint32_t json_len = u32_at(bytes, 12);
    EXPECT_EQ(u32_at(bytes, 16), 0x4E4F534Au);
    EXPECT_EQ(json_len % 4, 0u);
    const size_t bin_at = 20 + size_t(json_len);
    ASSERT_LE(bin_at + 8, bytes.size());
    const uint32_t bin_len = u32_at(bytes, bin_at);
    EXPECT_EQ(u32_at(bytes, bin_at + 4), 0x004E4942u);
    EXPECT_EQ(bin_len % 4, 0u);
    EXPECT_EQ(bin_at + 8 + bin_len, bytes.size());

    const std::string text = bytes.substr(20, json_len);
    EXPECT_EQ(text.find_last_not_of(' ') + 1, text.find_last_of('}') + 1) << "JSON padded with spaces only";
    const nlohmann::json doc = nlohmann::json::parse(text);
    EXPECT_EQ(doc["asset"]["version"], "2.0");
    EXPECT_EQ(doc["asset"]["generator"], "pvsbake");
    EXPECT_EQ(doc["scene"], 0);
    EXPECT_EQ(doc["scenes"][0]["nodes"].size(), 7u);
    EXPECT_EQ(doc["buffers"].size(), 1u);
    EXPECT_EQ(doc["buffers"][0]["byteLength"], bin_len);
    EXPECT_FALSE(doc["buffers"][0].contains("uri"));
    EXPECT_EQ(doc["meshes"].size(), 6u);  // every node but the seed

    const auto& materials = doc["materials"];
    ASSERT_EQ(materials.size(), 3u);
    EXPECT_FALSE(materials[0].contains("alphaMode"));
    EXPECT_FALSE(materials[0].contains("doubleSided"));
    EXPECT_EQ(materials[1]["alphaMode"], "BLEND");
    EXPECT_EQ(materials[1]["doubleSided"], true);
    EXPECT_EQ(materials[2]["alphaMode"], "MASK");
    EXPECT_NEAR(materials[1]["pbrMetallicRoughness"]["baseColorFactor"][3].get<double>(), 0.3, 1e-6);

    const auto& nodes = doc["nodes"];
    ASSERT_EQ(nodes.size(), 7u);
    EXPECT_EQ(nodes[0]["name"], "wall");
    EXPECT_FALSE(nodes[0].contains("translation"));
    EXPECT_FALSE(nodes[0].contains("extras"));
    EXPECT_EQ(nodes[2]["extras"], nlohmann::json({{"pvs_occluder", false}}));
    EXPECT_EQ(nodes[3]["extras"], nlohmann::json({{"pvs_always_visible", true}}));
    EXPECT_EQ(nodes[4]["translation"][0], 10.0);
    EXPECT_FALSE(nodes[5].contains("mesh"));
    EXPECT_EQ(nodes[5]["extras"], nlohmann::json({{"pvs_view_seed", true}}));
    EXPECT_EQ(nodes[6]["extras"], nlohmann::json({{"pvs_view_volume", true}}));

    // Accessors: float VEC3 positions with min/max, u32 indices; views 4-byte aligned inside the buffer.
    const auto& mesh0 = doc["meshes"][0]["primitives"][0];
    EXPECT_EQ(mesh0["mode"], 4);
    EXPECT_EQ(mesh0["material"], 0);
    EXPECT_FALSE(doc["meshes"][3]["primitives"][0].contains("material"));
    const auto& pos = doc["accessors"][mesh0["attributes"]["POSITION"].get<int>()];
    EXPECT_EQ(pos["componentType"], 5126);
    EXPECT_EQ(pos["type"], "VEC3");
    EXPECT_EQ(pos["count"], 8);
    EXPECT_EQ(pos["min"], nlohmann::json({0.0, 0.0, 0.0}));
    EXPECT_EQ(pos["max"], nlohmann::json({4.0, 3.0, 0.25}));
    const auto& idx = doc["accessors"][mesh0["indices"].get<int>()];
    EXPECT_EQ(idx["componentType"], 5125);
    EXPECT_EQ(idx["count"], 36);
    for (const auto& view : doc["bufferViews"]) {
        EXPECT_EQ(view["byteOffset"].get<size_t>() % 4, 0u);
        EXPECT_LE(view["byteOffset"].get<size_t>() + view["byteLength"].get<size_t>(), bin_len);
    }
}

TEST(GltfWriter, RoundTripThroughLoader) {
    TempDir dir;
    const std::string path = dir.file("round.glb");
    write_glb(sample_scene(), path);
    Context ctx = quiet_context();
    const World w = load_world(ctx, path);
    ASSERT_EQ(w.object_count(), 5u);
    const char* names[] = {"wall", "window", "ghost", "beacon", "moved"};
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(w.objects[i].name, names[i]);
        EXPECT_EQ(w.objects[i].triangle_count, 12u);
        EXPECT_EQ(w.objects[i].first_triangle, 12 * i);
    }
    EXPECT_EQ(w.triangle_count(), 60u);
    EXPECT_EQ(w.stats.degenerate_triangles_dropped, 0u);
    expect_near(w.objects[0].bounds.min, {0, 0, 0});
    expect_near(w.objects[0].bounds.max, {4, 3, 0.25f});
    expect_near(w.objects[4].bounds.min, {10, 0, 0});  // translation applied
    expect_near(w.objects[4].bounds.max, {11, 1, 1});
    expect_near(w.bounds.min, {-3, 0, -3});
    expect_near(w.bounds.max, {11, 4, 6});

    EXPECT_EQ(w.objects[0].flags, uint32_t(kObjectHasOpaque));
    EXPECT_EQ(w.objects[1].flags, uint32_t(kObjectHasSeeThrough)) << "BLEND is not opaque";
    EXPECT_EQ(w.objects[2].flags, uint32_t(kObjectHasSeeThrough | kObjectNeverOccludes));
    EXPECT_EQ(w.objects[3].flags, uint32_t(kObjectHasOpaque | kObjectAlwaysVisible));
    EXPECT_EQ(w.objects[4].flags, uint32_t(kObjectHasSeeThrough)) << "MASK is not opaque";
    for (size_t t = 0; t < w.triangle_count(); ++t) {
        const size_t object = t / 12;
        EXPECT_EQ(w.triangle_opaque[t], object == 0 || object == 3 ? 1 : 0) << t;
        EXPECT_EQ(w.triangle_double_sided[t], object == 1 ? 1 : 0) << t;
    }
    // Winding survives: every normal points away from its box's centre.
    for (const WorldObject& o : w.objects) {
        for (uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t) {
            const glm::vec3 a = w.positions[w.triangles[t].v[0]];
            const glm::vec3 b = w.positions[w.triangles[t].v[1]];
            const glm::vec3 c = w.positions[w.triangles[t].v[2]];
            EXPECT_GT(glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - o.bounds.center()), 0.0f);
        }
    }
    ASSERT_EQ(w.view_seeds.size(), 1u);
    expect_near(w.view_seeds[0], {1, 1.6f, 1});
    ASSERT_EQ(w.view_volume_boxes.size(), 1u);
    expect_near(w.view_volume_boxes[0].min, {-10, -1, -10});
    expect_near(w.view_volume_boxes[0].max, {20, 5, 20});
}

// edited_world without edits (samples/world_edit.h): a world written as a scene and loaded again is the same world (objects, triangles in order, their
// positions bit for bit, flags, seeds and view boxes), on the sample scene's world (every material kind and
// flag) and on a random world (turned and hollow walls, see-through blocks).
TEST(GltfWriter, AWorldWrittenAsASceneLoadsAsTheSameWorld) {
    TempDir dir;
    Context ctx = quiet_context();
    const std::string first = dir.file("first.glb");
    write_glb(sample_scene(), first);
    const std::vector<World> worlds = {load_world(ctx, first), make_random_world(3, 0).world};
    for (size_t k = 0; k < worlds.size(); ++k) {
        SCOPED_TRACE("world " + std::to_string(k));
        const World& a = worlds[k];
        const std::string path = dir.file("again" + std::to_string(k) + ".glb");
        write_glb(edited_world(a, {}), path);
        const World b = load_world(ctx, path);
        ASSERT_EQ(b.objects.size(), a.objects.size());
        ASSERT_EQ(b.triangles.size(), a.triangles.size());
        for (size_t o = 0; o < a.objects.size(); ++o) {
            EXPECT_EQ(b.objects[o].name, a.objects[o].name);
            EXPECT_EQ(b.objects[o].flags, a.objects[o].flags) << a.objects[o].name;
            EXPECT_EQ(b.objects[o].first_triangle, a.objects[o].first_triangle);
            EXPECT_EQ(b.objects[o].triangle_count, a.objects[o].triangle_count);
            EXPECT_EQ(b.objects[o].bounds.min, a.objects[o].bounds.min);
            EXPECT_EQ(b.objects[o].bounds.max, a.objects[o].bounds.max);
        }
        for (size_t t = 0; t < a.triangles.size(); ++t) {
            for (int v = 0; v < 3; ++v)
                EXPECT_EQ(b.positions[b.triangles[t].v[v]], a.positions[a.triangles[t].v[v]]) << t;
            EXPECT_EQ(b.triangle_opaque[t], a.triangle_opaque[t]) << t;
            EXPECT_EQ(b.triangle_double_sided[t], a.triangle_double_sided[t]) << t;
        }
        EXPECT_EQ(b.view_seeds, a.view_seeds);
        ASSERT_EQ(b.view_volume_boxes.size(), a.view_volume_boxes.size());
        for (size_t v = 0; v < a.view_volume_boxes.size(); ++v) {
            EXPECT_EQ(b.view_volume_boxes[v].min, a.view_volume_boxes[v].min);
            EXPECT_EQ(b.view_volume_boxes[v].max, a.view_volume_boxes[v].max);
        }
    }
}

TEST(GltfWriter, SeedsOnlySceneHasNoBuffer) {
    TempDir dir;
    SceneDesc s;
    SceneNode seed;
    seed.name = "only";
    seed.view_seed = true;
    s.nodes.push_back(seed);
    const std::string path = dir.file("seeds.glb");
    write_glb(s, path);
    const std::string bytes = test::read_file(path);
    const uint32_t json_len = u32_at(bytes, 12);
    EXPECT_EQ(bytes.size(), 20u + json_len) << "no BIN chunk without triangles";
    const nlohmann::json doc = nlohmann::json::parse(bytes.substr(20, json_len));
    EXPECT_FALSE(doc.contains("buffers"));
    Context ctx = quiet_context();
    try {
        load_world(ctx, path);
        ADD_FAILURE() << "a world without triangles loaded";
    } catch (const Error& e) {
        EXPECT_TRUE(std::string(e.what()).find("no triangles") != std::string::npos) << e.what();
    }
}

TEST(GltfWriter, InvalidInputThrowsAndLeavesNoFile) {
    TempDir dir;
    const std::string path = dir.file("bad.glb");
    auto expect_error = [&](const SceneDesc& s, const std::string& word) {
        try {
            write_glb(s, path);
            ADD_FAILURE() << "no error for " << word;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
            EXPECT_TRUE(std::string(e.what()).find(word) != std::string::npos) << e.what();
        }
        EXPECT_FALSE(std::filesystem::exists(path));
        EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "a temporary file was left behind";
    };
    SceneDesc index;
    index.nodes.push_back(make_box_node("box", Aabb::of({0, 0, 0}, {1, 1, 1})));
    index.nodes[0].indices[5] = 8;
    expect_error(index, "index");
    SceneDesc material;
    material.nodes.push_back(make_box_node("box", Aabb::of({0, 0, 0}, {1, 1, 1}), 2));
    expect_error(material, "material 2");
    SceneDesc partial;
    partial.nodes.push_back(make_box_node("box", Aabb::of({0, 0, 0}, {1, 1, 1})));
    partial.nodes[0].indices.pop_back();
    expect_error(partial, "multiple of 3");
}

TEST(GltfWriter, OverwritesAtomically) {
    TempDir dir;
    const std::string path = dir.file("twice.glb");
    SceneDesc one;
    one.nodes.push_back(make_box_node("a", Aabb::of({0, 0, 0}, {1, 1, 1})));
    write_glb(one, path);
    SceneDesc two = one;
    two.nodes.push_back(make_box_node("b", Aabb::of({2, 0, 0}, {3, 1, 1})));
    write_glb(two, path);
    Context ctx = quiet_context();
    EXPECT_EQ(load_world(ctx, path).object_count(), 2u);
    size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1u);
}

}  // namespace
}  // namespace pvs
