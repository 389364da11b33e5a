// SPDX-License-Identifier: MIT
// Tests the runtime file (io/runtime_file.h) and the C99 runtime that reads it (runtime/pvsr.h): an exported
// bake answers every query as the HDF5 loader does on the same bake (every cell, every object, random points
// for the lookups; grids and octrees, with and without masks, object counts around the word edges and past
// the stack bit set); damaged files are refused with a named reason, and hostile ones (any byte changed and
// the checksum made right again) are refused or stay in range; the runtime's XXH64 equals libxxhash's.
// Links the loader, io and core only, so that scripts/test.sh runs it under the sanitizers too
// (test_runtime_export has the tests that bake or run the pvsbake command).
#include "core/error.h"
#include "tests/random_polygons.h"
#include "tests/runtime_file_checks.h"

#include <pvsbake/occlusion.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>

namespace pvs {
namespace {

using test::Bytes;
using test::opened_message;
using test::rechecksum;
using test::round_trip;

TEST(RuntimeFile, GridsAndOctreesAnswerAsTheHdf5Loader) {
    for (const bool octree : {false, true})
        for (const bool view : {false, true}) {
            SCOPED_TRACE(std::string(octree ? "octree" : "grid") + (view ? " with masks" : ""));
            round_trip(test::coherent_bake(133, {7, 3, 6}, octree, view, 3 + uint32_t(octree), view), 11);
        }
}

// The runtime file of a bake, written through a bake file.
std::string exported(const BakeData& bake) {
    test::TempDir dir;
    const std::string h5 = dir.file("x.h5");
    write_bake_file(h5, bake);
    return runtime_file_bytes(h5);
}

// Horizon lists (bake file 1.8, runtime file 2.1), per block and per cell (5.2: each cell's positions in
// its block's list), with and without the cells' tests (5.3, bake file 1.10): the C99 runtime's and the
// HDF5 loader's horizons are built from the same lists and draw the same objects (round_trip: the PVS less
// what they hide of the cell's tests, the rest untested), and a cell out of range has no list in either.
TEST(RuntimeFile, HorizonListsAnswerAsTheHdf5Loader) {
    for (const int kind : {0, 1, 2})  // per block, per cell, per cell with tests
        for (const bool octree : {false, true}) {
            const bool per_cell = kind > 0, tests = kind == 2;
            SCOPED_TRACE(std::string(octree ? "octree" : "grid") + (per_cell ? ", per cell" : "") +
                         (tests ? ", tests" : ""));
            BakeData bake = test::coherent_bake(133, {7, 3, 6}, octree, true, 5, true);
            test::add_horizon_lists(bake, per_cell, tests);
            uint64_t horizon_culled = 0;
            round_trip(bake, 7, nullptr, &horizon_culled);
            Bytes b(exported(bake));
            pvsr_level l;
            ASSERT_EQ(pvsr_open(&l, b.data(), b.size, nullptr, 0), PVSR_OK);
            EXPECT_EQ(l.horizon_cell_offsets.at != nullptr, per_cell);
            EXPECT_EQ(l.horizon_test_offsets.at != nullptr, tests);
            for (uint32_t c = 0; c < pvsr_cell_count(&l); ++c) {
                const uint32_t list = bake.horizon.cell_list[c];
                EXPECT_EQ(pvsr_horizon_list_count(&l, c),
                          bake.horizon.offsets[list + 1] - bake.horizon.offsets[list])
                    << c;
            }
        }
}

// The reason a copy of `file` is refused with, its n bytes at `at` set to `value` and its checksum made
// right.
std::string damaged_message(const std::string& file, size_t at, const void* value, size_t n) {
    Bytes b(file);
    std::memcpy(b.bytes() + at, value, n);
    rechecksum(b);
    pvsr_status s;
    return opened_message(b, &s);
}

// The cells' lists' sections (5.2): damaged offsets or codes are refused with their reason.
TEST(RuntimeFile, HorizonListsPerCellRefuseDamage) {
    BakeData bake = test::coherent_bake(70, {4, 2, 3}, false, true, 8);
    test::add_horizon_lists(bake, true);
    const std::string file = exported(bake);
    Bytes good(file);
    pvsr_level l;
    ASSERT_EQ(pvsr_open(&l, good.data(), good.size, nullptr, 0), PVSR_OK);
    const size_t offsets = size_t(l.horizon_cell_offsets.at - static_cast<const uint8_t*>(good.data())),
                 codes = size_t(l.horizon_cell_lists.at - static_cast<const uint8_t*>(good.data()));
    const auto damaged = [&](size_t at, const void* value, size_t n) {
        return damaged_message(file, at, value, n);
    };
    const uint32_t one = 1, past = uint32_t(l.horizon_cell_lists.count + 1);
    const uint8_t bad_head = 0xff;
    EXPECT_NE(damaged(offsets, &one, 4).find("the cells' horizon lists do not start at 0"),
              std::string::npos);
    EXPECT_NE(damaged(offsets + 4, &past, 4).find("offsets decrease or pass their bytes"), std::string::npos);
    EXPECT_NE(damaged(codes, &bad_head, 1).find("a cell's horizon list's"), std::string::npos);
    EXPECT_NE(damaged(file.find("HCOF"), "XCOF", 4).find("the cells' horizon lists without their offsets"),
              std::string::npos);
    EXPECT_NE(damaged(file.find("HLOF"), "XLOF", 4).find("the cells' horizon lists without the horizon's"),
              std::string::npos);
}

// The cells' tests (5.3): a walk gives the horizon only a cell's tests (an object the horizon hides is drawn
// where the cell does not test it); damaged offsets or codes are refused with their reason; a file without
// the horizon's lists has none.
TEST(RuntimeFile, CellsTestsLeaveTheRestUntestedAndRefuseDamage) {
    BakeData bake = test::coherent_bake(70, {4, 2, 3}, false, true, 8);
    test::add_horizon_lists(bake, true, true);
    const std::string file = exported(bake);
    BakeData all = bake;  // the same lists, every object tested
    all.horizon.test_offsets.clear();
    all.horizon.tests.clear();
    const std::string file_all = exported(all);
    Bytes good(file), good_all(file_all);
    pvsr_level l, l_all;
    ASSERT_EQ(pvsr_open(&l, good.data(), good.size, nullptr, 0), PVSR_OK);
    ASSERT_EQ(pvsr_open(&l_all, good_all.data(), good_all.size, nullptr, 0), PVSR_OK);
    EXPECT_EQ(l_all.horizon_test_offsets.at, nullptr);
    std::vector<uint64_t> memory(pvsr_horizon_memory_bytes(64, 1 << 14) / 8 + 1);
    pvsr_horizon h;
    ASSERT_TRUE(pvsr_horizon_init(&h, 64, 1 << 14, memory.data(), memory.size() * 8));
    std::mt19937 rng(5);
    uint64_t untested_hidden = 0;
    for (uint32_t c = 0; c < bake.cells.size(); ++c) {
        float box[6];
        ASSERT_TRUE(pvsr_cell_bounds(&l, c, box));
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const float eye[3] = {box[0] + u(rng) * (box[3] - box[0]), box[1] + u(rng) * (box[4] - box[1]),
                              box[2] + u(rng) * (box[5] - box[2])};
        std::vector<uint32_t> with(256), without(256), pvs(256);
        pvsr_horizon_begin_cell(&h, &l, c, eye);
        with.resize(pvsr_drawn_objects_horizon(&l, c, nullptr, &h, with.data(), with.size()));
        without.resize(pvsr_drawn_objects_horizon(&l_all, c, nullptr, &h, without.data(), without.size()));
        pvs.resize(pvsr_visible_objects(&l, c, pvs.data(), pvs.size()));
        const uint32_t *t0 = bake.horizon.tests.data() + bake.horizon.test_offsets[c],
                       *t1 = bake.horizon.tests.data() + bake.horizon.test_offsets[c + 1];
        std::vector<uint32_t> expected;
        for (const uint32_t o : pvs)
            if (!std::binary_search(t0, t1, o) || std::binary_search(without.begin(), without.end(), o))
                expected.push_back(o);
        EXPECT_EQ(with, expected) << "cell " << c;
        for (const uint32_t o : pvs)
            untested_hidden +=
                !std::binary_search(t0, t1, o) && !std::binary_search(without.begin(), without.end(), o);
    }
    EXPECT_GT(untested_hidden, 0u);  // the scene has objects the horizon hides that a cell does not test

    const size_t offsets = size_t(l.horizon_test_offsets.at - static_cast<const uint8_t*>(good.data())),
                 codes = size_t(l.horizon_tests.at - static_cast<const uint8_t*>(good.data()));
    const auto damaged = [&](size_t at, const void* value, size_t n) {
        return damaged_message(file, at, value, n);
    };
    const uint32_t one = 1, past = uint32_t(l.horizon_tests.count + 1);
    const uint8_t bad_head = 0xff;
    EXPECT_NE(damaged(offsets, &one, 4).find("the cells' tests do not start at 0"), std::string::npos);
    EXPECT_NE(damaged(offsets + 4, &past, 4).find("the cells' tests' offsets decrease or pass their bytes"),
              std::string::npos);
    EXPECT_NE(damaged(codes, &bad_head, 1).find("a cell's tests'"), std::string::npos);
    EXPECT_NE(damaged(file.find("HTOF"), "XTOF", 4).find("the cells' tests without their offsets"),
              std::string::npos);
    EXPECT_NE(damaged(file.find("HLOF"), "XLOF", 4).find("the cells' horizon lists without the horizon's"),
              std::string::npos);
}

// Object parts (bake file 1.9, runtime file 2.2): the runtime and the loader hold the same part boxes, and
// their walks (culler, horizon, both) cull an object whose bounds are not hidden when every part is, alike.
TEST(RuntimeFile, ObjectPartsAnswerAsTheHdf5Loader) {
    uint64_t part_culled = 0;
    for (const bool octree : {false, true}) {
        SCOPED_TRACE(octree ? "octree" : "grid");
        BakeData bake = test::coherent_bake(133, {7, 3, 6}, octree, true, 5, true);
        test::add_horizon_lists(bake);
        test::add_object_parts(bake);
        round_trip(bake, 9, nullptr, nullptr, &part_culled);
    }
    EXPECT_GT(part_culled, 0u);  // some object culled by its parts alone
}

// The file's bytes with its version set to 1.1 and the checksum made right again.
Bytes labelled_1_1(Bytes bytes) {
    const uint16_t old_version[2] = {1, 1};
    std::memcpy(bytes.bytes() + 8, old_version, sizeof old_version);
    rechecksum(bytes);
    return bytes;
}

// 2.0: a grid whose position g is cell g is stored without GRID, CGRD and CROW (each cell has its own row,
// in block order), and answers as before; an octree over every position keeps its root grid. The same file
// labelled 1.1 is refused (1.x requires GRID), and a 1.1-shaped file (with GRID) still opens.
TEST(RuntimeFile, AGridOfEveryPositionIsStoredWithoutItsPositions) {
    for (const bool octree : {false, true})
        for (const bool view : {false, true}) {
            SCOPED_TRACE(std::string(octree ? "octree" : "grid") + (view ? " with masks" : ""));
            const BakeData bake =
                test::coherent_bake(97, {5, 3, 4}, octree, view, 21, view, /*every_position=*/true);
            round_trip(bake, 13);
            test::TempDir dir;
            const std::string h5 = dir.file("full.h5");
            write_bake_file(h5, bake);
            Bytes bytes(runtime_file_bytes(h5));
            pvsr_level level;
            char message[256];
            ASSERT_EQ(pvsr_open(&level, bytes.data(), bytes.size, message, sizeof message), PVSR_OK)
                << message;
            EXPECT_EQ(level.grid_identity, octree ? 0u : 1u);
            EXPECT_EQ(level.grid_to_cell.at == nullptr, !octree);
            EXPECT_EQ(level.cell_grid.at, nullptr);
            EXPECT_EQ(level.cell_row.at == nullptr, !octree);  // every cell its own row, in block order
            if (octree) continue;
            for (uint32_t c = 0; c < level.cell_count; ++c) {
                float box[6];
                ASSERT_EQ(pvsr_cell_bounds(&level, c, box), 1);
                if (!view) {  // (the mask has holes)
                    EXPECT_EQ(pvsr_find_cell(&level, 0.5f * (box[0] + box[3]), 0.5f * (box[1] + box[4]),
                                             0.5f * (box[2] + box[5])),
                              int32_t(c));
                }
            }
            pvsr_status status;
            EXPECT_EQ(opened_message(labelled_1_1(bytes), &status), "a required section is missing");
            EXPECT_EQ(status, PVSR_CORRUPT);
        }
    test::TempDir dir;
    const std::string h5 = dir.file("octree.h5");  // an octree keeps its root grid (GRID) and cell boxes
    write_bake_file(h5, test::coherent_bake(50, {4, 2, 3}, true, true, 4));
    pvsr_status status;
    EXPECT_EQ(opened_message(labelled_1_1(Bytes(runtime_file_bytes(h5))), &status), "");
    EXPECT_EQ(status, PVSR_OK);
}

// 4.0: a PVS code past 64 KiB keeps 16-bit row offsets after the offset of every 64th row ('ROFB'), and the
// ranked entries each cell's count in a byte after the first entry of every 64th cell ('RCNT', 'RCNB'): the
// same answers as the HDF5 loader; a base moved is refused by the rows' checks, a count changed by the sum.
TEST(RuntimeFile, BigFilesKeepSixteenBitRowOffsetsAndEntryCounts) {
    const BakeData bake = test::coherent_bake(600, {40, 8, 40}, false, true, 8);
    round_trip(bake, 23);
    test::TempDir dir;
    const std::string h5 = dir.file("big.h5");
    write_bake_file(h5, bake);
    RuntimeFileOptions options;
    options.max_chain = 1;  // every row whole: the most code
    const Bytes good(runtime_file_bytes(h5, options));
    pvsr_level l;
    char message[256];
    ASSERT_EQ(pvsr_open(&l, good.data(), good.size, message, sizeof message), PVSR_OK) << message;
    ASSERT_GT(l.code_bytes, 65535u);
    ASSERT_NE(l.row_offset_bases.at, nullptr);
    EXPECT_EQ(l.row_offsets.item_bytes, 2u);
    EXPECT_EQ(l.row_offset_bases.count, (uint64_t(l.row_count) + 1 + 63) / 64);
    ASSERT_NE(l.ranked_counts.at, nullptr);
    EXPECT_EQ(l.ranked_offsets.at, nullptr);
    const auto at = [&](const uint8_t* p) { return size_t(p - static_cast<const uint8_t*>(good.data())); };
    pvsr_status status;
    {
        Bytes b(good);
        uint32_t base;
        std::memcpy(&base, l.row_offset_bases.at + 4, 4);
        base += 3;
        std::memcpy(b.bytes() + at(l.row_offset_bases.at) + 4, &base, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &status).find("PVS row"), std::string::npos);
    }
    {
        Bytes b(good);
        b.bytes()[at(l.ranked_counts.at) + 5] ^= 1;
        rechecksum(b);
        EXPECT_NE(opened_message(b, &status).find("ranked entry"), std::string::npos);
    }
}

// 2.0: with more ranked boxes than a byte indexes, each block of cells (4 x 4 x 4 grid positions, or 64
// cells of an octree) gets a palette of the boxes its cells rank, and the entries index it in a byte: the
// same answers as the HDF5 loader on grids with and without positions and on octrees. A damaged palette is
// refused; an entry past its own block's palette but inside the largest (a file made to pass the checksum)
// opens and reads as an empty box.
TEST(RuntimeFile, BlocksOfCellsShareAPaletteOfRankedBoxes) {
    for (int kind = 0; kind < 3; ++kind) {
        SCOPED_TRACE(kind == 0 ? "grid" : kind == 1 ? "grid of every position" : "octree");
        BakeData bake = test::coherent_bake(80, {13, 3, 13}, kind == 2, true, 31, false, kind == 1);
        test::rank_many_boxes(bake, 600, 12, 5);
        round_trip(bake, 17);
        test::TempDir dir;
        const std::string h5 = dir.file("palette.h5");
        write_bake_file(h5, bake);
        const Bytes good(runtime_file_bytes(h5));
        pvsr_level l;
        char message[256];
        ASSERT_EQ(pvsr_open(&l, good.data(), good.size, message, sizeof message), PVSR_OK) << message;
        ASSERT_NE(l.palette.at, nullptr);
        EXPECT_EQ(l.ranked_boxes.item_bytes, 1u);
        EXPECT_EQ(l.occupancy.at != nullptr, kind == 0);  // a grid with empty positions: an occupancy mask
        if (kind != 0) continue;
        const auto offset = [&](const uint8_t* at) {
            return size_t(at - static_cast<const uint8_t*>(good.data()));
        };
        const uint32_t* blocks = reinterpret_cast<const uint32_t*>(l.palette_blocks.at);
        uint32_t largest = 0;
        for (uint64_t k = 0; k + 1 < l.palette_blocks.count; ++k)
            largest = std::max(largest, blocks[k + 1] - blocks[k]);
        pvsr_status status;
        {
            Bytes b(good);  // an occupancy count that disagrees with the bits before it
            const uint32_t bad = reinterpret_cast<const uint32_t*>(l.occupancy_ranks.at)[1] + 1;
            std::memcpy(b.bytes() + offset(l.occupancy_ranks.at) + 4, &bad, 4);
            rechecksum(b);
            EXPECT_EQ(opened_message(b, &status), "the occupancy's counts disagree with its bits");
        }
        {
            Bytes b(good);  // a palette entry past the boxes
            const uint32_t bad = l.occluder_box_count;
            if (l.palette.item_bytes == 2) {
                const uint16_t bad16 = uint16_t(bad);
                std::memcpy(b.bytes() + offset(l.palette.at), &bad16, 2);
            } else {
                std::memcpy(b.bytes() + offset(l.palette.at), &bad, 4);
            }
            rechecksum(b);
            EXPECT_EQ(opened_message(b, &status), "a ranked occluder names a box out of range");
        }
        {
            Bytes b(good);  // the palettes' offsets decreasing
            uint64_t k = 1;
            while (k + 1 < l.palette_blocks.count && blocks[k] == 0) ++k;
            ASSERT_LT(k + 1, l.palette_blocks.count);
            const uint32_t bad = blocks[k] - 1;
            std::memcpy(b.bytes() + offset(l.palette_blocks.at) + 4 * (k + 1), &bad, 4);
            rechecksum(b);
            EXPECT_EQ(opened_message(b, &status), "the palettes' offsets decrease");
        }
        {
            Bytes b(good);  // an entry past every palette
            b.bytes()[offset(l.ranked_boxes.at)] = uint8_t(largest);
            rechecksum(b);
            EXPECT_EQ(opened_message(b, &status), "a ranked occluder is out of its block's palette");
        }
        {
            // An entry past its own block's palette but inside the largest: it opens, and reads as nothing.
            uint32_t cell = UINT32_MAX;
            for (uint32_t c = 0; c < l.cell_count && cell == UINT32_MAX; ++c) {
                if (pvsr_occluder_count(&l, c) == 0) continue;
                float box[6];
                pvsr_cell_bounds(&l, c, box);
                const int32_t g[3] = {int32_t(std::floor((box[0] + 1e-3f - l.origin[0]) / l.cell_size_m)),
                                      int32_t(std::floor((box[1] + 1e-3f - l.origin[1]) / l.cell_size_m)),
                                      int32_t(std::floor((box[2] + 1e-3f - l.origin[2]) / l.cell_size_m))};
                const uint32_t n0 = (uint32_t(l.dims[0]) + 3) / 4, n1 = (uint32_t(l.dims[1]) + 3) / 4;
                const uint32_t block =
                    uint32_t(g[0]) / 4 + n0 * (uint32_t(g[1]) / 4 + n1 * (uint32_t(g[2]) / 4));
                if (blocks[block + 1] - blocks[block] < largest) cell = c;
            }
            ASSERT_NE(cell, UINT32_MAX);
            // The cell's first entry: the offsets (ROFS), or its 64's base and the counts before it (4.0).
            uint32_t entry = 0;
            if (l.ranked_offsets.at != nullptr) {
                entry = reinterpret_cast<const uint32_t*>(l.ranked_offsets.at)[cell];
            } else {
                entry = reinterpret_cast<const uint32_t*>(l.ranked_count_bases.at)[cell / 64];
                for (uint32_t c = cell & ~63u; c < cell; ++c) entry += l.ranked_counts.at[c];
            }
            Bytes b(good);
            b.bytes()[offset(l.ranked_boxes.at) + entry] = uint8_t(largest - 1);
            rechecksum(b);
            pvsr_level damaged;
            ASSERT_EQ(pvsr_open(&damaged, b.data(), b.size, message, sizeof message), PVSR_OK) << message;
            pvsr_ranked_occluder o;
            EXPECT_EQ(pvsr_occluder(&damaged, cell, 0, &o), 0);
            EXPECT_EQ(pvsr_occluder(&damaged, cell, 1, &o), 1);
            std::vector<float> boxes(6 * 64);
            ASSERT_GE(pvsr_occluder_boxes(&damaged, cell, boxes.data(), 64), 1u);
            EXPECT_GT(boxes[0], boxes[3]);  // empty
        }
    }
}

// Around the 64-bit words, none at all, and past the 16,384 objects the walk XORs on the stack (it merges
// the two rows' indices there).
TEST(RuntimeFile, ObjectCountsAroundTheEdges) {
    for (const uint32_t objects : {0u, 1u, 63u, 64u, 65u, 16400u}) {
        SCOPED_TRACE(std::to_string(objects) + " objects");
        round_trip(test::coherent_bake(objects, {3, 2, 3}, objects % 2 == 1, true, 5), 12);
    }
}

// --merge-cells K: every cell lists the union of its K x K x K block's rows (so never less than its own row:
// conservative), the cells of a block share it, and the file says so; an octree bake is refused.
TEST(RuntimeFile, MergedCellsListTheUnionOfTheirBlock) {
    test::TempDir dir;
    const std::string h5 = dir.file("m.h5");
    write_bake_file(h5, test::coherent_bake(90, {7, 3, 6}, false, true, 9));
    pvsbake::Bake bake;
    ASSERT_TRUE(bake.load(h5));
    for (const uint32_t k : {2u, 3u}) {
        RuntimeFileOptions options;
        options.merge_cells = k;
        const Bytes bytes(runtime_file_bytes(h5, options));
        pvsr::Level level;
        ASSERT_EQ(level.open(bytes.data(), bytes.size), PVSR_OK);
        EXPECT_EQ(level.string("cell_merge"), std::to_string(k));
        // The union of each block's rows, from the HDF5 loader.
        std::map<int, std::set<uint32_t>> block_union;
        // The grid's origin is cell 0's min corner (the fixture keeps grid position 0), cells of 1.5 m.
        const pvsbake::Box first = bake.cell_bounds(0);
        const auto block_of = [&](uint32_t c) {
            const pvsbake::Box box = bake.cell_bounds(c);
            int key = 0;
            for (int a = 2; a >= 0; --a) {
                const int index = int(std::lround((box.min[a] - first.min[a]) / 1.5f));
                key = key * 64 + index / int(k);
            }
            return key;
        };
        for (uint32_t c = 0; c < bake.cell_count(); ++c)
            bake.for_each_visible(c, [&](uint32_t o) { block_union[block_of(c)].insert(o); });
        uint64_t grew = 0;
        for (uint32_t c = 0; c < bake.cell_count(); ++c) {
            std::set<uint32_t> got;
            level.for_each_visible(c, [&](uint32_t o) { got.insert(o); });
            bake.for_each_visible(c, [&](uint32_t o) { EXPECT_TRUE(got.count(o)) << "cell " << c << " lost " << o; });
            EXPECT_EQ(got, block_union[block_of(c)]) << "cell " << c;
            grew += got.size() - bake.visible_count(c);
        }
        EXPECT_GT(grew, 0u) << "a merge lists more";
    }
    // Not a grid: refused, naming the option.
    const std::string octree = dir.file("o.h5");
    write_bake_file(octree, test::coherent_bake(20, {3, 2, 3}, true, false, 9));
    RuntimeFileOptions options;
    options.merge_cells = 2;
    try {
        runtime_file_bytes(octree, options);
        ADD_FAILURE() << "an octree merged";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--merge-cells"), std::string::npos) << e.what();
    }
}

// ---- Damaged and hostile files

class RuntimeFileDamage : public ::testing::Test {
protected:
    void SetUp() override {
        test::TempDir dir;
        const std::string h5 = dir.file("d.h5");
        BakeData bake = test::coherent_bake(70, {4, 2, 3}, true, true, 8);
        test::add_horizon_lists(bake);  // the horizon sections (file 2.1) too
        test::add_object_parts(bake);   // and the objects' parts (file 2.2)
        write_bake_file(h5, bake);
        file_ = runtime_file_bytes(h5);
    }
    std::string file_;
};

// The horizon sections: each cell lists the three occluders; a damaged section is refused with its reason,
// and a list whose codes run past its bytes or past the occluders ends early (files 5.0 and 3.0).
TEST_F(RuntimeFileDamage, HorizonListsReadAndRefuseDamage) {
    Bytes good(file_);
    pvsr_level l;
    ASSERT_EQ(pvsr_open(&l, good.data(), good.size, nullptr, 0), PVSR_OK);
    ASSERT_EQ(pvsr_horizon_occluder_count(&l), 3u);
    for (uint32_t c = 0; c < pvsr_cell_count(&l); ++c) EXPECT_EQ(pvsr_horizon_list_count(&l, c), 3u);
    EXPECT_EQ(pvsr_horizon_list_count(&l, pvsr_cell_count(&l)), 0u);
    const auto offset_of = [&](const pvsr_array& a) {
        return size_t(a.at - static_cast<const uint8_t*>(good.data()));
    };
    pvsr_status s;
    {
        Bytes b(file_);
        const float nan = std::nanf("");
        std::memcpy(b.bytes() + offset_of(l.horizon_boxes) + 4, &nan, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("a horizon box is not finite"), std::string::npos);
    }
    {
        Bytes b(file_);
        const uint32_t many = PVSR_HORIZON_MAX_CORNERS + 1;
        std::memcpy(b.bytes() + offset_of(l.horizon_tiles) + 24, &many, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("a horizon tile's corners are out of range"), std::string::npos);
    }
    {
        Bytes b(file_);
        const uint32_t past = uint32_t(l.horizon_lists.count + 1);
        std::memcpy(b.bytes() + offset_of(l.horizon_list_offsets) + 4, &past, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("the horizon lists' offsets"), std::string::npos);
    }
    // A list's bytes (file 5.0): a key row of the PVS code less its reference, the head count << 5 | k and
    // the gaps' Rice codes; here each list is {0, 1, 2}, three zero gaps at k = 0: 60 07. A head that cannot
    // hold is refused at open; damaged codes end a list early and never read past the list and its padding.
    const size_t list0 = offset_of(l.horizon_lists);
    ASSERT_EQ(l.horizon_lists.at[0], 0x60u);
    ASSERT_EQ(l.horizon_lists.at[1], 0x07u);
    const auto with_list0 = [&](const std::vector<uint8_t>& bytes, uint16_t major) {
        Bytes b(file_);
        for (size_t k = 0; k < bytes.size(); ++k) b.bytes()[list0 + k] = bytes[k];
        std::memcpy(b.bytes() + 8, &major, 2);  // the version lies before the checksummed bytes
        rechecksum(b);
        return b;
    };
    const auto list0_count_with = [&](const std::vector<uint8_t>& bytes, uint16_t major) {
        const Bytes b = with_list0(bytes, major);
        pvsr_level d;
        EXPECT_EQ(pvsr_open(&d, b.data(), b.size, nullptr, 0), PVSR_OK);
        return pvsr_horizon_list_count(&d, 0);
    };
    const auto refused_list0 = [&](const std::vector<uint8_t>& bytes) {
        return opened_message(with_list0(bytes, PVSR_VERSION_MAJOR), &s);
    };
    EXPECT_EQ(list0_count_with({0x60, 0x07}, PVSR_VERSION_MAJOR), 3u);
    EXPECT_EQ(list0_count_with({0x60, 0x0f}, PVSR_VERSION_MAJOR), 3u) << "bits past the count are not read";
    EXPECT_EQ(list0_count_with({0x40, 0x07}, PVSR_VERSION_MAJOR), 2u) << "a smaller count";
    EXPECT_EQ(list0_count_with({0x60, 0x31}, PVSR_VERSION_MAJOR), 1u) << "a gap of 3 after index 0";
    EXPECT_EQ(list0_count_with({0x60, 0x00}, PVSR_VERSION_MAJOR), 0u) << "a quotient past the bytes";
    EXPECT_NE(refused_list0({0x79, 0x07}).find("a horizon list's Rice parameter is above 24"),
              std::string::npos);
    EXPECT_NE(refused_list0({0x80, 0x01}).find("a horizon list has more entries than occluders"),
              std::string::npos);
    EXPECT_NE(refused_list0({0x63, 0x07}).find("a horizon list's code runs past the list"),
              std::string::npos);
    EXPECT_NE(refused_list0({0xe0, 0x87}).find("a horizon list's head is damaged"), std::string::npos);
    // A 4.x file (a development format whose lists 5.0 codes anew) is refused, naming what to do.
    EXPECT_NE(opened_message(with_list0({}, 4), &s).find("export it again"), std::string::npos);
    EXPECT_EQ(s, PVSR_VERSION_TOO_NEW);
    // Files before 4.0 code the gaps in LEB128 varints (here in the list's two bytes).
    EXPECT_EQ(list0_count_with({0, 0}, 3), 2u);
    EXPECT_EQ(list0_count_with({0, 0x7f}, 3), 1u) << "a gap past the occluders";
    EXPECT_EQ(list0_count_with({0x80, 0x80}, 3), 0u) << "a varint past the bytes";
}

// The file as 5.0 wrote it, its parts in 'OPOF' u32 offsets and 'OPBX' floats: the decoded boxes and the
// offsets appended after the last section and named in the table in place of 'OPOQ' and 'OPBQ' (whose
// bytes stay, unread); or, with keep_steps, in two new entries of the table beside them (the first section
// moved to the end, for room).
Bytes with_float_parts(const std::string& file, bool keep_steps = false) {
    Bytes in(file);
    pvsr_level l;
    EXPECT_EQ(pvsr_open(&l, in.data(), in.size, nullptr, 0), PVSR_OK);
    std::string out = file, floats, offsets;
    uint32_t parts = 0;
    for (uint32_t o = 0; o <= pvsr_object_count(&l); ++o) {
        offsets.append(reinterpret_cast<const char*>(&parts), 4);
        for (uint32_t k = 0; o < pvsr_object_count(&l) && k < pvsr_object_part_count(&l, o); ++k, ++parts) {
            float box[6];
            EXPECT_TRUE(pvsr_object_part(&l, o, k, box));
            floats.append(reinterpret_cast<const char*>(box), sizeof box);
        }
    }
    const auto align = [&] { out.resize((out.size() + PVSR_ALIGN - 1) / PVSR_ALIGN * PVSR_ALIGN, '\0'); };
    const auto entry = [&](uint32_t i) {
        return out.data() + PVSR_HEADER_BYTES + size_t(i) * PVSR_ENTRY_BYTES;
    };
    uint32_t sections;
    std::memcpy(&sections, out.data() + 32, 4);
    if (keep_steps) {
        uint32_t first = 0;
        uint64_t first_at = UINT64_MAX, first_bytes, moved_to = out.size();
        for (uint32_t i = 0; i < sections; ++i) {
            uint64_t offset;
            std::memcpy(&offset, entry(i) + 8, 8);
            if (offset < first_at) first_at = offset, first = i;
        }
        std::memcpy(&first_bytes, entry(first) + 24, 8);
        out += out.substr(first_at, first_bytes);
        align();
        std::memcpy(entry(first) + 8, &moved_to, 8);
        EXPECT_LE(PVSR_HEADER_BYTES + (sections + 2) * PVSR_ENTRY_BYTES, first_at + first_bytes);
        std::memcpy(entry(sections), "OPOQ", 4);
        std::memcpy(entry(sections + 1), "OPBQ", 4);
        sections += 2;
        std::memcpy(out.data() + 32, &sections, 4);
    }
    for (const auto& [from, to, bytes, item] :
         {std::tuple{"OPOQ", "OPOF", &offsets, 4u}, std::tuple{"OPBQ", "OPBX", &floats, 24u}}) {
        const uint64_t at = out.size(), count = bytes->size() / item;
        out += *bytes;
        align();
        const uint64_t size = out.size() - at;
        for (uint32_t i = keep_steps ? sections - 2 : 0; i < sections; ++i) {
            char* e = entry(i);
            if (std::memcmp(e, from, 4) != 0) continue;
            std::memcpy(e, to, 4);
            std::memcpy(e + 4, &item, 4);
            std::memcpy(e + 8, &at, 8);
            std::memcpy(e + 16, &count, 8);
            std::memcpy(e + 24, &size, 8);
            break;
        }
    }
    const uint16_t minor = 0;
    const uint64_t size = out.size();
    std::memcpy(out.data() + 10, &minor, 2);
    std::memcpy(out.data() + 16, &size, 8);
    Bytes result(out);
    rechecksum(result);
    return result;
}

// The object parts' sections: each object of the bake has its halves (or quarters), read as the bake holds
// them from the steps of file 5.1 and from the floats of 5.0; a damaged offset or box is refused with its
// reason.
TEST_F(RuntimeFileDamage, ObjectPartsReadAndRefuseDamage) {
    Bytes good(file_);
    pvsr_level l;
    ASSERT_EQ(pvsr_open(&l, good.data(), good.size, nullptr, 0), PVSR_OK);
    ASSERT_GT(l.object_parts.count, 0u);
    ASSERT_EQ(l.object_parts.item_bytes, 12u);
    EXPECT_EQ(pvsr_object_part_count(&l, pvsr_object_count(&l)), 0u);
    const auto offset_of = [&](const pvsr_array& a) {
        return size_t(a.at - static_cast<const uint8_t*>(good.data()));
    };
    pvsr_status s;
    {
        // A 5.0 file's floats: the same boxes.
        Bytes old = with_float_parts(file_);
        pvsr_level f;
        ASSERT_EQ(pvsr_open(&f, old.data(), old.size, nullptr, 0), PVSR_OK);
        ASSERT_EQ(f.object_parts.item_bytes, 24u);
        for (uint32_t o = 0; o < pvsr_object_count(&l); ++o) {
            ASSERT_EQ(pvsr_object_part_count(&f, o), pvsr_object_part_count(&l, o));
            for (uint32_t k = 0; k < pvsr_object_part_count(&l, o); ++k) {
                float a[6], b[6];
                ASSERT_TRUE(pvsr_object_part(&l, o, k, a));
                ASSERT_TRUE(pvsr_object_part(&f, o, k, b));
                EXPECT_EQ(std::memcmp(a, b, sizeof a), 0) << "object " << o << " part " << k;
            }
        }
        const auto floats_at = size_t(f.object_parts.at - static_cast<const uint8_t*>(old.data()));
        Bytes nan_box = old;
        const float nan = std::nanf("");
        std::memcpy(nan_box.bytes() + floats_at + 8, &nan, 4);
        rechecksum(nan_box);
        EXPECT_NE(opened_message(nan_box, &s).find("an object part box is not finite"), std::string::npos);
        Bytes outside = old;
        float x;
        std::memcpy(&x, outside.bytes() + floats_at + 12, 4);
        x += 100.0f;  // past its object's bounds
        std::memcpy(outside.bytes() + floats_at + 12, &x, 4);
        rechecksum(outside);
        EXPECT_NE(opened_message(outside, &s).find("not inside its object's bounds"), std::string::npos);
    }
    const auto with_steps = [&](uint16_t lo, uint16_t hi) {
        Bytes b(file_);
        for (int a = 0; a < 3; ++a) {
            std::memcpy(b.bytes() + offset_of(l.object_parts) + 2 * a, &lo, 2);
            std::memcpy(b.bytes() + offset_of(l.object_parts) + 6 + 2 * a, &hi, 2);
        }
        rechecksum(b);
        return b;
    };
    EXPECT_NE(opened_message(with_steps(2, 1), &s).find("an object part box is empty or passes"),
              std::string::npos);
    // Steps past the bounds' (at most 65,535 on each axis, fewer on some).
    EXPECT_NE(opened_message(with_steps(65535, 65535), &s).find("an object part box is empty or passes"),
              std::string::npos);
    {
        Bytes b(file_);
        const uint32_t past = uint32_t(l.object_parts.count + 1);
        std::memcpy(b.bytes() + offset_of(l.object_part_offsets) + 4, &past, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("the object parts' offsets"), std::string::npos);
    }
    {
        Bytes b(file_);
        const uint32_t one = 1;
        std::memcpy(b.bytes() + offset_of(l.object_part_offsets), &one, 4);
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("the object parts' offsets"), std::string::npos);
    }
    {
        // The offsets' section renamed in the table (an unknown tag is skipped): boxes without offsets.
        Bytes b(file_);
        const size_t at = file_.find("OPOQ");
        ASSERT_LT(at, size_t(l.object_part_offsets.at - static_cast<const uint8_t*>(good.data())));
        b.bytes()[at] = 'X';
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("object part boxes without their offsets"), std::string::npos);
    }
    {
        Bytes b = with_float_parts(file_, true);  // 'OPBX' beside 'OPBQ'
        EXPECT_NE(opened_message(b, &s).find("two kinds of object part boxes"), std::string::npos);
    }
}

