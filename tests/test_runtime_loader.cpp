// SPDX-License-Identifier: MIT
// Tests the runtime loader (pvsbake/loader.h, pvsbake/loader_c.h): everything write_bake_file writes, the
// loader reads back identically (cells and their lookup, rows, objects, figures; grids and octrees, view
// masks, format 1.0 files without the PVS code); each status comes with its message; the C API mirrors
// the C++ one; the PVS code round-trips and refuses damage; the example program runs. Links the loader,
// io and core only, so that scripts/test.sh builds and runs it under the sanitizers quickly
// (test_runtime_loader_package has the tests that need the pvsbake command or an install).
#include "core/error.h"
#include "io/bake_file.h"
#include "io/runtime_file.h"
#include "io/loader/row_code.h"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>
#include <pvsbake/loader_c.h>

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace pvs {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------------

TEST(RuntimeLoader, GridRoundTrip) {
    test::TempDir dir;
    for (bool view : {false, true}) {
        SCOPED_TRACE(view);
        const BakeData bake = test::coherent_bake(133, {7, 3, 6}, false, view, 3, /*polygons=*/view);
        const std::string path = dir.file("grid.h5");
        pvsbake::Bake loaded;
        test::write_and_load(bake, path, loaded);
        EXPECT_EQ(loaded.format_minor(), kBakeFormatMinor);
        test::expect_loaded_equals(loaded, bake);
        test::expect_same_lookup(loaded, bake.cells, 5);
        const pvsbake::PvsStats& s = loaded.pvs_stats();
        EXPECT_EQ(s.cell_count, bake.cells.size());
        EXPECT_EQ(s.bytes_raw, bake.cells.size() * ((133 + 7) / 8));
        EXPECT_GT(s.bytes_stored, 0u);
        EXPECT_GT(s.memory_bytes, s.bytes_code);
    }
}

TEST(RuntimeLoader, OctreeRoundTrip) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(70, {4, 2, 3}, true, true, 8);
    const std::string path = dir.file("octree.h5");
    pvsbake::Bake loaded;
    test::write_and_load(bake, path, loaded);
    EXPECT_EQ(loaded.cell_kind(), pvsbake::CellKind::kOctree);
    test::expect_loaded_equals(loaded, bake);
    test::expect_same_lookup(loaded, bake.cells, 9);
}

// Object counts around byte and word edges, no objects, no cells.
TEST(RuntimeLoader, CountsAroundEdgesAndEmptyBakes) {
    test::TempDir dir;
    for (uint32_t objects : {0u, 1u, 7u, 8u, 63u, 64u, 65u, 200u}) {
        for (glm::ivec3 dims : {glm::ivec3(0, 0, 0), glm::ivec3(1, 1, 1), glm::ivec3(3, 2, 2)}) {
            SCOPED_TRACE(::testing::Message()
                         << objects << " objects, " << dims.x * dims.y * dims.z << " grid");
            const BakeData bake = test::coherent_bake(objects, dims, false, false, objects + 1);
            const std::string path = dir.file("edge.h5");
            write_bake_file(path, bake);
            pvsbake::Bake loaded;
            test::load_ok(loaded, path);
            test::expect_loaded_equals(loaded, bake);
            test::expect_same_lookup(loaded, bake.cells, 2);
        }
    }
}

// Out-of-range indices give nothing, never a crash.
TEST(RuntimeLoader, OutOfRangeQueries) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(20, {2, 2, 2}, false, false, 4);
    write_bake_file(dir.file("b.h5"), bake);
    pvsbake::Bake loaded;
    test::load_ok(loaded, dir.file("b.h5"));
    const uint32_t c = loaded.cell_count(), o = loaded.object_count();
    int visits = 0;
    loaded.for_each_visible(c, [&](uint32_t) { ++visits; });
    EXPECT_EQ(visits, 0);
    EXPECT_EQ(loaded.visible_count(c), 0u);
    EXPECT_FALSE(loaded.is_visible(c, 0));
    EXPECT_FALSE(loaded.is_visible(0, o));
    uint64_t word = 7;
    EXPECT_EQ(loaded.fill_bitset(0, &word, 0), UINT32_MAX);
    EXPECT_EQ(word, 7u);
    EXPECT_EQ(loaded.object_name(o), "");
    EXPECT_EQ(loaded.object_triangles(o), 0u);
    EXPECT_TRUE(std::isinf(loaded.cell_bounds(c).min[0]));
    EXPECT_EQ(loaded.figure("no such figure"), nullptr);
    ASSERT_NE(loaded.figure("cells"), nullptr);
    EXPECT_EQ(*loaded.figure("cells"), double(c));  // the first of the repeated name
    ASSERT_NE(loaded.parameter("bake.mode"), nullptr);
    pvsbake::Bake empty;
    EXPECT_TRUE(empty.empty());
    EXPECT_EQ(empty.find_cell(0, 0, 0), -1);
}

