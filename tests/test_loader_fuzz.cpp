// SPDX-License-Identifier: MIT
// Fuzz test of load_world: truncations, bit and byte flips and JSON digit edits of real and hand-built
// worlds (fixed seeds). Each mutant must load into a sane World or throw pvs::Error (kBadInput); any other
// exception, an internal error, or a crash fails.
#include "core/error.h"
#include "io/gltf_loader.h"
#include "io/gltf_writer.h"
#include "tests/gltf_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

namespace pvs {
namespace {

using test::GltfBuilder;
using test::TempDir;

// 300 mutants per base file, 60 under CI; PVSBAKE_FUZZ_ITERATIONS overrides both for a long local run
// (PVSBAKE_FUZZ_VERBOSE=1 prints every rejection).
int iterations() {
    if (const char* env = std::getenv("PVSBAKE_FUZZ_ITERATIONS")) return std::max(1, std::atoi(env));
    return test::in_ci() ? 60 : 300;
}

struct Outcome {
    int loaded = 0;
    int rejected = 0;
};

// A loaded mutant must still be a consistent World.
void check_world(const World& w, const std::string& what) {
    ASSERT_FALSE(w.triangles.empty()) << what;
    ASSERT_EQ(w.triangle_opaque.size(), w.triangles.size()) << what;
    ASSERT_EQ(w.triangle_double_sided.size(), w.triangles.size()) << what;
    for (const Triangle& t : w.triangles) {
        for (uint32_t v : t.v) ASSERT_LT(v, w.positions.size()) << what;
    }
    for (const glm::vec3& p : w.positions) ASSERT_TRUE(is_finite(p)) << what;
    uint64_t next = 0;
    for (const WorldObject& o : w.objects) {
        ASSERT_EQ(o.first_triangle, next) << what;
        ASSERT_GT(o.triangle_count, 0u) << what;
        next += o.triangle_count;
    }
    ASSERT_EQ(next, w.triangles.size()) << what;
}

// Loads path; records the outcome; fails on anything but a World or a bad-input pvs::Error.
void load_mutant(const std::string& path, const std::string& what, Outcome& outcome) {
    Context ctx(Context::Options{.sink = nullptr});
    try {
        const World w = load_world(ctx, path);
        check_world(w, what);
        ++outcome.loaded;
    } catch (const Error& e) {
        if (std::getenv("PVSBAKE_FUZZ_VERBOSE") != nullptr) std::printf("%s: %s\n", what.c_str(), e.what());
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << what << ": " << e.what();
        const std::string msg = e.what();
        EXPECT_TRUE(msg.find('\n') == std::string::npos) << what << ": multi-line message: " << msg;
        ++outcome.rejected;
    } catch (const std::exception& e) {
        ADD_FAILURE() << what << ": unexpected exception: " << e.what();
    } catch (...) {
        ADD_FAILURE() << what << ": unexpected non-standard exception";
    }
}

size_t pick(std::mt19937_64& rng, size_t n) {
    return n == 0 ? 0 : size_t(rng() % n);
}

// Edits digits of a JSON text: replace one, insert a run (huge counts and offsets), or negate.
std::string mutate_json_digits(std::string text, std::mt19937_64& rng, std::string& what) {
    std::vector<size_t> digits;
    for (size_t i = 0; i < text.size(); ++i) {
        if (text[i] >= '0' && text[i] <= '9') digits.push_back(i);
    }
    if (digits.empty()) return text;
    const int edits = 1 + int(pick(rng, 3));
    for (int e = 0; e < edits; ++e) {
        const size_t at = digits[pick(rng, digits.size())];
        if (at >= text.size()) continue;
        switch (pick(rng, 4)) {
            case 0:
                text[at] = char('0' + pick(rng, 10));
                break;
            case 1:
                text.insert(at, std::string(1 + pick(rng, 12), char('1' + pick(rng, 9))));
                break;
            case 2:
                text.insert(at, "-");
                break;
            default:
                text[at] = char('0' + (text[at] - '0' + 1) % 10);
                break;
        }
        what += " digit@" + std::to_string(at);
    }
    return text;
}

void flip_bits(std::string& bytes, size_t from, size_t to, std::mt19937_64& rng, std::string& what) {
    if (to <= from) return;
    const int flips = 1 + int(pick(rng, 4));
    for (int f = 0; f < flips; ++f) {
        const size_t at = from + pick(rng, to - from);
        if (pick(rng, 2) == 0) {
            bytes[at] = char(uint8_t(bytes[at]) ^ uint8_t(1u << pick(rng, 8)));
        } else {
            bytes[at] = char(rng() & 0xFF);
        }
        what += " flip@" + std::to_string(at);
    }
}

// Mutates a .glb: raw truncation, raw flips (anywhere, JSON chunk, BIN chunk), or JSON edits with a
// rebuilt, consistent container (so they reach the glTF parser and the accessor checks).
std::string mutate_glb(const std::string& base, std::mt19937_64& rng, std::string& what) {
    std::string json_text, bin;
    const bool split = test::split_glb(base, &json_text, &bin);
    const size_t json_from = 20, json_to = 20 + json_text.size();
    std::string out = base;
    switch (pick(rng, 6)) {
        case 0:
            out.resize(pick(rng, base.size()));
            what = "truncate to " + std::to_string(out.size());
            break;
        case 1:
            what = "flip anywhere";
            flip_bits(out, 0, out.size(), rng, what);
            break;
        case 2:
            what = "flip JSON";
            flip_bits(out, json_from, json_to, rng, what);
            break;
        case 3:
            what = "flip BIN";
            flip_bits(out, split && !bin.empty() ? json_to + 8 : 0, out.size(), rng, what);
            break;
        case 4:
            what = "JSON digits";
            out = test::make_glb_bytes(mutate_json_digits(json_text, rng, what), bin);
            break;
        default: {
            what = "JSON cut";
            std::string t = json_text;
            const size_t at = pick(rng, t.size());
            t.erase(at, 1 + pick(rng, 16));
            what += " @" + std::to_string(at);
            out = test::make_glb_bytes(t, bin);
            break;
        }
    }
    return out;
}

std::string mutate_text(const std::string& base, std::mt19937_64& rng, std::string& what) {
    std::string out = base;
    switch (pick(rng, 4)) {
        case 0:
            out.resize(pick(rng, base.size()));
            what = "truncate to " + std::to_string(out.size());
            break;
        case 1:
            what = "flip";
            flip_bits(out, 0, out.size(), rng, what);
            break;
        case 2:
            what = "JSON digits";
            out = mutate_json_digits(out, rng, what);
            break;
        default: {
            const size_t at = pick(rng, out.size());
            out.erase(at, 1 + pick(rng, 16));
            what = "cut @" + std::to_string(at);
            break;
        }
    }
    return out;
}

Outcome fuzz_glb(const std::string& base, uint64_t seed, const TempDir& dir) {
    std::mt19937_64 rng(seed);
    Outcome outcome;
    const std::string path = dir.file("mutant.glb");
    for (int i = 0; i < iterations(); ++i) {
        std::string what;
        test::write_file(path, mutate_glb(base, rng, what));
        load_mutant(path, "iteration " + std::to_string(i) + ": " + what, outcome);
        if (testing::Test::HasFailure()) break;
    }
    return outcome;
}

// A small hand-built world with strided, sparse, u16/u8-indexed, strip and fan primitives and extras.
GltfBuilder varied_world() {
    GltfBuilder b;
    const int glass = b.add_material("BLEND", true);
    const int box_pos = b.add_strided_positions(
        {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}, 16);
    const int box_idx = b.add_indices({0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4,
                                       2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6},
                                      test::kGlUnsignedShort);
    const int strip_pos = b.add_positions({{0, 0, 3}, {1, 0, 3}, {0, 1, 3}, {1, 1, 3}, {0, 2, 3}});
    const int fan_idx = b.add_indices({0, 1, 2, 3, 4}, test::kGlUnsignedByte);
    const std::vector<uint16_t> sparse_idx = {1, 3};
    const std::vector<float> sparse_val = {2, 0, 3, 2, 1, 3};
    const int iv = b.add_view(std::string(reinterpret_cast<const char*>(sparse_idx.data()), 4));
    const int vv = b.add_view(std::string(reinterpret_cast<const char*>(sparse_val.data()), 24));
    b.json["accessors"][size_t(strip_pos)]["sparse"] = {
        {"count", 2},
        {"indices", {{"bufferView", iv}, {"componentType", test::kGlUnsignedShort}}},
        {"values", {{"bufferView", vv}}}};
    b.json["accessors"][size_t(strip_pos)]["max"] = {2, 2, 3};  // the sparse values reach x = 2
    const int zeros = b.add_accessor(-1, test::kGlFloat, 3, "VEC3");
    b.json["accessors"][size_t(zeros)]["sparse"] = {
        {"count", 2},
        {"indices", {{"bufferView", iv}, {"componentType", test::kGlUnsignedShort}, {"byteOffset", 0}}},
        {"values", {{"bufferView", vv}}}};
    b.json["accessors"][size_t(zeros)]["count"] = 4;
    const int box = b.add_mesh({GltfBuilder::primitive(box_pos, box_idx)});
    const int strips =
        b.add_mesh({GltfBuilder::primitive(strip_pos, -1, 5, glass),
                    GltfBuilder::primitive(strip_pos, fan_idx, 6), GltfBuilder::primitive(strip_pos, -1, 1)});
    const int sparse_only =
        b.add_mesh({GltfBuilder::primitive(zeros, b.add_indices({1, 3, 0}, test::kGlUnsignedByte))});
    const int leaf = b.add_node("leaf", box, {{"translation", {0, 0, 1}}, {"rotation", {0, 0.6, 0, 0.8}}});
    const int group = b.add_node("group", -1, {{"children", {leaf}}, {"scale", {2, 2, 2}}});
    b.set_scene({group,
                 b.add_node("strips", strips, {{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1}}}),
                 b.add_node("zeros", sparse_only, {{"extras", {{"pvs_occluder", false}}}}),
                 b.add_node("spawn", -1, {{"translation", {0, 1, 0}}, {"extras", {{"pvs_view_seed", true}}}}),
                 b.add_node("volume", box, {{"extras", {{"pvs_view_volume", true}}}})});
    return b;
}

TEST(LoaderFuzz, RealWorldGlb) {
    const std::string world = test::shared_world("oa_dm4.glb");
    if (world.empty()) GTEST_SKIP() << "../shared/worlds/oa_dm4.glb not present";
    TempDir dir;
    const auto start = std::chrono::steady_clock::now();
    const Outcome o = fuzz_glb(test::read_file(world), 0xD4D4D4ULL, dir);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[ info     ] oa_dm4 mutants: %d loaded, %d rejected, %.1f s\n", o.loaded, o.rejected, s);
    EXPECT_GT(o.rejected, 0);
}

TEST(LoaderFuzz, WrittenGlb) {
    TempDir dir;
    SceneDesc scene;
    scene.materials.push_back({"glass", {0.5f, 0.7f, 0.9f, 0.4f}, SceneMaterial::Alpha::kBlend, true});
    for (int i = 0; i < 6; ++i) {
        const glm::vec3 lo(float(i) * 2.0f, 0.0f, float(i % 3));
        scene.nodes.push_back(
            make_box_node("box" + std::to_string(i), Aabb::of(lo, lo + glm::vec3(1.5f)), i % 2 - 1));
    }
    SceneNode seed;
    seed.name = "seed";
    seed.translation = {1, 1, 1};
    seed.view_seed = true;
    scene.nodes.push_back(seed);
    const std::string base_path = dir.file("base.glb");
    write_glb(scene, base_path);
    const Outcome o = fuzz_glb(test::read_file(base_path), 0x5EED0001ULL, dir);
    std::printf("[ info     ] written .glb mutants: %d loaded, %d rejected\n", o.loaded, o.rejected);
    EXPECT_GT(o.loaded, 0);
    EXPECT_GT(o.rejected, 0);
}

TEST(LoaderFuzz, HandBuiltGlb) {
    TempDir dir;
    const std::string base = varied_world().glb_bytes();
    {
        Outcome sanity;
        test::write_file(dir.file("sanity.glb"), base);
        load_mutant(dir.file("sanity.glb"), "unmutated", sanity);
        ASSERT_EQ(sanity.loaded, 1);
    }
    const Outcome o = fuzz_glb(base, 0x5EED0002ULL, dir);
    std::printf("[ info     ] hand-built .glb mutants: %d loaded, %d rejected\n", o.loaded, o.rejected);
    EXPECT_GT(o.loaded, 0);
    EXPECT_GT(o.rejected, 0);
}

TEST(LoaderFuzz, GltfWithExternalBin) {
    TempDir dir;
    const GltfBuilder b = varied_world();
    const std::string base_path = b.write_gltf(dir, "world");  // world.gltf + world.bin
    const std::string base = test::read_file(base_path);
    const std::string bin = b.padded_bin();
    {
        Outcome sanity;
        load_mutant(base_path, "unmutated", sanity);
        ASSERT_EQ(sanity.loaded, 1);
    }
    std::mt19937_64 rng(0x5EED0003ULL);
    Outcome o;
    const std::string path = dir.file("mutant.gltf");
    for (int i = 0; i < iterations() && !testing::Test::HasFailure(); ++i) {
        std::string what;
        std::string mutant_bin = bin;
        std::string text = base;
        if (pick(rng, 5) == 0) {  // mutate the .bin instead: truncate it or flip bytes in it
            if (pick(rng, 2) == 0) {
                mutant_bin.resize(pick(rng, bin.size()));
                what = "bin truncated to " + std::to_string(mutant_bin.size());
            } else {
                what = "bin";
                flip_bits(mutant_bin, 0, mutant_bin.size(), rng, what);
            }
        } else {
            text = mutate_text(base, rng, what);
        }
        test::write_file(dir.file("world.bin"), mutant_bin);
        test::write_file(path, text);
        load_mutant(path, "iteration " + std::to_string(i) + ": " + what, o);
    }
    std::printf("[ info     ] .gltf + .bin mutants: %d loaded, %d rejected\n", o.loaded, o.rejected);
    EXPECT_GT(o.loaded, 0);
    EXPECT_GT(o.rejected, 0);
}

TEST(LoaderFuzz, EmbeddedGltf) {
    TempDir dir;
    const std::string base = test::read_file(varied_world().write_embedded(dir, "embedded"));
    std::mt19937_64 rng(0x5EED0004ULL);
    Outcome o;
    const std::string path = dir.file("mutant.gltf");
    for (int i = 0; i < iterations() && !testing::Test::HasFailure(); ++i) {
        std::string what;
        test::write_file(path, mutate_text(base, rng, what));
        load_mutant(path, "iteration " + std::to_string(i) + ": " + what, o);
    }
    std::printf("[ info     ] embedded .gltf mutants: %d loaded, %d rejected\n", o.loaded, o.rejected);
    EXPECT_GT(o.rejected, 0);
}

}  // namespace
}  // namespace pvs
