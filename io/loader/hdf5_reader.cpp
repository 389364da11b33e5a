// SPDX-License-Identifier: MIT
// pvsbake loader (internal): checked HDF5 reading (see hdf5_reader.h). Every check here guards against a
// kind of damaged file that crashed or exhausted HDF5 1.10.8 in fuzzing (docs/FORMAT.md, "Reading").
#include "hdf5_reader.h"

#include <cstring>

namespace pvsbake::detail {
namespace {

// Called by HDF5's C code: nothing may be thrown through it (an allocation that fails leaves the detail out).
herr_t innermost_error(unsigned n, const H5E_error2_t* err, void* out) noexcept {
    try {
        if (n == 0 && err->desc != nullptr) *static_cast<std::string*>(out) = err->desc;
    } catch (...) {
        return -1;
    }
    return 0;
}

template <class D>
std::string shape_text(const std::vector<D>& dims) {
    std::string s = "[";
    for (size_t i = 0; i < dims.size(); ++i) {
        if (i > 0) s += " x ";
        s += int64_t(dims[i]) < 0 ? std::string("any") : std::to_string(int64_t(dims[i]));
    }
    return s + "]";
}

}  // namespace

std::string hdf5_detail() {
    std::string detail;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost_error, &detail);
    H5Eclear2(H5E_DEFAULT);
    return detail;
}

hid_t file_access_list() {
    const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl >= 0 && H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0) {
        H5Pclose(fapl);
        return H5I_INVALID_HID;
    }
    return fapl;
}

void Reader::fail(const std::string& what, Status status) const {
    throw ReadError(status, path_ + ": " + what);
}

void Reader::fail_hdf5(const std::string& what) const {
    const std::string detail = hdf5_detail();
    fail(detail.empty() ? what : what + " (" + detail + ")");
}

bool Reader::has_attr(hid_t loc, const std::string& name) const {
    const htri_t r = H5Aexists(loc, name.c_str());
    if (r < 0) fail_hdf5("cannot look for attribute " + name);
    return r > 0;
}

bool Reader::has_link(hid_t loc, const std::string& name) const {
    return H5Lexists(loc, name.c_str(), H5P_DEFAULT) > 0;
}

Handle Reader::open_attr(hid_t loc, const std::string& where, const std::string& name) const {
    if (!has_attr(loc, name)) fail(cat(where, " has no attribute '", name, "'"));
    return handle(H5Aopen(loc, name.c_str(), H5P_DEFAULT), H5Aclose,
                  cat("cannot open attribute '", name, "' of ", where));
}

Handle Reader::open_group(hid_t loc, const std::string& where) const {
    const std::string name = where.substr(where.rfind('/') + 1);
    if (!has_link(loc, name)) fail("missing group " + where);
    return handle(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose, "cannot open group " + where);
}

Handle Reader::open_dataset(hid_t loc, const std::string& where, const std::string& name) const {
    if (!has_link(loc, name)) fail("missing dataset " + at(where, name));
    return handle(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose,
                  "cannot open dataset " + at(where, name));
}

std::vector<hsize_t> Reader::dims_of(hid_t space, const std::string& full) const {
    Handle s(space, H5Sclose);
    if (space < 0) fail_hdf5("cannot read the shape of " + full);
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 0 || rank > H5S_MAX_RANK) fail_hdf5("cannot read the shape of " + full);
    std::vector<hsize_t> dims(size_t(rank), 0);
    if (rank > 0 && H5Sget_simple_extent_dims(space, dims.data(), nullptr) < 0) {
        fail_hdf5("cannot read the shape of " + full);
    }
    return dims;
}

