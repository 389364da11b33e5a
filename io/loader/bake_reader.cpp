// SPDX-License-Identifier: MIT
// pvsbake loader (internal): the validated sections of a bake file (bake_reader.h).
#include "bake_reader.h"

#include "mask_bricks.h"
#include "row_code.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace pvsbake::detail {
namespace {

const char* kind_name(int32_t kind) {
    return kind == 1 ? "octree" : "grid";
}

uint8_t last_byte_mask(uint32_t objects) {
    return objects % 8 == 0 ? uint8_t(0xff) : uint8_t((1u << (objects % 8)) - 1);
}

// `count` boxes of the dataset `bounds` (6 floats each) under loc; count -1 accepts any and sets it.
std::vector<float> read_bounds(const Reader& r, hid_t loc, const std::string& where, int64_t& count) {
    std::vector<int64_t> shape = {count, 6};
    std::vector<float> flat =
        r.numeric_dataset<float>(loc, where, "bounds", H5T_NATIVE_FLOAT, shape, H5T_FLOAT);
    count = shape[0];
    return flat;
}

FileMask read_mask(const Reader& r, hid_t cells_group, const std::string& where, bool bricks) {
    Handle g = r.open_group(cells_group, where);
    FileMask mask;
    const std::vector<float> origin = r.numeric_attr<float>(g.get(), where, "origin", H5T_NATIVE_FLOAT, 3);
    std::copy(origin.begin(), origin.end(), mask.origin);
    mask.voxel_size_m = r.numeric_attr<float>(g.get(), where, "voxel_size_m", H5T_NATIVE_FLOAT, 1)[0];
    const std::vector<int32_t> dims = r.numeric_attr<int32_t>(g.get(), where, "dims", H5T_NATIVE_INT32, 3);
    std::copy(dims.begin(), dims.end(), mask.dims);
    mask.voxels = volume_of(mask.dims);
    if (mask.voxels == UINT64_MAX) r.fail(where + " attribute dims is negative or too large");
    if (bricks && r.has_link(g.get(), "brick_index")) {
        const uint64_t count =
            bricks_along(mask.dims[0]) * bricks_along(mask.dims[1]) * bricks_along(mask.dims[2]);
        std::vector<int64_t> index_shape = {-1};
        mask.brick_index = r.numeric_dataset<uint32_t>(g.get(), where, "brick_index", H5T_NATIVE_UINT32,
                                                       index_shape, H5T_INTEGER);
        if (mask.brick_index.empty()) return mask;  // no mask
        if (uint64_t(mask.brick_index.size()) != count) {
            r.fail(cat(where, "/brick_index has ", mask.brick_index.size(), " entries, expected 0 or ", count,
                       " (8 x 8 x 8 bricks of ", mask.dims[0], " x ", mask.dims[1], " x ", mask.dims[2],
                       " voxels)"));
        }
        std::vector<int64_t> bytes_shape = {-1};
        mask.brick_bytes = r.numeric_dataset<uint8_t>(g.get(), where, "brick_bits", H5T_NATIVE_UINT8,
                                                      bytes_shape, H5T_INTEGER);
        if (mask.brick_bytes.size() % kBrickBytes != 0)
            r.fail(cat(where, "/brick_bits has ", mask.brick_bytes.size(), " bytes, not a multiple of 64"));
        const uint64_t limit = kFirstBrick + mask.brick_bytes.size() / kBrickBytes;
        for (size_t b = 0; b < mask.brick_index.size(); ++b) {
            if (mask.brick_index[b] >= limit) {
                r.fail(cat(where, "/brick_index[", b, "] = ", mask.brick_index[b],
                           " is not 0, 1 or 2 + a brick below ", limit - kFirstBrick));
            }
        }
        mask.present = true;
        return mask;
    }
    std::vector<int64_t> shape = {-1};
    mask.bytes = r.numeric_dataset<uint8_t>(g.get(), where, "bits", H5T_NATIVE_UINT8, shape, H5T_INTEGER);
    if (mask.bytes.empty()) return mask;  // no mask
    if (uint64_t(mask.bytes.size()) != (mask.voxels + 7) / 8) {
        r.fail(cat(where, "/bits has ", mask.bytes.size(), " bytes, expected 0 or ", (mask.voxels + 7) / 8,
                   " for ", mask.voxels, " voxels"));
    }
    if (mask.voxels % 8 != 0 && (mask.bytes.back() >> (mask.voxels % 8)) != 0) {
        r.fail(cat(where, "/bits sets bits beyond voxel ", mask.voxels - 1));
    }
    mask.present = true;
    return mask;
}

void read_octree(const Reader& r, hid_t cells_group, FileCells& cells) {
    const std::string ow = "/cells/octree";
    Handle o = r.open_group(cells_group, ow);
    int64_t nodes = -1;
    cells.node_bounds = read_bounds(r, o.get(), ow, nodes);
    if (nodes > int64_t(INT32_MAX)) r.fail("/cells/octree/bounds has more than 2^31 nodes");
    cells.node_first_child =
        r.numeric_dataset<int32_t>(o.get(), ow, "first_child", H5T_NATIVE_INT32, {nodes}, H5T_INTEGER);
    cells.node_cell = r.numeric_dataset<int32_t>(o.get(), ow, "cell", H5T_NATIVE_INT32, {nodes}, H5T_INTEGER);
    cells.node_parent =
        r.numeric_dataset<int32_t>(o.get(), ow, "parent", H5T_NATIVE_INT32, {nodes}, H5T_INTEGER);
    // Children after their parent, so that a lookup always ends inside the arrays.
    for (int64_t i = 0; i < nodes; ++i) {
        const int32_t fc = cells.node_first_child[size_t(i)];
        if (fc != -1 && (fc <= i || int64_t(fc) + 8 > nodes)) {
            r.fail(cat("/cells/octree/first_child[", i, "] = ", fc,
                       " is not -1 or a node after it with 8 children below ", nodes));
        }
        const int32_t c = cells.node_cell[size_t(i)];
        if (c < -1 || int64_t(c) >= int64_t(cells.count)) {
            r.fail(
                cat("/cells/octree/cell[", i, "] = ", c, " is not -1 or a cell index below ", cells.count));
        }
        const int32_t p = cells.node_parent[size_t(i)];
        if (p < -1 || p >= nodes) {
            r.fail(cat("/cells/octree/parent[", i, "] = ", p, " is not -1 or a node index below ", nodes));
        }
    }
}

}  // namespace

