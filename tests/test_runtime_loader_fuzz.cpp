// SPDX-License-Identifier: MIT
// Fuzz test of the runtime loader (pvsbake::Bake::load): damaged copies of small grid and octree bakes
// (truncations, flipped bytes anywhere, in the stored data of datasets and in attributes, datasets and
// attributes rewritten with wrong types, and datasets claiming huge sizes). Every mutant must load or
// return a non-ok status with a one-line message; a loaded mutant must answer every query without a fault
// (the sanitizer build, scripts/test.sh, checks reads out of bounds); no load may take long (a hang).
// Fixed seeds. PVSBAKE_FUZZ_ITERATIONS overrides the number of random mutants.
#include "io/bake_file.h"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace pvs {
namespace {

int iterations() {
    return test::fuzz_iterations(1500, 300);
}

struct Outcome {
    int loaded = 0;
    int refused = 0;
};

// Loads path; a loaded bake is queried everywhere. Fails on a slow load or a malformed message.
void load_mutant(const std::string& path, const std::string& what, Outcome& outcome) {
    pvsbake::Bake bake;
    const ssize_t open_before = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
    const auto t0 = std::chrono::steady_clock::now();
    const pvsbake::LoadResult r = bake.load(path);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(seconds, 5.0) << what << ": a load this slow is a hang";
    ASSERT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), open_before) << what << ": left HDF5 objects open";
    if (!r) {
        ++outcome.refused;
        EXPECT_NE(r.status, pvsbake::Status::kOk);
        EXPECT_EQ(r.message.rfind(path + ": ", 0), 0u) << what << ": " << r.message;
        EXPECT_EQ(r.message.find('\n'), std::string::npos) << what << ": " << r.message;
        EXPECT_TRUE(bake.empty()) << what;
        if (std::getenv("PVSBAKE_FUZZ_VERBOSE") != nullptr)
            std::printf("%s: %s\n", what.c_str(), r.message.c_str());
        return;
    }
    ++outcome.loaded;
    std::vector<uint64_t> words(bake.words_per_row());
    for (uint32_t c = 0; c < bake.cell_count(); ++c) {
        uint32_t n = 0, last = 0;
        bool increasing = true;
        bake.for_each_visible(c, [&](uint32_t o) {
            increasing = increasing && (n == 0 || o > last) && o < bake.object_count();
            last = o;
            ++n;
        });
        ASSERT_TRUE(increasing) << what << ": cell " << c;
        ASSERT_EQ(bake.fill_bitset(c, words.data(), words.size()), n) << what;
        if (n > 0) {
            EXPECT_TRUE(bake.is_visible(c, last)) << what;
        }
        const pvsbake::Box b = bake.cell_bounds(c);
        const int32_t found = bake.find_cell(0.5f * (b.min[0] + b.max[0]), 0.5f * (b.min[1] + b.max[1]),
                                             0.5f * (b.min[2] + b.max[2]));
        ASSERT_LT(found, int32_t(bake.cell_count())) << what;
    }
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-20.0f, 40.0f);
    for (int i = 0; i < 200; ++i)
        ASSERT_LT(bake.find_cell(u(rng), u(rng), u(rng)), int32_t(bake.cell_count())) << what;
    for (uint32_t o = 0; o < bake.object_count(); ++o)
        ASSERT_EQ(bake.object_name(o).size(), std::strlen(bake.object_name_c(o)));
    // Ranked occluders: what load() let through is sound (validated there), so reading them is safe.
    for (uint32_t c = 0; c <= bake.cell_count(); ++c) {
        const auto list = bake.occluders(c);
        ASSERT_EQ(list.size(), bake.occluder_count(c)) << what;
        for (size_t k = 0; k < list.size(); ++k) {
            const pvsbake::RankedOccluder& r = list[k];
            ASSERT_TRUE(std::isfinite(r.score) && r.score >= 0.0f) << what;
            ASSERT_TRUE(k == 0 || r.score <= list[k - 1].score) << what;
            ASSERT_TRUE(r.hidden_triangle_share >= 0.0f && r.hidden_triangle_share <= 1.0f) << what;
            for (int a = 0; a < 3; ++a) ASSERT_LE(r.box.min[a], r.box.max[a]) << what;
        }
    }
}

