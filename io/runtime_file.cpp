// SPDX-License-Identifier: MIT
// pvsbake io: writes the runtime file (io/runtime_file.h; docs/FORMAT.md, "The runtime file") from the
// arrays the bake file's validating reader gives (io/loader/bake_reader.h).
#include "io/runtime_file.h"

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/hdf5_file.h"
#include "io/loader/bake_reader.h"
#include "io/loader/mask_bricks.h"
#include "io/loader/row_code.h"
#include "runtime/pvsr.h"

#include <fmt/format.h>
#include <xxhash.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <unordered_map>

namespace pvs {
namespace {

using pvsbake::detail::FileCells;
using pvsbake::detail::FileHorizon;
using pvsbake::detail::FileMask;
using pvsbake::detail::FileObjects;
using pvsbake::detail::FileOccluders;
using pvsbake::detail::FilePvs;

// Little-endian bytes of plain values (the machines the baker runs on are little-endian: checked below).
template <class T>
void put(std::string& out, const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
void put_all(std::string& out, const std::vector<T>& v) {
    if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

// A LEB128 varint.
struct Section {
    uint32_t tag = 0;
    uint32_t item_bytes = 1;
    uint64_t count = 0;
    std::string bytes;
};

std::string tag_name(uint32_t tag) {
    std::string s(4, ' ');
    for (int i = 0; i < 4; ++i) s[size_t(i)] = char((tag >> (8 * i)) & 0xff);
    return s;
}

// Values that fit 16 bits as 2 bytes each, else 4.
Section index_section(uint32_t tag, const std::vector<uint32_t>& values) {
    Section s{tag, 4, values.size(), {}};
    const uint32_t top = values.empty() ? 0 : *std::max_element(values.begin(), values.end());
    if (top <= std::numeric_limits<uint16_t>::max()) {
        s.item_bytes = 2;
        for (uint32_t v : values) put(s.bytes, uint16_t(v));
    } else {
        put_all(s.bytes, values);
    }
    return s;
}

// Ascending offsets (ROFF): 16-bit items when they fit; else (4.0) when each fits 16 bits after the offset of
// its 64 (every 64th item in `bases_tag`, u32), 16-bit items after those bases; else 32-bit items.
std::vector<Section> offset_sections(uint32_t tag, uint32_t bases_tag, const std::vector<uint64_t>& offsets) {
    const uint64_t top = offsets.empty() ? 0 : offsets.back();
    Section s{tag, 2, offsets.size(), {}};
    if (top <= std::numeric_limits<uint16_t>::max()) {
        for (const uint64_t v : offsets) put(s.bytes, uint16_t(v));
        return {std::move(s)};
    }
    bool relative = top <= std::numeric_limits<uint32_t>::max();
    for (size_t i = 0; i < offsets.size() && relative; ++i)
        relative = offsets[i] - offsets[i & ~size_t(63)] <= std::numeric_limits<uint16_t>::max();
    if (!relative) {
        s.item_bytes = 4;
        for (const uint64_t v : offsets) put(s.bytes, uint32_t(v));
        return {std::move(s)};
    }
    Section bases{bases_tag, 4, (offsets.size() + 63) / 64, {}};
    for (size_t i = 0; i < offsets.size(); ++i) {
        if ((i & 63) == 0) put(bases.bytes, uint32_t(offsets[i]));
        put(s.bytes, uint16_t(offsets[i] - offsets[i & ~size_t(63)]));
    }
    return {std::move(s), std::move(bases)};
}

template <class T>
Section array_section(uint32_t tag, uint32_t item_bytes, const std::vector<T>& values) {
    Section s{tag, item_bytes, uint64_t(values.size()) * sizeof(T) / item_bytes, {}};
    put_all(s.bytes, values);
    return s;
}

// A mask as bricks (io/loader/mask_bricks.h): as the file holds them (format 1.4), or made from its bits.
void bricks_of(FileMask& m, std::vector<uint32_t>& index, std::vector<uint8_t>& bytes) {
    if (!m.brick_index.empty()) {
        index = std::move(m.brick_index);
        bytes = std::move(m.brick_bytes);
    } else {
        pvsbake::detail::make_bricks(m.bytes, m.dims, index, bytes);
    }
}

// Masks as tiles of 4 x 4 x 4 bricks of 8 x 8 x 8 voxels (docs/FORMAT.md, "The runtime file"): a tile is empty,
// full, or names a block of 64 brick references; a reference is an empty or full brick, or names 64 bytes of
// bits. Identical bricks and identical blocks are stored once, for every mask added (the view and eye masks
// share most of theirs).
struct MaskTiles {
    int32_t brick_dims[3], tile_dims[3];
    std::vector<uint32_t> refs;    // 64 per block
    std::vector<uint8_t> bricks;   // 64 bytes per distinct mixed brick
    std::unordered_map<std::string, uint32_t> brick_of, block_of;

    explicit MaskTiles(const int32_t dims[3]) {
        for (int a = 0; a < 3; ++a) {
            brick_dims[a] = int32_t(pvsbake::detail::bricks_along(dims[a]));
            tile_dims[a] = (brick_dims[a] + PVSR_TILE_BRICKS - 1) / PVSR_TILE_BRICKS;
        }
    }

    // The tiles of one mask given as bricks (io/loader/mask_bricks.h).
    std::vector<uint32_t> add(const std::vector<uint32_t>& index, const std::vector<uint8_t>& bytes) {
        const int T = PVSR_TILE_BRICKS;
        std::vector<uint32_t> tiles(size_t(tile_dims[0]) * size_t(tile_dims[1]) * size_t(tile_dims[2]));
        std::vector<uint32_t> block(size_t(T * T * T));
        for (int tz = 0; tz < tile_dims[2]; ++tz)
            for (int ty = 0; ty < tile_dims[1]; ++ty)
                for (int tx = 0; tx < tile_dims[0]; ++tx) {
                    bool empty = true, full = true;
                    for (int k = 0; k < T * T * T; ++k) {
                        const int bx = tx * T + k % T, by = ty * T + k / T % T, bz = tz * T + k / (T * T);
                        uint32_t ref = PVSR_BRICK_EMPTY;
                        if (bx < brick_dims[0] && by < brick_dims[1] && bz < brick_dims[2]) {
                            const uint32_t t = index[size_t(bx) + size_t(brick_dims[0]) *
                                                         (size_t(by) + size_t(brick_dims[1]) * size_t(bz))];
                            if (t == pvsbake::detail::kBrickFull) {
                                ref = PVSR_BRICK_FULL;
                            } else if (t >= pvsbake::detail::kFirstBrick) {
                                const std::string bits(
                                    reinterpret_cast<const char*>(&bytes[size_t(t - pvsbake::detail::kFirstBrick) * 64]), 64);
                                auto [it, fresh] = brick_of.emplace(bits, uint32_t(bricks.size() / 64));
                                if (fresh) bricks.insert(bricks.end(), bits.begin(), bits.end());
                                ref = PVSR_FIRST_BRICK + it->second;
                            }
                        }
                        // A brick past the mask's edge counts as full for a full tile: no voxel there is looked up.
                        const bool outside = bx >= brick_dims[0] || by >= brick_dims[1] || bz >= brick_dims[2];
                        empty = empty && ref == PVSR_BRICK_EMPTY;
                        full = full && (ref == PVSR_BRICK_FULL || outside);
                        block[size_t(k)] = ref;
                    }
                    uint32_t& tile = tiles[size_t(tx) + size_t(tile_dims[0]) * (size_t(ty) + size_t(tile_dims[1]) * size_t(tz))];
                    if (empty) {
                        tile = PVSR_BRICK_EMPTY;
                    } else if (full) {
                        tile = PVSR_BRICK_FULL;
                    } else {
                        const std::string key(reinterpret_cast<const char*>(block.data()), block.size() * 4);
                        auto [it, fresh] = block_of.emplace(key, uint32_t(refs.size() / block.size()));
                        if (fresh) refs.insert(refs.end(), block.begin(), block.end());
                        tile = PVSR_FIRST_BRICK + it->second;
                    }
                }
        return tiles;
    }
};

struct Bake {
    pvsbake::BakeInfo info;
    FileObjects objects;
    FileCells cells;
    FilePvs pvs;
    FileOccluders occluders;
    FileHorizon horizon;
};

// 2.0: the ranked entries as indices into the palette of each cell's block (runtime/pvsr.c, palette_block:
// the 4 x 4 x 4 block of grid positions holding the cell when cells have positions, else 64 cells in turn).
struct PaletteLists {
    std::vector<uint32_t> offsets;  // blocks + 1: block b's palette is boxes[offsets[b] .. offsets[b + 1])
    std::vector<uint32_t> boxes;    // into the file's ranked boxes
    std::vector<uint32_t> entries;  // per ranked entry, its index in its cell's block's palette
    uint32_t largest = 0;           // the largest palette
    uint64_t bytes() const {
        const uint64_t top = boxes.empty() ? 0 : *std::max_element(boxes.begin(), boxes.end());
        return 4 * offsets.size() + (top <= 65535 ? 2 : 4) * boxes.size() +
               entries.size() * (largest <= 256     ? 1
                                 : largest <= 65536 ? 2
                                                    : 4);
    }
};

// The block of each cell (runtime/pvsr.c, palette_block): the 4 x 4 x 4 block of grid positions holding it
// when cells have positions (cell_grid, a grid), else 64 cells in turn. Palettes and horizon lists are per
// block.
struct CellBlocks {
    uint32_t count = 0;
    std::vector<uint32_t> of;  // per cell
};

CellBlocks cell_blocks(const FileCells& cells, const std::vector<uint32_t>& cell_grid) {
    constexpr uint32_t kSide = 4, kCells = 64;
    const bool positions = !cell_grid.empty();
    uint32_t n[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) n[a] = (uint32_t(cells.dims[a]) + kSide - 1) / kSide;
    CellBlocks out;
    out.count = positions ? n[0] * n[1] * n[2] : (cells.count + kCells - 1) / kCells;
    out.of.resize(cells.count);
    for (uint32_t c = 0; c < cells.count; ++c) {
        if (!positions) {
            out.of[c] = c / kCells;
            continue;
        }
        const uint32_t g = cell_grid[c], d0 = uint32_t(cells.dims[0]), d1 = uint32_t(cells.dims[1]);
        out.of[c] = g % d0 / kSide + n[0] * (g / d0 % d1 / kSide + n[1] * (g / (d0 * d1) / kSide));
    }
    return out;
}

PaletteLists palette_lists(const FileCells& cells, const std::vector<uint32_t>& cell_grid,
                           const std::vector<uint32_t>& ranked_offsets,
                           const std::vector<uint32_t>& entry_box) {
    const uint32_t count = cells.count;
    const CellBlocks cb = cell_blocks(cells, cell_grid);
    const uint32_t blocks = cb.count;
    const auto block_of = [&](uint32_t c) { return cb.of[c]; };
    std::vector<std::vector<uint32_t>> palette(blocks);
    std::vector<std::unordered_map<uint32_t, uint32_t>> index(blocks);
    PaletteLists out;
    out.entries.resize(entry_box.size());
    for (uint32_t c = 0; c < count; ++c) {
        const uint32_t b = block_of(c);
        for (uint32_t e = ranked_offsets[c]; e < ranked_offsets[size_t(c) + 1]; ++e) {
            const auto [it, fresh] = index[b].emplace(entry_box[e], uint32_t(palette[b].size()));
            if (fresh) palette[b].push_back(entry_box[e]);
            out.entries[e] = it->second;
        }
    }
    out.offsets.push_back(0);
    for (const std::vector<uint32_t>& p : palette) {
        out.boxes.insert(out.boxes.end(), p.begin(), p.end());
        out.offsets.push_back(uint32_t(out.boxes.size()));
        out.largest = std::max(out.largest, uint32_t(p.size()));
    }
    return out;
}

std::string assemble(const std::string& path, Bake& b, const RuntimeFileOptions& options) {
    const uint32_t objects = uint32_t(b.objects.names.size());
    const uint32_t cells = b.cells.count;
    if (objects >= PVSR_MAX_OBJECTS)
        throw bad_input(fmt::format("{}: {} objects, over the runtime file's {}", path, objects, PVSR_MAX_OBJECTS));
    std::vector<Section> sections;

    // LEVL: the grid and the masks' voxels.
    {
        Section s{PVSR_TAG('L', 'E', 'V', 'L'), PVSR_LEVEL_BYTES, 1, {}};
        const FileMask& m = b.cells.view;
        const bool eyes = b.cells.eyes.present && m.present && b.cells.eyes.voxel_size_m == m.voxel_size_m &&
                          std::equal(m.origin, m.origin + 3, b.cells.eyes.origin) &&
                          std::equal(m.dims, m.dims + 3, b.cells.eyes.dims);
        for (int a = 0; a < 3; ++a) put(s.bytes, b.cells.origin[a]);
        put(s.bytes, b.cells.cell_size_m);
        for (int a = 0; a < 3; ++a) put(s.bytes, b.cells.dims[a]);
        put(s.bytes, uint32_t(b.cells.node_first_child.size()));
        for (int a = 0; a < 3; ++a) put(s.bytes, m.present ? m.origin[a] : 0.0f);
        put(s.bytes, m.present ? m.voxel_size_m : 0.0f);
        for (int a = 0; a < 3; ++a) put(s.bytes, m.present ? m.dims[a] : 0);
        put(s.bytes, uint32_t((m.present ? PVSR_MASK_VIEW : 0u) | (eyes ? PVSR_MASK_EYES : 0u)));
        sections.push_back(std::move(s));
        if (m.present) {
            MaskTiles tiles(m.dims);
            std::vector<uint32_t> index;
            std::vector<uint8_t> bytes;
            bricks_of(b.cells.view, index, bytes);
            sections.push_back(array_section(PVSR_TAG('V', 'T', 'I', 'L'), 4, tiles.add(index, bytes)));
            if (eyes) {
                bricks_of(b.cells.eyes, index, bytes);
                sections.push_back(array_section(PVSR_TAG('E', 'T', 'I', 'L'), 4, tiles.add(index, bytes)));
            }
            sections.push_back(index_section(PVSR_TAG('M', 'R', 'E', 'F'), tiles.refs));
            sections.push_back(array_section(PVSR_TAG('M', 'B', 'I', 'T'), 64, tiles.bricks));
        }
    }
    // GRID, NODE, and CGRD (a grid cell's box is its grid box: 4 bytes, not 24) or CBOX; neither GRID nor
    // CGRD for a grid whose position g is cell g (2.0).
    const size_t placed_sections = sections.size();
    sections.push_back(array_section(PVSR_TAG('G', 'R', 'I', 'D'), 4, b.cells.grid_to_cell));
    if (b.cells.kind == 1) {
        Section s{PVSR_TAG('N', 'O', 'D', 'E'), PVSR_NODE_BYTES, b.cells.node_first_child.size(), {}};
        for (size_t i = 0; i < b.cells.node_first_child.size(); ++i) {
            for (int a = 0; a < 3; ++a)  // as Aabb::center() and the HDF5 loader
                put(s.bytes, 0.5f * (b.cells.node_bounds[6 * i + size_t(a)] + b.cells.node_bounds[6 * i + 3 + size_t(a)]));
            put(s.bytes, b.cells.node_first_child[i]);
            put(s.bytes, b.cells.node_cell[i]);
        }
        sections.push_back(std::move(s));
    }
    std::vector<uint32_t> cell_grid;  // each cell's grid position (a grid whose cells are their grid boxes)
    bool grid_identity =
        false;  // a grid whose cells are its (occupied) positions in order (2.0: no GRID, CGRD)
    {
        bool derived = b.cells.kind == 0;
        if (derived) {
            cell_grid.assign(cells, UINT32_MAX);
            for (size_t g = 0; g < b.cells.grid_to_cell.size() && derived; ++g) {
                const int32_t c = b.cells.grid_to_cell[g];
                if (c < 0) continue;
                derived = cell_grid[size_t(c)] == UINT32_MAX && g <= UINT32_MAX;
                cell_grid[size_t(c)] = uint32_t(g);
            }
            const int32_t* d = b.cells.dims;
            for (uint32_t c = 0; c < cells && derived; ++c) {
                const uint32_t g = cell_grid[c];
                if (g == UINT32_MAX) {
                    derived = false;
                    break;
                }
                const uint32_t idx[3] = {g % uint32_t(d[0]), g / uint32_t(d[0]) % uint32_t(d[1]),
                                         g / (uint32_t(d[0]) * uint32_t(d[1]))};
                for (int a = 0; a < 3; ++a) {
                    const float lo = b.cells.origin[a] + float(idx[a]) * b.cells.cell_size_m;
                    const float hi = b.cells.origin[a] + float(idx[a] + 1) * b.cells.cell_size_m;
                    derived = derived && lo == b.cells.bounds[6 * c + size_t(a)] &&
                              hi == b.cells.bounds[6 * c + 3 + size_t(a)];
                }
            }
        }
        grid_identity = derived && b.cells.grid_to_cell.size() <= UINT32_MAX;
        for (uint32_t c = 1; c < cells && grid_identity; ++c) grid_identity = cell_grid[c - 1] < cell_grid[c];
        if (grid_identity) {
            sections.resize(placed_sections);  // GRID is implied: every position a cell, or an occupancy mask
            const size_t positions = b.cells.grid_to_cell.size();
            if (positions != cells) {
                std::vector<uint64_t> occupied((positions + 63) / 64, 0);
                std::vector<uint32_t> before(occupied.size(), 0);
                for (const uint32_t g : cell_grid) occupied[g / 64] |= uint64_t(1) << (g % 64);
                for (size_t w = 1; w < occupied.size(); ++w)
                    before[w] = before[w - 1] + uint32_t(__builtin_popcountll(occupied[w - 1]));
                sections.push_back(array_section(PVSR_TAG('G', 'O', 'C', 'C'), 8, occupied));
                sections.push_back(array_section(PVSR_TAG('G', 'O', 'C', 'R'), 4, before));
            }
        } else if (derived) {
            sections.push_back(array_section(PVSR_TAG('C', 'G', 'R', 'D'), 4, cell_grid));
        } else {
            cell_grid.clear();
            sections.push_back(array_section(PVSR_TAG('C', 'B', 'O', 'X'), 24, b.cells.bounds));
        }
    }
    // --merge-cells K: each cell takes the union of the rows of its block of K x K x K grid cells, so that the
    // cells of a block share one row (conservative by construction: a row only grows).
    const uint32_t merge = std::max<uint32_t>(1, options.merge_cells);
    const std::string merge_text = std::to_string(merge);
    if (merge > 1) {
        if (cell_grid.empty())
            throw bad_input(fmt::format("{}: --merge-cells needs a grid bake whose cells are its grid boxes", path));
        const int32_t* d = b.cells.dims;
        const uint32_t bytes = b.pvs.row_bytes;
        std::unordered_map<uint64_t, uint32_t> block_of;  // block key -> merged row
        std::vector<uint8_t> merged;
        std::vector<uint32_t> cell_block(cells);
        for (uint32_t c = 0; c < cells; ++c) {
            const uint32_t g = cell_grid[c];
            const uint64_t key = uint64_t(g % uint32_t(d[0]) / merge) +
                                 (uint64_t(g / uint32_t(d[0]) % uint32_t(d[1]) / merge) << 21) +
                                 (uint64_t(g / (uint32_t(d[0]) * uint32_t(d[1])) / merge) << 42);
            auto [it, fresh] = block_of.emplace(key, uint32_t(block_of.size()));
            if (fresh) merged.resize(merged.size() + bytes, 0);
            const uint8_t* row = &b.pvs.rows[size_t(b.pvs.cell_row[c]) * bytes];
            uint8_t* into = &merged[size_t(it->second) * bytes];
            for (uint32_t j = 0; j < bytes; ++j) into[j] |= row[j];
            cell_block[c] = it->second;
        }
        // Each distinct merged row once, in order of the first cell that uses it.
        std::unordered_map<std::string, uint32_t> row_of;
        std::vector<uint8_t> rows;
        for (uint32_t c = 0; c < cells; ++c) {
            const std::string row(reinterpret_cast<const char*>(&merged[size_t(cell_block[c]) * bytes]), bytes);
            auto [it, fresh] = row_of.emplace(row, uint32_t(row_of.size()));
            if (fresh) rows.insert(rows.end(), row.begin(), row.end());
            b.pvs.cell_row[c] = it->second;
        }
        b.pvs.rows = std::move(rows);
        b.pvs.unique_rows = row_of.size();
    }
    // STRS: what the bake is.
    {
        Section s{PVSR_TAG('S', 'T', 'R', 'S'), 1, 0, {}};
        const std::pair<const char*, const std::string*> pairs[] = {{"tool_version", &b.info.tool_version},
                                                                    {"world_path", &b.info.world_path},
                                                                    {"world_hash", &b.info.world_hash},
                                                                    {"mode", &b.info.mode},
                                                                    {"cell_merge", &merge_text}};
        for (const auto& [key, value] : pairs) {
            s.bytes += key;
            s.bytes.push_back('\0');
            s.bytes += *value;
            s.bytes.push_back('\0');
        }
        s.count = s.bytes.size();
        sections.push_back(std::move(s));
    }
    // CROW, ROFF, CODE (and the padding the decoders read into): the rows coded again, each against the
    // cheapest of its cell's earlier neighbours (a grid) and the rows before it, in chains of at most
    // PVSR_MAX_CHAIN rows (2 past the runtime's stack bit set: PVSR_STACK_OBJECTS). On a grid whose cells are
    // its grid boxes the rows are put in BLOCK ORDER first: blocks of kRowBlock^3 grid positions in turn, and
    // in each the positions in breadth-first order from one near its centre, so that every cell but the first
    // of a block has a neighbour one step nearer that centre before it, and chains need not restart along a
    // line (docs/FORMAT.md, "The rows' code").
    // On a grid of every position, every cell has a row of its own in block order (2.0): a cell's row is then
    // its place in that order, computed where it is read (runtime/pvsr.c, block_rank), and CROW is left out;
    // a row that repeats an earlier one is coded against it (twin).
    const size_t positions = b.cells.grid_to_cell.size();
    const bool implicit_rows = grid_identity && options.block_order && b.pvs.row_bytes > 0 &&
                               (positions - cells) * 16 <= positions;  // few empty rows to code
    std::vector<uint64_t> twin;
    if (!cell_grid.empty() && options.block_order && b.pvs.row_bytes > 0) {
        const int32_t* d = b.cells.dims;
        const uint32_t bytes = b.pvs.row_bytes;
        constexpr int32_t kRowBlock = 4;
        std::vector<uint32_t> new_row(size_t(b.pvs.unique_rows), UINT32_MAX);
        std::vector<uint32_t> cell_own_row(implicit_rows ? cells : 0, UINT32_MAX);
        uint64_t empty_row = UINT64_MAX;
        std::vector<uint8_t> rows;
        rows.reserve(implicit_rows ? positions * b.pvs.row_bytes : b.pvs.rows.size());
        std::vector<std::array<int32_t, 3>> order;  // positions of a block, breadth first from (1, 1, 1)
        {
            std::vector<int32_t> seen(size_t(kRowBlock * kRowBlock * kRowBlock), 0);
            order.push_back({1, 1, 1});
            seen[size_t(1 + kRowBlock * (1 + kRowBlock))] = 1;
            for (size_t i = 0; i < order.size(); ++i) {
                for (int a = 0; a < 3; ++a) {
                    for (const int32_t step : {-1, 1}) {
                        std::array<int32_t, 3> q = order[i];
                        q[size_t(a)] += step;
                        if (q[size_t(a)] < 0 || q[size_t(a)] >= kRowBlock) continue;
                        int32_t& s = seen[size_t(q[0] + kRowBlock * (q[1] + kRowBlock * q[2]))];
                        if (s) continue;
                        s = 1;
                        order.push_back(q);
                    }
                }
            }
        }
        for (int32_t bz = 0; bz < d[2]; bz += kRowBlock) {
            for (int32_t by = 0; by < d[1]; by += kRowBlock) {
                for (int32_t bx = 0; bx < d[0]; bx += kRowBlock) {
                    for (const std::array<int32_t, 3>& o : order) {
                        const int32_t x = bx + o[0], y = by + o[1], z = bz + o[2];
                        if (x >= d[0] || y >= d[1] || z >= d[2]) continue;
                        const int32_t c =
                            b.cells.grid_to_cell[size_t(x) +
                                                 size_t(d[0]) * (size_t(y) + size_t(d[1]) * size_t(z))];
                        if (c < 0 && implicit_rows) {  // an empty position: an empty row (never read)
                            twin.push_back(empty_row);
                            if (empty_row == UINT64_MAX) empty_row = rows.size() / bytes;
                            rows.resize(rows.size() + bytes, 0);
                            continue;
                        }
                        if (c < 0) continue;
                        const uint32_t r = b.pvs.cell_row[size_t(c)];
                        if (implicit_rows) {
                            twin.push_back(new_row[r] == UINT32_MAX ? UINT64_MAX : new_row[r]);
                            if (new_row[r] == UINT32_MAX) new_row[r] = uint32_t(rows.size() / bytes);
                            cell_own_row[size_t(c)] = uint32_t(rows.size() / bytes);
                            rows.insert(rows.end(), b.pvs.rows.begin() + std::ptrdiff_t(size_t(r) * bytes),
                                        b.pvs.rows.begin() + std::ptrdiff_t(size_t(r + 1) * bytes));
                            continue;
                        }
                        if (new_row[r] != UINT32_MAX) continue;
                        new_row[r] = uint32_t(rows.size() / bytes);
                        rows.insert(rows.end(), b.pvs.rows.begin() + std::ptrdiff_t(size_t(r) * bytes),
                                    b.pvs.rows.begin() + std::ptrdiff_t(size_t(r + 1) * bytes));
                    }
                }
            }
        }
        for (uint64_t r = 0; r < b.pvs.unique_rows && !implicit_rows;
             ++r) {  // rows of no grid position (none)
            if (new_row[size_t(r)] != UINT32_MAX) continue;
            new_row[size_t(r)] = uint32_t(rows.size() / bytes);
            rows.insert(rows.end(), b.pvs.rows.begin() + std::ptrdiff_t(size_t(r) * bytes),
                        b.pvs.rows.begin() + std::ptrdiff_t(size_t(r + 1) * bytes));
        }
        if (implicit_rows) {
            b.pvs.cell_row = std::move(cell_own_row);
            b.pvs.unique_rows = positions;
        } else {
            for (uint32_t& r : b.pvs.cell_row) r = new_row[r];
        }
        b.pvs.rows = std::move(rows);
    }
    {
        std::vector<uint64_t> first_cell(size_t(b.pvs.unique_rows), UINT64_MAX);
        for (uint32_t c = 0; c < cells; ++c) first_cell[b.pvs.cell_row[c]] = std::min<uint64_t>(first_cell[b.pvs.cell_row[c]], c);
        const int32_t* d = b.cells.dims;
        const auto neighbours = [&](uint64_t r, std::vector<uint64_t>& out) {
            if (r < twin.size() && twin[size_t(r)] != UINT64_MAX) out.push_back(twin[size_t(r)]);
            if (cell_grid.empty() || first_cell[size_t(r)] == UINT64_MAX) return;
            const uint32_t g = cell_grid[size_t(first_cell[size_t(r)])];
            const int64_t at[3] = {int64_t(g % uint32_t(d[0])), int64_t(g / uint32_t(d[0]) % uint32_t(d[1])),
                                   int64_t(g / (uint32_t(d[0]) * uint32_t(d[1])))};
            const int64_t stride[3] = {1, d[0], int64_t(d[0]) * d[1]};
            for (int a = 0; a < 3; ++a) {  // the six neighbours (the encoder keeps the earlier rows)
                for (const int64_t step : {-1, 1}) {
                    if (at[a] + step < 0 || at[a] + step >= d[a]) continue;
                    const int32_t n = b.cells.grid_to_cell[size_t(int64_t(g) + step * stride[a])];
                    if (n >= 0) out.push_back(b.pvs.cell_row[size_t(n)]);
                }
            }
        };
        const uint32_t max_chain = std::clamp<uint32_t>(options.max_chain, 1, objects <= PVSR_STACK_OBJECTS ? PVSR_MAX_CHAIN : 2);
        const pvsbake::detail::RowCode code = pvsbake::detail::encode_rows_chained(
            b.pvs.rows.data(), b.pvs.unique_rows, b.pvs.row_bytes, max_chain, neighbours);
        const uint64_t code_size = code.offsets.back();
        if (!implicit_rows) sections.push_back(index_section(PVSR_TAG('C', 'R', 'O', 'W'), b.pvs.cell_row));
        for (Section& o : offset_sections(PVSR_TAG('R', 'O', 'F', 'F'), PVSR_TAG('R', 'O', 'F', 'B'),
                                          std::vector<uint64_t>(code.offsets.begin(), code.offsets.end())))
            sections.push_back(std::move(o));
        Section s{PVSR_TAG('C', 'O', 'D', 'E'), 1, code_size, {}};
        s.bytes.assign(reinterpret_cast<const char*>(code.code.data()), size_t(code_size));
        s.bytes.append(pvsbake::detail::code_padding(objects), '\0');
        sections.push_back(std::move(s));
    }
    // Objects.
    {
        sections.push_back(array_section(PVSR_TAG('O', 'B', 'O', 'X'), 24, b.objects.bounds));
        sections.push_back(array_section(PVSR_TAG('O', 'T', 'R', 'I'), 4, b.objects.triangle_count));
        sections.push_back(array_section(PVSR_TAG('O', 'F', 'L', 'G'), 4, b.objects.flags));
        Section offsets{PVSR_TAG('O', 'N', 'A', 'M'), 4, uint64_t(objects) + 1, {}};
        Section names{PVSR_TAG('O', 'S', 'T', 'R'), 1, 0, {}};
        for (const std::string& n : b.objects.names) {
            put(offsets.bytes, uint32_t(names.bytes.size()));
            names.bytes += n;
            names.bytes.push_back('\0');
        }
        put(offsets.bytes, uint32_t(names.bytes.size()));
        names.count = names.bytes.size();
        if (names.bytes.size() > UINT32_MAX) throw bad_input(fmt::format("{}: the object names pass 4 GiB", path));
        sections.push_back(std::move(offsets));
        sections.push_back(std::move(names));
    }
    // Ranked occluders: only the boxes a ranking names, renumbered in order of first use; each entry's box in
    // 1, 2 or 4 bytes; the measures only when asked for (a culler needs the boxes in rank order).
    if (!b.occluders.ranked_offsets.empty()) {
        std::vector<uint32_t> renumber(size_t(b.occluders.count), UINT32_MAX), entry_box;
        Section boxes{PVSR_TAG('R', 'B', 'O', 'X'), 24, 0, {}};
        Section measures{PVSR_TAG('R', 'M', 'E', 'A'), PVSR_MEASURE_BYTES, b.occluders.ranked_box.size(), {}};
        for (size_t e = 0; e < b.occluders.ranked_box.size(); ++e) {
            const uint32_t box = b.occluders.ranked_box[e];
            if (renumber[box] == UINT32_MAX) {
                renumber[box] = uint32_t(boxes.count++);
                for (int a = 0; a < 6; ++a) put(boxes.bytes, b.occluders.bounds[6 * size_t(box) + size_t(a)]);
            }
            entry_box.push_back(renumber[box]);
            put(measures.bytes, b.occluders.ranked_score[e]);
            put(measures.bytes, b.occluders.ranked_solid_angle_sr[e]);
            put(measures.bytes, b.occluders.ranked_hidden_objects[e]);
            put(measures.bytes, b.occluders.ranked_hidden_triangle_share[e]);
        }
        // 2.0: when it is smaller, each entry indexes the palette of its cell's block (the distinct boxes its
        // cells name, in order of first use): neighbouring cells rank mostly the same boxes.
        const PaletteLists palettes =
            palette_lists(b.cells, cell_grid, b.occluders.ranked_offsets, entry_box);
        const uint64_t direct_bytes = entry_box.size() * (boxes.count <= 256     ? 1
                                                          : boxes.count <= 65536 ? 2
                                                                                 : 4);
        const bool use_palette = palettes.bytes() < direct_bytes;
        const std::vector<uint32_t>& entries = use_palette ? palettes.entries : entry_box;
        Section list{PVSR_TAG('R', 'L', 'S', 'T'), 4, entries.size(), {}};
        if ((use_palette ? palettes.largest : boxes.count) <= 256) {
            list.item_bytes = 1;
            for (uint32_t v : entries) put(list.bytes, uint8_t(v));
        } else {
            list = index_section(PVSR_TAG('R', 'L', 'S', 'T'), entries);
        }
        sections.push_back(std::move(boxes));
        // 4.0: each cell's entry count in a byte ('RCNT') and the first entry of every 64th cell ('RCNB'),
        // where every cell ranks at most 255; else the offsets ('ROFS').
        const std::vector<uint32_t>& ro = b.occluders.ranked_offsets;
        bool counts = true;
        for (uint32_t c = 0; c < cells && counts; ++c) counts = ro[size_t(c) + 1] - ro[c] <= 255;
        if (counts) {
            Section n{PVSR_TAG('R', 'C', 'N', 'T'), 1, cells, {}},
                base{PVSR_TAG('R', 'C', 'N', 'B'), 4, (uint64_t(cells) + 63) / 64, {}};
            for (uint32_t c = 0; c < cells; ++c) {
                if ((c & 63) == 0) put(base.bytes, ro[c]);
                n.bytes.push_back(char(uint8_t(ro[size_t(c) + 1] - ro[c])));
            }
            sections.push_back(std::move(n));
            sections.push_back(std::move(base));
        } else {
            sections.push_back(array_section(PVSR_TAG('R', 'O', 'F', 'S'), 4, ro));
        }
        sections.push_back(std::move(list));
        if (use_palette) {
            sections.push_back(array_section(PVSR_TAG('R', 'P', 'B', 'K'), 4, palettes.offsets));
            sections.push_back(index_section(PVSR_TAG('R', 'P', 'A', 'L'), palettes.boxes));
        }
        if (options.occluder_measures) sections.push_back(std::move(measures));
    }
    // 1.1: the polygons a ranking names, renumbered in order of first use ('OPLN': plane and corner range,
    // 'OPCO': corners), and per cell its polygons with their places in its whole list ('RPOF', 'RPLS').
    if (!b.occluders.ranked_polygon_offsets.empty()) {
        const size_t polygons = b.occluders.polygon_offsets.size() - 1;
        std::vector<uint32_t> renumber(polygons, UINT32_MAX);
        Section planes{PVSR_TAG('O', 'P', 'L', 'N'), PVSR_POLYGON_BYTES, 0, {}};
        Section corners{PVSR_TAG('O', 'P', 'C', 'O'), 12, 0, {}};
        Section list{PVSR_TAG('R', 'P', 'L', 'S'), 8, b.occluders.ranked_polygon.size(), {}};
        for (size_t e = 0; e < b.occluders.ranked_polygon.size(); ++e) {
            const uint32_t p = b.occluders.ranked_polygon[e];
            if (renumber[p] == UINT32_MAX) {
                renumber[p] = uint32_t(planes.count++);
                for (int k = 0; k < 5; ++k)
                    put(planes.bytes, b.occluders.polygon_planes[5 * size_t(p) + size_t(k)]);
                put(planes.bytes, uint32_t(corners.count));
                const uint32_t first = b.occluders.polygon_offsets[p],
                               end = b.occluders.polygon_offsets[p + 1];
                put(planes.bytes, end - first);
                put(planes.bytes, uint32_t(0));
                for (uint32_t c = first; c < end; ++c) {
                    for (int a = 0; a < 3; ++a)
                        put(corners.bytes, b.occluders.polygon_corners[3 * size_t(c) + size_t(a)]);
                    ++corners.count;
                }
            }
            put(list.bytes, renumber[p]);
            put(list.bytes, b.occluders.ranked_polygon_rank[e]);
        }
        sections.push_back(std::move(planes));
        sections.push_back(std::move(corners));
        sections.push_back(
            array_section(PVSR_TAG('R', 'P', 'O', 'F'), 4, b.occluders.ranked_polygon_offsets));
        sections.push_back(std::move(list));
    }

    // 2.1: the horizon's occluders that some list names ('HBOX', then 'HTIL' and 'HTCO' in the 'OPLN' layout,
    // renumbered in order), and per block of cells (the palettes' blocks) the union of its cells' lists, each
    // in the PVS rows' code less the reference (5.0; row_code.h put_rice_indices: 'HLOF' byte offsets,
    // 'HLST' and the padding its reader may read into).
    if (b.horizon.present) {
        const FileHorizon& h = b.horizon;
        const CellBlocks cb = cell_blocks(b.cells, cell_grid);
        const uint64_t occluders = h.box_count() + h.tile_count();
        std::vector<std::vector<uint32_t>> lists(cb.count);
        std::vector<uint32_t> last_list(cb.count, UINT32_MAX);
        for (uint32_t c = 0; c < cells; ++c) {
            const uint32_t l = h.cell_list[c], blk = cb.of[c];
            if (last_list[blk] == l) continue;  // the cells of a block mostly share one list
            last_list[blk] = l;
            lists[blk].insert(lists[blk].end(), h.list_entries.begin() + h.list_offsets[l],
                              h.list_entries.begin() + h.list_offsets[size_t(l) + 1]);
        }
        std::vector<uint8_t> named(occluders, 0);
        for (std::vector<uint32_t>& list : lists) {
            std::sort(list.begin(), list.end());
            list.erase(std::unique(list.begin(), list.end()), list.end());
            for (const uint32_t o : list) named[o] = 1;
        }
        std::vector<uint32_t> renumber(occluders, UINT32_MAX);
        Section hboxes{PVSR_TAG('H', 'B', 'O', 'X'), 24, 0, {}};
        Section htiles{PVSR_TAG('H', 'T', 'I', 'L'), PVSR_POLYGON_BYTES, 0, {}};
        Section hcorners{PVSR_TAG('H', 'T', 'C', 'O'), 12, 0, {}};
        for (uint64_t o = 0; o < h.box_count(); ++o) {
            if (!named[o]) continue;
            renumber[o] = uint32_t(hboxes.count++);
            for (int a = 0; a < 6; ++a) put(hboxes.bytes, h.boxes[6 * o + uint64_t(a)]);
        }
        for (uint64_t t = 0; t < h.tile_count(); ++t) {
            if (!named[h.box_count() + t]) continue;
            renumber[h.box_count() + t] = uint32_t(hboxes.count + htiles.count++);
            for (int k = 0; k < 5; ++k) put(htiles.bytes, h.tile_planes[5 * t + uint64_t(k)]);
            put(htiles.bytes, uint32_t(hcorners.count));
            put(htiles.bytes, h.tile_offsets[t + 1] - h.tile_offsets[t]);
            put(htiles.bytes, uint32_t(0));
            for (uint32_t k = h.tile_offsets[t]; k < h.tile_offsets[t + 1]; ++k) {
                for (int a = 0; a < 3; ++a) put(hcorners.bytes, h.tile_corners[3 * size_t(k) + size_t(a)]);
                ++hcorners.count;
            }
        }
        // Each list in the rows' code, its end in `offsets`; then the padding its reader may read into.
        std::vector<uint8_t> code;
        const auto put_list = [&](Section& into, std::vector<uint32_t>& offsets,
                                  const std::vector<uint32_t>& list, const char* what) {
            code.clear();
            if (!list.empty()) pvsbake::detail::put_rice_indices(code, list);
            into.bytes.append(reinterpret_cast<const char*>(code.data()), code.size());
            if (into.bytes.size() > UINT32_MAX) throw bad_input(fmt::format("{}: {} pass 4 GiB", path, what));
            offsets.push_back(uint32_t(into.bytes.size()));
        };
        // The padding after a section of codes whose entries lie below `limit`.
        const auto pad = [&](Section& lists_section, uint64_t limit) {
            lists_section.count = lists_section.bytes.size();
            lists_section.bytes.append(size_t(PVSR_HORIZON_LIST_PADDING(limit)), '\0');
        };
        const uint64_t occluder_limit = hboxes.count + htiles.count;
        std::vector<uint32_t> offsets = {0};
        Section hlist{PVSR_TAG('H', 'L', 'S', 'T'), 1, 0, {}};
        for (std::vector<uint32_t>& list : lists) {
            for (uint32_t& o : list) o = renumber[o];  // renumbering keeps the order: still ascending
            put_list(hlist, offsets, list, "the horizon lists");
        }
        pad(hlist, occluder_limit);
        // 5.2: where some cell's list is not its block's whole list (lists per cell), each cell's list as its
        // positions in its block's list ('HCOF' byte offsets, cells + 1, into 'HCLS'; the same code), which a
        // 5.1 runtime skips, taking the block's.
        bool per_cell = false;
        for (uint32_t c = 0; c < cells && !per_cell; ++c) {
            const uint32_t l = h.cell_list[c];
            per_cell = h.list_offsets[size_t(l) + 1] - h.list_offsets[l] < lists[cb.of[c]].size();
        }
        if (per_cell) {
            std::vector<uint32_t> cell_offsets = {0}, picks;
            Section cell_lists{PVSR_TAG('H', 'C', 'L', 'S'), 1, 0, {}};
            for (uint32_t c = 0; c < cells; ++c) {
                const uint32_t l = h.cell_list[c];
                const std::vector<uint32_t>& list = lists[cb.of[c]];
                picks.clear();
                for (uint32_t e = h.list_offsets[l]; e < h.list_offsets[size_t(l) + 1]; ++e)
                    picks.push_back(
                        uint32_t(std::lower_bound(list.begin(), list.end(), renumber[h.list_entries[e]]) -
                                 list.begin()));
                std::sort(picks.begin(), picks.end());
                picks.erase(std::unique(picks.begin(), picks.end()), picks.end());
                put_list(cell_lists, cell_offsets, picks, "the cells' horizon lists");
            }
            pad(cell_lists, occluder_limit);
            sections.push_back(array_section(PVSR_TAG('H', 'C', 'O', 'F'), 4, cell_offsets));
            sections.push_back(std::move(cell_lists));
        }
        // 5.3: where the bake kept them, the objects each cell's frames test ('HTOF' byte offsets, cells + 1,
        // into 'HTST': each cell's ascending object indices in the rows' code, then the padding its reader
        // may read into), which a 5.2 runtime skips, testing every object.
        if (!h.test_offsets.empty()) {
            std::vector<uint32_t> test_offsets = {0}, tests;
            Section test_code{PVSR_TAG('H', 'T', 'S', 'T'), 1, 0, {}};
            for (uint32_t c = 0; c < cells; ++c) {
                tests.assign(h.tests.begin() + h.test_offsets[c],
                             h.tests.begin() + h.test_offsets[size_t(c) + 1]);
                put_list(test_code, test_offsets, tests, "the cells' tests");
            }
            pad(test_code, objects);
            sections.push_back(array_section(PVSR_TAG('H', 'T', 'O', 'F'), 4, test_offsets));
            sections.push_back(std::move(test_code));
        }
        sections.push_back(std::move(hboxes));
        sections.push_back(std::move(htiles));
        sections.push_back(std::move(hcorners));
        sections.push_back(array_section(PVSR_TAG('H', 'L', 'O', 'F'), 4, offsets));
        sections.push_back(std::move(hlist));
    }

    // The objects' part boxes, when some object has parts: 5.1, 'OPOQ' offsets (objects + 1, 2 or 4 bytes)
    // into 'OPBQ', six 16-bit steps a part on the grid of the object's bounds (pvsr_part_encode; 2.2's 'OPOF'
    // and 'OPBX' held floats). A bake's parts lie on that grid already (round_parts_to_runtime_grid), so
    // the runtime decodes the bake file's floats; an older bake's are rounded outward to it.
    if (!b.objects.part_offsets.empty() && b.objects.part_offsets.back() > 0) {
        std::vector<uint16_t> steps(b.objects.part_boxes.size());
        float box[6];
        for (size_t o = 0; o + 1 < b.objects.part_offsets.size(); ++o)
            for (uint32_t e = b.objects.part_offsets[o]; e < b.objects.part_offsets[o + 1]; ++e)
                if (!pvsr_part_encode(&b.objects.bounds[6 * o], &b.objects.part_boxes[6 * size_t(e)],
                                      &steps[6 * size_t(e)], box))
                    throw bad_input(fmt::format("{}: object {}'s part box {} is not inside its bounds", path,
                                                o, e - b.objects.part_offsets[o]));
        sections.push_back(index_section(PVSR_TAG('O', 'P', 'O', 'Q'), b.objects.part_offsets));
        sections.push_back(array_section(PVSR_TAG('O', 'P', 'B', 'Q'), 12, steps));
    }

    // The header, the table, the sections at multiples of 64.
    const auto aligned = [](uint64_t n) { return (n + PVSR_ALIGN - 1) / PVSR_ALIGN * PVSR_ALIGN; };
    std::string out(PVSR_HEADER_BYTES, '\0');
    std::string table;
    uint64_t at = aligned(PVSR_HEADER_BYTES + uint64_t(sections.size()) * PVSR_ENTRY_BYTES);
    for (const Section& s : sections) {
        const uint64_t bytes = aligned(s.bytes.size());
        put(table, s.tag);
        put(table, s.item_bytes);
        put(table, at);
        put(table, s.count);
        put(table, bytes);
        at += bytes;
    }
    out += table;
    out.resize(size_t(aligned(out.size())), '\0');
    for (const Section& s : sections) {
        out += s.bytes;
        out.resize(size_t(aligned(out.size())), '\0');
    }
    static const uint8_t kMagic[8] = {'P', 'V', 'S', 'R', 0x0d, 0x0a, 0x1a, 0x0a};
    std::memcpy(out.data(), kMagic, 8);
    std::string head;
    put(head, uint16_t(PVSR_VERSION_MAJOR));
    put(head, uint16_t(PVSR_VERSION_MINOR));
    put(head, uint32_t(PVSR_HEADER_BYTES));
    put(head, uint64_t(out.size()));
    put(head, uint64_t(0));  // the checksum, below
    put(head, uint32_t(sections.size()));
    put(head, uint32_t(b.info.conservative ? PVSR_FLAG_CONSERVATIVE : 0u));
    put(head, objects);
    put(head, cells);
    put(head, uint32_t(b.cells.kind));
    std::memcpy(out.data() + 8, head.data(), head.size());
    const uint64_t sum = XXH64(out.data() + PVSR_CHECKSUMMED_FROM, out.size() - PVSR_CHECKSUMMED_FROM, 0);
    std::memcpy(out.data() + 24, &sum, 8);
    return out;
}

}  // namespace

void round_parts_to_runtime_grid(const World& world, ObjectParts& parts) {
    if (parts.offsets.empty()) return;
    std::vector<Aabb> kept;
    std::vector<uint32_t> offsets = {0};
    for (size_t o = 0; o + 1 < parts.offsets.size() && o < world.objects.size(); ++o) {
        const Aabb& b = world.objects[o].bounds;
        const float bounds[6] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
        const size_t first = kept.size();
        for (uint32_t e = parts.offsets[o]; e < parts.offsets[o + 1]; ++e) {
            const Aabb& p = parts.boxes[e];
            const float part[6] = {p.min.x, p.min.y, p.min.z, p.max.x, p.max.y, p.max.z};
            uint16_t steps[6];
            float box[6];
            if (!pvsr_part_encode(bounds, part, steps, box)) {
                kept.resize(first);
                break;
            }
            kept.push_back(Aabb::of({box[0], box[1], box[2]}, {box[3], box[4], box[5]}));
        }
        offsets.push_back(uint32_t(kept.size()));
    }
    parts.boxes = std::move(kept);
    parts.offsets = std::move(offsets);
}

std::string runtime_file_bytes(const std::string& bake_path, const RuntimeFileOptions& options,
                               RuntimeFileFigures* figures) {
    static_assert(sizeof(float) == 4);
    const uint16_t probe = 1;
    if (*reinterpret_cast<const uint8_t*>(&probe) != 1)
        throw bad_input("the runtime file is written on little-endian machines only");
    Bake b = h5::read_file(bake_path, [&](const pvsbake::detail::Reader& r, hid_t root) {
        Bake bake;
        bake.info = pvsbake::detail::read_header(r, root);
        bake.objects = pvsbake::detail::read_objects(r, root);
        bake.cells = pvsbake::detail::read_cells(r, root, /*read_eyes=*/true, /*bricks=*/true);
        const uint32_t objects = uint32_t(bake.objects.names.size());
        bake.pvs = pvsbake::detail::read_pvs(r, root, objects, bake.cells.count, /*want_rows=*/true);
        bake.occluders = pvsbake::detail::read_occluders(r, root, objects, bake.cells.count, /*want_boxes=*/false);
        bake.horizon = pvsbake::detail::read_horizon(r, root, bake.cells.count, objects);
        return bake;
    });
    std::string bytes = assemble(bake_path, b, options);
    if (figures) {
        figures->file_bytes = bytes.size();
        figures->sections.clear();
        const uint32_t n = *reinterpret_cast<const uint32_t*>(bytes.data() + 32);
        for (uint32_t i = 0; i < n; ++i) {
            const char* e = bytes.data() + PVSR_HEADER_BYTES + size_t(i) * PVSR_ENTRY_BYTES;
            uint32_t tag;
            uint64_t size;
            std::memcpy(&tag, e, 4);
            std::memcpy(&size, e + 24, 8);
            figures->sections.emplace_back(tag_name(tag), size);
        }
    }
    return bytes;
}

RuntimeFileFigures export_runtime_file(const std::string& bake_path, const std::string& out_path,
                                       const RuntimeFileOptions& options) {
    RuntimeFileFigures figures;
    const std::string bytes = runtime_file_bytes(bake_path, options, &figures);
    write_file_atomically(out_path, bytes, "the runtime file");
    return figures;
}

}  // namespace pvs
