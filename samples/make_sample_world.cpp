// SPDX-License-Identifier: MIT
// make_sample_world: writes the bundled sample world, a maze of rooms joined by doorways, to a .glb.
//
//   make_sample_world OUT.glb [--rooms N] [--seed S]
//
// A square building of N x N rooms (8 m, 3 m high) with 0.5 m floor and ceiling slabs and 0.6 m walls
// (thick enough to keep a shrunk occluder at the default epsilon and voxels), one
// doorway per wall of a random spanning tree (a maze: the rooms are all reachable, most walls are
// closed), glass windows (alphaMode BLEND) in a few closed walls, crates and pillars in the rooms, and
// a view seed (extras.pvs_view_seed) at eye height in every room. Every wall piece, slab and prop is
// its own object, so a PVS has something to cull: from most rooms, most of the building is hidden.
// Deterministic: the same arguments give the same bytes.
#include "core/random.h"
#include "io/gltf_writer.h"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <numeric>
#include <string>
#include <vector>

namespace {

constexpr float kRoomM = 8.0f;
constexpr float kWallM = 0.6f;
constexpr float kHeightM = 3.0f;
constexpr float kSlabM = 0.5f;
constexpr float kDoorWidthM = 1.2f;
constexpr float kDoorHeightM = 2.2f;
constexpr float kWindowWidthM = 1.6f;
constexpr float kWindowLowM = 1.0f;
constexpr float kWindowHighM = 2.0f;
constexpr float kGlassM = 0.02f;

enum Material { kStone = 0, kWood = 1, kGlass = 2, kFloor = 3 };

struct Builder {
    pvs::SceneDesc scene;
    void box(const std::string& name, glm::vec3 lo, glm::vec3 hi, int material) {
        scene.nodes.push_back(pvs::make_box_node(name, pvs::Aabb::of(lo, hi), material));
    }
};

// A wall along axis `along` (0 = x, 2 = z) from a to b at `across` (the wall's centre line), with an
// optional opening [o0, o1] x [y0, y1]; glass fills the opening when `glass`.
void wall(Builder& b, const std::string& name, int along, float across, float a, float c, bool open, float y0,
          float y1, float width, bool glass) {
    auto piece = [&](const std::string& suffix, float s0, float s1, float h0, float h1, float thick,
                     int mat) {
        if (s1 - s0 <= 1e-4f || h1 - h0 <= 1e-4f) return;
        glm::vec3 lo(0.0f), hi(0.0f);
        lo[along] = s0;
        hi[along] = s1;
        const int other = along == 0 ? 2 : 0;
        lo[other] = across - thick / 2;
        hi[other] = across + thick / 2;
        lo.y = h0;
        hi.y = h1;
        b.box(name + suffix, lo, hi, mat);
    };
    if (!open) {
        piece("", a, c, 0.0f, kHeightM, kWallM, kStone);
        return;
    }
    const float mid = 0.5f * (a + c);
    const float o0 = mid - width / 2, o1 = mid + width / 2;
    piece("_left", a, o0, 0.0f, kHeightM, kWallM, kStone);
    piece("_right", o1, c, 0.0f, kHeightM, kWallM, kStone);
    piece("_above", o0, o1, y1, kHeightM, kWallM, kStone);
    piece("_below", o0, o1, 0.0f, y0, kWallM, kStone);
    if (glass) piece("_glass", o0, o1, y0, y1, kGlassM, kGlass);
}

pvs::SceneDesc make_rooms(int n, uint64_t seed) {
    Builder b;
    b.scene.materials = {
        {"stone", {0.62f, 0.60f, 0.56f, 1.0f}, pvs::SceneMaterial::Alpha::kOpaque, false},
        {"wood", {0.55f, 0.38f, 0.20f, 1.0f}, pvs::SceneMaterial::Alpha::kOpaque, false},
        {"glass", {0.60f, 0.80f, 0.95f, 0.3f}, pvs::SceneMaterial::Alpha::kBlend, true},
        {"floor", {0.45f, 0.45f, 0.48f, 1.0f}, pvs::SceneMaterial::Alpha::kOpaque, false},
    };
    pvs::Rng rng(seed, 0);
    const float size = float(n) * kRoomM;

    // A maze: a random spanning tree of the rooms (Kruskal over shuffled walls) decides the doorways.
    struct Wall {
        int i, j, axis;  // between room (i, j) and its +x (axis 0) or +z (axis 2) neighbour
    };
    std::vector<Wall> walls;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (i + 1 < n) walls.push_back({i, j, 0});
            if (j + 1 < n) walls.push_back({i, j, 2});
        }
    for (size_t k = walls.size(); k > 1; --k) std::swap(walls[k - 1], walls[rng.below(uint32_t(k))]);
    std::vector<int> parent(size_t(n * n));
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    std::vector<uint8_t> door(walls.size(), 0), window(walls.size(), 0);
    int windows = 0;
    for (size_t k = 0; k < walls.size(); ++k) {
        const Wall& w = walls[k];
        const int r0 = w.j * n + w.i, r1 = w.axis == 0 ? r0 + 1 : r0 + n;
        if (find(r0) != find(r1)) {
            parent[find(r0)] = find(r1);
            door[k] = 1;
        } else if (windows < n - 1) {
            window[k] = 1;  // a few closed walls get a window: sight through glass, not through a doorway
            ++windows;
        }
    }

