// SPDX-License-Identifier: MIT
// pvsbake io: HDF5 plumbing for the baker's files (the bake file, checkpoint chunks), with the HDF5 C API
// only. Handles, the quiet error stack and the validating Reader are the loader's (io/loader/hdf5_reader.h);
// files are written without object times and with creation order tracked, so the same content gives the
// same bytes.
#pragma once

#include "core/error.h"
#include "io/bake_file.h"
#include "io/loader/bake_reader.h"
#include "io/loader/hdf5_reader.h"

#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <atomic>
#include <new>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

namespace pvs::h5 {

using pvsbake::detail::at;
using pvsbake::detail::Handle;
using pvsbake::detail::hdf5_detail;

// Chunk size for the large datasets (FACTS.md: keep chunks at 32-128 KiB; one random row read inflates a
// whole chunk). Level 6 was measured against level 1 on a 20,000 x 3,000 PVS: see docs/FORMAT.md.
constexpr size_t kChunkBytes = 64 * 1024;
constexpr unsigned kGzipLevel = 6;

// ---------------------------------------------------------------------------------------------------------
// HDF5 plumbing for writing (handles and the quiet error stack come from io/loader/hdf5_reader.h).

// Names the file in every message and throws pvs::Error of one kind (kIo: the writer's failures).
class Site {
public:
    Site(std::string path, ErrorKind kind, std::string prefix)
        : path_(std::move(path)), kind_(kind), prefix_(std::move(prefix)) {}

    [[noreturn]] void fail(const std::string& what) const {
        throw Error(kind_, fmt::format("{}: {}{}", path_, prefix_, what));
    }
    // An HDF5 call failed: adds what HDF5 said.
    [[noreturn]] void fail_hdf5(const std::string& what) const {
        const std::string detail = hdf5_detail();
        fail(detail.empty() ? what : fmt::format("{} ({})", what, detail));
    }
    Handle handle(hid_t id, Handle::Closer closer, const std::string& what) const {
        if (id < 0) fail_hdf5(what);
        return Handle(id, closer);
    }
    void check(herr_t r, const std::string& what) const {
        if (r < 0) fail_hdf5(what);
    }

private:
    std::string path_;
    ErrorKind kind_;
    std::string prefix_;
};

// A fixed-length UTF-8 string type of `bytes` bytes, each string NUL-terminated inside it. Fixed, not
// variable-length: variable-length strings live in HDF5's global heap, and HDF5 1.10.8 reads a damaged
// global heap out of bounds (segfaults in H5HG_read when a fuzzed file is read); fixed-length strings are
// plain bytes in the dataset or attribute, so damage can only garble them. A C reader also gets them as
// one n x bytes buffer.
inline Handle string_type(const Site& site, size_t bytes) {
    Handle t = site.handle(H5Tcopy(H5T_C_S1), H5Tclose, "cannot copy the string type");
    site.check(H5Tset_size(t.get(), std::max<size_t>(bytes, 1)), "cannot size the string type");
    site.check(H5Tset_strpad(t.get(), H5T_STR_NULLTERM), "cannot set the string padding");
    site.check(H5Tset_cset(t.get(), H5T_CSET_UTF8), "cannot set UTF-8 on the string type");
    return t;
}

inline Handle file_access_list(const Site& site) {
    return site.handle(pvsbake::detail::file_access_list(), H5Pclose, "cannot create a file access list");
}

// Group creation list that remembers the order links and attributes were created in, so that
// `h5dump --sort_by=creation_order` shows them in the writer's order (by name is h5dump's default).
// No modification times in object headers (HDF5 stores them by default): the same bake gives the same bytes.
inline Handle ordered_group_list(const Site& site) {
    Handle gcpl = site.handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "cannot create a group creation list");
    const unsigned order = H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED;
    site.check(H5Pset_link_creation_order(gcpl.get(), order), "cannot track link order");
    site.check(H5Pset_attr_creation_order(gcpl.get(), order), "cannot track attribute order");
    site.check(H5Pset_obj_track_times(gcpl.get(), false), "cannot turn off object times");
    return gcpl;
}

// ---------------------------------------------------------------------------------------------------------
// Writing.

class Writer {
public:
    explicit Writer(const Site& site) : site_(site) {}

    Handle group(hid_t loc, const std::string& where, const std::string& name) {
        Handle gcpl = ordered_group_list(site_);
        return site_.handle(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose,
                            "cannot create group " + at(where, name));
    }

