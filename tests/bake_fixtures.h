// SPDX-License-Identifier: MIT
// Bakes and checks for the loader's tests (test_runtime_loader*): bakes are written by write_bake_file, so
// every file a test loads is one the baker could have made; the checks compare what the loader answers
// with what was written.
#pragma once

#include "io/bake_file.h"
#include "tests/horizon_fixture.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace pvs::test {

// A bake over a grid of `dims` cells of 1.5 m (every fifth grid position dropped unless every_position),
// `objects` objects and a
// PVS that is spatially coherent (object o is seen from cells near its own cell, plus noise), so that the
// code has both key rows and rows coded against them. octree: each kept root position becomes a node;
// every third splits into 8 leaves, the first of which is empty. view: a voxel mask of 0.5 m voxels
// with a hole in it (about one voxel in seven unset). Six occluder boxes (box 1 not proven) and a ranking:
// cell c has c % 4 ranked occluders, best first.
inline BakeData coherent_bake(uint32_t objects, glm::ivec3 dims, bool octree, bool view, uint32_t seed,
                              bool polygons = false, bool every_position = false) {
    BakeData b;
    b.tool_version = "pvsbake test";
    b.world_path = "worlds/hof_ü.glb";
    b.world_hash = "00ff";
    b.mode = seed % 2 ? "sampled" : "conservative";
    b.conservative = seed % 2 == 0;
    b.parameters = {{"cells.cell_size_m", "1.5"}, {"bake.mode", b.mode}, {"", "empty key"}};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (uint32_t o = 0; o < objects; ++o) {
        const glm::vec3 lo(u(rng) * 10.0f, u(rng) * 5.0f, u(rng) * 10.0f);
        b.objects.push_back({"obj_" + std::to_string(o) + (o % 3 ? "" : "_ü"), Aabb::of(lo, lo + 0.5f),
                             uint32_t(rng() % 900), o % 16});
    }
    CellSet& cells = b.cells;
    cells.kind = octree ? CellSet::Kind::kOctree : CellSet::Kind::kGrid;
    cells.origin = {-1.25f, 0.5f, 2.0f};
    cells.cell_size_m = 1.5f;
    cells.dims = dims;
    const size_t grid = size_t(dims.x) * size_t(dims.y) * size_t(dims.z);
    auto add_cell = [&](const Aabb& box, int32_t parent) {
        cells.cells.push_back(Cell{box, parent});
        return int32_t(cells.cells.size() - 1);
    };
    for (size_t g = 0; g < grid; ++g) {
        if (g % 5 == 1 && !every_position) {
            cells.grid_to_cell.push_back(-1);
            continue;
        }
        const glm::ivec3 i(int(g % size_t(dims.x)), int(g / size_t(dims.x) % size_t(dims.y)),
                           int(g / (size_t(dims.x) * size_t(dims.y))));
        const glm::vec3 lo = cells.origin + glm::vec3(float(i.x), float(i.y), float(i.z)) * cells.cell_size_m;
        const Aabb box = Aabb::of(
            lo, cells.origin + glm::vec3(float(i.x + 1), float(i.y + 1), float(i.z + 1)) * cells.cell_size_m);
        if (!octree) {
            cells.grid_to_cell.push_back(add_cell(box, -1));
            continue;
        }
        const int32_t node = int32_t(cells.nodes.size());
        cells.grid_to_cell.push_back(node);
        cells.nodes.push_back(OctreeNode{box, -1, -1, -1});
        if (g % 3 != 0) {
            cells.nodes[size_t(node)].cell = add_cell(box, -1);
            continue;
        }
        const int32_t first = int32_t(cells.nodes.size());
        cells.nodes[size_t(node)].first_child = first;
        const glm::vec3 c = box.center(), h = 0.5f * box.size();
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 lo8(k & 1 ? c.x : box.min.x, k & 2 ? c.y : box.min.y, k & 4 ? c.z : box.min.z);
            const Aabb child = Aabb::of(lo8, lo8 + h);
            cells.nodes.push_back(OctreeNode{child, -1, k == 0 ? -1 : add_cell(child, node), node});
        }
    }
    if (view) {
        cells.view.origin = cells.origin - 0.25f;
        cells.view.voxel_size_m = 0.5f;
        cells.view.dims = dims * 3 + 1;
        const uint64_t n = cells.view.count();
        cells.view.bits.assign(size_t((n + 63) / 64), 0);
        for (uint64_t v = 0; v < n; ++v)
            if (v % 7 != 3) cells.view.bits[v / 64] |= uint64_t(1) << (v % 64);
        cells.eyes = cells.view;  // the eye space: the view volume less a rim (here every fifth voxel)
        for (uint64_t v = 2; v < n; v += 5) cells.eyes.bits[v / 64] &= ~(uint64_t(1) << (v % 64));
    }
    const uint32_t n_cells = uint32_t(cells.size());
    b.pvs = PvsSet::make(n_cells, objects);
    for (uint32_t c = 0; c < n_cells; ++c) {
        const glm::vec3 at = cells.cells[c].bounds.center();
        for (uint32_t o = 0; o < objects; ++o) {
            const float d = glm::length(at - b.objects[o].bounds.min);
            if ((d < 6.0f && u(rng) > 0.05f) || u(rng) < 0.01f) b.pvs.set(c, o);
        }
    }
    for (uint32_t c = 3; c < n_cells; c += 4) {  // some rows repeat: stored once
        std::copy(b.pvs.row(c - 1), b.pvs.row(c - 1) + b.pvs.words_per_row, b.pvs.row(c));
    }
    for (uint32_t i = 0; i < 6; ++i) {
        const glm::vec3 lo(u(rng) * 10.0f, u(rng) * 5.0f, u(rng) * 10.0f);
        b.occluders.push_back(Occluder{Aabb::of(lo, lo + glm::vec3(1.0f, 2.0f, 0.5f)), 0.25f, i != 1, {}});
    }
    const uint32_t proven[5] = {0, 2, 3, 4, 5};
    b.ranked.offsets = {0};
    for (uint32_t c = 0; c < n_cells; ++c) {
        for (uint32_t k = 0; k < c % 4; ++k) {
            b.ranked.entries.push_back(RankedOccluder{proven[(c + k) % 5], 0.5f / float(k + 1),
                                                      0.25f * float(c % 7), float(std::min(objects, k)),
                                                      0.125f * float(k)});
        }
        b.ranked.offsets.push_back(uint32_t(b.ranked.entries.size()));
    }
    if (polygons) {  // two slanted quads, ranked first in every third cell (format 1.7)
        for (int i = 0; i < 2; ++i) {
            OccluderPolygon p;
            p.normal = glm::normalize(glm::vec3(0.0f, 0.6f, i == 0 ? 0.8f : -0.8f));
            const float z0 = i == 0 ? 6.0f : 3.0f, z1 = i == 0 ? 3.0f : 6.0f;
            p.corners = {{1.0f, 0.5f, z0}, {8.0f, 0.5f, z0}, {8.0f, 4.5f, z1}, {1.0f, 4.5f, z1}};
            if (glm::dot(glm::cross(p.corners[1] - p.corners[0], p.corners[2] - p.corners[1]), p.normal) <
                0.0f)
                std::reverse(p.corners.begin(), p.corners.end());
            p.offset = glm::dot(p.normal, p.corners[0]);
            p.thickness = 0.001f;
            for (const glm::vec3& c : p.corners) p.bounds.extend(c);
            b.polygons.push_back(p);
        }
        RankedOccluders mixed;
        mixed.offsets = {0};
        for (uint32_t c = 0; c < n_cells; ++c) {
            if (c % 3 == 0)
                mixed.entries.push_back(RankedOccluder{uint32_t(b.occluders.size()) + c % 2, 1.0f, 0, 0, 0});
            for (uint32_t k = b.ranked.offsets[c]; k < b.ranked.offsets[c + 1]; ++k)
                mixed.entries.push_back(b.ranked.entries[k]);
            mixed.offsets.push_back(uint32_t(mixed.entries.size()));
        }
        b.ranked = std::move(mixed);
    }
    b.figures = {{"cells", double(n_cells)}, {"objects", double(objects)}, {"", 0.5}, {"cells", 7.0}};
    b.run.timings_s = {{"solve", 1.25}};
    b.verification.ran = true;
    b.verification.figures = {{"rays", 4096.0}, {"misses", 0.0}};
    return b;
}

