// SPDX-License-Identifier: MIT
// pvsbake io: writes and reads the HDF5 bake file, format 1.2 (layout in docs/FORMAT.md), with the HDF5 C
// API only (the runtime loader must depend on libhdf5 alone). The writer dedupes PVS rows, builds the file in
// memory and writes it whole through write_file_atomically() (io/atomic_file.h). The reader is the loader
// library's (io/loader/bake_reader.h: one validating reader of the format, shared with the runtime); this
// file turns its sections into a BakeData and its failures into a pvs::Error naming the file.
#include "io/bake_file.h"

#include "core/config.h"
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/hdf5_file.h"
#include "io/loader/bake_reader.h"
#include "io/loader/hdf5_reader.h"
#include "io/loader/mask_bricks.h"
#include "io/loader/row_code.h"

#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace pvs {
namespace {

using h5::kChunkBytes;
using h5::Site;
using h5::string_type;
using h5::write_string_pairs;
using h5::Writer;
using pvsbake::detail::at;
using pvsbake::detail::Handle;
using pvsbake::detail::hdf5_detail;
using pvsbake::detail::QuietHdf5;
using pvsbake::detail::Reader;

static_assert(pvsbake::detail::kFormatMajor == kBakeFormatMajor &&
                  pvsbake::detail::kFormatMinor == kBakeFormatMinor,
              "the loader and the baker must read and write the same format version");

using pvsbake::detail::kFormatName;
constexpr const char* kConservativeNote = "conservative";
constexpr const char* kAggressiveNote = "aggressive (sampled: may miss visible objects)";
constexpr const char* kBoundsColumns = "min_x, min_y, min_z, max_x, max_y, max_z";

// A miss as it is laid out in memory for HDF5 (the file type is the packed little-endian twin).
struct MissRecord {
    uint32_t cell;
    uint32_t object;
    float eye[3];
    float direction[3];
    float distance_m;
    float opening_width_m;
};

// The compound type of /verification/misses: native (in memory) or packed little-endian (on file).
// Site: the writer's Site or the reader's Reader (both name the file and add what HDF5 said).
// `with_width`: the member opening_width_m (format 1.3) is part of the type.
template <class Site>
Handle miss_type(const Site& site, bool on_file, bool with_width = true) {
    const hsize_t three[1] = {3};
    const hid_t u32 = on_file ? H5T_STD_U32LE : H5T_NATIVE_UINT32;
    const hid_t f32 = on_file ? H5T_IEEE_F32LE : H5T_NATIVE_FLOAT;
    Handle vec3 = site.handle(H5Tarray_create2(f32, 1, three), H5Tclose, "cannot create the float[3] type");
    const size_t size = on_file ? (with_width ? 40 : 36) : sizeof(MissRecord);
    Handle t = site.handle(H5Tcreate(H5T_COMPOUND, size), H5Tclose, "cannot create the miss type");
    const size_t off_cell = on_file ? 0 : offsetof(MissRecord, cell);
    const size_t off_object = on_file ? 4 : offsetof(MissRecord, object);
    const size_t off_eye = on_file ? 8 : offsetof(MissRecord, eye);
    const size_t off_direction = on_file ? 20 : offsetof(MissRecord, direction);
    const size_t off_distance = on_file ? 32 : offsetof(MissRecord, distance_m);
    bool ok = H5Tinsert(t.get(), "cell", off_cell, u32) >= 0;
    ok = ok && H5Tinsert(t.get(), "object", off_object, u32) >= 0;
    ok = ok && H5Tinsert(t.get(), "eye", off_eye, vec3.get()) >= 0;
    ok = ok && H5Tinsert(t.get(), "direction", off_direction, vec3.get()) >= 0;
    ok = ok && H5Tinsert(t.get(), "distance_m", off_distance, f32) >= 0;
    const size_t off_width = on_file ? 36 : offsetof(MissRecord, opening_width_m);
    if (with_width) ok = ok && H5Tinsert(t.get(), "opening_width_m", off_width, f32) >= 0;
    if (!ok) site.fail_hdf5("cannot build the miss type");
    return t;
}

uint32_t bytes_per_row(uint32_t objects) {
    return (objects + 7) / 8;
}

// Byte j of a PVS row from its 64-bit words (object i is bit i % 8 of byte i / 8, on any endianness).
uint8_t row_byte(const uint64_t* words, uint32_t j) {
    return uint8_t(words[j / 8] >> (8 * (j % 8)));
}

// The mask of the valid bits of a row's last byte (0xff when the object count is a multiple of 8).
uint8_t last_byte_mask(uint32_t objects) {
    return objects % 8 == 0 ? uint8_t(0xff) : uint8_t((1u << (objects % 8)) - 1);
}

// dims.x * dims.y * dims.z, or UINT64_MAX when a dimension is negative or the product passes 2^48 (a grid
// or voxel mask that large could not be held in memory anyway; the limit keeps the product from wrapping).
uint64_t volume_of(glm::ivec3 d) {
    const int32_t dims[3] = {d.x, d.y, d.z};
    return pvsbake::detail::volume_of(dims);
}

// The writer refuses what the reader would refuse: a file it writes is always readable.
void check_writable(const std::string& path, const BakeData& bake) {
    auto bad = [&](const std::string& what) {
        throw internal_error(fmt::format("{}: cannot write the bake file: {}", path, what));
    };
    const size_t cells = bake.cells.size();
    const size_t objects = bake.objects.size();
    if (cells > UINT32_MAX || objects > UINT32_MAX) bad("more than 2^32 cells or objects");
    const PvsSet& pvs = bake.pvs;
    if (pvs.cell_count != cells || pvs.object_count != objects || pvs.words_per_row != (objects + 63) / 64 ||
        pvs.words.size() != size_t(pvs.cell_count) * pvs.words_per_row) {
        bad(fmt::format(
            "the PVS is {} cells x {} objects ({} words) but the bake has {} cells and {} objects",
            pvs.cell_count, pvs.object_count, pvs.words.size(), cells, objects));
    }
    const uint64_t grid_size = volume_of(bake.cells.dims);
    if (grid_size == UINT64_MAX) bad("grid dims negative or too large");
    if (grid_size != bake.cells.grid_to_cell.size()) {
        bad("grid_to_cell does not have dims.x * dims.y * dims.z entries");
    }
    for (const auto& [mask, name] :
         {std::pair{&bake.cells.view, "view"}, std::pair{&bake.cells.eyes, "eyes"}}) {
        const uint64_t voxels = volume_of(mask->dims);
        if (voxels == UINT64_MAX) bad(fmt::format("the {} mask's dims are negative or too large", name));
        if (!mask->bits.empty() && mask->bits.size() != (voxels + 63) / 64) {
            bad(fmt::format("the {} mask has {} words for {} voxels", name, mask->bits.size(), voxels));
        }
    }
    // As the reader checks: grid_to_cell holds cells (grid) or root nodes (octree); parents are nodes.
    const bool octree = bake.cells.kind == CellSet::Kind::kOctree;
    const int64_t nodes = octree ? int64_t(bake.cells.nodes.size()) : 0;
    for (int32_t c : bake.cells.grid_to_cell) {
        if (c < -1 || int64_t(c) >= (octree ? nodes : int64_t(cells)))
            bad(fmt::format("grid_to_cell entry {} out of range", c));
    }
    for (const Cell& c : bake.cells.cells) {
        if (c.parent < -1 || int64_t(c.parent) >= nodes)
            bad(fmt::format("cell parent {} out of range", c.parent));
    }
    for (size_t i = 0; i < bake.cells.nodes.size(); ++i) {
        const OctreeNode& n = bake.cells.nodes[i];
        if ((n.first_child != -1 &&
             (int64_t(n.first_child) <= int64_t(i) || int64_t(n.first_child) + 8 > nodes)) ||
            n.cell < -1 || int64_t(n.cell) >= int64_t(cells) || n.parent < -1 || int64_t(n.parent) >= nodes) {
            bad(fmt::format("octree node {} has a child, cell or parent out of range", i));
        }
    }
    // As the reader checks the ranking (io/loader/bake_reader.h, read_occluders).
    const RankedOccluders& ranked = bake.ranked;
    if (!ranked.empty()) {
        if (ranked.offsets.size() != cells + 1 || ranked.offsets[0] != 0 ||
            ranked.offsets.back() != ranked.entries.size()) {
            bad(fmt::format("the ranked occluders have {} offsets for {} cells and {} entries",
                            ranked.offsets.size(), cells, ranked.entries.size()));
        }
        for (size_t c = 0; c < cells; ++c) {
            if (ranked.offsets[c + 1] < ranked.offsets[c]) bad("the ranked occluders' offsets decrease");
            for (uint32_t k = ranked.offsets[c]; k < ranked.offsets[c + 1]; ++k) {
                const RankedOccluder& e = ranked.entries[k];
                if (k > ranked.offsets[c] && e.score > ranked.entries[k - 1].score)
                    bad(fmt::format("the ranked occluders of cell {} are not best first", c));
                if (e.box >= bake.occluders.size()) {  // a polygon
                    if (e.box - bake.occluders.size() >= bake.polygons.size())
                        bad(fmt::format("ranked occluder {} names occluder {}, neither a box nor a polygon",
                                        k, e.box));
                    if (!std::isfinite(e.score) || e.score < 0.0f)
                        bad(fmt::format("ranked occluder {} has a score out of range", k));
                    continue;
                }
                if (!bake.occluders[e.box].proven)
                    bad(fmt::format("ranked occluder {} names box {}, not a proven occluder", k, e.box));
                if (!std::isfinite(e.score) || e.score < 0.0f || !(e.solid_angle_sr >= 0.0f) ||
                    !(e.solid_angle_sr <= 12.566371f) || !(e.hidden_objects >= 0.0f) ||
                    !(e.hidden_objects <= float(objects)) || !(e.hidden_triangle_share >= 0.0f) ||
                    !(e.hidden_triangle_share <= 1.0f))
                    bad(fmt::format("ranked occluder {} has a measure out of range", k));
                if (!is_finite(bake.occluders[e.box].box.min) || !is_finite(bake.occluders[e.box].box.max) ||
                    bake.occluders[e.box].box.is_empty())
                    bad(fmt::format("ranked occluder {} names box {}, which is not a finite box", k, e.box));
            }
        }
    }
    for (size_t i = 0; i < bake.polygons.size(); ++i) {  // as the reader checks them
        const OccluderPolygon& p = bake.polygons[i];
        bool ok = p.corners.size() >= 3 && p.corners.size() <= 8 && is_finite(p.normal) &&
                  std::isfinite(p.offset) && std::isfinite(p.thickness) && p.thickness >= 0.0f &&
                  p.normal != glm::vec3(0.0f);
        for (const glm::vec3& c : p.corners) ok = ok && is_finite(c);
        if (!ok) bad(fmt::format("polygon occluder {} is not 3 to 8 finite corners on a finite plane", i));
    }
    const HorizonLists& hz = bake.horizon;  // as the reader checks it (io/loader/bake_reader.h, read_horizon)
    if (!hz.empty()) {
        if (hz.cell_list.size() != cells || hz.offsets[0] != 0 || hz.offsets.back() != hz.entries.size())
            bad("the horizon lists' cell lists or offsets do not match the cells and entries");
        for (const uint32_t l : hz.cell_list)
            if (l >= hz.lists()) bad(fmt::format("a cell names horizon list {} of {}", l, hz.lists()));
        for (size_t l = 0; l < hz.lists(); ++l)
            for (uint32_t k = hz.offsets[l]; k < hz.offsets[l + 1]; ++k)
                if (hz.offsets[l + 1] < hz.offsets[l] || hz.entries[k] >= hz.occluders() ||
                    (k > hz.offsets[l] && hz.entries[k] <= hz.entries[k - 1]))
                    bad(fmt::format("horizon list {} is not ascending occluders in range", l));
        if (!hz.test_offsets.empty()) {
            if (hz.test_offsets.size() != size_t(cells) + 1 || hz.test_offsets[0] != 0 ||
                hz.test_offsets.back() != hz.tests.size())
                bad("the horizon's tests' offsets do not match the cells and tests");
            for (size_t c = 0; c < cells; ++c) {
                if (hz.test_offsets[c + 1] < hz.test_offsets[c] || hz.test_offsets[c + 1] > hz.tests.size())
                    bad(fmt::format("cell {}'s horizon tests' offsets decrease or pass the tests", c));
                for (uint32_t k = hz.test_offsets[c]; k < hz.test_offsets[c + 1]; ++k)
                    if (hz.tests[k] >= bake.objects.size() ||
                        (k > hz.test_offsets[c] && hz.tests[k] <= hz.tests[k - 1]))
                        bad(fmt::format("cell {}'s horizon tests are not ascending objects in range", c));
            }
        }
        for (const Aabb& b : hz.boxes)
            if (!is_finite(b.min) || !is_finite(b.max) || b.is_empty())
                bad("a horizon box is not a finite box");
        for (const OccluderPolygon& t : hz.tiles) {
            bool ok = t.corners.size() >= 3 && t.corners.size() <= pvsbake::detail::kHorizonTileMaxCorners &&
                      is_finite(t.normal) && std::isfinite(t.offset) && std::isfinite(t.thickness) &&
                      t.thickness >= 0.0f && t.normal != glm::vec3(0.0f);
            for (const glm::vec3& c : t.corners) ok = ok && is_finite(c);
            if (!ok) bad("a horizon tile is not 3 to 32 finite corners on a finite plane");
        }
    }
    const ObjectParts& parts = bake.object_parts;  // as the reader checks them (bake_reader.h, read_objects)
    if (!parts.offsets.empty()) {
        if (parts.offsets.size() != objects + 1 || parts.offsets[0] != 0 ||
            parts.offsets.back() != parts.boxes.size())
            bad("the objects' part offsets do not match the objects and part boxes");
        for (size_t i = 0; i < objects; ++i) {
            if (parts.offsets[i + 1] < parts.offsets[i] || parts.offsets[i + 1] > parts.boxes.size())
                bad(fmt::format("the part offsets of object {} decrease or pass the part boxes", i));
            for (uint32_t k = parts.offsets[i]; k < parts.offsets[i + 1]; ++k) {
                const Aabb& p = parts.boxes[k];
                const Aabb& b = bake.objects[i].bounds;
                if (!is_finite(p.min) || !is_finite(p.max) || p.is_empty() ||
                    !glm::all(glm::greaterThanEqual(p.min, b.min)) || !glm::all(glm::lessThanEqual(p.max, b.max)))
                    bad(fmt::format("part box {} of object {} is not a finite box inside its bounds", k, i));
            }
        }
    }
    const VerificationRecord& v = bake.verification;
    if (!v.cell_sampled_visible.empty() && v.cell_sampled_visible.size() != cells) {
        bad("verification cell_sampled_visible does not have one entry per cell");
    }
    for (const Miss& m : v.misses) {
        if (m.cell >= cells || m.object >= objects)
            bad("a verification miss names a cell or object out of range");
    }
    // Strings are stored NUL-terminated (fixed-length HDF5 strings): a NUL inside would cut them short.
    auto check_text = [&](const std::string& s, const std::string& what) {
        if (s.find('\0') != std::string::npos) bad(what + " contains a NUL byte");
    };
    for (size_t i = 0; i < objects; ++i)
        check_text(bake.objects[i].name, fmt::format("the name of object {}", i));
    for (size_t i = 0; i < bake.parameters.size(); ++i) {
        check_text(bake.parameters[i].first + bake.parameters[i].second, fmt::format("parameter {}", i));
    }
    for (size_t i = 0; i < bake.figures.size(); ++i)
        check_text(bake.figures[i].first, fmt::format("figure {}", i));
    for (size_t i = 0; i < bake.run.parameters.size(); ++i) {
        check_text(bake.run.parameters[i].first + bake.run.parameters[i].second,
                   fmt::format("run parameter {}", i));
    }
    for (size_t i = 0; i < bake.run.figures.size(); ++i)
        check_text(bake.run.figures[i].first, fmt::format("run figure {}", i));
    for (size_t i = 0; i < bake.run.timings_s.size(); ++i) {
        check_text(bake.run.timings_s[i].first, fmt::format("timing {}", i));
    }
    for (size_t i = 0; i < v.figures.size(); ++i) {
        check_text(v.figures[i].first, fmt::format("verification figure {}", i));
    }
    check_text(bake.tool_version, "tool_version");
    check_text(bake.world_path, "world_path");
    check_text(bake.world_hash, "world_hash");
    check_text(bake.mode, "mode");
}

void write_bounds(Writer& w, hid_t loc, const std::string& where, const std::vector<Aabb>& boxes) {
    std::vector<float> flat;
    flat.reserve(boxes.size() * 6);
    for (const Aabb& b : boxes) {
        flat.insert(flat.end(), {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z});
    }
    Handle ds =
        w.dataset(loc, where, "bounds", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {boxes.size(), 6}, flat.data());
    w.string_attr(ds.get(), "columns", kBoundsColumns);
}

void write_root(Writer& w, hid_t root, const BakeData& bake) {
    w.string_attr(root, "format", kFormatName);
    w.int_attr(root, "format_major", kBakeFormatMajor);
    w.int_attr(root, "format_minor", kBakeFormatMinor);
    w.string_attr(root, "tool_version", bake.tool_version);
    w.string_attr(root, "world_path", bake.world_path);
    w.string_attr(root, "world_hash", bake.world_hash);
    w.string_attr(root, "mode", bake.mode);
    w.int_attr(root, "conservative", bake.conservative ? 1 : 0);
    w.string_attr(root, "pvs_kind", bake.conservative ? kConservativeNote : kAggressiveNote);
}

// A group `name` in `loc` (at `where`) of keys and values: /parameters and /run/parameters.

// /run: the run's own record (RunRecord). The root keeps an empty /timings, which readers of 1.4 and
// older require.
void write_run(Writer& w, hid_t root, const RunRecord& run) {
    Handle g = w.group(root, "/", "run");
    write_string_pairs(w, g.get(), "/run", "parameters", run.parameters);
    w.named_values(g.get(), "/run", "figures", run.figures, nullptr);
    w.named_values(g.get(), "/run", "timings", run.timings_s, "s");
    w.named_values(root, "/", "timings", {}, "s");
}

// The run's record of a file: /run, or for a file older than 1.5 its /timings and the run.* parameters,
// which move out of bake.parameters.
void read_run(const Reader& r, hid_t root, BakeData& bake) {
    RunRecord& run = bake.run;
    if (r.has_link(root, "run")) {
        Handle g = r.open_group(root, "/run");
        run.parameters = pvsbake::detail::read_string_pairs(r, g.get(), "/run/parameters");
        run.figures = r.named_values(g.get(), "/run/figures");
        run.timings_s = r.named_values(g.get(), "/run/timings");
        return;
    }
    run.timings_s = r.named_values(root, "/timings");
    NamedStrings kept;
    for (auto& p : bake.parameters)
        (is_run_parameter(p.first) ? run.parameters : kept).push_back(std::move(p));
    bake.parameters = std::move(kept);
}

// /reuse: the geometry print (core/geometry_print.h), what a re-bake after an edit compares; absent when
// the bake has none.
void write_print(Writer& w, hid_t root, const GeometryPrint& p) {
    if (p.empty()) return;
    Handle g = w.group(root, "/", "reuse");
    const uint64_t header[2] = {p.header, p.outside};
    w.attr(g.get(), "header", H5T_STD_U64LE, H5T_NATIVE_UINT64, 2, header);
    const float origin[3] = {p.origin.x, p.origin.y, p.origin.z};
    w.attr(g.get(), "origin", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 3, origin);
    w.attr(g.get(), "tile_m", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 1, &p.tile_m);
    const int32_t dims[3] = {p.dims.x, p.dims.y, p.dims.z};
    w.attr(g.get(), "dims", H5T_STD_I32LE, H5T_NATIVE_INT32, 3, dims);
    w.dataset(g.get(), "/reuse", "tiles", H5T_STD_U64LE, H5T_NATIVE_UINT64, {p.tiles.size()}, p.tiles.data());
    w.dataset(g.get(), "/reuse", "objects", H5T_STD_U64LE, H5T_NATIVE_UINT64, {p.objects.size()},
              p.objects.data());
}

void read_print(const Reader& r, hid_t root, BakeData& bake) {
    if (!r.has_link(root, "reuse")) return;  // older than 1.6, or not conservative
    Handle g = r.open_group(root, "/reuse");
    GeometryPrint& p = bake.print;
    const std::vector<uint64_t> header =
        r.numeric_attr<uint64_t>(g.get(), "/reuse", "header", H5T_NATIVE_UINT64, 2);
    const std::vector<float> origin = r.numeric_attr<float>(g.get(), "/reuse", "origin", H5T_NATIVE_FLOAT, 3);
    const std::vector<float> tile = r.numeric_attr<float>(g.get(), "/reuse", "tile_m", H5T_NATIVE_FLOAT, 1);
    const std::vector<int32_t> dims = r.numeric_attr<int32_t>(g.get(), "/reuse", "dims", H5T_NATIVE_INT32, 3);
    if (!(tile[0] > 0.0f) || dims[0] <= 0 || dims[1] <= 0 || dims[2] <= 0 || header[0] == 0)
        r.fail("/reuse has no tiles (tile_m, dims or header out of range)");
    const uint64_t n = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
    p.tiles =
        r.numeric_dataset<uint64_t>(g.get(), "/reuse", "tiles", H5T_NATIVE_UINT64, {int64_t(n)}, H5T_INTEGER);
    p.objects = r.numeric_dataset<uint64_t>(g.get(), "/reuse", "objects", H5T_NATIVE_UINT64,
                                            {int64_t(bake.objects.size())}, H5T_INTEGER);
    p.header = header[0];
    p.outside = header[1];
    p.origin = {origin[0], origin[1], origin[2]};
    p.tile_m = tile[0];
    p.dims = {dims[0], dims[1], dims[2]};
}

void write_objects(Writer& w, hid_t root, const std::vector<ObjectRecord>& objects,
                   const ObjectParts& parts) {
    Handle g = w.group(root, "/", "objects");
    std::vector<std::string> names;
    std::vector<Aabb> bounds;
    std::vector<uint32_t> triangles, flags;
    for (const ObjectRecord& o : objects) {
        names.push_back(o.name);
        bounds.push_back(o.bounds);
        triangles.push_back(o.triangle_count);
        flags.push_back(o.flags);
    }
    w.string_dataset(g.get(), "/objects", "name", names);
    write_bounds(w, g.get(), "/objects", bounds);
    w.dataset(g.get(), "/objects", "triangle_count", H5T_STD_U32LE, H5T_NATIVE_UINT32, {objects.size()},
              triangles.data());
    w.dataset(g.get(), "/objects", "flags", H5T_STD_U32LE, H5T_NATIVE_UINT32, {objects.size()}, flags.data());
    if (!parts.offsets.empty()) {  // 1.9: the part boxes (core/object_parts.h)
        w.dataset(g.get(), "/objects", "part_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32,
                  {parts.offsets.size()}, parts.offsets.data());
        std::vector<float> boxes;
        for (const Aabb& b : parts.boxes)
            boxes.insert(boxes.end(), {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z});
        w.dataset(g.get(), "/objects", "part_boxes", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                  {parts.boxes.size(), 6}, boxes.data(), true);
    }
}

const char* kind_name(CellSet::Kind kind) {
    return kind == CellSet::Kind::kOctree ? "octree" : "grid";
}

// A voxel mask as a group: origin, voxel_size_m, dims, and the bits as bytes (voxel i, x fastest, is bit
// i % 8 of byte i / 8, as in PVS rows); no bytes = no mask.
void write_mask(Writer& w, hid_t cells_group, const std::string& name, const VoxelMask& mask) {
    const std::string where = at("/cells", name);
    Handle g = w.group(cells_group, "/cells", name);
    const float origin[3] = {mask.origin.x, mask.origin.y, mask.origin.z};
    w.attr(g.get(), "origin", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 3, origin);
    w.attr(g.get(), "voxel_size_m", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 1, &mask.voxel_size_m);
    const int32_t dims[3] = {mask.dims.x, mask.dims.y, mask.dims.z};
    w.attr(g.get(), "dims", H5T_STD_I32LE, H5T_NATIVE_INT32, 3, dims);
    std::vector<uint8_t> bytes;
    if (!mask.empty()) {
        const uint64_t voxels = volume_of(mask.dims);
        bytes.resize(size_t((voxels + 7) / 8));
        for (size_t j = 0; j < bytes.size(); ++j) bytes[j] = uint8_t(mask.bits[j / 8] >> (8 * (j % 8)));
        if (voxels % 8 != 0) bytes.back() &= uint8_t((1u << (voxels % 8)) - 1);
    }
    Handle ds =
        w.dataset(g.get(), where, "bits", H5T_STD_U8LE, H5T_NATIVE_UINT8, {bytes.size()}, bytes.data(),
                  /*compress=*/true);
    w.string_attr(
        ds.get(), "bit_order",
        "voxel i = ix + dims[0] * (iy + dims[1] * iz) is bit (i % 8) of byte (i / 8); no bytes = no mask");
    // Format 1.4: the same mask as 8 x 8 x 8 bricks (io/loader/mask_bricks.h), the runtime loader's form,
    // stored plain so that it loads without inflating or converting the bits.
    std::vector<uint32_t> index;
    std::vector<uint8_t> brick_bytes;
    if (!bytes.empty()) pvsbake::detail::make_bricks(bytes, dims, index, brick_bytes);
    Handle bi = w.dataset(g.get(), where, "brick_index", H5T_STD_U32LE, H5T_NATIVE_UINT32, {index.size()},
                          index.data());
    w.string_attr(bi.get(), "meaning",
                  "brick b = bx + bdx * (by + bdy * bz), bd = ceil(dims / 8): 0 empty, 1 full, 2 + j: "
                  "brick_bits[64 j .. 64 j + 64), voxel (x, y, z) of the brick = bit x of byte 8 z + y");
    w.dataset(g.get(), where, "brick_bits", H5T_STD_U8LE, H5T_NATIVE_UINT8, {brick_bytes.size()},
              brick_bytes.data());
}

void write_cells(Writer& w, hid_t root, const CellSet& cells) {
    Handle g = w.group(root, "/", "cells");
    w.string_attr(g.get(), "kind", kind_name(cells.kind));
    w.int_attr(g.get(), "kind_code", int32_t(cells.kind));
    const float origin[3] = {cells.origin.x, cells.origin.y, cells.origin.z};
    w.attr(g.get(), "origin", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 3, origin);
    w.attr(g.get(), "cell_size_m", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 1, &cells.cell_size_m);
    const int32_t dims[3] = {cells.dims.x, cells.dims.y, cells.dims.z};
    w.attr(g.get(), "dims", H5T_STD_I32LE, H5T_NATIVE_INT32, 3, dims);
    w.u32_attr(g.get(), "cell_count", uint32_t(cells.size()));

    Handle g2c = w.dataset(g.get(), "/cells", "grid_to_cell", H5T_STD_I32LE, H5T_NATIVE_INT32,
                           {cells.grid_to_cell.size()}, cells.grid_to_cell.data(), /*compress=*/true);
    w.string_attr(g2c.get(), "index", "ix + dims[0] * (iy + dims[1] * iz); -1 = no cell there");
    std::vector<Aabb> bounds;
    std::vector<int32_t> parents;
    for (const Cell& c : cells.cells) {
        bounds.push_back(c.bounds);
        parents.push_back(c.parent);
    }
    write_bounds(w, g.get(), "/cells", bounds);
    Handle p = w.dataset(g.get(), "/cells", "parent", H5T_STD_I32LE, H5T_NATIVE_INT32, {parents.size()},
                         parents.data());
    w.string_attr(p.get(), "meaning",
                  "octree: the parent node (index into /cells/octree); -1 = none (grid cells, roots)");
    if (cells.kind == CellSet::Kind::kOctree) {
        Handle o = w.group(g.get(), "/cells", "octree");
        w.string_attr(
            o.get(), "layout",
            "grid_to_cell holds the root node of each root-grid cell; a node's 8 children are consecutive "
            "from first_child (octant bits x = 1, y = 2, z = 4), always after the node");
        std::vector<Aabb> node_bounds;
        std::vector<int32_t> first_child, cell, parent;
        for (const OctreeNode& n : cells.nodes) {
            node_bounds.push_back(n.bounds);
            first_child.push_back(n.first_child);
            cell.push_back(n.cell);
            parent.push_back(n.parent);
        }
        write_bounds(w, o.get(), "/cells/octree", node_bounds);
        w.dataset(o.get(), "/cells/octree", "first_child", H5T_STD_I32LE, H5T_NATIVE_INT32,
                  {first_child.size()}, first_child.data(), true);
        w.dataset(o.get(), "/cells/octree", "cell", H5T_STD_I32LE, H5T_NATIVE_INT32, {cell.size()},
                  cell.data(), true);
        w.dataset(o.get(), "/cells/octree", "parent", H5T_STD_I32LE, H5T_NATIVE_INT32, {parent.size()},
                  parent.data(), true);
    }
    write_mask(w, g.get(), "view", cells.view);
    write_mask(w, g.get(), "eyes", cells.eyes);
}

hsize_t storage_size(const Site& site, hid_t ds, const std::string& name) {
    site.check(H5Dflush(ds), "cannot flush " + name);  // chunks still in the cache have no size yet
    return H5Dget_storage_size(ds);
}

void write_pvs(Writer& w, hid_t root, const BakeData& bake) {
    const PvsSet& pvs = bake.pvs;
    const uint32_t cells = pvs.cell_count;
    const uint32_t row_bytes = bytes_per_row(pvs.object_count);
    const uint8_t mask = last_byte_mask(pvs.object_count);

    // Dedupe: each distinct row is stored once, in the order of the first cell that has it.
    std::unordered_map<std::string, uint32_t> row_index;
    std::vector<uint8_t> rows;
    std::vector<uint32_t> cell_row(cells);
    std::string key(row_bytes, '\0');
    for (uint32_t c = 0; c < cells; ++c) {
        const uint64_t* words = pvs.row(c);
        for (uint32_t j = 0; j < row_bytes; ++j) key[j] = char(row_byte(words, j));
        if (row_bytes > 0) key[row_bytes - 1] = char(uint8_t(key[row_bytes - 1]) & mask);
        const auto [it, inserted] = row_index.try_emplace(key, uint32_t(row_index.size()));
        if (inserted) rows.insert(rows.end(), key.begin(), key.end());
        cell_row[c] = it->second;
    }
    const uint32_t unique_rows = uint32_t(row_index.size());

    Handle g = w.group(root, "/", "pvs");
    Handle rows_ds = w.dataset(g.get(), "/pvs", "rows", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                               {unique_rows, row_bytes}, rows.data(), /*compress=*/true);
    w.string_attr(rows_ds.get(), "bit_order", "object i is bit (i % 8) of byte (i / 8); bit 0 = 1");
    Handle cell_row_ds =
        w.dataset(g.get(), "/pvs", "cell_row", H5T_STD_U32LE, H5T_NATIVE_UINT32, {cells}, cell_row.data());
    const uint64_t stored = storage_size(w.site(), rows_ds.get(), "/pvs/rows") +
                            storage_size(w.site(), cell_row_ds.get(), "/pvs/cell_row");
    // Format 1.1: the same rows in the PVS code (io/loader/row_code.h), which the runtime loader keeps in
    // memory as it is: loading is one plain read, no inflate (docs/FORMAT.md, "The PVS code").
    if (pvs.object_count < pvsbake::detail::kMaxCodedObjects) {
        const pvsbake::detail::RowCode code =
            pvsbake::detail::encode_rows(rows.data(), unique_rows, row_bytes, pvs.object_count);
        if (code.code.size() >= UINT32_MAX) w.site().fail("the PVS code passes 4 GiB");
        Handle code_ds = w.dataset(g.get(), "/pvs", "code", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                                   {code.code.size()}, code.code.data());
        w.string_attr(
            code_ds.get(), "coding",
            "per distinct row: varint ref (0 = key row, else XOR with row r - ref), varint count << 5 | k, "
            "count Rice(k) codes of the gaps between visible object indices; docs/FORMAT.md");
        w.dataset(g.get(), "/pvs", "code_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32, {code.offsets.size()},
                  code.offsets.data());
        w.u64_attr(g.get(), "bytes_code", code.code.size() + 4 * code.offsets.size() + 4 * uint64_t(cells));
        // Format 1.4: the code's checksum, so that the runtime loader checks it whole without decoding it.
        w.u64_attr(g.get(), "code_xxh3", pvsbake::detail::code_checksum(code.code.data(), code.code.size()));
    }
    w.u32_attr(g.get(), "object_count", pvs.object_count);
    w.u32_attr(g.get(), "cell_count", cells);
    w.u32_attr(g.get(), "unique_rows", unique_rows);
    w.u32_attr(g.get(), "bytes_per_row", row_bytes);
    w.u64_attr(g.get(), "bytes_raw", uint64_t(cells) * row_bytes);
    w.u64_attr(g.get(), "bytes_stored", stored);
}

void write_leak_path(Writer& w, hid_t root, const std::vector<glm::vec3>& path) {
    std::vector<float> flat;
    for (const glm::vec3& p : path) flat.insert(flat.end(), {p.x, p.y, p.z});
    Handle ds =
        w.dataset(root, "/", "leak_path", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {path.size(), 3}, flat.data());
    w.string_attr(ds.get(), "meaning",
                  "view volume flood from a seed to the outside, when the level leaks; empty = sealed");
}

// Polygons as the file keeps them (/occluders/polygon_*, /horizon/tile_*): corner offsets (polygons + 1),
// corners (3 floats each) and planes (normal, offset, thickness).
struct FlatPolygons {
    std::vector<uint32_t> offsets = {0};
    std::vector<float> corners, planes;
};

FlatPolygons flat_polygons(const std::vector<OccluderPolygon>& polygons) {
    FlatPolygons f;
    for (const OccluderPolygon& p : polygons) {
        for (const glm::vec3& c : p.corners) f.corners.insert(f.corners.end(), {c.x, c.y, c.z});
        f.offsets.push_back(uint32_t(f.corners.size() / 3));
        f.planes.insert(f.planes.end(), {p.normal.x, p.normal.y, p.normal.z, p.offset, p.thickness});
    }
    return f;
}

void write_occluders(Writer& w, hid_t root, bool by_sight, const std::vector<Occluder>& occluders,
                     const std::vector<OccluderPolygon>& polygons, const RankedOccluders& ranked) {
    Handle g = w.group(root, "/", "occluders");
    w.u32_attr(g.get(), "count", uint32_t(occluders.size()));
    w.string_attr(
        g.get(), "meaning",
        "synthesized occluder boxes inside the opaque solid; only proven ones (proven = 1) may be used by a "
        "conservative bake");
    std::vector<Aabb> boxes;
    std::vector<float> voxel;
    std::vector<uint8_t> proven;
    std::vector<uint32_t> offsets = {0}, objects;
    for (const Occluder& o : occluders) {
        boxes.push_back(o.box);
        voxel.push_back(o.voxel_size_m);
        proven.push_back(o.proven ? 1 : 0);
        objects.insert(objects.end(), o.objects.begin(), o.objects.end());
        offsets.push_back(uint32_t(objects.size()));
    }
    write_bounds(w, g.get(), "/occluders", boxes);
    w.dataset(g.get(), "/occluders", "voxel_size_m", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {voxel.size()},
              voxel.data());
    w.dataset(g.get(), "/occluders", "proven", H5T_STD_U8LE, H5T_NATIVE_UINT8, {proven.size()},
              proven.data());
    w.dataset(g.get(), "/occluders", "object_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32, {offsets.size()},
              offsets.data());
    w.dataset(g.get(), "/occluders", "objects", H5T_STD_U32LE, H5T_NATIVE_UINT32, {objects.size()},
              objects.data(), true);
    if (ranked.empty()) return;
    // Format 1.2: the ranked occluders of each cell (occluders/ranking.h), as indices into the boxes above
    // and their measures; cell c has entries ranked_offsets[c] .. ranked_offsets[c + 1], best first. From
    // 1.7 the polygons a cell ranks are kept apart (a 1.6 reader reads the boxes as before), each with its
    // place in the cell's whole list.
    std::vector<uint32_t> box, box_offsets = {0}, poly, poly_rank, poly_offsets = {0};
    std::vector<float> score, solid, hidden, share, poly_score;
    for (size_t c = 0; c + 1 < ranked.offsets.size(); ++c) {
        for (uint32_t k = ranked.offsets[c]; k < ranked.offsets[c + 1]; ++k) {
            const RankedOccluder& e = ranked.entries[k];
            if (e.box >= occluders.size()) {
                poly.push_back(e.box - uint32_t(occluders.size()));
                poly_rank.push_back(k - ranked.offsets[c]);
                poly_score.push_back(e.score);
                continue;
            }
            box.push_back(e.box);
            score.push_back(e.score);
            solid.push_back(e.solid_angle_sr);
            hidden.push_back(e.hidden_objects);
            share.push_back(e.hidden_triangle_share);
        }
        box_offsets.push_back(uint32_t(box.size()));
        poly_offsets.push_back(uint32_t(poly.size()));
    }
    const size_t m = box.size();
    w.string_attr(g.get(), "ranked_score",
                  by_sight
                      ? "the share of the cell's sampled sight lines (from its eyes to points of its PVS's "
                        "objects) that the occluder stops first; higher is better (docs/FORMAT.md)"
                      : "sqrt(mean solid angle / 4 pi * (mean hidden objects / objects + mean hidden "
                        "triangle share) / 2), over the cell's sampled eyes; higher is better "
                        "(docs/FORMAT.md)");
    w.dataset(g.get(), "/occluders", "ranked_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32, {box_offsets.size()},
              box_offsets.data(), true);
    // The entries are stored plain (not deflated): their measures gain 1.1 to 1.6 x from deflate, and
    // inflating them was most of the runtime loader's load time (docs/LOADER.md, "Costs").
    w.dataset(g.get(), "/occluders", "ranked_box", H5T_STD_U32LE, H5T_NATIVE_UINT32, {m}, box.data());
    w.dataset(g.get(), "/occluders", "ranked_score", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {m}, score.data());
    Handle sa = w.dataset(g.get(), "/occluders", "ranked_solid_angle_sr", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                          {m}, solid.data());
    w.string_attr(sa.get(), "units", "sr");
    w.dataset(g.get(), "/occluders", "ranked_hidden_objects", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {m},
              hidden.data());
    w.dataset(g.get(), "/occluders", "ranked_hidden_triangle_share", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {m},
              share.data());
    if (polygons.empty()) return;
    // Format 1.7: the polygon occluders (docs/ALGORITHMS.md#runtime-polygons) and the cells' ranked polygons.
    const FlatPolygons flat = flat_polygons(polygons);
    const std::vector<uint32_t>& corner_offsets = flat.offsets;
    const std::vector<float>&corners = flat.corners, &planes = flat.planes;
    w.dataset(g.get(), "/occluders", "polygon_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32,
              {corner_offsets.size()}, corner_offsets.data());
    w.dataset(g.get(), "/occluders", "polygon_corners", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
              {corners.size() / 3, 3}, corners.data());
    Handle pl = w.dataset(g.get(), "/occluders", "polygon_planes", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                          {polygons.size(), 5}, planes.data());
    w.string_attr(pl.get(), "columns", "normal x, normal y, normal z, offset, thickness");
    w.dataset(g.get(), "/occluders", "ranked_polygon_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32,
              {poly_offsets.size()}, poly_offsets.data(), true);
    w.dataset(g.get(), "/occluders", "ranked_polygon", H5T_STD_U32LE, H5T_NATIVE_UINT32, {poly.size()},
              poly.data());
    w.dataset(g.get(), "/occluders", "ranked_polygon_rank", H5T_STD_U32LE, H5T_NATIVE_UINT32, {poly.size()},
              poly_rank.data());
    w.dataset(g.get(), "/occluders", "ranked_polygon_score", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {poly.size()},
              poly_score.data());
}

// Format 1.8: the run-time horizon's occluders and lists (docs/FORMAT.md, /horizon).
void write_horizon(Writer& w, hid_t root, const HorizonLists& h) {
    if (h.empty()) return;
    Handle g = w.group(root, "/", "horizon");
    std::vector<float> boxes;
    for (const Aabb& b : h.boxes)
        boxes.insert(boxes.end(), {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z});
    const FlatPolygons flat = flat_polygons(h.tiles);
    const std::vector<uint32_t>& tile_offsets = flat.offsets;
    const std::vector<float>&corners = flat.corners, &planes = flat.planes;
    Handle b = w.dataset(g.get(), "/horizon", "boxes", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {h.boxes.size(), 6},
                         boxes.data());
    w.string_attr(b.get(), "columns", "min x, min y, min z, max x, max y, max z");
    w.dataset(g.get(), "/horizon", "tile_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32, {tile_offsets.size()},
              tile_offsets.data());
    w.dataset(g.get(), "/horizon", "tile_corners", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {corners.size() / 3, 3},
              corners.data());
    Handle pl = w.dataset(g.get(), "/horizon", "tile_planes", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                          {h.tiles.size(), 5}, planes.data());
    w.string_attr(pl.get(), "columns", "normal x, normal y, normal z, offset, thickness");
    w.dataset(g.get(), "/horizon", "cell_list", H5T_STD_U32LE, H5T_NATIVE_UINT32, {h.cell_list.size()},
              h.cell_list.data(), true);
    w.dataset(g.get(), "/horizon", "list_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32, {h.offsets.size()},
              h.offsets.data(), true);
    w.dataset(g.get(), "/horizon", "list_entries", H5T_STD_U32LE, H5T_NATIVE_UINT32, {h.entries.size()},
              h.entries.data(), true);
    if (!h.test_offsets.empty()) {  // 1.10: the objects each cell's frames test
        w.dataset(g.get(), "/horizon", "test_offsets", H5T_STD_U32LE, H5T_NATIVE_UINT32,
                  {h.test_offsets.size()}, h.test_offsets.data(), true);
        w.dataset(g.get(), "/horizon", "tests", H5T_STD_U32LE, H5T_NATIVE_UINT32, {h.tests.size()},
                  h.tests.data(), true);
    }
}

void write_verification(Writer& w, hid_t root, const VerificationRecord& v) {
    Handle g = w.group(root, "/", "verification");
    w.int_attr(g.get(), "ran", v.ran ? 1 : 0);
    w.named_values(g.get(), "/verification", "figures", v.figures, nullptr);
    w.dataset(g.get(), "/verification", "cell_sampled_visible", H5T_STD_U32LE, H5T_NATIVE_UINT32,
              {v.cell_sampled_visible.size()}, v.cell_sampled_visible.data());
    std::vector<MissRecord> misses;
    for (const Miss& m : v.misses) {
        misses.push_back({m.cell,
                          m.object,
                          {m.eye.x, m.eye.y, m.eye.z},
                          {m.direction.x, m.direction.y, m.direction.z},
                          m.distance_m,
                          m.opening_width_m});
    }
    Handle file_type = miss_type(w.site(), true);
    Handle mem_type = miss_type(w.site(), false);
    w.dataset(g.get(), "/verification", "misses", file_type.get(), mem_type.get(), {misses.size()},
              misses.data());
}

// ---------------------------------------------------------------------------------------------------------
// Reading: the loader's validated sections (io/loader/bake_reader.h) into a BakeData, plus what only the
// baker reads (leak path, occluders, verification).

// The stored type of /verification/misses: a compound whose members all lie inside its record, with
// the members this reader needs (more are allowed: a later minor version may add some).
void check_miss_type(const Reader& r, hid_t type_id, const std::string& full) {
    Handle t = r.handle(type_id, H5Tclose, "cannot read the type of " + full);
    if (H5Tget_class(t.get()) != H5T_COMPOUND) r.fail(full + " is not a compound dataset");
    const size_t record = H5Tget_size(t.get());
    const int members = H5Tget_nmembers(t.get());
    if (record == 0 || record > 4096 || members < 0) r.fail(full + " has a damaged compound type");
    for (unsigned i = 0; i < unsigned(members); ++i) {
        Handle m = r.handle(H5Tget_member_type(t.get(), i), H5Tclose, "cannot read the type of " + full);
        size_t bytes = H5Tget_size(m.get());
        if (H5Tget_class(m.get()) == H5T_ARRAY) {
            Handle base = r.handle(H5Tget_super(m.get()), H5Tclose, "cannot read the type of " + full);
            r.check_number_type(base.get(), full);
            hsize_t dims[H5S_MAX_RANK];
            const int rank = H5Tget_array_ndims(m.get());
            if (rank < 0 || rank > H5S_MAX_RANK || H5Tget_array_dims2(m.get(), dims) != rank) {
                r.fail(full + " has a damaged array member");
            }
            uint64_t n = 1;
            for (int d = 0; d < rank; ++d) n *= dims[d];
            if (n * H5Tget_size(base.get()) != bytes) r.fail(full + " has a damaged array member");
        } else if (H5Tget_class(m.get()) == H5T_INTEGER || H5Tget_class(m.get()) == H5T_FLOAT) {
            r.check_number_type(m.get(), full);
        }
        if (bytes == 0 || H5Tget_member_offset(t.get(), i) + bytes > record) {
            r.fail(full + " has a compound member outside its record (damaged type)");
        }
    }
    for (const char* name : {"cell", "object", "eye", "direction", "distance_m"}) {
        if (H5Tget_member_index(t.get(), name) < 0) r.fail(fmt::format("{} has no member '{}'", full, name));
    }
}

Aabb box_at(const std::vector<float>& flat, size_t i) {
    const float* b = &flat[i * 6];
    return Aabb::of({b[0], b[1], b[2]}, {b[3], b[4], b[5]});
}

VoxelMask to_mask(const pvsbake::detail::FileMask& m) {
    VoxelMask mask;
    mask.origin = {m.origin[0], m.origin[1], m.origin[2]};
    mask.voxel_size_m = m.voxel_size_m;
    mask.dims = {m.dims[0], m.dims[1], m.dims[2]};
    if (m.bytes.empty()) return mask;
    mask.bits.assign(size_t((m.voxels + 63) / 64), 0);
    for (size_t j = 0; j < m.bytes.size(); ++j) mask.bits[j / 8] |= uint64_t(m.bytes[j]) << (8 * (j % 8));
    return mask;
}

void read_objects(const Reader& r, hid_t root, BakeData& bake) {
    const pvsbake::detail::FileObjects o = pvsbake::detail::read_objects(r, root);
    bake.objects.resize(o.names.size());
    for (size_t i = 0; i < o.names.size(); ++i) {
        bake.objects[i] = ObjectRecord{o.names[i], box_at(o.bounds, i), o.triangle_count[i], o.flags[i]};
    }
    bake.object_parts.offsets = o.part_offsets;
    bake.object_parts.boxes.clear();
    for (size_t k = 0; k < o.part_boxes.size() / 6; ++k)
        bake.object_parts.boxes.push_back(box_at(o.part_boxes, k));
}

void read_cells(const Reader& r, hid_t root, BakeData& bake) {
    pvsbake::detail::FileCells f = pvsbake::detail::read_cells(r, root, /*read_eyes=*/true);
    CellSet& cells = bake.cells;
    cells.kind = CellSet::Kind(f.kind);
    cells.origin = {f.origin[0], f.origin[1], f.origin[2]};
    cells.cell_size_m = f.cell_size_m;
    cells.dims = {f.dims[0], f.dims[1], f.dims[2]};
    cells.grid_to_cell = std::move(f.grid_to_cell);
    cells.cells.resize(f.count);
    for (size_t i = 0; i < cells.cells.size(); ++i) cells.cells[i] = Cell{box_at(f.bounds, i), f.parent[i]};
    cells.nodes.resize(f.node_first_child.size());
    for (size_t i = 0; i < cells.nodes.size(); ++i) {
        cells.nodes[i] =
            OctreeNode{box_at(f.node_bounds, i), f.node_first_child[i], f.node_cell[i], f.node_parent[i]};
    }
    cells.view = to_mask(f.view);
    cells.eyes = to_mask(f.eyes);
}

void read_pvs(const Reader& r, hid_t root, BakeData& bake) {
    const uint32_t objects = uint32_t(bake.objects.size());
    const uint32_t cells = uint32_t(bake.cells.size());
    const pvsbake::detail::FilePvs f = pvsbake::detail::read_pvs(r, root, objects, cells, /*want_rows=*/true);
    bake.pvs = PvsSet::make(cells, objects);
    for (uint32_t c = 0; c < cells; ++c) {
        const uint8_t* bytes = f.rows.data() + size_t(f.cell_row[c]) * f.row_bytes;
        uint64_t* words = bake.pvs.row(c);
        for (uint32_t j = 0; j < f.row_bytes; ++j) words[j / 8] |= uint64_t(bytes[j]) << (8 * (j % 8));
    }
}

void read_leak_path(const Reader& r, hid_t root, BakeData& bake) {
    std::vector<int64_t> shape = {-1, 3};
    const std::vector<float> flat =
        r.numeric_dataset<float>(root, "/", "leak_path", H5T_NATIVE_FLOAT, shape, H5T_FLOAT);
    for (size_t i = 0; i + 2 < flat.size(); i += 3)
        bake.leak_path.emplace_back(flat[i], flat[i + 1], flat[i + 2]);
}

// The inverse of flat_polygons (offsets validated by the reader).
std::vector<OccluderPolygon> polygons_of(const std::vector<uint32_t>& offsets,
                                         const std::vector<float>& corners, const std::vector<float>& planes,
                                         bool tiles) {
    std::vector<OccluderPolygon> out;
    for (size_t i = 0; i + 1 < offsets.size(); ++i) {
        OccluderPolygon p;
        p.tile = tiles;
        p.normal = glm::vec3(planes[5 * i], planes[5 * i + 1], planes[5 * i + 2]);
        p.offset = planes[5 * i + 3];
        p.thickness = planes[5 * i + 4];
        for (uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
            p.corners.emplace_back(corners[3 * k], corners[3 * k + 1], corners[3 * k + 2]);
            p.bounds.extend(p.corners.back());
        }
        out.push_back(std::move(p));
    }
    return out;
}

void read_occluders(const Reader& r, hid_t root, BakeData& bake) {
    const pvsbake::detail::FileOccluders f = pvsbake::detail::read_occluders(
        r, root, uint32_t(bake.objects.size()), uint32_t(bake.cells.size()), /*want_boxes=*/true);
    if (!f.present) return;  // a bake made without occluders
    for (size_t i = 0; i < f.count; ++i) {
        Occluder o;
        o.box = box_at(f.bounds, i);
        o.voxel_size_m = f.voxel_size_m[i];
        o.proven = f.proven[i] != 0;
        o.objects.assign(f.objects.begin() + f.object_offsets[i],
                         f.objects.begin() + f.object_offsets[i + 1]);
        bake.occluders.push_back(std::move(o));
    }
    bake.polygons = polygons_of(f.polygon_offsets, f.polygon_corners, f.polygon_planes, false);
    if (f.ranked_offsets.empty()) return;  // older than format 1.2, or ranking was off
    // The boxes and (1.7) the polygons of each cell in one list, each polygon at its place.
    const size_t cells = f.ranked_offsets.size() - 1;
    const bool polys = !f.ranked_polygon_offsets.empty();
    bake.ranked.offsets = {0};
    for (size_t c = 0; c < cells; ++c) {
        uint32_t b = f.ranked_offsets[c], p = polys ? f.ranked_polygon_offsets[c] : 0;
        const uint32_t b_end = f.ranked_offsets[c + 1], p_end = polys ? f.ranked_polygon_offsets[c + 1] : 0;
        for (uint32_t place = 0; b < b_end || p < p_end; ++place) {
            if (p < p_end && f.ranked_polygon_rank[p] == place) {
                RankedOccluder e;
                e.box = uint32_t(bake.occluders.size()) + f.ranked_polygon[p];
                e.score = f.ranked_polygon_score[p++];
                bake.ranked.entries.push_back(e);
            } else {
                bake.ranked.entries.push_back(
                    RankedOccluder{f.ranked_box[b], f.ranked_score[b], f.ranked_solid_angle_sr[b],
                                   f.ranked_hidden_objects[b], f.ranked_hidden_triangle_share[b]});
                ++b;
            }
        }
        bake.ranked.offsets.push_back(uint32_t(bake.ranked.entries.size()));
    }
}

void read_horizon(const Reader& r, hid_t root, BakeData& bake) {
    const pvsbake::detail::FileHorizon f =
        pvsbake::detail::read_horizon(r, root, uint32_t(bake.cells.size()), uint32_t(bake.objects.size()));
    if (!f.present) return;
    HorizonLists& h = bake.horizon;
    for (size_t i = 0; i < f.box_count(); ++i) h.boxes.push_back(box_at(f.boxes, i));
    h.tiles = polygons_of(f.tile_offsets, f.tile_corners, f.tile_planes, true);
    h.cell_list = f.cell_list;
    h.offsets = f.list_offsets;
    h.entries = f.list_entries;
    h.test_offsets = f.test_offsets;
    h.tests = f.tests;
}

void read_verification(const Reader& r, hid_t root, BakeData& bake) {
    const std::string where = "/verification";
    Handle g = r.open_group(root, where);
    VerificationRecord& v = bake.verification;
    const int64_t ran = r.int_attr(g.get(), where, "ran");
    if (ran != 0 && ran != 1) r.fail("/verification attribute ran is not 0 or 1");
    v.ran = ran == 1;
    v.figures = r.named_values(g.get(), where + "/figures");
    const int64_t cells = int64_t(bake.cells.size());
    std::vector<int64_t> shape = {-1};
    v.cell_sampled_visible = r.numeric_dataset<uint32_t>(g.get(), where, "cell_sampled_visible",
                                                         H5T_NATIVE_UINT32, shape, H5T_INTEGER);
    if (shape[0] != 0 && shape[0] != cells) {
        r.fail(
            fmt::format("/verification/cell_sampled_visible has {} entries, expected 0 or {} (one per cell)",
                        shape[0], cells));
    }

    const std::string full = where + "/misses";
    Handle ds = r.open_dataset(g.get(), where, "misses");
    check_miss_type(r, H5Dget_type(ds.get()), full);
    const std::vector<hsize_t> dims = r.dataset_dims(ds.get(), full);
    if (dims.size() != 1) r.fail(full + " is not one-dimensional");
    r.check_budget(dims[0], 64, full);
    r.check_storage(ds.get(), full);
    std::vector<MissRecord> misses(static_cast<size_t>(dims[0]));
    bool with_width = false;
    {
        Handle file_type = r.handle(H5Dget_type(ds.get()), H5Tclose, "cannot read the type of " + full);
        with_width = H5Tget_member_index(file_type.get(), "opening_width_m") >= 0;
    }
    if (!misses.empty()) {
        // Older files have no opening width: it is read as "not measured".
        for (MissRecord& m : misses) m.opening_width_m = -1.0f;
        Handle mem_type = miss_type(r, false, with_width);
        r.check(H5Dread(ds.get(), mem_type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, misses.data()),
                "cannot read " + full);
    }
    for (size_t i = 0; i < misses.size(); ++i) {
        const MissRecord& m = misses[i];
        if (m.cell >= bake.cells.size() || m.object >= bake.objects.size()) {
            r.fail(fmt::format("{}[{}] names cell {} and object {}, out of range ({} cells, {} objects)",
                               full, i, m.cell, m.object, bake.cells.size(), bake.objects.size()));
        }
        v.misses.push_back(Miss{m.cell,
                                m.object,
                                {m.eye[0], m.eye[1], m.eye[2]},
                                {m.direction[0], m.direction[1], m.direction[2]},
                                m.distance_m,
                                m.opening_width_m});
    }
}

}  // namespace

