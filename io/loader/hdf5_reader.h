// SPDX-License-Identifier: MIT
// pvsbake loader (internal): checked reading of HDF5 files with the HDF5 C library alone. The one place
// that knows how HDF5 1.10.8 must be guarded against damaged files (docs/FORMAT.md, "Reading"); both the
// baker's reader (io/bake_file.cpp, read_bake_file) and the runtime loader (pvsbake::Bake::load) use it.
// Not installed: HDF5 types stay out of the public headers.
//
// Conventions: every failure throws ReadError with a status and a one-line message that starts with the
// file's path ("<path>: /pvs/cell_row has shape [8] but [9] was expected"). The callers catch it: the
// loader turns it into its status, read_bake_file into pvs::Error (kBadInput).
#pragma once

#include "pvsbake/loader.h"

#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace pvsbake::detail {

class ReadError : public std::runtime_error {
public:
    ReadError(Status status, const std::string& message) : std::runtime_error(message), status_(status) {}
    Status status() const { return status_; }

private:
    Status status_;
};

// Text of integers and strings, concatenated (the loader links no formatting library).
inline void append(std::string& out, const std::string& s) {
    out += s;
}
inline void append(std::string& out, const char* s) {
    out += s;
}
template <class T, std::enable_if_t<std::is_integral_v<T>, int> = 0>
void append(std::string& out, T v) {
    out += std::to_string(v);
}
template <class... A>
std::string cat(const A&... parts) {
    std::string out;
    (append(out, parts), ...);
    return out;
}

// Where an object sits in the file, for messages: at("/pvs", "rows") = "/pvs/rows".
inline std::string at(const std::string& group, const std::string& name) {
    return group == "/" ? "/" + name : group + "/" + name;
}

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Handle {
public:
    using Closer = herr_t (*)(hid_t);
    Handle() = default;
    Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
    Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), closer_(o.closer_) {}
    Handle& operator=(Handle&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, H5I_INVALID_HID);
            closer_ = o.closer_;
        }
        return *this;
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle() { reset(); }

    hid_t get() const { return id_; }
    // Closes now and reports the result (a file's close is where its last bytes reach the disk).
    herr_t close() {
        const herr_t r = id_ >= 0 ? closer_(id_) : 0;
        id_ = H5I_INVALID_HID;
        return r;
    }

private:
    void reset() {
        if (id_ >= 0) closer_(id_);
        id_ = H5I_INVALID_HID;
    }
    hid_t id_ = H5I_INVALID_HID;
    Closer closer_ = nullptr;
};

// Turns off HDF5's automatic printing of its error stack while alive (and restores what was set before);
// failures become our messages.
class QuietHdf5 {
public:
    QuietHdf5() {
        H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    }
    ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
    QuietHdf5(const QuietHdf5&) = delete;
    QuietHdf5& operator=(const QuietHdf5&) = delete;

private:
    H5E_auto2_t func_ = nullptr;
    void* data_ = nullptr;
};

// The description of the deepest entry of HDF5's current error stack (where the failure started), then
// clears the stack.
std::string hdf5_detail();

// The file access list both the writer and the readers use: close degree STRONG (H5Fclose closes every
// object still open in the file), file locking at the library default (an explicit H5Pset_file_locking
// makes a second open of the same file in one process fail with "file locking flag values don't match").
hid_t file_access_list();

// Checked reads from one open file. HDF5 1.10.8 trusts what a file says about its types and sizes: a
// damaged element size or compound member offset makes H5Dread copy out of bounds, and a damaged dimension
// makes us allocate gigabytes. So every stored type is checked (numbers of 1-8 bytes, IEEE floats), and a
// dataset larger than the file could hold even at deflate's best ratio (~1032:1) is refused.
class Reader {
public:
    Reader(std::string path, uint64_t file_bytes)
        : path_(std::move(path)),
          max_bytes_(file_bytes * 1100 + (1u << 20)),
          max_chunks_(file_bytes / 16 + 1024) {}

    const std::string& path() const { return path_; }
    [[noreturn]] void fail(const std::string& what, Status status = Status::kCorrupt) const;
    // An HDF5 call failed: adds what HDF5 said.
    [[noreturn]] void fail_hdf5(const std::string& what) const;
    Handle handle(hid_t id, Handle::Closer closer, const std::string& what) const {
        if (id < 0) fail_hdf5(what);
        return Handle(id, closer);
    }
    void check(herr_t r, const std::string& what) const {
        if (r < 0) fail_hdf5(what);
    }

    bool has_attr(hid_t loc, const std::string& name) const;
    bool has_link(hid_t loc, const std::string& name) const;
    Handle open_attr(hid_t loc, const std::string& where, const std::string& name) const;
    Handle open_group(hid_t loc, const std::string& where) const;
    Handle open_dataset(hid_t loc, const std::string& where, const std::string& name) const;