uint64_t volume_of(const int32_t dims[3]) {
    if (dims[0] < 0 || dims[1] < 0 || dims[2] < 0) return UINT64_MAX;
    constexpr uint64_t kLimit = uint64_t(1) << 48;
    uint64_t v = 1;
    for (int a = 0; a < 3; ++a) {
        if (dims[a] != 0 && v > kLimit / uint64_t(dims[a])) return UINT64_MAX;
        v *= uint64_t(dims[a]);
    }
    return v;
}

Handle open_bake_file(const std::string& path, uint64_t& file_bytes) {
    const Reader site(path, 0);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) site.fail("no such file", Status::kFileMissing);
        site.fail(cat("cannot read: ", std::strerror(errno)), Status::kIoError);
    }
    struct stat st {};
    const int stat_result = ::fstat(fd, &st);
    ::close(fd);
    if (stat_result == 0 && S_ISDIR(st.st_mode))
        site.fail("is a folder, not a bake file", Status::kNotBakeFile);
    file_bytes = stat_result == 0 ? uint64_t(st.st_size) : 0;
    if (H5Fis_hdf5(path.c_str()) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        site.fail("not an HDF5 file", Status::kNotBakeFile);
    }
    Handle fapl = site.handle(file_access_list(), H5Pclose, "cannot create a file access list");
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get());
    if (file < 0) {
        // HDF5 says "truncated file: eof = A, sblock->base_addr = B, stored_eof = C": said in plain words.
        const std::string detail = hdf5_detail();
        unsigned long long eof = 0, base = 0, stored = 0;
        if (std::sscanf(detail.c_str(), "truncated file: eof = %llu, sblock->base_addr = %llu, stored_eof = %llu",
                        &eof, &base, &stored) == 3) {
            site.fail(cat("truncated: it holds ", eof, " of the ", stored,
                          " bytes it was written with (an interrupted copy?)"));
        }
        site.fail(detail.empty() ? "cannot open the HDF5 file (damaged?)"
                                 : cat("cannot open the HDF5 file (damaged?): ", detail));
    }
    return Handle(file, H5Fclose);
}

BakeInfo read_header(const Reader& r, hid_t root) {
    if (!r.has_attr(root, "format"))
        r.fail("not a pvsbake bake file (no 'format' attribute)", Status::kNotBakeFile);
    std::string format;
    try {
        format = r.string_attr(root, "/", "format");
    } catch (const ReadError&) {
        r.fail("not a pvsbake bake file ('format' is not text)", Status::kNotBakeFile);
    }
    if (format != kFormatName)
        r.fail(cat("not a pvsbake bake file (format is '", format, "')"), Status::kNotBakeFile);
    const int64_t major = r.int_attr(root, "/", "format_major");
    const int64_t minor = r.int_attr(root, "/", "format_minor");
    if (major > kFormatMajor) {
        r.fail(cat("bake format ", major, ".", minor, " is newer than this tool reads (", kFormatMajor,
                   ".x); use a newer pvsbake"),
               Status::kVersionTooNew);
    }
    if (major < kFormatMajor || minor < 0 || minor > INT32_MAX) {
        r.fail(cat("bake format ", major, ".", minor, " is not one this tool reads (", kFormatMajor, ".x)"));
    }
    BakeInfo h;
    h.format_major = int(major);
    h.format_minor = int(minor);
    h.tool_version = r.string_attr(root, "/", "tool_version");
    h.world_path = r.string_attr(root, "/", "world_path");
    h.world_hash = r.string_attr(root, "/", "world_hash");
    h.mode = r.string_attr(root, "/", "mode");
    const int64_t conservative = r.int_attr(root, "/", "conservative");
    if (conservative != 0 && conservative != 1) r.fail("root attribute 'conservative' is not 0 or 1");
    h.conservative = conservative == 1;
    return h;
}

