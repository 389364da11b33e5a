/* SPDX-License-Identifier: MIT
 * MIT License
 *
 * Copyright (c) 2026 the pvsbake authors
 *
 * Permission is hereby granted, free of charge, to any person obtaining a copy
 * of this software and associated documentation files (the "Software"), to deal
 * in the Software without restriction, including without limitation the rights
 * to use, copy, modify, merge, publish, distribute, sublicense, and/or sell
 * copies of the Software, and to permit persons to whom the Software is
 * furnished to do so, subject to the following conditions:
 *
 * The above copyright notice and this permission notice shall be included in all
 * copies or substantial portions of the Software.
 *
 * THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
 * IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
 * FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
 * AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
 * LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
 * OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
 * SOFTWARE.
 */
/* pvsr: the pvsbake runtime (pvsr.h). C99 and the C standard library only. The file's layout and every
 * check made here: docs/FORMAT.md, "The runtime file". */
#include "pvsr.h"

#include <float.h>
#include <math.h>
#include <string.h>

#if defined(_MSC_VER)
#include <intrin.h>
#endif

/* ---- Little pieces */

/* Little-endian values at any address (the host is little-endian: checked at open). */
#define PVSR_READER(name, type)              \
    static type name(const uint8_t* p) {     \
        type v;                              \
        memcpy(&v, p, sizeof v);             \
        return v;                            \
    }
PVSR_READER(rd16, uint16_t)
PVSR_READER(rd32, uint32_t)
PVSR_READER(rd64, uint64_t)
PVSR_READER(rdf, float)
PVSR_READER(rdi32, int32_t)
#undef PVSR_READER

/* Trailing zero bits of a non-zero word. */
static unsigned ctz64(uint64_t w) {
#if defined(__GNUC__) || defined(__clang__)
    return (unsigned)__builtin_ctzll(w);
#elif defined(_MSC_VER) && defined(_M_X64)
    unsigned long i;
    _BitScanForward64(&i, w);
    return (unsigned)i;
#else
    unsigned n = 0;
    while ((w & 1u) == 0) {
        w >>= 1;
        ++n;
    }
    return n;
#endif
}

/* Set bits of a word. */
static unsigned popcount64(uint64_t w) {
#if defined(__GNUC__) || defined(__clang__)
    return (unsigned)__builtin_popcountll(w);
#else
    unsigned n = 0;
    for (; w != 0; w &= w - 1) ++n;
    return n;
#endif
}

/* Item i of an array of 2- or 4-byte unsigned integers (CROW, ROFF). */
static uint32_t index_at(const pvsr_array* a, uint64_t i) {
    return a->item_bytes == 2 ? rd16(a->at + 2 * i) : rd32(a->at + 4 * i);
}

/* Where row i's code starts: ROFF's item, or from 4.0 with 'ROFB' its 16-bit item after the base of its 64.
 */
static uint64_t row_offset(const pvsr_level* l, uint64_t i) {
    if (l->row_offset_bases.at != NULL)
        return (uint64_t)rd32(l->row_offset_bases.at + 4 * (i >> 6)) + rd16(l->row_offsets.at + 2 * i);
    return index_at(&l->row_offsets, i);
}

/* The cell's first entry in 'RLST': ROFS's item, or from 4.0 ('RCNT', 'RCNB') the entries of the cells of
 * its 64 before it after their base. */
static uint64_t ranked_first(const pvsr_level* l, uint64_t cell) {
    uint64_t e, c;
    if (l->ranked_offsets.at != NULL) return rd32(l->ranked_offsets.at + 4 * cell);
    e = rd32(l->ranked_count_bases.at + 4 * (cell >> 6));
    for (c = cell & ~(uint64_t)63; c < cell; ++c) e += l->ranked_counts.at[c];
    return e;
}

/* The cell's entries in 'RLST' (ranked_first: the same sections). */
static uint32_t ranked_count(const pvsr_level* l, uint64_t cell) {
    if (l->ranked_offsets.at != NULL)
        return rd32(l->ranked_offsets.at + 4 * cell + 4) - rd32(l->ranked_offsets.at + 4 * cell);
    return l->ranked_counts.at[cell];
}

/* The largest item of an array of 1-, 2- or 4-byte unsigned integers (0 when empty): a range check of a
 * big index array as one pass of a loop with no exit, which compilers vectorize. */
static uint32_t max_item(const pvsr_array* a) {
    uint64_t i;
    uint32_t m = 0;
    if (a->item_bytes == 1) {
        for (i = 0; i < a->count; ++i) m = a->at[i] > m ? a->at[i] : m;
    } else if (a->item_bytes == 2) {
        for (i = 0; i < a->count; ++i) {
            const uint32_t v = rd16(a->at + 2 * i);
            m = v > m ? v : m;
        }
    } else {
        for (i = 0; i < a->count; ++i) {
            const uint32_t v = rd32(a->at + 4 * i);
            m = v > m ? v : m;
        }
    }
    return m;
}

/* The largest items of the big index arrays, found as the checksum passes them (while they are in cache). */
#define PVSR_PRESCANS 4
typedef struct prescan {
    pvsr_array a[PVSR_PRESCANS]; /* at NULL: none */
    uint64_t done[PVSR_PRESCANS]; /* items seen */
    uint32_t max[PVSR_PRESCANS];
} prescan;

/* Takes in the items of each array that lie wholly before `hashed`. */
static void prescan_upto(prescan* ps, const uint8_t* hashed) {
    int k;
    for (k = 0; k < PVSR_PRESCANS; ++k) {
        const pvsr_array* a = &ps->a[k];
        uint64_t n;
        if (a->at == NULL || hashed <= a->at) continue;
        n = (uint64_t)(hashed - a->at) / a->item_bytes;
        if (n > a->count) n = a->count;
        if (n > ps->done[k]) {
            pvsr_array part = *a;
            uint32_t m;
            part.at = a->at + ps->done[k] * a->item_bytes;
            part.count = n - ps->done[k];
            m = max_item(&part);
            ps->max[k] = m > ps->max[k] ? m : ps->max[k];
            ps->done[k] = n;
        }
    }
}

/* max_item(a), from the prescan when it holds the array whole. */
static uint32_t largest(const prescan* ps, const pvsr_array* a) {
    int k;
    for (k = 0; ps != NULL && k < PVSR_PRESCANS; ++k)
        if (ps->a[k].at == a->at && ps->a[k].item_bytes == a->item_bytes && ps->a[k].count == a->count &&
            ps->done[k] == a->count)
            return ps->max[k];
    return max_item(a);
}

/* 2.0, a grid without GRID: the cell at grid position g (-1 for none): g itself, or, with an occupancy mask
 * (GOCC, one bit a position), the number of occupied positions before g (GOCR: per 64 positions, those
 * before them). */
static int32_t cell_of_position(const pvsr_level* l, uint64_t g) {
    uint64_t word;
    if (l->occupancy.at == NULL) return (int32_t)g;
    word = rd64(l->occupancy.at + 8 * (g >> 6));
    if (!((word >> (g & 63u)) & 1u)) return -1;
    word &= ((uint64_t)1 << (g & 63u)) - 1u;
    return (int32_t)(rd32(l->occupancy_ranks.at + 4 * (g >> 6)) + (uint32_t)popcount64(word));
}

/* The grid position of a cell of a grid whose cells have positions (in range: checked at open). */
static uint32_t cell_position(const pvsr_level* l, uint32_t cell) {
    uint64_t lo = 0, hi;
    uint64_t word;
    uint32_t left;
    if (!l->grid_identity) return rd32(l->cell_grid.at + 4 * (uint64_t)cell);
    if (l->occupancy.at == NULL) return cell;
    hi = l->occupancy_ranks.count; /* the last word whose rank is at most cell */
    while (hi - lo > 1) {
        const uint64_t mid = lo + (hi - lo) / 2;
        if (rd32(l->occupancy_ranks.at + 4 * mid) <= cell)
            lo = mid;
        else
            hi = mid;
    }
    word = rd64(l->occupancy.at + 8 * lo);
    left = cell - rd32(l->occupancy_ranks.at + 4 * lo);
    while (left > 0 && word != 0) { /* the (left + 1)-th set bit */
        word &= word - 1u;
        --left;
    }
    return (uint32_t)(64u * lo + (uint32_t)ctz64(word));
}

/* 2.0: the block of the cell whose ranked entries index its palette: on a grid whose cells have positions,
 * the 4 x 4 x 4 block of grid positions holding it (x fastest, then y, then z); else cells 64 c / 64 .. + 63.
 */
#define PVSR_PALETTE_SIDE 4u
#define PVSR_PALETTE_CELLS 64u
static uint32_t palette_block_count(const pvsr_level* l) {
    uint32_t n[3];
    int a;
    if (!l->grid_identity && l->cell_grid.at == NULL)
        return (uint32_t)(((uint64_t)l->cell_count + PVSR_PALETTE_CELLS - 1) / PVSR_PALETTE_CELLS);
    for (a = 0; a < 3; ++a) n[a] = ((uint32_t)l->dims[a] + PVSR_PALETTE_SIDE - 1) / PVSR_PALETTE_SIDE;
    return n[0] * n[1] * n[2];
}

static uint32_t palette_block(const pvsr_level* l, uint32_t cell) {
    uint32_t g, d0, d1, n0, n1;
    if (!l->grid_identity && l->cell_grid.at == NULL) return cell / PVSR_PALETTE_CELLS;
    g = cell_position(l, cell);
    d0 = (uint32_t)l->dims[0];
    d1 = (uint32_t)l->dims[1];
    n0 = (d0 + PVSR_PALETTE_SIDE - 1) / PVSR_PALETTE_SIDE;
    n1 = (d1 + PVSR_PALETTE_SIDE - 1) / PVSR_PALETTE_SIDE;
    return g % d0 / PVSR_PALETTE_SIDE +
           n0 * (g / d0 % d1 / PVSR_PALETTE_SIDE + n1 * (g / (d0 * d1) / PVSR_PALETTE_SIDE));
}

static uint32_t array_item(const pvsr_array* a, uint64_t i) {
    return a->item_bytes == 1 ? a->at[i] : a->item_bytes == 2 ? rd16(a->at + 2 * i) : rd32(a->at + 4 * i);
}

/* Entry e of the ranked occluders, of cell `cell`: its box (1, 2 or 4 bytes an entry; 2.0: through the
 * palette of the cell's block when the file has one), or UINT32_MAX for an entry past its block's palette
 * (only in a file made to pass the checksum: pvsr_open checks every entry against the largest palette). */
static uint32_t ranked_box(const pvsr_level* l, uint32_t cell, uint64_t e) {
    const uint32_t v = array_item(&l->ranked_boxes, e);
    const uint8_t* block;
    if (l->palette.at == NULL) return v;
    block = l->palette_blocks.at + 4 * (uint64_t)palette_block(l, cell);
    if (v >= rd32(block + 4) - rd32(block)) return UINT32_MAX;
    return array_item(&l->palette, (uint64_t)rd32(block) + v);
}

static const char* const kEmpty = "";

/* ---- XXH64 (the xxHash specification, seed given) */

#define P64_1 0x9E3779B185EBCA87ull
#define P64_2 0xC2B2AE3D27D4EB4Full
#define P64_3 0x165667B19E3779F9ull
#define P64_4 0x85EBCA77C2B2AE63ull
#define P64_5 0x27D4EB2F165667C5ull

static uint64_t rotl64(uint64_t x, int r) {
    return (x << r) | (x >> (64 - r));
}
static uint64_t xxh_round(uint64_t acc, uint64_t input) {
    acc += input * P64_2;
    acc = rotl64(acc, 31);
    return acc * P64_1;
}
static uint64_t xxh_merge(uint64_t acc, uint64_t val) {
    acc ^= xxh_round(0, val);
    return acc * P64_1 + P64_4;
}

/* XXH64 of a buffer in steps: the stripes of 32 bytes up to a point, then the rest (so that a caller can
 * check what was just hashed while it is in cache). */
typedef struct xxh64_run {
    const uint8_t *p, *begin, *end;
    uint64_t v[4], seed;
} xxh64_run;

static void xxh_start(xxh64_run* r, const uint8_t* data, size_t size, uint64_t seed) {
    r->p = r->begin = data;
    r->end = data + size;
    r->seed = seed;
    r->v[0] = seed + P64_1 + P64_2;
    r->v[1] = seed + P64_2;
    r->v[2] = seed;
    r->v[3] = seed - P64_1;
}

/* The whole stripes before `until` (clamped to the buffer). */
static void xxh_stripes(xxh64_run* r, const uint8_t* until) {
    const uint8_t* p = r->p;
    uint64_t v1 = r->v[0], v2 = r->v[1], v3 = r->v[2], v4 = r->v[3];
    if (until > r->end) until = r->end;
    while (until - p >= 32) {
        v1 = xxh_round(v1, rd64(p));
        v2 = xxh_round(v2, rd64(p + 8));
        v3 = xxh_round(v3, rd64(p + 16));
        v4 = xxh_round(v4, rd64(p + 24));
        p += 32;
    }
    r->p = p;
    r->v[0] = v1;
    r->v[1] = v2;
    r->v[2] = v3;
    r->v[3] = v4;
}

static uint64_t xxh_finish(xxh64_run* r) {
    const uint8_t* p;
    const uint8_t* const end = r->end;
    const uint64_t size = (uint64_t)(end - r->begin);
    uint64_t h;
    xxh_stripes(r, end);
    p = r->p;
    if (size >= 32) {
        h = rotl64(r->v[0], 1) + rotl64(r->v[1], 7) + rotl64(r->v[2], 12) + rotl64(r->v[3], 18);
        h = xxh_merge(h, r->v[0]);
        h = xxh_merge(h, r->v[1]);
        h = xxh_merge(h, r->v[2]);
        h = xxh_merge(h, r->v[3]);
    } else {
        h = r->seed + P64_5;
    }
    h += size;
    while (end - p >= 8) {
        h ^= xxh_round(0, rd64(p));
        h = rotl64(h, 27) * P64_1 + P64_4;
        p += 8;
    }
    if (end - p >= 4) {
        h ^= (uint64_t)rd32(p) * P64_1;
        h = rotl64(h, 23) * P64_2 + P64_3;
        p += 4;
    }
    while (p < end) {
        h ^= (uint64_t)(*p) * P64_5;
        h = rotl64(h, 11) * P64_1;
        ++p;
    }
    h ^= h >> 33;
    h *= P64_2;
    h ^= h >> 29;
    h *= P64_3;
    h ^= h >> 32;
    return h;
}

uint64_t pvsr_xxh64(const void* data, size_t size, uint64_t seed) {
    xxh64_run r;
    xxh_start(&r, (const uint8_t*)data, size, seed);
    return xxh_finish(&r);
}

/* ---- The PVS code (docs/FORMAT.md, "The PVS code"): a bounded reader of one row's Rice-coded gaps */

#define PVSR_END 0xffffffffu

/* A LEB128 varint of at most 5 bytes at *p (before end), into *value; 0 when it does not end there. */
static int checked_varint(const uint8_t** p, const uint8_t* end, uint64_t* value) {
    int shift = 0;
    *value = 0;
    for (;;) {
        uint8_t byte;
        if (*p >= end || shift > 28) return 0;
        byte = *(*p)++;
        *value |= (uint64_t)(byte & 0x7fu) << shift;
        shift += 7;
        if ((byte & 0x80u) == 0) return 1;
    }
}

/* What is wrong with a Rice code's head (count << 5 | k) for indices below limit in `bits` bits: 0 nothing,
 * 1 a parameter above 24, 2 more indices than limit, 3 codes that cannot fit the bits. A code whose head
 * passes is read by gap_next within its bits plus the padding of FORMAT.md, whatever its bits. */
static int rice_head_fault(uint64_t head, uint32_t limit, uint64_t bits) {
    if (head > 0xffffffffu) return 2;
    if ((head & 31) > 24) return 1;
    if ((head >> 5) > limit) return 2;
    if ((head >> 5) * (1 + (head & 31)) > bits) return 3;
    return 0;
}

typedef struct gap_reader {
    const uint8_t* bits;
    uint64_t pos; /* bit position, bit 0 = the lowest bit of bits[0] */
    uint32_t left, k, limit;
    uint32_t last; /* + 1 wraps to 0 at the start */
} gap_reader;

static uint64_t peek(const gap_reader* g) {
    return rd64(g->bits + (g->pos >> 3)) >> (g->pos & 7);
}

static void gap_init(gap_reader* g, const uint8_t* bits, uint32_t count, uint32_t k, uint32_t limit) {
    g->bits = bits;
    g->pos = 0;
    g->left = count;
    g->k = k;
    g->limit = limit;
    g->last = 0xffffffffu;
}

static uint32_t gap_stop(gap_reader* g) {
    g->left = 0;
    return PVSR_END;
}

/* The next index, increasing, below limit; PVSR_END at the row's end. Reads at most 27 bits an object
 * plus 16 bytes past the row's start whatever the bits (the file pads the code so). */
static uint32_t gap_next(gap_reader* g) {
    uint64_t w, q = 0, low, next;
    if (g->left == 0) return PVSR_END;
    --g->left;
    w = peek(g);
    if (w != 0) {
        const uint32_t z = ctz64(w);
        if (z + 1 + g->k <= 57) {
            const uint32_t lo = (uint32_t)(w >> (z + 1)) & ((1u << g->k) - 1u);
            g->pos += z + 1 + g->k;
            g->last += 1 + ((z << g->k) | lo);
            return g->last < g->limit ? g->last : gap_stop(g);
        }
    }
    for (;;) {
        w = peek(g);
        if (w != 0) {
            const uint32_t z = ctz64(w);
            q += z;
            g->pos += z + 1;
            break;
        }
        {
            const uint32_t valid = 64 - (uint32_t)(g->pos & 7);
            q += valid;
            g->pos += valid;
        }
        if (q > g->limit) return gap_stop(g);
    }
    if (q > g->limit) return gap_stop(g);
    low = peek(g) & (((uint64_t)1 << g->k) - 1);
    g->pos += g->k;
    next = (uint64_t)g->last + 1 + ((q << g->k) | low);
    if ((next & 0xffffffffu) >= g->limit || (q << g->k) >= g->limit) return gap_stop(g);
    g->last = (uint32_t)next;
    return g->last;
}

/* A varint of checked code. */
static uint32_t varint(const uint8_t** p) {
    uint32_t v = 0;
    int shift;
    for (shift = 0;; shift += 7) {
        const uint8_t b = *(*p)++;
        v |= (uint32_t)(b & 0x7f) << shift;
        if ((b & 0x80) == 0) return v;
    }
}

/* The readers of row r's chain (docs/FORMAT.md, "The runtime file"): the row, the row it is coded against,
 * and so on to a key row, at most PVSR_MAX_CHAIN (checked at open). Returns how many; the row is their XOR. */
static int row_chain(const pvsr_level* l, uint32_t r, gap_reader readers[PVSR_MAX_CHAIN]) {
    int n = 0;
    for (;;) {
        const uint8_t* p = l->code.at + row_offset(l, r);
        const uint32_t ref = varint(&p);
        const uint32_t head = varint(&p);
        gap_init(&readers[n++], p, head >> 5, head & 31, l->object_count);
        if (ref == 0 || n == PVSR_MAX_CHAIN) return n;
        r -= ref;
    }
}

/* ---- Opening: every check (docs/FORMAT.md, "The runtime file", "What the runtime checks") */

typedef struct opening {
    pvsr_level* l;
    char* message;
    size_t message_size;
} opening;

static pvsr_status fail(opening* o, pvsr_status status, const char* what) {
    if (o->message != NULL && o->message_size > 0) {
        size_t n = strlen(what);
        if (n >= o->message_size) n = o->message_size - 1;
        memcpy(o->message, what, n);
        o->message[n] = '\0';
    }
    memset(o->l, 0, sizeof *o->l);
    return status;
}

/* Section `tag` of the table: 1 and *out when present with items of item_bytes (0: 2 or 4), else 0.
 * The table was checked: every section lies in the file. */
static int section(const pvsr_level* l, uint32_t tag, pvsr_array* out) {
    const uint32_t n = rd32(l->bytes + 32);
    uint32_t i;
    for (i = 0; i < n; ++i) {
        const uint8_t* e = l->bytes + PVSR_HEADER_BYTES + (uint64_t)i * PVSR_ENTRY_BYTES;
        if (rd32(e) == tag) {
            out->item_bytes = rd32(e + 4);
            out->at = l->bytes + rd64(e + 8);
            out->count = rd64(e + 16);
            out->bytes = rd64(e + 24);
            return 1;
        }
    }
    memset(out, 0, sizeof *out);
    return 0;
}

/* A required or optional section with the expected item size (0: 2 or 4) and count. */
static const char* need(const pvsr_level* l, uint32_t tag, uint32_t item_bytes, uint64_t count, int required,
                        pvsr_array* out) {
    if (!section(l, tag, out)) return required ? "a required section is missing" : NULL;
    if (item_bytes == 0 ? (out->item_bytes != 2 && out->item_bytes != 4) : out->item_bytes != item_bytes)
        return "a section's item size is wrong";
    if (count != UINT64_MAX && out->count != count) return "a section's item count disagrees with the level";
    return NULL;
}

static int finite_box(const uint8_t* p) {
    int a;
    for (a = 0; a < 6; ++a)
        if (!isfinite(rdf(p + 4 * a))) return 0;
    return 1;
}

/* A box may be empty (min +inf, max -inf, the bake's empty object) but holds no NaN. */
static int box_without_nan(const uint8_t* p) {
    int a;
    for (a = 0; a < 6; ++a)
        if (isnan(rdf(p + 4 * a))) return 0;
    return 1;
}

static const char* check_table(pvsr_level* l) {
    const uint32_t n = rd32(l->bytes + 32);
    const uint64_t table_end = PVSR_HEADER_BYTES + (uint64_t)n * PVSR_ENTRY_BYTES;
    uint32_t i, j;
    if (n > 64 || table_end > l->size) return "the section table does not fit the file";
    for (i = 0; i < n; ++i) {
        const uint8_t* e = l->bytes + PVSR_HEADER_BYTES + (uint64_t)i * PVSR_ENTRY_BYTES;
        const uint32_t item = rd32(e + 4);
        const uint64_t at = rd64(e + 8), count = rd64(e + 16), bytes = rd64(e + 24);
        if (at % PVSR_ALIGN != 0 || at < table_end || at > l->size || bytes > l->size - at)
            return "a section lies outside the file or off its 64-byte alignment";
        if (item == 0 || item > 64 || count > bytes / item) return "a section's size disagrees with its items";
        for (j = 0; j < i; ++j) {
            const uint8_t* f = l->bytes + PVSR_HEADER_BYTES + (uint64_t)j * PVSR_ENTRY_BYTES;
            const uint64_t at2 = rd64(f + 8), bytes2 = rd64(f + 24);
            if (rd32(f) == rd32(e)) return "a section appears twice";
            if (at < at2 + bytes2 && at2 < at + bytes) return "two sections overlap";
        }
    }
    return NULL;
}