// Format 1.0 files have no /pvs/code: the loader codes their rows at load, with the same result.
TEST(RuntimeLoader, ReadsFormat10Files) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(90, {5, 4, 3}, false, true, 11);
    const std::string path = dir.file("old.h5");
    write_bake_file(path, bake);
    {
        const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(f, 0);
        ASSERT_GE(H5Ldelete(f, "/pvs/code", H5P_DEFAULT), 0);
        ASSERT_GE(H5Ldelete(f, "/pvs/code_offsets", H5P_DEFAULT), 0);
        const hid_t a = H5Aopen(f, "format_minor", H5P_DEFAULT);
        const int zero = 0;
        ASSERT_GE(H5Awrite(a, H5T_NATIVE_INT, &zero), 0);
        H5Aclose(a);
        H5Fclose(f);
    }
    pvsbake::Bake loaded;
    test::load_ok(loaded, path);
    EXPECT_EQ(loaded.format_minor(), 0);
    test::expect_loaded_equals(loaded, bake);
}

// ---------------------------------------------------------------------------------------------------------
// Statuses.

void expect_status(const std::string& path, pvsbake::Status status, const std::string& needle) {
    pvsbake::Bake bake;
    const pvsbake::LoadResult r = bake.load(path);
    EXPECT_EQ(r.status, status) << r.message;
    EXPECT_EQ(r.message.rfind(path + ": ", 0), 0u) << r.message;
    EXPECT_NE(r.message.find(needle), std::string::npos) << "'" << needle << "' in " << r.message;
    EXPECT_EQ(r.message.find('\n'), std::string::npos) << r.message;
    EXPECT_TRUE(bake.empty());
    EXPECT_EQ(bake.cell_count(), 0u);
}

void set_int_attr(const std::string& path, const char* name, int value) {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t a = H5Aopen(f, name, H5P_DEFAULT);
    ASSERT_GE(a, 0);
    EXPECT_GE(H5Awrite(a, H5T_NATIVE_INT, &value), 0);
    H5Aclose(a);
    H5Fclose(f);
}

TEST(RuntimeLoaderStatus, EachStatusWithItsMessage) {
    test::TempDir dir;
    expect_status(dir.file("nope.h5"), pvsbake::Status::kFileMissing, "no such file");
    test::write_file(dir.file("text.h5"), "not a bake\n");
    expect_status(dir.file("text.h5"), pvsbake::Status::kNotBakeFile, "not an HDF5 file");
    fs::create_directory(dir.file("folder.h5"));
    expect_status(dir.file("folder.h5"), pvsbake::Status::kNotBakeFile, "folder");
    const hid_t f = H5Fcreate(dir.file("other.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    H5Fclose(f);
    expect_status(dir.file("other.h5"), pvsbake::Status::kNotBakeFile, "not a pvsbake bake file");

    const std::string path = dir.file("bake.h5");
    write_bake_file(path, test::coherent_bake(30, {3, 2, 2}, false, false, 1));
    set_int_attr(path, "format_major", 2);
    set_int_attr(path, "format_minor", 0);
    expect_status(path, pvsbake::Status::kVersionTooNew,
                  "bake format 2.0 is newer than this tool reads (1.x)");
    set_int_attr(path, "format_major", 1);
    set_int_attr(path, "format_minor", 9);  // a newer minor version only adds: it loads
    pvsbake::Bake bake;
    test::load_ok(bake, path);
    EXPECT_EQ(bake.format_minor(), 9);

    const std::string bytes = test::read_file(path);
    test::write_file(dir.file("cut.h5"), bytes.substr(0, bytes.size() / 2));
    pvsbake::Bake cut;
    const pvsbake::LoadResult r = cut.load(dir.file("cut.h5"));
    EXPECT_TRUE(r.status == pvsbake::Status::kCorrupt || r.status == pvsbake::Status::kNotBakeFile)
        << r.message;
    EXPECT_STREQ(pvsbake::status_name(pvsbake::Status::kVersionTooNew), "version too new");
}

// An index out of range anywhere is refused at load, so that queries need no checks.
TEST(RuntimeLoaderStatus, IndicesOutOfRangeAreCorrupt) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, test::coherent_bake(30, {3, 2, 2}, true, false, 1));
    struct Patch {
        const char* dataset;
        int32_t value;
        const char* needle;
    };
    for (const Patch& p : {Patch{"/pvs/cell_row", 99, "/pvs/cell_row[1]"},
                           Patch{"/cells/grid_to_cell", 999, "/cells/grid_to_cell[1]"},
                           Patch{"/cells/octree/first_child", 1, "/cells/octree/first_child[1]"},
                           Patch{"/cells/octree/cell", 500, "/cells/octree/cell[1]"},
                           Patch{"/pvs/code_offsets", 100000, "/pvs/code"},
                           Patch{"/pvs/code", 0x55, "/pvs/code does not match its checksum"}}) {
        SCOPED_TRACE(p.dataset);
        const std::string path = dir.file("bad.h5");
        fs::copy_file(good, path, fs::copy_options::overwrite_existing);
        const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const hid_t ds = H5Dopen2(f, p.dataset, H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        const hid_t space = H5Dget_space(ds);
        const hsize_t at = 1, one = 1;
        H5Sselect_hyperslab(space, H5S_SELECT_SET, &at, nullptr, &one, nullptr);
        const hid_t mem = H5Screate_simple(1, &one, nullptr);
        EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_INT32, mem, space, H5P_DEFAULT, &p.value), 0);
        H5Sclose(mem);
        H5Sclose(space);
        H5Dclose(ds);
        H5Fclose(f);
        expect_status(path, pvsbake::Status::kCorrupt, p.needle);
    }
}