    void attr(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type, size_t count,
              const void* value) {
        Handle space;
        if (count == 1) {
            space = site_.handle(H5Screate(H5S_SCALAR), H5Sclose, "cannot create a dataspace");
        } else {
            const hsize_t dims[1] = {count};
            space = site_.handle(H5Screate_simple(1, dims, nullptr), H5Sclose, "cannot create a dataspace");
        }
        Handle a =
            site_.handle(H5Acreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                         H5Aclose, "cannot create attribute " + name);
        site_.check(H5Awrite(a.get(), mem_type, value), "cannot write attribute " + name);
    }
    void string_attr(hid_t loc, const std::string& name, const std::string& value) {
        Handle t = string_type(site_, value.size() + 1);
        attr(loc, name, t.get(), t.get(), 1, value.c_str());
    }
    void int_attr(hid_t loc, const std::string& name, int32_t value) {
        attr(loc, name, H5T_STD_I32LE, H5T_NATIVE_INT32, 1, &value);
    }
    void u32_attr(hid_t loc, const std::string& name, uint32_t value) {
        attr(loc, name, H5T_STD_U32LE, H5T_NATIVE_UINT32, 1, &value);
    }
    void u64_attr(hid_t loc, const std::string& name, uint64_t value) {
        attr(loc, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, 1, &value);
    }

    // A dataset of the given shape. compress: chunked (~kChunkBytes per chunk, whole rows) and deflated.
    // A dataset with a zero dimension is written contiguous and empty (HDF5 refuses zero chunk sizes).
    Handle dataset(hid_t loc, const std::string& where, const std::string& name, hid_t file_type,
                   hid_t mem_type, std::vector<hsize_t> dims, const void* data, bool compress = false) {
        const std::string full = at(where, name);
        Handle space = site_.handle(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose,
                                    "cannot create the dataspace of " + full);
        Handle dcpl = site_.handle(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "cannot create a dataset list");
        site_.check(H5Pset_obj_track_times(dcpl.get(), false), "cannot turn off object times");
        const bool empty = std::any_of(dims.begin(), dims.end(), [](hsize_t d) { return d == 0; });
        if (compress && !empty) {
            hsize_t inner = H5Tget_size(file_type);
            for (size_t i = 1; i < dims.size(); ++i) inner *= dims[i];
            std::vector<hsize_t> chunk = dims;
            chunk[0] = std::clamp<hsize_t>(kChunkBytes / std::max<hsize_t>(inner, 1), 1, dims[0]);
            site_.check(H5Pset_chunk(dcpl.get(), int(chunk.size()), chunk.data()), "cannot chunk " + full);
            // Shuffle groups the bytes of multi-byte integers before deflate: grid_to_cell (a mostly
            // increasing int32 index) shrank from 27,970 to 1,068 bytes on a 20,000-cell grid. The PVS rows
            // are bytes, where shuffle does nothing, so they go without it.
            if (H5Tget_class(file_type) == H5T_INTEGER && H5Tget_size(file_type) > 1) {
                site_.check(H5Pset_shuffle(dcpl.get()), "cannot set shuffle on " + full);
            }
            site_.check(H5Pset_deflate(dcpl.get(), kGzipLevel), "cannot set gzip on " + full);
        }
        Handle ds = site_.handle(
            H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
            H5Dclose, "cannot create dataset " + full);
        if (!empty) {
            site_.check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
                        "cannot write dataset " + full);
        }
        return ds;
    }

    void string_dataset(hid_t loc, const std::string& where, const std::string& name,
                        const std::vector<std::string>& values) {
        size_t longest = 0;
        for (const std::string& s : values) longest = std::max(longest, s.size());
        const size_t stride = longest + 1;
        std::vector<char> buf(values.size() * stride, '\0');
        for (size_t i = 0; i < values.size(); ++i) values[i].copy(&buf[i * stride], values[i].size());
        Handle t = string_type(site_, stride);
        // Padding compresses well: a long string list (object names) is chunked and deflated.
        dataset(loc, where, name, t.get(), t.get(), {values.size()}, buf.data(), buf.size() > kChunkBytes);
    }

    // A group holding one attribute per name (for a quick look) and the ordered pair of datasets
    // names/values (the authoritative copy: attributes cannot keep a duplicate or an empty name).
    void named_values(hid_t loc, const std::string& where, const std::string& name, const NamedValues& values,
                      const char* units) {
        Handle g = group(loc, where, name);
        const std::string full = at(where, name);
        std::vector<std::string> names;
        std::vector<double> numbers;
        std::unordered_set<std::string> seen;
        for (const auto& [n, v] : values) {
            names.push_back(n);
            numbers.push_back(v);
            if (!n.empty() && seen.insert(n).second)
                attr(g.get(), n, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, &v);
        }
        string_dataset(g.get(), full, "names", names);
        Handle ds = dataset(g.get(), full, "values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {numbers.size()},
                            numbers.data());
        if (units != nullptr) string_attr(ds.get(), "units", units);
    }

    const Site& site() const { return site_; }