static const char* check_level(pvsr_level* l, const prescan* ps) {
    pvsr_array a;
    const uint8_t* p;
    uint64_t g;
    int k;
    const char* bad = need(l, PVSR_TAG('L', 'E', 'V', 'L'), PVSR_LEVEL_BYTES, 1, 1, &a);
    if (bad) return bad;
    p = a.at;
    for (k = 0; k < 3; ++k) {
        l->origin[k] = rdf(p + 4 * k);
        l->dims[k] = rdi32(p + 16 + 4 * k);
        l->mask_origin[k] = rdf(p + 32 + 4 * k);
        l->mask_dims[k] = rdi32(p + 48 + 4 * k);
    }
    l->cell_size_m = rdf(p + 12);
    l->node_count = rd32(p + 28);
    l->mask_voxel_m = rdf(p + 44);
    l->mask_flags = rd32(p + 60);
    if (l->mask_flags & ~(PVSR_MASK_VIEW | PVSR_MASK_EYES)) return "the level's mask flags are unknown";
    if (!(isfinite(l->cell_size_m) && l->cell_size_m > 0.0f)) return "the cell size is not a positive number";
    g = 1;
    for (k = 0; k < 3; ++k) {
        if (!isfinite(l->origin[k])) return "the grid's origin is not finite";
        if (l->dims[k] < 0 || l->dims[k] > (1 << 20)) return "the grid's dimensions are out of range";
        g *= (uint64_t)l->dims[k];
    }
    if (g > (1u << 31)) return "the grid has too many cells";
    if (l->cell_kind > 1) return "the cell kind is neither grid nor octree";
    if (l->cell_kind == 0 && l->node_count != 0) return "a grid with octree nodes";
    /* 2.0: a grid whose cells are its positions in order has neither GRID nor CGRD: every position a cell
     * (cell g at position g), or the occupied ones of an occupancy mask. */
    l->grid_identity =
        l->version_major >= 2 && l->cell_kind == 0 && !section(l, PVSR_TAG('G', 'R', 'I', 'D'), &a);
    if (l->grid_identity && section(l, PVSR_TAG('G', 'O', 'C', 'C'), &l->occupancy)) {
        const uint64_t words = (g + 63u) / 64u;
        uint64_t w;
        uint32_t before = 0;
        bad = need(l, PVSR_TAG('G', 'O', 'C', 'C'), 8, words, 1, &l->occupancy);
        if (!bad) bad = need(l, PVSR_TAG('G', 'O', 'C', 'R'), 4, words, 1, &l->occupancy_ranks);
        if (bad) return bad;
        for (w = 0; w < words; ++w) {
            const uint64_t word = rd64(l->occupancy.at + 8 * w);
            if (rd32(l->occupancy_ranks.at + 4 * w) != before)
                return "the occupancy's counts disagree with its bits";
            if (w + 1 == words && (g & 63u) != 0 && (word >> (g & 63u)) != 0)
                return "the occupancy marks positions past the grid";
            before += (uint32_t)popcount64(word);
        }
        if (before != l->cell_count) return "the occupancy's positions are not the cells";
    } else if (l->grid_identity && g != l->cell_count) {
        return "a grid without positions whose cells are not its positions";
    }
    /* Cells with their own rows (no CROW): one row a grid position, in block order. */
    if (l->grid_identity && l->cell_row.at == NULL && l->row_count != g)
        return "a grid whose cells have their own rows with another count of rows";
    bad = l->grid_identity ? NULL : need(l, PVSR_TAG('G', 'R', 'I', 'D'), 4, g, 1, &l->grid_to_cell);
    if (bad) return bad;
    if (l->mask_flags & PVSR_MASK_VIEW) {
        uint64_t tiles = 1, t;
        if (!(isfinite(l->mask_voxel_m) && l->mask_voxel_m > 0.0f)) return "the mask's voxel size is not positive";
        for (k = 0; k < 3; ++k) {
            if (!isfinite(l->mask_origin[k])) return "the mask's origin is not finite";
            if (l->mask_dims[k] < 0 || l->mask_dims[k] > (1 << 24)) return "the mask's dimensions are out of range";
            l->tile_dims[k] = (int32_t)(((uint32_t)l->mask_dims[k] + 8u * PVSR_TILE_BRICKS - 1u) / (8u * PVSR_TILE_BRICKS));
            tiles *= (uint64_t)l->tile_dims[k];
        }
        if (tiles > (1u << 30)) return "the mask has too many tiles";
        bad = need(l, PVSR_TAG('V', 'T', 'I', 'L'), 4, tiles, 1, &l->view_tiles);
        if (!bad && (l->mask_flags & PVSR_MASK_EYES)) bad = need(l, PVSR_TAG('E', 'T', 'I', 'L'), 4, tiles, 1, &l->eye_tiles);
        if (!bad) bad = need(l, PVSR_TAG('M', 'R', 'E', 'F'), 0, UINT64_MAX, 1, &l->mask_refs);
        if (!bad) bad = need(l, PVSR_TAG('M', 'B', 'I', 'T'), 64, UINT64_MAX, 1, &l->mask_bits);
        if (bad) return bad;
        if (l->mask_refs.count % 64 != 0) return "the mask's brick references are not whole blocks";
        for (t = 0; t < tiles; ++t) {
            if (rd32(l->view_tiles.at + 4 * t) >= PVSR_FIRST_BRICK + l->mask_refs.count / 64 ||
                (l->eye_tiles.at != NULL && rd32(l->eye_tiles.at + 4 * t) >= PVSR_FIRST_BRICK + l->mask_refs.count / 64))
                return "a mask tile is out of range";
        }
        if (l->mask_refs.count > 0 && largest(ps, &l->mask_refs) >= PVSR_FIRST_BRICK + l->mask_bits.count)
            return "a mask brick reference is out of range";
    } else if (l->mask_flags & PVSR_MASK_EYES) {
        return "an eye mask without a view mask";
    }
    return NULL;
}