    // Slabs: one floor and one ceiling per room.
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const glm::vec3 lo(float(i) * kRoomM, 0.0f, float(j) * kRoomM);
            b.box(fmt::format("floor_{}_{}", i, j), lo + glm::vec3(0, -kSlabM, 0),
                  lo + glm::vec3(kRoomM, 0, kRoomM), kFloor);
            b.box(fmt::format("ceiling_{}_{}", i, j), lo + glm::vec3(0, kHeightM, 0),
                  lo + glm::vec3(kRoomM, kHeightM + kSlabM, kRoomM), kStone);
        }
    // Outer walls, one piece per room side.
    for (int k = 0; k < n; ++k) {
        const float a = float(k) * kRoomM, c = a + kRoomM;
        wall(b, fmt::format("outer_south_{}", k), 0, 0.0f, a, c, false, 0, 0, 0, false);
        wall(b, fmt::format("outer_north_{}", k), 0, size, a, c, false, 0, 0, 0, false);
        wall(b, fmt::format("outer_west_{}", k), 2, 0.0f, a, c, false, 0, 0, 0, false);
        wall(b, fmt::format("outer_east_{}", k), 2, size, a, c, false, 0, 0, 0, false);
    }
    // Inner walls.
    for (size_t k = 0; k < walls.size(); ++k) {
        const Wall& w = walls[k];
        const std::string name = fmt::format("wall_{}_{}_{}", w.i, w.j, w.axis == 0 ? "x" : "z");
        if (w.axis == 0) {  // between (i, j) and (i + 1, j): the plane x = (i + 1) * room, along z
            const float a = float(w.j) * kRoomM;
            wall(b, name, 2, float(w.i + 1) * kRoomM, a, a + kRoomM, door[k] || window[k],
                 door[k] ? 0.0f : kWindowLowM, door[k] ? kDoorHeightM : kWindowHighM,
                 door[k] ? kDoorWidthM : kWindowWidthM, window[k] != 0);
        } else {
            const float a = float(w.i) * kRoomM;
            wall(b, name, 0, float(w.j + 1) * kRoomM, a, a + kRoomM, door[k] || window[k],
                 door[k] ? 0.0f : kWindowLowM, door[k] ? kDoorHeightM : kWindowHighM,
                 door[k] ? kDoorWidthM : kWindowWidthM, window[k] != 0);
        }
    }
    // Props and view seeds.
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const glm::vec3 o(float(i) * kRoomM, 0.0f, float(j) * kRoomM);
            const int crates = 1 + int(rng.below(3));
            for (int c = 0; c < crates; ++c) {
                const float s = 0.5f + 0.5f * rng.uniform();
                const float x = 1.0f + (kRoomM - 2.0f - s) * rng.uniform();
                const float z = 1.0f + (kRoomM - 2.0f - s) * rng.uniform();
                b.box(fmt::format("crate_{}_{}_{}", i, j, c), o + glm::vec3(x, 0, z),
                      o + glm::vec3(x + s, s, z + s), kWood);
            }
            if (rng.below(2) == 0) {
                const float x = 2.0f + 3.5f * rng.uniform(), z = 2.0f + 3.5f * rng.uniform();
                b.box(fmt::format("pillar_{}_{}", i, j), o + glm::vec3(x, 0, z),
                      o + glm::vec3(x + 0.5f, kHeightM, z + 0.5f), kStone);
            }
            pvs::SceneNode seed_node;
            seed_node.name = fmt::format("spawn_{}_{}", i, j);
            seed_node.translation = o + glm::vec3(kRoomM / 2, 1.6f, kRoomM / 2);
            seed_node.view_seed = true;
            b.scene.nodes.push_back(seed_node);
        }
    return b.scene;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || std::strcmp(argv[1], "--help") == 0) {
        std::fprintf(
            stderr,
            "usage: make_sample_world OUT.glb [--rooms N (2..32, default 4)] [--seed S (default 1)]\n");
        return argc < 2 ? 2 : 0;
    }
    int rooms = 4;
    uint64_t seed = 1;
    for (int a = 2; a + 1 < argc; a += 2) {
        if (std::strcmp(argv[a], "--rooms") == 0) {
            rooms = std::atoi(argv[a + 1]);
        } else if (std::strcmp(argv[a], "--seed") == 0) {
            seed = std::strtoull(argv[a + 1], nullptr, 10);
        } else {
            std::fprintf(stderr, "error: unknown option %s\n", argv[a]);
            return 2;
        }
    }
    if (rooms < 2 || rooms > 32) {
        std::fprintf(stderr, "error: --rooms must be in 2..32 (got %d)\n", rooms);
        return 2;
    }
    try {
        const pvs::SceneDesc scene = make_rooms(rooms, seed);
        pvs::write_glb(scene, argv[1]);
        std::fprintf(stderr, "wrote %s: %d x %d rooms, %zu nodes\n", argv[1], rooms, rooms,
                     scene.nodes.size());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
