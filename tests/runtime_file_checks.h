// SPDX-License-Identifier: MIT
// Checks of the runtime file (io/runtime_file.h) against the HDF5 loader, for test_runtime_file and
// test_runtime_export: an exported bake answers every query of the C99 runtime (runtime/pvsr.h, through
// runtime/pvsr.hpp) as the HDF5 loader answers it on the bake file.
#pragma once

#include "io/bake_file.h"
#include "io/runtime_file.h"
#include "runtime/pvsr.h"
#include "runtime/pvsr.hpp"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>
#include <pvsbake/loader_c.h>
#include <pvsbake/occlusion.h>
#include <pvsbake/occlusion_c.h>

#include <gtest/gtest.h>
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace pvs::test {

// The file's bytes in 8-byte aligned memory, as a mapped file or a pak's buffer would be.
struct Bytes {
    std::vector<uint64_t> words;
    size_t size = 0;
    explicit Bytes(const std::string& s) : words((s.size() + 7) / 8), size(s.size()) {
        if (size) std::memcpy(words.data(), s.data(), size);
    }
    const void* data() const { return words.data(); }
    uint8_t* bytes() { return reinterpret_cast<uint8_t*>(words.data()); }
};

// Sets the checksum of a (changed) file right again.
inline void rechecksum(Bytes& b) {
    const uint64_t sum = XXH64(b.bytes() + PVSR_CHECKSUMMED_FROM, b.size - PVSR_CHECKSUMMED_FROM, 0);
    std::memcpy(b.bytes() + 24, &sum, 8);
}

inline std::string opened_message(const Bytes& b, pvsr_status* status) {
    pvsr_level level;
    char message[256];
    *status = pvsr_open(&level, b.data(), b.size, message, sizeof message);
    return message;
}

// What a game draws (the culled walk) from a random eye in each cell (every cell of small bakes), with all
// of the cell's ranked occluders and with the best 2: the C99 runtime (C and C++ calls) and the HDF5
// loader (C++ and C calls) give the same objects, and they are the cell's PVS less exactly the objects
// whose bounds the culler hides, objects flagged always visible kept. Adds how many were culled to culled.
// Whether the walks cull object o of the runtime level by `hidden` (a box test): its bounds, or every one of
// its parts (file 2.2); never an object flagged always visible. Counts in *by_parts those only its parts hid.
template <class Hidden>
bool culled_by_rule(const pvsr::Level& l, uint32_t o, Hidden&& hidden, uint64_t* by_parts = nullptr) {
    if (l.object_flags(o) & PVSR_OBJECT_ALWAYS_VISIBLE) return false;
    float box[6];
    l.object_bounds(o, box);
    if (hidden(box)) return true;
    const uint32_t n = l.object_part_count(o);
    for (uint32_t k = 0; k < n; ++k)
        if (!l.object_part(o, k, box) || !hidden(box)) return false;
    if (n > 0 && by_parts != nullptr) ++*by_parts;
    return n > 0;
}

inline void expect_same_drawn(const pvsr::Level& got, const pvsbake::Bake& want, const pvsbake_bake* c_bake,
                              uint32_t seed, uint64_t& culled, uint64_t* horizon_culled_out = nullptr,
                              uint64_t* part_culled_out = nullptr) {
    uint64_t part_culled = 0;
    std::mt19937 rng(seed ^ 0xd7a3u);
    pvsr::Horizon horizon(64, 1 << 14);
    pvsbake::Horizon want_horizon(64, 1 << 14);
    pvsbake_horizon* c_horizon = pvsbake_horizon_create(64, 1 << 14);
    EXPECT_TRUE(horizon.ok() && want_horizon.ok() && c_horizon != nullptr);
    uint64_t horizon_culled = 0;
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    pvsr::Culler culler(32);
    pvsbake::OcclusionCuller want_culler(32);
    EXPECT_TRUE(culler.ok());
    pvsbake_culler* c_culler = pvsbake_culler_create(32);
    EXPECT_NE(c_culler, nullptr);
    const uint32_t step = std::max(1u, want.cell_count() / 150);
    std::vector<uint32_t> list(want.object_count() + 1);
    for (uint32_t c = 0; c < want.cell_count(); c += step) {
        const pvsbake::Box cell = want.cell_bounds(c);
        float eye[3];
        for (int a = 0; a < 3; ++a) eye[a] = cell.min[a] + u(rng) * (cell.max[a] - cell.min[a]);
        for (const uint32_t max : {uint32_t(PVSR_CULLER_MAX_OCCLUDERS), 2u}) {
            SCOPED_TRACE("cell " + std::to_string(c) + ", up to " + std::to_string(max) + " occluders");
            const uint32_t given = culler.begin_cell(got, c, eye, max);
            EXPECT_LE(given, std::min(want.occluder_count(c) + want.occluder_polygon_count(c), max));
            EXPECT_EQ(want_culler.begin_cell(want, c, eye, max), given);
            std::vector<uint32_t> expected, walked, want_walked;
            want.for_each_visible(c, [&](uint32_t o) {
                if (!culled_by_rule(
                        got, o, [&](const float* b) { return culler.is_hidden(b); }, &part_culled))
                    expected.push_back(o);
            });
            culled += want.visible_count(c) - expected.size();
            const uint32_t n = got.for_each_drawn(c, culler, [&](uint32_t o) { walked.push_back(o); });
            ASSERT_EQ(walked, expected);
            EXPECT_EQ(n, expected.size());
            EXPECT_EQ(got.drawn_objects(c, culler, list.data(), list.size()), expected.size());
            EXPECT_TRUE(std::equal(expected.begin(), expected.end(), list.begin()));
            EXPECT_EQ(pvsr_visit_drawn(&got.c_level(), c, &culler.c_culler(), nullptr, nullptr),
                      expected.size());
            EXPECT_EQ(
                pvsbake::for_each_drawn(want, c, want_culler, [&](uint32_t o) { want_walked.push_back(o); }),
                expected.size());
            ASSERT_EQ(want_walked, expected);
            if (c_culler != nullptr && c_bake != nullptr) {
                EXPECT_EQ(pvsbake_culler_begin_cell(c_culler, c_bake, c, eye, max), given);
                EXPECT_EQ(pvsbake_drawn_objects(c_bake, c, c_culler, list.data(), list.size()),
                          expected.size());
                EXPECT_TRUE(std::equal(expected.begin(), expected.end(), list.begin()));
                EXPECT_EQ(pvsbake_visit_drawn(c_bake, c, c_culler, nullptr, nullptr), expected.size());
                EXPECT_EQ(pvsbake_visit_drawn(c_bake, c, nullptr, nullptr, nullptr), want.visible_count(c));
            }
        }
        // No culler: the whole PVS.
        EXPECT_EQ(pvsr_visit_drawn(&got.c_level(), c, nullptr, nullptr, nullptr), want.visible_count(c));
        // The horizon of the cell's list (file 2.1, bake file 1.8), after the culler of all the cell's ranked
        // occluders and alone: the runtime's and the loader's (C++ and C) draw the same objects, the PVS less
        // exactly those whose bounds the culler or the horizon hides; where the bake kept the cell's tests
        // (file 5.3, bake file 1.10), the horizon tests those alone.
        if (horizon.ok() && want_horizon.ok()) {
            SCOPED_TRACE("cell " + std::to_string(c) + ", the horizon");
            EXPECT_EQ(got.horizon_list_count(c), want.horizon_list_count(c));
            const uint32_t given = horizon.begin_cell(got, c, eye);
            EXPECT_EQ(want_horizon.begin_cell(want, c, eye), given);
            if (c_horizon != nullptr && c_bake != nullptr) {
                EXPECT_EQ(pvsbake_horizon_begin_cell(c_horizon, c_bake, c, eye), given);
                EXPECT_EQ(pvsbake_horizon_list_count(c_bake, c), given);
            }
            culler.begin_cell(got, c, eye);
            want_culler.begin_cell(want, c, eye);
            if (c_culler != nullptr && c_bake != nullptr)
                pvsbake_culler_begin_cell(c_culler, c_bake, c, eye, 64);
            const uint32_t *tests = nullptr, *tests_end = nullptr;
            const bool testing = want.horizon_tests(c, tests, tests_end);
            for (const bool with_culler : {true, false}) {
                std::vector<uint32_t> expected, walked, want_walked;
                want.for_each_visible(c, [&](uint32_t o) {
                    const bool tested = !testing || std::binary_search(tests, tests_end, o);
                    const auto hidden = [&](const float* b) {
                        return (with_culler && culler.is_hidden(b)) || (tested && horizon.is_hidden(b));
                    };
                    if (!culled_by_rule(got, o, hidden, &part_culled)) expected.push_back(o);
                });
                horizon_culled += with_culler ? 0 : want.visible_count(c) - expected.size();
                got.for_each_drawn(c, with_culler ? &culler : nullptr, horizon,
                                   [&](uint32_t o) { walked.push_back(o); });
                ASSERT_EQ(walked, expected);
                pvsbake::for_each_drawn(want, c, with_culler ? &want_culler : nullptr, want_horizon,
                                        [&](uint32_t o) { want_walked.push_back(o); });
                ASSERT_EQ(want_walked, expected);
                if (c_horizon != nullptr && c_bake != nullptr && c_culler != nullptr) {
                    const pvsbake_culler* cc = with_culler ? c_culler : nullptr;
                    EXPECT_EQ(
                        pvsbake_drawn_objects_horizon(c_bake, c, cc, c_horizon, list.data(), list.size()),
                        expected.size());
                    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), list.begin()));
                    EXPECT_EQ(pvsbake_visit_drawn_horizon(c_bake, c, cc, c_horizon, nullptr, nullptr),
                              expected.size());
                }
                EXPECT_EQ(
                    pvsr_drawn_objects_horizon(&got.c_level(), c, with_culler ? &culler.c_culler() : nullptr,
                                               &horizon.c_horizon(), list.data(), list.size()),
                    expected.size());
                EXPECT_TRUE(std::equal(expected.begin(), expected.end(), list.begin()));
            }
        }
    }
    if (horizon_culled_out != nullptr) *horizon_culled_out += horizon_culled;
    if (part_culled_out != nullptr) *part_culled_out += part_culled;
    pvsbake_horizon_free(c_horizon);
    // Out of range, or no bake: nothing.
    EXPECT_EQ(got.for_each_drawn(want.cell_count(), culler, [](uint32_t) {}), 0u);
    if (c_culler != nullptr) {
        const float eye[3] = {0, 0, 0};
        EXPECT_EQ(pvsbake_culler_begin_cell(c_culler, nullptr, 0, eye, 8), 0u);
        EXPECT_EQ(pvsbake_drawn_objects(nullptr, 0, c_culler, nullptr, 0), 0u);
    }
    pvsbake_culler_free(c_culler);
}