private:
    const Site& site_;
};

// An HDF5 file built in memory (the core driver, no backing store), with the lists above. The writers build
// their files whole in memory and hand the bytes to write_file_atomically() (io/atomic_file.h): HDF5 itself
// never touches the disk, so a full disk or a failing write is met by our own checked calls, with its errno,
// and never leaves the library's state half-flushed (docs/ALGORITHMS.md#faults).
inline Handle create_memory_file(const Site& site) {
    Handle fapl = file_access_list(site);
    // Grows by 1 MiB steps; the image taken at the end is as long as the file, not its steps.
    site.check(H5Pset_fapl_core(fapl.get(), size_t(1) << 20, false), "cannot set the in-memory file driver");
    Handle fcpl = site.handle(H5Pcreate(H5P_FILE_CREATE), H5Pclose, "cannot create a file creation list");
    const unsigned order = H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED;
    site.check(H5Pset_link_creation_order(fcpl.get(), order), "cannot track link order");
    site.check(H5Pset_attr_creation_order(fcpl.get(), order), "cannot track attribute order");
    site.check(H5Pset_obj_track_times(fcpl.get(), false), "cannot turn off object times");
    // The name is only the in-memory file's: nothing is created under it. Unique, so that two such files may
    // be open at once (the core driver tells files apart by name).
    static std::atomic<uint64_t> counter{0};
    const std::string name = fmt::format("pvsbake-in-memory-{}.h5", counter.fetch_add(1));
    return site.handle(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), H5Fclose,
                       "cannot create the file in memory");
}

// The bytes of a file create_memory_file() made (every object in it closed but the file), then closes it.
inline std::string take_file_image(const Site& site, Handle& file) {
    // HDF5 1.10.8's H5Fget_file_image does not flush the metadata cache first: without this flush the image
    // lacks the root group's object header.
    site.check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "cannot flush the file in memory");
    const ssize_t size = H5Fget_file_image(file.get(), nullptr, 0);
    if (size < 0) site.fail_hdf5("cannot take the file's bytes from memory");
    std::string bytes(size_t(size), '\0');
    if (size > 0 && H5Fget_file_image(file.get(), bytes.data(), bytes.size()) != size)
        site.fail_hdf5("cannot take the file's bytes from memory");
    site.check(file.close(), "cannot close the file in memory");
    return bytes;
}

// A group of (key, value) text pairs: one attribute per key, and the datasets keys and values.
inline void write_string_pairs(Writer& w, hid_t loc, const std::string& where, const std::string& name,
                               const NamedStrings& pairs) {
    Handle g = w.group(loc, where, name);
    const std::string full = at(where, name);
    std::vector<std::string> keys, values;
    std::unordered_set<std::string> seen;
    for (const auto& [k, v] : pairs) {
        keys.push_back(k);
        values.push_back(v);
        if (!k.empty() && seen.insert(k).second) w.string_attr(g.get(), k, v);
    }
    w.string_dataset(g.get(), full, "keys", keys);
    w.string_dataset(g.get(), full, "values", values);
}

// Opens the HDF5 file at `path` and returns body(reader, root) under the loader's guards: a dataset too large
// to load fails as damage, and the reader's failures become pvs::Error (kIo when reading failed, else bad
// input), naming the file.
template <class Body>
auto read_file(const std::string& path, Body&& body) {
    pvsbake::detail::QuietHdf5 quiet;
    try {
        uint64_t file_bytes = 0;
        Handle file = pvsbake::detail::open_bake_file(path, file_bytes);
        const pvsbake::detail::Reader r(path, file_bytes);
        try {
            Handle root = r.handle(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose, "cannot open /");
            return body(r, root.get());
        } catch (const std::bad_alloc&) {
            r.fail("a dataset is too large to load (damaged file?)");
        } catch (const std::length_error&) {
            r.fail("a dataset is too large to load (damaged file?)");
        }
    } catch (const pvsbake::detail::ReadError& e) {
        if (e.status() == pvsbake::Status::kIoError) throw io_error(e.what());
        throw bad_input(e.what());
    }
}

}  // namespace pvs::h5