// The view and eye masks load from their bricks (format 1.4) and, in older files, from their bits: both
// answer every lookup as the cells do. A brick index past the stored bricks is refused.
TEST(RuntimeLoader, MasksLoadFromBricksAndOlderFilesFromBitsAlike) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(133, {7, 3, 6}, false, true, 3);
    const std::string path = dir.file("bricks.h5");
    pvsbake::Bake loaded;
    test::write_and_load(bake, path, loaded);
    test::expect_same_lookup(loaded, bake.cells, 11);

    const std::string old_path = dir.file("old.h5");
    fs::copy_file(path, old_path, fs::copy_options::overwrite_existing);
    {
        const hid_t f = H5Fopen(old_path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(f, 0);
        for (const char* name : {"/cells/view/brick_index", "/cells/view/brick_bits",
                                 "/cells/eyes/brick_index", "/cells/eyes/brick_bits"})
            ASSERT_GE(H5Ldelete(f, name, H5P_DEFAULT), 0) << name;
        H5Fclose(f);
    }
    set_int_attr(old_path, "format_minor", 3);
    pvsbake::Bake old;
    test::load_ok(old, old_path);
    test::expect_same_lookup(old, bake.cells, 11);

    const std::string bad = dir.file("bad.h5");
    fs::copy_file(path, bad, fs::copy_options::overwrite_existing);
    {
        const hid_t f = H5Fopen(bad.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const hid_t ds = H5Dopen2(f, "/cells/view/brick_index", H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        const hid_t space = H5Dget_space(ds);
        const hsize_t at = 0, one = 1;
        H5Sselect_hyperslab(space, H5S_SELECT_SET, &at, nullptr, &one, nullptr);
        const hid_t mem = H5Screate_simple(1, &one, nullptr);
        const uint32_t value = 1u << 30;
        EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_UINT32, mem, space, H5P_DEFAULT, &value), 0);
        H5Sclose(mem);
        H5Sclose(space);
        H5Dclose(ds);
        H5Fclose(f);
    }
    expect_status(bad, pvsbake::Status::kCorrupt, "/cells/view/brick_index[0] = 1073741824 is not 0, 1 or 2");
}

