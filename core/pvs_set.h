// SPDX-License-Identifier: MIT
// pvsbake core: the PVS of every cell, as one packed bit row per cell.
//
// Bit order: object i is bit (i % 64) of word (i / 64) of its cell's row. On file the row is stored
// as bytes, object i in bit (i % 8) of byte (i / 8) (see io/bake_file.h): on a little-endian machine
// those are the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pvs {

struct PvsSet {
    uint32_t cell_count = 0;
    uint32_t object_count = 0;
    uint32_t words_per_row = 0;
    std::vector<uint64_t> words;  // cell_count * words_per_row

    static PvsSet make(uint32_t cells, uint32_t objects) {
        PvsSet s;
        s.cell_count = cells;
        s.object_count = objects;
        s.words_per_row = (objects + 63) / 64;
        s.words.assign(size_t(cells) * s.words_per_row, 0);
        return s;
    }
    uint64_t* row(uint32_t cell) { return words.data() + size_t(cell) * words_per_row; }
    const uint64_t* row(uint32_t cell) const { return words.data() + size_t(cell) * words_per_row; }
    void set(uint32_t cell, uint32_t object) { row(cell)[object >> 6] |= uint64_t(1) << (object & 63); }
    void clear(uint32_t cell, uint32_t object) { row(cell)[object >> 6] &= ~(uint64_t(1) << (object & 63)); }
    bool test(uint32_t cell, uint32_t object) const { return (row(cell)[object >> 6] >> (object & 63)) & 1u; }
    uint32_t count(uint32_t cell) const {
        uint32_t n = 0;
        for (uint32_t w = 0; w < words_per_row; ++w) n += uint32_t(__builtin_popcountll(row(cell)[w]));
        return n;
    }
    bool operator==(const PvsSet& o) const {
        return cell_count == o.cell_count && object_count == o.object_count && words == o.words;
    }
};

}  // namespace pvs
