// SPDX-License-Identifier: MIT
// pvsbake loader (internal): reads and validates the sections of a bake file (docs/FORMAT.md) into plain
// arrays, as they are in the file. The one reader of the format: the runtime loader builds its lookup
// structures from these, and the baker's read_bake_file (io/bake_file.cpp) builds a BakeData.
//
// Conventions: as the file's (glTF axes, metres, x-fastest grid order, object i = bit i % 8 of byte i / 8).
// Every function throws ReadError (hdf5_reader.h) naming the file and the dataset when something is wrong;
// what it returns is consistent: every index is in range and every size agrees with the counts.
#pragma once

#include "hdf5_reader.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace pvsbake::detail {

constexpr const char* kFormatName = "pvsbake";
constexpr int kFormatMajor = 1;
constexpr int kFormatMinor = 10;
constexpr uint32_t kHorizonTileMaxCorners = 32;  // runtime/pvsr.h PVSR_HORIZON_MAX_CORNERS

// The root attributes. Throws kNotBakeFile without format = "pvsbake", kVersionTooNew for a newer major.
BakeInfo read_header(const Reader& r, hid_t root);

// The group `where` in `loc` (its last name, opened in loc) of `keys` and `values` string datasets
// (/parameters, /run/parameters) as pairs, in order.
std::vector<std::pair<std::string, std::string>> read_string_pairs(const Reader& r, hid_t loc,
                                                                   const std::string& where);
inline std::vector<std::pair<std::string, std::string>> read_parameters(const Reader& r, hid_t root) {
    return read_string_pairs(r, root, "/parameters");
}

// The part box rounded outward to the grid of its object's bounds on which the runtime file stores it
// (pvsr_part_encode, runtime/pvsr.h; a bake's parts lie on it already), so that the loader and the runtime
// test the same boxes; false when it is not a finite box inside the bounds. Defined beside the runtime
// compiled into the loader (occlusion.cpp).
bool part_on_runtime_grid(const float bounds[6], float part[6]);

struct FileObjects {
    std::vector<std::string> names;
    std::vector<float> bounds;  // 6 per object: min xyz, max xyz
    std::vector<uint32_t> triangle_count, flags;
    // 1.9: object o's part boxes are part_boxes[6 part_offsets[o] ..] up to part_offsets[o + 1] (both empty:
    // no parts); each inside the object's bounds (checked).
    std::vector<uint32_t> part_offsets;
    std::vector<float> part_boxes;
};
FileObjects read_objects(const Reader& r, hid_t root);

// dims x*y*z, or UINT64_MAX when a dimension is negative or the product passes 2^48.
uint64_t volume_of(const int32_t dims[3]);

struct FileMask {
    bool present = false;  // false: no mask
    float origin[3] = {0, 0, 0};
    float voxel_size_m = 0;
    int32_t dims[3] = {0, 0, 0};
    uint64_t voxels = 0;
    std::vector<uint8_t>
        bytes;  // empty (no mask, or read as bricks) or ceil(voxels / 8), bits past the voxels zero
    // As bricks (mask_bricks.h), when they were asked for and the file has them (format 1.4): every index
    // below kFirstBrick + brick_bytes.size() / 64. Else empty.
    std::vector<uint32_t> brick_index;
    std::vector<uint8_t> brick_bytes;
};

struct FileCells {
    int32_t kind = 0;  // 0 grid, 1 octree
    float origin[3] = {0, 0, 0};
    float cell_size_m = 0;
    int32_t dims[3] = {0, 0, 0};
    uint32_t count = 0;
    std::vector<float> bounds;          // 6 per cell
    std::vector<int32_t> parent;        // per cell: -1 or an octree node
    std::vector<int32_t> grid_to_cell;  // dims product entries: -1 or a cell (grid) / root node (octree)
    // Octree nodes: first_child -1 or > the node, with 8 children below the node count.
    std::vector<float> node_bounds;
    std::vector<int32_t> node_first_child, node_cell, node_parent;
    FileMask view, eyes;
};
// read_eyes false skips /cells/eyes. With bricks, a mask the file also stores as bricks (format 1.4) is read
// as bricks only, not as bits.
FileCells read_cells(const Reader& r, hid_t root, bool read_eyes, bool bricks = false);