// Ranked occluders (format 1.2): each entry with its box; files of 1.1 (no ranking) load with none.
TEST(RuntimeLoader, RankedOccludersRoundTripAndOldFilesHaveNone) {
    test::TempDir dir;
    BakeData bake = test::coherent_bake(40, {3, 2, 3}, false, false, 5);
    ASSERT_GT(bake.ranked.entries.size(), 10u);
    const std::string path = dir.file("ranked.h5");
    pvsbake::Bake loaded;
    test::write_and_load(bake, path, loaded);
    test::expect_same_ranked(loaded, bake);
    EXPECT_EQ(loaded.occluder_count(3), 3u);
    EXPECT_TRUE(loaded.occluders(loaded.cell_count()).empty());
    EXPECT_EQ(loaded.occluder_count(UINT32_MAX), 0u);

    // A 1.1 file: the same bake without the ranked datasets (as pvsbake 1.1 wrote them).
    bake.ranked = RankedOccluders{};
    const std::string old_path = dir.file("old.h5");
    write_bake_file(old_path, bake);
    set_int_attr(old_path, "format_minor", 1);
    pvsbake::Bake old;
    test::load_ok(old, old_path);
    EXPECT_EQ(old.format_minor(), 1);
    for (uint32_t c = 0; c < old.cell_count(); ++c) {
        EXPECT_EQ(old.occluder_count(c), 0u);
        EXPECT_TRUE(old.occluders(c).empty());
    }
    test::expect_loaded_equals(old, bake);
    // And a bake made without occluders (no /occluders group at all).
    {
        const hid_t f = H5Fopen(old_path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(f, 0);
        ASSERT_GE(H5Ldelete(f, "/occluders", H5P_DEFAULT), 0);
        H5Fclose(f);
    }
    test::load_ok(old, old_path);
    EXPECT_EQ(old.occluder_count(0), 0u);
}

// Damaged ranked occluders are refused at load with a message naming the dataset.
TEST(RuntimeLoaderStatus, DamagedRankedOccludersAreCorrupt) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, test::coherent_bake(30, {3, 2, 2}, false, false, 1));
    struct Patch {
        const char* dataset;
        hid_t type;
        uint32_t index;
        float value;
        const char* needle;
    };
    for (const Patch& p :
         {Patch{"/occluders/ranked_box", H5T_NATIVE_FLOAT, 1, 6.0f,
                "/occluders/ranked_box[1] = 6 is not a box index below 6"},
          Patch{"/occluders/ranked_box", H5T_NATIVE_FLOAT, 0, 1.0f, "not proven"},
          Patch{"/occluders/ranked_offsets", H5T_NATIVE_FLOAT, 3, 0.0f,
                "/occluders/ranked_offsets[3] decreases"},
          Patch{"/occluders/ranked_score", H5T_NATIVE_FLOAT, 0, NAN, "/occluders/ranked_score[0]"},
          Patch{"/occluders/ranked_score", H5T_NATIVE_FLOAT, 2, 2.0f, "best first"},
          Patch{"/occluders/ranked_hidden_triangle_share", H5T_NATIVE_FLOAT, 0, -0.5f,
                "/occluders/ranked_hidden_triangle_share[0]"},
          Patch{"/occluders/proven", H5T_NATIVE_FLOAT, 0, 0.0f, "not proven"}}) {
        SCOPED_TRACE(p.dataset);
        const std::string path = dir.file("bad.h5");
        fs::copy_file(good, path, fs::copy_options::overwrite_existing);
        const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const hid_t ds = H5Dopen2(f, p.dataset, H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        const hid_t space = H5Dget_space(ds);
        const hsize_t at = p.index, one = 1;
        H5Sselect_hyperslab(space, H5S_SELECT_SET, &at, nullptr, &one, nullptr);
        const hid_t mem = H5Screate_simple(1, &one, nullptr);
        EXPECT_GE(H5Dwrite(ds, p.type, mem, space, H5P_DEFAULT, &p.value), 0);
        H5Sclose(mem);
        H5Sclose(space);
        H5Dclose(ds);
        H5Fclose(f);
        expect_status(path, pvsbake::Status::kCorrupt, p.needle);
    }
}