// Every query of the runtime equals the HDF5 loader's on the same bake.
inline void expect_same_as_loader(const pvsr::Level& got, const pvsbake::Bake& want, uint32_t seed) {
    ASSERT_EQ(got.cell_count(), want.cell_count());
    ASSERT_EQ(got.object_count(), want.object_count());
    EXPECT_EQ(got.cell_kind(), uint32_t(want.cell_kind()));
    EXPECT_EQ(got.words_per_row(), want.words_per_row());
    EXPECT_EQ(got.is_conservative(), want.is_conservative());
    EXPECT_STREQ(got.mode_label(), want.mode_label());
    EXPECT_EQ(got.string("tool_version"), want.tool_version());
    EXPECT_EQ(got.string("world_path"), want.world_path());
    EXPECT_EQ(got.string("world_hash"), want.world_hash());
    EXPECT_EQ(got.string("mode"), want.mode());
    EXPECT_EQ(got.string("no such key"), "");
    EXPECT_EQ(got.total_triangles(), want.total_triangles());
    for (uint32_t o = 0; o <= want.object_count(); ++o) {  // one past the end too
        EXPECT_EQ(got.object_name(o), want.object_name(o));
        EXPECT_EQ(got.object_triangles(o), want.object_triangles(o));
        EXPECT_EQ(got.object_flags(o), want.object_flags(o));
        float box[6] = {7, 7, 7, 7, 7, 7};
        const bool in = got.object_bounds(o, box);
        EXPECT_EQ(in, o < want.object_count());
        if (in) {
            const pvsbake::Box w = want.object_bounds(o);
            for (int a = 0; a < 3; ++a) {
                EXPECT_EQ(box[a], w.min[a]);
                EXPECT_EQ(box[3 + a], w.max[a]);
            }
        }
    }
    std::vector<uint64_t> got_words(want.words_per_row() + 1), want_words(want.words_per_row() + 1);
    std::vector<uint32_t> list(want.object_count() + 1);
    for (uint32_t c = 0; c <= want.cell_count(); ++c) {  // one past the end: nothing
        SCOPED_TRACE("cell " + std::to_string(c));
        std::vector<uint32_t> walked, expected;
        const uint32_t n = got.for_each_visible(c, [&](uint32_t o) { walked.push_back(o); });
        if (c < want.cell_count()) want.for_each_visible(c, [&](uint32_t o) { expected.push_back(o); });
        ASSERT_EQ(walked, expected);
        EXPECT_EQ(n, expected.size());
        EXPECT_EQ(got.visible_count(c), expected.size());
        EXPECT_EQ(got.visible_objects(c, list.data(), list.size()), expected.size());
        EXPECT_TRUE(std::equal(expected.begin(), expected.end(), list.begin()));
        if (expected.size() > 1) {  // a short buffer: the count, the first ones
            EXPECT_EQ(got.visible_objects(c, list.data(), 1), expected.size());
            EXPECT_EQ(list[0], expected[0]);
        }
        EXPECT_EQ(got.fill_bitset(c, got_words.data(), got_words.size()),
                  want.fill_bitset(c, want_words.data(), want_words.size()));
        if (c < want.cell_count()) {
            EXPECT_EQ(got_words, want_words);
        }
        if (want.words_per_row() > 0) {
            EXPECT_EQ(got.fill_bitset(c, got_words.data(), want.words_per_row() - 1), UINT32_MAX);
        }
        const uint32_t step = want.object_count() > 1000 ? 37 : 1;  // every object of small bakes
        for (uint32_t o = 0; o <= want.object_count(); o += step)
            ASSERT_EQ(got.is_visible(c, o), want.is_visible(c, o)) << o;
        for (const uint32_t o : expected) ASSERT_TRUE(got.is_visible(c, o)) << o;
        float box[6] = {7, 7, 7, 7, 7, 7};
        EXPECT_EQ(got.cell_bounds(c, box), c < want.cell_count());
        if (c < want.cell_count()) {
            const pvsbake::Box w = want.cell_bounds(c);
            for (int a = 0; a < 3; ++a) {
                EXPECT_EQ(box[a], w.min[a]);
                EXPECT_EQ(box[3 + a], w.max[a]);
            }
        }
        ASSERT_EQ(got.occluder_count(c), want.occluder_count(c));
        std::vector<float> boxes(6 * size_t(want.occluder_count(c)) + 6);
        EXPECT_EQ(got.occluder_boxes(c, boxes.data(), want.occluder_count(c) + 1), want.occluder_count(c));
        for (uint32_t k = 0; k < want.occluder_count(c); ++k) {
            pvsr_ranked_occluder g;
            ASSERT_TRUE(got.occluder(c, k, g));
            const pvsbake::RankedOccluder w = want.occluders(c)[k];
            for (int a = 0; a < 3; ++a) {
                EXPECT_EQ(g.box[a], w.box.min[a]);
                EXPECT_EQ(g.box[3 + a], w.box.max[a]);
                EXPECT_EQ(boxes[6 * k + size_t(a)], w.box.min[a]);
            }
            if (pvsr_has_occluder_measures(&got.c_level())) {
                EXPECT_EQ(g.score, w.score);
                EXPECT_EQ(g.solid_angle_sr, w.solid_angle_sr);
                EXPECT_EQ(g.hidden_objects, w.hidden_objects);
                EXPECT_EQ(g.hidden_triangle_share, w.hidden_triangle_share);
            } else {
                EXPECT_TRUE(std::isnan(g.score) && std::isnan(g.solid_angle_sr) && std::isnan(g.hidden_objects) &&
                            std::isnan(g.hidden_triangle_share));
            }
        }
        pvsr_ranked_occluder none;
        EXPECT_FALSE(got.occluder(c, want.occluder_count(c), none));
        ASSERT_EQ(got.occluder_polygon_count(c), want.occluder_polygon_count(c));
        for (uint32_t k = 0; k <= want.occluder_polygon_count(c); ++k) {
            float plane[5], corners[3 * PVSR_POLYGON_MAX_CORNERS];
            uint32_t place = 0;
            const uint32_t n = got.occluder_polygon(c, k, plane, corners, PVSR_POLYGON_MAX_CORNERS, &place);
            pvsbake::RankedPolygon w;
            if (!want.occluder_polygon(c, k, w)) {
                EXPECT_EQ(n, 0u);
                continue;
            }
            ASSERT_EQ(n, w.count);
            EXPECT_EQ(place, w.place);
            EXPECT_TRUE(std::equal(plane, plane + 5, w.plane));
            EXPECT_TRUE(std::equal(corners, corners + 3 * n, w.corners));
        }
    }
    // Lookups at random points in and around the cells, on cell and voxel faces, and not finite.
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t c = 0; c < want.cell_count(); ++c) {
        const pvsbake::Box b = want.cell_bounds(c);
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], b.min[a]);
            hi[a] = std::max(hi[a], b.max[a]);
        }
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.2f, 1.2f);
    const int points = in_ci() ? 4000 : 40000;
    int found = 0;
    for (int i = 0; i < points && want.cell_count() > 0; ++i) {
        float p[3];
        for (int a = 0; a < 3; ++a) {
            p[a] = lo[a] + u(rng) * (hi[a] - lo[a]);
            if (i % 3 == 1) p[a] = lo[a] + std::round((p[a] - lo[a]) * 8.0f) / 8.0f;  // on many faces
        }
        ASSERT_EQ(got.find_cell(p[0], p[1], p[2]), want.find_cell(p[0], p[1], p[2])) << p[0] << " " << p[1] << " " << p[2];
        ASSERT_EQ(got.in_eye_space(p[0], p[1], p[2]), want.in_eye_space(p[0], p[1], p[2]));
        found += want.find_cell(p[0], p[1], p[2]) >= 0;
    }
    if (want.cell_count() > 0) {
        EXPECT_GT(found, 0);
    }
    EXPECT_EQ(got.find_cell(std::nanf(""), 0, 0), -1);
    EXPECT_EQ(got.find_cell(0, INFINITY, 0), -1);
    EXPECT_EQ(got.find_cell(1e30f, -1e30f, 1e30f), -1);
}

