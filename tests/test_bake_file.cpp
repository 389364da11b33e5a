// SPDX-License-Identifier: MIT
// Tests io/bake_file: write-then-read is lossless for every field (UTF-8 names, deduped rows, object counts
// around byte and word edges, empty sets, dropped grid cells), the file is byte-identical for the same
// bake, damaged or foreign files are refused with a pvs::Error (kBadInput) naming the file and what is
// wrong, and a failed write leaves no file behind and the old file untouched.
#include "io/bake_file.h"

#include "core/error.h"
#include "tests/horizon_fixture.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace pvs {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------------
// Building bakes.

// A voxel mask with every `every`-th voxel set (0: no mask: bits empty).
VoxelMask make_mask(glm::vec3 origin, float voxel_size_m, glm::ivec3 dims, int every) {
    VoxelMask m;
    m.origin = origin;
    m.voxel_size_m = voxel_size_m;
    m.dims = dims;
    if (every == 0) return m;
    const uint64_t n = m.count();
    m.bits.assign(size_t((n + 63) / 64), 0);
    for (uint64_t i = 0; i < n; i += uint64_t(every)) m.bits[i / 64] |= uint64_t(1) << (i % 64);
    return m;
}

// A grid of dims cells where every `drop_every`-th grid position has no cell (0: none dropped), objects
// with UTF-8 names, and a PVS whose rows repeat with period `distinct_rows` (0: random rows).
BakeData make_bake(uint32_t objects, glm::ivec3 dims, int drop_every, uint32_t distinct_rows, uint32_t seed) {
    BakeData b;
    b.tool_version = "pvsbake 0.1.0 (test)";
    b.world_path = "worlds/Stadt_Ü/town.glb";
    b.world_hash = "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08";
    b.mode = "conservative";
    b.conservative = true;
    b.parameters = {{"cells.cell_size_m", "2"},
                    {"bake.mode", "conservative"},
                    {"a key with spaces", ""},
                    {"verify.rays_per_cell", "4096"},
                    {"world", "worlds/Stadt_Ü/town.glb"}};
    const char* stems[] = {"Wall", "Tür_ü", "門_日本", "crate 🙂", ""};
    for (uint32_t i = 0; i < objects; ++i) {
        ObjectRecord o;
        o.name = std::string(stems[i % 5]) + "#" + std::to_string(i);
        const glm::vec3 lo(float(i), -0.5f * float(i), 0.25f);
        o.bounds = Aabb::of(lo, lo + glm::vec3(1.0f, 2.5f, 0.125f * float(i % 7 + 1)));
        o.triangle_count = 12 * i + 1;
        o.flags = i % 4;
        b.objects.push_back(o);
    }
    if (objects > 2) b.objects[2].bounds = Aabb::empty();  // infinities survive too

    CellSet& cells = b.cells;
    cells.kind = CellSet::Kind::kGrid;
    cells.origin = {-10.0f, 0.5f, 3.25f};
    cells.cell_size_m = 2.0f;
    cells.dims = dims;
    const size_t grid = size_t(dims.x) * size_t(dims.y) * size_t(dims.z);
    for (size_t g = 0; g < grid; ++g) {
        if (drop_every > 0 && g % size_t(drop_every) == 0) {
            cells.grid_to_cell.push_back(-1);
            continue;
        }
        const int ix = int(g % size_t(dims.x));
        const int iy = int(g / size_t(dims.x) % size_t(dims.y));
        const int iz = int(g / (size_t(dims.x) * size_t(dims.y)));
        const glm::vec3 lo = cells.origin + cells.cell_size_m * glm::vec3(ix, iy, iz);
        cells.grid_to_cell.push_back(int32_t(cells.cells.size()));
        cells.cells.push_back(Cell{Aabb::of(lo, lo + glm::vec3(cells.cell_size_m)), -1});
    }
    const uint32_t n_cells = uint32_t(cells.size());
    // View volume: every half-cell voxel of the grid; eye points: an odd-sized mask (105 voxels, not a
    // multiple of 8 or 64) with every third voxel set.
    cells.view = make_mask(cells.origin, cells.cell_size_m / 2, dims * 2, 1);
    cells.eyes = make_mask(cells.origin + 0.25f, 1.0f, {5, 3, 7}, 3);
    b.leak_path = {{0.5f, 1.0f, 2.0f}, {0.5f, 1.0f, 12.0f}, {-3.0f, 1.0f, 40.0f}};

    b.pvs = PvsSet::make(n_cells, objects);
    std::bernoulli_distribution bit(0.3);
    for (uint32_t c = 0; c < n_cells; ++c) {
        const uint32_t pattern = distinct_rows > 0 ? c % distinct_rows : c;
        std::mt19937 row_rng(seed * 7919u + pattern);
        for (uint32_t o = 0; o < objects; ++o) {
            if (bit(row_rng)) b.pvs.set(c, o);
        }
    }

    b.figures = {{"cells", double(n_cells)},
                 {"objects", double(objects)},
                 {"mean_visible", 0.3125},
                 {"huge", 1e300},
                 {"tiny", -4.9e-324}};
    b.run.parameters = {{"run.threads", "2"}};
    b.run.figures = {{"conservative_seconds", 11.5}, {"peak_memory_mb", 512.0}};
    b.run.timings_s = {{"load", 0.25}, {"cells", 1.5}, {"solve", 12.75}, {"write", 0.0625}};
    VerificationRecord& v = b.verification;
    v.ran = true;
    v.figures = {{"rays", 1e6}, {"misses", 2.0}, {"overestimation", 1.75}};
    for (uint32_t c = 0; c < n_cells; ++c) v.cell_sampled_visible.push_back(c * 3 % 17);
    if (n_cells > 0 && objects > 0) {
        v.misses.push_back({0, objects - 1, {1.0f, 2.0f, 3.0f}, {0.0f, 0.6f, 0.8f}, 12.5f, 0.0004f});
        v.misses.push_back({n_cells - 1, 0, {-1.0f, 0.5f, 7.0f}, {1.0f, 0.0f, 0.0f}, 0.001f});
    }
    return b;
}

// The small bake docs/FORMAT.md shows in its h5dump example.
BakeData make_example_bake() {
    BakeData b = make_bake(3, {2, 1, 2}, 4, 2, 1);
    b.objects[0].name = "wall_north";
    b.objects[1].name = "door_ü";
    b.objects[2].name = "crate";
    b.objects[2].bounds = Aabb::of({0.5f, 0.0f, 0.5f}, {1.5f, 1.0f, 1.5f});
    b.tool_version = "pvsbake 0.1.0";
    b.world_path = "worlds/town.glb";
    b.mode = "sampled";
    b.conservative = false;
    b.parameters = {{"cells.cell_size_m", "2"}, {"bake.mode", "sampled"}};
    b.figures = {{"cells", 3.0}, {"mean_visible", 1.5}};
    b.run.parameters = {{"run.threads", "0"}};
    b.run.figures = {{"peak_memory_mb", 42.0}};
    b.run.timings_s = {{"solve", 0.5}, {"write", 0.01}};
    b.verification.figures = {{"rays", 3000.0}, {"misses", 1.0}};
    b.verification.misses.resize(1);
    // Cells 0 and 2 see the same objects: two distinct rows for three cells.
    b.pvs = PvsSet::make(3, 3);
    for (uint32_t c : {0u, 2u}) {
        b.pvs.set(c, 0);
        b.pvs.set(c, 2);
    }
    b.pvs.set(1, 1);
    return b;
}

void expect_same_values(const NamedValues& a, const NamedValues& b) {
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].first, b[i].first);
        EXPECT_EQ(a[i].second, b[i].second) << a[i].first;
    }
}