// HDF5 1.10.8 trusts a chunk's filter mask and size: a chunk whose mask says its deflate was skipped, or an
// unfiltered chunk shorter than a chunk, made H5Dread copy a whole chunk out of the few bytes it read (the
// fuzz test found it under AddressSanitizer). Both are refused at load.
TEST(RuntimeLoaderStatus, ChunksStoredWithoutTheirFiltersAreCorrupt) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, test::coherent_bake(30, {3, 2, 2}, false, false, 1));
    const std::string path = dir.file("bad.h5");
    const std::vector<uint8_t> junk(20, 0x3f);
    const hsize_t origin[1] = {0};
    // A dataset rewritten deflated whose chunk's mask says "deflate skipped" (bit 0): 20 raw bytes for a
    // longer chunk (the writer stores the ranked measures plain; the rule is the same for every dataset).
    fs::copy_file(good, path, fs::copy_options::overwrite_existing);
    {
        const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const hid_t old = H5Dopen2(f, "/occluders/ranked_score", H5P_DEFAULT);
        const hid_t space = H5Dget_space(old);
        hsize_t n = 0;
        H5Sget_simple_extent_dims(space, &n, nullptr);
        H5Dclose(old);
        ASSERT_GE(H5Ldelete(f, "/occluders/ranked_score", H5P_DEFAULT), 0);
        const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
        H5Pset_chunk(dcpl, 1, &n);
        H5Pset_deflate(dcpl, 6);
        const hid_t ds =
            H5Dcreate2(f, "/occluders/ranked_score", H5T_IEEE_F32LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        ASSERT_GE(H5Dwrite_chunk(ds, H5P_DEFAULT, 1, origin, junk.size(), junk.data()), 0);
        H5Dclose(ds);
        H5Pclose(dcpl);
        H5Sclose(space);
        H5Fclose(f);
    }
    expect_status(path, pvsbake::Status::kCorrupt,
                  "/occluders/ranked_score has a chunk stored without its filters");
    // An unfiltered chunked dataset whose one chunk is short.
    fs::copy_file(good, path, fs::copy_options::overwrite_existing);
    {
        const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const hid_t old = H5Dopen2(f, "/occluders/ranked_score", H5P_DEFAULT);
        const hid_t space = H5Dget_space(old);
        hsize_t n = 0;
        H5Sget_simple_extent_dims(space, &n, nullptr);
        H5Dclose(old);
        ASSERT_GT(n * 4, junk.size());
        ASSERT_GE(H5Ldelete(f, "/occluders/ranked_score", H5P_DEFAULT), 0);
        const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
        H5Pset_chunk(dcpl, 1, &n);
        const hid_t ds =
            H5Dcreate2(f, "/occluders/ranked_score", H5T_IEEE_F32LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        ASSERT_GE(H5Dwrite_chunk(ds, H5P_DEFAULT, 0, origin, junk.size(), junk.data()), 0);
        H5Dclose(ds);
        H5Pclose(dcpl);
        H5Sclose(space);
        H5Fclose(f);
    }
    expect_status(path, pvsbake::Status::kCorrupt, "/occluders/ranked_score stores a chunk of 20 bytes");
}

// ---------------------------------------------------------------------------------------------------------
// The PVS code.

TEST(RowCode, RoundTripsRandomRowsOfEveryDensity) {
    std::mt19937 rng(17);
    for (uint32_t objects : {0u, 1u, 5u, 8u, 9u, 64u, 100u, 1000u, 3000u}) {
        for (double density : {0.0, 0.01, 0.1, 0.5, 0.97, 1.0}) {
            const uint32_t row_bytes = (objects + 7) / 8;
            const uint32_t rows = 40;
            std::vector<uint8_t> data(size_t(rows) * row_bytes, 0);
            std::bernoulli_distribution bit(density), keep(0.9);
            for (uint32_t r = 0; r < rows; ++r) {
                for (uint32_t o = 0; o < objects; ++o) {
                    const bool base = r > 0 && keep(rng)
                                          ? (data[size_t(r - 1) * row_bytes + o / 8] >> (o % 8)) & 1
                                          : bit(rng);  // rows like their predecessor
                    if (base) data[size_t(r) * row_bytes + o / 8] |= uint8_t(1u << (o % 8));
                }
            }
            pvsbake::detail::RowCode code =
                pvsbake::detail::encode_rows(data.data(), rows, row_bytes, objects);
            ASSERT_EQ(code.offsets.size(), rows + 1u);
            const size_t size = code.code.size();
            code.code.resize(size + pvsbake::detail::code_padding(objects), 0);
            ASSERT_EQ(
                pvsbake::detail::check_row_code(code.code.data(), size, code.offsets.data(), rows, objects),
                "");
            std::vector<uint8_t> row(row_bytes);
            for (uint32_t r = 0; r < rows; ++r) {
                pvsbake::detail::decode_row(code.code.data(), code.offsets.data(), r, objects, row.data(),
                                            row_bytes);
                ASSERT_TRUE(std::equal(row.begin(), row.end(), data.begin() + ptrdiff_t(r) * row_bytes))
                    << objects << " objects, density " << density << ", row " << r;
            }
        }
    }
}

// Damaged code is refused, or (when the damage still makes a sound code) decodes to indices in range.
TEST(RowCode, DamagedCodeIsRefusedOrStaysInRange) {
    std::mt19937 rng(5);
    const uint32_t objects = 300, row_bytes = 38, rows = 30;
    std::vector<uint8_t> data(size_t(rows) * row_bytes);
    for (uint8_t& b : data) b = uint8_t(rng() & rng() & rng());
    data[size_t(rows) * row_bytes - 1] &= 0x0f;  // objects 300..303 do not exist
    for (uint32_t r = 0; r < rows; ++r) data[size_t(r) * row_bytes + row_bytes - 1] &= 0x0f;
    const pvsbake::detail::RowCode good = pvsbake::detail::encode_rows(data.data(), rows, row_bytes, objects);
    int refused = 0, refused_in_full = 0;
    const int cases = test::in_ci() ? 2000 : 20000;
    for (int i = 0; i < cases; ++i) {
        std::vector<uint8_t> code = good.code;
        std::vector<uint32_t> offsets = good.offsets;
        const int flips = 1 + int(rng() % 3);
        for (int k = 0; k < flips; ++k) {
            if (rng() % 8 == 0) {
                offsets[rng() % offsets.size()] += uint32_t(int(rng() % 5) - 2);
            } else {
                code[rng() % code.size()] ^= uint8_t(1u << (rng() % 8));
            }
        }
        const size_t size = code.size();
        code.resize(size + pvsbake::detail::code_padding(objects), 0);
        code.shrink_to_fit();  // so that a read past the padding is a read past the allocation (sanitizers)
        // The heads' check (format 1.4, with the checksum) passes more damage than the full one; the
        // bounded decoders keep even that in range.
        if (!pvsbake::detail::check_row_heads(code.data(), size, offsets.data(), rows, objects).empty()) {
            ++refused;
            continue;
        }
        std::vector<uint8_t> row(row_bytes);
        for (uint32_t r = 0; r < rows; ++r) {
            pvsbake::detail::decode_row(code.data(), offsets.data(), r, objects, row.data(), row_bytes);
            ASSERT_EQ(row.back() & 0xf0, 0) << "case " << i;  // nothing beyond object 299
        }
        if (!pvsbake::detail::check_row_code(code.data(), size, offsets.data(), rows, objects).empty())
            ++refused_in_full;
    }
    EXPECT_GT(refused + refused_in_full, cases / 2);
}

// Rows whose heads are sound but whose bits are anything at all (what a file made to pass the checksum
// could hold): the bounded decoder returns increasing indices below the object count and reads only the
// code and its padding.
TEST(RowCode, BoundedDecodingOfArbitraryBitsStaysInRange) {
    std::mt19937 rng(23);
    for (uint32_t objects : {1u, 7u, 64u, 300u, 2636u}) {
        for (int t = 0; t < (test::in_ci() ? 300 : 3000); ++t) {
            std::vector<uint8_t> code;
            std::vector<uint32_t> offsets;
            const uint32_t rows = 1 + rng() % 6;
            for (uint32_t r = 0; r < rows; ++r) {
                offsets.push_back(uint32_t(code.size()));
                const uint32_t k = rng() % 25, count = objects == 0 ? 0 : uint32_t(rng() % (objects + 1));
                const uint32_t ref = r > 0 && rng() % 2 ? 1 + uint32_t(rng() % r) : 0;
                for (uint32_t v : {ref, count << 5 | k}) {
                    for (; v >= 0x80; v >>= 7) code.push_back(uint8_t(v | 0x80));
                    code.push_back(uint8_t(v));
                }
                // As many bits as the heads' check asks for, each byte dense, sparse or random.
                const uint64_t bytes = (uint64_t(count) * (1 + k) + 7) / 8 + rng() % 4;
                const int style = int(rng() % 3);
                for (uint64_t b = 0; b < bytes; ++b)
                    code.push_back(style == 0 ? 0 : style == 1 ? uint8_t(1u << (rng() % 8)) : uint8_t(rng()));
            }
            offsets.push_back(uint32_t(code.size()));
            const size_t size = code.size();
            code.resize(size + pvsbake::detail::code_padding(objects), 0);
            code.shrink_to_fit();
            std::string bad =
                pvsbake::detail::check_row_heads(code.data(), size, offsets.data(), rows, objects);
            if (!bad.empty()) continue;  // a reference to a row that is not a key row
            for (uint32_t r = 0; r < rows; ++r) {
                const uint8_t* p = code.data() + offsets[r];
                pvsbake::detail::read_varint(p);
                const uint32_t head = pvsbake::detail::read_varint(p);
                pvsbake::detail::GapReader g(p, head >> 5, head & 31, objects);
                int64_t last = -1;
                for (uint32_t i = g.next(); i != pvsbake::detail::kEnd; i = g.next()) {
                    ASSERT_LT(i, objects);
                    ASSERT_GT(int64_t(i), last);
                    last = i;
                }
                ASSERT_EQ(g.next(), pvsbake::detail::kEnd);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// The C API.

struct Visits {
    std::vector<uint32_t> objects;
};

void record(void* user, uint32_t object) {
    static_cast<Visits*>(user)->objects.push_back(object);
}

TEST(RuntimeLoaderC, MirrorsTheCppApi) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(77, {4, 3, 2}, false, true, 6);
    const std::string path = dir.file("c.h5");
    pvsbake::Bake cpp;
    test::write_and_load(bake, path, cpp);

    char message[16];
    pvsbake_bake* b = nullptr;
    ASSERT_EQ(pvsbake_load(path.c_str(), &b, message, sizeof message), PVSBAKE_OK);
    ASSERT_NE(b, nullptr);
    EXPECT_STREQ(message, "");
    EXPECT_EQ(pvsbake_cell_count(b), cpp.cell_count());
    EXPECT_EQ(pvsbake_object_count(b), cpp.object_count());
    EXPECT_EQ(pvsbake_words_per_row(b), cpp.words_per_row());
    EXPECT_EQ(pvsbake_total_triangles(b), cpp.total_triangles());
    EXPECT_EQ(pvsbake_is_conservative(b), cpp.is_conservative() ? 1 : 0);
    EXPECT_STREQ(pvsbake_mode(b), bake.mode.c_str());
    EXPECT_STREQ(pvsbake_world_path(b), bake.world_path.c_str());
    int major = 0, minor = -1;
    pvsbake_format_version(b, &major, &minor);
    EXPECT_EQ(major, 1);
    EXPECT_EQ(minor, kBakeFormatMinor);
    uint32_t ranked = 0;
    for (uint32_t c = 0; c <= pvsbake_cell_count(b); ++c) {
        ASSERT_EQ(pvsbake_occluder_count(b, c), cpp.occluder_count(c));
        pvsbake_ranked_occluder r;
        for (uint32_t k = 0; k < cpp.occluder_count(c); ++k, ++ranked) {
            ASSERT_EQ(pvsbake_occluder(b, c, k, &r), 1);
            const pvsbake::RankedOccluder& w = cpp.occluders(c)[k];
            EXPECT_EQ(std::memcmp(r.box, w.box.min, sizeof(float) * 3), 0);
            EXPECT_EQ(std::memcmp(r.box + 3, w.box.max, sizeof(float) * 3), 0);
            EXPECT_EQ(r.score, w.score);
            EXPECT_EQ(r.solid_angle_sr, w.solid_angle_sr);
            EXPECT_EQ(r.hidden_objects, w.hidden_objects);
            EXPECT_EQ(r.hidden_triangle_share, w.hidden_triangle_share);
        }
        r.score = -7.0f;
        EXPECT_EQ(pvsbake_occluder(b, c, cpp.occluder_count(c), &r), 0);
        EXPECT_EQ(r.score, -7.0f);  // untouched
        EXPECT_EQ(pvsbake_occluder(b, c, 0, nullptr), 0);
    }
    EXPECT_GT(ranked, 0u);
    EXPECT_EQ(pvsbake_occluder_count(nullptr, 0), 0u);
    for (uint32_t c = 0; c < pvsbake_cell_count(b); ++c) {
        Visits v;
        const uint32_t n = pvsbake_visit_visible(b, c, record, &v);
        std::vector<uint32_t> want;
        cpp.for_each_visible(c, [&](uint32_t o) { want.push_back(o); });
        ASSERT_EQ(v.objects, want);
        ASSERT_EQ(n, want.size());
        std::vector<uint32_t> some(3, 12345);
        EXPECT_EQ(pvsbake_visible_objects(b, c, some.data(), some.size()), n);
        for (size_t i = 0; i < std::min<size_t>(3, n); ++i) EXPECT_EQ(some[i], want[i]);
        std::vector<uint64_t> words(pvsbake_words_per_row(b));
        EXPECT_EQ(pvsbake_fill_bitset(b, c, words.data(), words.size()), n);
        EXPECT_EQ(pvsbake_fill_bitset(b, c, words.data(), words.size() - 1), UINT32_MAX);
        for (uint32_t o : want) EXPECT_EQ(pvsbake_is_visible(b, c, o), 1);
        float box[6];
        ASSERT_EQ(pvsbake_cell_bounds(b, c, box), 1);
        EXPECT_EQ(box[3], cpp.cell_bounds(c).max[0]);
        EXPECT_EQ(
            pvsbake_find_cell(b, 0.5f * (box[0] + box[3]), 0.5f * (box[1] + box[4]),
                              0.5f * (box[2] + box[5])),
            cpp.find_cell(0.5f * (box[0] + box[3]), 0.5f * (box[1] + box[4]), 0.5f * (box[2] + box[5])));
        EXPECT_EQ(pvsbake_in_eye_space(b, box[0], box[1], box[2]) == 1,
                  cpp.in_eye_space(box[0], box[1], box[2]));
    }
    for (uint32_t o = 0; o < pvsbake_object_count(b); ++o) {
        EXPECT_STREQ(pvsbake_object_name(b, o), bake.objects[o].name.c_str());
        EXPECT_EQ(pvsbake_object_triangles(b, o), bake.objects[o].triangle_count);
        EXPECT_EQ(pvsbake_object_flags(b, o), bake.objects[o].flags);
        float box[6];
        ASSERT_EQ(pvsbake_object_bounds(b, o, box), 1);
        EXPECT_EQ(box[0], bake.objects[o].bounds.min.x);
    }
    ASSERT_EQ(pvsbake_figure_count(b), bake.figures.size());
    EXPECT_STREQ(pvsbake_figure_name(b, 0), "cells");
    double value = 0;
    EXPECT_EQ(pvsbake_find_figure(b, "objects", &value), 1);
    EXPECT_EQ(value, 77.0);
    EXPECT_EQ(pvsbake_find_figure(b, "nope", &value), 0);
    EXPECT_STREQ(pvsbake_find_parameter(b, "bake.mode"), bake.mode.c_str());
    EXPECT_EQ(pvsbake_parameter_key(b, 99), nullptr);
    pvsbake_pvs_stats stats;
    ASSERT_EQ(pvsbake_get_pvs_stats(b, &stats), 1);
    EXPECT_EQ(stats.bytes_code, cpp.pvs_stats().bytes_code);
    // Out of range and null handles.
    EXPECT_EQ(pvsbake_visit_visible(b, pvsbake_cell_count(b), record, nullptr), 0u);
    EXPECT_STREQ(pvsbake_object_name(b, 1000), "");
    EXPECT_EQ(pvsbake_cell_bounds(b, 1000, nullptr), 0);
    pvsbake_free(b);
    EXPECT_EQ(pvsbake_cell_count(nullptr), 0u);
    EXPECT_EQ(pvsbake_find_cell(nullptr, 0, 0, 0), -1);
    EXPECT_EQ(pvsbake_in_eye_space(nullptr, 0, 0, 0), 0);
    EXPECT_STREQ(pvsbake_mode(nullptr), "");
    pvsbake_free(nullptr);

    // Failures: the message names the file (shortened to the buffer), the handle stays NULL.
    b = reinterpret_cast<pvsbake_bake*>(&value);
    EXPECT_EQ(pvsbake_load(dir.file("missing.h5").c_str(), &b, message, sizeof message),
              PVSBAKE_FILE_MISSING);
    EXPECT_EQ(b, nullptr);
    EXPECT_EQ(std::string(message), dir.file("missing.h5").substr(0, sizeof message - 1));
    EXPECT_EQ(pvsbake_load(nullptr, &b, message, sizeof message), PVSBAKE_INVALID_ARGUMENT);
    EXPECT_EQ(pvsbake_load(path.c_str(), nullptr, nullptr, 0), PVSBAKE_INVALID_ARGUMENT);
    EXPECT_STREQ(pvsbake_status_name(PVSBAKE_CORRUPT), "corrupt");
}

// ---------------------------------------------------------------------------------------------------------
// The example program.

TEST(RuntimeLoaderExample, WalksThroughASmallBake) {
    test::TempDir dir;
    const std::string path = dir.file("walk.h5");
    write_bake_file(path, test::coherent_bake(60, {6, 2, 5}, false, true, 2));
    const std::string out = dir.file("out.txt");
    const std::string cmd = std::string(PVSBAKE_WALKTHROUGH) + " " + path + " --frames 48 > " + out;
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const std::string text = test::read_file(out);
    EXPECT_NE(text.find("loaded " + path), std::string::npos) << text;
    EXPECT_NE(text.find("frame   47"), std::string::npos) << text;
    EXPECT_NE(text.find("total: 48 frames"), std::string::npos) << text;
    EXPECT_NE(text.find("moving objects: 300; the occluders culled"), std::string::npos) << text;
    EXPECT_NE(
        std::system((std::string(PVSBAKE_WALKTHROUGH) + " " + dir.file("none.h5") + " 2> /dev/null").c_str()),
        0);
    // The same bake as a runtime file (the C99 runtime and its culler): the same frames, the same culling.
    const std::string level = dir.file("walk.pvsr"), out2 = dir.file("out2.txt");
    test::write_file(level, runtime_file_bytes(path));
    ASSERT_EQ(std::system((std::string(PVSBAKE_WALKTHROUGH) + " " + level + " --frames 48 > " + out2).c_str()), 0);
    const std::string text2 = test::read_file(out2);
    EXPECT_NE(text2.find("(runtime file)"), std::string::npos) << text2;
    const auto frames_of = [](const std::string& t) {  // everything from the first frame, timings cut
        std::string s = t.substr(t.find("frame    0"));
        for (size_t at = s.find(" at "); at != std::string::npos; at = s.find(" at ", at + 1)) {
            const size_t end = s.find(" a frame", at);
            if (end != std::string::npos) s.erase(at, end - at);
        }
        return s;
    };
    EXPECT_EQ(frames_of(text2), frames_of(text));
}

}  // namespace
}  // namespace pvs

namespace pvsbake::detail {
namespace {

// Row offsets and cell rows drop to 16 bits when every value fits, and keep 32 when one does not.
TEST(IndexArray, NarrowWhenEveryValueFitsWideOtherwise) {
    for (const uint32_t top : {0u, 65535u, 65536u, 4000000000u}) {
        std::vector<uint32_t> values = {7, top, 0, 12345};
        const std::vector<uint32_t> copy = values;
        IndexArray a;
        a.assign(std::move(values));
        ASSERT_EQ(a.size(), copy.size());
        for (size_t i = 0; i < copy.size(); ++i) EXPECT_EQ(a[i], copy[i]) << top;
        EXPECT_EQ(a.bytes(), copy.size() * (top <= 65535u ? 2u : 4u)) << top;
    }
    IndexArray empty;
    empty.assign({});
    EXPECT_TRUE(empty.empty());
}

}  // namespace
}  // namespace pvsbake::detail