void Reader::check_storage(hid_t ds, uint64_t stored_element_bytes, const std::string& full) const {
    Handle space = handle(H5Dget_space(ds), H5Sclose, "cannot read the shape of " + full);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    hsize_t dims[H5S_MAX_RANK], max_dims[H5S_MAX_RANK];
    if (rank < 0 || rank > H5S_MAX_RANK || H5Sget_simple_extent_dims(space.get(), dims, max_dims) < 0) {
        fail_hdf5("cannot read the shape of " + full);
    }
    for (int i = 0; i < rank; ++i) {
        if (max_dims[i] != H5S_UNLIMITED && dims[i] > max_dims[i]) {
            fail(full + " is larger than its maximum size (damaged file?)");
        }
    }
    Handle dcpl = handle(H5Dget_create_plist(ds), H5Pclose, "cannot read the layout of " + full);
    const H5D_layout_t layout = H5Pget_layout(dcpl.get());
    if (layout == H5D_CHUNKED) {
        hsize_t chunk[H5S_MAX_RANK];
        if (H5Pget_chunk(dcpl.get(), H5S_MAX_RANK, chunk) != rank) fail(full + " has a damaged chunk layout");
        uint64_t chunk_bytes = stored_element_bytes;
        uint64_t chunks = 1;
        for (int i = 0; i < rank; ++i) {
            if (chunk[i] == 0 || (max_dims[i] != H5S_UNLIMITED && chunk[i] > max_dims[i])) {
                fail(full + " has a damaged chunk layout");
            }
            chunk_bytes *= chunk[i];
            if (chunk_bytes > (uint64_t(1) << 32)) fail(full + " has a damaged chunk layout");
            // HDF5 spends about 2.5 KB of memory on each chunk a read touches, and each stored chunk
            // takes well over 16 bytes of the file: a layout with more chunks than that is damaged.
            chunks *= (dims[i] + chunk[i] - 1) / chunk[i];
            if (chunks > max_chunks_) fail(full + " has more chunks than the file can hold (damaged file?)");
        }
        // Every stored chunk went through every filter (the writer never skips one). A damaged filter mask
        // says a deflated chunk was stored raw: HDF5 then copies a whole chunk's bytes out of the few it
        // read (fuzzing: 528 bytes from a 27-byte chunk). Unfiltered chunks must hold a whole chunk.
        const int filters = H5Pget_nfilters(dcpl.get());
        if (filters < 0) fail_hdf5("cannot read the filters of " + full);
        // By coordinate (a lookup in the chunk index each), not by index (HDF5 1.10 walks the index for
        // each): linear in the chunks, which are bounded above.
        hsize_t grid[H5S_MAX_RANK], at[H5S_MAX_RANK];
        for (int i = 0; i < rank; ++i) grid[i] = (dims[i] + chunk[i] - 1) / chunk[i];
        for (uint64_t n = 0; n < chunks && rank > 0; ++n) {
            uint64_t rest = n;
            for (int i = rank - 1; i >= 0; --i) {
                at[i] = (rest % grid[i]) * chunk[i];
                rest /= grid[i];
            }
            unsigned mask = 0;
            haddr_t addr = HADDR_UNDEF;
            hsize_t size = 0;
            if (H5Dget_chunk_info_by_coord(ds, at, &mask, &addr, &size) < 0)
                fail_hdf5("cannot read the chunks of " + full);
            if (addr == HADDR_UNDEF) continue;  // not stored: reads as fill values
            if (mask != 0) fail(full + " has a chunk stored without its filters (damaged file?)");
            if (filters == 0 && stored_element_bytes != 0 && size != chunk_bytes)
                fail(cat(full, " stores a chunk of ", uint64_t(size), " bytes, not ", chunk_bytes,
                         " (damaged file?)"));
        }
    } else if (layout == H5D_CONTIGUOUS) {
        uint64_t bytes = stored_element_bytes;
        for (int i = 0; i < rank; ++i) bytes *= dims[i];
        const hsize_t stored = H5Dget_storage_size(ds);
        if (stored_element_bytes != 0 && stored != 0 && stored != bytes) {
            fail(cat(full, " stores ", uint64_t(stored), " bytes for ", bytes,
                     " bytes of data (damaged file?)"));
        }
    } else if (layout == H5D_COMPACT) {
        // The writer never makes compact datasets, but a damaged layout can say compact: HDF5 then copies
        // the dataspace's bytes out of the compact buffer whatever its size (fuzzing: 528 bytes read from
        // a 30-byte buffer). The buffer must hold exactly the data.
        uint64_t bytes = stored_element_bytes;
        for (int i = 0; i < rank; ++i) bytes *= dims[i];
        const hsize_t stored = H5Dget_storage_size(ds);
        if (stored_element_bytes != 0 && stored != bytes) {
            fail(cat(full, " stores ", uint64_t(stored), " bytes for ", bytes,
                     " bytes of data (damaged file?)"));
        }
    } else {
        fail(full + " has an unknown storage layout");
    }
}