// More ranked boxes than a byte indexes, so that the runtime file gives each block of cells a palette
// (format 2.0): `boxes` proven boxes added, and every cell's ranking replaced by `per_cell` of them (at most
// 40) drawn from a window of 40 that its 4 x 4 x 4 block of grid positions picks, best first: neighbours
// rank mostly the same boxes. For bakes without polygons.
inline void rank_many_boxes(BakeData& b, uint32_t boxes, uint32_t per_cell, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const uint32_t first = uint32_t(b.occluders.size());
    for (uint32_t i = 0; i < boxes; ++i) {
        const glm::vec3 lo(u(rng) * 10.0f, u(rng) * 5.0f, u(rng) * 10.0f);
        b.occluders.push_back(Occluder{Aabb::of(lo, lo + glm::vec3(0.5f, 1.5f, 2.0f)), 0.25f, true, {}});
    }
    b.ranked = {};
    b.ranked.offsets = {0};
    for (uint32_t c = 0; c < uint32_t(b.cells.size()); ++c) {
        const glm::vec3 at = b.cells.cells[c].bounds.min - b.cells.origin;
        const glm::ivec3 block = glm::ivec3(glm::floor(at / (4.0f * b.cells.cell_size_m)));
        const uint32_t base = uint32_t(block.x * 73 + block.y * 151 + block.z * 233) % boxes;
        for (uint32_t k = 0; k < std::min(per_cell, 40u); ++k) {
            const uint32_t box = first + (base + (k * 7 + c % 3) % 40) % boxes;
            b.ranked.entries.push_back(
                RankedOccluder{box, 1.0f / float(k + 1), 0.01f * float(k), float(k % 3), 0.02f * float(k)});
        }
        b.ranked.offsets.push_back(uint32_t(b.ranked.entries.size()));
    }
}