static const char* check_cells(pvsr_level* l, const prescan* ps) {
    const uint32_t c = l->cell_count;
    const int32_t top = (int32_t)(l->cell_kind == 0 ? c : l->node_count);
    uint64_t i;
    const char* bad;
    if (c > (1u << 31) || l->node_count > (1u << 31)) return "too many cells or nodes";
    {
        int32_t lo = -1, hi = -1; /* one pass with no exit, which compilers vectorize */
        for (i = 0; i < l->grid_to_cell.count; ++i) {
            const int32_t v = rdi32(l->grid_to_cell.at + 4 * i);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        if (lo < -1 || hi >= top) return "a grid position names a cell or node out of range";
    }
    if (l->cell_kind == 1) {
        bad = need(l, PVSR_TAG('N', 'O', 'D', 'E'), PVSR_NODE_BYTES, l->node_count, 1, &l->nodes);
        if (bad) return bad;
        for (i = 0; i < l->node_count; ++i) {
            const uint8_t* n = l->nodes.at + PVSR_NODE_BYTES * i;
            const int32_t first = rdi32(n + 12), cell = rdi32(n + 16);
            int k;
            for (k = 0; k < 3; ++k)
                if (!isfinite(rdf(n + 4 * k))) return "an octree node's centre is not finite";
            /* Children come after their parent, so a descent always ends. */
            if (first != -1 && (first <= (int64_t)i || (uint64_t)first + 8 > l->node_count))
                return "an octree node's children are out of order or range";
            if (cell < -1 || cell >= (int64_t)c) return "an octree node names a cell out of range";
        }
    }
    if (l->grid_identity) {
        if (section(l, PVSR_TAG('C', 'G', 'R', 'D'), &l->cell_grid) ||
            section(l, PVSR_TAG('C', 'B', 'O', 'X'), &l->cell_boxes))
            return "a grid without positions that gives its cells' places";
    } else if (section(l, PVSR_TAG('C', 'G', 'R', 'D'), &l->cell_grid)) {
        bad = need(l, PVSR_TAG('C', 'G', 'R', 'D'), 4, c, 1, &l->cell_grid);
        if (bad) return bad;
        if (l->cell_kind != 0) return "an octree's cells given by grid positions";
        if (c > 0 && largest(ps, &l->cell_grid) >= l->grid_to_cell.count)
            return "a cell's grid position is out of range";
    } else {
        bad = need(l, PVSR_TAG('C', 'B', 'O', 'X'), 24, c, 1, &l->cell_boxes);
        if (bad) return bad;
        for (i = 0; i < c; ++i)
            if (!finite_box(l->cell_boxes.at + 24 * i)) return "a cell's box is not finite";
    }
    return NULL;
}

/* The rows' sections and their sizes (the rows themselves: check_row). */
static const char* check_row_sections(pvsr_level* l) {
    const uint32_t n = l->object_count;
    uint64_t code_size, padding;
    pvsr_array grid;
    /* 2.0: a grid without GRID and without CROW gives every grid position its own row, in block order. */
    const int implicit = l->version_major >= 2 && l->cell_kind == 0 &&
                         !section(l, PVSR_TAG('G', 'R', 'I', 'D'), &grid) &&
                         !section(l, PVSR_TAG('C', 'R', 'O', 'W'), &l->cell_row);
    const char* bad =
        implicit ? NULL : need(l, PVSR_TAG('C', 'R', 'O', 'W'), 0, l->cell_count, 1, &l->cell_row);
    if (!bad) bad = need(l, PVSR_TAG('R', 'O', 'F', 'F'), 0, UINT64_MAX, 1, &l->row_offsets);
    if (!bad) bad = need(l, PVSR_TAG('C', 'O', 'D', 'E'), 1, UINT64_MAX, 1, &l->code);
    if (bad) return bad;
    if (l->row_offsets.count < 1 || l->row_offsets.count - 1 > 0xffffffffu) return "the row offsets are empty";
    /* 4.0: 'ROFB', the offset of every 64th row, and ROFF's 16-bit items after them */
    if (section(l, PVSR_TAG('R', 'O', 'F', 'B'), &l->row_offset_bases)) {
        if (l->row_offsets.item_bytes != 2) return "row offset bases with 32-bit row offsets";
        bad = need(l, PVSR_TAG('R', 'O', 'F', 'B'), 4, (l->row_offsets.count + 63) / 64, 1,
                   &l->row_offset_bases);
        if (bad) return bad;
    }
    l->row_count = (uint32_t)(l->row_offsets.count - 1);
    code_size = l->code.count;
    l->code_bytes = code_size;
    /* The decoders read whole words past a row: the section holds the code and then at least this much. */
    padding = 4 * (uint64_t)n + 24;
    if (l->code.bytes < code_size + padding) return "the PVS code is not followed by its padding";
    if (l->row_count == 0 && l->cell_count > 0) return "cells but no PVS rows";
    return NULL;
}

/* The cells' rows in range and the row offsets' ends (after check_row_sections, before the rows). */
static const char* check_row_ends(const pvsr_level* l, const prescan* ps) {
    if (l->cell_row.at != NULL && l->cell_count > 0 && largest(ps, &l->cell_row) >= l->row_count)
        return "a cell's row is out of range";
    if (row_offset(l, 0) != 0 || row_offset(l, l->row_count) != l->code.count)
        return "the row offsets do not start at 0 and end at the code's size";
    return NULL;
}

/* 2.0: the positions of a 4 x 4 x 4 block (x + 4 (y + 4 z)) breadth first from (1, 1, 1), neighbours taken
 * -x, +x, -y, +y, -z, +z: the order of the rows of a grid whose cells have their own rows. */
static const uint8_t kBlockOrder[64] = {21, 20, 22, 17, 25, 5,  37, 16, 24, 4,  36, 23, 18, 26, 6,  38,
                                        1,  33, 29, 9,  41, 53, 0,  32, 28, 8,  40, 52, 19, 27, 7,  39,
                                        2,  34, 30, 10, 42, 54, 49, 13, 45, 57, 48, 12, 44, 56, 3,  35,
                                        31, 11, 43, 55, 50, 14, 46, 58, 61, 60, 51, 15, 47, 59, 62, 63};

/* The place of grid position g in block order: the blocks of 4 x 4 x 4 positions x fastest, then y, then z
 * (cut at the grid's faces), and in each its positions in kBlockOrder. */
static uint32_t block_rank(const pvsr_level* l, uint32_t g) {
    const uint32_t dx = (uint32_t)l->dims[0], dy = (uint32_t)l->dims[1], dz = (uint32_t)l->dims[2];
    const uint32_t x = g % dx, y = g / dx % dy, z = g / (dx * dy);
    const uint32_t bx = x & ~3u, by = y & ~3u, bz = z & ~3u;
    const uint32_t tx = dx - bx < 4u ? dx - bx : 4u, ty = dy - by < 4u ? dy - by : 4u,
                   tz = dz - bz < 4u ? dz - bz : 4u;
    const uint32_t want = (x - bx) + 4u * ((y - by) + 4u * (z - bz));
    uint32_t r = bz * dx * dy + by * dx * tz + bx * ty * tz, i;
    for (i = 0; i < 64u && kBlockOrder[i] != want; ++i) {
        const uint32_t p = kBlockOrder[i];
        r += (p & 3u) < tx && (p >> 2 & 3u) < ty && (p >> 4) < tz;
    }
    return r;
}

/* The row of a cell (in range: checked at open). */
static uint32_t cell_row(const pvsr_level* l, uint32_t cell) {
    return l->cell_row.at != NULL ? index_at(&l->cell_row, cell) : block_rank(l, cell_position(l, cell));
}

/* Rows whose chain lengths check_row keeps (a power of 2): a row coded against one of the rows just before
 * it takes that row's length plus one instead of walking its chain. */
#define PVSR_DEPTH_RING 4096

/* Row i's head and chain, the rows before it checked in order with the same `depth` ring. */
static const char* check_row(const pvsr_level* l, uint64_t i, uint8_t depth[PVSR_DEPTH_RING]) {
    const uint32_t n = l->object_count;
    const uint32_t max_chain = n <= PVSR_STACK_OBJECTS ? PVSR_MAX_CHAIN : 2;
    const uint64_t code_size = l->code.count;
    const uint64_t begin = row_offset(l, i), end = row_offset(l, i + 1);
    const uint8_t* p = l->code.at + begin;
    const uint8_t* const stop = l->code.at + end;
    uint64_t fields[2];
    if (end < begin + 2 || end > code_size) return "a PVS row's offsets decrease, pass the code or leave no room for it";
    if (!checked_varint(&p, stop, &fields[0]) || !checked_varint(&p, stop, &fields[1]) ||
        fields[0] > 0xffffffffu || fields[1] > 0xffffffffu)
        return "a PVS row's head is damaged";
    if (fields[0] > i) return "a PVS row refers to a row after it";
    if (fields[0] == 0) {
        depth[i & (PVSR_DEPTH_RING - 1)] = 1;
    } else if (fields[0] < PVSR_DEPTH_RING) {
        const uint32_t length = depth[(i - fields[0]) & (PVSR_DEPTH_RING - 1)] + 1u;
        if (length > max_chain) return "a PVS row's chain of references is too long";
        depth[i & (PVSR_DEPTH_RING - 1)] = (uint8_t)length;
    } else { /* the rows before it were checked: follow its chain to a key row */
        uint64_t at = i - fields[0];
        uint32_t length = 2;
        for (;;) {
            const uint8_t* q = l->code.at + row_offset(l, at);
            const uint32_t ref = varint(&q);
            if (ref == 0) break;
            if (++length > max_chain) return "a PVS row's chain of references is too long";
            at -= ref;
        }
        depth[i & (PVSR_DEPTH_RING - 1)] = (uint8_t)length;
    }
    switch (rice_head_fault(fields[1], n, (uint64_t)(stop - p) * 8)) {
        case 1:
            return "a PVS row's Rice parameter is above 24";
        case 2:
            return "a PVS row has more indices than objects";
        case 3:
            return "a PVS row's code runs past the row";
        default:
            return NULL;
    }
}

/* Bytes of the code hashed between checks of the rows they hold (so that a row's head is checked while the
 * checksum has just brought it into the cache). */
#define PVSR_CHECK_CHUNK 65536

static const char* check_objects(pvsr_level* l) {
    const uint32_t n = l->object_count;
    uint64_t i;
    const char* bad = need(l, PVSR_TAG('O', 'B', 'O', 'X'), 24, n, 1, &l->object_boxes);
    if (!bad) bad = need(l, PVSR_TAG('O', 'T', 'R', 'I'), 4, n, 1, &l->object_triangles);
    if (!bad) bad = need(l, PVSR_TAG('O', 'F', 'L', 'G'), 4, n, 1, &l->object_flags);
    if (!bad) bad = need(l, PVSR_TAG('O', 'N', 'A', 'M'), 4, (uint64_t)n + 1, 1, &l->name_offsets);
    if (!bad) bad = need(l, PVSR_TAG('O', 'S', 'T', 'R'), 1, UINT64_MAX, 1, &l->names);
    if (bad) return bad;
    if (n >= PVSR_MAX_OBJECTS) return "too many objects";
    l->total_triangles = 0;
    for (i = 0; i < n; ++i) {
        const uint32_t a = rd32(l->name_offsets.at + 4 * i), b = rd32(l->name_offsets.at + 4 * i + 4);
        if (!box_without_nan(l->object_boxes.at + 24 * i)) return "an object's box holds a NaN";
        if (b <= a || b > l->names.count || l->names.at[b - 1] != 0)
            return "an object's name is out of range or not NUL-terminated";
        l->total_triangles += rd32(l->object_triangles.at + 4 * i);
    }
    if (rd32(l->name_offsets.at) != 0 && n > 0) return "the names do not start at 0";
    return NULL;
}

static const char* check_ranked(pvsr_level* l, const prescan* ps) {
    uint64_t c, e;
    const char* bad;
    if (section(l, PVSR_TAG('R', 'O', 'F', 'S'), &l->ranked_offsets)) {
        bad = need(l, PVSR_TAG('R', 'O', 'F', 'S'), 4, (uint64_t)l->cell_count + 1, 1, &l->ranked_offsets);
    } else if (section(l, PVSR_TAG('R', 'C', 'N', 'T'), &l->ranked_counts)) {
        /* 4.0: each cell's entry count ('RCNT') and the first entry of every 64th cell ('RCNB') */
        bad = need(l, PVSR_TAG('R', 'C', 'N', 'T'), 1, l->cell_count, 1, &l->ranked_counts);
        if (!bad)
            bad = need(l, PVSR_TAG('R', 'C', 'N', 'B'), 4, ((uint64_t)l->cell_count + 63) / 64, 1,
                       &l->ranked_count_bases);
    } else {
        return NULL; /* no ranking */
    }
    if (!bad) bad = need(l, PVSR_TAG('R', 'B', 'O', 'X'), 24, UINT64_MAX, 1, &l->occluder_boxes);
    if (!bad && !section(l, PVSR_TAG('R', 'L', 'S', 'T'), &l->ranked_boxes)) bad = "a required section is missing";
    if (!bad && l->ranked_boxes.item_bytes != 1 && l->ranked_boxes.item_bytes != 2 && l->ranked_boxes.item_bytes != 4)
        bad = "a section's item size is wrong";
    if (!bad && section(l, PVSR_TAG('R', 'M', 'E', 'A'), &l->ranked_measures))
        bad = need(l, PVSR_TAG('R', 'M', 'E', 'A'), PVSR_MEASURE_BYTES, l->ranked_boxes.count, 1, &l->ranked_measures);
    if (bad) return bad;
    if (l->occluder_boxes.count > 0xffffffffu) return "too many occluder boxes";
    l->occluder_box_count = (uint32_t)l->occluder_boxes.count;
    for (e = 0; e < l->occluder_boxes.count; ++e)
        if (!finite_box(l->occluder_boxes.at + 24 * e)) return "an occluder box is not finite";
    if (section(l, PVSR_TAG('R', 'P', 'A', 'L'),
                &l->palette)) { /* 2.0: entries index their block's palette */
        const uint32_t blocks = palette_block_count(l);
        uint32_t wrong = 0, largest_palette = 0;
        if (l->version_major < 2) return "a palette of ranked occluders in a 1.x file";
        bad = need(l, PVSR_TAG('R', 'P', 'A', 'L'), 0, UINT64_MAX, 1, &l->palette);
        if (!bad) bad = need(l, PVSR_TAG('R', 'P', 'B', 'K'), 4, (uint64_t)blocks + 1, 1, &l->palette_blocks);
        if (bad) return bad;
        if (l->palette.count > 0 && max_item(&l->palette) >= l->occluder_boxes.count)
            return "a ranked occluder names a box out of range";
        if (rd32(l->palette_blocks.at) != 0 ||
            rd32(l->palette_blocks.at + 4 * (uint64_t)blocks) != l->palette.count)
            return "the palettes do not start at 0 and end at their entries' count";
        for (c = 0; c < blocks; ++c) {
            const uint32_t size = rd32(l->palette_blocks.at + 4 * c + 4) - rd32(l->palette_blocks.at + 4 * c);
            wrong |= rd32(l->palette_blocks.at + 4 * c + 4) < rd32(l->palette_blocks.at + 4 * c);
            largest_palette = size > largest_palette ? size : largest_palette;
        }
        if (wrong) return "the palettes' offsets decrease";
        /* Within the largest palette here; within its own block's when read (ranked_box). */
        if (l->ranked_boxes.count > 0 && largest(ps, &l->ranked_boxes) >= largest_palette)
            return "a ranked occluder is out of its block's palette";
    } else if (l->ranked_boxes.count > 0 && largest(ps, &l->ranked_boxes) >= l->occluder_boxes.count) {
        return "a ranked occluder names a box out of range";
    }
    if (l->ranked_offsets.at != NULL) {
        uint32_t wrong = 0; /* one pass with no exit, which compilers vectorize */
        if (rd32(l->ranked_offsets.at) != 0 ||
            rd32(l->ranked_offsets.at + 4 * (uint64_t)l->cell_count) != l->ranked_boxes.count)
            return "the ranked offsets do not start at 0 and end at the entries' count";
        for (c = 0; c < l->cell_count; ++c)
            wrong |= rd32(l->ranked_offsets.at + 4 * c + 4) < rd32(l->ranked_offsets.at + 4 * c);
        if (wrong) return "the ranked offsets decrease or pass the entries";
    } else { /* each base the sum of the counts before it, and all of them the entries' count */
        uint64_t sum = 0;
        for (c = 0; c < l->cell_count; ++c) {
            if ((c & 63) == 0 && rd32(l->ranked_count_bases.at + 4 * (c >> 6)) != sum)
                return "a ranked entry base is not the sum of the counts before it";
            sum += l->ranked_counts.at[c];
        }
        if (sum != l->ranked_boxes.count)
            return "the ranked entry counts do not add up to the entries' count";
    }
    for (c = 0; c < l->cell_count && l->ranked_measures.at != NULL; ++c) {
        const uint64_t a = ranked_first(l, c), b = a + ranked_count(l, c);
        for (e = a; e < b; ++e) {
            const uint8_t* r = l->ranked_measures.at + PVSR_MEASURE_BYTES * e;
            const float score = rdf(r), sa = rdf(r + 4), hidden = rdf(r + 8), share = rdf(r + 12);
            if (!(isfinite(score) && score >= 0.0f) || (e > a && score > rdf(r - PVSR_MEASURE_BYTES)))
                return "a ranked occluder's score is not finite, negative, or above the one before it";
            if (!(sa >= 0.0f && sa <= 12.5664f) || !(hidden >= 0.0f && hidden <= (float)l->object_count) ||
                !(share >= 0.0f && share <= 1.0f))
                return "a ranked occluder's measure is out of range";
        }
    }
    return NULL;
}

/* Polygon records in the 'OPLN' layout (polygon occluders, horizon tiles) and their corners: 0 when every
 * plane is finite with thickness >= 0, every record has 3 to max_corners corners within `corners`, and every
 * corner is finite; else 1 (plane), 2 (thickness), 3 (corner range) or 4 (corner not finite). */
static int check_polygon_records(const pvsr_array* records, const pvsr_array* corners, uint64_t max_corners) {
    uint64_t e;
    for (e = 0; e < records->count; ++e) {
        const uint8_t* p = records->at + PVSR_POLYGON_BYTES * e;
        const uint64_t first = rd32(p + 20), n = rd32(p + 24);
        int k;
        for (k = 0; k < 5; ++k)
            if (!isfinite(rdf(p + 4 * k))) return 1;
        if (!(rdf(p + 16) >= 0.0f)) return 2;
        if (n < 3 || n > max_corners || first + n > corners->count) return 3;
    }
    for (e = 0; e < 3 * corners->count; ++e)
        if (!isfinite(rdf(corners->at + 4 * e))) return 4;
    return 0;
}

/* File version 1.1: the polygon occluders ('OPLN', 'OPCO') and the cells' ranked polygons ('RPOF', 'RPLS'):
 * all four or none; each polygon 3 to PVSR_POLYGON_MAX_CORNERS finite corners in range on a finite plane;
 * each cell's polygons in range, at places increasing and within its whole list. */
static const char* check_polygons(pvsr_level* l) {
    uint64_t c, e;
    const char* bad;
    if (!section(l, PVSR_TAG('R', 'P', 'O', 'F'), &l->ranked_polygon_offsets)) return NULL; /* none */
    if (l->ranked_offsets.at == NULL && l->ranked_counts.at == NULL)
        return "ranked polygons without ranked occluders";
    bad =
        need(l, PVSR_TAG('R', 'P', 'O', 'F'), 4, (uint64_t)l->cell_count + 1, 1, &l->ranked_polygon_offsets);
    if (!bad)
        bad = need(l, PVSR_TAG('O', 'P', 'L', 'N'), PVSR_POLYGON_BYTES, UINT64_MAX, 1, &l->occluder_polygons);
    if (!bad) bad = need(l, PVSR_TAG('O', 'P', 'C', 'O'), 12, UINT64_MAX, 1, &l->polygon_corners);
    if (!bad) bad = need(l, PVSR_TAG('R', 'P', 'L', 'S'), 8, UINT64_MAX, 1, &l->ranked_polygons);
    if (bad) return bad;
    switch (check_polygon_records(&l->occluder_polygons, &l->polygon_corners, PVSR_POLYGON_MAX_CORNERS)) {
        case 1:
            return "a polygon occluder's plane is not finite";
        case 2:
            return "a polygon occluder's thickness is negative";
        case 3:
            return "a polygon occluder's corners are out of range";
        case 4:
            return "a polygon occluder's corner is not finite";
        default:
            break;
    }
    if (rd32(l->ranked_polygon_offsets.at) != 0 ||
        rd32(l->ranked_polygon_offsets.at + 4 * (uint64_t)l->cell_count) != l->ranked_polygons.count)
        return "the ranked polygon offsets do not start at 0 and end at the entries' count";
    for (c = 0; c < l->cell_count; ++c) {
        const uint32_t a = rd32(l->ranked_polygon_offsets.at + 4 * c),
                       b = rd32(l->ranked_polygon_offsets.at + 4 * c + 4);
        uint64_t whole;
        if (b < a) return "the ranked polygon offsets decrease";
        whole = (uint64_t)(b - a) + pvsr_occluder_count(l, (uint32_t)c);
        for (e = a; e < b; ++e) {
            const uint8_t* r = l->ranked_polygons.at + 8 * e;
            if (rd32(r) >= l->occluder_polygons.count) return "a ranked polygon names a polygon out of range";
            if (rd32(r + 4) >= whole || (e > a && rd32(r + 4) <= rd32(r - 4)))
                return "a ranked polygon's place is out of its cell's list or not after the one before it";
        }
    }
    return NULL;
}

/* The horizon's occluders: boxes, then tiles (at most 2^32 - 1: checked at open). */
static uint32_t hz_limit(const pvsr_level* l) {
    return (uint32_t)(l->horizon_boxes.count + l->horizon_tiles.count);
}

/* What a damaged section of per-cell codes is refused with (check_cell_codes). */
typedef struct cell_code_faults {
    const char *no_offsets, *too_old, *no_padding, *not_at_0, *offsets, *head, *code;
} cell_code_faults;

/* Per-cell codes ('offsets_tag' byte offsets, cells + 1, into 'codes_tag'): each cell's a key row of the PVS
 * code less its reference, its entries below limit; both sections or neither, from 5.0. Offsets from 0,
 * never decreasing, within the bytes; each head as a row's; the padding after them. */
static const char* check_cell_codes(pvsr_level* l, uint32_t offsets_tag, uint32_t codes_tag,
                                    pvsr_array* offsets, pvsr_array* codes, uint32_t limit,
                                    const cell_code_faults* f) {
    uint64_t e;
    const char* bad;
    if (!section(l, offsets_tag, offsets)) return section(l, codes_tag, codes) ? f->no_offsets : NULL;
    bad = need(l, offsets_tag, 4, (uint64_t)l->cell_count + 1, 1, offsets);
    if (!bad) bad = need(l, codes_tag, 1, UINT64_MAX, 1, codes);
    if (!bad && l->version_major < 5) bad = f->too_old;
    if (bad) return bad;
    if (codes->bytes - codes->count < PVSR_HORIZON_LIST_PADDING(limit)) return f->no_padding;
    if (rd32(offsets->at) != 0) return f->not_at_0;
    for (e = 0; e + 1 < offsets->count; ++e) {
        const uint32_t a = rd32(offsets->at + 4 * e), b = rd32(offsets->at + 4 * e + 4);
        const uint8_t* p = codes->at + a;
        uint64_t head;
        if (b < a || b > codes->count) return f->offsets;
        if (b == a) continue;
        if (!checked_varint(&p, codes->at + b, &head)) return f->head;
        if (rice_head_fault(head, limit, (uint64_t)(codes->at + b - p) * 8) != 0) return f->code;
    }
    return NULL;
}

/* File version 5.2: lists per cell ('HCOF' into 'HCLS'): each cell's list as the ascending positions of its
 * occluders in its block's list (limit: the occluders), read only with the horizon's lists. A position past
 * the block's list ends the cell's list where it is read (hz_list_next). */
static const char* check_horizon_cells(pvsr_level* l) {
    static const cell_code_faults faults = {"the cells' horizon lists without their offsets",
                                            "the cells' horizon lists in a file before 5.0",
                                            "the cells' horizon lists are not followed by their padding",
                                            "the cells' horizon lists do not start at 0",
                                            "the cells' horizon lists' offsets decrease or pass their bytes",
                                            "a cell's horizon list's head is damaged",
                                            "a cell's horizon list's code is damaged"};
    return check_cell_codes(l, PVSR_TAG('H', 'C', 'O', 'F'), PVSR_TAG('H', 'C', 'L', 'S'),
                            &l->horizon_cell_offsets, &l->horizon_cell_lists, hz_limit(l), &faults);
}

/* File version 5.3: the objects each cell's frames give the horizon ('HTOF' into 'HTST'): each cell's
 * ascending object indices (limit: the objects), read only with the horizon's lists. A damaged code ends the
 * cell's tests where it is read (the horizon then tests none of the rest). */
static const char* check_horizon_tests(pvsr_level* l) {
    static const cell_code_faults faults = {"the cells' tests without their offsets",
                                            "the cells' tests in a file before 5.0",
                                            "the cells' tests are not followed by their padding",
                                            "the cells' tests do not start at 0",
                                            "the cells' tests' offsets decrease or pass their bytes",
                                            "a cell's tests' head is damaged",
                                            "a cell's tests' code is damaged"};
    return check_cell_codes(l, PVSR_TAG('H', 'T', 'O', 'F'), PVSR_TAG('H', 'T', 'S', 'T'),
                            &l->horizon_test_offsets, &l->horizon_tests, l->object_count, &faults);
}

/* File version 2.1: the horizon's occluders ('HBOX' boxes, 'HTIL' tiles in the 'OPLN' layout, 'HTCO' their
 * corners) and a list per block of cells ('HLOF' byte offsets, blocks + 1, into 'HLST': per list the gaps
 * between its ascending occluder indices, less one, as LEB128 varints; from 5.0 a key row of the PVS code
 * less its reference, hz_list):
 * all five or none. Boxes finite with
 * min <= max; tiles 3 to PVSR_HORIZON_MAX_CORNERS finite corners in range on a finite plane; offsets from 0,
 * never decreasing, within the lists' bytes; from 5.0 each list's head as check_row checks a row's, and the
 * padding after the lists. A list's codes are bounded where they are read (gap_next; the LEB128 lists:
 * hz_list_next), not here: a damaged list ends early. */
static const char* check_horizon(pvsr_level* l) {
    uint64_t e;
    const char* bad;
    pvsr_array cells;
    if (!section(l, PVSR_TAG('H', 'L', 'O', 'F'), &l->horizon_list_offsets)) /* none */
        return section(l, PVSR_TAG('H', 'C', 'O', 'F'), &cells) ||
                       section(l, PVSR_TAG('H', 'C', 'L', 'S'), &cells)
                   ? "the cells' horizon lists without the horizon's"
                   : NULL;
    bad = need(l, PVSR_TAG('H', 'L', 'O', 'F'), 4, (uint64_t)palette_block_count(l) + 1, 1,
               &l->horizon_list_offsets);
    if (!bad) bad = need(l, PVSR_TAG('H', 'L', 'S', 'T'), 1, UINT64_MAX, 1, &l->horizon_lists);
    if (!bad) bad = need(l, PVSR_TAG('H', 'B', 'O', 'X'), 24, UINT64_MAX, 1, &l->horizon_boxes);
    if (!bad)
        bad = need(l, PVSR_TAG('H', 'T', 'I', 'L'), PVSR_POLYGON_BYTES, UINT64_MAX, 1, &l->horizon_tiles);
    if (!bad) bad = need(l, PVSR_TAG('H', 'T', 'C', 'O'), 12, UINT64_MAX, 1, &l->horizon_corners);
    if (bad) return bad;
    if (l->horizon_boxes.count + l->horizon_tiles.count > 0xffffffffu) return "too many horizon occluders";
    if (l->version_major >= 5 &&
        l->horizon_lists.bytes - l->horizon_lists.count <
            PVSR_HORIZON_LIST_PADDING(hz_limit(l)))
        return "the horizon lists are not followed by their padding";
    for (e = 0; e < l->horizon_boxes.count; ++e) {
        const uint8_t* p = l->horizon_boxes.at + 24 * e;
        int a;
        if (!finite_box(p)) return "a horizon box is not finite";
        for (a = 0; a < 3; ++a)
            if (rdf(p + 4 * a) > rdf(p + 12 + 4 * a)) return "a horizon box's min is above its max";
    }
    switch (check_polygon_records(&l->horizon_tiles, &l->horizon_corners, PVSR_HORIZON_MAX_CORNERS)) {
        case 1:
            return "a horizon tile's plane is not finite";
        case 2:
            return "a horizon tile's thickness is negative";
        case 3:
            return "a horizon tile's corners are out of range";
        case 4:
            return "a horizon tile's corner is not finite";
        default:
            break;
    }
    if (rd32(l->horizon_list_offsets.at) != 0) return "the horizon lists do not start at 0";
    for (e = 0; e + 1 < l->horizon_list_offsets.count; ++e) {
        const uint32_t a = rd32(l->horizon_list_offsets.at + 4 * e),
                       b = rd32(l->horizon_list_offsets.at + 4 * e + 4);
        if (b < a || b > l->horizon_lists.count)
            return "the horizon lists' offsets decrease or pass their bytes";
        if (l->version_major >= 5 && b > a) { /* a key row of the PVS code less its reference */
            const uint8_t* p = l->horizon_lists.at + a;
            const uint8_t* const end = l->horizon_lists.at + b;
            uint64_t head;
            if (!checked_varint(&p, end, &head)) return "a horizon list's head is damaged";
            switch (rice_head_fault(head, hz_limit(l), (uint64_t)(end - p) * 8)) {
                case 1:
                    return "a horizon list's Rice parameter is above 24";
                case 2:
                    return "a horizon list has more entries than occluders";
                case 3:
                    return "a horizon list's code runs past the list";
                default:
                    break;
            }
        }
    }
    bad = check_horizon_cells(l);
    return bad ? bad : check_horizon_tests(l);
}

/* ---- Part boxes on their object's grid (file 5.1, 'OPBQ'; docs/FORMAT.md, docs/ALGORITHMS.md#object-parts).
 * A part's coordinate on an axis is (B + q) 2^k met with the object's bounds: q a 16-bit step, B = floor(min
 * / 2^k) of the bounds, k the least integer from -100 at which, on every axis, the bounds span at most 65,535
 * steps and floor(min / 2^k), ceil(max / 2^k) are at most 2^24 in size. A valid q keeps B + q within those,
 * so B + q and its product with 2^k are exact floats: every reader decodes the same floats, whatever its
 * rounding, contraction or excess precision. */
typedef struct part_grid {
    float scale, inverse;    /* 2^k, 2^-k */
    float base[3], steps[3]; /* B; ceil(max / 2^k) - B */
} part_grid;

static int part_grid_of(const float bounds[6], part_grid* g) {
    float m = 0.0f, s = 0.0f;
    int k, e, a;
    for (a = 0; a < 3; ++a) {
        if (!isfinite(bounds[a]) || !isfinite(bounds[a + 3]) || !(bounds[a] <= bounds[a + 3])) return 0;
        m = fabsf(bounds[a]) > m ? fabsf(bounds[a]) : m;
        m = fabsf(bounds[a + 3]) > m ? fabsf(bounds[a + 3]) : m;
        s = bounds[a + 3] - bounds[a] > s ? bounds[a + 3] - bounds[a] : s;
    }
    (void)frexpf(m, &e); /* m < 2^e: k = e - 24 keeps the ends within 2^24 steps */
    k = e - 24;
    if (isfinite(s)) {
        (void)frexpf(s, &e); /* s < 2^e: 2^(e - 16) steps of it span at most 2^16 */
        if (e - 16 > k) k = e - 16;
    }
    if (k < -100) k = -100;
    for (; k <= 127; ++k) {
        int ok = 1;
        g->scale = ldexpf(1.0f, k);
        g->inverse = ldexpf(1.0f, -k);
        for (a = 0; a < 3 && ok; ++a) {
            const float lo = floorf(bounds[a] * g->inverse), hi = ceilf(bounds[a + 3] * g->inverse);
            ok = fabsf(lo) <= 16777216.0f && fabsf(hi) <= 16777216.0f && hi - lo <= 65535.0f;
            g->base[a] = lo;
            g->steps[a] = hi - lo;
        }
        if (ok) return 1;
    }
    return 0;
}

/* The part whose steps are q[6] (min x .. max z), as every reader decodes it. */
static void part_decode(const part_grid* g, const float bounds[6], const float q[6], float box[6]) {
    int a;
    for (a = 0; a < 3; ++a) {
        const float lo = (g->base[a] + q[a]) * g->scale, hi = (g->base[a] + q[a + 3]) * g->scale;
        box[a] = lo > bounds[a] ? lo : bounds[a];
        box[a + 3] = hi < bounds[a + 3] ? hi : bounds[a + 3];
    }
}

int pvsr_part_encode(const float bounds[6], const float part[6], uint16_t steps[6], float box[6]) {
    part_grid g;
    float q[6];
    int a;
    if (bounds == NULL || part == NULL || steps == NULL || box == NULL || !part_grid_of(bounds, &g)) return 0;
    for (a = 0; a < 3; ++a)
        if (!(part[a] >= bounds[a] && part[a] <= part[a + 3] && part[a + 3] <= bounds[a + 3])) return 0;
    for (a = 0; a < 3; ++a) {
        q[a] = floorf(part[a] * g.inverse) - g.base[a];
        q[a + 3] = ceilf(part[a + 3] * g.inverse) - g.base[a];
    }
    for (a = 0; a < 6; ++a) steps[a] = (uint16_t)q[a]; /* within [0, steps of the axis]: the part is inside */
    part_decode(&g, bounds, q, box);
    return 1;
}

/* Object o's part e of a 5.1 file's 'OPBQ' on the grid g of its bounds; 0 when its steps pass the bounds'
 * or its box is empty. */
static int quantized_part(const pvsr_level* l, const part_grid* g, const float bounds[6], uint64_t e,
                          float box[6]) {
    const uint8_t* p = l->object_parts.at + 12 * e;
    float q[6];
    int a;
    for (a = 0; a < 6; ++a) q[a] = (float)rd16(p + 2 * a);
    for (a = 0; a < 3; ++a)
        if (q[a] > q[a + 3] || q[a + 3] > g->steps[a]) return 0;
    part_decode(g, bounds, q, box);
    for (a = 0; a < 3; ++a)
        if (!(box[a] <= box[a + 3])) return 0;
    return 1;
}

/* The grid of an object's parts in a 5.1 file (g, from its bounds); 1 for the floats of older files, 0 when
 * bounds have no grid. */
static int parts_grid(const pvsr_level* l, const float bounds[6], part_grid* g) {
    return l->object_parts.item_bytes != 12 || part_grid_of(bounds, g);
}

/* Part e of the file's part boxes (g and bounds: parts_grid's, of its object); 0 where parts_grid() or
 * quantized_part() refuse it. */
static int part_at(const pvsr_level* l, const part_grid* g, const float bounds[6], uint64_t e, float box[6]) {
    int a;
    if (l->object_parts.item_bytes == 12) return quantized_part(l, g, bounds, e, box);
    for (a = 0; a < 6; ++a) box[a] = rdf(l->object_parts.at + 24 * e + 4 * a);
    return 1;
}

/* File version 2.2: the objects' part boxes ('OPOF' u32 offsets, objects + 1, into 'OPBX' boxes of floats);
 * 5.1: 'OPOQ' offsets (2 or 4 bytes) into 'OPBQ' steps on the grid of each object's bounds (above), so that
 * a 5.0 runtime, which knows neither, reads the file without parts. One of the two pairs or none. Offsets
 * from 0, never decreasing, ending at the boxes' count; each box finite with min <= max, inside its object's
 * bounds. */
static const char* check_object_parts(pvsr_level* l) {
    uint64_t o, e;
    const char* bad;
    pvsr_array a;
    const int floats = section(l, PVSR_TAG('O', 'P', 'O', 'F'), &a) ||
                       section(l, PVSR_TAG('O', 'P', 'B', 'X'), &a),
              steps = section(l, PVSR_TAG('O', 'P', 'O', 'Q'), &a) ||
                      section(l, PVSR_TAG('O', 'P', 'B', 'Q'), &a);
    if (floats && steps) return "two kinds of object part boxes";
    if (!floats && !steps) return NULL;
    if (!section(l, steps ? PVSR_TAG('O', 'P', 'O', 'Q') : PVSR_TAG('O', 'P', 'O', 'F'), &a))
        return "object part boxes without their offsets";
    bad = need(l, steps ? PVSR_TAG('O', 'P', 'O', 'Q') : PVSR_TAG('O', 'P', 'O', 'F'), steps ? 0 : 4,
               (uint64_t)l->object_count + 1, 1, &l->object_part_offsets);
    if (!bad)
        bad = steps ? need(l, PVSR_TAG('O', 'P', 'B', 'Q'), 12, UINT64_MAX, 1, &l->object_parts)
                    : need(l, PVSR_TAG('O', 'P', 'B', 'X'), 24, UINT64_MAX, 1, &l->object_parts);
    if (bad) return bad;
    if (index_at(&l->object_part_offsets, 0) != 0 ||
        index_at(&l->object_part_offsets, l->object_count) != l->object_parts.count)
        return "the object parts' offsets do not start at 0 and end at their boxes";
    for (o = 0; o < l->object_count; ++o) {
        const uint32_t first = index_at(&l->object_part_offsets, o),
                       end = index_at(&l->object_part_offsets, o + 1);
        float bounds[6], box[6];
        part_grid g;
        if (end < first || end > l->object_parts.count)
            return "the object parts' offsets decrease or pass their boxes";
        if (first == end) continue;
        pvsr_object_bounds(l, (uint32_t)o, bounds);
        if (!parts_grid(l, bounds, &g)) return "an object with part boxes has no finite bounds";
        for (e = first; e < end; ++e) {
            int k;
            if (!part_at(l, &g, bounds, e, box))
                return "an object part box is empty or passes its object's bounds";
            if (steps) continue; /* inside the bounds by its decoding */
            if (!finite_box(l->object_parts.at + 24 * e)) return "an object part box is not finite";
            for (k = 0; k < 3; ++k)
                if (box[k] > box[k + 3] || !(box[k] >= bounds[k]) || !(box[k + 3] <= bounds[k + 3]))
                    return "an object part box is not inside its object's bounds";
        }
    }
    return NULL;
}

static const char* check_strings(pvsr_level* l) {
    uint64_t i, fields = 0;
    const char* bad = need(l, PVSR_TAG('S', 'T', 'R', 'S'), 1, UINT64_MAX, 1, &l->strings);
    if (bad) return bad;
    if (l->strings.count > 0 && l->strings.at[l->strings.count - 1] != 0) return "the strings are not NUL-terminated";
    for (i = 0; i < l->strings.count; ++i) fields += l->strings.at[i] == 0;
    if (fields % 2 != 0) return "the strings are not key and value pairs";
    return NULL;
}

pvsr_status pvsr_open(pvsr_level* level, const void* data, size_t size, char* message, size_t message_size) {
    static const uint8_t kMagic[8] = {'P', 'V', 'S', 'R', 0x0d, 0x0a, 0x1a, 0x0a};
    const uint8_t* b = (const uint8_t*)data;
    opening o;
    const char *bad, *table_bad, *rows_bad, *row_bad = NULL;
    xxh64_run hash;
    prescan ps;
    uint64_t rows = 0;
    uint8_t depth[PVSR_DEPTH_RING]; /* the chain lengths of the rows just checked */
    const uint16_t probe = 1;
    if (level == NULL) return PVSR_INVALID_ARGUMENT;
    o.l = level;
    o.message = message;
    o.message_size = message_size;
    memset(level, 0, sizeof *level);
    if (data == NULL) return fail(&o, PVSR_INVALID_ARGUMENT, "no bytes (a null pointer)");
    if (*(const uint8_t*)&probe != 1) return fail(&o, PVSR_UNSUPPORTED, "this runtime reads on little-endian machines only");
    if (size < PVSR_HEADER_BYTES || memcmp(b, kMagic, 8) != 0)
        return fail(&o, PVSR_NOT_A_RUNTIME_FILE, "not a pvsbake runtime file (no PVSR magic)");
    level->bytes = b;
    level->size = size;
    level->version_major = rd16(b + 8);
    level->version_minor = rd16(b + 10);
    if (level->version_major > PVSR_VERSION_MAJOR)
        return fail(&o, PVSR_VERSION_TOO_NEW, "a newer major version of the runtime file than this runtime reads");
    if (level->version_major < 1) return fail(&o, PVSR_CORRUPT, "version 0 is not a runtime file version");
    if (level->version_major == 4)
        return fail(
            &o, PVSR_VERSION_TOO_NEW,
            "a 4.x runtime file (a development format whose horizon lists 5.0 codes anew): export it again");
    if (rd32(b + 12) != PVSR_HEADER_BYTES) return fail(&o, PVSR_CORRUPT, "the header's size is wrong");
    if (rd64(b + 16) != (uint64_t)size)
        return fail(&o, PVSR_CORRUPT, "the file's size is not the size its header says (truncated or padded)");
    level->flags = rd32(b + 36);
    level->object_count = rd32(b + 40);
    level->cell_count = rd32(b + 44);
    level->cell_kind = rd32(b + 48);
    /* The checksum, and the rows and big index arrays checked as it passes them (while they are in cache); a
     * damaged file is refused for its checksum first, and then the checks' first failure is told in their
     * usual order. */
    xxh_start(&hash, b + PVSR_CHECKSUMMED_FROM, size - PVSR_CHECKSUMMED_FROM, 0);
    memset(&ps, 0, sizeof ps);
    table_bad = check_table(level);
    rows_bad = table_bad ? NULL : check_row_sections(level);
    if (!table_bad) {
        static const uint32_t kTags[PVSR_PRESCANS] = {PVSR_TAG('C', 'R', 'O', 'W'), PVSR_TAG('M', 'R', 'E', 'F'),
                                                      PVSR_TAG('C', 'G', 'R', 'D'), PVSR_TAG('R', 'L', 'S', 'T')};
        int k;
        for (k = 0; k < PVSR_PRESCANS; ++k)
            if (!section(level, kTags[k], &ps.a[k]) ||
                (ps.a[k].item_bytes != 1 && ps.a[k].item_bytes != 2 && ps.a[k].item_bytes != 4))
                memset(&ps.a[k], 0, sizeof ps.a[k]);
    }
    {
        const uint8_t* const code = !table_bad && !rows_bad ? level->code.at : NULL;
        const uint8_t* until = hash.p;
        while (until < hash.end) {
            until = hash.end - until > PVSR_CHECK_CHUNK ? until + PVSR_CHECK_CHUNK : hash.end;
            xxh_stripes(&hash, until);
            if (table_bad) continue;
            prescan_upto(&ps, hash.p);
            while (code != NULL && hash.p >= code && rows < level->row_count && !row_bad &&
                   row_offset(level, rows + 1) <= (uint64_t)(hash.p - code))
                row_bad = check_row(level, rows++, depth);
        }
    }
    if (xxh_finish(&hash) != rd64(b + 24))
        return fail(&o, PVSR_CORRUPT, "the bytes do not match the file's checksum (damaged)");
    if (level->flags & ~PVSR_FLAG_CONSERVATIVE) return fail(&o, PVSR_CORRUPT, "unknown header flags");
    if (!table_bad) prescan_upto(&ps, hash.end);
    if (!table_bad && !rows_bad) {
        rows_bad = check_row_ends(level, &ps);
        while (!rows_bad && !row_bad && rows < level->row_count) row_bad = check_row(level, rows++, depth);
        if (!rows_bad) rows_bad = row_bad;
    }
    bad = table_bad;
    if (!bad) bad = check_level(level, &ps);
    if (!bad) bad = check_cells(level, &ps);
    if (!bad) bad = rows_bad;
    if (!bad) bad = check_objects(level);
    if (!bad) bad = check_ranked(level, &ps);
    if (!bad) bad = check_polygons(level);
    if (!bad) bad = check_horizon(level);
    if (!bad) bad = check_object_parts(level);
    if (!bad) bad = check_strings(level);
    if (bad) return fail(&o, PVSR_CORRUPT, bad);
    if (message != NULL && message_size > 0) message[0] = '\0';
    return PVSR_OK;
}

const char* pvsr_status_name(pvsr_status status) {
    switch (status) {
        case PVSR_OK: return "ok";
        case PVSR_NOT_A_RUNTIME_FILE: return "not a runtime file";
        case PVSR_VERSION_TOO_NEW: return "version too new";
        case PVSR_CORRUPT: return "corrupt";
        case PVSR_UNSUPPORTED: return "unsupported machine";
        case PVSR_INVALID_ARGUMENT: return "invalid argument";
    }
    return "unknown status";
}

/* ---- Queries */

size_t pvsr_level_bytes(void) {
    return sizeof(pvsr_level);
}

size_t pvsr_culler_bytes(void) {
    return sizeof(pvsr_culler);
}

size_t pvsr_horizon_bytes(void) {
    return sizeof(pvsr_horizon);
}

uint32_t pvsr_cell_count(const pvsr_level* l) {
    return l ? l->cell_count : 0;
}
uint32_t pvsr_object_count(const pvsr_level* l) {
    return l ? l->object_count : 0;
}
uint32_t pvsr_cell_kind(const pvsr_level* l) {
    return l ? l->cell_kind : 0;
}
size_t pvsr_words_per_row(const pvsr_level* l) {
    return l ? ((size_t)l->object_count + 63) / 64 : 0;
}

static int mask_voxel(const pvsr_level* l, int eyes, int64_t x, int64_t y, int64_t z) {
    const pvsr_array* tiles = eyes ? &l->eye_tiles : &l->view_tiles;
    const uint64_t t = (uint64_t)(x >> 5) + (uint64_t)l->tile_dims[0] * ((uint64_t)(y >> 5) + (uint64_t)l->tile_dims[1] * (uint64_t)(z >> 5));
    const uint32_t tile = rd32(tiles->at + 4 * t);
    uint32_t ref;
    if (tile < PVSR_FIRST_BRICK) return tile == PVSR_BRICK_FULL;
    ref = index_at(&l->mask_refs, (uint64_t)(tile - PVSR_FIRST_BRICK) * 64 + (uint64_t)((x >> 3) & 3) +
                                      4 * ((uint64_t)((y >> 3) & 3) + 4 * (uint64_t)((z >> 3) & 3)));
    if (ref < PVSR_FIRST_BRICK) return ref == PVSR_BRICK_FULL;
    return (l->mask_bits.at[(uint64_t)(ref - PVSR_FIRST_BRICK) * 64 + (uint64_t)(z & 7) * 8 + (uint64_t)(y & 7)] >> (x & 7)) & 1;
}

/* Voxels are closed boxes: a point on a face of a set voxel is in (core/cell_set.h VoxelMask::contains). */
static int mask_contains(const pvsr_level* l, int eyes, float x, float y, float z) {
    const float p[3] = {x, y, z};
    int lo[3], hi[3], a, i, j, k;
    for (a = 0; a < 3; ++a) {
        const float rel = (p[a] - l->mask_origin[a]) / l->mask_voxel_m;
        float f;
        if (!(rel >= 0.0f) || rel > (float)l->mask_dims[a]) return 0;
        f = floorf(rel);
        hi[a] = (int)f < l->mask_dims[a] - 1 ? (int)f : l->mask_dims[a] - 1;
        if (rel == f) {
            lo[a] = (int)f - 1 > 0 ? (int)f - 1 : 0;
            if (lo[a] > hi[a]) lo[a] = hi[a];
        } else {
            lo[a] = hi[a];
        }
        if (hi[a] < 0) return 0;
    }
    for (k = lo[2]; k <= hi[2]; ++k)
        for (j = lo[1]; j <= hi[1]; ++j)
            for (i = lo[0]; i <= hi[0]; ++i)
                if (mask_voxel(l, eyes, i, j, k)) return 1;
    return 0;
}

int32_t pvsr_find_cell(const pvsr_level* l, float x, float y, float z) {
    const float p[3] = {x, y, z};
    int idx[3], a;
    uint64_t g;
    int32_t n;
    if (l == NULL || l->cell_count == 0 || !isfinite(x) || !isfinite(y) || !isfinite(z)) return -1;
    if ((l->mask_flags & PVSR_MASK_VIEW) && !mask_contains(l, 0, x, y, z)) return -1;
    for (a = 0; a < 3; ++a) {
        const float rel = (p[a] - l->origin[a]) / l->cell_size_m;
        int f;
        if (!(rel >= 0.0f) || rel > (float)l->dims[a] || l->dims[a] == 0) return -1;
        f = (int)floorf(rel);
        idx[a] = f < l->dims[a] - 1 ? f : l->dims[a] - 1;
    }
    g = (uint64_t)idx[0] + (uint64_t)l->dims[0] * ((uint64_t)idx[1] + (uint64_t)l->dims[1] * (uint64_t)idx[2]);
    if (l->grid_identity) return cell_of_position(l, g);
    n = rdi32(l->grid_to_cell.at + 4 * g);
    if (l->cell_kind == 0) return n;
    while (n >= 0) { /* children come after their parent (checked): this ends */
        const uint8_t* node = l->nodes.at + PVSR_NODE_BYTES * (uint64_t)n;
        const int32_t first = rdi32(node + 12);
        if (first < 0) return rdi32(node + 16);
        n = first + (x >= rdf(node) ? 1 : 0) + (y >= rdf(node + 4) ? 2 : 0) + (z >= rdf(node + 8) ? 4 : 0);
    }
    return -1;
}

int pvsr_in_eye_space(const pvsr_level* l, float x, float y, float z) {
    if (pvsr_find_cell(l, x, y, z) < 0) return 0;
    return !(l->mask_flags & PVSR_MASK_EYES) || mask_contains(l, 1, x, y, z);
}

int pvsr_cell_bounds(const pvsr_level* l, uint32_t cell, float box[6]) {
    int a;
    if (l == NULL || box == NULL || cell >= l->cell_count) return 0;
    if (l->cell_boxes.at != NULL) {
        for (a = 0; a < 6; ++a) box[a] = rdf(l->cell_boxes.at + 24 * (uint64_t)cell + 4 * a);
        return 1;
    }
    {
        const uint32_t g = cell_position(l, cell);
        const uint32_t idx[3] = {g % (uint32_t)l->dims[0], g / (uint32_t)l->dims[0] % (uint32_t)l->dims[1],
                                 g / ((uint32_t)l->dims[0] * (uint32_t)l->dims[1])};
        for (a = 0; a < 3; ++a) {
            box[a] = l->origin[a] + (float)idx[a] * l->cell_size_m;
            box[3 + a] = l->origin[a] + (float)(idx[a] + 1) * l->cell_size_m;
        }
    }
    return 1;
}

/* XORs the rows of the chain in readers into words (ceil(objects / 64) of them). */
static void xor_chain(gap_reader* chain, int n, uint64_t* words) {
    int k;
    uint32_t i;
    for (k = 0; k < n; ++k)
        for (i = gap_next(&chain[k]); i != PVSR_END; i = gap_next(&chain[k])) words[i >> 6] ^= (uint64_t)1 << (i & 63);
}

/* What a walk gives each visible object to: a callback, or a list (counting past its capacity); with a
 * culler, only the objects it does not prove hidden (drawn()). */
typedef struct sink {
    pvsr_visit_fn visit;
    void* user;
    uint32_t* list;
    size_t capacity;
    const pvsr_culler* culler;
    const pvsr_horizon* horizon;
    int cull; /* culler or horizon given */
} sink;

/* Whether the culler, or with `horizon` the horizon, proves the box hidden. */
static int hidden_box(const sink* s, int horizon, const float box[6]) {
    return (s->culler != NULL && pvsr_culler_is_hidden(s->culler, box)) ||
           (horizon && s->horizon != NULL && pvsr_horizon_is_hidden(s->horizon, box));
}

/* 1 when the walk with a culler or horizon gives the object on: an object the bake marks always visible, one
 * without bounds, or one neither proves hidden by its bounds nor, where it has parts, by every part (the
 * horizon only with `horizon`). */
static int drawn(const pvsr_level* l, const sink* s, int horizon, uint32_t object) {
    float bounds[6], box[6];
    uint32_t k, parts;
    uint64_t first;
    part_grid g;
    if ((pvsr_object_flags(l, object) & PVSR_OBJECT_ALWAYS_VISIBLE) != 0) return 1;
    if (s->culler == NULL && !(horizon && s->horizon != NULL)) return 1; /* nothing tests it */
    if (!pvsr_object_bounds(l, object, bounds)) return 1;
    if (hidden_box(s, horizon, bounds)) return 0;
    parts = pvsr_object_part_count(l, object);
    if (parts == 0 || !parts_grid(l, bounds, &g)) return 1;
    first = index_at(&l->object_part_offsets, object);
    for (k = 0; k < parts; ++k)
        if (!part_at(l, &g, bounds, first + k, box) || !hidden_box(s, horizon, box)) return 1;
    return 0;
}

static void hz_code_open(gap_reader* g, const uint8_t* p, const uint8_t* end, uint32_t limit);

/* The objects a cell's frames test with the horizon (file 5.3): whether the next one is `object`, the
 * reader advanced past what comes before it (objects come in increasing order). */
typedef struct tests_reader {
    gap_reader code;
    uint32_t next;
    int on; /* the walk has a horizon and the file the cell's tests: only they meet the horizon */
} tests_reader;

static void tests_open(const pvsr_level* l, uint32_t cell, const sink* s, tests_reader* t) {
    t->on = s->horizon != NULL && l->horizon_test_offsets.at != NULL;
    t->next = 0;
    if (t->on) {
        const uint8_t* tests = l->horizon_tests.at;
        hz_code_open(&t->code, tests + rd32(l->horizon_test_offsets.at + 4 * (uint64_t)cell),
                     tests + rd32(l->horizon_test_offsets.at + 4 * (uint64_t)cell + 4), l->object_count);
        t->next = gap_next(&t->code);
    }
}

static int tested(tests_reader* t, uint32_t object) {
    if (!t->on) return 1;
    while (t->next < object) t->next = gap_next(&t->code); /* PVSR_END ends it */
    return t->next == object;
}

/* Walks the cell's row: gives each visible object to the sink in increasing order; returns how many. With a
 * horizon and the cell's tests (file 5.3), the horizon tests only those objects; the culler tests every one
 * (docs/ALGORITHMS.md#horizon-tests). */
static uint32_t walk(const pvsr_level* l, uint32_t cell, const sink* s) {
    gap_reader chain[PVSR_MAX_CHAIN];
    tests_reader t;
    uint32_t count = 0, i, a, b;
    int n;
    if (l == NULL || cell >= l->cell_count) return 0;
    n = row_chain(l, cell_row(l, cell), chain);
    tests_open(l, cell, s, &t);
#define PVSR_GIVE(object)                                       \
    do {                                                        \
        const uint32_t o_ = (object);                           \
        if (s->cull && !drawn(l, s, tested(&t, o_), o_)) break; \
        if (s->list != NULL) {                                  \
            if (count < s->capacity) s->list[count] = o_;       \
        } else if (s->visit != NULL) {                          \
            s->visit(s->user, o_);                              \
        }                                                       \
        ++count;                                                \
    } while (0)
    if (n == 1) {
        for (i = gap_next(&chain[0]); i != PVSR_END; i = gap_next(&chain[0])) PVSR_GIVE(i);
        return count;
    }
    if (l->object_count <= PVSR_STACK_OBJECTS) {
        /* The chain's rows XORed in a bit set on the stack: branch-light. */
        uint64_t bits[PVSR_STACK_OBJECTS / 64];
        const size_t words = pvsr_words_per_row(l);
        size_t w;
        memset(bits, 0, words * sizeof(uint64_t));
        xor_chain(chain, n, bits);
        for (w = 0; w < words; ++w) {
            uint64_t v;
            for (v = bits[w]; v != 0; v &= v - 1) PVSR_GIVE((uint32_t)(w * 64) + ctz64(v));
        }
        return count;
    }
    /* Past the stack bit set chains hold two rows (checked at open): merge them, an index in both cancels. */
    a = gap_next(&chain[0]);
    b = gap_next(&chain[1]);
    for (;;) {
        if (a < b) {
            PVSR_GIVE(a);
            a = gap_next(&chain[0]);
        } else if (b < a) {
            PVSR_GIVE(b);
            b = gap_next(&chain[1]);
        } else {
            if (a == PVSR_END) return count;
            a = gap_next(&chain[0]);
            b = gap_next(&chain[1]);
        }
    }
#undef PVSR_GIVE
}

uint32_t pvsr_visit_visible(const pvsr_level* l, uint32_t cell, pvsr_visit_fn visit, void* user) {
    return pvsr_visit_drawn(l, cell, NULL, visit, user);
}

uint32_t pvsr_visit_drawn(const pvsr_level* l, uint32_t cell, const pvsr_culler* culler, pvsr_visit_fn visit,
                          void* user) {
    return pvsr_visit_drawn_horizon(l, cell, culler, NULL, visit, user);
}

uint32_t pvsr_visible_count(const pvsr_level* l, uint32_t cell) {
    return pvsr_visit_visible(l, cell, NULL, NULL);
}

uint32_t pvsr_visible_objects(const pvsr_level* l, uint32_t cell, uint32_t* objects, size_t capacity) {
    return pvsr_drawn_objects(l, cell, NULL, objects, capacity);
}

uint32_t pvsr_drawn_objects(const pvsr_level* l, uint32_t cell, const pvsr_culler* culler, uint32_t* objects,
                            size_t capacity) {
    return pvsr_drawn_objects_horizon(l, cell, culler, NULL, objects, capacity);
}

uint32_t pvsr_visit_drawn_horizon(const pvsr_level* l, uint32_t cell, const pvsr_culler* culler,
                                  const pvsr_horizon* horizon, pvsr_visit_fn visit, void* user) {
    sink s;
    s.visit = visit;
    s.user = user;
    s.list = NULL;
    s.capacity = 0;
    s.culler = culler;
    s.horizon = horizon;
    s.cull = culler != NULL || horizon != NULL;
    return walk(l, cell, &s);
}

uint32_t pvsr_drawn_objects_horizon(const pvsr_level* l, uint32_t cell, const pvsr_culler* culler,
                                    const pvsr_horizon* horizon, uint32_t* objects, size_t capacity) {
    static uint32_t none;
    sink s;
    s.visit = NULL;
    s.user = NULL;
    s.list = objects != NULL ? objects : &none; /* a list of no room: counts */
    s.capacity = objects != NULL ? capacity : 0;
    s.culler = culler;
    s.horizon = horizon;
    s.cull = culler != NULL || horizon != NULL;
    return walk(l, cell, &s);
}

uint32_t pvsr_fill_bitset(const pvsr_level* l, uint32_t cell, uint64_t* words, size_t word_count) {
    gap_reader chain[PVSR_MAX_CHAIN];
    uint32_t count = 0;
    size_t w;
    if (l == NULL || words == NULL || cell >= l->cell_count || word_count < pvsr_words_per_row(l)) return 0xffffffffu;
    memset(words, 0, word_count * sizeof(uint64_t));
    xor_chain(chain, row_chain(l, cell_row(l, cell), chain), words);
    for (w = 0; w < pvsr_words_per_row(l); ++w) count += popcount64(words[w]);
    return count;
}

int pvsr_is_visible(const pvsr_level* l, uint32_t cell, uint32_t object) {
    gap_reader chain[PVSR_MAX_CHAIN];
    uint32_t i;
    int in = 0, n, k;
    if (l == NULL || cell >= l->cell_count || object >= l->object_count) return 0;
    n = row_chain(l, cell_row(l, cell), chain);
    for (k = 0; k < n; ++k) { /* in when an odd number of the chain's rows hold it */
        for (i = gap_next(&chain[k]); i < object; i = gap_next(&chain[k])) {
        }
        in ^= i == object;
    }
    return in;
}

const char* pvsr_object_name(const pvsr_level* l, uint32_t object) {
    if (l == NULL || object >= l->object_count) return kEmpty;
    return (const char*)l->names.at + rd32(l->name_offsets.at + 4 * (uint64_t)object);
}

int pvsr_object_bounds(const pvsr_level* l, uint32_t object, float box[6]) {
    int a;
    if (l == NULL || box == NULL || object >= l->object_count) return 0;
    for (a = 0; a < 6; ++a) box[a] = rdf(l->object_boxes.at + 24 * (uint64_t)object + 4 * a);
    return 1;
}

uint32_t pvsr_object_part_count(const pvsr_level* l, uint32_t object) {
    if (l == NULL || object >= l->object_count || l->object_part_offsets.at == NULL) return 0;
    return index_at(&l->object_part_offsets, (uint64_t)object + 1) -
           index_at(&l->object_part_offsets, object);
}

int pvsr_object_part(const pvsr_level* l, uint32_t object, uint32_t part, float box[6]) {
    float bounds[6];
    part_grid g;
    if (box == NULL || part >= pvsr_object_part_count(l, object)) return 0;
    return pvsr_object_bounds(l, object, bounds) && parts_grid(l, bounds, &g) &&
           part_at(l, &g, bounds, (uint64_t)index_at(&l->object_part_offsets, object) + part, box);
}

uint32_t pvsr_object_triangles(const pvsr_level* l, uint32_t object) {
    if (l == NULL || object >= l->object_count) return 0;
    return rd32(l->object_triangles.at + 4 * (uint64_t)object);
}

uint32_t pvsr_object_flags(const pvsr_level* l, uint32_t object) {
    if (l == NULL || object >= l->object_count) return 0;
    return rd32(l->object_flags.at + 4 * (uint64_t)object);
}

uint64_t pvsr_total_triangles(const pvsr_level* l) {
    return l ? l->total_triangles : 0;
}

uint32_t pvsr_occluder_count(const pvsr_level* l, uint32_t cell) {
    if (l == NULL || cell >= l->cell_count || (l->ranked_offsets.at == NULL && l->ranked_counts.at == NULL))
        return 0;
    return ranked_count(l, cell);
}

int pvsr_occluder(const pvsr_level* l, uint32_t cell, uint32_t rank, pvsr_ranked_occluder* out) {
    uint64_t e;
    uint32_t box;
    int a;
    if (out == NULL || rank >= pvsr_occluder_count(l, cell)) return 0;
    e = ranked_first(l, cell) + rank;
    box = ranked_box(l, cell, e);
    if (box == UINT32_MAX) return 0;
    for (a = 0; a < 6; ++a) out->box[a] = rdf(l->occluder_boxes.at + 24 * (uint64_t)box + 4 * a);
    if (l->ranked_measures.at != NULL) {
        const uint8_t* r = l->ranked_measures.at + PVSR_MEASURE_BYTES * e;
        out->score = rdf(r);
        out->solid_angle_sr = rdf(r + 4);
        out->hidden_objects = rdf(r + 8);
        out->hidden_triangle_share = rdf(r + 12);
    } else {
        out->score = out->solid_angle_sr = out->hidden_objects = out->hidden_triangle_share = NAN;
    }
    return 1;
}

uint32_t pvsr_occluder_polygon_count(const pvsr_level* l, uint32_t cell) {
    if (l == NULL || cell >= l->cell_count || l->ranked_polygon_offsets.at == NULL) return 0;
    return rd32(l->ranked_polygon_offsets.at + 4 * (uint64_t)cell + 4) -
           rd32(l->ranked_polygon_offsets.at + 4 * (uint64_t)cell);
}

uint32_t pvsr_occluder_polygon(const pvsr_level* l, uint32_t cell, uint32_t rank, float plane[5],
                               float* corners, uint32_t capacity, uint32_t* place) {
    const uint8_t *r, *p;
    uint32_t n, k;
    int a;
    if (plane == NULL || rank >= pvsr_occluder_polygon_count(l, cell)) return 0;
    r = l->ranked_polygons.at +
        8 * ((uint64_t)rd32(l->ranked_polygon_offsets.at + 4 * (uint64_t)cell) + rank);
    p = l->occluder_polygons.at + PVSR_POLYGON_BYTES * (uint64_t)rd32(r);
    for (a = 0; a < 5; ++a) plane[a] = rdf(p + 4 * a);
    n = rd32(p + 24);
    for (k = 0; k < n && k < capacity && corners != NULL; ++k)
        for (a = 0; a < 3; ++a)
            corners[3 * k + (uint32_t)a] =
                rdf(l->polygon_corners.at + 12 * ((uint64_t)rd32(p + 20) + k) + 4 * a);
    if (place != NULL) *place = rd32(r + 4);
    return n;
}

int pvsr_has_occluder_measures(const pvsr_level* l) {
    return l != NULL && l->ranked_measures.at != NULL;
}

uint32_t pvsr_occluder_boxes(const pvsr_level* l, uint32_t cell, float* boxes, uint32_t capacity) {
    const uint32_t count = pvsr_occluder_count(l, cell);
    uint32_t k, n = count < capacity ? count : capacity;
    if (boxes == NULL) return 0;
    for (k = 0; k < n; ++k) {
        pvsr_ranked_occluder o;
        if (!pvsr_occluder(l, cell, k, &o)) { /* an entry past its palette (a forged file): an empty box */
            o.box[0] = o.box[1] = o.box[2] = INFINITY;
            o.box[3] = o.box[4] = o.box[5] = -INFINITY;
        }
        memcpy(boxes + 6 * (size_t)k, o.box, sizeof o.box);
    }
    return n;
}

int pvsr_is_conservative(const pvsr_level* l) {
    return l != NULL && (l->flags & PVSR_FLAG_CONSERVATIVE) != 0;
}

const char* pvsr_mode_label(const pvsr_level* l) {
    return pvsr_is_conservative(l) ? "conservative" : "aggressive";
}

const char* pvsr_string(const pvsr_level* l, const char* key) {
    uint64_t i = 0;
    if (l == NULL || key == NULL || l->strings.at == NULL) return kEmpty;
    while (i < l->strings.count) {
        const char* k = (const char*)l->strings.at + i;
        const size_t kn = strlen(k); /* NUL-terminated: checked at open */
        const char* v = k + kn + 1;
        if (strcmp(k, key) == 0) return v;
        i += kn + 1 + strlen(v) + 1;
    }
    return kEmpty;
}

/* ---- The culler of moving objects (docs/ALGORITHMS.md#runtime-culler; the conventions and constants of
 * pvsbake/occlusion.h). The HDF5 loader's pvsbake::OcclusionCuller is this code, compiled into the loader
 * (io/loader/occlusion.cpp). */

#define CULL_NEAR_PLANE_M 1e-3f
#define CULL_DEPTH_SLACK 1e-5f
#define CULL_RECT_PAD 1e-5f
#define CULL_MARGIN_M 1e-5
#define CULL_MARGIN_REL 1e-6

/* As std::max and std::min (the loader's culler uses them): no library call in the inner loops. */
static float maxf(float a, float b) {
    return a < b ? b : a;
}
static float minf(float a, float b) {
    return b < a ? b : a;
}
static double maxd(double a, double b) {
    return a < b ? b : a;
}
static float fmaxf3(float a, float b, float c) {
    return maxf(maxf(a, b), c);
}

static int usable_box(const float b[6]) {
    int a;
    for (a = 0; a < 3; ++a)
        if (!isfinite(b[a]) || !isfinite(b[3 + a]) || b[a] > b[3 + a]) return 0;
    return 1;
}

/* The one axis along which b is flat (a panel), -1 for a solid box, -2 when flat along two or three axes. */
static int flat_axis(const float b[6]) {
    int flat = -1, a;
    for (a = 0; a < 3; ++a) {
        if (b[a] != b[3 + a]) continue;
        if (flat != -1) return -2;
        flat = a;
    }
    return flat;
}

/* x + delta rounded up to a float (x - |delta| rounded down for delta < 0): a bound moved inward by |delta|.
 */
static float moved_in(float x, double delta) {
    const double want = (double)x + delta;
    float f = (float)want;
    if (delta > 0.0 && (double)f < want) f = nextafterf(f, INFINITY);
    if (delta < 0.0 && (double)f > want) f = nextafterf(f, -INFINITY);
    return f;
}

/* Largest |coordinate| of the eye and the box: the scale of the margins. */
static double scale_of(const double eye[3], const float b[6]) {
    double m = 0.0;
    int a;
    for (a = 0; a < 3; ++a) {
        m = maxd(m, fabs(eye[a]));
        m = maxd(m, fabs((double)b[a]));
        m = maxd(m, fabs((double)b[3 + a]));
    }
    return m;
}

typedef struct face_box {
    float d_min, d_max, u_lo, u_hi, v_lo, v_hi;
} face_box;

static face_box face_box_of(const float b[6], const float eye[3], int face) {
    const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const float lo = b[a] - eye[a], hi = b[3 + a] - eye[a];
    face_box fb;
    if (face % 2 == 0) {
        fb.d_min = lo;
        fb.d_max = hi;
    } else {
        fb.d_min = -hi;
        fb.d_max = -lo;
    }
    fb.u_lo = b[ua] - eye[ua];
    fb.u_hi = b[3 + ua] - eye[ua];
    fb.v_lo = b[va] - eye[va];
    fb.v_hi = b[3 + va] - eye[va];
    return fb;
}

static int finite_face_box(const face_box* f) {
    return isfinite(f->d_min) && isfinite(f->d_max) && isfinite(f->u_lo) && isfinite(f->u_hi) && isfinite(f->v_lo) &&
           isfinite(f->v_hi);
}

static float dist_to_zero(float lo, float hi) {
    return fmaxf3(0.0f, lo, -hi);
}

static void slab(float lo, float hi, float c, float* enter, float* exit) {
    if (c > 0.0f) {
        *enter = lo / c;
        *exit = hi / c;
    } else if (c < 0.0f) {
        *enter = hi / c;
        *exit = lo / c;
    } else if (lo <= 0.0f && 0.0f <= hi) {
        *enter = -INFINITY;
        *exit = INFINITY;
    } else {
        *enter = INFINITY;
        *exit = -INFINITY;
    }
}

static int clampi(int x, int lo, int hi) {
    return x < lo ? lo : x > hi ? hi : x;
}

static int first_pixel_reaching(const float* g, float lo, int r) {
    int i = clampi((int)floorf((lo + 1.0f) * 0.5f * (float)r), 0, r - 1);
    while (i > 0 && g[i] >= lo) --i;
    while (i < r - 1 && g[i + 1] < lo) ++i;
    return i;
}

static int last_pixel_reaching(const float* g, float hi, int r) {
    int i = clampi((int)floorf((hi + 1.0f) * 0.5f * (float)r), 0, r - 1);
    while (i < r - 1 && g[i + 1] <= hi) ++i;
    while (i > 0 && g[i] > hi) --i;
    return i;
}

static float pad_low(float x) {
    const float y = x - CULL_RECT_PAD * maxf(1.0f, fabsf(x));
    return y > -1.0f ? minf(y, 1.0f) : -1.0f;
}

static float pad_high(float x) {
    const float y = x + CULL_RECT_PAD * maxf(1.0f, fabsf(x));
    return y < 1.0f ? maxf(y, -1.0f) : 1.0f;
}

static int culler_resolution(int resolution) {
    if (resolution <= 0) return 0;
    resolution = (resolution + 1) & ~1;
    return clampi(resolution, PVSR_CULLER_MIN_RESOLUTION, PVSR_CULLER_MAX_RESOLUTION);
}

size_t pvsr_culler_memory_bytes(int resolution) {
    const size_t r = (size_t)culler_resolution(resolution);
    return r == 0 ? 0 : sizeof(float) * (6 * r * r + 7 * (r + 1));
}

int pvsr_culler_init(pvsr_culler* c, int resolution, void* memory, size_t memory_bytes) {
    const int r = culler_resolution(resolution);
    size_t k;
    int f;
    if (c == NULL) return 0;
    memset(c, 0, sizeof *c);
    for (f = 0; f < 6; ++f) {
        c->written[f][0] = 0;
        c->written[f][1] = -1;
        c->written[f][2] = 0;
        c->written[f][3] = -1;
    }
    if (r > 0) {
        float* m = (float*)memory;
        if (memory == NULL || memory_bytes < pvsr_culler_memory_bytes(r)) return 0; /* ok stays 0: culls nothing */
        c->depth = m;
        m += 6 * (size_t)r * (size_t)r;
        c->grid = m;
        m += r + 1;
        c->col_enter = m;
        m += r + 1;
        c->col_exit = m;
        m += r + 1;
        c->row_enter = m;
        m += r + 1;
        c->row_exit = m;
        m += r + 1;
        c->corner_prev = m;
        m += r + 1;
        c->corner_cur = m;
        for (k = 0; k <= (size_t)r; ++k) c->grid[k] = (float)(-1.0 + 2.0 * (double)k / (double)r);
        for (k = 0; k < 6 * (size_t)r * (size_t)r; ++k) c->depth[k] = INFINITY;
    }
    c->resolution = r;
    c->ok = 1;
    return 1;
}

static void build_frustum(const pvsr_culler* c, const float b[6], double delta, int flat,
                          pvsr_culler_frustum* fr) {
    const double* e = c->eye_d;
    double lo[3], hi[3];
    int below[3], above[3], a, k3, si, sj;
    fr->planes = 0;
    fr->usable = 1;
    for (a = 0; a < 3; ++a) {
        const double shrink = a == flat ? 0.0 : delta;
        lo[a] = (double)b[a] + shrink - e[a];
        hi[a] = (double)b[3 + a] - shrink - e[a];
        fr->usable = fr->usable && (a == flat ? lo[a] == hi[a] && lo[a] != 0.0 : lo[a] < hi[a]);
        below[a] = 0.0 < lo[a];
        above[a] = hi[a] < 0.0;
        fr->lo[a] = below[a] ? lo[a] : -INFINITY;
        fr->hi[a] = above[a] ? hi[a] : INFINITY;
    }
    if (!fr->usable) return;
    for (k3 = 0; k3 < 3 && fr->usable; ++k3) {
        const int i = (k3 + 1) % 3, j = (k3 + 2) % 3;
        for (si = 0; si < 2; ++si) {
            for (sj = 0; sj < 2; ++sj) {
                const int front_i = si == 0 ? below[i] : above[i];
                const int front_j = sj == 0 ? below[j] : above[j];
                double pi, pj, ni, nj, side, *n;
                if (front_i == front_j) continue;
                pi = si == 0 ? lo[i] : hi[i];
                pj = sj == 0 ? lo[j] : hi[j];
                ni = -pj;
                nj = pi;
                side = ni * 0.5 * (lo[i] + hi[i]) + nj * 0.5 * (lo[j] + hi[j]);
                if (!(side != 0.0) || fr->planes == 6) {
                    fr->usable = 0;
                    break;
                }
                if (side < 0.0) {
                    ni = -ni;
                    nj = -nj;
                }
                n = fr->n[fr->planes];
                n[k3] = 0.0;
                n[i] = ni;
                n[j] = nj;
                fr->w[fr->planes] = 0.0;
                ++fr->planes;
            }
            if (!fr->usable) break;
        }
    }
}

static int vertex_lo(float x, int r) {
    const int v = (int)floorf((maxf(x, -1.0f) + 1.0f) * 0.5f * (float)r) - 1;
    return v > 0 ? v : 0;
}

static int vertex_hi(float x, int r) {
    const int v = (int)ceilf((minf(x, 1.0f) + 1.0f) * 0.5f * (float)r) + 1;
    return v < r ? v : r;
}

static float corner_pixel(const float* p, const float* c, int i) {
    const float a = p[i] > p[i + 1] ? p[i] : p[i + 1];
    const float b = c[i] > c[i + 1] ? c[i] : c[i + 1];
    return a > b ? a : b;
}

static void rasterize(pvsr_culler* c, const float b[6], int flat) {
    const int r = c->resolution;
    const float* g = c->grid;
    const float room = flat >= 0 ? 1.0f : 1.0f + CULL_DEPTH_SLACK; /* a panel's plane is one depth */
    int face;
    for (face = 0; face < 6; ++face) {
        const face_box fb = face_box_of(b, c->eye, face);
        float d_lo, u0, u1, v0, v1, *face_depth;
        int iv0, iv1, jv0, jv1, iv, jv;
        int* w;
        if (!finite_face_box(&fb)) return;
        d_lo = maxf(fb.d_min, CULL_NEAR_PLANE_M);
        if (flat == face / 2 ? !(d_lo <= fb.d_max) : !(d_lo < fb.d_max)) continue;
        u0 = fb.u_lo >= 0.0f ? fb.u_lo / fb.d_max : fb.u_lo / d_lo;
        u1 = fb.u_hi >= 0.0f ? fb.u_hi / d_lo : fb.u_hi / fb.d_max;
        v0 = fb.v_lo >= 0.0f ? fb.v_lo / fb.d_max : fb.v_lo / d_lo;
        v1 = fb.v_hi >= 0.0f ? fb.v_hi / d_lo : fb.v_hi / fb.d_max;
        if (u0 > 1.0f || u1 < -1.0f || v0 > 1.0f || v1 < -1.0f) continue;
        iv0 = vertex_lo(u0, r);
        iv1 = vertex_hi(u1, r);
        jv0 = vertex_lo(v0, r);
        jv1 = vertex_hi(v1, r);
        if (iv1 - iv0 < 1 || jv1 - jv0 < 1) continue;
        for (iv = iv0; iv <= iv1; ++iv) slab(fb.u_lo, fb.u_hi, g[iv], &c->col_enter[iv], &c->col_exit[iv]);
        for (jv = jv0; jv <= jv1; ++jv) slab(fb.v_lo, fb.v_hi, g[jv], &c->row_enter[jv], &c->row_exit[jv]);
        face_depth = c->depth + (size_t)face * (size_t)r * (size_t)r;
        w = c->written[face];
        for (jv = jv0; jv <= jv1; ++jv) {
            const float re = maxf(d_lo, c->row_enter[jv]), rx = minf(fb.d_max, c->row_exit[jv]);
            float* swap;
            for (iv = iv0; iv <= iv1; ++iv) {
                const float enter = maxf(re, c->col_enter[iv]);
                const float exit = minf(rx, c->col_exit[iv]);
                const float hit_depth = enter * (1.0f + CULL_DEPTH_SLACK);
                c->corner_cur[iv] = exit >= enter * room ? hit_depth : INFINITY;
            }
            if (jv > jv0) {
                float* const row = face_depth + (size_t)(jv - 1) * (size_t)r;
                int i, first = iv0, last = iv1 - 1;
                for (i = iv0; i < iv1; ++i) {
                    const float d = corner_pixel(c->corner_prev, c->corner_cur, i);
                    row[i] = d < row[i] ? d : row[i];
                }
                while (first <= last && !(corner_pixel(c->corner_prev, c->corner_cur, first) < INFINITY)) ++first;
                while (last >= first && !(corner_pixel(c->corner_prev, c->corner_cur, last) < INFINITY)) --last;
                if (first <= last) {
                    if (w[0] > w[1]) {
                        w[0] = first;
                        w[1] = last;
                        w[2] = jv - 1;
                        w[3] = jv - 1;
                    } else {
                        w[0] = w[0] < first ? w[0] : first;
                        w[1] = w[1] > last ? w[1] : last;
                        w[2] = w[2] < jv - 1 ? w[2] : jv - 1;
                        w[3] = w[3] > jv - 1 ? w[3] : jv - 1;
                    }
                }
            }
            swap = c->corner_prev;
            c->corner_prev = c->corner_cur;
            c->corner_cur = swap;
        }
    }
}

static int inside_shadow(const pvsr_culler_frustum* fr, const double q_min[3], const double q_max[3]) {
    int a, p;
    for (a = 0; a < 3; ++a)
        if (!(q_min[a] >= fr->lo[a] && q_max[a] <= fr->hi[a])) return 0;
    for (p = 0; p < fr->planes; ++p) {
        const double* n = fr->n[p];
        double s = 0.0;
        for (a = 0; a < 3; ++a) s += n[a] * (n[a] >= 0.0 ? q_min[a] : q_max[a]);
        if (!(s > fr->w[p])) return 0;
    }
    return 1;
}

static int hidden_by_shadow_frusta(const pvsr_culler* c, const float box[6]) {
    double delta, q_min[3], q_max[3];
    size_t k;
    int a;
    if (!c->eye_ok || c->frustum_count == 0 || !usable_box(box)) return 0;
    delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale_of(c->eye_d, box);
    for (a = 0; a < 3; ++a) {
        q_min[a] = (double)box[a] - delta - c->eye_d[a];
        q_max[a] = (double)box[3 + a] + delta - c->eye_d[a];
    }
    for (k = 0; k < c->frustum_count; ++k)
        if (c->frusta[k].usable && inside_shadow(&c->frusta[k], q_min, q_max)) return 1;
    return 0;
}

static int hidden_by_depth_cube(const pvsr_culler* c, const float box[6]) {
    const int r = c->resolution;
    int near_eye = 1, any_face = 0, a, face;
    if (!c->eye_ok || r == 0 || c->used == 0 || !usable_box(box)) return 0;
    for (a = 0; a < 3; ++a)
        near_eye = near_eye && box[a] - c->eye[a] <= CULL_NEAR_PLANE_M && box[3 + a] - c->eye[a] >= -CULL_NEAR_PLANE_M;
    if (near_eye) return 0;
    for (face = 0; face < 6; ++face) {
        const face_box fb = face_box_of(box, c->eye, face);
        float lower, u0, u1, v0, v1, limit;
        int i0, i1, j0, j1, i, j;
        const int* w = c->written[face];
        const float* face_depth;
        if (!finite_face_box(&fb)) return 0;
        lower = maxf(fmaxf3(fb.d_min, dist_to_zero(fb.u_lo, fb.u_hi), dist_to_zero(fb.v_lo, fb.v_hi)), CULL_NEAR_PLANE_M);
        if (lower > fb.d_max * (1.0f + CULL_DEPTH_SLACK)) continue;
        lower = minf(lower, fb.d_max);
        any_face = 1;
        u0 = fb.u_lo >= 0.0f ? fb.u_lo / fb.d_max : fb.u_lo / lower;
        u1 = fb.u_hi >= 0.0f ? fb.u_hi / lower : fb.u_hi / fb.d_max;
        v0 = fb.v_lo >= 0.0f ? fb.v_lo / fb.d_max : fb.v_lo / lower;
        v1 = fb.v_hi >= 0.0f ? fb.v_hi / lower : fb.v_hi / fb.d_max;
        i0 = first_pixel_reaching(c->grid, pad_low(u0), r);
        i1 = last_pixel_reaching(c->grid, pad_high(u1), r);
        j0 = first_pixel_reaching(c->grid, pad_low(v0), r);
        j1 = last_pixel_reaching(c->grid, pad_high(v1), r);
        if (i0 > i1 || j0 > j1) continue;
        if (i0 < w[0] || i1 > w[1] || j0 < w[2] || j1 > w[3]) return 0;
        limit = lower * (1.0f - CULL_DEPTH_SLACK);
        face_depth = c->depth + (size_t)face * (size_t)r * (size_t)r;
        for (j = j0; j <= j1; ++j) {
            const float* const row = face_depth + (size_t)j * (size_t)r;
            for (i = i0; i <= i1; ++i)
                if (!(row[i] < limit)) return 0;
        }
    }
    return any_face;
}

/* ---- Exact fusion of the occluders' faces (docs/ALGORITHMS.md#runtime-faces): the box is cut into
 * fragments, each a sub-box with a convex polygon of directions, until every fragment lies beyond a face in
 * directions the face covers (hidden) or one fragment has passed every face (visible). Directions are
 * central projections along one axis p on which the whole box lies ahead of the eye: u = x[U] / d,
 * v = x[V] / d with d = sign * x[p] > 0 (everything relative to the eye). */
#define FUSE_MAX_VERTS 12     /* of a fragment's polygon; more: give up (visible) */
#define FUSE_MAX_FACES 96     /* faces a box is tested against (the nearest first), polygons among them */
#define FUSE_MAX_FRAGMENTS 32 /* fragments pending; more: give up (visible) */
#define FUSE_EPS 1e-12        /* relative: a covered region shrunk, a box's directions widened */
#define FUSE_GROW_REL 1e-9    /* a face grows by this times (1 + the largest |coordinate|), metres */
#define FUSE_PROJ_VERTS \
    (PVSR_POLYGON_MAX_CORNERS + 1)            /* a polygon's cross-section clipped at the near plane */
#define FUSE_POLY_VERTS (2 * FUSE_PROJ_VERTS) /* two such projections intersected */
#define FUSE_POOL (6 * FUSE_MAX_FACES + FUSE_POLY_VERTS * PVSR_CULLER_MAX_POLYGONS) /* projected vertices */

typedef struct fuse_poly {
    int n;
    double x[FUSE_MAX_VERTS], y[FUSE_MAX_VERTS];
} fuse_poly;

/* A face or polygon occluder in the test's frame. The part of a box beyond it is, along `axis`, where the
 * coordinate is at least (`above`) or at most its cut: a face's plane moved away by delta, or, for a
 * polygon, the least coordinate there at which every point of the box's cross-section has n.x >= w. */
typedef struct fuse_face {
    const double *x, *y; /* its projection (counter-clockwise), in the test's vertex pool */
    double lo[2], hi[2]; /* that polygon's bounds */
    double plane, delta; /* a face */
    double n[3], w;      /* a polygon: n.x >= w (relative) lies beyond its slab and margin */
    int count, axis, above, poly;
} fuse_face;

typedef struct fuse_fragment {
    double b[6]; /* relative to the eye */
    fuse_poly r;
    int next; /* the first face not yet applied */
} fuse_fragment;

typedef struct fuse_frame {
    int p, u, v;
    double sign;
} fuse_frame;

static double widen(double x, int up) {
    const double m = FUSE_EPS * (1.0 + fabs(x));
    return up ? x + m : x - m;
}

/* Keeps the part of the polygon (ix, iy, n) where a * x + b * y <= w, into (ox, oy); its vertex count, or -1
 * when it would have more than cap. */
static int clip_arrays(const double* ix, const double* iy, int n, double a, double b, double w, double* ox,
                       double* oy, int cap) {
    int i, m = 0;
    for (i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        const double si = a * ix[i] + b * iy[i] - w, sj = a * ix[j] + b * iy[j] - w;
        if (si <= 0.0) {
            if (m == cap) return -1;
            ox[m] = ix[i];
            oy[m++] = iy[i];
        }
        if ((si < 0.0 && sj > 0.0) || (si > 0.0 && sj < 0.0)) {
            const double t = si / (si - sj);
            if (m == cap) return -1;
            ox[m] = ix[i] + t * (ix[j] - ix[i]);
            oy[m++] = iy[i] + t * (iy[j] - iy[i]);
        }
    }
    return m;
}

/* Keeps the part of `in` where a * x + b * y <= w; 0 when the result would have too many vertices. */
static int clip_poly(const fuse_poly* in, double a, double b, double w, fuse_poly* out) {
    out->n = clip_arrays(in->x, in->y, in->n, a, b, w, out->x, out->y, FUSE_MAX_VERTS);
    if (out->n >= 0) return 1;
    out->n = 0;
    return 0;
}

static void poly_bounds(const double* x, const double* y, int n, double lo[2], double hi[2]) {
    int i;
    lo[0] = hi[0] = x[0];
    lo[1] = hi[1] = y[0];
    for (i = 1; i < n; ++i) {
        lo[0] = x[i] < lo[0] ? x[i] : lo[0];
        hi[0] = x[i] > hi[0] ? x[i] : hi[0];
        lo[1] = y[i] < lo[1] ? y[i] : lo[1];
        hi[1] = y[i] > hi[1] ? y[i] : hi[1];
    }
}

/* The bounds of the directions of box b (relative, all of it at d >= its near side > 0), widened. */
static void box_directions(const fuse_frame* f, const double b[6], double lo[2], double hi[2]) {
    const double d0 = f->sign > 0.0 ? b[f->p] : -b[3 + f->p], d1 = f->sign > 0.0 ? b[3 + f->p] : -b[f->p];
    const int ax[2] = {f->u, f->v};
    int k;
    for (k = 0; k < 2; ++k) {
        const double l = b[ax[k]], h = b[3 + ax[k]];
        lo[k] = widen(l >= 0.0 ? l / d1 : l / d0, 0);
        hi[k] = widen(h >= 0.0 ? h / d0 : h / d1, 1);
    }
}

/* r clipped to the rectangle [lo, hi]: 1, 0 when empty, -1 when a polygon would have too many vertices. */
static int clip_to_rect(fuse_poly* r, const double lo[2], const double hi[2]) {
    const double a[4] = {-1.0, 1.0, 0.0, 0.0}, b[4] = {0.0, 0.0, -1.0, 1.0};
    const double w[4] = {-lo[0], hi[0], -lo[1], hi[1]};
    double plo[2], phi[2];
    int k;
    fuse_poly t;
    poly_bounds(r->x, r->y, r->n, plo, phi);
    for (k = 0; k < 4 && r->n >= 3; ++k) {
        const int cuts = k == 0   ? plo[0] < lo[0]
                         : k == 1 ? phi[0] > hi[0]
                         : k == 2 ? plo[1] < lo[1]
                                  : phi[1] > hi[1];
        if (!cuts) continue;
        if (!clip_poly(r, a[k], b[k], w[k], &t)) return -1;
        *r = t;
    }
    return r->n >= 3;
}

/* Projects a convex polygon of n <= PVSR_POLYGON_MAX_CORNERS points (relative to the eye) in frame f: its
 * part at d >= the near plane, counter-clockwise, into x, y (FUSE_PROJ_VERTS room); its vertex count, or 0
 * when nothing or a degenerate polygon is left. */
static int project_points(const fuse_frame* f, const double (*c)[3], int n, double* x, double* y) {
    const double near_d = (double)CULL_NEAR_PLANE_M;
    double d[FUSE_PROJ_VERTS], u[FUSE_PROJ_VERTS], v[FUSE_PROJ_VERTS], area = 0.0;
    int i, m = 0;
    for (i = 0; i < n; ++i) { /* clipped to d >= near */
        const int j = (i + 1) % n;
        const double di = f->sign * c[i][f->p], dj = f->sign * c[j][f->p];
        if (di >= near_d) {
            d[m] = di;
            u[m] = c[i][f->u];
            v[m++] = c[i][f->v];
        }
        if ((di < near_d && dj > near_d) || (di > near_d && dj < near_d)) {
            const double t = (near_d - di) / (dj - di);
            d[m] = near_d;
            u[m] = c[i][f->u] + t * (c[j][f->u] - c[i][f->u]);
            v[m++] = c[i][f->v] + t * (c[j][f->v] - c[i][f->v]);
        }
    }
    if (m < 3) return 0;
    for (i = 0; i < m; ++i) {
        const double inv = 1.0 / d[i];
        x[i] = u[i] * inv;
        y[i] = v[i] * inv;
    }
    for (i = 0; i < m; ++i) {
        const int j = (i + 1) % m;
        area += x[i] * y[j] - x[j] * y[i];
    }
    if (!(area != 0.0) || !isfinite(area)) return 0;
    if (area < 0.0) {
        for (i = 0; i < m / 2; ++i) {
            double t = x[i];
            x[i] = x[m - 1 - i];
            x[m - 1 - i] = t;
            t = y[i];
            y[i] = y[m - 1 - i];
            y[m - 1 - i] = t;
        }
    }
    return m;
}

/* Projects a face (relative to the eye) in frame f into the pool at x, y. */
static int project_face(const fuse_frame* f, const pvsr_culler_face* face, const double e[3], double* x,
                        double* y, fuse_face* out) {
    const int a = face->axis, a1 = (a + 1) % 3, a2 = (a + 2) % 3;
    double c[4][3];
    int i;
    for (i = 0; i < 4; ++i) {
        c[i][a] = face->plane - e[a];
        c[i][a1] = (i == 1 || i == 2 ? face->hi[0] : face->lo[0]) - e[a1];
        c[i][a2] = (i >= 2 ? face->hi[1] : face->lo[1]) - e[a2];
    }
    out->count = project_points(f, (const double(*)[3])c, 4, x, y);
    if (out->count == 0) return 0;
    out->x = x;
    out->y = y;
    poly_bounds(x, y, out->count, out->lo, out->hi);
    out->axis = a;
    out->above = face->above;
    out->plane = face->plane - e[a];
    out->delta = face->delta;
    out->poly = 0;
    return 1;
}

/* Projects a polygon occluder in frame f into the pool at x, y (FUSE_POLY_VERTS room): the directions whose
 * segments cross both planes of its slab inside its prism, the projections of the two cross-sections
 * intersected (docs/ALGORITHMS.md#runtime-polygons). */
static int project_polygon(const fuse_frame* f, const pvsr_culler_polygon* pg, double* x, double* y,
                           fuse_face* out) {
    double s[2][PVSR_POLYGON_MAX_CORNERS][3], px[2][FUSE_PROJ_VERTS], py[2][FUSE_PROJ_VERTS];
    double cx[2][FUSE_POLY_VERTS], cy[2][FUSE_POLY_VERTS];
    int n[2], h, i, k, a, m, cur = 0;
    for (h = 0; h < 2; ++h) {
        const double w = h == 0 ? pg->near_w : pg->far_w;
        for (i = 0; i < pg->count; ++i) {
            const double up = w - (pg->n[0] * pg->c[i][0] + pg->n[1] * pg->c[i][1] + pg->n[2] * pg->c[i][2]);
            for (a = 0; a < 3; ++a) s[h][i][a] = pg->c[i][a] + up * pg->n[a];
        }
        n[h] = project_points(f, (const double(*)[3])s[h], pg->count, px[h], py[h]);
        if (n[h] == 0) return 0;
    }
    m = n[0];
    memcpy(cx[0], px[0], (size_t)m * sizeof(double));
    memcpy(cy[0], py[0], (size_t)m * sizeof(double));
    for (k = 0; k < n[1] && m >= 3; ++k) { /* left of every edge of the far projection */
        const int k1 = (k + 1) % n[1];
        const double dx = px[1][k1] - px[1][k], dy = py[1][k1] - py[1][k];
        m = clip_arrays(cx[cur], cy[cur], m, dy, -dx, dy * px[1][k] - dx * py[1][k], cx[1 - cur], cy[1 - cur],
                        FUSE_POLY_VERTS);
        cur = 1 - cur;
    }
    if (m < 3) return 0;
    memcpy(x, cx[cur], (size_t)m * sizeof(double));
    memcpy(y, cy[cur], (size_t)m * sizeof(double));
    out->x = x;
    out->y = y;
    out->count = m;
    poly_bounds(x, y, m, out->lo, out->hi);
    memcpy(out->n, pg->n, sizeof out->n);
    out->w = pg->far_w + pg->delta;
    out->axis = pg->axis;
    out->above = pg->n[pg->axis] > 0.0;
    out->poly = 1;
    return 1;
}

/* The part of box b beyond face t: along *ax the coordinates at least *cut (t->above) or at most it; 0 when
 * no part of b lies beyond. */
static int beyond_part(const fuse_face* t, const double b[6], int* ax, double* cut) {
    const int a = t->axis;
    *ax = a;
    if (!t->poly) {
        *cut = t->above ? t->plane + t->delta : t->plane - t->delta;
    } else { /* n.x >= w over the cross-section: n[a] x[a] >= w - (the least of the other two terms) */
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        const double m1 = t->n[a1] > 0.0 ? t->n[a1] * b[a1] : t->n[a1] * b[3 + a1];
        const double m2 = t->n[a2] > 0.0 ? t->n[a2] * b[a2] : t->n[a2] * b[3 + a2];
        *cut = widen((t->w - m1 - m2) / t->n[a], t->above);
    }
    return t->above ? b[3 + a] > *cut : b[a] < *cut;
}

static int push_fragment(fuse_fragment* stack, int* top, const double b[6], const fuse_poly* r, int next) {
    if (*top == FUSE_MAX_FRAGMENTS) return 0;
    memcpy(stack[*top].b, b, sizeof stack[*top].b);
    stack[*top].r = *r;
    stack[(*top)++].next = next;
    return 1;
}

/* Pushes the parts of r outside the face's polygon, shrunk by FUSE_EPS (their union covers r less the
 * shrunk polygon); 0 when the stack or a polygon overflows. */
static int push_outside(fuse_fragment* stack, int* top, const double b[6], const fuse_poly* r,
                        const fuse_face* q, int next) {
    fuse_poly cur = *r, piece, rest;
    int k, i;
    for (k = 0; k < q->count; ++k) {
        const int k1 = (k + 1) % q->count;
        const double nx = -(q->y[k1] - q->y[k]), ny = q->x[k1] - q->x[k]; /* inward: left of the edge */
        const double w = nx * q->x[k] + ny * q->y[k];
        const double eps = FUSE_EPS * (fabs(nx) + fabs(ny)) * (1.0 + fabs(q->x[k]) + fabs(q->y[k]));
        int any_out = 0, any_in = 0;
        for (i = 0; i < cur.n; ++i) {
            const double s = nx * cur.x[i] + ny * cur.y[i] - w;
            any_out = any_out || !(s >= eps); /* a NaN counts as outside: kept, never hidden */
            any_in = any_in || s > eps;
        }
        if (!any_out) continue;
        if (!any_in) return push_fragment(stack, top, b, &cur, next);
        if (!clip_poly(&cur, nx, ny, w + eps, &piece) || !clip_poly(&cur, -nx, -ny, -(w + eps), &rest))
            return 0;
        if (piece.n >= 3 && !push_fragment(stack, top, b, &piece, next)) return 0;
        if (rest.n < 3) return 1;
        cur = rest;
    }
    return 1;
}

/* 1 when the segment from the eye to point x (relative) crosses a face (beyond its plane, inside its
 * rectangle) or a polygon (its slab, entering and leaving inside its prism): a point nothing hides proves
 * the box it belongs to visible, before any projection. */
static int point_behind_a_face(const pvsr_culler* c, const double x[3]) {
    size_t k;
    int i;
    for (k = 0; k < c->face_count; ++k) { /* the crossing p x[a1] / x[a], p x[a2] / x[a], times |x[a]| */
        const pvsr_culler_face* f = &c->faces[k];
        const double p = f->rel_plane, xa = x[f->axis];
        double m, u1, u2;
        if (f->above ? !(xa > p) : !(xa < p)) continue;
        m = f->above ? xa : -xa; /* p and x[a] have one sign: the eye is off the plane, x beyond it */
        u1 = (f->above ? p : -p) * x[f->axis1];
        u2 = (f->above ? p : -p) * x[f->axis2];
        if (u1 >= f->rel_lo[0] * m && u1 <= f->rel_hi[0] * m && u2 >= f->rel_lo[1] * m &&
            u2 <= f->rel_hi[1] * m)
            return 1;
    }
    for (k = 0; k < c->polygon_count; ++k) {
        const pvsr_culler_polygon* pg = &c->polygons[k];
        const double s = pg->n[0] * x[0] + pg->n[1] * x[1] + pg->n[2] * x[2];
        double t0, t1;
        if (!(s > pg->far_w)) continue;
        t0 = pg->near_w / s; /* the segment t * x meets the slab's planes at t0 and t1 */
        t1 = pg->far_w / s;
        for (i = 0; i < pg->count; ++i) {
            const double mx = pg->m[i][0] * x[0] + pg->m[i][1] * x[1] + pg->m[i][2] * x[2];
            if (!(t0 * mx >= pg->k[i]) || !(t1 * mx >= pg->k[i])) break;
        }
        if (i == pg->count) return 1;
    }
    return 0;
}

static int hidden_by_faces(const pvsr_culler* c, const float box[6]) {
    const double near_d = (double)CULL_NEAR_PLANE_M;
    fuse_face faces[FUSE_MAX_FACES];
    fuse_fragment stack[FUSE_MAX_FRAGMENTS];
    double pool_x[FUSE_POOL], pool_y[FUSE_POOL];
    fuse_frame f;
    double delta, q[6], best = near_d, lo[2], hi[2], cut;
    int a, nf = 0, top = 0, ax, used = 0;
    size_t k;
    fuse_poly r;
    if (!c->eye_ok || c->face_count + c->polygon_count == 0 || !usable_box(box)) return 0;
    delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale_of(c->eye_d, box);
    f.p = -1;
    f.sign = 1.0;
    for (a = 0; a < 3; ++a) {
        q[a] = (double)box[a] - delta - c->eye_d[a];
        q[3 + a] = (double)box[3 + a] + delta - c->eye_d[a];
    }
    for (a = 0; a < 3; ++a) { /* the axis along which the box lies farthest ahead of the eye */
        if (q[a] > best) {
            best = q[a];
            f.p = a;
            f.sign = 1.0;
        }
        if (-q[3 + a] > best) {
            best = -q[3 + a];
            f.p = a;
            f.sign = -1.0;
        }
    }
    if (f.p < 0) return 0;
    for (a = 0; a < 8; ++a) { /* the corners (classify tried the centre): one nothing hides shows the box */
        double x[3];
        int b;
        for (b = 0; b < 3; ++b) x[b] = (a >> b & 1) ? q[3 + b] : q[b];
        if (!point_behind_a_face(c, x)) return 0;
    }
    f.u = (f.p + 1) % 3;
    f.v = (f.p + 2) % 3;
    box_directions(&f, q, lo, hi);
    for (k = 0; k < c->face_count + c->polygon_count && nf < FUSE_MAX_FACES; ++k) {
        fuse_face* ff = &faces[nf];
        const int is_poly = k >= c->face_count;
        if (!is_poly) {
            const pvsr_culler_face* face = &c->faces[k];
            const float* db = c->face_directions[2 * f.p + (f.sign < 0.0)][k];
            if ((double)db[2] < lo[0] || (double)db[0] > hi[0] || (double)db[3] < lo[1] ||
                (double)db[1] > hi[1])
                continue; /* its projection misses the box's directions: the check below would skip it */
            ff->poly = 0;
            ff->axis = face->axis;
            ff->above = face->above;
            ff->plane = face->plane - c->eye_d[face->axis];
            ff->delta = face->delta;
            if (!beyond_part(ff, q, &ax, &cut)) continue; /* nothing of the box lies beyond it */
            if (!project_face(&f, face, c->eye_d, pool_x + used, pool_y + used, ff)) continue;
        } else {
            const pvsr_culler_polygon* pg = &c->polygons[k - c->face_count];
            ff->poly = 1;
            ff->axis = pg->axis;
            ff->above = pg->n[pg->axis] > 0.0;
            memcpy(ff->n, pg->n, sizeof ff->n);
            ff->w = pg->far_w + pg->delta;
            if (!beyond_part(ff, q, &ax, &cut)) continue;
            if (FUSE_POOL - used < FUSE_POLY_VERTS) break;
            if (!project_polygon(&f, pg, pool_x + used, pool_y + used, ff)) continue;
        }
        if (ff->hi[0] < lo[0] || ff->lo[0] > hi[0] || ff->hi[1] < lo[1] || ff->lo[1] > hi[1]) continue;
        used += ff->count;
        ++nf;
    }
    if (nf == 0) return 0;
    r.n = 4;
    r.x[0] = lo[0];
    r.y[0] = lo[1];
    r.x[1] = hi[0];
    r.y[1] = lo[1];
    r.x[2] = hi[0];
    r.y[2] = hi[1];
    r.x[3] = lo[0];
    r.y[3] = hi[1];
    push_fragment(stack, &top, q, &r, 0);
    while (top > 0) {
        const fuse_fragment g = stack[--top];
        double plo[2], phi[2], near_part[6], far_part[6], blo[2], bhi[2];
        const fuse_face* ff = NULL;
        int i = g.next, ok;
        fuse_poly rn, rf;
        poly_bounds(g.r.x, g.r.y, g.r.n, plo, phi);
        for (; i < nf; ++i) { /* the next face that could hide part of this fragment */
            const fuse_face* t = &faces[i];
            if (t->hi[0] < plo[0] || t->lo[0] > phi[0] || t->hi[1] < plo[1] || t->lo[1] > phi[1]) continue;
            if (!beyond_part(t, g.b, &ax, &cut)) continue;
            ff = t;
            break;
        }
        if (ff == NULL) return 0; /* a fragment nothing hides: visible */
        memcpy(near_part, g.b, sizeof near_part);
        memcpy(far_part, g.b, sizeof far_part);
        if (ff->above) {
            near_part[3 + ax] = near_part[3 + ax] < cut ? near_part[3 + ax] : cut;
            far_part[ax] = far_part[ax] > cut ? far_part[ax] : cut;
        } else {
            near_part[ax] = near_part[ax] > cut ? near_part[ax] : cut;
            far_part[3 + ax] = far_part[3 + ax] < cut ? far_part[3 + ax] : cut;
        }
        if (near_part[ax] <= near_part[3 + ax]) { /* the part on the eye's side keeps its directions */
            rn = g.r;
            box_directions(&f, near_part, blo, bhi);
            ok = clip_to_rect(&rn, blo, bhi);
            if (ok < 0 || (ok > 0 && !push_fragment(stack, &top, near_part, &rn, i + 1))) return 0;
        }
        rf = g.r;
        box_directions(&f, far_part, blo, bhi);
        ok = clip_to_rect(&rf, blo, bhi);
        if (ok < 0) return 0;
        if (ok == 0) continue;
        if (!push_outside(stack, &top, far_part, &rf, ff, i + 1)) return 0;
    }
    return 1;
}

/* 0 when the centre of the box (grown by its margin) lies behind no face: then no test can hide the box
 * (each hides only boxes every point of which some face hides), so most visible boxes end here. */
static int centre_behind_a_face(const pvsr_culler* c, const float box[6]) {
    const double delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale_of(c->eye_d, box);
    double x[3];
    int a;
    for (a = 0; a < 3; ++a)
        x[a] = 0.5 * (((double)box[a] - delta - c->eye_d[a]) + ((double)box[3 + a] + delta - c->eye_d[a]));
    return point_behind_a_face(c, x);
}

int pvsr_culler_classify(const pvsr_culler* c, const float box[6]) {
    if (c == NULL || box == NULL || !c->eye_ok || (c->used == 0 && c->polygon_count == 0) || !usable_box(box))
        return PVSR_CULL_VISIBLE;
    if (!centre_behind_a_face(c, box)) return PVSR_CULL_VISIBLE;
    if (hidden_by_shadow_frusta(c, box)) return PVSR_CULL_SHADOW_FRUSTUM;
    if (hidden_by_depth_cube(c, box)) return PVSR_CULL_DEPTH_CUBE;
    if (hidden_by_faces(c, box)) return PVSR_CULL_FACES;
    return PVSR_CULL_VISIBLE;
}

int pvsr_culler_is_hidden(const pvsr_culler* c, const float box[6]) {
    return pvsr_culler_classify(c, box) != PVSR_CULL_VISIBLE;
}

/* The faces of a used occluder that face the eye: a panel's rectangle, or a box's faces toward the eye, each
 * GROWN in its plane by FUSE_GROW_REL of its scale (far below the float precision of its corners), so that
 * faces meeting at a junction close it (docs/ALGORITHMS.md#runtime-faces). */
static void add_faces(pvsr_culler* c, const pvsr_culler_candidate* cand) {
    const double grow = FUSE_GROW_REL * (1.0 + scale_of(c->eye_d, cand->box));
    int a;
    for (a = 0; a < 3; ++a) {
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        pvsr_culler_face* f = &c->faces[c->face_count];
        if (cand->flat >= 0 && a != cand->flat) continue;
        if (cand->flat < 0 && !(c->eye_d[a] < (double)cand->box[a] - cand->delta) &&
            !(c->eye_d[a] > (double)cand->box[3 + a] + cand->delta))
            continue;
        f->axis = a;
        f->above = c->eye_d[a] < (double)cand->box[a];
        f->plane = f->above ? (double)cand->box[a] : (double)cand->box[3 + a];
        f->delta = cand->delta;
        f->lo[0] = (double)cand->box[a1] - grow;
        f->hi[0] = (double)cand->box[3 + a1] + grow;
        f->lo[1] = (double)cand->box[a2] - grow;
        f->hi[1] = (double)cand->box[3 + a2] + grow;
        f->axis1 = a1;
        f->axis2 = a2;
        f->rel_plane = f->plane - c->eye_d[a];
        f->rel_lo[0] = f->lo[0] - c->eye_d[a1];
        f->rel_hi[0] = f->hi[0] - c->eye_d[a1];
        f->rel_lo[1] = f->lo[1] - c->eye_d[a2];
        f->rel_hi[1] = f->hi[1] - c->eye_d[a2];
        ++c->face_count;
    }
}

static float float_down(double x) {
    float f = (float)x;
    if ((double)f > x) f = nextafterf(f, -INFINITY);
    return f;
}
static float float_up(double x) {
    float f = (float)x;
    if ((double)f < x) f = nextafterf(f, INFINITY);
    return f;
}

/* Each face's projection bounds in the six frames of the faces test, once a frame: the test then projects a
 * face only for the boxes whose directions its bounds meet (the same faces as projecting each for every box).
 */
static void face_directions(pvsr_culler* c) {
    double x[FUSE_PROJ_VERTS], y[FUSE_PROJ_VERTS];
    size_t k;
    int frame;
    for (k = 0; k < c->face_count; ++k) {
        for (frame = 0; frame < 6; ++frame) {
            fuse_frame f;
            fuse_face ff;
            float* b = c->face_directions[frame][k];
            f.p = frame / 2;
            f.sign = frame % 2 == 0 ? 1.0 : -1.0;
            f.u = (f.p + 1) % 3;
            f.v = (f.p + 2) % 3;
            if (!project_face(&f, &c->faces[k], c->eye_d, x, y, &ff)) {
                b[0] = b[1] = INFINITY;
                b[2] = b[3] = -INFINITY;
                continue;
            }
            b[0] = float_down(ff.lo[0]);
            b[1] = float_down(ff.lo[1]);
            b[2] = float_up(ff.hi[0]);
            b[3] = float_up(ff.hi[1]);
        }
    }
}

void pvsr_culler_begin_frame(pvsr_culler* c, const float eye[3], const float* boxes, size_t count) {
    const int r = c != NULL ? c->resolution : 0;
    size_t k, n;
    int face, a;
    if (c == NULL) return;
    for (face = 0; face < 6; ++face) { /* clear what the last frame wrote */
        int* w = c->written[face];
        int i, j;
        for (j = w[2]; j <= w[3]; ++j) {
            float* row = c->depth + ((size_t)face * (size_t)r + (size_t)j) * (size_t)r;
            for (i = w[0]; i <= w[1]; ++i) row[i] = INFINITY;
        }
        w[0] = 0;
        w[1] = -1;
        w[2] = 0;
        w[3] = -1;
    }
    c->used = 0;
    c->redundant = 0;
    c->frustum_count = 0;
    c->face_count = 0;
    c->polygon_count = 0;
    c->candidate_count = 0;
    c->eye_ok = c->ok && eye != NULL && isfinite(eye[0]) && isfinite(eye[1]) && isfinite(eye[2]);
    if (!c->eye_ok) return;
    for (a = 0; a < 3; ++a) {
        c->eye[a] = eye[a];
        c->eye_d[a] = (double)eye[a];
    }
    if (boxes == NULL) count = 0;
    /* The usable boxes (the first PVSR_CULLER_MAX_OCCLUDERS), nearest first; one the nearer ones hide is skipped. */
    for (k = 0; k < count && c->candidate_count < PVSR_CULLER_MAX_OCCLUDERS; ++k) {
        pvsr_culler_candidate cand;
        int touches_eye = 1;
        double dist2 = 0.0;
        memcpy(cand.box, boxes + 6 * k, sizeof cand.box);
        if (!usable_box(cand.box)) continue;
        cand.delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale_of(c->eye_d, cand.box);
        cand.flat = flat_axis(cand.box);
        memcpy(cand.raster, cand.box, sizeof cand.raster);
        if (cand.flat == -2) continue; /* a segment or a point: hides nothing */
        if (cand.flat >= 0) {          /* a panel: off its plane, its rectangle shrunk by the margin */
            int empty = 0;
            if (!(fabs((double)cand.box[cand.flat] - c->eye_d[cand.flat]) > cand.delta)) continue;
            for (a = 0; a < 3; ++a) {
                if (a == cand.flat) continue;
                cand.raster[a] = moved_in(cand.box[a], cand.delta);
                cand.raster[3 + a] = moved_in(cand.box[3 + a], -cand.delta);
                empty = empty || !(cand.raster[a] < cand.raster[3 + a]);
            }
            if (empty) continue;
        }
        for (a = 0; a < 3; ++a) {
            const double d = maxd(0.0, maxd((double)cand.box[a] - c->eye_d[a], c->eye_d[a] - (double)cand.box[3 + a]));
            touches_eye = touches_eye && (double)cand.box[a] - cand.delta <= c->eye_d[a] &&
                          c->eye_d[a] <= (double)cand.box[3 + a] + cand.delta;
            dist2 += d * d;
        }
        if (touches_eye) continue;
        cand.dist2 = dist2;
        /* Insertion in order of distance (stable: ties keep their order). */
        n = c->candidate_count++;
        while (n > 0 && c->candidates[n - 1].dist2 > dist2) {
            c->candidates[n] = c->candidates[n - 1];
            --n;
        }
        c->candidates[n] = cand;
    }
    for (k = 0; k < c->candidate_count; ++k) {
        const pvsr_culler_candidate* cand = &c->candidates[k];
        if (c->used > 0 && (hidden_by_shadow_frusta(c, cand->box) || hidden_by_depth_cube(c, cand->box))) {
            ++c->redundant;
            continue;
        }
        ++c->used;
        if (r > 0) rasterize(c, cand->raster, cand->flat);
        build_frustum(c, cand->box, cand->delta, cand->flat, &c->frusta[c->frustum_count++]);
        add_faces(c, cand);
    }
    face_directions(c);
}

/* A polygon occluder's slab from its arguments (pvsr_culler_add_polygon): 3 to PVSR_POLYGON_MAX_CORNERS
 * corners, every value finite, a normal and a thickness >= 0. Its unit normal n, offset o and thickness t
 * along n, and in *scale the larger of *scale and the largest |corner coordinate|; 0 when refused. */
static int polygon_slab(const float plane[5], const float* corners, uint32_t count, uint32_t max_count,
                        double n[3], double* o, double* t, double* scale) {
    double len;
    uint32_t i;
    int a;
    if (plane == NULL || corners == NULL || count < 3 || count > max_count) return 0;
    for (i = 0; i < 5; ++i)
        if (!isfinite(plane[i])) return 0;
    for (i = 0; i < 3 * count; ++i)
        if (!isfinite(corners[i])) return 0;
    len = sqrt((double)plane[0] * plane[0] + (double)plane[1] * plane[1] + (double)plane[2] * plane[2]);
    if (!(len > 0.0) || !isfinite(len) || !(plane[4] >= 0.0f)) return 0;
    for (a = 0; a < 3; ++a) n[a] = (double)plane[a] / len;
    *o = (double)plane[3] / len;
    *t = (double)plane[4] / len;
    for (i = 0; i < 3 * count; ++i) *scale = maxd(*scale, fabs((double)corners[i]));
    return 1;
}

int pvsr_culler_add_polygon(pvsr_culler* c, const float plane[5], const float* corners, uint32_t count) {
    pvsr_culler_polygon* pg;
    double n[3], o, t, scale = 0.0, s_e, sign, grow, area = 0.0;
    uint32_t i, j;
    int a;
    if (c == NULL || !c->eye_ok || c->polygon_count >= PVSR_CULLER_MAX_POLYGONS) return 0;
    for (a = 0; a < 3; ++a) scale = maxd(scale, fabs(c->eye_d[a]));
    if (!polygon_slab(plane, corners, count, PVSR_POLYGON_MAX_CORNERS, n, &o, &t, &scale)) return 0;
    pg = &c->polygons[c->polygon_count];
    pg->delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale;
    grow = FUSE_GROW_REL * (1.0 + scale);
    s_e = n[0] * c->eye_d[0] + n[1] * c->eye_d[1] + n[2] * c->eye_d[2] - o;
    if (s_e < -(t + pg->delta))
        sign = 1.0;
    else if (s_e > t + pg->delta)
        sign = -1.0;
    else
        return 0;                 /* the eye within the slab and its margin */
    pg->near_w = -sign * s_e - t; /* > delta */
    pg->far_w = -sign * s_e + t;
    pg->axis = 0;
    for (a = 0; a < 3; ++a) {
        pg->n[a] = sign * n[a];
        if (fabs(n[a]) > fabs(n[pg->axis])) pg->axis = a;
    }
    for (i = 0; i < count; ++i)
        for (a = 0; a < 3; ++a) pg->c[i][a] = (double)corners[3 * i + (uint32_t)a] - c->eye_d[a];
    for (i = 0; i < count; ++i) { /* edge planes, inward for a counter-clockwise polygon seen from +n */
        const double* p0 = pg->c[i];
        const double* p1 = pg->c[(i + 1) % count];
        const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double* m = pg->m[i];
        double ml;
        m[0] = n[1] * d[2] - n[2] * d[1];
        m[1] = n[2] * d[0] - n[0] * d[2];
        m[2] = n[0] * d[1] - n[1] * d[0];
        ml = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(ml > 0.0) || !isfinite(ml)) return 0;
        for (a = 0; a < 3; ++a) m[a] /= ml;
        pg->k[i] = m[0] * p0[0] + m[1] * p0[1] + m[2] * p0[2];
        for (j = 0; j < count; ++j) /* convex and counter-clockwise: every corner inside every edge */
            if (!(m[0] * pg->c[j][0] + m[1] * pg->c[j][1] + m[2] * pg->c[j][2] >= pg->k[i] - grow)) return 0;
        pg->k[i] -= grow;
        area += n[0] * (p0[1] * p1[2] - p0[2] * p1[1]) + n[1] * (p0[2] * p1[0] - p0[0] * p1[2]) +
                n[2] * (p0[0] * p1[1] - p0[1] * p1[0]);
    }
    if (!(area > 0.0)) return 0;
    pg->count = (int)count;
    ++c->polygon_count;
    return 1;
}