// A row's chain (docs/FORMAT.md, "The rows' code") holds at most PVSR_MAX_CHAIN rows (16 from file 3.0):
// a file of whole rows made to code rows 1 .. n against the row before each (the checksum made right) opens
// with a chain of 16 and is refused with one of 17.
TEST(RuntimeFileChains, SixteenRowsOpenAndSeventeenAreRefused) {
    static_assert(PVSR_MAX_CHAIN == 16);
    test::TempDir dir;
    const std::string h5 = dir.file("chain.h5");
    write_bake_file(h5, test::coherent_bake(90, {7, 3, 6}, false, true, 9));
    RuntimeFileOptions options;
    options.max_chain = 1;  // every row whole: each row's code starts with the one-byte reference 0
    const Bytes whole(runtime_file_bytes(h5, options));
    pvsr_level l;
    char message[256];
    ASSERT_EQ(pvsr_open(&l, whole.data(), whole.size, message, sizeof message), PVSR_OK) << message;
    ASSERT_GE(l.row_offsets.count, uint64_t(PVSR_MAX_CHAIN) + 2);
    const auto row_start = [&](uint64_t r) {
        const uint64_t at = l.row_offsets.item_bytes == 2
                                ? reinterpret_cast<const uint16_t*>(l.row_offsets.at)[r]
                                : reinterpret_cast<const uint32_t*>(l.row_offsets.at)[r];
        return size_t(l.code.at - static_cast<const uint8_t*>(whole.data())) + size_t(at);
    };
    for (const uint32_t length : {uint32_t(PVSR_MAX_CHAIN), uint32_t(PVSR_MAX_CHAIN) + 1}) {
        SCOPED_TRACE(length);
        Bytes b(whole);
        for (uint64_t r = 1; r < length; ++r) {
            ASSERT_EQ(b.bytes()[row_start(r)], 0u);
            b.bytes()[row_start(r)] = 1;  // coded against row r - 1
        }
        rechecksum(b);
        pvsr_status status;
        EXPECT_EQ(opened_message(b, &status),
                  length <= PVSR_MAX_CHAIN ? "" : "a PVS row's chain of references is too long");
    }
}

