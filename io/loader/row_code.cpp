// SPDX-License-Identifier: MIT
// pvsbake loader (internal): the PVS code (row_code.h). Rice coding of gaps: Golomb, "Run-length encodings"
// (IEEE Trans. Inf. Theory, 1966), with power-of-two parameters after Rice (1979); coding a row against a
// similar earlier one is the key-frame idea of video codecs.
#include "row_code.h"

#include "pvsbake/loader.h"

#include <algorithm>
#include <cstring>
#include <functional>

// Compiled into the loader (no library to link for games): xxHash's header-only mode.
#define XXH_INLINE_ALL
#include <xxhash.h>

namespace pvsbake::detail {
namespace {

constexpr size_t kKeyWindow = 32;  // key rows a row may be coded against
constexpr double kDiffGain = 0.8;  // code against a key row when that needs at most 0.8 x the bits

void put_varint(std::vector<uint8_t>& out, uint32_t v) {
    while (v >= 0x80) {
        out.push_back(uint8_t(v | 0x80));
        v >>= 7;
    }
    out.push_back(uint8_t(v));
}

// The best Rice parameter for these increasing indices and the bits it needs.
std::pair<uint32_t, uint64_t> best_rice(const std::vector<uint32_t>& idx) {
    uint32_t best_k = 0;
    uint64_t best_bits = UINT64_MAX;
    for (uint32_t k = 0; k <= kMaxRiceK; ++k) {
        uint64_t bits = 0;
        uint32_t prev = UINT32_MAX;
        for (uint32_t i : idx) {
            bits += ((i - prev - 1) >> k) + 1 + k;
            prev = i;
        }
        if (bits < best_bits) {
            best_bits = bits;
            best_k = k;
        }
        if ((uint64_t(1) << k) > (idx.empty() ? 0 : idx.back())) break;  // larger k only adds bits
    }
    return {best_k, best_bits};
}

// The head (count << 5 | k) and the Rice codes of idx (row_code.h).
void put_indices(std::vector<uint8_t>& out, const std::vector<uint32_t>& idx, uint32_t k) {
    put_varint(out, uint32_t(idx.size()) << 5 | k);
    uint64_t acc = 0;
    int used = 0;
    auto put_bits = [&](uint64_t v, int n) {  // n <= 32
        acc |= v << used;
        used += n;
        while (used >= 8) {
            out.push_back(uint8_t(acc));
            acc >>= 8;
            used -= 8;
        }
    };
    uint32_t prev = UINT32_MAX;
    for (uint32_t i : idx) {
        const uint32_t g = i - prev - 1;
        prev = i;
        for (uint32_t q = g >> k; q > 0;) {
            const uint32_t n = std::min<uint32_t>(q, 32);
            put_bits(0, int(n));
            q -= n;
        }
        put_bits(1, 1);
        put_bits(g & ((uint32_t(1) << k) - 1), int(k));
    }
    if (used > 0) out.push_back(uint8_t(acc));
}

void put_row(std::vector<uint8_t>& out, uint32_t ref, const std::vector<uint32_t>& idx, uint32_t k) {
    put_varint(out, ref);
    put_indices(out, idx, k);
}

void set_bits(const uint64_t* words, uint32_t word_count, std::vector<uint32_t>& idx) {
    idx.clear();
    for (uint32_t w = 0; w < word_count; ++w) {
        for (uint64_t b = words[w]; b != 0; b &= b - 1) idx.push_back(w * 64 + uint32_t(__builtin_ctzll(b)));
    }
}

}  // namespace

void put_rice_indices(std::vector<uint8_t>& out, const std::vector<uint32_t>& idx) {
    put_indices(out, idx, best_rice(idx).first);
}

RowCode encode_rows(const uint8_t* rows, uint64_t row_count, uint32_t row_bytes, uint32_t objects) {
    const uint32_t words = (row_bytes + 7) / 8;
    std::vector<uint64_t> packed(size_t(row_count) * words, 0);
    std::vector<uint32_t> ones(static_cast<size_t>(row_count), 0);
    for (uint64_t r = 0; r < row_count; ++r) {
        uint64_t* w = packed.data() + size_t(r) * words;
        for (uint32_t j = 0; j < row_bytes; ++j)
            w[j / 8] |= uint64_t(rows[size_t(r) * row_bytes + j]) << (8 * (j % 8));
        for (uint32_t i = 0; i < words; ++i) ones[size_t(r)] += uint32_t(__builtin_popcountll(w[i]));
    }
    RowCode out;
    out.offsets.reserve(size_t(row_count) + 1);
    std::vector<uint64_t> keys;
    std::vector<uint32_t> idx, diff_idx;
    std::vector<uint64_t> diff(words);
    for (uint64_t r = 0; r < row_count; ++r) {
        out.offsets.push_back(uint32_t(out.code.size()));
        const uint64_t* w = packed.data() + size_t(r) * words;
        set_bits(w, words, idx);
        const auto [k, bits] = best_rice(idx);
        // The key row with the fewest differing bits, then the exact cost of coding against it.
        uint64_t best_key = UINT64_MAX;
        uint32_t best_ones = ones[size_t(r)];
        for (size_t i = keys.size() > kKeyWindow ? keys.size() - kKeyWindow : 0; i < keys.size(); ++i) {
            const uint64_t* kw = packed.data() + size_t(keys[i]) * words;
            uint32_t n = 0;
            for (uint32_t j = 0; j < words && n < best_ones; ++j)
                n += uint32_t(__builtin_popcountll(w[j] ^ kw[j]));
            if (n < best_ones) {
                best_ones = n;
                best_key = keys[i];
            }
        }
        if (best_key != UINT64_MAX) {
            const uint64_t* kw = packed.data() + size_t(best_key) * words;
            for (uint32_t j = 0; j < words; ++j) diff[j] = w[j] ^ kw[j];
            set_bits(diff.data(), words, diff_idx);
            const auto [dk, dbits] = best_rice(diff_idx);
            if (double(dbits + 16) <= kDiffGain * double(bits)) {
                put_row(out.code, uint32_t(r - best_key), diff_idx, dk);
                continue;
            }
        }
        put_row(out.code, 0, idx, k);
        keys.push_back(r);
    }
    out.offsets.push_back(uint32_t(out.code.size()));
    (void)objects;
    return out;
}

RowCode encode_rows_chained(const uint8_t* rows, uint64_t row_count, uint32_t row_bytes, uint32_t max_chain,
                            const std::function<void(uint64_t, std::vector<uint64_t>&)>& neighbours) {
    const uint32_t words = (row_bytes + 7) / 8;
    std::vector<uint64_t> packed(size_t(row_count) * words, 0);
    for (uint64_t r = 0; r < row_count; ++r) {
        uint64_t* w = packed.data() + size_t(r) * words;
        for (uint32_t j = 0; j < row_bytes; ++j)
            w[j / 8] |= uint64_t(rows[size_t(r) * row_bytes + j]) << (8 * (j % 8));
    }
    RowCode out;
    out.offsets.reserve(size_t(row_count) + 1);
    std::vector<uint32_t> chain(size_t(row_count), 1);  // rows in each row's chain, itself included
    std::vector<uint32_t> idx, diff_idx, best_idx;
    std::vector<uint64_t> diff(words), candidates, keys;
    for (uint64_t r = 0; r < row_count; ++r) {
        out.offsets.push_back(uint32_t(out.code.size()));
        const uint64_t* w = packed.data() + size_t(r) * words;
        set_bits(w, words, idx);
        auto [best_k, best_bits] = best_rice(idx);
        const uint64_t whole_bits = best_bits;
        uint64_t best_ref = 0;
        best_idx = idx;
        // Candidates: the rows the caller names (spatial neighbours), the last kKeyWindow rows and the last
        // kKeyWindow key rows; the three with the fewest differing bits are costed exactly.
        candidates.clear();
        neighbours(r, candidates);
        for (uint64_t i = r > kKeyWindow ? r - kKeyWindow : 0; i < r; ++i) candidates.push_back(i);
        for (size_t i = keys.size() > kKeyWindow ? keys.size() - kKeyWindow : 0; i < keys.size(); ++i)
            candidates.push_back(keys[i]);
        std::sort(candidates.begin(), candidates.end());
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
        std::pair<uint32_t, uint64_t> near[3] = {{UINT32_MAX, 0}, {UINT32_MAX, 0}, {UINT32_MAX, 0}};
        for (const uint64_t cand : candidates) {
            if (cand >= r || chain[size_t(cand)] >= max_chain) continue;
            const uint64_t* kw = packed.data() + size_t(cand) * words;
            uint32_t n = 0;
            for (uint32_t j = 0; j < words && n < near[2].first; ++j) n += uint32_t(__builtin_popcountll(w[j] ^ kw[j]));
            if (n >= near[2].first) continue;
            near[2] = {n, cand};
            std::sort(near, near + 3);
        }
        for (const auto& [n, cand] : near) {
            if (n == UINT32_MAX) continue;
            const uint64_t* kw = packed.data() + size_t(cand) * words;
            for (uint32_t j = 0; j < words; ++j) diff[j] = w[j] ^ kw[j];
            set_bits(diff.data(), words, diff_idx);
            const auto [dk, dbits] = best_rice(diff_idx);
            // As encode_rows: a row coded against another must save a fifth of its bits, or it is better kept
            // as a key row later rows can be coded against (the reference's varint counted as 16 bits).
            if (dbits + 16 < best_bits && double(dbits + 16) <= kDiffGain * double(whole_bits)) {
                best_bits = dbits + 16;
                best_k = dk;
                best_ref = r - cand;
                best_idx = diff_idx;
            }
        }
        put_row(out.code, uint32_t(best_ref), best_idx, best_k);
        if (best_ref > 0) chain[size_t(r)] = chain[size_t(r - best_ref)] + 1;
        if (best_ref == 0) keys.push_back(r);
    }
    out.offsets.push_back(uint32_t(out.code.size()));
    return out;
}

namespace {

// The head of row r (code[offsets[r] ..)): "" and its fields and where its bits start, or what is wrong.
struct RowHead {
    uint32_t ref = 0, count = 0, k = 0;
    const uint8_t* bits = nullptr;
    const uint8_t* stop = nullptr;
};

std::string check_offsets(uint64_t code_size, const uint32_t* offsets, uint64_t row_count, uint32_t objects) {
    if (offsets[0] != 0 || offsets[row_count] != code_size) {
        return "/pvs/code_offsets does not start at 0 and end at the size of /pvs/code";
    }
    if (objects >= kMaxCodedObjects) return "/pvs: too many objects for the PVS code";
    return "";
}

std::string read_head(const uint8_t* code, const uint32_t* offsets, uint64_t r, uint32_t objects,
                      const std::vector<bool>& is_key, RowHead& h) {
    const uint64_t begin = offsets[r], end = offsets[r + 1];
    if (end < begin + 2)
        return "/pvs/code row " + std::to_string(r) + ": offsets decrease or leave no room for a row";
    const uint8_t* p = code + begin;
    h.stop = code + end;
    uint32_t fields[2];
    for (uint32_t& f : fields) {
        uint64_t v = 0;
        for (int shift = 0;; shift += 7) {
            if (p == h.stop || shift > 28) return "/pvs/code row " + std::to_string(r) + ": a damaged varint";
            const uint8_t b = *p++;
            v |= uint64_t(b & 0x7f) << shift;
            if ((b & 0x80) == 0) break;
        }
        if (v > UINT32_MAX) return "/pvs/code row " + std::to_string(r) + ": a damaged varint";
        f = uint32_t(v);
    }
    h.ref = fields[0];
    h.count = fields[1] >> 5;
    h.k = fields[1] & 31;
    h.bits = p;
    const char* wrong = nullptr;
    if (h.ref > r || (h.ref > 0 && !is_key[size_t(r - h.ref)]))
        wrong = ": refers to a row that is not a key row before it";
    else if (h.k > kMaxRiceK)
        wrong = ": Rice parameter above 24";
    else if (h.count > objects)
        wrong = ": more indices than objects";
    return wrong == nullptr ? std::string() : "/pvs/code row " + std::to_string(r) + wrong;
}

// Every index of a row whose head passed: "" or what is wrong (after "/pvs/code row r"). Every bit used
// must lie before h.stop (reads may look up to 8 bytes past it: the buffer is padded).
const char* check_indices(const RowHead& h, uint32_t objects) {
    const uint8_t* const p = h.bits;
    const uint32_t k = h.k;
    const uint64_t limit = uint64_t(h.stop - p) * 8;
    const uint64_t mask = (uint64_t(1) << k) - 1;
    uint64_t pos = 0, last = UINT64_MAX;
    for (uint32_t n = 0; n < h.count; ++n) {
        uint64_t q = 0;
        for (;;) {
            if (pos >= limit || q > objects) return ": the code runs past the row";
            const uint64_t w = peek_bits(p, pos);
            if (w != 0) {
                const unsigned z = unsigned(__builtin_ctzll(w));
                q += z;
                pos += z + 1;
                break;
            }
            q += 64 - (pos & 7);
            pos += 64 - (pos & 7);
        }
        if (pos + k > limit || q > objects) return ": the code runs past the row";
        const uint64_t low = peek_bits(p, pos) & mask;
        pos += k;
        last += 1 + ((q << k) | low);
        if (last >= objects) return ": an index beyond the objects";
    }
    if ((pos + 7) / 8 != limit / 8) return ": bytes left after the code";
    return nullptr;
}

// The offsets and every row's head; with `indices`, every index too.
std::string check_rows(const uint8_t* code, uint64_t code_size, const uint32_t* offsets, uint64_t row_count,
                       uint32_t objects, bool indices) {
    std::string bad = check_offsets(code_size, offsets, row_count, objects);
    if (!bad.empty()) return bad;
    std::vector<bool> is_key(size_t(row_count), false);
    RowHead h;
    for (uint64_t r = 0; r < row_count; ++r) {
        bad = read_head(code, offsets, r, objects, is_key, h);
        if (!bad.empty()) return bad;
        is_key[size_t(r)] = h.ref == 0;
        const char* wrong = nullptr;
        if (uint64_t(h.count) * (1 + h.k) > uint64_t(h.stop - h.bits) * 8)
            wrong = ": the code runs past the row";
        else if (indices)
            wrong = check_indices(h, objects);
        if (wrong != nullptr) return "/pvs/code row " + std::to_string(r) + wrong;
    }
    return "";
}

}  // namespace

std::string check_row_code(const uint8_t* code, uint64_t code_size, const uint32_t* offsets,
                           uint64_t row_count, uint32_t objects) {
    return check_rows(code, code_size, offsets, row_count, objects, /*indices=*/true);
}

std::string check_row_heads(const uint8_t* code, uint64_t code_size, const uint32_t* offsets,
                            uint64_t row_count, uint32_t objects) {
    return check_rows(code, code_size, offsets, row_count, objects, /*indices=*/false);
}

uint64_t code_checksum(const uint8_t* code, uint64_t code_size) {
    return XXH3_64bits(code, size_t(code_size));
}

void decode_row(const uint8_t* code, const uint32_t* offsets, uint64_t r, uint32_t objects, uint8_t* out,
                uint32_t row_bytes) {
    if (row_bytes > 0) std::memset(out, 0, row_bytes);
    auto flip = [&](const uint8_t* p) {
        const uint32_t head = read_varint(p);
        GapReader g(p, head >> 5, head & 31, objects);
        for (uint32_t i = g.next(); i != kEnd; i = g.next()) out[i / 8] ^= uint8_t(1u << (i % 8));
    };
    const uint8_t* p = code + offsets[r];
    const uint32_t ref = read_varint(p);
    flip(p);
    if (ref != 0) {
        const uint8_t* q = code + offsets[r - ref];
        read_varint(q);
        flip(q);
    }
}

}  // namespace pvsbake::detail