void expect_same(const BakeData& a, const BakeData& b) {
    EXPECT_EQ(a.format_major, b.format_major);
    EXPECT_EQ(a.format_minor, b.format_minor);
    EXPECT_EQ(a.tool_version, b.tool_version);
    EXPECT_EQ(a.world_path, b.world_path);
    EXPECT_EQ(a.world_hash, b.world_hash);
    EXPECT_EQ(a.mode, b.mode);
    EXPECT_EQ(a.conservative, b.conservative);
    EXPECT_EQ(a.parameters, b.parameters);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (size_t i = 0; i < a.objects.size(); ++i) {
        EXPECT_EQ(a.objects[i].name, b.objects[i].name);
        EXPECT_EQ(a.objects[i].bounds, b.objects[i].bounds) << i;
        EXPECT_EQ(a.objects[i].triangle_count, b.objects[i].triangle_count);
        EXPECT_EQ(a.objects[i].flags, b.objects[i].flags);
    }
    EXPECT_EQ(a.cells.kind, b.cells.kind);
    EXPECT_EQ(a.cells.origin, b.cells.origin);
    EXPECT_EQ(a.cells.cell_size_m, b.cells.cell_size_m);
    EXPECT_EQ(a.cells.dims, b.cells.dims);
    EXPECT_EQ(a.cells.grid_to_cell, b.cells.grid_to_cell);
    EXPECT_TRUE(a.cells.view == b.cells.view);
    EXPECT_TRUE(a.cells.eyes == b.cells.eyes);
    EXPECT_EQ(a.leak_path, b.leak_path);
    ASSERT_EQ(a.cells.size(), b.cells.size());
    for (size_t i = 0; i < a.cells.size(); ++i) {
        EXPECT_EQ(a.cells.cells[i].bounds, b.cells.cells[i].bounds);
        EXPECT_EQ(a.cells.cells[i].parent, b.cells.cells[i].parent);
    }
    EXPECT_EQ(a.ranked.offsets, b.ranked.offsets);
    ASSERT_EQ(a.ranked.entries.size(), b.ranked.entries.size());
    for (size_t k = 0; k < a.ranked.entries.size(); ++k) {
        const RankedOccluder &x = a.ranked.entries[k], &y = b.ranked.entries[k];
        EXPECT_EQ(x.box, y.box) << k;
        EXPECT_EQ(x.score, y.score) << k;
        EXPECT_EQ(x.solid_angle_sr, y.solid_angle_sr) << k;
        EXPECT_EQ(x.hidden_objects, y.hidden_objects) << k;
        EXPECT_EQ(x.hidden_triangle_share, y.hidden_triangle_share) << k;
    }
    EXPECT_EQ(a.pvs.cell_count, b.pvs.cell_count);
    EXPECT_EQ(a.pvs.object_count, b.pvs.object_count);
    EXPECT_EQ(a.pvs.words_per_row, b.pvs.words_per_row);
    EXPECT_TRUE(a.pvs == b.pvs);
    expect_same_values(a.figures, b.figures);
    EXPECT_EQ(a.run.parameters, b.run.parameters);
    expect_same_values(a.run.figures, b.run.figures);
    expect_same_values(a.run.timings_s, b.run.timings_s);
    EXPECT_EQ(a.verification.ran, b.verification.ran);
    expect_same_values(a.verification.figures, b.verification.figures);
    EXPECT_EQ(a.verification.cell_sampled_visible, b.verification.cell_sampled_visible);
    ASSERT_EQ(a.verification.misses.size(), b.verification.misses.size());
    for (size_t i = 0; i < a.verification.misses.size(); ++i) {
        const Miss& x = a.verification.misses[i];
        const Miss& y = b.verification.misses[i];
        EXPECT_EQ(x.cell, y.cell);
        EXPECT_EQ(x.object, y.object);
        EXPECT_EQ(x.eye, y.eye);
        EXPECT_EQ(x.direction, y.direction);
        EXPECT_EQ(x.distance_m, y.distance_m);
        EXPECT_EQ(x.opening_width_m, y.opening_width_m);
    }
}

BakeData round_trip(const BakeData& bake, const test::TempDir& dir, const std::string& name = "bake.h5") {
    const std::string path = dir.file(name);
    write_bake_file(path, bake);
    return read_bake_file(path);
}

// ---------------------------------------------------------------------------------------------------------
// Looking into and patching files with the HDF5 C API directly.

class H5File {
public:
    H5File(const std::string& path, bool write) {
        id_ = H5Fopen(path.c_str(), write ? H5F_ACC_RDWR : H5F_ACC_RDONLY, H5P_DEFAULT);
    }
    ~H5File() {
        if (id_ >= 0) H5Fclose(id_);
    }
    hid_t id() const { return id_; }

private:
    hid_t id_ = -1;
};

// An open attribute of an object. The object is opened first: in HDF5 1.10.8 an attribute opened with
// H5Aopen_by_name(file, "/group", ...) cannot be written ("can't locate open attribute?").
class H5Attr {
public:
    H5Attr(const H5File& f, const std::string& object, const std::string& name) {
        obj_ = H5Oopen(f.id(), object.c_str(), H5P_DEFAULT);
        id_ = obj_ >= 0 ? H5Aopen(obj_, name.c_str(), H5P_DEFAULT) : -1;
    }
    ~H5Attr() {
        if (id_ >= 0) H5Aclose(id_);
        if (obj_ >= 0) H5Oclose(obj_);
    }
    hid_t id() const { return id_; }

private:
    hid_t obj_ = -1;
    hid_t id_ = -1;
};

int64_t int_attr(const std::string& path, const std::string& object, const std::string& name) {
    H5File f(path, false);
    H5Attr a(f, object, name);
    int64_t value = -12345;
    EXPECT_GE(a.id(), 0) << object << " " << name;
    EXPECT_GE(H5Aread(a.id(), H5T_NATIVE_INT64, &value), 0);
    return value;
}

double double_attr(const std::string& path, const std::string& object, const std::string& name) {
    H5File f(path, false);
    H5Attr a(f, object, name);
    double value = -12345.0;
    EXPECT_GE(a.id(), 0) << object << " " << name;
    EXPECT_GE(H5Aread(a.id(), H5T_NATIVE_DOUBLE, &value), 0);
    return value;
}

// A string attribute as the writer stores it: fixed-length, NUL-terminated, UTF-8.
std::string string_attr(const std::string& path, const std::string& object, const std::string& name) {
    H5File f(path, false);
    H5Attr a(f, object, name);
    EXPECT_GE(a.id(), 0) << object << " " << name;
    const hid_t t = H5Aget_type(a.id());
    EXPECT_EQ(H5Tget_class(t), H5T_STRING);
    EXPECT_EQ(H5Tis_variable_str(t), 0);
    EXPECT_EQ(H5Tget_cset(t), H5T_CSET_UTF8);
    std::string s(H5Tget_size(t), '\0');
    EXPECT_GE(H5Aread(a.id(), t, s.data()), 0);
    H5Tclose(t);
    return s.substr(0, s.find('\0'));
}

void patch_int_attr(const std::string& path, const std::string& object, const std::string& name, int value) {
    H5File f(path, true);
    ASSERT_GE(f.id(), 0);
    H5Attr a(f, object, name);
    ASSERT_GE(a.id(), 0);
    ASSERT_GE(H5Awrite(a.id(), H5T_NATIVE_INT, &value), 0);
}

// Writes one element of a 1-D or 2-D dataset, `index` counted in row-major order (mem_type: the element
// type in memory; for a compound, a type with only the members to change).
void patch_element(const std::string& path, const std::string& dataset, hsize_t index, hid_t mem_type,
                   const void* value) {
    H5File f(path, true);
    ASSERT_GE(f.id(), 0);
    const hid_t ds = H5Dopen2(f.id(), dataset.c_str(), H5P_DEFAULT);
    ASSERT_GE(ds, 0) << dataset;
    const hid_t space = H5Dget_space(ds);
    const hsize_t one = 1;
    hsize_t dims[2] = {0, 0};
    const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
    ASSERT_TRUE(rank == 1 || rank == 2) << dataset;
    const hsize_t start[2] = {rank == 2 ? index / dims[1] : index, rank == 2 ? index % dims[1] : 0};
    const hsize_t count[2] = {1, 1};
    ASSERT_GE(H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr), 0);
    const hid_t mem_space = H5Screate_simple(1, &one, nullptr);
    ASSERT_GE(H5Dwrite(ds, mem_type, mem_space, space, H5P_DEFAULT, value), 0);
    H5Sclose(mem_space);
    H5Sclose(space);
    H5Dclose(ds);
}