std::vector<std::pair<std::string, std::string>> read_string_pairs(const Reader& r, hid_t loc,
                                                                   const std::string& where) {
    Handle g = r.open_group(loc, where);
    const std::vector<std::string> keys = r.string_dataset(g.get(), where, "keys", -1);
    const std::vector<std::string> values = r.string_dataset(g.get(), where, "values", int64_t(keys.size()));
    std::vector<std::pair<std::string, std::string>> out;
    for (size_t i = 0; i < keys.size(); ++i) out.emplace_back(keys[i], values[i]);
    return out;
}

FileObjects read_objects(const Reader& r, hid_t root) {
    Handle g = r.open_group(root, "/objects");
    FileObjects o;
    o.names = r.string_dataset(g.get(), "/objects", "name", -1);
    int64_t n = int64_t(o.names.size());
    if (n > int64_t(UINT32_MAX)) r.fail("/objects/name has more than 2^32 entries");
    o.bounds = read_bounds(r, g.get(), "/objects", n);
    o.triangle_count = r.numeric_dataset<uint32_t>(g.get(), "/objects", "triangle_count", H5T_NATIVE_UINT32,
                                                   {n}, H5T_INTEGER);
    o.flags = r.numeric_dataset<uint32_t>(g.get(), "/objects", "flags", H5T_NATIVE_UINT32, {n}, H5T_INTEGER);
    if (r.has_link(g.get(), "part_offsets")) {  // 1.9
        o.part_offsets = r.numeric_dataset<uint32_t>(g.get(), "/objects", "part_offsets", H5T_NATIVE_UINT32,
                                                     {n + 1}, H5T_INTEGER);
        std::vector<int64_t> shape = {-1, 6};
        o.part_boxes =
            r.numeric_dataset<float>(g.get(), "/objects", "part_boxes", H5T_NATIVE_FLOAT, shape, H5T_FLOAT);
        if (o.part_offsets[0] != 0 || int64_t(o.part_offsets.back()) != shape[0])
            r.fail("/objects/part_offsets does not start at 0 and end at the rows of /objects/part_boxes");
        for (int64_t i = 0; i < n; ++i) {
            const uint32_t a = o.part_offsets[size_t(i)], b = o.part_offsets[size_t(i) + 1];
            if (b < a || int64_t(b) > shape[0])
                r.fail(cat("/objects/part_offsets is not ascending within the part boxes at object ", i));
            const float* bounds = &o.bounds[6 * size_t(i)];
            for (uint32_t k = a; k < b; ++k) {
                const float* p = &o.part_boxes[6 * size_t(k)];
                bool ok = true;
                for (int c = 0; c < 3; ++c)
                    ok = ok && std::isfinite(p[c]) && std::isfinite(p[c + 3]) && p[c] <= p[c + 3] &&
                         p[c] >= bounds[c] && p[c + 3] <= bounds[c + 3];
                if (!ok || !part_on_runtime_grid(bounds, &o.part_boxes[6 * size_t(k)]))
                    r.fail(cat("/objects/part_boxes[", k, "] (object ", i,
                               ") is not a finite box inside the object's bounds"));
            }
        }
    }
    return o;
}