// The byte ranges of the stored data of every dataset in the file (contiguous: one range; chunked: one
// per chunk).
std::vector<std::pair<size_t, size_t>> data_ranges(const std::string& path) {
    std::vector<std::pair<size_t, size_t>> ranges;
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    auto visit = [](hid_t obj, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        if (info->type != H5O_TYPE_DATASET) return 0;
        auto& out = *static_cast<std::vector<std::pair<size_t, size_t>>*>(data);
        const hid_t ds = H5Dopen2(obj, name, H5P_DEFAULT);
        const hid_t dcpl = H5Dget_create_plist(ds);
        const bool chunked = H5Pget_layout(dcpl) == H5D_CHUNKED;
        H5Pclose(dcpl);
        if (!chunked) {
            const haddr_t at = H5Dget_offset(ds);  // HADDR_UNDEF when empty
            if (at != HADDR_UNDEF) out.emplace_back(size_t(at), size_t(H5Dget_storage_size(ds)));
        } else {
            hsize_t chunks = 0;
            const hid_t space = H5Dget_space(ds);
            H5Dget_num_chunks(ds, space, &chunks);
            for (hsize_t i = 0; i < chunks; ++i) {
                haddr_t addr = 0;
                hsize_t size = 0;
                if (H5Dget_chunk_info(ds, space, i, nullptr, nullptr, &addr, &size) >= 0)
                    out.emplace_back(size_t(addr), size_t(size));
            }
            H5Sclose(space);
        }
        H5Dclose(ds);
        return 0;
    };
    H5Ovisit2(f, H5_INDEX_NAME, H5_ITER_NATIVE, visit, &ranges, H5O_INFO_BASIC);
    H5Fclose(f);
    ranges.erase(std::remove_if(ranges.begin(), ranges.end(), [](auto r) { return r.second == 0; }),
                 ranges.end());
    return ranges;
}

// Where attribute names appear in the file: their messages (type, shape, value) follow the name.
std::vector<size_t> attribute_sites(const std::string& bytes) {
    std::vector<size_t> sites;
    for (const char* name :
         {"format_major", "format_minor", "dims", "origin", "cell_size_m", "voxel_size_m", "cell_count",
          "object_count", "unique_rows", "kind_code", "conservative", "ran"}) {
        for (size_t at = bytes.find(name); at != std::string::npos; at = bytes.find(name, at + 1))
            sites.push_back(at);
    }
    return sites;
}

// Random damage to the bytes: truncation, flips anywhere, in dataset data, or after attribute names.
std::string mutate(const std::string& good, const std::vector<std::pair<size_t, size_t>>& data,
                   const std::vector<size_t>& attrs, std::mt19937& rng, std::string& what) {
    std::string bytes = good;
    const int kind = int(rng() % 4);
    const int flips = 1 + int(rng() % 4);
    for (int k = 0; k < flips; ++k) {
        size_t at = rng() % bytes.size();
        if (kind == 1 && !data.empty()) {
            const auto& [from, size] = data[rng() % data.size()];
            at = std::min(bytes.size() - 1, from + rng() % size);
        } else if (kind == 2 && !attrs.empty()) {
            at = std::min(bytes.size() - 1, attrs[rng() % attrs.size()] + rng() % 96);
        }
        bytes[at] = char(uint8_t(bytes[at]) ^ uint8_t(1 + rng() % 255));
        what += ' ';
        what += std::to_string(at);
    }
    if (kind == 3) {
        bytes.resize(rng() % bytes.size());
        what = "truncated to " + std::to_string(bytes.size());
    } else {
        what = std::string(kind == 0 ? "flips" : kind == 1 ? "data flips" : "attribute flips") + what;
    }
    return bytes;
}

