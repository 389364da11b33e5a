// SPDX-License-Identifier: MIT
// pvsbake loader (internal): the PVS code, the compact form of PVS rows that the loader keeps in memory and
// that format 1.1 files store in /pvs/code (docs/FORMAT.md, "The PVS code"). The writer (io/bake_file.cpp)
// encodes with encode_rows(); the loader validates with check_row_code() and decodes while walking
// (pvsbake/loader.h, detail::GapReader).
//
// A row is the set bits of a distinct PVS row (object i = bit i % 8 of byte i / 8). Each row's code is
//   varint ref    0: a key row, coded whole; else coded as its XOR with row (r - ref), which is a key row
//   varint head   count << 5 | k: count coded indices, Rice parameter k (0 .. 24)
//   bits          count Rice codes, bit 0 = lowest bit of the first byte: the gap g = index - previous - 1
//                 (previous = -1 at the start) as q = g >> k zero bits, a one bit, then the k low bits of g
// padded with zero bits to a whole byte. Varints hold 7 bits a byte, low first, high bit = more follows.
// Its size against plain rows, deflate and Quake's zero-run code on real bakes: docs/FORMAT.md.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pvsbake::detail {

constexpr uint32_t kMaxRiceK = 24;
// Objects a coded row may index: count << 5 must fit 32 bits.
constexpr uint64_t kMaxCodedObjects = uint64_t(1) << 27;

struct RowCode {
    std::vector<uint8_t> code;
    std::vector<uint32_t> offsets;  // row_count + 1: row r is code[offsets[r] .. offsets[r + 1])
};

// Appends increasing indices (each below kMaxCodedObjects) as a row's code less its reference: the varint
// head and the Rice codes, with the k of the fewest bits. The runtime file's horizon lists (5.0) use it.
void put_rice_indices(std::vector<uint8_t>& out, const std::vector<uint32_t>& idx);

// Codes row_count distinct rows of row_bytes bytes each (rows laid out one after the other). A row is
// coded against the most similar of the last 32 key rows when that saves a fifth of its bits or more.
// objects < kMaxCodedObjects; bits past `objects` in a row must be zero.
RowCode encode_rows(const uint8_t* rows, uint64_t row_count, uint32_t row_bytes, uint32_t objects);

// Codes the rows as encode_rows does, but a row may be coded against any earlier row, itself perhaps coded
// against another: each row's chain (the row, the row it is coded against, and so on to a key row) holds at
// most max_chain rows, and decoding it XORs them all (the runtime file: docs/FORMAT.md, "The runtime file").
// A row's candidates are the rows neighbours(r, out) appends (earlier ones count; the caller's spatial
// neighbours), the last 32 rows and the last 32 key rows; the three with the fewest differing bits are costed
// exactly, and the cheapest of them and the row coded whole is kept.
RowCode encode_rows_chained(const uint8_t* rows, uint64_t row_count, uint32_t row_bytes, uint32_t max_chain,
                            const std::function<void(uint64_t, std::vector<uint64_t>&)>& neighbours);

// "" when code and offsets are a sound code of row_count rows of `objects` objects: offsets start at 0,
// increase, end at code_size; every varint is whole, every reference is a key row before it, every index
// is below `objects` and increasing, and every row's bits end in its last byte. Else what is wrong.
// code must be followed by code_padding(objects) readable bytes. Decodes every index: the check of files
// without a code checksum (before format 1.4).
std::string check_row_code(const uint8_t* code, uint64_t code_size, const uint32_t* offsets,
                           uint64_t row_count, uint32_t objects);

// The check of files with a code checksum (format 1.4): the same as check_row_code for the offsets and each
// row's head (varints whole, references to earlier key rows, Rice parameter <= 24, count <= objects, and
// count * (1 + k) bits fitting the row), without decoding the indices. What it leaves unchecked cannot
// take a decoder out of range (detail::GapReader is bounded: docs/FORMAT.md, "The PVS code"); that the
// bytes are the writer's is what the checksum checks.
std::string check_row_heads(const uint8_t* code, uint64_t code_size, const uint32_t* offsets,
                            uint64_t row_count, uint32_t objects);

// XXH3 (64 bits, seed 0) of the code's bytes: /pvs attribute code_xxh3 (format 1.4).
uint64_t code_checksum(const uint8_t* code, uint64_t code_size);

// Bytes of padding the decoders need after the code: they read whole 8-byte words, and a bounded decode of
// any row whose head passed check_row_heads reads less than 27 bits an object plus 16 bytes past the row's
// start (the unary parts advance the index, which stops below `objects`, at most once more by up to
// objects + 64 bits; count <= objects codes carry 1 + k <= 25 more bits each).
inline size_t code_padding(uint32_t objects) {
    return 4 * size_t(objects) + 24;
}

// Row r decoded into row_bytes bytes (a code whose heads passed check_row_heads, padded with
// code_padding(objects) bytes): bits of indices below `objects` only. For tests and old files.
void decode_row(const uint8_t* code, const uint32_t* offsets, uint64_t r, uint32_t objects, uint8_t* out,
                uint32_t row_bytes);

}  // namespace pvsbake::detail