// The loader's ranked occluders are the bake's, each with its box (C++ and C), and its polygons (format 1.7)
// at their places among them.
inline void expect_same_ranked(const pvsbake::Bake& got, const BakeData& want) {
    for (uint32_t c = 0; c <= got.cell_count(); ++c) {  // one past the end too: 0, empty
        std::vector<RankedOccluder> boxes;
        std::vector<std::pair<uint32_t, RankedOccluder>> polygons;  // (place, entry)
        for (uint32_t k = 0; k < want.ranked.count(c); ++k) {
            const RankedOccluder& e = want.ranked.entries[want.ranked.offsets[c] + k];
            if (e.box < want.occluders.size())
                boxes.push_back(e);
            else
                polygons.push_back({k, e});
        }
        const uint32_t n = uint32_t(boxes.size());
        ASSERT_EQ(got.occluder_count(c), n) << "cell " << c;
        const pvsbake::OccluderList list = got.occluders(c);
        ASSERT_EQ(list.size(), n);
        for (uint32_t k = 0; k < n; ++k) {
            const RankedOccluder& w = boxes[k];
            const Aabb& box = want.occluders[w.box].box;
            const pvsbake::RankedOccluder& g = list[k];
            EXPECT_EQ(glm::vec3(g.box.min[0], g.box.min[1], g.box.min[2]), box.min);
            EXPECT_EQ(glm::vec3(g.box.max[0], g.box.max[1], g.box.max[2]), box.max);
            EXPECT_EQ(g.score, w.score);
            EXPECT_EQ(g.solid_angle_sr, w.solid_angle_sr);
            EXPECT_EQ(g.hidden_objects, w.hidden_objects);
            EXPECT_EQ(g.hidden_triangle_share, w.hidden_triangle_share);
        }
        ASSERT_EQ(got.occluder_polygon_count(c), polygons.size()) << "cell " << c;
        for (uint32_t k = 0; k < polygons.size(); ++k) {
            pvsbake::RankedPolygon g;
            ASSERT_TRUE(got.occluder_polygon(c, k, g));
            const OccluderPolygon& w = want.polygons[polygons[k].second.box - want.occluders.size()];
            EXPECT_EQ(g.place, polygons[k].first);
            EXPECT_EQ(g.score, polygons[k].second.score);
            ASSERT_EQ(g.count, uint32_t(w.corners.size()));
            for (uint32_t i = 0; i < g.count; ++i)
                EXPECT_EQ(glm::vec3(g.corners[3 * i], g.corners[3 * i + 1], g.corners[3 * i + 2]),
                          w.corners[i]);
            EXPECT_EQ(g.plane[0], w.normal.x);
            EXPECT_EQ(g.plane[3], w.offset);
            EXPECT_EQ(g.plane[4], w.thickness);
        }
        pvsbake::RankedPolygon none;
        EXPECT_FALSE(got.occluder_polygon(c, uint32_t(polygons.size()), none));
    }
}