// A 1-D uint32 dataset, whole.
std::vector<uint32_t> read_u32_dataset(const std::string& path, const std::string& dataset) {
    H5File f(path, false);
    std::vector<uint32_t> out;
    const hid_t ds = H5Dopen2(f.id(), dataset.c_str(), H5P_DEFAULT);
    if (ds < 0) return out;
    const hid_t space = H5Dget_space(ds);
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, nullptr);
    out.resize(size_t(n));
    if (n > 0) H5Dread(ds, H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
    H5Sclose(space);
    H5Dclose(ds);
    return out;
}

void patch_byte(const std::string& path, const std::string& dataset, hsize_t row, hsize_t column,
                uint8_t value) {
    H5File f(path, true);
    const hid_t ds = H5Dopen2(f.id(), dataset.c_str(), H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    const hid_t space = H5Dget_space(ds);
    const hsize_t start[2] = {row, column}, count[2] = {1, 1};
    ASSERT_GE(H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr), 0);
    const hid_t mem_space = H5Screate_simple(2, count, nullptr);
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_UINT8, mem_space, space, H5P_DEFAULT, &value), 0);
    H5Sclose(mem_space);
    H5Sclose(space);
    H5Dclose(ds);
}

// read_bake_file(path) must throw pvs::Error of kBadInput whose message names the path and contains every
// one of `needles`.
void expect_bad_input(const std::string& path, const std::vector<std::string>& needles) {
    try {
        read_bake_file(path);
        ADD_FAILURE() << path << ": read without error";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << msg;
        EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
        for (const std::string& n : needles)
            EXPECT_NE(msg.find(n), std::string::npos) << "'" << n << "' in " << msg;
    }
}

// A copy of the good file at `path` with element `index` of `dataset` patched to `value` is refused as
// expect_bad_input says.
void expect_patch_refused(const std::string& good, const std::string& path, const char* dataset,
                          hsize_t index, hid_t type, const void* value,
                          const std::vector<std::string>& needles) {
    SCOPED_TRACE(dataset);
    fs::copy_file(good, path, fs::copy_options::overwrite_existing);
    patch_element(path, dataset, index, type, value);
    expect_bad_input(path, needles);
}

std::vector<std::string> folder_entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder)) names.push_back(e.path().filename().string());
    return names;
}

// ---------------------------------------------------------------------------------------------------------
// Round trips.

TEST(BakeFile, RoundTripIsLosslessAndDedupesRows) {
    test::TempDir dir;
    const BakeData bake = make_bake(200, {6, 5, 4}, 5, 7, 42);
    ASSERT_EQ(bake.cells.size(), 96u);
    const std::string path = dir.file("bake.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);

    EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 7);
    EXPECT_EQ(int_attr(path, "/pvs", "cell_count"), 96);
    EXPECT_EQ(int_attr(path, "/pvs", "object_count"), 200);
    EXPECT_EQ(int_attr(path, "/pvs", "bytes_raw"), 96 * 25);
    EXPECT_GT(int_attr(path, "/pvs", "bytes_stored"), 0);
    EXPECT_EQ(string_attr(path, "/", "format"), "pvsbake");
    EXPECT_EQ(int_attr(path, "/", "format_major"), kBakeFormatMajor);
    EXPECT_EQ(int_attr(path, "/", "format_minor"), kBakeFormatMinor);
    EXPECT_EQ(string_attr(path, "/", "pvs_kind"), "conservative");
    EXPECT_EQ(string_attr(path, "/cells", "kind"), "grid");
    // One attribute per parameter and per figure, next to the ordered datasets.
    EXPECT_EQ(string_attr(path, "/parameters", "world"), "worlds/Stadt_Ü/town.glb");
    EXPECT_EQ(string_attr(path, "/parameters", "a key with spaces"), "");
    EXPECT_EQ(double_attr(path, "/run/timings", "solve"), 12.75);
    EXPECT_EQ(string_attr(path, "/run/parameters", "run.threads"), "2");
    EXPECT_EQ(double_attr(path, "/run/figures", "peak_memory_mb"), 512.0);
    EXPECT_EQ(double_attr(path, "/verification/figures", "overestimation"), 1.75);
}

TEST(BakeFile, AllDistinctRowsAreAllStored) {
    test::TempDir dir;
    const BakeData bake = make_bake(100, {5, 4, 3}, 0, 0, 3);
    const std::string path = dir.file("bake.h5");
    write_bake_file(path, bake);
    expect_same(bake, read_bake_file(path));
    EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 60);
}

TEST(BakeFile, ObjectCountsAroundByteAndWordEdges) {
    test::TempDir dir;
    for (uint32_t objects : {1u, 7u, 8u, 9u, 63u, 64u, 65u, 127u, 128u, 200u}) {
        SCOPED_TRACE(objects);
        const BakeData bake = make_bake(objects, {3, 2, 2}, 0, 3, objects);
        const BakeData back = round_trip(bake, dir, std::to_string(objects) + "_objects.h5");
        expect_same(bake, back);
        if (objects > 0) {
            // The last object's bit survives in every row that has it.
            for (uint32_t c = 0; c < bake.pvs.cell_count; ++c) {
                EXPECT_EQ(back.pvs.test(c, objects - 1), bake.pvs.test(c, objects - 1));
            }
        }
    }
}

TEST(BakeFile, BitsBeyondTheObjectCountAreNotWritten) {
    test::TempDir dir;
    BakeData bake = make_bake(13, {2, 2, 1}, 0, 0, 5);
    BakeData dirty = bake;
    for (uint64_t& w : dirty.pvs.words) w |= ~uint64_t(0) << 13;  // garbage past object 12
    const BakeData back = round_trip(dirty, dir);
    expect_same(bake, back);
}

TEST(BakeFile, ZeroCellsAndZeroObjects) {
    test::TempDir dir;
    {
        SCOPED_TRACE("no cells, no objects");
        const BakeData bake = make_bake(0, {0, 0, 0}, 0, 0, 1);
        const std::string path = dir.file("empty.h5");
        write_bake_file(path, bake);
        expect_same(bake, read_bake_file(path));
        EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 0);
    }
    {
        SCOPED_TRACE("cells but no objects");
        const BakeData bake = make_bake(0, {3, 2, 1}, 0, 0, 1);
        ASSERT_EQ(bake.cells.size(), 6u);
        const std::string path = dir.file("no_objects.h5");
        write_bake_file(path, bake);
        expect_same(bake, read_bake_file(path));
        EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 1);  // the one empty row
    }
    {
        SCOPED_TRACE("objects but no cells");
        const BakeData bake = make_bake(10, {4, 1, 1}, 1, 0, 1);  // every grid position dropped
        ASSERT_EQ(bake.cells.size(), 0u);
        expect_same(bake, round_trip(bake, dir, "no_cells.h5"));
    }
}

TEST(BakeFile, EmptyVerificationAndNoMisses) {
    test::TempDir dir;
    BakeData bake = make_bake(20, {3, 3, 3}, 0, 4, 9);
    bake.verification = VerificationRecord{};
    expect_same(bake, round_trip(bake, dir, "not_ran.h5"));

    bake.verification.ran = true;
    bake.verification.figures = {{"rays", 5e5}, {"misses", 0.0}};
    bake.verification.cell_sampled_visible.assign(bake.cells.size(), 4);
    expect_same(bake, round_trip(bake, dir, "no_misses.h5"));
}

TEST(BakeFile, GridWithDroppedCellsStillFindsCells) {
    test::TempDir dir;
    const BakeData bake = make_bake(16, {4, 3, 2}, 3, 2, 11);
    const BakeData back = round_trip(bake, dir);
    expect_same(bake, back);
    int dropped = 0;
    for (int32_t c : back.cells.grid_to_cell) dropped += c == -1;
    EXPECT_EQ(dropped, 8);
    for (size_t c = 0; c < back.cells.size(); ++c) {
        EXPECT_EQ(back.cells.find(back.cells.cells[c].bounds.center()), int32_t(c));
    }
}