uint32_t pvsr_culler_begin_cell(pvsr_culler* c, const pvsr_level* l, uint32_t cell, const float eye[3],
                                uint32_t max_occluders) {
    float boxes[6 * PVSR_CULLER_MAX_OCCLUDERS] = {0.0f}, plane[5], corners[3 * PVSR_POLYGON_MAX_CORNERS];
    const uint32_t limit =
        max_occluders < PVSR_CULLER_MAX_OCCLUDERS ? max_occluders : PVSR_CULLER_MAX_OCCLUDERS;
    const uint32_t polygons = pvsr_occluder_polygon_count(l, cell);
    uint32_t k, place, first = 0, n; /* first: the cell's polygons at places below the limit */
    while (first < polygons && pvsr_occluder_polygon(l, cell, first, plane, NULL, 0, &place) > 0 &&
           place < limit)
        ++first;
    n = pvsr_occluder_boxes(l, cell, boxes, limit - first);
    pvsr_culler_begin_frame(c, eye, boxes, n);
    for (k = 0; k < first; ++k) {
        const uint32_t m = pvsr_occluder_polygon(l, cell, k, plane, corners, PVSR_POLYGON_MAX_CORNERS, NULL);
        n += (uint32_t)pvsr_culler_add_polygon(c, plane, corners, m);
    }
    return n;
}