// Loads path, failing the test on a non-ok status.
inline void load_ok(pvsbake::Bake& bake, const std::string& path) {
    const pvsbake::LoadResult r = bake.load(path);
    ASSERT_TRUE(r) << r.message;
    EXPECT_TRUE(r.message.empty());
}

// Writes bake to path with write_bake_file, then loads it into `loaded`.
inline void write_and_load(const BakeData& bake, const std::string& path, pvsbake::Bake& loaded) {
    write_bake_file(path, bake);
    load_ok(loaded, path);
}

// The loader's view of a bake equals what was written: every field a runtime can query.
inline void expect_loaded_equals(const pvsbake::Bake& got, const BakeData& want) {
    EXPECT_EQ(got.format_major(), kBakeFormatMajor);
    EXPECT_EQ(got.tool_version(), want.tool_version);
    EXPECT_EQ(got.world_path(), want.world_path);
    EXPECT_EQ(got.world_hash(), want.world_hash);
    EXPECT_EQ(got.mode(), want.mode);
    EXPECT_EQ(got.is_conservative(), want.conservative);
    EXPECT_STREQ(got.mode_label(), want.conservative ? "conservative" : "aggressive");
    EXPECT_EQ(got.parameters(), want.parameters);
    ASSERT_EQ(got.figures().size(), want.figures.size());
    for (size_t i = 0; i < want.figures.size(); ++i) {
        EXPECT_EQ(got.figures()[i].first, want.figures[i].first);
        EXPECT_EQ(got.figures()[i].second, want.figures[i].second);
    }
    EXPECT_EQ(got.verification_ran(), want.verification.ran);
    EXPECT_EQ(got.verification_figures().size(), want.verification.figures.size());

    ASSERT_EQ(got.object_count(), want.objects.size());
    uint64_t triangles = 0;
    for (uint32_t o = 0; o < got.object_count(); ++o) {
        const ObjectRecord& w = want.objects[o];
        EXPECT_EQ(got.object_name(o), w.name);
        EXPECT_STREQ(got.object_name_c(o), w.name.c_str());
        const pvsbake::Box box = got.object_bounds(o);
        EXPECT_EQ(glm::vec3(box.min[0], box.min[1], box.min[2]), w.bounds.min) << o;
        EXPECT_EQ(glm::vec3(box.max[0], box.max[1], box.max[2]), w.bounds.max) << o;
        EXPECT_EQ(got.object_triangles(o), w.triangle_count);
        EXPECT_EQ(got.object_flags(o), w.flags);
        triangles += w.triangle_count;
    }
    EXPECT_EQ(got.total_triangles(), triangles);

    ASSERT_EQ(got.cell_count(), want.cells.size());
    EXPECT_EQ(int(got.cell_kind()), int(want.cells.kind));
    expect_same_ranked(got, want);
    std::vector<uint64_t> words(got.words_per_row() + 1, ~uint64_t(0));
    for (uint32_t c = 0; c < got.cell_count(); ++c) {
        const pvsbake::Box box = got.cell_bounds(c);
        EXPECT_EQ(glm::vec3(box.min[0], box.min[1], box.min[2]), want.cells.cells[c].bounds.min) << c;
        EXPECT_EQ(glm::vec3(box.max[0], box.max[1], box.max[2]), want.cells.cells[c].bounds.max) << c;
        std::vector<uint32_t> walked;
        got.for_each_visible(c, [&](uint32_t o) { walked.push_back(o); });
        std::vector<uint32_t> expected;
        for (uint32_t o = 0; o < want.pvs.object_count; ++o)
            if (want.pvs.test(c, o)) expected.push_back(o);
        ASSERT_EQ(walked, expected) << "cell " << c;
        EXPECT_EQ(got.visible_count(c), expected.size());
        ASSERT_EQ(got.fill_bitset(c, words.data(), words.size()), expected.size());
        for (uint32_t w = 0; w < want.pvs.words_per_row; ++w) EXPECT_EQ(words[w], want.pvs.row(c)[w]);
        EXPECT_EQ(words.back(), 0u);  // past the objects: zeroed
        for (uint32_t o = 0; o < want.pvs.object_count; ++o)
            ASSERT_EQ(got.is_visible(c, o), want.pvs.test(c, o));
    }
}