TEST(BakeFile, OctreeCellsWithParents) {
    test::TempDir dir;
    BakeData bake = make_bake(10, {0, 0, 0}, 0, 0, 2);
    // One root grid cell holding node 0, split into eight leaves (nodes 1..8); the last leaf is empty.
    CellSet& cells = bake.cells;
    cells.kind = CellSet::Kind::kOctree;
    cells.origin = glm::vec3(0.0f);
    cells.cell_size_m = 2.0f;
    cells.dims = glm::ivec3(1);
    cells.grid_to_cell = {0};
    cells.cells.clear();
    cells.nodes.push_back(OctreeNode{Aabb::of(glm::vec3(0.0f), glm::vec3(2.0f)), 1, -1, -1});
    for (int o = 0; o < 8; ++o) {
        const glm::vec3 lo(o & 1 ? 1.0f : 0.0f, o & 2 ? 1.0f : 0.0f, o & 4 ? 1.0f : 0.0f);
        cells.nodes.push_back(OctreeNode{Aabb::of(lo, lo + 1.0f), -1, o < 7 ? o : -1, 0});
        if (o < 7) cells.cells.push_back(Cell{Aabb::of(lo, lo + 1.0f), 0});
    }
    bake.pvs = PvsSet::make(7, 10);
    bake.pvs.set(3, 9);
    bake.verification.cell_sampled_visible.assign(7, 1);
    const std::string path = dir.file("octree.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    EXPECT_EQ(string_attr(path, "/cells", "kind"), "octree");
    ASSERT_EQ(back.cells.nodes.size(), 9u);
    for (size_t i = 0; i < 9; ++i) {
        EXPECT_EQ(back.cells.nodes[i].bounds, cells.nodes[i].bounds);
        EXPECT_EQ(back.cells.nodes[i].first_child, cells.nodes[i].first_child);
        EXPECT_EQ(back.cells.nodes[i].cell, cells.nodes[i].cell);
        EXPECT_EQ(back.cells.nodes[i].parent, cells.nodes[i].parent);
    }
    // Lookups descend the stored tree.
    EXPECT_EQ(back.cells.find({0.5f, 0.5f, 0.5f}), 0);
    EXPECT_EQ(back.cells.find({1.5f, 0.5f, 1.5f}), 5);
    EXPECT_EQ(back.cells.find({1.5f, 1.5f, 1.5f}), -1);  // the empty leaf
}

TEST(BakeFile, VoxelMasksAroundByteAndWordEdges) {
    test::TempDir dir;
    for (int voxels : {1, 7, 8, 9, 63, 64, 65, 129}) {
        SCOPED_TRACE(voxels);
        BakeData bake = make_bake(3, {2, 2, 1}, 0, 0, 5);
        bake.cells.view = VoxelMask{};  // no mask
        bake.cells.eyes = make_mask({1.0f, 2.0f, 3.0f}, 0.5f, {voxels, 1, 1}, 2);
        bake.cells.eyes.bits.back() |= uint64_t(1) << ((voxels - 1) % 64);  // the last voxel too
        const BakeData back = round_trip(bake, dir, std::to_string(voxels) + "_voxels.h5");
        expect_same(bake, back);
        EXPECT_TRUE(back.cells.view.empty());
        EXPECT_TRUE(back.cells.eyes.get(uint64_t(voxels - 1)));
    }
}

TEST(BakeFile, NoLeakPathAndEmptyMasksWithDims) {
    test::TempDir dir;
    BakeData bake = make_bake(3, {2, 2, 1}, 0, 0, 5);
    bake.leak_path.clear();
    bake.cells.view = make_mask({0.0f, 0.0f, 0.0f}, 0.25f, {4, 4, 4}, 0);  // dims but no bits: no mask
    expect_same(bake, round_trip(bake, dir));
}

TEST(BakeFile, AggressiveBakesAreLabelled) {
    test::TempDir dir;
    BakeData bake = make_bake(9, {2, 2, 2}, 0, 0, 4);
    bake.mode = "sampled";
    bake.conservative = false;
    const std::string path = dir.file("sampled.h5");
    write_bake_file(path, bake);
    expect_same(bake, read_bake_file(path));
    EXPECT_EQ(string_attr(path, "/", "pvs_kind"), "aggressive (sampled: may miss visible objects)");
    EXPECT_EQ(int_attr(path, "/", "conservative"), 0);
}

TEST(BakeFile, DuplicateAndEmptyNamesKeepTheirOrder) {
    test::TempDir dir;
    BakeData bake = make_bake(4, {2, 1, 1}, 0, 0, 6);
    bake.parameters = {{"z", "1"}, {"a", "2"}, {"z", "3"}, {"", "4"}};
    bake.figures = {{"b", 1.0}, {"b", 2.0}, {"", 3.0}, {"a", 4.0}};
    expect_same(bake, round_trip(bake, dir));
}

TEST(BakeFile, LongStrings) {
    test::TempDir dir;
    BakeData bake = make_bake(5, {2, 2, 1}, 0, 0, 7);
    bake.parameters.emplace_back("long", std::string(100000, 'x'));
    bake.objects[3].name = std::string(70000, 'n') + "ü";  // the name list outgrows one chunk
    bake.world_path = std::string(5000, 'p');
    const std::string path = dir.file("long.h5");
    write_bake_file(path, bake);
    expect_same(bake, read_bake_file(path));
}

TEST(BakeFileWrite, NulInsideAStringIsRefused) {
    test::TempDir dir;
    BakeData bake = make_bake(5, {2, 2, 1}, 0, 0, 7);
    bake.objects[4].name = std::string("a\0b", 3);
    try {
        write_bake_file(dir.file("nul.h5"), bake);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kInternal);
        EXPECT_NE(std::string(e.what()).find("the name of object 4 contains a NUL byte"), std::string::npos)
            << e.what();
    }
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(BakeFile, SameBakeGivesTheSameBytes) {
    test::TempDir dir;
    const BakeData bake = make_bake(70, {4, 4, 4}, 6, 5, 8);
    write_bake_file(dir.file("a.h5"), bake);
    write_bake_file(dir.file("b.h5"), bake);
    EXPECT_EQ(test::read_file(dir.file("a.h5")), test::read_file(dir.file("b.h5")));
}

TEST(BakeFile, LargeGridAndPvsAreChunkedAndCompressed) {
    test::TempDir dir;
    const BakeData bake = make_bake(3000, {40, 20, 25}, 9, 300, 13);  // 17,777 cells, 300 distinct rows
    const std::string path = dir.file("large.h5");
    write_bake_file(path, bake);
    expect_same(bake, read_bake_file(path));
    EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 300);
    EXPECT_LT(int_attr(path, "/pvs", "bytes_stored"), int_attr(path, "/pvs", "bytes_raw"));
    H5File f(path, false);
    for (const char* name : {"/pvs/rows", "/cells/grid_to_cell"}) {
        const hid_t ds = H5Dopen2(f.id(), name, H5P_DEFAULT);
        const hid_t dcpl = H5Dget_create_plist(ds);
        EXPECT_EQ(H5Pget_layout(dcpl), H5D_CHUNKED) << name;
        // rows: deflate; grid_to_cell: shuffle + deflate.
        EXPECT_EQ(H5Pget_nfilters(dcpl), std::string(name) == "/pvs/rows" ? 1 : 2) << name;
        hsize_t chunk[2] = {0, 0};
        const int rank = H5Pget_chunk(dcpl, 2, chunk);
        const hsize_t chunk_bytes = rank == 2 ? chunk[0] * chunk[1] : chunk[0] * 4;
        const hid_t space = H5Dget_space(ds);
        const hsize_t dataset_bytes = hsize_t(H5Sget_simple_extent_npoints(space)) * (rank == 2 ? 1 : 4);
        H5Sclose(space);
        // ~64 KiB, or the whole dataset when it is smaller than 32 KiB.
        EXPECT_GE(chunk_bytes, std::min<hsize_t>(32u * 1024, dataset_bytes)) << name;
        EXPECT_LE(chunk_bytes, 128u * 1024) << name;
        H5Pclose(dcpl);
        H5Dclose(ds);
    }
}

// Writes the small bake of docs/FORMAT.md's h5dump example; PVSBAKE_EXAMPLE_BAKE=<path> keeps a copy.
TEST(BakeFile, DocumentedExample) {
    test::TempDir dir;
    const BakeData bake = make_example_bake();
    const std::string path = dir.file("example.h5");
    write_bake_file(path, bake);
    expect_same(bake, read_bake_file(path));
    EXPECT_EQ(int_attr(path, "/pvs", "unique_rows"), 2);
    if (const char* keep = std::getenv("PVSBAKE_EXAMPLE_BAKE")) write_bake_file(keep, bake);
}