void write_bake_file(const std::string& path, const BakeData& bake) {
    check_writable(path, bake);
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!folder.empty() && !std::filesystem::is_directory(folder, ec)) {
        throw write_error(path, ENOENT, "the bake file");
    }

    QuietHdf5 quiet;
    std::string bytes;
    {
        const Site site(path, ErrorKind::kIo, "cannot write the bake file: ");
        Handle file = create_memory_file(site);
        {
            Writer w(site);
            Handle root = site.handle(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose, "cannot open /");
            write_root(w, root.get(), bake);
            write_string_pairs(w, root.get(), "/", "parameters", bake.parameters);
            write_objects(w, root.get(), bake.objects, bake.object_parts);
            write_cells(w, root.get(), bake.cells);
            write_pvs(w, root.get(), bake);
            write_leak_path(w, root.get(), bake.leak_path);
            const auto lines = std::find_if(bake.parameters.begin(), bake.parameters.end(),
                                            [](const auto& p) { return p.first == "ranking.sight_lines"; });
            const bool by_sight = lines != bake.parameters.end() && lines->second != "0";
            write_occluders(w, root.get(), by_sight, bake.occluders, bake.polygons, bake.ranked);
            write_horizon(w, root.get(), bake.horizon);
            w.named_values(root.get(), "/", "figures", bake.figures, nullptr);
            write_verification(w, root.get(), bake.verification);
            write_print(w, root.get(), bake.print);
            write_run(w, root.get(), bake.run);
        }
        bytes = take_file_image(site, file);
    }
    write_file_atomically(path, bytes, "the bake file");
}

BakeData read_bake_file(const std::string& path) {
    return h5::read_file(path, [&](const Reader& r, hid_t root) {
        BakeData bake;
        const pvsbake::BakeInfo h = pvsbake::detail::read_header(r, root);
        std::tie(bake.format_major, bake.format_minor, bake.tool_version, bake.world_path, bake.world_hash,
                 bake.mode, bake.conservative) = std::tie(h.format_major, h.format_minor, h.tool_version,
                                                          h.world_path, h.world_hash, h.mode, h.conservative);
        bake.parameters = pvsbake::detail::read_parameters(r, root);
        read_objects(r, root, bake);
        read_cells(r, root, bake);
        read_pvs(r, root, bake);
        read_leak_path(r, root, bake);
        read_occluders(r, root, bake);
        read_horizon(r, root, bake);
        bake.figures = r.named_values(root, "/figures");
        read_verification(r, root, bake);
        read_print(r, root, bake);
        read_run(r, root, bake);
        return bake;
    });
}

}  // namespace pvs