TEST_F(RuntimeFileDamage, EachDamageIsRefusedWithItsReason) {
    pvsr_status s;
    {
        Bytes b(file_.substr(0, file_.size() - 64));
        EXPECT_NE(opened_message(b, &s).find("truncated"), std::string::npos);
        EXPECT_EQ(s, PVSR_CORRUPT);
    }
    {
        Bytes b(file_.substr(0, 40));
        EXPECT_NE(opened_message(b, &s).find("not a pvsbake runtime file"), std::string::npos);
        EXPECT_EQ(s, PVSR_NOT_A_RUNTIME_FILE);
    }
    {
        Bytes b("PK\x03\x04 a zip, not a level" + std::string(80, ' '));
        opened_message(b, &s);
        EXPECT_EQ(s, PVSR_NOT_A_RUNTIME_FILE);
    }
    {
        Bytes b(file_);
        b.bytes()[b.size / 2] ^= 0x10;
        EXPECT_NE(opened_message(b, &s).find("checksum"), std::string::npos);
        EXPECT_EQ(s, PVSR_CORRUPT);
    }
    {
        Bytes b(file_);
        b.bytes()[8] = PVSR_VERSION_MAJOR + 1;  // the version lies before the checksummed bytes
        EXPECT_NE(opened_message(b, &s).find("newer major version"), std::string::npos);
        EXPECT_EQ(s, PVSR_VERSION_TOO_NEW);
    }
    {
        Bytes b(file_);
        b.bytes()[26] ^= 1;  // the checksum itself
        EXPECT_NE(opened_message(b, &s).find("checksum"), std::string::npos);
    }
    {
        // A hostile file: a cell's row out of range, with the checksum made right.
        Bytes b(file_);
        pvsr_level l;
        ASSERT_EQ(pvsr_open(&l, b.data(), b.size, nullptr, 0), PVSR_OK);
        const size_t at = size_t(l.cell_row.at - static_cast<const uint8_t*>(b.data()));
        if (l.cell_row.item_bytes == 2) {
            const uint16_t bad = uint16_t(l.row_count);
            std::memcpy(b.bytes() + at, &bad, 2);
        } else {
            const uint32_t bad = l.row_count;
            std::memcpy(b.bytes() + at, &bad, 4);
        }
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("a cell's row is out of range"), std::string::npos);
        EXPECT_EQ(s, PVSR_CORRUPT);
        // Also the last row's head damaged (checked as the checksum passes it, before the cells' rows):
        // the refusal is still the first failing check in the documented order.
        const size_t last = size_t(l.code.at - static_cast<const uint8_t*>(b.data())) +
                            (l.row_offsets.item_bytes == 2
                                 ? size_t(reinterpret_cast<const uint16_t*>(l.row_offsets.at)[l.row_count - 1])
                                 : size_t(reinterpret_cast<const uint32_t*>(l.row_offsets.at)[l.row_count - 1]));
        ASSERT_LT(l.row_count, 128u);
        b.bytes()[last] = 0x7f;  // a reference 127 rows back, before the first row
        rechecksum(b);
        EXPECT_NE(opened_message(b, &s).find("a cell's row is out of range"), std::string::npos);
        Bytes only_row(file_);
        only_row.bytes()[last] = 0x7f;
        rechecksum(only_row);
        EXPECT_NE(opened_message(only_row, &s).find("a PVS row refers to a row after it"), std::string::npos);
    }
    {
        // A file whose checksummed bytes end in less than one 32-byte stripe past the last section: the
        // checks beside the checksum must still end.
        std::string longer = file_ + std::string(3, '\0');
        const uint64_t size = longer.size();
        std::memcpy(&longer[16], &size, 8);
        Bytes b(longer);
        rechecksum(b);
        opened_message(b, &s);
        EXPECT_TRUE(s == PVSR_OK || s == PVSR_CORRUPT);
    }
    pvsr_level l;
    EXPECT_EQ(pvsr_open(nullptr, file_.data(), file_.size(), nullptr, 0), PVSR_INVALID_ARGUMENT);
    EXPECT_EQ(pvsr_open(&l, nullptr, 0, nullptr, 0), PVSR_INVALID_ARGUMENT);
    EXPECT_STREQ(pvsr_status_name(PVSR_CORRUPT), "corrupt");
    // A refused level is empty: queries answer as for no level.
    EXPECT_EQ(pvsr_cell_count(&l), 0u);
    EXPECT_EQ(pvsr_find_cell(&l, 0, 0, 0), -1);
    EXPECT_EQ(pvsr_visible_count(&l, 0), 0u);
    EXPECT_STREQ(pvsr_object_name(&l, 0), "");
}