// ---------------------------------------------------------------------------------------------------------
// Bad files.

TEST(BakeFileBad, MissingFile) {
    test::TempDir dir;
    expect_bad_input(dir.file("nope.h5"), {"no such file"});
}

TEST(BakeFileBad, TextFileAndEmptyFile) {
    test::TempDir dir;
    test::write_file(dir.file("notes.txt"), "this is not a bake\n");
    expect_bad_input(dir.file("notes.txt"), {"not an HDF5 file"});
    test::write_file(dir.file("empty.h5"), "");
    expect_bad_input(dir.file("empty.h5"), {"not an HDF5 file"});
}

TEST(BakeFileBad, FolderInsteadOfFile) {
    test::TempDir dir;
    fs::create_directory(dir.file("folder.h5"));
    expect_bad_input(dir.file("folder.h5"), {"folder"});
}

TEST(BakeFileBad, HdfFileThatIsNotABake) {
    test::TempDir dir;
    const std::string path = dir.file("other.h5");
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    H5Fclose(f);
    expect_bad_input(path, {"not a pvsbake bake file"});
}

TEST(BakeFileBad, TruncatedCopies) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, make_bake(300, {8, 6, 5}, 7, 11, 21));
    const std::string bytes = test::read_file(good);
    for (double fraction : {0.02, 0.1, 0.5, 0.9, 0.999}) {
        SCOPED_TRACE(fraction);
        const std::string path = dir.file("cut.h5");
        test::write_file(path, bytes.substr(0, size_t(double(bytes.size()) * fraction)));
        try {
            read_bake_file(path);
            ADD_FAILURE() << "a truncated file was read";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
            EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
        }
    }
}

TEST(BakeFileBad, NewerMajorVersion) {
    test::TempDir dir;
    const std::string path = dir.file("future.h5");
    write_bake_file(path, make_bake(5, {2, 2, 2}, 0, 0, 1));
    patch_int_attr(path, "/", "format_major", 2);
    patch_int_attr(path, "/", "format_minor", 0);
    expect_bad_input(path, {"bake format 2.0 is newer than this tool reads (1.x); use a newer pvsbake"});
}

TEST(BakeFileBad, NewerMinorVersionIsRead) {
    test::TempDir dir;
    const std::string path = dir.file("minor.h5");
    const BakeData bake = make_bake(5, {2, 2, 2}, 0, 0, 1);
    write_bake_file(path, bake);
    patch_int_attr(path, "/", "format_minor", 7);
    EXPECT_EQ(read_bake_file(path).format_minor, 7);
}

// A file from before the run's record (format 1.4: no /run; run.threads among /parameters, seconds in
// /timings) reads into the same form: its run.* parameters and its timings become the run record.
TEST(BakeFile, AFileWithoutRunReadsItsRunRecordFromTheOldPlaces) {
    test::TempDir dir;
    const std::string path = dir.file("old.h5");
    BakeData bake = make_bake(5, {2, 2, 2}, 0, 0, 1);
    bake.parameters.emplace_back("run.threads", "3");
    write_bake_file(path, bake);
    {
        H5File f(path, true);
        ASSERT_GE(f.id(), 0);
        ASSERT_GE(H5Ldelete(f.id(), "/run", H5P_DEFAULT), 0);
    }
    patch_int_attr(path, "/", "format_minor", 4);
    const BakeData back = read_bake_file(path);
    EXPECT_EQ(back.run.parameters, (NamedStrings{{"run.threads", "3"}}));
    bake.parameters.pop_back();
    EXPECT_EQ(back.parameters, bake.parameters);
    EXPECT_TRUE(back.run.timings_s.empty());  // the empty /timings a 1.5 file keeps for older readers
    EXPECT_TRUE(back.run.figures.empty());
}