FileCells read_cells(const Reader& r, hid_t root, bool read_eyes, bool bricks) {
    const std::string where = "/cells";
    Handle g = r.open_group(root, where);
    FileCells cells;
    const int64_t kind = r.int_attr(g.get(), where, "kind_code");
    if (kind != 0 && kind != 1)
        r.fail(cat("/cells attribute kind_code is ", kind, ", expected 0 (grid) or 1 (octree)"));
    cells.kind = int32_t(kind);
    const std::string kind_text = r.string_attr(g.get(), where, "kind");
    if (kind_text != kind_name(cells.kind)) {
        r.fail(cat("/cells attribute kind '", kind_text, "' disagrees with kind_code ", kind));
    }
    const std::vector<float> origin = r.numeric_attr<float>(g.get(), where, "origin", H5T_NATIVE_FLOAT, 3);
    std::copy(origin.begin(), origin.end(), cells.origin);
    cells.cell_size_m = r.numeric_attr<float>(g.get(), where, "cell_size_m", H5T_NATIVE_FLOAT, 1)[0];
    const std::vector<int32_t> dims = r.numeric_attr<int32_t>(g.get(), where, "dims", H5T_NATIVE_INT32, 3);
    std::copy(dims.begin(), dims.end(), cells.dims);
    const uint64_t grid_size = volume_of(cells.dims);
    if (grid_size == UINT64_MAX) r.fail("/cells attribute dims is negative or too large");

    int64_t count = -1;
    cells.bounds = read_bounds(r, g.get(), where, count);
    if (count > int64_t(INT32_MAX)) r.fail("/cells/bounds has more than 2^31 cells");
    cells.count = uint32_t(count);
    cells.parent =
        r.numeric_dataset<int32_t>(g.get(), where, "parent", H5T_NATIVE_INT32, {count}, H5T_INTEGER);
    int64_t nodes = 0;
    if (cells.kind == 1) {
        read_octree(r, g.get(), cells);
        nodes = int64_t(cells.node_first_child.size());
    }
    for (size_t i = 0; i < cells.parent.size(); ++i) {
        if (cells.parent[i] < -1 || cells.parent[i] >= nodes) {
            r.fail(cat("/cells/parent[", i, "] = ", cells.parent[i],
                       " is not -1 or an octree node index below ", nodes));
        }
    }
    if (r.has_attr(g.get(), "cell_count") && r.int_attr(g.get(), where, "cell_count") != count) {
        r.fail(cat("/cells attribute cell_count disagrees with /cells/bounds (", count, " cells)"));
    }
    cells.grid_to_cell = r.numeric_dataset<int32_t>(g.get(), where, "grid_to_cell", H5T_NATIVE_INT32,
                                                    {int64_t(grid_size)}, H5T_INTEGER);
    const int64_t target = cells.kind == 1 ? nodes : count;
    for (size_t i = 0; i < cells.grid_to_cell.size(); ++i) {
        const int32_t c = cells.grid_to_cell[i];
        if (c < -1 || c >= target) {
            r.fail(cat("/cells/grid_to_cell[", i, "] = ", c, " is not -1 or a ",
                       cells.kind == 1 ? "root node" : "cell", " index below ", target));
        }
    }
    cells.view = read_mask(r, g.get(), "/cells/view", bricks);
    if (read_eyes) cells.eyes = read_mask(r, g.get(), "/cells/eyes", bricks);
    return cells;
}

FilePvs read_pvs(const Reader& r, hid_t root, uint32_t objects, uint32_t cells, bool want_rows) {
    const std::string where = "/pvs";
    Handle g = r.open_group(root, where);
    if (r.int_attr(g.get(), where, "object_count") != objects) {
        r.fail(cat("/pvs attribute object_count disagrees with /objects (", objects, " objects)"));
    }
    if (r.int_attr(g.get(), where, "cell_count") != cells) {
        r.fail(cat("/pvs attribute cell_count disagrees with /cells (", cells, " cells)"));
    }
    FilePvs pvs;
    pvs.row_bytes = (objects + 7) / 8;
    pvs.bytes_raw = uint64_t(cells) * pvs.row_bytes;
    if (r.has_attr(g.get(), "bytes_stored")) {
        pvs.bytes_stored =
            uint64_t(r.numeric_attr<uint64_t>(g.get(), where, "bytes_stored", H5T_NATIVE_UINT64, 1)[0]);
    }
    const bool use_code = !want_rows && r.has_link(g.get(), "code");
    int64_t unique_rows = -1;
    if (use_code) {
        std::vector<int64_t> offsets_shape = {-1};
        pvs.code_offsets = r.numeric_dataset<uint32_t>(g.get(), where, "code_offsets", H5T_NATIVE_UINT32,
                                                       offsets_shape, H5T_INTEGER);
        if (offsets_shape[0] < 1) r.fail("/pvs/code_offsets is empty");
        unique_rows = offsets_shape[0] - 1;
        std::vector<int64_t> code_shape = {-1};
        if (objects >= kMaxCodedObjects) r.fail("/pvs: too many objects for the PVS code");
        pvs.code = r.numeric_dataset<uint8_t>(g.get(), where, "code", H5T_NATIVE_UINT8, code_shape,
                                              H5T_INTEGER, code_padding(objects));
        const uint64_t code_size = uint64_t(code_shape[0]);
        // Format 1.4 files carry the code's checksum: then each row's head is checked and the bounded
        // decoders need no more (row_code.h). Older files: every index is decoded and checked.
        std::string bad;
        if (r.has_attr(g.get(), "code_xxh3")) {
            const uint64_t want =
                r.numeric_attr<uint64_t>(g.get(), where, "code_xxh3", H5T_NATIVE_UINT64, 1)[0];
            if (code_checksum(pvs.code.data(), code_size) != want)
                r.fail("/pvs/code does not match its checksum (attribute code_xxh3): damaged file");
            bad = check_row_heads(pvs.code.data(), code_size, pvs.code_offsets.data(), uint64_t(unique_rows),
                                  objects);
        } else {
            bad = check_row_code(pvs.code.data(), code_size, pvs.code_offsets.data(), uint64_t(unique_rows),
                                 objects);
        }
        if (!bad.empty()) r.fail(bad);
    } else {
        std::vector<int64_t> rows_shape = {-1, pvs.row_bytes};
        pvs.rows =
            r.numeric_dataset<uint8_t>(g.get(), where, "rows", H5T_NATIVE_UINT8, rows_shape, H5T_INTEGER);
        unique_rows = rows_shape[0];
        const uint8_t mask = last_byte_mask(objects);
        for (int64_t i = 0; pvs.row_bytes > 0 && i < unique_rows; ++i) {
            if (pvs.rows[size_t(i) * pvs.row_bytes + pvs.row_bytes - 1] & ~mask) {
                r.fail(cat("/pvs/rows row ", i, " sets bits beyond object ", int64_t(objects) - 1));
            }
        }
    }
    pvs.unique_rows = uint64_t(unique_rows);
    if (unique_rows > int64_t(cells))
        r.fail(cat("/pvs/rows has ", unique_rows, " rows, more than the ", cells, " cells"));
    if (r.has_attr(g.get(), "unique_rows") && r.int_attr(g.get(), where, "unique_rows") != unique_rows) {
        r.fail(cat("/pvs attribute unique_rows disagrees with /pvs/rows (", unique_rows, " rows)"));
    }
    pvs.cell_row =
        r.numeric_dataset<uint32_t>(g.get(), where, "cell_row", H5T_NATIVE_UINT32, {cells}, H5T_INTEGER);
    for (uint32_t c = 0; c < cells; ++c) {
        if (int64_t(pvs.cell_row[c]) >= unique_rows) {
            r.fail(cat("/pvs/cell_row[", c, "] = ", pvs.cell_row[c], " is not below the ", unique_rows,
                       " rows of /pvs/rows"));
        }
    }
    return pvs;
}