void random_damage(bool octree) {
    test::TempDir dir;
    const std::string good_path = dir.file("good.h5");
    write_bake_file(good_path, test::coherent_bake(45, {4, 3, 3}, octree, true, 7));
    const std::string good = test::read_file(good_path);
    const auto data = data_ranges(good_path);
    const auto attrs = attribute_sites(good);
    ASSERT_GT(data.size(), 10u);
    ASSERT_GT(attrs.size(), 10u);
    std::mt19937 rng(octree ? 99 : 42);
    Outcome outcome;
    const std::string path = dir.file("mutant.h5");
    for (int i = 0; i < iterations(); ++i) {
        std::string what;
        test::write_file(path, mutate(good, data, attrs, rng, what));
        load_mutant(path, "case " + std::to_string(i) + ": " + what, outcome);
        if (::testing::Test::HasFatalFailure()) return;
    }
    EXPECT_GT(outcome.refused, iterations() / 5);
    EXPECT_GT(outcome.loaded, 0);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // see BakeFileBad.DamagedBytesNeverCrash
}

TEST(RuntimeLoaderFuzz, DamagedGridBakes) {
    random_damage(false);
}

TEST(RuntimeLoaderFuzz, DamagedOctreeBakes) {
    random_damage(true);
}

// Rewrites one dataset or attribute of a copy of the good file with `edit`, then loads it.
void edited(const std::string& good, const std::string& path, const std::string& what,
            const std::function<void(hid_t)>& edit, Outcome& outcome) {
    test::write_file(path, test::read_file(good));
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    edit(f);
    H5Fclose(f);
    load_mutant(path, what, outcome);
}

// Replaces the dataset `name` by one of type `type` and shape `dims` (max dims unlimited, chunked when
// `chunk` > 0), holding `bytes` of data written from a junk buffer, or nothing when bytes is 0.
void replace_dataset(hid_t f, const std::string& name, hid_t type, std::vector<hsize_t> dims, hsize_t chunk,
                     bool write) {
    H5Ldelete(f, name.c_str(), H5P_DEFAULT);
    std::vector<hsize_t> max(dims.size(), H5S_UNLIMITED);
    const hid_t space = H5Screate_simple(int(dims.size()), dims.data(), chunk > 0 ? max.data() : nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (chunk > 0) {
        std::vector<hsize_t> c(dims.size(), 1);
        c[0] = chunk;
        H5Pset_chunk(dcpl, int(c.size()), c.data());
    }
    const hid_t ds = H5Dcreate2(f, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(ds, 0) << name;
    if (write) {
        hsize_t n = H5Tget_size(type);
        for (hsize_t d : dims) n *= d;
        std::vector<uint8_t> junk(static_cast<size_t>(n));
        for (size_t i = 0; i < junk.size(); ++i) junk[i] = uint8_t(i * 37 + 11);
        H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, junk.data());
    }
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
}

void replace_attribute(hid_t f, const std::string& object, const std::string& name, hid_t type,
                       hsize_t count) {
    const hid_t obj = H5Oopen(f, object.c_str(), H5P_DEFAULT);
    H5Adelete(obj, name.c_str());
    const hid_t space = count == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &count, nullptr);
    const hid_t a = H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
    std::vector<uint8_t> junk(H5Tget_size(type) * count, 0x41);
    H5Awrite(a, type, junk.data());
    H5Aclose(a);
    H5Sclose(space);
    H5Oclose(obj);
}