TEST(BakeFileBad, CellRowOutOfRange) {
    test::TempDir dir;
    const std::string path = dir.file("bad_row.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    const uint32_t bad = 3;  // three unique rows: 0, 1, 2
    patch_element(path, "/pvs/cell_row", 4, H5T_NATIVE_UINT32, &bad);
    expect_bad_input(path, {"/pvs/cell_row[4] = 3"});
}

TEST(BakeFileBad, GridToCellOutOfRange) {
    test::TempDir dir;
    const std::string path = dir.file("bad_grid.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    for (int32_t bad : {9, -2}) {
        patch_element(path, "/cells/grid_to_cell", 5, H5T_NATIVE_INT32, &bad);
        expect_bad_input(path, {"/cells/grid_to_cell[5]"});
    }
}

TEST(BakeFileBad, DimsDisagreeWithGridToCell) {
    test::TempDir dir;
    const std::string path = dir.file("bad_dims.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    {
        H5File f(path, true);
        H5Attr a(f, "/cells", "dims");
        const int32_t dims[3] = {3, 3, 2};
        ASSERT_GE(H5Awrite(a.id(), H5T_NATIVE_INT32, dims), 0);
    }
    expect_bad_input(path, {"/cells/grid_to_cell"});
}

TEST(BakeFileBad, BitsBeyondTheObjectCount) {
    test::TempDir dir;
    const std::string path = dir.file("bad_bits.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    patch_byte(path, "/pvs/rows", 1, 1, 0xff);  // objects 12..15 do not exist
    expect_bad_input(path, {"/pvs/rows", "beyond object 11"});
}

TEST(BakeFileBad, ObjectCountDisagrees) {
    test::TempDir dir;
    const std::string path = dir.file("bad_count.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    patch_int_attr(path, "/pvs", "object_count", 13);
    expect_bad_input(path, {"/pvs", "object_count"});
}

TEST(BakeFileBad, MissOutOfRange) {
    test::TempDir dir;
    const std::string path = dir.file("bad_miss.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    const hid_t only_object = H5Tcreate(H5T_COMPOUND, sizeof(uint32_t));
    H5Tinsert(only_object, "object", 0, H5T_NATIVE_UINT32);
    const uint32_t bad = 12;
    patch_element(path, "/verification/misses", 1, only_object, &bad);
    H5Tclose(only_object);
    expect_bad_input(path, {"/verification/misses[1]", "object 12"});
}

TEST(BakeFileBad, MaskBitsBeyondTheVoxelCount) {
    test::TempDir dir;
    const std::string path = dir.file("bad_mask.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));  // eyes: 105 voxels, 14 bytes
    const uint8_t bad = 0x80;                                  // voxel 111
    patch_element(path, "/cells/eyes/bits", 13, H5T_NATIVE_UINT8, &bad);
    expect_bad_input(path, {"/cells/eyes/bits sets bits beyond voxel 104"});
}

TEST(BakeFileBad, MissingDataset) {
    test::TempDir dir;
    const std::string path = dir.file("no_bounds.h5");
    write_bake_file(path, make_bake(12, {3, 3, 1}, 0, 3, 1));
    {
        H5File f(path, true);
        ASSERT_GE(H5Ldelete(f.id(), "/objects/bounds", H5P_DEFAULT), 0);
    }
    expect_bad_input(path, {"missing dataset /objects/bounds"});
}

// Damaged bytes anywhere in a small bake: reading either succeeds (the damage hit a value, not the
// structure) or throws pvs::Error (kBadInput); it never crashes. HDF5 1.10.8 itself segfaults on some of
// these when the file holds variable-length strings or when types and sizes are not checked before
// reading: this guards the checks in read_bake_file. The output is byte-identical for the same bake, so
// the cases are fixed.
TEST(BakeFileBad, DamagedBytesNeverCrash) {
    test::TempDir dir;
    const std::string good_path = dir.file("good.h5");
    write_bake_file(good_path, make_example_bake());
    const std::string good = test::read_file(good_path);
    const std::string path = dir.file("damaged.h5");
    std::mt19937 rng(2024);
    int refused = 0;
    const int cases = test::in_ci() ? 300 : 1500;
    for (int i = 0; i < cases; ++i) {
        std::string bytes = good;
        const int flips = 1 + int(rng() % 4);
        for (int k = 0; k < flips; ++k) bytes[rng() % bytes.size()] ^= char(1 + rng() % 255);
        test::write_file(path, bytes);
        try {
            read_bake_file(path);
        } catch (const Error& e) {
            ++refused;
            EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
            EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
        }
        // Nothing left open, whatever happened.
        ASSERT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0) << "case " << i;
    }
    EXPECT_GT(refused, cases / 4);
    // HDF5 1.10.8 keeps some internal state after an object header fails its checksum (the file itself is
    // closed, no descriptor or ID is left), and when automatic error printing is on at exit it prints
    // "HDF5: infinite loop closing library". A pure C program opening the same damaged group shows it
    // too. Keep this test binary's output clean: printing stays off from here on.
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

// ---------------------------------------------------------------------------------------------------------
// Failed writes.

TEST(BakeFileWrite, MissingFolderThrowsAndLeavesNothing) {
    test::TempDir dir;
    const std::string path = dir.file("no_such_folder/bake.h5");
    try {
        write_bake_file(path, make_bake(5, {2, 2, 2}, 0, 0, 1));
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kIo) << e.what();
        EXPECT_EQ(std::string(e.what()), path + ": the folder does not exist (any more) while writing the bake file");
    }
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(BakeFileWrite, FailedRenameLeavesTheTargetUntouched) {
    test::TempDir dir;
    // The target exists as a folder: the file is written whole, then the rename fails.
    const std::string path = dir.file("bake.h5");
    fs::create_directory(path);
    test::write_file(path + "/keep.txt", "keep");
    EXPECT_THROW(write_bake_file(path, make_bake(5, {2, 2, 2}, 0, 0, 1)), Error);
    EXPECT_TRUE(fs::is_directory(path));
    EXPECT_EQ(test::read_file(path + "/keep.txt"), "keep");
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"bake.h5"});
}

TEST(BakeFileWrite, MaskWithTheWrongWordCountIsRefused) {
    test::TempDir dir;
    BakeData bake = make_bake(5, {2, 2, 1}, 0, 0, 7);
    bake.cells.eyes.bits.push_back(0);
    try {
        write_bake_file(dir.file("mask.h5"), bake);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kInternal);
        EXPECT_NE(std::string(e.what()).find("eyes mask"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(BakeFileWrite, InconsistentBakeLeavesTheOldFileUntouched) {
    test::TempDir dir;
    const std::string path = dir.file("bake.h5");
    const BakeData good = make_bake(5, {2, 2, 2}, 0, 0, 1);
    write_bake_file(path, good);
    const std::string before = test::read_file(path);
    BakeData bad = good;
    bad.pvs = PvsSet::make(3, 5);  // the bake has 8 cells
    try {
        write_bake_file(path, bad);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kInternal) << e.what();
    }
    EXPECT_EQ(test::read_file(path), before);
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"bake.h5"});
    expect_same(good, read_bake_file(path));
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

TEST(BakeFile, OccludersRoundTrip) {
    test::TempDir dir;
    BakeData bake = make_bake(10, {2, 1, 2}, 0, 0, 3);
    bake.occluders.push_back(Occluder{Aabb::of({0, 0, 0}, {1, 2, 3}), 0.25f, true, {1, 4, 9}});
    bake.occluders.push_back(Occluder{Aabb::of({-5, 0, 0}, {-4, 1, 1}), 0.25f, false, {}});
    bake.occluders.push_back(Occluder{Aabb::of({7, 7, 7}, {8.5f, 9, 10}), 0.1f, true, {0}});
    const std::string path = dir.file("occ.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    ASSERT_EQ(back.occluders.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(back.occluders[i].box, bake.occluders[i].box);
        EXPECT_EQ(back.occluders[i].voxel_size_m, bake.occluders[i].voxel_size_m);
        EXPECT_EQ(back.occluders[i].proven, bake.occluders[i].proven);
        EXPECT_EQ(back.occluders[i].objects, bake.occluders[i].objects);
    }
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

// A bake of 4 cells with 3 occluders (the second not proven) and a ranking: cell 0 has two entries, cell 1
// none, cell 2 one, cell 3 two.
BakeData ranked_bake() {
    BakeData bake = make_bake(10, {2, 1, 2}, 0, 0, 3);
    bake.occluders.push_back(Occluder{Aabb::of({0, 0, 0}, {1, 2, 3}), 0.25f, true, {1, 4, 9}});
    bake.occluders.push_back(Occluder{Aabb::of({-5, 0, 0}, {-4, 1, 1}), 0.25f, false, {}});
    bake.occluders.push_back(Occluder{Aabb::of({7, 7, 7}, {8.5f, 9, 10}), 0.1f, true, {0}});
    bake.ranked.offsets = {0, 2, 2, 3, 5};
    bake.ranked.entries = {{2, 0.5f, 1.25f, 3.5f, 0.25f},
                           {0, 0.125f, 0.5f, 1.0f, 0.0625f},
                           {0, 0.75f, 2.0f, 9.0f, 0.5f},
                           {0, 0.0f, 0.02f, 0.0f, 0.0f},
                           {2, 0.0f, 0.01f, 0.0f, 0.0f}};
    return bake;
}

TEST(BakeFile, RankedOccludersRoundTrip) {
    test::TempDir dir;
    const BakeData bake = ranked_bake();
    const std::string path = dir.file("ranked.h5");
    write_bake_file(path, bake);
    EXPECT_EQ(int_attr(path, "/", "format_minor"), kBakeFormatMinor);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    EXPECT_EQ(back.ranked.count(0), 2u);
    EXPECT_EQ(back.ranked.count(1), 0u);
    EXPECT_EQ(back.ranked.count(3), 2u);
    EXPECT_EQ(back.ranked.count(4), 0u);  // out of range
    // Same bake, same bytes (the ranking too).
    write_bake_file(dir.file("again.h5"), back);
    EXPECT_EQ(test::read_file(dir.file("again.h5")), test::read_file(path));
}

// The ranked bake with two polygon occluders (format 1.7) among the boxes: cell 0 ranks polygon 1 between its
// two boxes, cell 3 polygon 0 first and polygon 1 last. They come back at their places; a 1.6 reader's
// datasets (the boxes' ranking) hold the boxes alone.
BakeData polygon_bake() {
    BakeData bake = ranked_bake();
    OccluderPolygon p;
    p.normal = glm::normalize(glm::vec3(0.0f, 0.6f, 0.8f));
    p.offset = 2.0f;
    p.thickness = 0.001f;
    p.corners = {{-1, 0, 2.5f}, {3, 0, 2.5f}, {3, 3, 0.25f}, {-1, 3, 0.25f}};
    for (const glm::vec3& c : p.corners) p.bounds.extend(c);
    bake.polygons.push_back(p);
    p.corners.pop_back();
    p.bounds = Aabb{};
    for (const glm::vec3& c : p.corners) p.bounds.extend(c);
    bake.polygons.push_back(p);
    bake.ranked.offsets = {0, 3, 3, 4, 8};
    bake.ranked.entries = {
        {2, 0.5f, 1.25f, 3.5f, 0.25f}, {4, 0.25f, 0, 0, 0}, {0, 0.125f, 0.5f, 1.0f, 0.0625f},
        {0, 0.75f, 2.0f, 9.0f, 0.5f},  {3, 0.5f, 0, 0, 0},  {0, 0.0f, 0.02f, 0.0f, 0.0f},
        {2, 0.0f, 0.01f, 0.0f, 0.0f},  {4, 0.0f, 0, 0, 0}};
    return bake;
}

TEST(BakeFile, PolygonOccludersRoundTripAtTheirPlaces) {
    test::TempDir dir;
    const BakeData bake = polygon_bake();
    const std::string path = dir.file("polygons.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    ASSERT_EQ(back.polygons.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(back.polygons[i].normal, bake.polygons[i].normal);
        EXPECT_EQ(back.polygons[i].offset, bake.polygons[i].offset);
        EXPECT_EQ(back.polygons[i].thickness, bake.polygons[i].thickness);
        EXPECT_EQ(back.polygons[i].corners, bake.polygons[i].corners);
        EXPECT_EQ(back.polygons[i].bounds, bake.polygons[i].bounds);
    }
    EXPECT_EQ(read_u32_dataset(path, "/occluders/ranked_offsets"), (std::vector<uint32_t>{0, 2, 2, 3, 5}));
    EXPECT_EQ(read_u32_dataset(path, "/occluders/ranked_polygon_offsets"),
              (std::vector<uint32_t>{0, 1, 1, 1, 3}));
    EXPECT_EQ(read_u32_dataset(path, "/occluders/ranked_polygon_rank"), (std::vector<uint32_t>{1, 0, 3}));
    write_bake_file(dir.file("again.h5"), back);
    EXPECT_EQ(test::read_file(dir.file("again.h5")), test::read_file(path));
}

TEST(BakeFileBad, PolygonOccludersOutOfRangeOrDamaged) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, polygon_bake());
    const std::string path = dir.file("bad.h5");
    auto patched = [&](const char* dataset, hsize_t index, hid_t type, const void* value,
                       std::vector<std::string> needles) {
        expect_patch_refused(good, path, dataset, index, type, value, needles);
    };
    const uint32_t big = 99, two = 2, zero = 0;
    const float negative = -1.0f;
    patched("/occluders/ranked_polygon", 0, H5T_NATIVE_UINT32, &big,
            {"/occluders/ranked_polygon[0]", "not a polygon index below 2"});
    patched("/occluders/ranked_polygon_rank", 0, H5T_NATIVE_UINT32, &big,
            {"/occluders/ranked_polygon_rank[0]"});
    patched("/occluders/ranked_polygon_rank", 2, H5T_NATIVE_UINT32, &zero,
            {"/occluders/ranked_polygon_rank[2]"});
    patched("/occluders/ranked_polygon_score", 1, H5T_NATIVE_FLOAT, &negative,
            {"/occluders/ranked_polygon_score[1]"});
    patched("/occluders/polygon_offsets", 1, H5T_NATIVE_UINT32, &two, {"/occluders/polygon_offsets"});
    patched("/occluders/ranked_polygon_offsets", 2, H5T_NATIVE_UINT32, &zero,
            {"/occluders/ranked_polygon_offsets[2] decreases"});
}

// The ranked bake with horizon lists (format 1.8): two boxes (a solid one and a panel) and a tile, two lists
// over its cells, and the cells' tests (1.10). They come back as written, and a damaged list, tile, cell
// entry or test is refused by name.
BakeData horizon_bake(bool tests = true) {
    BakeData bake = ranked_bake();
    test::add_horizon_lists(bake);
    bake.horizon.cell_list.back() = 1;
    bake.horizon.offsets = {0, 2, 3};
    bake.horizon.entries = {0, 2, 1};
    if (tests) {
        bake.horizon.test_offsets = {0};
        for (uint32_t c = 0; c < bake.cells.size(); ++c) {
            for (uint32_t o = 0; o < bake.objects.size(); ++o)
                if ((o + c) % 2 == 0 && bake.pvs.test(c, o)) bake.horizon.tests.push_back(o);
            bake.horizon.test_offsets.push_back(uint32_t(bake.horizon.tests.size()));
        }
    }
    return bake;
}

TEST(BakeFile, HorizonListsRoundTrip) {
    test::TempDir dir;
    const BakeData bake = horizon_bake();
    const std::string path = dir.file("horizon.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    EXPECT_EQ(back.horizon.boxes, bake.horizon.boxes);
    ASSERT_EQ(back.horizon.tiles.size(), 1u);
    EXPECT_TRUE(back.horizon.tiles[0].tile);
    EXPECT_EQ(back.horizon.tiles[0].corners, bake.horizon.tiles[0].corners);
    EXPECT_EQ(back.horizon.tiles[0].normal, bake.horizon.tiles[0].normal);
    EXPECT_EQ(back.horizon.tiles[0].thickness, bake.horizon.tiles[0].thickness);
    EXPECT_EQ(back.horizon.cell_list, bake.horizon.cell_list);
    EXPECT_EQ(back.horizon.offsets, bake.horizon.offsets);
    EXPECT_EQ(back.horizon.entries, bake.horizon.entries);
    ASSERT_GE(bake.horizon.tests.size(), 2u);
    EXPECT_EQ(back.horizon.test_offsets, bake.horizon.test_offsets);
    EXPECT_EQ(back.horizon.tests, bake.horizon.tests);
    write_bake_file(dir.file("again.h5"), back);
    EXPECT_EQ(test::read_file(dir.file("again.h5")), test::read_file(path));
    // Without tests (or in a file before 1.10), none come back: every object is tested.
    write_bake_file(dir.file("untested.h5"), horizon_bake(false));
    const BakeData untested = read_bake_file(dir.file("untested.h5"));
    EXPECT_TRUE(untested.horizon.test_offsets.empty() && untested.horizon.tests.empty());
    EXPECT_EQ(untested.horizon.entries, bake.horizon.entries);
    // Without lists, no /horizon group, and nothing comes back.
    BakeData none = bake;
    none.horizon = HorizonLists{};
    write_bake_file(dir.file("none.h5"), none);
    EXPECT_TRUE(read_bake_file(dir.file("none.h5")).horizon.empty());
}

TEST(BakeFileBad, HorizonListsOutOfRangeOrDamaged) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, horizon_bake());
    const std::string path = dir.file("bad.h5");
    auto patched = [&](const char* dataset, hsize_t index, hid_t type, const void* value,
                       std::vector<std::string> needles) {
        expect_patch_refused(good, path, dataset, index, type, value, needles);
    };
    const uint32_t big = 99, zero = 0;
    const float nan = std::nanf(""), negative = -1.0f;
    patched("/horizon/list_entries", 1, H5T_NATIVE_UINT32, &big, {"/horizon/list_entries[1]"});
    patched("/horizon/list_entries", 1, H5T_NATIVE_UINT32, &zero, {"/horizon/list_entries[1]"});
    patched("/horizon/cell_list", 0, H5T_NATIVE_UINT32, &big, {"/horizon/cell_list[0]"});
    patched("/horizon/list_offsets", 1, H5T_NATIVE_UINT32, &big, {"/horizon/list_offsets"});
    patched("/horizon/boxes", 3, H5T_NATIVE_FLOAT, &nan, {"/horizon/boxes[0]"});
    patched("/horizon/tile_planes", 4, H5T_NATIVE_FLOAT, &negative, {"/horizon/tile_planes[0]"});
    patched("/horizon/tile_corners", 2, H5T_NATIVE_FLOAT, &nan, {"/horizon/tile_corners[0]"});
    patched("/horizon/tile_offsets", 1, H5T_NATIVE_UINT32, &zero, {"/horizon/tile_offsets"});
    patched("/horizon/tests", 0, H5T_NATIVE_UINT32, &big, {"/horizon/tests[0]"});
    patched("/horizon/test_offsets", 1, H5T_NATIVE_UINT32, &big, {"/horizon/test_offsets"});
}

// Format 1.9: the objects' part boxes come back as written; without parts no datasets and none come back;
// a part outside its object's bounds, a NaN or offsets that decrease are refused by name.
BakeData parts_bake() {
    BakeData bake = make_bake(6, glm::ivec3(2, 1, 1), 0, 2, 3);
    ObjectParts& p = bake.object_parts;
    p.offsets = {0, 2, 2, 2, 5, 5, 5};
    const Aabb& a = bake.objects[0].bounds;
    const glm::vec3 mid = 0.5f * (a.min + a.max);
    p.boxes = {Aabb::of(a.min, mid), Aabb::of(mid, a.max)};
    const Aabb& d = bake.objects[3].bounds;
    for (int k = 0; k < 3; ++k)
        p.boxes.push_back(Aabb::of(d.min + 0.25f * float(k) * (d.max - d.min), d.max));
    return bake;
}

TEST(BakeFile, ObjectPartsRoundTrip) {
    test::TempDir dir;
    const BakeData bake = parts_bake();
    const std::string path = dir.file("parts.h5");
    write_bake_file(path, bake);
    const BakeData back = read_bake_file(path);
    expect_same(bake, back);
    EXPECT_EQ(back.object_parts.offsets, bake.object_parts.offsets);
    EXPECT_EQ(back.object_parts.boxes, bake.object_parts.boxes);
    EXPECT_EQ(back.object_parts.count(3), 3u);
    write_bake_file(dir.file("again.h5"), back);
    EXPECT_EQ(test::read_file(dir.file("again.h5")), test::read_file(path));
    BakeData none = bake;
    none.object_parts = ObjectParts{};
    write_bake_file(dir.file("none.h5"), none);
    EXPECT_TRUE(read_bake_file(dir.file("none.h5")).object_parts.offsets.empty());
    // The writer refuses a part outside its object's bounds (the reader would).
    BakeData outside = bake;
    outside.object_parts.boxes[1].max.x += 1.0f;
    EXPECT_THROW(write_bake_file(dir.file("outside.h5"), outside), std::exception);
}

TEST(BakeFileBad, ObjectPartsOutsideOrDamaged) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, parts_bake());
    const std::string path = dir.file("bad.h5");
    auto patched = [&](const char* dataset, hsize_t index, hid_t type, const void* value,
                       std::vector<std::string> needles) {
        expect_patch_refused(good, path, dataset, index, type, value, needles);
    };
    const uint32_t zero = 0, big = 99;
    const float nan = std::nanf(""), far = 1e6f;
    patched("/objects/part_boxes", 3, H5T_NATIVE_FLOAT, &far, {"/objects/part_boxes[0]", "inside"});
    patched("/objects/part_boxes", 7, H5T_NATIVE_FLOAT, &nan, {"/objects/part_boxes[1]"});
    patched("/objects/part_offsets", 4, H5T_NATIVE_UINT32, &zero, {"/objects/part_offsets", "ascending"});
    // An offset past the boxes before a later one comes back down: refused before any box is read.
    patched("/objects/part_offsets", 1, H5T_NATIVE_UINT32, &big, {"/objects/part_offsets", "object 0"});
    patched("/objects/part_offsets", 6, H5T_NATIVE_UINT32, &big, {"/objects/part_offsets"});
}