namespace {

// Format 1.7: the polygon occluders and the cells' ranked polygons (FileOccluders), checked.
void read_polygons(const Reader& r, hid_t g, uint32_t cells, FileOccluders& o) {
    const std::string where = "/occluders";
    std::vector<int64_t> shape = {-1};
    o.polygon_offsets =
        r.numeric_dataset<uint32_t>(g, where, "polygon_offsets", H5T_NATIVE_UINT32, shape, H5T_INTEGER);
    const int64_t polygons = shape[0] - 1;
    std::vector<int64_t> corner_shape = {-1, 3};
    o.polygon_corners =
        r.numeric_dataset<float>(g, where, "polygon_corners", H5T_NATIVE_FLOAT, corner_shape, H5T_FLOAT);
    o.polygon_planes =
        r.numeric_dataset<float>(g, where, "polygon_planes", H5T_NATIVE_FLOAT, {polygons, 5}, H5T_FLOAT);
    if (polygons < 0 || o.polygon_offsets[0] != 0 || int64_t(o.polygon_offsets.back()) != corner_shape[0])
        r.fail(
            "/occluders/polygon_offsets does not start at 0 and end at the rows of "
            "/occluders/polygon_corners");
    for (int64_t i = 0; i < polygons; ++i) {
        const uint32_t n = o.polygon_offsets[size_t(i) + 1] - o.polygon_offsets[size_t(i)];
        if (o.polygon_offsets[size_t(i) + 1] < o.polygon_offsets[size_t(i)] || n < 3 || n > 8)
            r.fail(cat("/occluders/polygon_offsets: polygon ", i, " does not have 3 to 8 corners"));
        const float* pl = &o.polygon_planes[5 * size_t(i)];
        bool ok = pl[4] >= 0.0f && (pl[0] != 0.0f || pl[1] != 0.0f || pl[2] != 0.0f);
        for (int k = 0; k < 5; ++k) ok = ok && std::isfinite(pl[k]);
        if (!ok) r.fail(cat("/occluders/polygon_planes[", i, "] is not a finite plane with thickness >= 0"));
    }
    for (size_t k = 0; k < o.polygon_corners.size(); ++k)
        if (!std::isfinite(o.polygon_corners[k]))
            r.fail(cat("/occluders/polygon_corners[", k / 3, "] is not finite"));
    o.ranked_polygon_offsets = r.numeric_dataset<uint32_t>(
        g, where, "ranked_polygon_offsets", H5T_NATIVE_UINT32, {int64_t(cells) + 1}, H5T_INTEGER);
    shape = {-1};
    o.ranked_polygon =
        r.numeric_dataset<uint32_t>(g, where, "ranked_polygon", H5T_NATIVE_UINT32, shape, H5T_INTEGER);
    const int64_t m = shape[0];
    o.ranked_polygon_rank =
        r.numeric_dataset<uint32_t>(g, where, "ranked_polygon_rank", H5T_NATIVE_UINT32, {m}, H5T_INTEGER);
    o.ranked_polygon_score =
        r.numeric_dataset<float>(g, where, "ranked_polygon_score", H5T_NATIVE_FLOAT, {m}, H5T_FLOAT);
    const std::vector<uint32_t>& off = o.ranked_polygon_offsets;
    if (off[0] != 0 || int64_t(off.back()) != m)
        r.fail(cat("/occluders/ranked_polygon_offsets does not start at 0 and end at ", m));
    for (uint32_t c = 0; c < cells; ++c) {
        if (off[c + 1] < off[c]) r.fail(cat("/occluders/ranked_polygon_offsets[", c + 1, "] decreases"));
        const uint32_t total = off[c + 1] - off[c] + o.ranked_offsets[c + 1] - o.ranked_offsets[c];
        for (uint32_t k = off[c]; k < off[c + 1]; ++k) {
            if (int64_t(o.ranked_polygon[k]) >= polygons)
                r.fail(cat("/occluders/ranked_polygon[", k, "] is not a polygon index below ", polygons));
            if (!std::isfinite(o.ranked_polygon_score[k]) || o.ranked_polygon_score[k] < 0.0f)
                r.fail(cat("/occluders/ranked_polygon_score[", k, "] is not a finite number >= 0"));
            if (o.ranked_polygon_rank[k] >= total ||
                (k > off[c] && o.ranked_polygon_rank[k] <= o.ranked_polygon_rank[k - 1]))
                r.fail(cat("/occluders/ranked_polygon_rank[", k, "] is not a place in cell ", c,
                           "'s list after the polygon before it"));
        }
    }
}

}  // namespace