// find_cell agrees with CellSet::find: random points in and around the cells, points on cell faces and
// voxel faces, and non-finite points.
inline void expect_same_lookup(const pvsbake::Bake& got, const CellSet& cells, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.2f, 1.2f);
    Aabb all;
    for (const Cell& c : cells.cells) {
        all.extend(c.bounds.min);
        all.extend(c.bounds.max);
    }
    const int n = test::in_ci() ? 4000 : 40000;
    int found = 0, eyes = 0, rim = 0;
    for (int i = 0; i < n && !all.is_empty(); ++i) {
        glm::vec3 p = all.min + glm::vec3(u(rng), u(rng), u(rng)) * (all.max - all.min);
        if (i % 4 == 1)
            p = cells.origin + glm::round((p - cells.origin) / cells.cell_size_m) * cells.cell_size_m;
        if (i % 4 == 2 && !cells.view.empty()) {
            p = cells.view.origin +
                glm::round((p - cells.view.origin) / cells.view.voxel_size_m) * cells.view.voxel_size_m;
        }
        const int32_t want = cells.find(p);
        ASSERT_EQ(got.find_cell(p.x, p.y, p.z), want) << p.x << " " << p.y << " " << p.z;
        found += want >= 0;
        const bool eye = want >= 0 && (cells.eyes.empty() || cells.eyes.contains(p));
        ASSERT_EQ(got.in_eye_space(p.x, p.y, p.z), eye) << p.x << " " << p.y << " " << p.z;
        eyes += eye;
        rim += want >= 0 && !eye;
    }
    if (!cells.cells.empty()) {
        EXPECT_GT(found, n / 10);
        EXPECT_GT(eyes, n / 20);
    }
    if (!cells.eyes.empty() && !cells.cells.empty()) {
        EXPECT_GT(rim, 0);
    }
    const float nan = std::nanf(""), inf = INFINITY;
    EXPECT_EQ(got.find_cell(nan, 0, 0), -1);
    EXPECT_EQ(got.find_cell(0, inf, 0), -1);
    EXPECT_EQ(got.find_cell(0, 0, -inf), -1);
    EXPECT_EQ(got.find_cell(1e30f, 1e30f, 1e30f), -1);
}

}  // namespace pvs::test