/* ---- The occlusion horizon (docs/ALGORITHMS.md#runtime-horizon). Frame fr: depth d = s x_p along axis p
 * (x for frames 0 and 1, z for 2 and 3; s = +1 for even frames), direction (u, v) = (x_h / d, x_y / d) with
 * h the other horizontal axis; u in [-1, 1] cut into `columns` columns. */
#define HZ_NEAR 1e-3    /* the near plane: a face's part at a smaller depth is clipped away */
#define HZ_ROUND 1e-12  /* relative: a piece is shrunk by this on both ends, for double rounding */
#define HZ_TOUCH 1e-9   /* relative: pieces whose ends are this close count as meeting */
#define HZ_DEPTH 1e-9   /* relative: depths are made larger by this */
#define HZ_MAX_VERTS (2 * PVSR_HORIZON_MAX_CORNERS + 8) /* a projected face, clipped, then by another */
#define HZ_MAX_PIECES (1u << 26)
#define HZ_FRONT 4  /* lines a column's test keeps reached at once */
#define HZ_PASSES 3 /* walks of a column's pieces a test makes at most */
#define HZ_DENT 1e-6 /* relative: the deepest dent a tile's directions may have */
#define HZ_CANDIDATES 256 /* pieces a node's test takes at most */
#define HZ_STACK 64       /* nodes a test keeps to try */
#define HZ_CUTS 16        /* cuts of a leaf at its faces' ends a test makes at most */
#define HZ_USES 1024      /* tags pvsr_horizon_hidden_by reports at most */