FileHorizon read_horizon(const Reader& r, hid_t root, uint32_t cells, uint32_t objects) {
    FileHorizon h;
    if (!r.has_link(root, "horizon")) return h;  // older than 1.8, or a bake without lists
    h.present = true;
    const std::string where = "/horizon";
    Handle g = r.open_group(root, where);
    std::vector<int64_t> box_shape = {-1, 6};
    h.boxes = r.numeric_dataset<float>(g.get(), where, "boxes", H5T_NATIVE_FLOAT, box_shape, H5T_FLOAT);
    for (size_t i = 0; i < h.box_count(); ++i) {
        const float* b = &h.boxes[6 * i];
        bool ok = true;
        for (int a = 0; a < 3; ++a)
            ok = ok && std::isfinite(b[a]) && std::isfinite(b[a + 3]) && b[a] <= b[a + 3];
        if (!ok) r.fail(cat("/horizon/boxes[", i, "] is not a finite box with min <= max"));
    }
    std::vector<int64_t> shape = {-1};
    h.tile_offsets =
        r.numeric_dataset<uint32_t>(g.get(), where, "tile_offsets", H5T_NATIVE_UINT32, shape, H5T_INTEGER);
    const int64_t tiles = shape[0] - 1;
    std::vector<int64_t> corner_shape = {-1, 3};
    h.tile_corners =
        r.numeric_dataset<float>(g.get(), where, "tile_corners", H5T_NATIVE_FLOAT, corner_shape, H5T_FLOAT);
    h.tile_planes = r.numeric_dataset<float>(g.get(), where, "tile_planes", H5T_NATIVE_FLOAT,
                                             {std::max<int64_t>(tiles, 0), 5}, H5T_FLOAT);
    if (tiles < 0 || h.tile_offsets[0] != 0 || int64_t(h.tile_offsets.back()) != corner_shape[0])
        r.fail("/horizon/tile_offsets does not start at 0 and end at the rows of /horizon/tile_corners");
    for (int64_t i = 0; i < tiles; ++i) {
        const uint32_t a = h.tile_offsets[size_t(i)], b = h.tile_offsets[size_t(i) + 1];
        if (b < a || b - a < 3 || b - a > kHorizonTileMaxCorners)
            r.fail(cat("/horizon/tile_offsets: tile ", i, " does not have 3 to ", kHorizonTileMaxCorners,
                       " corners"));
        const float* pl = &h.tile_planes[5 * size_t(i)];
        bool ok = pl[4] >= 0.0f && (pl[0] != 0.0f || pl[1] != 0.0f || pl[2] != 0.0f);
        for (int k = 0; k < 5; ++k) ok = ok && std::isfinite(pl[k]);
        if (!ok) r.fail(cat("/horizon/tile_planes[", i, "] is not a finite plane with thickness >= 0"));
    }
    for (size_t k = 0; k < h.tile_corners.size(); ++k)
        if (!std::isfinite(h.tile_corners[k]))
            r.fail(cat("/horizon/tile_corners[", k / 3, "] is not finite"));
    h.list_offsets = r.numeric_dataset<uint32_t>(g.get(), where, "list_offsets", H5T_NATIVE_UINT32,
                                                 shape = {-1}, H5T_INTEGER);
    const int64_t lists = int64_t(h.list_offsets.size()) - 1;
    h.list_entries = r.numeric_dataset<uint32_t>(g.get(), where, "list_entries", H5T_NATIVE_UINT32,
                                                 shape = {-1}, H5T_INTEGER);
    h.cell_list = r.numeric_dataset<uint32_t>(g.get(), where, "cell_list", H5T_NATIVE_UINT32,
                                              {int64_t(cells)}, H5T_INTEGER);
    if (lists < 0 || h.list_offsets[0] != 0 || h.list_offsets.back() != h.list_entries.size())
        r.fail(cat("/horizon/list_offsets does not start at 0 and end at the ", h.list_entries.size(),
                   " entries of /horizon/list_entries"));
    const uint64_t occluders = h.box_count() + h.tile_count();
    for (int64_t l = 0; l < lists; ++l) {
        const uint32_t a = h.list_offsets[size_t(l)], b = h.list_offsets[size_t(l) + 1];
        if (b < a || b > h.list_entries.size())
            r.fail(cat("/horizon/list_offsets[", l + 1, "] decreases or passes the entries"));
        for (uint32_t k = a; k < b; ++k)
            if (h.list_entries[k] >= occluders || (k > a && h.list_entries[k] <= h.list_entries[k - 1]))
                r.fail(cat("/horizon/list_entries[", k, "] is not an occluder below ", occluders,
                           " after the one before it in its list"));
    }
    for (uint32_t c = 0; c < cells; ++c)
        if (int64_t(h.cell_list[c]) >= lists)
            r.fail(
                cat("/horizon/cell_list[", c, "] = ", h.cell_list[c], " is not below the ", lists, " lists"));
    if (r.has_link(g.get(), "test_offsets")) {  // 1.10
        h.test_offsets = r.numeric_dataset<uint32_t>(g.get(), where, "test_offsets", H5T_NATIVE_UINT32,
                                                     {int64_t(cells) + 1}, H5T_INTEGER);
        h.tests = r.numeric_dataset<uint32_t>(g.get(), where, "tests", H5T_NATIVE_UINT32, shape = {-1},
                                              H5T_INTEGER);
        if (h.test_offsets[0] != 0 || h.test_offsets.back() != h.tests.size())
            r.fail(cat("/horizon/test_offsets does not start at 0 and end at the ", h.tests.size(),
                       " entries of /horizon/tests"));
        for (uint32_t c = 0; c < cells; ++c) {
            const uint32_t a = h.test_offsets[c], b = h.test_offsets[size_t(c) + 1];
            if (b < a || b > h.tests.size())
                r.fail(cat("/horizon/test_offsets[", c + 1, "] decreases or passes the tests"));
            for (uint32_t k = a; k < b; ++k)
                if (h.tests[k] >= objects || (k > a && h.tests[k] <= h.tests[k - 1]))
                    r.fail(cat("/horizon/tests[", k, "] is not an object below ", objects,
                               " after the one before it in its cell's tests"));
        }
    }
    return h;
}