// Wrong types and huge sizes, on every dataset and attribute the loader reads.
TEST(RuntimeLoaderFuzz, WrongTypesAndHugeSizes) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5");
    write_bake_file(good, test::coherent_bake(45, {4, 3, 3}, true, true, 7));
    const std::string path = dir.file("edited.h5");
    Outcome outcome;
    const hid_t text = H5Tcopy(H5T_C_S1);
    H5Tset_size(text, 7);
    const hid_t odd_int = H5Tcopy(H5T_STD_I32LE);
    H5Tset_precision(odd_int, 12);
    const hid_t compound = H5Tcreate(H5T_COMPOUND, 8);
    H5Tinsert(compound, "a", 0, H5T_STD_U32LE);
    H5Tinsert(compound, "b", 4, H5T_IEEE_F32LE);
    const hsize_t huge = hsize_t(1) << 40;
    for (const char* name : {"/pvs/code",
                             "/pvs/code_offsets",
                             "/pvs/cell_row",
                             "/pvs/rows",
                             "/cells/grid_to_cell",
                             "/cells/bounds",
                             "/cells/parent",
                             "/cells/view/bits",
                             "/cells/view/brick_index",
                             "/cells/view/brick_bits",
                             "/cells/eyes/brick_index",
                             "/cells/octree/first_child",
                             "/cells/octree/cell",
                             "/cells/octree/bounds",
                             "/objects/name",
                             "/objects/bounds",
                             "/objects/triangle_count",
                             "/parameters/keys",
                             "/figures/values",
                             "/occluders/bounds",
                             "/occluders/proven",
                             "/occluders/ranked_offsets",
                             "/occluders/ranked_box",
                             "/occluders/ranked_score",
                             "/occluders/ranked_solid_angle_sr",
                             "/occluders/ranked_hidden_objects",
                             "/occluders/ranked_hidden_triangle_share"}) {
        for (hid_t type : {H5T_IEEE_F64LE, H5T_STD_I8LE, H5T_STD_U64BE, text, odd_int, compound}) {
            edited(
                good, path, std::string(name) + " retyped",
                [&](hid_t f) { replace_dataset(f, name, type, {9}, 0, true); }, outcome);
        }
        edited(
            good, path, std::string(name) + " huge 1-D",
            [&](hid_t f) { replace_dataset(f, name, H5T_STD_U8LE, {huge}, 4096, false); }, outcome);
        edited(
            good, path, std::string(name) + " huge 2-D",
            [&](hid_t f) {
                replace_dataset(f, name, H5T_STD_U32LE, {huge, 6}, 1, false);
            },
            outcome);
        edited(
            good, path, std::string(name) + " 3-D",
            [&](hid_t f) {
                replace_dataset(f, name, H5T_STD_I32LE, {2, 2, 2}, 0, true);
            },
            outcome);
        edited(
            good, path, std::string(name) + " missing", [&](hid_t f) { H5Ldelete(f, name, H5P_DEFAULT); },
            outcome);
    }
    struct Attr {
        const char* object;
        const char* name;
    };
    for (const Attr& a :
         {Attr{"/", "format"}, Attr{"/", "format_major"}, Attr{"/", "conservative"}, Attr{"/", "mode"},
          Attr{"/cells", "dims"}, Attr{"/cells", "kind_code"}, Attr{"/cells", "cell_size_m"},
          Attr{"/cells/view", "dims"}, Attr{"/cells/view", "voxel_size_m"}, Attr{"/pvs", "object_count"},
          Attr{"/pvs", "cell_count"}, Attr{"/pvs", "unique_rows"}, Attr{"/verification", "ran"}}) {
        for (hid_t type : {H5T_IEEE_F64LE, H5T_STD_I64BE, text, odd_int, compound}) {
            for (hsize_t count : {hsize_t(1), hsize_t(3), hsize_t(5)}) {
                edited(
                    good, path, std::string(a.object) + " attribute " + a.name + " retyped",
                    [&](hid_t f) { replace_attribute(f, a.object, a.name, type, count); }, outcome);
            }
        }
    }
    H5Tclose(compound);
    H5Tclose(odd_int);
    H5Tclose(text);
    EXPECT_GT(outcome.refused, 200);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

}  // namespace
}  // namespace pvs