// Any byte changed, the checksum made right: the runtime refuses the file, or every query of it stays in
// range (run under the sanitizers by scripts/test.sh: no read outside the bytes).
TEST_F(RuntimeFileDamage, HostileBytesAreRefusedOrStayInRange) {
    std::mt19937 rng(20261127u);
    const int trials = test::in_ci() ? 3000 : 30000;
    std::vector<uint64_t> horizon_memory(pvsr_horizon_memory_bytes(16, 4096) / 8 + 1);
    pvsr_horizon horizon;
    ASSERT_TRUE(pvsr_horizon_init(&horizon, 16, 4096, horizon_memory.data(), horizon_memory.size() * 8));
    int refused = 0;
    for (int t = 0; t < trials; ++t) {
        Bytes b(file_);
        const int changes = 1 + int(rng() % 4);
        for (int k = 0; k < changes; ++k) {
            const size_t at = PVSR_CHECKSUMMED_FROM + rng() % (b.size - PVSR_CHECKSUMMED_FROM);
            b.bytes()[at] = uint8_t(rng() % 4 == 0 ? rng() : b.bytes()[at] ^ (1u << (rng() % 8)));
        }
        rechecksum(b);
        pvsr_level l;
        if (pvsr_open(&l, b.data(), b.size, nullptr, 0) != PVSR_OK) {
            ++refused;
            continue;
        }
        const uint32_t objects = pvsr_object_count(&l);
        for (uint32_t c = 0; c < pvsr_cell_count(&l); ++c) {
            pvsr_visit_visible(&l, c, [](void* user, uint32_t o) {
                if (o >= *static_cast<const uint32_t*>(user)) ADD_FAILURE() << "index " << o << " out of range";
            }, const_cast<uint32_t*>(&objects));
            pvsr_is_visible(&l, c, objects / 2);
            float box[6];
            pvsr_cell_bounds(&l, c, box);
            for (uint32_t k = 0; k < pvsr_occluder_count(&l, c); ++k) {
                pvsr_ranked_occluder o;
                pvsr_occluder(&l, c, k, &o);
            }
            const float eye[3] = {box[0], box[1], box[2]};
            pvsr_horizon_begin_cell(&horizon, &l, c, eye);
            pvsr_horizon_is_hidden(&horizon, box);
        }
        for (uint32_t o = 0; o < objects; ++o) (void)std::strlen(pvsr_object_name(&l, o));
        for (int p = 0; p < 50; ++p) {
            const float x = float(rng() % 2000) / 100.0f - 5.0f, y = float(rng() % 1000) / 100.0f - 2.0f,
                        z = float(rng() % 2000) / 100.0f - 5.0f;
            const int32_t c = pvsr_find_cell(&l, x, y, z);
            EXPECT_LT(c, int32_t(pvsr_cell_count(&l)));
            pvsr_in_eye_space(&l, x, y, z);
        }
        (void)std::strlen(pvsr_string(&l, "mode"));
    }
    EXPECT_GT(refused, trials / 4) << "the checks should refuse most changes";
}