void Reader::check_storage(hid_t ds, const std::string& full) const {
    Handle t = handle(H5Dget_type(ds), H5Tclose, "cannot read the type of " + full);
    const size_t bytes = H5Tget_size(t.get());
    if (bytes == 0) fail_hdf5("cannot read the type of " + full);
    // A variable-length element's size on file is not its size in memory: check the chunks only.
    const bool variable = H5Tget_class(t.get()) == H5T_VLEN || H5Tis_variable_str(t.get()) > 0;
    check_storage(ds, variable ? 0 : bytes, full);
}

void Reader::check_budget(uint64_t count, uint64_t element_bytes, const std::string& full) const {
    if (element_bytes != 0 && count > max_bytes_ / element_bytes) {
        fail(cat(full, " claims ", count, " elements of ", element_bytes,
                 " bytes, more than the file can hold (damaged file?)"));
    }
}

H5T_class_t Reader::check_number_type(hid_t t, const std::string& full) const {
    const H5T_class_t c = H5Tget_class(t);
    if (c == H5T_INTEGER) {
        const size_t size = H5Tget_size(t);
        const size_t precision = H5Tget_precision(t);
        const int offset = H5Tget_offset(t);
        if ((size == 1 || size == 2 || size == 4 || size == 8) && precision > 0 && offset >= 0 &&
            size_t(offset) + precision <= 8 * size) {
            return c;
        }
        fail(full + " has a damaged integer type");
    }
    if (c == H5T_FLOAT) {
        for (hid_t ieee : {H5T_IEEE_F32LE, H5T_IEEE_F32BE, H5T_IEEE_F64LE, H5T_IEEE_F64BE}) {
            if (H5Tequal(t, ieee) > 0) return c;
        }
        fail(full + " has a float type that is not IEEE single or double");
    }
    fail(full + " is not a number");
}