static double hz_min(double a, double b) {
    return b < a ? b : a;
}
static double hz_max(double a, double b) {
    return a < b ? b : a;
}
/* Columns a side frame: the request clamped to [PVSR_HORIZON_MIN_COLUMNS, PVSR_HORIZON_MAX_COLUMNS] and
 * rounded down to a power of two (the columns are the leaves of a binary tree). */
static int hz_columns(int columns) {
    int c = PVSR_HORIZON_MIN_COLUMNS;
    while (c * 2 <= columns && c * 2 <= PVSR_HORIZON_MAX_COLUMNS) c *= 2;
    return c;
}

size_t pvsr_horizon_memory_bytes(int columns, size_t max_pieces) {
    const size_t c = (size_t)hz_columns(columns);
    if (max_pieces > HZ_MAX_PIECES) max_pieces = HZ_MAX_PIECES;
    return 2 * max_pieces * sizeof(pvsr_horizon_piece) + (8 * c + 1) * sizeof(uint32_t);
}

int pvsr_horizon_init(pvsr_horizon* h, int columns, size_t max_pieces, void* memory, size_t memory_bytes) {
    if (h == NULL) return 0;
    memset(h, 0, sizeof *h);
    h->columns = hz_columns(columns);
    if (memory == NULL || ((uintptr_t)memory & 7u) != 0 || max_pieces == 0 || max_pieces > HZ_MAX_PIECES ||
        memory_bytes < pvsr_horizon_memory_bytes(columns, max_pieces))
        return 0;
    h->pieces = (pvsr_horizon_piece*)memory;
    h->sorted = h->pieces + max_pieces;
    h->first = (uint32_t*)(void*)(h->sorted + max_pieces);
    h->capacity = max_pieces;
    h->ok = 1;
    return 1;
}

void pvsr_horizon_begin(pvsr_horizon* h, const float eye[3]) {
    int a;
    if (h == NULL) return;
    h->eye_ok = h->ready = 0;
    h->count = h->dropped = 0;
    h->tag = 0;
    h->scale = 0.0;
    if (!h->ok || eye == NULL) return;
    for (a = 0; a < 3; ++a) {
        if (!isfinite(eye[a])) return;
        h->eye[a] = (double)eye[a];
        h->scale = hz_max(h->scale, fabs(h->eye[a]));
    }
    h->eye_ok = 1;
}

static void hz_frame(int fr, int* p, int* hx, double* s) {
    *p = fr < 2 ? 0 : 2;
    *hx = fr < 2 ? 2 : 0;
    *s = (fr & 1) ? -1.0 : 1.0;
}

/* The directions of the polygon's part at depth >= HZ_NEAR in frame fr (its corners less the eye): a convex
 * polygon of the returned number of corners (u, v). */