// /pvs. With want_rows, `rows` holds the distinct rows (format 1.0 and later); else, when the file has
// the code (format 1.1), `code` and `code_offsets` hold it, validated, and rows stays empty (old files
// without the code always give rows). The code is followed by code_padding(objects) zero bytes (row_code.h).
struct FilePvs {
    uint32_t row_bytes = 0;
    uint64_t unique_rows = 0;
    std::vector<uint8_t> rows;
    std::vector<uint32_t> cell_row;
    std::vector<uint8_t> code;
    std::vector<uint32_t> code_offsets;
    uint64_t bytes_raw = 0, bytes_stored = 0;
};
FilePvs read_pvs(const Reader& r, hid_t root, uint32_t objects, uint32_t cells, bool want_rows);

// /occluders (docs/FORMAT.md): the synthesized boxes and, from format 1.2, the ranked occluders of each cell.
// `present` is false in a bake made with --no-occluders (no group). With want_boxes every box is read
// (bounds, voxel sizes, proven flags, the objects of each box: the baker); without it (the runtime), the
// boxes' bounds and proven flags only when the file has a ranking, and never their objects. The ranking is
// empty (ranked_offsets empty) in older files and when ranking was off; else it is validated: ranked_offsets
// has cells + 1 entries from 0, never decreasing, ending at the number of entries; each entry names a proven
// box with finite bounds; scores are finite, >= 0 and never increase within a cell (best first); solid angles
// lie in [0, 4 pi], hidden objects in [0, objects], hidden triangle shares in [0, 1].
struct FileOccluders {
    bool present = false;
    uint64_t count = 0;           // boxes (0 when they were not read)
    std::vector<float> bounds;    // 6 per box
    std::vector<uint8_t> proven;  // 0 or 1 per box
    std::vector<float> voxel_size_m;
    std::vector<uint32_t> object_offsets, objects;  // want_boxes only
    std::vector<uint32_t> ranked_offsets;           // cells + 1, or empty: no ranking
    std::vector<uint32_t> ranked_box;
    std::vector<float> ranked_score, ranked_solid_angle_sr, ranked_hidden_objects,
        ranked_hidden_triangle_share;
    // 1.7: the polygon occluders (3 to 8 corners each) and the polygons each cell ranks, with their place in
    // the cell's whole list (boxes and polygons); all empty in older files or without polygons.
    std::vector<uint32_t> polygon_offsets;  // polygons + 1, into polygon_corners' corners
    std::vector<float> polygon_corners;     // 3 floats a corner
    std::vector<float> polygon_planes;      // 5 floats a polygon: normal, offset, thickness
    std::vector<uint32_t> ranked_polygon_offsets, ranked_polygon, ranked_polygon_rank;
    std::vector<float> ranked_polygon_score;
};
FileOccluders read_occluders(const Reader& r, hid_t root, uint32_t objects, uint32_t cells, bool want_boxes);

// /horizon (format 1.8, docs/FORMAT.md): the run-time horizon's occluders and the list each block of cells
// gives it; `present` is false in older files and bakes without lists. Validated: boxes finite with
// min <= max; tiles of 3 to 32 finite corners on a finite plane with thickness >= 0; cell_list has one entry
// per cell, each below the lists; list_offsets from 0, never decreasing, ending at the entries; each list's
// entries ascending and below boxes + tiles. 1.10, optionally: test_offsets (cells + 1) from 0, never
// decreasing, ending at the tests; each cell's tests ascending and below the objects (both empty: none).
struct FileHorizon {
    bool present = false;
    std::vector<float> boxes;            // 6 floats a box
    std::vector<uint32_t> tile_offsets;  // tiles + 1, into tile_corners' corners
    std::vector<float> tile_corners;     // 3 floats a corner
    std::vector<float> tile_planes;      // 5 floats a tile: normal, offset, thickness
    std::vector<uint32_t> cell_list;     // per cell
    std::vector<uint32_t> list_offsets;  // lists + 1
    std::vector<uint32_t> list_entries;
    std::vector<uint32_t> test_offsets;  // cells + 1, or empty: every object is tested
    std::vector<uint32_t> tests;         // per cell, the objects its frames test (ascending)
    uint64_t box_count() const { return boxes.size() / 6; }
    uint64_t tile_count() const { return tile_offsets.empty() ? 0 : tile_offsets.size() - 1; }
};
FileHorizon read_horizon(const Reader& r, hid_t root, uint32_t cells, uint32_t objects);

// Opens path for reading: kFileMissing, kIoError, kNotBakeFile (not HDF5, a folder) or kCorrupt (HDF5
// cannot open it). The returned handle is the file; `file_bytes` receives its size.
Handle open_bake_file(const std::string& path, uint64_t& file_bytes);

}  // namespace pvsbake::detail