// The C99 culler compiled as C answers as pvsbake::OcclusionCuller, the same code compiled into the loader as
// C++ (io/loader/occlusion.cpp; checked against rays by test_runtime_occlusion), on random scenes: the same
// path for every box, the same occluders used and skipped, at every resolution (0: shadow frusta and faces
// only), and a culler without its memory culls nothing.
TEST(RuntimeFile, TheCullerAnswersAsTheLoadersCuller) {
    std::mt19937 rng(20261128u);
    std::uniform_real_distribution<float> u(-20.0f, 20.0f), size(0.2f, 6.0f), thin(0.05f, 0.6f);
    const auto random_box = [&](bool flat) {  // flat: thin along one axis
        pvsbake::Box b;
        for (int a = 0; a < 3; ++a) {
            b.min[a] = u(rng);
            b.max[a] = b.min[a] + (flat && a == int(rng() % 3) ? thin(rng) : size(rng));
        }
        return b;
    };
    // Panels (boxes flat along one axis) come from their own stream: the boxes above do not depend on them.
    std::mt19937 panel_rng(20261129u);
    const auto random_panel = [&]() {
        pvsbake::Box b;
        const int flat = int(panel_rng() % 3);
        for (int a = 0; a < 3; ++a) {
            b.min[a] = u(panel_rng);
            b.max[a] = a == flat ? b.min[a] : b.min[a] + size(panel_rng);
        }
        return b;
    };
    std::mt19937 polygon_rng(20261206u);
    uint64_t hidden = 0, fused = 0, by_faces = 0, total = 0;
    for (const int resolution : {0, 2, 32, 64}) {
        pvsbake::OcclusionCuller want(resolution);
        std::vector<float> memory(pvsr_culler_memory_bytes(resolution) / sizeof(float) + 1);
        pvsr_culler got;
        ASSERT_EQ(pvsr_culler_init(&got, resolution, memory.data(), memory.size() * sizeof(float)), 1);
        for (int scene = 0; scene < (test::in_ci() ? 40 : 200); ++scene) {
            std::vector<pvsbake::Box> occluders;
            const int n = 1 + int(rng() % 24);
            for (int k = 0; k < n; ++k) occluders.push_back(random_box(k % 2 == 0));
            for (int k = 0; k < n / 3; ++k) occluders.push_back(random_panel());
            const float eye[3] = {u(rng) * 0.5f, u(rng) * 0.5f, u(rng) * 0.5f};
            want.begin_frame(eye, occluders);
            pvsr_culler_begin_frame(&got, eye, &occluders[0].min[0], occluders.size());
            ASSERT_EQ(got.used, want.occluders_used());
            ASSERT_EQ(got.redundant, want.occluders_redundant());
            for (int k = 0, m = int(polygon_rng() % 5); k < m; ++k) {  // polygons, from their own stream
                const float centre[3] = {u(polygon_rng), u(polygon_rng), u(polygon_rng)};
                const test::TestPolygon p = test::random_polygon(polygon_rng, centre, 8.0f, 0.05f);
                ASSERT_EQ(pvsr_culler_add_polygon(&got, p.plane, p.corners.data(), p.count()),
                          int(want.add_polygon(p.plane, p.corners.data(), p.count())));
            }
            for (int q = 0; q < 300; ++q) {
                const pvsbake::Box box = random_box(false);
                const int path = pvsr_culler_classify(&got, &box.min[0]);
                ASSERT_EQ(path, int(want.classify(box))) << "resolution " << resolution << " scene " << scene;
                hidden += path != PVSR_CULL_VISIBLE;
                fused += path == PVSR_CULL_DEPTH_CUBE;
                by_faces += path == PVSR_CULL_FACES;
                ++total;
            }
        }
    }
    EXPECT_GT(hidden, total / 100) << "the scenes should hide something";
    EXPECT_GT(fused, 0u) << "some boxes should be hidden by fused occluders only";
    EXPECT_GT(by_faces, 0u) << "some boxes should be hidden by the union of faces only";
    // No memory: it culls nothing.
    pvsr_culler none;
    EXPECT_EQ(pvsr_culler_init(&none, 32, nullptr, 0), 0);
    const float eye[3] = {0, 0, 0}, wall[6] = {1, -5, -5, 2, 5, 5}, behind[6] = {4, -1, -1, 5, 1, 1};
    pvsr_culler_begin_frame(&none, eye, wall, 1);
    EXPECT_EQ(pvsr_culler_is_hidden(&none, behind), 0);
    pvsr::Culler wrapped(32);  // the C++ wrapper: the same culler with its memory
    ASSERT_TRUE(wrapped.ok());
    wrapped.begin_frame(eye, wall, 1);
    EXPECT_TRUE(wrapped.is_hidden(behind));
    pvsr_culler frusta;
    ASSERT_EQ(pvsr_culler_init(&frusta, 0, nullptr, 0), 1);
    pvsr_culler_begin_frame(&frusta, eye, wall, 1);
    EXPECT_EQ(pvsr_culler_classify(&frusta, behind), PVSR_CULL_SHADOW_FRUSTUM);
}

TEST(RuntimeFile, Xxh64EqualsLibxxhash) {
    std::mt19937 rng(7);
    std::vector<uint8_t> data(5000);
    for (uint8_t& v : data) v = uint8_t(rng());
    for (size_t n = 0; n < 300; ++n)
        ASSERT_EQ(pvsr_xxh64(data.data() + n % 8, n, n * 31), XXH64(data.data() + n % 8, n, n * 31)) << n;
    EXPECT_EQ(pvsr_xxh64(data.data(), data.size(), 0), XXH64(data.data(), data.size(), 0));
}

}  // namespace
}  // namespace pvs