    // Dimensions of an attribute's or a dataset's space (takes ownership of space); a scalar has none.
    std::vector<hsize_t> dims_of(hid_t space, const std::string& full) const;
    std::vector<hsize_t> dataset_dims(hid_t ds, const std::string& full) const {
        return dims_of(H5Dget_space(ds), full);
    }

    // Fails unless the dataset's storage fits its shape: chunks no larger than the dataset's maximum
    // dimensions and not too many of them, and contiguous storage of exactly the dataset's bytes (or none
    // yet). HDF5 enforces that when it creates a dataset but trusts a damaged file: a chunk dimension
    // damaged to 14,286,849 made H5Dread copy out of bounds.
    void check_storage(hid_t ds, uint64_t stored_element_bytes, const std::string& full) const;
    void check_storage(hid_t ds, const std::string& full) const;
    // Fails unless `count` elements of `element_bytes` each could come from this file.
    void check_budget(uint64_t count, uint64_t element_bytes, const std::string& full) const;
    // Fails unless t is a sound integer (1, 2, 4 or 8 bytes) or IEEE float type; returns its class.
    H5T_class_t check_number_type(hid_t t, const std::string& full) const;
    // Takes ownership of type_id.
    H5T_class_t number_type(hid_t type_id, const std::string& full) const {
        Handle t = handle(type_id, H5Tclose, "cannot read the type of " + full);
        return check_number_type(t.get(), full);
    }

    // A numeric attribute with exactly `count` values (a scalar when count is 1).
    template <class T>
    std::vector<T> numeric_attr(hid_t loc, const std::string& where, const std::string& name, hid_t mem_type,
                                size_t count) const {
        const std::string full = cat("attribute '", name, "' of ", where);
        Handle a = open_attr(loc, where, name);
        number_type(H5Aget_type(a.get()), full);
        size_t n = 1;
        for (hsize_t d : dims_of(H5Aget_space(a.get()), full)) n *= size_t(d);
        if (n != count) fail(cat(full, " has ", n, " values, expected ", count));
        std::vector<T> out(count);
        check(H5Aread(a.get(), mem_type, out.data()), "cannot read " + full);
        return out;
    }
    int64_t int_attr(hid_t loc, const std::string& where, const std::string& name) const {
        return numeric_attr<int64_t>(loc, where, name, H5T_NATIVE_INT64, 1)[0];
    }

    // Strings of a dataset or an attribute, variable-length or fixed-length.
    std::vector<std::string> strings(hid_t obj, bool is_attr, const std::string& full, size_t count) const;
    std::string string_attr(hid_t loc, const std::string& where, const std::string& name) const;
    // A one-dimensional string dataset of `expected` entries (-1: any).
    std::vector<std::string> string_dataset(hid_t loc, const std::string& where, const std::string& name,
                                            int64_t expected) const;

    // A numeric dataset whose shape must equal `expected` (a -1 entry accepts any size on that axis, and
    // `expected` then receives the actual size). want: H5T_INTEGER or H5T_FLOAT, or H5T_NO_CLASS for any.
    // padding: zero elements appended after the data.
    template <class T>
    std::vector<T> numeric_dataset(hid_t loc, const std::string& where, const std::string& name,
                                   hid_t mem_type, std::vector<int64_t>& expected,
                                   H5T_class_t want = H5T_NO_CLASS, size_t padding = 0) const {
        const std::string full = at(where, name);
        Handle ds = open_dataset(loc, where, name);
        const uint64_t n = check_numeric_dataset(ds.get(), full, expected, want);
        check_budget(n, std::max(sizeof(T), H5Tget_size(mem_type)), full);
        std::vector<T> out(static_cast<size_t>(n) + padding);
        check_storage(ds.get(), full);
        if (n > 0) {
            check(H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
                  "cannot read " + full);
        }
        return out;
    }
    template <class T>
    std::vector<T> numeric_dataset(hid_t loc, const std::string& where, const std::string& name,
                                   hid_t mem_type, std::vector<int64_t>&& expected,
                                   H5T_class_t want = H5T_NO_CLASS) const {
        std::vector<int64_t> e = std::move(expected);
        return numeric_dataset<T>(loc, where, name, mem_type, e, want);
    }

    // A named list (docs/FORMAT.md): the datasets `names` and `values` of the group at `where`.
    std::vector<std::pair<std::string, double>> named_values(hid_t loc, const std::string& where) const;

private:
    // Checks the type class and shape of a numeric dataset (see numeric_dataset); returns its element count.
    uint64_t check_numeric_dataset(hid_t ds, const std::string& full, std::vector<int64_t>& expected,
                                   H5T_class_t want) const;

    std::string path_;
    uint64_t max_bytes_;
    uint64_t max_chunks_;
};

}  // namespace pvsbake::detail