// Writes the bake as HDF5, exports it (without the ranked occluders' measures and every row whole, with them
// and chains of 2 rows, and with the defaults), and checks the runtime against the HDF5 loader.
// Adds to *culled (when given) the objects the drawn walks culled (expect_same_drawn).
inline void round_trip(const BakeData& bake, uint32_t seed, uint64_t* culled = nullptr,
                       uint64_t* horizon_culled = nullptr, uint64_t* part_culled = nullptr) {
    uint64_t culled_here = 0, horizon_culled_here = 0, part_culled_here = 0;
    TempDir dir;
    const std::string h5 = dir.file("bake.h5");
    pvsbake::Bake loaded;
    write_and_load(bake, h5, loaded);
    pvsbake_bake* c_bake = nullptr;
    char message[256];
    EXPECT_EQ(pvsbake_load(h5.c_str(), &c_bake, message, sizeof message), PVSBAKE_OK) << message;
    for (const int variant : {0, 1, 2}) {
        const bool measures = variant == 1;
        SCOPED_TRACE(variant == 0 ? "rows whole" : variant == 1 ? "measures, chains of 2" : "defaults");
        RuntimeFileOptions options;
        options.occluder_measures = measures;
        if (variant < 2) options.max_chain = variant == 0 ? 1 : 2;
        RuntimeFileFigures figures;
        const Bytes bytes(runtime_file_bytes(h5, options, &figures));
        EXPECT_EQ(figures.file_bytes, bytes.size);
        EXPECT_EQ(bytes.size % PVSR_ALIGN, 0u);
        pvsr::Level level;
        std::string why = "not set";
        ASSERT_EQ(level.open(bytes.data(), bytes.size, &why), PVSR_OK) << why;
        EXPECT_EQ(why, "");
        EXPECT_EQ(pvsr_has_occluder_measures(&level.c_level()) != 0, measures && !bake.ranked.offsets.empty());
        expect_same_as_loader(level, loaded, seed);
        expect_same_drawn(level, loaded, c_bake, seed, culled_here, &horizon_culled_here, &part_culled_here);
        // The objects' part boxes (file 2.2, bake file 1.9): as the bake holds them, in both.
        for (uint32_t o = 0; o < loaded.object_count(); ++o) {
            const uint32_t n = bake.object_parts.count(o);
            ASSERT_EQ(level.object_part_count(o), n) << "object " << o;
            ASSERT_EQ(loaded.object_part_count(o), n) << "object " << o;
            for (uint32_t k = 0; k < n; ++k) {
                float box[6];
                ASSERT_TRUE(level.object_part(o, k, box));
                const Aabb& p = bake.object_parts.boxes[bake.object_parts.offsets[o] + k];
                const pvsbake::Box lb = loaded.object_part(o, k);
                for (int a = 0; a < 3; ++a) {
                    EXPECT_EQ(box[a], p.min[a]);
                    EXPECT_EQ(box[3 + a], p.max[a]);
                    EXPECT_EQ(lb.min[a], p.min[a]);
                    EXPECT_EQ(lb.max[a], p.max[a]);
                }
            }
            float box[6];
            EXPECT_FALSE(level.object_part(o, n, box));
            EXPECT_EQ(pvsbake_object_part_count(c_bake, o), n);
            EXPECT_EQ(pvsbake_object_part(c_bake, o, n, box), 0);
        }
        // The horizon lists (file 2.1): each cell's list holds the occluders of the bake's list of its cell
        // (the bake's blocks are the file's, and every occluder some list names is kept), ascending.
        EXPECT_EQ(pvsr_horizon_occluder_count(&level.c_level()) > 0, !bake.horizon.empty());
        for (uint32_t c = 0; c < bake.cells.size() && !bake.horizon.empty(); ++c) {
            const uint32_t l = bake.horizon.cell_list[c];
            ASSERT_EQ(level.horizon_list_count(c), bake.horizon.offsets[l + 1] - bake.horizon.offsets[l])
                << "cell " << c;
        }
        EXPECT_EQ(level.horizon_list_count(uint32_t(bake.cells.size())), 0u);
        EXPECT_EQ(loaded.horizon_list_count(uint32_t(bake.cells.size())), 0u);  // out of range: none
        EXPECT_EQ(loaded.horizon_list_count(UINT32_MAX), 0u);
    }
    pvsbake_free(c_bake);
    if (culled != nullptr) *culled += culled_here;
    if (horizon_culled != nullptr) *horizon_culled += horizon_culled_here;
    if (part_culled != nullptr) *part_culled += part_culled_here;
}

}  // namespace pvs::test