std::vector<std::string> Reader::strings(hid_t obj, bool is_attr, const std::string& full,
                                         size_t count) const {
    const hid_t stored_type = is_attr ? H5Aget_type(obj) : H5Dget_type(obj);
    Handle ftype = handle(stored_type, H5Tclose, "cannot read the type of " + full);
    if (H5Tget_class(ftype.get()) != H5T_STRING) fail(full + " is not text");
    const htri_t variable = H5Tis_variable_str(ftype.get());
    if (variable < 0) fail_hdf5("cannot read the type of " + full);
    Handle mtype = handle(H5Tcopy(H5T_C_S1), H5Tclose, "cannot copy the string type");
    check(H5Tset_cset(mtype.get(), H5Tget_cset(ftype.get())), "cannot set the string encoding");
    check_budget(count, sizeof(std::string), full);
    std::vector<std::string> out(count);
    if (count == 0) return out;
    auto read = [&](void* buf) {
        return is_attr ? H5Aread(obj, mtype.get(), buf)
                       : H5Dread(obj, mtype.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    };
    if (variable > 0) {
        // Variable-length strings (pvsbake never stores them; other tools may) are read through the global
        // heap, which HDF5 does not check: a damaged one can still crash HDF5 here.
        check_budget(count, sizeof(char*), full);
        check(H5Tset_size(mtype.get(), H5T_VARIABLE), "cannot make a string type");
        std::vector<char*> ptrs(count, nullptr);
        const herr_t r = read(ptrs.data());
        std::string err;
        if (r < 0) err = hdf5_detail();
        for (size_t i = 0; i < count; ++i) {
            if (ptrs[i] != nullptr) out[i] = ptrs[i];
            H5free_memory(ptrs[i]);
        }
        if (r < 0) fail(cat("cannot read ", full, " (", err, ")"));
    } else {
        const size_t size = H5Tget_size(ftype.get());
        if (size == 0) fail_hdf5("cannot read the type of " + full);
        check_budget(count, size, full);
        check(H5Tset_size(mtype.get(), size), "cannot make a string type");
        check(H5Tset_strpad(mtype.get(), H5Tget_strpad(ftype.get())), "cannot make a string type");
        std::vector<char> buf(size * count);
        check(read(buf.data()), "cannot read " + full);
        for (size_t i = 0; i < count; ++i) {
            const char* s = buf.data() + i * size;
            out[i].assign(s, strnlen(s, size));
        }
    }
    return out;
}

std::string Reader::string_attr(hid_t loc, const std::string& where, const std::string& name) const {
    const std::string full = cat("attribute '", name, "' of ", where);
    Handle a = open_attr(loc, where, name);
    size_t n = 1;
    for (hsize_t d : dims_of(H5Aget_space(a.get()), full)) n *= size_t(d);
    if (n != 1) fail(full + " is not a single string");
    return strings(a.get(), true, full, 1)[0];
}

std::vector<std::string> Reader::string_dataset(hid_t loc, const std::string& where, const std::string& name,
                                                int64_t expected) const {
    const std::string full = at(where, name);
    Handle ds = open_dataset(loc, where, name);
    const std::vector<hsize_t> dims = dataset_dims(ds.get(), full);
    if (dims.size() != 1) fail(full + " is not one-dimensional");
    if (expected >= 0 && dims[0] != hsize_t(expected)) {
        fail(cat(full, " has ", uint64_t(dims[0]), " entries, expected ", expected));
    }
    check_storage(ds.get(), full);
    return strings(ds.get(), false, full, size_t(dims[0]));
}

uint64_t Reader::check_numeric_dataset(hid_t ds, const std::string& full, std::vector<int64_t>& expected,
                                       H5T_class_t want) const {
    const H5T_class_t c = number_type(H5Dget_type(ds), full);
    if (want != H5T_NO_CLASS && c != want) {
        fail(cat(full, " holds ", c == H5T_FLOAT ? "floats" : "integers", " where ",
                 want == H5T_FLOAT ? "floats" : "integers", " are expected"));
    }
    const std::vector<hsize_t> dims = dataset_dims(ds, full);
    bool ok = dims.size() == expected.size();
    for (size_t i = 0; ok && i < dims.size(); ++i) ok = expected[i] < 0 || dims[i] == hsize_t(expected[i]);
    if (!ok) fail(cat(full, " has shape ", shape_text(dims), " but ", shape_text(expected), " was expected"));
    uint64_t n = 1;
    for (size_t i = 0; i < dims.size(); ++i) {
        expected[i] = int64_t(dims[i]);
        check_budget(dims[i], 1, full);
        // Stepwise, so that the product of two damaged dimensions cannot wrap around to a small count.
        if (dims[i] != 0 && n > max_bytes_ / dims[i]) check_budget(max_bytes_, 2, full);
        n *= dims[i];
    }
    return n;
}

std::vector<std::pair<std::string, double>> Reader::named_values(hid_t loc, const std::string& where) const {
    Handle g = open_group(loc, where);
    const std::vector<std::string> names = string_dataset(g.get(), where, "names", -1);
    const std::vector<double> values =
        numeric_dataset<double>(g.get(), where, "values", H5T_NATIVE_DOUBLE, {int64_t(names.size())});
    std::vector<std::pair<std::string, double>> out;
    for (size_t i = 0; i < names.size(); ++i) out.emplace_back(names[i], values[i]);
    return out;
}

}  // namespace pvsbake::detail