// A bake without a ranking (ranking off, or read from an older file) writes no ranked datasets, and a file
// of format 1.1 (which has none) still reads, with no ranked occluders.
TEST(BakeFile, Format11FilesWithoutRankingRead) {
    test::TempDir dir;
    BakeData bake = ranked_bake();
    bake.ranked = RankedOccluders{};
    const std::string path = dir.file("old.h5");
    write_bake_file(path, bake);
    patch_int_attr(path, "/", "format_minor", 1);
    const BakeData back = read_bake_file(path);
    EXPECT_EQ(back.format_minor, 1);
    EXPECT_TRUE(back.ranked.empty());
    EXPECT_EQ(back.ranked.count(0), 0u);
    ASSERT_EQ(back.occluders.size(), 3u);
    EXPECT_EQ(back.occluders[2].box, bake.occluders[2].box);
}

TEST(BakeFileBad, RankedOccludersOutOfRangeOrDamaged) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, ranked_bake());
    const std::string path = dir.file("bad.h5");
    auto patched = [&](const char* dataset, hsize_t index, hid_t type, const void* value,
                       std::vector<std::string> needles) {
        expect_patch_refused(good, path, dataset, index, type, value, needles);
    };
    const uint32_t big = 99, unproven = 1, down = 1;
    const float nan = std::nanf(""), negative = -1.0f, higher = 0.9f, too_much = 1.5f, huge_angle = 13.0f;
    patched("/occluders/ranked_box", 1, H5T_NATIVE_UINT32, &big,
            {"/occluders/ranked_box[1] = 99 is not a box index below 3"});
    patched("/occluders/ranked_box", 0, H5T_NATIVE_UINT32, &unproven, {"ranked_box[0] = 1", "not proven"});
    patched("/occluders/ranked_offsets", 2, H5T_NATIVE_UINT32, &down,
            {"/occluders/ranked_offsets[2] decreases"});
    patched("/occluders/ranked_score", 0, H5T_NATIVE_FLOAT, &nan, {"/occluders/ranked_score[0]", "finite"});
    patched("/occluders/ranked_score", 3, H5T_NATIVE_FLOAT, &negative, {"/occluders/ranked_score[3]"});
    patched("/occluders/ranked_score", 1, H5T_NATIVE_FLOAT, &higher, {"ranked_score[1]", "best first"});
    patched("/occluders/ranked_hidden_triangle_share", 2, H5T_NATIVE_FLOAT, &too_much,
            {"/occluders/ranked_hidden_triangle_share[2]"});
    patched("/occluders/ranked_solid_angle_sr", 4, H5T_NATIVE_FLOAT, &huge_angle,
            {"/occluders/ranked_solid_angle_sr[4]"});
    patched("/occluders/ranked_hidden_objects", 4, H5T_NATIVE_FLOAT, &nan,
            {"/occluders/ranked_hidden_objects[4]"});
    // A ranked box whose bounds are not finite.
    fs::copy_file(good, path, fs::copy_options::overwrite_existing);
    {
        H5File f(path, true);
        const hid_t ds = H5Dopen2(f.id(), "/occluders/bounds", H5P_DEFAULT);
        ASSERT_GE(ds, 0);
        std::vector<float> flat(18);
        ASSERT_GE(H5Dread(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, flat.data()), 0);
        flat[12] = INFINITY;  // box 2's min x
        ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, flat.data()), 0);
        H5Dclose(ds);
    }
    expect_bad_input(path, {"/occluders/bounds[2]", "not a finite box"});
    // Offsets that do not match the cells.
    fs::copy_file(good, path, fs::copy_options::overwrite_existing);
    {
        H5File f(path, true);
        ASSERT_GE(H5Ldelete(f.id(), "/occluders/ranked_offsets", H5P_DEFAULT), 0);
        const hsize_t n = 3;
        const uint32_t values[3] = {0, 2, 5};
        const hid_t space = H5Screate_simple(1, &n, nullptr);
        const hid_t ds = H5Dcreate2(f.id(), "/occluders/ranked_offsets", H5T_STD_U32LE, space, H5P_DEFAULT,
                                    H5P_DEFAULT, H5P_DEFAULT);
        ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
        H5Dclose(ds);
        H5Sclose(space);
    }
    expect_bad_input(path, {"/occluders/ranked_offsets"});
}