FileOccluders read_occluders(const Reader& r, hid_t root, uint32_t objects, uint32_t cells, bool want_boxes) {
    FileOccluders o;
    if (!r.has_link(root, "occluders")) return o;  // a bake made without occluders
    o.present = true;
    const std::string where = "/occluders";
    Handle g = r.open_group(root, where);
    const bool ranked = r.has_link(g.get(), "ranked_offsets");
    if (!want_boxes && !ranked) return o;
    int64_t n = -1;
    o.bounds = read_bounds(r, g.get(), where, n);
    o.count = uint64_t(n);
    o.proven = r.numeric_dataset<uint8_t>(g.get(), where, "proven", H5T_NATIVE_UINT8, {n}, H5T_INTEGER);
    for (int64_t i = 0; i < n; ++i) {
        if (o.proven[size_t(i)] > 1) r.fail(cat("/occluders/proven[", i, "] is not 0 or 1"));
    }
    if (want_boxes) {
        o.voxel_size_m =
            r.numeric_dataset<float>(g.get(), where, "voxel_size_m", H5T_NATIVE_FLOAT, {n}, H5T_FLOAT);
        o.object_offsets = r.numeric_dataset<uint32_t>(g.get(), where, "object_offsets", H5T_NATIVE_UINT32,
                                                       {n + 1}, H5T_INTEGER);
        std::vector<int64_t> objects_shape = {-1};
        o.objects = r.numeric_dataset<uint32_t>(g.get(), where, "objects", H5T_NATIVE_UINT32, objects_shape,
                                                H5T_INTEGER);
        if (o.object_offsets.empty() || o.object_offsets[0] != 0 ||
            o.object_offsets.back() != o.objects.size())
            r.fail("/occluders/object_offsets does not start at 0 and end at the size of /occluders/objects");
        for (int64_t i = 0; i < n; ++i) {
            if (o.object_offsets[size_t(i) + 1] < o.object_offsets[size_t(i)])
                r.fail(cat("/occluders/object_offsets[", i + 1, "] decreases"));
        }
        for (size_t k = 0; k < o.objects.size(); ++k) {
            if (o.objects[k] >= objects) {
                r.fail(cat("/occluders/objects[", k, "] = ", o.objects[k], " is not an object index below ",
                           objects));
            }
        }
    }
    if (!ranked) return o;
    o.ranked_offsets = r.numeric_dataset<uint32_t>(g.get(), where, "ranked_offsets", H5T_NATIVE_UINT32,
                                                   {int64_t(cells) + 1}, H5T_INTEGER);
    std::vector<int64_t> shape = {-1};
    o.ranked_box =
        r.numeric_dataset<uint32_t>(g.get(), where, "ranked_box", H5T_NATIVE_UINT32, shape, H5T_INTEGER);
    const int64_t m = shape[0];
    o.ranked_score =
        r.numeric_dataset<float>(g.get(), where, "ranked_score", H5T_NATIVE_FLOAT, {m}, H5T_FLOAT);
    o.ranked_solid_angle_sr =
        r.numeric_dataset<float>(g.get(), where, "ranked_solid_angle_sr", H5T_NATIVE_FLOAT, {m}, H5T_FLOAT);
    o.ranked_hidden_objects =
        r.numeric_dataset<float>(g.get(), where, "ranked_hidden_objects", H5T_NATIVE_FLOAT, {m}, H5T_FLOAT);
    o.ranked_hidden_triangle_share = r.numeric_dataset<float>(g.get(), where, "ranked_hidden_triangle_share",
                                                              H5T_NATIVE_FLOAT, {m}, H5T_FLOAT);
    const std::vector<uint32_t>& off = o.ranked_offsets;
    if (off[0] != 0 || int64_t(off.back()) != m) {
        r.fail(cat("/occluders/ranked_offsets does not start at 0 and end at ", m,
                   " (the size of /occluders/ranked_box)"));
    }
    for (uint32_t c = 0; c < cells; ++c) {
        if (off[c + 1] < off[c]) r.fail(cat("/occluders/ranked_offsets[", c + 1, "] decreases"));
    }
    constexpr double kFourPi = 12.566370614359172;
    // Each box once (a proven, finite box with min <= max), then each entry against that.
    std::vector<uint8_t> usable(size_t(o.count), 0);
    for (uint64_t box = 0; box < o.count; ++box) {
        const float* b = &o.bounds[size_t(box) * 6];
        bool ok = o.proven[size_t(box)] == 1;
        for (int a = 0; a < 3; ++a)
            ok = ok && std::isfinite(b[a]) && std::isfinite(b[a + 3]) && b[a] <= b[a + 3];
        usable[size_t(box)] = ok ? 1 : 0;
    }
    for (int64_t k = 0; k < m; ++k) {
        const size_t i = size_t(k);
        const uint32_t box = o.ranked_box[i];
        const float score = o.ranked_score[i], solid = o.ranked_solid_angle_sr[i];
        const float hidden = o.ranked_hidden_objects[i], share = o.ranked_hidden_triangle_share[i];
        const bool ok = box < o.count && usable[box] && std::isfinite(score) && score >= 0.0f &&
                        solid >= 0.0f && double(solid) <= kFourPi && hidden >= 0.0f &&
                        double(hidden) <= double(objects) && share >= 0.0f && share <= 1.0f;
        if (ok) continue;
        // Say what is wrong (cold).
        if (box >= o.count) {
            r.fail(cat("/occluders/ranked_box[", k, "] = ", box, " is not a box index below ", o.count));
        }
        if (o.proven[box] != 1) {
            r.fail(cat("/occluders/ranked_box[", k, "] = ", box, " names a box that is not proven"));
        }
        if (!usable[box]) {
            r.fail(cat("/occluders/bounds[", box, "] (ranked_box[", k,
                       "]) is not a finite box with min <= max"));
        }
        if (!std::isfinite(score) || score < 0.0f)
            r.fail(cat("/occluders/ranked_score[", k, "] is not a finite number >= 0"));
        if (!(solid >= 0.0f && double(solid) <= kFourPi))
            r.fail(cat("/occluders/ranked_solid_angle_sr[", k, "] is not in [0, 4 pi]"));
        if (!(hidden >= 0.0f && double(hidden) <= double(objects)))
            r.fail(cat("/occluders/ranked_hidden_objects[", k, "] is not in [0, ", objects, "]"));
        r.fail(cat("/occluders/ranked_hidden_triangle_share[", k, "] is not in [0, 1]"));
    }
    for (uint32_t c = 0; c < cells; ++c) {
        for (uint32_t k = off[c] + 1; k < off[c + 1]; ++k) {
            if (o.ranked_score[k] > o.ranked_score[k - 1]) {
                r.fail(cat("/occluders/ranked_score[", k, "] is higher than the entry before it in cell ", c,
                           " (entries must come best first)"));
            }
        }
    }
    if (r.has_link(g.get(), "polygon_offsets")) read_polygons(r, g.get(), cells, o);
    return o;
}

}  // namespace pvsbake::detail