static int hz_project(int fr, const double (*pts)[3], int n, double* u, double* v) {
    int p, hx, i, m = 0;
    double s;
    hz_frame(fr, &p, &hx, &s);
    for (i = 0; i < n && m + 2 <= HZ_MAX_VERTS; ++i) {
        const double* a = pts[i];
        const double* b = pts[(i + 1) % n];
        const double da = s * a[p], db = s * b[p];
        if (da >= HZ_NEAR) {
            u[m] = a[hx] / da;
            v[m] = a[1] / da;
            ++m;
        }
        if ((da >= HZ_NEAR) != (db >= HZ_NEAR)) {
            const double t = (HZ_NEAR - da) / (db - da);
            u[m] = (a[hx] + (b[hx] - a[hx]) * t) / HZ_NEAR;
            v[m] = (a[1] + (b[1] - a[1]) * t) / HZ_NEAR;
            ++m;
        }
    }
    return m;
}

/* The convex polygon (u, v) of n corners clipped by the convex polygon (bu, bv) of nb (either orientation),
 * in place; returns its corner count. */
static int hz_clip(double* u, double* v, int n, const double* bu, const double* bv, int nb) {
    double area = 0.0, orient, tu[HZ_MAX_VERTS], tv[HZ_MAX_VERTS];
    int i, j, m;
    for (i = 0; i < nb; ++i) area += bu[i] * bv[(i + 1) % nb] - bu[(i + 1) % nb] * bv[i];
    orient = area >= 0.0 ? 1.0 : -1.0;
    for (i = 0; i < nb && n > 0; ++i) {
        const double pu = bu[i], pv = bv[i], qu = bu[(i + 1) % nb], qv = bv[(i + 1) % nb];
        m = 0;
        for (j = 0; j < n && m + 2 <= HZ_MAX_VERTS; ++j) {
            const int k = (j + 1) % n;
            const double sj = orient * ((qu - pu) * (v[j] - pv) - (qv - pv) * (u[j] - pu));
            const double sk = orient * ((qu - pu) * (v[k] - pv) - (qv - pv) * (u[k] - pu));
            if (sj >= 0.0) {
                tu[m] = u[j];
                tv[m] = v[j];
                ++m;
            }
            if ((sj >= 0.0) != (sk >= 0.0)) {
                const double t = sj / (sj - sk);
                tu[m] = u[j] + (u[k] - u[j]) * t;
                tv[m] = v[j] + (v[k] - v[j]) * t;
                ++m;
            }
        }
        memcpy(u, tu, (size_t)m * sizeof(double));
        memcpy(v, tv, (size_t)m * sizeof(double));
        n = m;
    }
    return n;
}

/* The v range of the convex polygon on the line u = x; 0 when the line misses it. */
static int hz_span(const double* u, const double* v, int n, double x, double* lo, double* hi) {
    int i;
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (i = 0; i < n; ++i) {
        const int k = (i + 1) % n;
        if ((u[i] - x) * (u[k] - x) > 0.0) continue;
        if (u[i] == u[k]) {
            *lo = hz_min(*lo, hz_min(v[i], v[k]));
            *hi = hz_max(*hi, hz_max(v[i], v[k]));
        } else {
            const double y = v[i] + (v[k] - v[i]) * ((x - u[i]) / (u[k] - u[i]));
            *lo = hz_min(*lo, y);
            *hi = hz_max(*hi, y);
        }
    }
    return *lo <= *hi;
}

/* The directions of a tile in frame fr: its corners moved along their rays onto a plane parallel to its own
 * (pts: those points, a planar polygon), clipped at depth HZ_NEAR, when they turn nearly one way, once
 * around. Every direction inside the polygon meets the tile's disk of surface (docs/ALGORITHMS.md#runtime-
 * horizon). A corner that turns the wrong way by a rounding's worth gets its DENT: how far its neighbours'
 * chord passes outside it, along v (0 at the other corners), which the pieces of its column give up. Returns
 * the corner count; 0 when the polygon is not nearly convex or a dent is past HZ_DENT of the scale. */
static int hz_tile_directions(int fr, const double (*pts)[3], int n, double* u, double* v, double* dent) {
    double area = 0.0, scale = 0.0, orient;
    int m = hz_project(fr, pts, n, u, v), i, changes = 0, du_sign = 0, first_du = 0;
    if (m < 3) return 0;
    for (i = 0; i < m; ++i) {
        const int j = (i + 1) % m;
        area += u[i] * v[j] - u[j] * v[i];
        scale = hz_max(scale, hz_max(fabs(u[i]), fabs(v[i])));
    }
    if (!(area != 0.0) || !isfinite(area)) return 0;
    orient = area > 0.0 ? 1.0 : -1.0;
    for (i = 0; i < m; ++i) {
        const int a = (i + m - 1) % m, b = (i + 1) % m;
        const double eu = u[i] - u[a], ev = v[i] - v[a], fu = u[b] - u[i], fv = v[b] - v[i];
        const double turn = orient * (eu * fv - ev * fu);
        const double len = sqrt((eu * eu + ev * ev) * (fu * fu + fv * fv));
        const double bound = HZ_ROUND * (fabs(u[i]) + fabs(u[b]) + fabs(fv));
        const int ds = fu > bound ? 1 : fu < -bound ? -1 : 0;
        dent[i] = 0.0;
        if (!(turn > HZ_ROUND * len) && !(eu == 0.0 && fu == 0.0 && ev * fv > 0.0)) {
            /* straight or the wrong way (but not straight up or down): onwards only, by a dent */
            const double cu = u[b] - u[a];
            if (!(eu * fu + ev * fv > 0.0) || !(fabs(cu) > 0.0)) return 0;
            dent[i] = fabs(v[i] - (v[a] + (v[b] - v[a]) * ((u[i] - u[a]) / cu))) +
                      HZ_ROUND * (1.0 + fabs(v[i]) + fabs(v[a]) + fabs(v[b]));
            if (!(dent[i] <= HZ_DENT * (1.0 + scale))) return 0;
        }
        if (ds != 0) { /* once around: u turns back at most twice (edges vertical to rounding aside) */
            if (du_sign != 0 && ds != du_sign) ++changes;
            if (du_sign == 0) first_du = ds;
            du_sign = ds;
        }
    }
    if (du_sign != 0 && du_sign != first_du) ++changes;
    return changes <= 2 ? m : 0;
}

/* The piece of a face over columns [k, k + w) of frame fr, as node `node` of the frame's tree: the trapezoid
 * between the chords of its boundaries at the two sides, each end shrunk for rounding and by `extra` (the
 * dents in it), with the deepest point of the plane n . x = c over it. 1 when it was added. */
static int hz_emit(pvsr_horizon* h, int fr, uint32_t node, double u0, double u1, const double* pu,
                   const double* pv, int m, const double n[3], double c, int p, int hx, double s,
                   double extra, double side[3]) {
    const int cols = h->columns;
    double lo0, hi0, lo1, hi1, r0, r1, l0, h0, l1, h1;
    int ok1;
    /* side: the span at u0 when side[2] says it is known (1 found, -1 missed), set to the span at u1 */
    if (side[2] == 0.0) side[2] = hz_span(pu, pv, m, u0, &side[0], &side[1]) ? 1.0 : -1.0;
    lo0 = side[0];
    hi0 = side[1];
    ok1 = hz_span(pu, pv, m, u1, &lo1, &hi1);
    if (side[2] < 0.0 || !ok1) {
        side[0] = lo1;
        side[1] = hi1;
        side[2] = ok1 ? 1.0 : -1.0;
        return 0;
    }
    side[0] = lo1;
    side[1] = hi1;
    side[2] = 1.0;
    r0 = HZ_ROUND * (1.0 + fabs(lo0) + fabs(hi0)) + extra;
    r1 = HZ_ROUND * (1.0 + fabs(lo1) + fabs(hi1)) + extra;
    l0 = lo0 + r0;
    h0 = hi0 - r0;
    l1 = lo1 + r1;
    h1 = hi1 - r1;
    if (h0 >= l0 && h1 >= l1 && (h0 > l0 || h1 > l1)) {
        /* The deepest point over the trapezoid: 1 / depth is linear in (u, v), so it is least at a corner. */
        const double g0 = (n[p] * s + n[hx] * u0) / c, g1 = (n[p] * s + n[hx] * u1) / c, gv = n[1] / c;
        const double g = hz_min(hz_min(g0 + gv * l0, g0 + gv * h0), hz_min(g1 + gv * l1, g1 + gv * h1));
        if (g > 0.0 && isfinite(g)) {
            if (h->count < h->capacity) {
                pvsr_horizon_piece* pc = &h->pieces[h->count++];
                pc->lo[0] = l0;
                pc->lo[1] = l1;
                pc->hi[0] = h0;
                pc->hi[1] = h1;
                pc->depth = (1.0 / g) * (1.0 + HZ_DEPTH);
                pc->plane[0] = n[p] * s / c;
                pc->plane[1] = n[hx] / c;
                pc->plane[2] = gv;
                pc->column = (uint32_t)(fr * 2 * cols) + node;
                pc->u[0] = (float)u0;
                pc->u[1] = (float)u1;
                pc->tag = h->tag;
                pc->reach = 0.0f;
                return 1;
            }
            ++h->dropped;
        }
    }
    return 0;
}

/* The pieces of a face over the run of columns [k0, k1]: the largest aligned blocks of the tree that tile it
 * (node (cols + k) >> L holds columns [k, k + 2^L) when k is a multiple of 2^L). With `single`, the run is
 * one column with bends inside, given `extra` to shrink. */
static int hz_run(pvsr_horizon* h, int fr, int k0, int k1, const double* pu, const double* pv, int m,
                  const double n[3], double c, int p, int hx, double s, const double* extra, int single) {
    const int cols = h->columns;
    int added = 0;
    double side[3] = {0.0, 0.0, 0.0}; /* the span at the next block's first side, once known */
    if (single)
        return hz_emit(h, fr, (uint32_t)(cols + k0), -1.0 + 2.0 * k0 / cols, -1.0 + 2.0 * (k0 + 1) / cols, pu,
                       pv, m, n, c, p, hx, s, *extra, side);
    while (k0 <= k1) {
        int w = 1, level = 0;
        while ((k0 & (2 * w - 1)) == 0 && k0 + 2 * w - 1 <= k1 && 2 * w <= cols) {
            w *= 2;
            ++level;
        }
        added |= hz_emit(h, fr, (uint32_t)(cols + k0) >> level, -1.0 + 2.0 * k0 / cols,
                         -1.0 + 2.0 * (k0 + w) / cols, pu, pv, m, n, c, p, hx, s, 0.0, side);
        k0 += w;
    }
    return added;
}

/* A float at or above (up = 1) or at or below (up = 0) x, for x in [-2, 2]. */
static double hz_float_in(double x, int up) {
    float f = (float)x;
    if (up && (double)f < x) f = nextafterf(f, 2.0f);
    if (!up && (double)f > x) f = nextafterf(f, -2.0f);
    return (double)f;
}

/* The pieces of a face's two end columns, those holding its least and its greatest u (e0, e1, given with
 * the rounding margin) and not wholly inside it (k0d .. k1d are): each a trapezoid over the face's part of
 * the column, its sides floats within it, as a piece of the leaf (docs/ALGORITHMS.md#runtime-horizon: the
 * faces' ends within a column). dent: the tile's dents by corner, or NULL. */
static int hz_ends(pvsr_horizon* h, int fr, double k0d, double k1d, double e0, double e1, const double* pu,
                   const double* pv, int m, const double n[3], double c, int p, int hx, double s,
                   const double* dent) {
    const int cols = h->columns;
    int added = 0, end, i;
    for (end = 0; end < 2; ++end) {
        const double at = end == 0 ? e0 : e1;
        double u0, u1, extra = 0.0, side[3] = {0.0, 0.0, 0.0};
        int k;
        if (!(at > -1.0) || !(at < 1.0)) continue; /* outside the frame's columns (or not a number) */
        k = (int)floor((at + 1.0) * 0.5 * cols);
        if (k < 0 || k > cols - 1) continue;
        if ((double)k >= k0d && (double)k <= k1d) continue; /* wholly inside: a full piece */
        if (end == 1 && e0 > -1.0 && (int)floor((e0 + 1.0) * 0.5 * cols) == k) continue; /* done at end 0 */
        u0 = hz_float_in(hz_max(e0, -1.0 + 2.0 * k / cols), 1);
        u1 = hz_float_in(hz_min(e1, -1.0 + 2.0 * (k + 1) / cols), 0);
        if (!(u0 < u1)) continue;
        if (dent != NULL)
            for (i = 0; i < m; ++i)
                if (dent[i] > 0.0 && pu[i] >= u0 && pu[i] <= u1) extra += dent[i];
        added |= hz_emit(h, fr, (uint32_t)(cols + k), u0, u1, pu, pv, m, n, c, p, hx, s, extra, side);
    }
    return added;
}

/* Adds the pieces of a face: the directions of polygon a (and of polygon b too, when given) meet an occluder
 * by the plane n . x = c (x less the eye; c / (n . direction) > 0 towards it), in every frame. Returns
 * whether it added one. */
static int hz_add_face(pvsr_horizon* h, const double (*a)[3], int na, const double (*b)[3], int nb,
                       const double (*tile)[3], int nt, const double n[3], double c) {
    const int cols = h->columns;
    int fr, added = 0;
    for (fr = 0; fr < 4; ++fr) {
        double pu[HZ_MAX_VERTS], pv[HZ_MAX_VERTS], umin = HUGE_VAL, umax = -HUGE_VAL, margin, s, k0d, k1d;
        double dent[HZ_MAX_VERTS];
        int m = 0, i, k0, k1, p, hx, dents = 0;
        if (tile != NULL && (m = hz_tile_directions(fr, tile, nt, pu, pv, dent)) >= 3) {
            for (i = 0; i < m; ++i) dents |= dent[i] > 0.0;
        } else if ((m = hz_project(fr, a, na, pu, pv)) < 3)
            continue;
        else if (b != NULL) {
            double qu[HZ_MAX_VERTS], qv[HZ_MAX_VERTS];
            const int mb = hz_project(fr, b, nb, qu, qv);
            if (mb < 3) continue;
            m = hz_clip(pu, pv, m, qu, qv, mb);
            if (m < 3) continue;
        }
        for (i = 0; i < m; ++i) {
            umin = hz_min(umin, pu[i]);
            umax = hz_max(umax, pu[i]);
        }
        /* The columns wholly inside [umin, umax], less a rounding margin. */
        margin = HZ_ROUND * (1.0 + hz_max(fabs(umin), fabs(umax)));
        k0d = ceil((umin + margin + 1.0) * 0.5 * cols);
        k1d = floor((umax - margin + 1.0) * 0.5 * cols) - 1.0;
        hz_frame(fr, &p, &hx, &s);
        if (!(k0d <= k1d) || k1d < 0.0 || k0d > (double)(cols - 1)) {
            added |= hz_ends(h, fr, k0d, k1d, umin + margin, umax - margin, pu, pv, m, n, c, p, hx, s,
                             dents ? dent : NULL);
            continue;
        }
        k0 = k0d < 0.0 ? 0 : (int)k0d;
        k1 = k1d > (double)(cols - 1) ? cols - 1 : (int)k1d;
        {
            /* Where the face's boundaries bend: its corners' positions in columns (x = k + f: in column k
             * at fraction f of it), sorted. Between them both boundaries are straight. */
            double bend[HZ_MAX_VERTS];
            int nb_ = 0, q, rs = k0;
            for (i = 0; i < m; ++i) {
                const double x = (pu[i] + 1.0) * 0.5 * cols;
                int at;
                if (!(x > (double)k0) || !(x < (double)(k1 + 1))) continue;
                for (at = nb_; at > 0 && bend[at - 1] > x; --at) bend[at] = bend[at - 1];
                bend[at] = x;
                ++nb_;
            }
            /* Runs of whole columns with no bend inside go to the tree as the largest aligned blocks; a
             * column with a bend inside gets its own piece (the chords of the bent boundaries, less the
             * dents of the corners in it). */
            for (q = 0; q < nb_; ++q) {
                const int kb = (int)floor(bend[q]);
                if (rs <= kb - 1) added |= hz_run(h, fr, rs, kb - 1, pu, pv, m, n, c, p, hx, s, NULL, 0);
                if (bend[q] > (double)kb && rs <= kb) { /* inside column kb */
                    double extra = 0.0;
                    if (dents)
                        for (i = 0; i < m; ++i) {
                            const double xi = (pu[i] + 1.0) * 0.5 * cols;
                            if (dent[i] > 0.0 && xi >= (double)kb && xi <= (double)(kb + 1)) extra += dent[i];
                        }
                    added |= hz_run(h, fr, kb, kb, pu, pv, m, n, c, p, hx, s, &extra, 1);
                    rs = kb + 1;
                } else if (rs < kb)
                    rs = kb;
            }
            if (rs <= k1) added |= hz_run(h, fr, rs, k1, pu, pv, m, n, c, p, hx, s, NULL, 0);
        }
        added |= hz_ends(h, fr, k0d, k1d, umin + margin, umax - margin, pu, pv, m, n, c, p, hx, s,
                         dents ? dent : NULL);
    }
    return added;
}

int pvsr_horizon_add_box(pvsr_horizon* h, const float box[6]) {
    double lo[3], hi[3], scale, delta, grow, q[4][3], n[3];
    int a, flat = -1, flats = 0, added = 0;
    if (h == NULL || !h->ok || !h->eye_ok || h->ready || box == NULL) return 0;
    scale = h->scale;
    for (a = 0; a < 3; ++a) {
        if (!isfinite(box[a]) || !isfinite(box[3 + a]) || box[a] > box[3 + a]) return 0;
        lo[a] = (double)box[a] - h->eye[a];
        hi[a] = (double)box[3 + a] - h->eye[a];
        scale = hz_max(scale, hz_max(fabs((double)box[a]), fabs((double)box[3 + a])));
        if (box[a] == box[3 + a]) {
            flat = a;
            ++flats;
        }
    }
    if (flats > 1) return 0;
    delta = CULL_MARGIN_M + CULL_MARGIN_REL * scale;
    grow = FUSE_GROW_REL * (1.0 + scale);
    if (flats == 0 && lo[0] <= delta && hi[0] >= -delta && lo[1] <= delta && hi[1] >= -delta &&
        lo[2] <= delta && hi[2] >= -delta)
        return 0; /* holding the eye */
    for (a = 0; a < 3; ++a) {
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        double plane;
        if (flats == 1 && a != flat) continue;
        if (flats == 1) {
            if (fabs(lo[a]) <= delta) return 0; /* a panel seen edge-on */
            plane = lo[a];
        } else if (lo[a] > delta) /* the eye before the box's min face on this axis */
            plane = lo[a];
        else if (hi[a] < -delta)
            plane = hi[a];
        else
            continue;
        q[0][a] = q[1][a] = q[2][a] = q[3][a] = plane;
        q[0][a1] = q[3][a1] = lo[a1] - grow;
        q[1][a1] = q[2][a1] = hi[a1] + grow;
        q[0][a2] = q[1][a2] = lo[a2] - grow;
        q[2][a2] = q[3][a2] = hi[a2] + grow;
        n[0] = n[1] = n[2] = 0.0;
        n[a] = 1.0;
        added |= hz_add_face(h, (const double(*)[3])q, 4, NULL, 0, NULL, 0, n, plane);
    }
    return added;
}

static int hz_add_slab(pvsr_horizon* h, const float plane[5], const float* corners, uint32_t count,
                       int tile) {
    double n[3], o, t, scale, s_e, w_near, w_far, area = 0.0, grow;
    double c[PVSR_HORIZON_MAX_CORNERS][3], near_s[PVSR_HORIZON_MAX_CORNERS][3],
        far_s[PVSR_HORIZON_MAX_CORNERS][3], on_plane[PVSR_HORIZON_MAX_CORNERS][3];
    uint32_t i, j;
    int a, added;
    if (h == NULL || !h->ok || !h->eye_ok || h->ready) return 0;
    scale = h->scale;
    if (!polygon_slab(plane, corners, count, PVSR_HORIZON_MAX_CORNERS, n, &o, &t, &scale)) return 0;
    o -= n[0] * h->eye[0] + n[1] * h->eye[1] + n[2] * h->eye[2]; /* less the eye */
    grow = FUSE_GROW_REL * (1.0 + scale);
    s_e = -o; /* the eye's height above the slab's middle plane */
    if (s_e > t + CULL_MARGIN_M + CULL_MARGIN_REL * scale) {
        w_near = o + t;
        w_far = o - t;
    } else if (s_e < -(t + CULL_MARGIN_M + CULL_MARGIN_REL * scale)) {
        w_near = o - t;
        w_far = o + t;
    } else
        return 0; /* the eye within the slab and its margin */
    for (i = 0; i < count; ++i)
        for (a = 0; a < 3; ++a) c[i][a] = (double)corners[3 * i + (uint32_t)a] - h->eye[a];
    for (i = 0; i < count; ++i) { /* convex and counter-clockwise seen from +n, as for the culler */
        const double* p0 = c[i];
        const double* p1 = c[(i + 1) % count];
        const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double m[3], ml, k;
        m[0] = n[1] * d[2] - n[2] * d[1];
        m[1] = n[2] * d[0] - n[0] * d[2];
        m[2] = n[0] * d[1] - n[1] * d[0];
        ml = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(ml > 0.0) || !isfinite(ml)) return 0;
        k = (m[0] * p0[0] + m[1] * p0[1] + m[2] * p0[2]) / ml;
        for (j = 0; j < count; ++j)
            if (!((m[0] * c[j][0] + m[1] * c[j][1] + m[2] * c[j][2]) / ml >= k - grow)) return 0;
        area += n[0] * (p0[1] * p1[2] - p0[2] * p1[1]) + n[1] * (p0[2] * p1[0] - p0[0] * p1[2]) +
                n[2] * (p0[0] * p1[1] - p0[1] * p1[0]);
    }
    if (!(area > 0.0)) return 0;
    /* The prism's cross-sections at the slab's near and far planes: the corners moved along n. A tile's
     * corners also move along their rays onto the plane n . x = w_near (so that clipping them at the near
     * plane of a frame is exact); a corner outside the slab's side away from the eye makes it no tile. */
    for (i = 0; i < count; ++i) {
        const double w = n[0] * c[i][0] + n[1] * c[i][1] + n[2] * c[i][2];
        const double ray = w / w_near;
        for (a = 0; a < 3; ++a) {
            near_s[i][a] = c[i][a] + n[a] * (w_near - w);
            far_s[i][a] = c[i][a] + n[a] * (w_far - w);
            on_plane[i][a] = c[i][a] / ray;
        }
        if (!(ray > 0.0) || !isfinite(ray)) tile = 0;
    }
    added = hz_add_face(h, (const double(*)[3])near_s, (int)count, (const double(*)[3])far_s, (int)count,
                        tile ? (const double(*)[3])on_plane : NULL, (int)count, n, w_far);
    return added;
}

int pvsr_horizon_add_polygon(pvsr_horizon* h, const float plane[5], const float* corners, uint32_t count) {
    return hz_add_slab(h, plane, corners, count, 0);
}

int pvsr_horizon_add_tile(pvsr_horizon* h, const float plane[5], const float* corners, uint32_t count) {
    return hz_add_slab(h, plane, corners, count, 1);
}

/* A piece's lowest point in its column: the sort key, and a bound below its lower chord anywhere in it. */
static double hz_bottom(const pvsr_horizon_piece* a) {
    return hz_min(a->lo[0], a->lo[1]);
}

/* The order of a node's pieces: by bottom, then top, then depth. */
static int hz_before(const pvsr_horizon_piece* a, const pvsr_horizon_piece* b) {
    const double ka = hz_bottom(a), kb = hz_bottom(b);
    if (ka != kb) return ka < kb;
    if (a->hi[0] + a->hi[1] != b->hi[0] + b->hi[1]) return a->hi[0] + a->hi[1] < b->hi[0] + b->hi[1];
    return a->depth < b->depth;
}

/* Sorts run[0 .. len) by hz_before: runs of 16 by insertion, then merged bottom-up through tmp. */
static void hz_sort(pvsr_horizon_piece* run, pvsr_horizon_piece* tmp, uint32_t len) {
    uint32_t a, b, width;
    pvsr_horizon_piece *src = run, *dst = tmp, *swap;
    for (a = 0; a < len; a += 16) {
        const uint32_t end = a + 16 < len ? a + 16 : len;
        for (b = a + 1; b < end; ++b) {
            const pvsr_horizon_piece x = run[b];
            uint32_t c = b;
            for (; c > a && hz_before(&x, &run[c - 1]); --c) run[c] = run[c - 1];
            run[c] = x;
        }
    }
    for (width = 16; width < len; width *= 2) {
        for (a = 0; a < len; a += 2 * width) {
            const uint32_t mid = a + width < len ? a + width : len, end = a + 2 * width < len ? a + 2 * width : len;
            uint32_t i = a, k = mid, o = a;
            while (i < mid && k < end) dst[o++] = hz_before(&src[k], &src[i]) ? src[k++] : src[i++];
            while (i < mid) dst[o++] = src[i++];
            while (k < end) dst[o++] = src[k++];
        }
        swap = src;
        src = dst;
        dst = swap;
    }
    if (src != run) memcpy(run, src, (size_t)len * sizeof(pvsr_horizon_piece));
}

/* Each piece's reach: the highest top of it and the pieces before it in the run, rounded up to a float, so
 * that a test skips at once the pieces that all lie below its range (and only those). */