TEST(BakeFileWrite, OccludersTheReaderWouldRefuseAreNotWritten) {
    test::TempDir dir;
    const std::string path = dir.file("bad.h5");
    auto refused = [&](const BakeData& bake, const std::string& needle) {
        try {
            write_bake_file(path, bake);
            ADD_FAILURE() << "written: " << needle;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::kInternal) << e.what();
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(path));
    };
    BakeData bake = ranked_bake();
    bake.ranked.entries[0].box = 1;  // not proven
    refused(bake, "not a proven occluder");
    bake = ranked_bake();
    bake.ranked.offsets.pop_back();
    refused(bake, "offsets");
    bake = ranked_bake();
    bake.ranked.entries[1].score = 0.75f;
    refused(bake, "not best first");
    // The cells' horizon tests (1.10): offsets that decrease, an object out of range, or out of order.
    bake = horizon_bake();
    ASSERT_GE(bake.horizon.test_offsets[1], 1u);
    std::swap(bake.horizon.test_offsets[1], bake.horizon.test_offsets[2]);
    if (bake.horizon.test_offsets[1] == bake.horizon.test_offsets[2]) bake.horizon.test_offsets[2] = 0;
    refused(bake, "horizon tests' offsets decrease");
    bake = horizon_bake();
    bake.horizon.tests[0] = uint32_t(bake.objects.size());
    refused(bake, "horizon tests are not ascending objects in range");
    bake = horizon_bake();
    size_t c = 0;  // a cell of two tests or more
    while (c + 1 < bake.horizon.test_offsets.size() &&
           bake.horizon.test_offsets[c + 1] - bake.horizon.test_offsets[c] < 2)
        ++c;
    ASSERT_LT(c + 1, bake.horizon.test_offsets.size());
    const uint32_t k = bake.horizon.test_offsets[c];
    std::swap(bake.horizon.tests[k], bake.horizon.tests[k + 1]);
    refused(bake, "horizon tests are not ascending objects in range");
}

}  // namespace
}  // namespace pvs