static void hz_reach(pvsr_horizon_piece* run, uint32_t len) {
    double top = -HUGE_VAL;
    uint32_t i;
    for (i = 0; i < len; ++i) {
        float r;
        top = hz_max(top, hz_max(run[i].hi[0], run[i].hi[1]));
        r = top > FLT_MAX ? FLT_MAX : top < -FLT_MAX ? -FLT_MAX : (float)top;
        if ((double)r < top) r = nextafterf(r, FLT_MAX);
        run[i].reach = r;
    }
}

void pvsr_horizon_end(pvsr_horizon* h) {
    const uint32_t n = h != NULL ? 8u * (uint32_t)h->columns : 0u; /* nodes: 2 * columns a frame */
    uint32_t j;
    size_t i;
    /* Once: the sorts take the unsorted pieces as their scratch. */
    if (h == NULL || !h->ok || !h->eye_ok || h->ready) return;
    memset(h->first, 0, (n + 1) * sizeof(uint32_t));
    for (i = 0; i < h->count; ++i) ++h->first[h->pieces[i].column + 1];
    for (j = 0; j < n; ++j) h->first[j + 1] += h->first[j];
    for (i = 0; i < h->count; ++i) h->sorted[h->first[h->pieces[i].column]++] = h->pieces[i];
    for (j = n; j > 0; --j) h->first[j] = h->first[j - 1];
    h->first[0] = 0;
    for (j = 0; j < n; ++j) { /* each node's pieces by bottom, with their reach */
        const uint32_t start = h->first[j], len = h->first[j + 1] - start;
        pvsr_horizon_piece* run = h->sorted + start;
        hz_sort(run, h->pieces + start, len);
        hz_reach(run, len);
    }
    h->ready = 1;
}

/* The tags of the pieces of the chains a test found (up to HZ_USES), and scratch for one node's candidates.
 */
typedef struct hz_uses {
    uint32_t tag[HZ_USES];
    int count;
    int16_t ref[HZ_CANDIDATES];
} hz_uses;

/* A piece on the path of a test down the tree, with its sides in u. */
typedef struct hz_ref {
    const pvsr_horizon_piece* piece;
    double u0, u1, per_width; /* the piece's sides in u; per_width: 1 / (u1 - u0) */
} hz_ref;

/* Appends to refs the pieces of frame fr's node that reach v_min and start below v_max somewhere in it (up
 * to HZ_CANDIDATES in all); returns the new count. */
static int hz_gather(const pvsr_horizon* h, int fr, uint32_t node, double v_min, double v_max, hz_ref* refs,
                     int n) {
    const int cols = h->columns;
    uint32_t level = 0, x, lo_e = h->first[(uint32_t)(fr * 2 * cols) + node],
             hi_e = h->first[(uint32_t)(fr * 2 * cols) + node + 1], end = hi_e;
    int w, k;
    double u0, u1, per_width, above;
    if (lo_e == hi_e) return n;
    above = v_max + HZ_TOUCH * (1.0 + fabs(v_max));
    for (x = node; x > 1; x >>= 1) ++level;
    w = cols >> level;
    k = (int)(node - (1u << level)) * w;
    u0 = -1.0 + 2.0 * k / cols;
    u1 = -1.0 + 2.0 * (k + w) / cols;
    per_width = cols / (2.0 * w);
    while (lo_e < end) { /* the first piece whose reach is not below v_min: those before it lie below */
        const uint32_t mid = lo_e + (end - lo_e) / 2;
        if ((double)h->sorted[mid].reach < v_min)
            lo_e = mid + 1;
        else
            end = mid;
    }
    for (; lo_e < hi_e && n < HZ_CANDIDATES; ++lo_e) {
        const pvsr_horizon_piece* pc = &h->sorted[lo_e];
        if (hz_bottom(pc) > above) break; /* it and the rest lie above the box: a chain never needs them */
        if (pc->hi[0] < v_min && pc->hi[1] < v_min) continue;
        refs[n].piece = pc;
        refs[n].u0 = pc->u[0];
        refs[n].u1 = pc->u[1];
        refs[n].per_width =
            pc->u[0] == u0 && pc->u[1] == u1 ? per_width : 1.0 / ((double)pc->u[1] - pc->u[0]);
        ++n;
    }
    return n;
}

/* The least depth d > 0 at which a point of direction coordinate w in [w0, w1] has its coordinate w d in
 * [lo, hi] (the box's range along that axis, less the eye): 0 when [lo, hi] holds 0, HUGE_VAL when no
 * direction of [w0, w1] reaches it. */
static double hz_entry(double w0, double w1, double lo, double hi) {
    if (lo > 0.0) return w1 > 0.0 ? lo / w1 : HUGE_VAL;
    if (hi < 0.0) return w0 < 0.0 ? hi / w0 : HUGE_VAL;
    return 0.0;
}

/* The greatest depth at which a point of direction coordinate w in [w0, w1] has its coordinate w d in
 * [lo, hi]: HUGE_VAL when [w0, w1] holds 0, 0 when no direction of it reaches the range. */
static double hz_exit(double w0, double w1, double lo, double hi) {
    if (w0 > 0.0) return hi > 0.0 ? hi / w0 : 0.0;
    if (w1 < 0.0) return lo < 0.0 ? lo / w1 : 0.0;
    return HUGE_VAL;
}

/* 1 when every point of the box part (its least depth, ranges across and up, part[0 .. 4], and greatest
 * depth part[5], less the eye) lies beyond the plane of a piece's depth (1 / depth = g[0] + g[1] u + g[2] v,
 * so a point x lies beyond it when g[0] d + g[1] x_h + g[2] x_y > 1): then along each direction of the piece
 * its occluder is met before any point of the box, however the two extend in depth
 * (docs/ALGORITHMS.md#runtime-horizon). The least of that linear function over the box, by 10^-9 of its
 * terms' size more than 1. */
static int hz_beyond(const double g[3], const double part[6]) {
    const double t0 = g[0] > 0.0 ? g[0] * part[0] : g[0] < 0.0 ? g[0] * part[5] : 0.0;
    const double t1 = g[1] > 0.0 ? g[1] * part[1] : g[1] < 0.0 ? g[1] * part[2] : 0.0;
    const double t2 = g[2] > 0.0 ? g[2] * part[3] : g[2] < 0.0 ? g[2] * part[4] : 0.0;
    return t0 + t1 + t2 - 1.0 > HZ_DEPTH * (1.0 + fabs(t0) + fabs(t1) + fabs(t2));
}

/* Is [a, b] x [v_min, v_max] covered by the pieces of refs[0 .. n) (a node's and its ancestors', whose
 * columns hold [a, b]) that lie wholly before the box in the directions they serve, or that it lies wholly
 * beyond (hz_beyond)? part: the box's part in the frame, its least depth d_lo, its ranges across (h) and up
 * (v), less the eye, and its greatest depth; the box's least depth over a rectangle of directions is
 * max(d_lo, hz_entry across, hz_entry up). Each piece's chords are taken at
 * a and b; the candidates, sorted by their bottom on [a, b], are chained from v_min as
 * docs/ALGORITHMS.md#runtime-horizon says: a chain that holds at a and at b holds between them, every chord
 * being linear. */
static int hz_covered(const hz_ref* refs, int n, double a, double b, const double part[6], double v_min,
                      double v_max, hz_uses* uses) {
    const double d_lo = part[0], d_u = hz_max(d_lo, hz_entry(a, b, part[1], part[2]));
    const double goal = v_max + HZ_ROUND * (1.0 + fabs(v_max));
    double la[HZ_CANDIDATES], lb[HZ_CANDIDATES], ha[HZ_CANDIDATES], hb[HZ_CANDIDATES], key[HZ_CANDIDATES];
    double sa[HZ_FRONT], sb[HZ_FRONT], top = v_min;
    uint16_t order[HZ_CANDIDATES]; /* the candidates by key */
    int16_t from[HZ_CANDIDATES], line[HZ_FRONT]; /* with uses: the chains, back to v_min (-1) */
    int nc = 0, ns = 1, covered = -1, pass, again, i, o, r;
    for (r = 0; r < n; ++r) {
        const pvsr_horizon_piece* pc = refs[r].piece;
        const double ta = hz_min(1.0, hz_max(0.0, (a - refs[r].u0) * refs[r].per_width));
        const double tb = hz_min(1.0, hz_max(ta, (b - refs[r].u0) * refs[r].per_width));
        const double qa = pc->hi[0] + (pc->hi[1] - pc->hi[0]) * ta,
                     qb = pc->hi[0] + (pc->hi[1] - pc->hi[0]) * tb;
        double pa, pb, kk;
        int at;
        if (a < refs[r].u0 || b > refs[r].u1) continue; /* a face's end: not across all of [a, b] */
        if (qa < v_min && qb < v_min) continue;         /* below the box here */
        pa = pc->lo[0] + (pc->lo[1] - pc->lo[0]) * ta;
        pb = pc->lo[0] + (pc->lo[1] - pc->lo[0]) * tb;
        if (!(d_u > pc->depth) && !hz_beyond(pc->plane, part)) {
            /* Deeper than the box somewhere in its node: over the part that can serve the box alone? That
             * part lies in [a, b] x [vlo, vhi], the piece's range over [a, b] within the box's, where the
             * box's points lie at depth d_here or more. */
            const double* g = pc->plane;
            const double ga = g[0] + g[1] * a, gb = g[0] + g[1] * b;
            const double vlo = hz_max(hz_min(pa, pb), v_min), vhi = hz_min(hz_max(qa, qb), v_max);
            const double d_here = hz_max(d_u, hz_entry(vlo, vhi, part[3], part[4]));
            const double gmin =
                hz_min(hz_min(ga + g[2] * vlo, ga + g[2] * vhi), hz_min(gb + g[2] * vlo, gb + g[2] * vhi));
            if (!(d_here > pc->depth) && (!(gmin > 0.0) || !(d_here * gmin > 1.0 + HZ_DEPTH)))
                continue; /* d_here > (1 / gmin)(1 + HZ_DEPTH) */
        }
        kk = hz_min(pa, pb);
        la[nc] = pa;
        lb[nc] = pb;
        ha[nc] = qa;
        hb[nc] = qb;
        key[nc] = kk;
        from[nc] = (int16_t)r; /* the candidate's ref, until the chains are walked */
        for (at = nc; at > 0 && key[order[at - 1]] > kk; --at) order[at] = order[at - 1];
        order[at] = (uint16_t)nc;
        ++nc;
    }
    if (uses != NULL) /* keep each candidate's ref apart; from[] then holds where its chain came from */
        for (i = 0; i < nc; ++i) {
            uses->ref[i] = from[i];
            from[i] = -1;
        }
    line[0] = -1;
    sa[0] = sb[0] = v_min;
    /* Walks again (up to HZ_PASSES in all) when a piece was passed over before a line that it would have met
     * was reached. */
    for (pass = 0, again = 1; pass < HZ_PASSES && again && covered < 0; ++pass) {
        int passed_over = 0;
        again = 0;
        for (o = 0; o < nc && covered < 0; ++o) {
            const int e = order[o];
            int usable = 0, m, via = 0;
            if (key[e] > top + HZ_TOUCH * (1.0 + fabs(top))) break; /* a gap under every line */
            for (i = 0; i < ns && !usable; ++i) {
                /* Pieces meet within HZ_TOUCH (their ends, rounded); the first one must reach v_min itself.
                 */
                const double ta = line[i] < 0 ? 0.0 : HZ_TOUCH * (1.0 + fabs(sa[i]));
                const double tb = line[i] < 0 ? 0.0 : HZ_TOUCH * (1.0 + fabs(sb[i]));
                if (la[e] <= sa[i] + ta && lb[e] <= sb[i] + tb) {
                    usable = 1;
                    via = i;
                }
            }
            if (!usable) {
                passed_over = 1;
                continue;
            }
            if (ha[e] > goal && hb[e] > goal) { /* covered: the chain ends here */
                covered = e;
                from[e] = line[via];
                break;
            }
            for (i = 0; i < ns && usable; ++i) usable = !(sa[i] >= ha[e] && sb[i] >= hb[e]);
            if (!usable) continue; /* no higher than a line already reached */
            from[e] = line[via];
            for (i = m = 0; i < ns; ++i) /* keep the lines it does not pass at both ends */
                if (!(ha[e] >= sa[i] && hb[e] >= sb[i])) {
                    sa[m] = sa[i];
                    sb[m] = sb[i];
                    line[m++] = line[i];
                }
            if (m == HZ_FRONT) --m; /* full: the newest line replaces the last */
            sa[m] = ha[e];
            sb[m] = hb[e];
            line[m] = (int16_t)e;
            ns = m + 1;
            top = hz_max(top, hz_max(ha[e], hb[e]));
            again |= passed_over;
        }
    }
    if (covered >= 0 && uses != NULL) /* the chain's pieces, back from the one that reached v_max */
        for (i = covered; i >= 0 && uses->count < HZ_USES; i = from[i])
            uses->tag[uses->count++] = refs[uses->ref[i]].piece->tag;
    return covered >= 0;
}

/* Is the box's part with u in [ua, ub] covered by refs[0 .. n)? part: the box's part in the frame, its depths
 * [d_lo, d_hi] and its ranges across (h) and up (y), less the eye. Its points there lie at depths
 * [d_in, d_out], so their directions at v within the bounds those give (widened for rounding), met with
 * [v_min, v_max] (docs/ALGORITHMS.md#runtime-horizon). */
static int hz_range_covered(const hz_ref* refs, int n, double ua, double ub, const double part[6],
                            double v_min, double v_max, hz_uses* uses) {
    const double d_in = hz_max(part[0], hz_entry(ua, ub, part[2], part[3]));
    const double d_out = hz_max(d_in, hz_min(part[1], hz_exit(ua, ub, part[2], part[3])));
    const double lo_v = hz_min(part[4] / d_in, part[4] / d_out),
                 hi_v = hz_max(part[5] / d_in, part[5] / d_out);
    const double range_part[6] = {d_in, part[2], part[3], part[4], part[5], d_out};
    return hz_covered(refs, n, ua, ub, range_part, hz_max(v_min, lo_v - HZ_ROUND * (1.0 + fabs(lo_v))),
                      hz_min(v_max, hi_v + HZ_ROUND * (1.0 + fabs(hi_v))), uses);
}

/* A leaf's test cut at the ends of its faces' end pieces (refs[first .. n), those ending inside (a, b)):
 * each part of [a, b] between two cuts is covered by its own chain, the pieces across it (the end pieces
 * that span it with the full ones), against the box's part in those directions. 0 when there is no cut or
 * a part is left open. */
static int hz_split_covered(const hz_ref* refs, int first, int n, double a, double b, const double part[6],
                            double v_min, double v_max, hz_uses* uses) {
    double cut[HZ_CUTS + 2];
    int nc = 1, i, j;
    cut[0] = a;
    for (i = first; i < n && nc < HZ_CUTS + 1; ++i)
        for (j = 0; j < 2 && nc < HZ_CUTS + 1; ++j) {
            const double x = j == 0 ? refs[i].u0 : refs[i].u1;
            int at;
            if (!(x > a && x < b)) continue;
            for (at = nc; at > 1 && cut[at - 1] > x; --at) cut[at] = cut[at - 1];
            cut[at] = x;
            ++nc;
        }
    if (nc == 1) return 0;
    cut[nc++] = b;
    for (i = 0; i + 1 < nc; ++i)
        if (cut[i + 1] > cut[i] && !hz_range_covered(refs, n, cut[i], cut[i + 1], part, v_min, v_max, uses))
            return 0;
    return 1;
}

static int hz_hidden(const pvsr_horizon* h, const float box[6], hz_uses* uses) {
    hz_ref path[HZ_CANDIDATES];
    double lo[3], hi[3];
    int fr, a;
    if (h == NULL || !h->ok || !h->eye_ok || !h->ready || box == NULL) return 0;
    for (a = 0; a < 3; ++a) {
        if (!isfinite(box[a]) || !isfinite(box[3 + a]) || box[a] > box[3 + a]) return 0;
        lo[a] = (double)box[a] - h->eye[a];
        hi[a] = (double)box[3 + a] - h->eye[a];
    }
    for (fr = 0; fr < 4; ++fr) {
        const int cols = h->columns;
        int p, hx, k0, k1, depth = 0, n_path = 0, path_len[HZ_STACK];
        uint32_t x, y, t, stack[HZ_STACK];
        double s, d_lo, d_hi, h_lo, h_hi, near_h, u_min, u_max, v_min, v_max;
        hz_frame(fr, &p, &hx, &s);
        d_lo = s > 0.0 ? lo[p] : -hi[p];
        d_hi = s > 0.0 ? hi[p] : -lo[p];
        h_lo = lo[hx];
        h_hi = hi[hx];
        /* The box's part in the frame's wedge d >= |x_h|: its depths, directions and heights bounded from
         * the box's ranges. */
        near_h = (h_lo <= 0.0 && h_hi >= 0.0) ? 0.0 : hz_min(fabs(h_lo), fabs(h_hi));
        d_lo = hz_max(d_lo, near_h);
        if (d_lo > d_hi) continue; /* no point of the box in this frame */
        if (!(d_lo > HZ_NEAR)) return 0;
        u_min = hz_max(-1.0, hz_min(h_lo / d_lo, h_lo / d_hi));
        u_max = hz_min(1.0, hz_max(h_hi / d_lo, h_hi / d_hi));
        v_min = hz_min(lo[1] / d_lo, lo[1] / d_hi);
        v_max = hz_max(hi[1] / d_lo, hi[1] / d_hi);
        k0 = (int)floor((u_min + 1.0) * 0.5 * cols);
        k1 = (int)floor((u_max + 1.0) * 0.5 * cols);
        if (k0 < 0) k0 = 0;
        if (k1 > cols - 1) k1 = cols - 1;
        if (k0 > k1) k0 = k1;
        /* From the smallest node holding columns k0 .. k1 down: a node whose pieces (with its ancestors')
         * cover the box's part of its columns settles them; else its children that the box reaches are
         * tried; a column (a leaf) left uncovered leaves the box visible. */
        x = (uint32_t)(cols + k0);
        y = (uint32_t)(cols + k1);
        while (x != y) {
            x >>= 1;
            y >>= 1;
        }
        /* The pieces of the path: the ancestors' first, then each node's own after its ancestors'. */
        for (t = x >> 1; t >= 1; t >>= 1) n_path = hz_gather(h, fr, t, v_min, v_max, path, n_path);
        stack[depth] = x;
        path_len[depth++] = n_path;
        while (depth > 0) {
            const uint32_t node = stack[--depth];
            uint32_t level = 0;
            int w, k, c, n;
            for (t = node; t > 1; t >>= 1) ++level;
            w = cols >> level;
            k = (int)(node - (1u << level)) * w;
            n = hz_gather(h, fr, node, v_min, v_max, path, path_len[depth]);
            /* A node of none of its own pieces is left to its children (what covers it covers them). */
            if (n > path_len[depth] || w == 1) { /* the box's part over the node's columns */
                const double ua = hz_max(u_min, -1.0 + 2.0 * k / cols),
                             ub = hz_min(u_max, -1.0 + 2.0 * (k + w) / cols);
                const double part[6] = {d_lo, d_hi, h_lo, h_hi, lo[1], hi[1]};
                if (hz_range_covered(path, n, ua, ub, part, v_min, v_max, uses)) continue;
                if (w == 1 && hz_split_covered(path, path_len[depth], n, ua, ub, part, v_min, v_max, uses))
                    continue;
            }
            if (w == 1 || depth + 2 > HZ_STACK) return 0;
            for (c = 1; c >= 0; --c) { /* the children the box's columns reach */
                const int ck = k + c * (w / 2);
                if (ck <= k1 && ck + w / 2 - 1 >= k0) {
                    stack[depth] = 2 * node + (uint32_t)c;
                    path_len[depth++] = n;
                }
            }
        }
    }
    return 1;
}

int pvsr_horizon_is_hidden(const pvsr_horizon* h, const float box[6]) {
    return hz_hidden(h, box, NULL);
}

int pvsr_horizon_hidden_by(const pvsr_horizon* h, const float box[6], pvsr_horizon_use_fn use, void* user) {
    hz_uses uses;
    int i;
    uses.count = 0;
    if (!hz_hidden(h, box, &uses)) return 0;
    if (use != NULL)
        for (i = 0; i < uses.count; ++i) use(user, uses.tag[i]);
    return 1;
}

void pvsr_horizon_set_tag(pvsr_horizon* h, uint32_t tag) {
    if (h != NULL) h->tag = tag;
}

/* ---- The cell's horizon occluders (file 2.1) ---- */

/* A reader of a cell's list in 'HLST': LEB128 gaps (files 2.1 to 3.x), or from 5.0 a key row of the PVS code
 * less its reference (its head and Rice codes, checked at open: check_horizon), read by gap_next. */
typedef struct hz_list {
    const uint8_t *p, *end; /* LEB128: the bytes left */
    uint64_t next;          /* LEB128: the least index the next entry may have */
    gap_reader rice;        /* 5.0 */
    int is_rice;
    gap_reader pick; /* 5.2, lists per cell: the positions in the block's list the cell keeps */
    int picking;
    uint32_t at; /* the position of the block's next entry */
} hz_list;

/* A key row (checked at open) at [p, end) read by g, its entries below limit. */
static void hz_code_open(gap_reader* g, const uint8_t* p, const uint8_t* end, uint32_t limit) {
    uint64_t head = 0;
    if (p < end) checked_varint(&p, end, &head);
    gap_init(g, p, (uint32_t)(head >> 5), (uint32_t)(head & 31), limit);
}

/* Opens the cell's list: its block's, and from 5.2, where the file has lists per cell, the positions in it
 * that the cell keeps; 0 when the file has no lists (or the cell none). */
static int hz_list_open(const pvsr_level* l, uint32_t cell, hz_list* r) {
    uint32_t b;
    memset(r, 0, sizeof *r);
    if (l == NULL || l->horizon_list_offsets.at == NULL || cell >= l->cell_count) return 0;
    b = palette_block(l, cell);
    r->p = l->horizon_lists.at + rd32(l->horizon_list_offsets.at + 4 * (uint64_t)b);
    r->end = l->horizon_lists.at + rd32(l->horizon_list_offsets.at + 4 * (uint64_t)b + 4);
    if (l->version_major >= 5) {
        r->is_rice = 1;
        hz_code_open(&r->rice, r->p, r->end, hz_limit(l));
        if (l->horizon_cell_offsets.at != NULL) {
            r->picking = 1;
            hz_code_open(&r->pick,
                         l->horizon_cell_lists.at + rd32(l->horizon_cell_offsets.at + 4 * (uint64_t)cell),
                         l->horizon_cell_lists.at + rd32(l->horizon_cell_offsets.at + 4 * (uint64_t)cell + 4),
                         hz_limit(l));
        }
    }
    return 1;
}

/* The next occluder of a list, or UINT32_MAX at its end (or where a damaged list leaves its bytes or the
 * occluders, or a cell's position passes its block's list). */
static uint32_t hz_list_next(const pvsr_level* l, hz_list* r) {
    uint64_t gap;
    if (r->picking) {
        const uint32_t want = gap_next(&r->pick);
        if (want == UINT32_MAX) return UINT32_MAX;
        for (;;) { /* positions ascend: the block's list is read once */
            const uint32_t o = gap_next(&r->rice);
            if (o == UINT32_MAX) return UINT32_MAX;
            if (r->at++ == want) return o;
        }
    }
    if (r->is_rice) return gap_next(&r->rice); /* PVSR_END is UINT32_MAX */
    if (!checked_varint(&r->p, r->end, &gap)) return UINT32_MAX;
    r->next += gap;
    if (r->next >= hz_limit(l)) {
        r->p = r->end;
        return UINT32_MAX;
    }
    return (uint32_t)(r->next)++;
}

uint32_t pvsr_horizon_occluder_count(const pvsr_level* l) {
    return l == NULL ? 0 : hz_limit(l);
}

uint32_t pvsr_horizon_list_count(const pvsr_level* l, uint32_t cell) {
    hz_list r;
    uint32_t n = 0;
    if (!hz_list_open(l, cell, &r)) return 0;
    while (hz_list_next(l, &r) != UINT32_MAX) ++n;
    return n;
}

uint32_t pvsr_horizon_begin_cell(pvsr_horizon* h, const pvsr_level* l, uint32_t cell, const float eye[3]) {
    hz_list r;
    uint32_t n = 0, o;
    if (h == NULL) return 0;
    pvsr_horizon_begin(h, eye);
    if (hz_list_open(l, cell, &r))
        while ((o = hz_list_next(l, &r)) != UINT32_MAX) {
            pvsr_horizon_set_tag(h, o);
            if (o < l->horizon_boxes.count) {
                const uint8_t* b = l->horizon_boxes.at + 24 * (uint64_t)o;
                float box[6];
                int a;
                for (a = 0; a < 6; ++a) box[a] = rdf(b + 4 * a);
                pvsr_horizon_add_box(h, box);
            } else {
                const uint8_t* t =
                    l->horizon_tiles.at + PVSR_POLYGON_BYTES * (uint64_t)(o - l->horizon_boxes.count);
                float plane[5], corners[3 * PVSR_HORIZON_MAX_CORNERS];
                const uint32_t first = rd32(t + 20), count = rd32(t + 24);
                uint32_t k;
                for (k = 0; k < 5; ++k) plane[k] = rdf(t + 4 * k);
                for (k = 0; k < 3 * count; ++k)
                    corners[k] = rdf(l->horizon_corners.at + 12 * (uint64_t)first + 4 * k);
                pvsr_horizon_add_tile(h, plane, corners, count);
            }
            ++n;
        }
    pvsr_horizon_end(h);
    return n;
}
