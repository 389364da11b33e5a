// SPDX-License-Identifier: MIT
// pvsbake runtime loader: load a bake file (docs/FORMAT.md) at level load, then every frame find the
// camera's cell and walk its potentially visible set. Links the HDF5 C library only; no exceptions leave
// it, no global state; a loaded Bake is immutable, so any number of threads may query it at once. load()
// may run on any thread: it turns HDF5's automatic error printing off for its own calls and puts back
// what was set (per thread in a thread-safe HDF5 build such as Debian's, which also serializes loads).
//
// Conventions: glTF axes (right-handed, +Y up), metres. Object and cell indices are those of the file:
// objects 0 .. object_count() - 1, cells 0 .. cell_count() - 1. A bake whose is_conservative() is true
// lists every object any eye in a cell may see ("conservative": never a missing object); otherwise it is
// "aggressive" (sampled: tight, but it may miss small or grazing objects) and mode_label() says so.
// A point outside the view volume (where eyes can be) has no cell: find_cell() returns -1, and a game
// should then draw everything.
//
// Costs: load() reads and validates everything (indices in range, sizes consistent; the PVS code by its
// checksum in format 1.4 files, and its walks are bounded), so queries check nothing but the index they
// are given, and never allocate. find_cell() is O(1) on a grid, O(depth) on an
// octree. Walking a cell's PVS costs O(visible objects); is_visible() is O(visible objects) too.
//
// The PVS rows are held compressed (docs/FORMAT.md, "The PVS code"): each distinct row once, as the gaps
// between visible object indices, Rice-coded; a row may be coded as its difference (XOR) from a "key" row
// of similar cells. Walking decodes on the fly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pvsbake {

// What load() found. Values are stable (the C API uses the same numbers).
enum class Status : int32_t {
    kOk = 0,
    kFileMissing = 1,      // no file at that path
    kNotBakeFile = 2,      // not HDF5, or HDF5 without format = "pvsbake" (also: a folder)
    kVersionTooNew = 3,    // a newer major format version than this loader reads
    kCorrupt = 4,          // damaged or inconsistent: a size, type, index or code that does not fit
    kOutOfMemory = 5,      // the bake does not fit in memory
    kIoError = 6,          // the file exists but cannot be read (permissions, read error)
    kInvalidArgument = 7,  // C API: a null pointer where one is required
};

// "ok", "file missing", ... (static strings).
const char* status_name(Status status) noexcept;

struct LoadResult {
    Status status = Status::kOk;
    std::string message;  // empty when ok; else one line: "<path>: what is wrong"
    explicit operator bool() const { return status == Status::kOk; }
};

// An axis-aligned box in metres. An empty box has min = +inf and max = -inf.
struct Box {
    float min[3];
    float max[3];
};

// One ranked occluder of a cell (format 1.2; docs/FORMAT.md, "/occluders"): a box inside the opaque solid,
// worth testing at run time to cull what the PVS cannot list (dynamic objects). Its shadow frustum from the
// eye (the points q for which the segment eye-q meets the box) hides whatever lies wholly inside it.
struct RankedOccluder {
    Box box;                      // the occluder box, world metres (already shrunk/proven as stored)
    float score;                  // the documented ranking score, higher is better
    float solid_angle_sr;         // largest solid angle seen from the cell's sampled eyes, steradians
    float hidden_objects;         // mean number of objects wholly in its shadow from the sampled eyes
    float hidden_triangle_share;  // mean share of the world's triangles wholly in its shadow
};

// One ranked POLYGON occluder of a cell (format 1.7; docs/FORMAT.md, "/occluders"): a slanted panel of the
// opaque surface for the run-time culler's faces test (OcclusionCuller::add_polygon takes plane and corners).
struct RankedPolygon {
    const float* plane = nullptr;    // normal x, y, z, offset, thickness (in the Bake's memory)
    const float* corners = nullptr;  // `count` corners of 3 floats, convex, counter-clockwise from +normal
    uint32_t count = 0;              // 3 to 8
    uint32_t place = 0;              // its place in the cell's whole list of ranked occluders (0 = the best)
    float score = 0.0f;              // the documented ranking score, higher is better
};

enum class CellKind : int32_t { kGrid = 0, kOctree = 1 };

// What a bake is: the root attributes of the file (docs/FORMAT.md).
struct BakeInfo {
    int format_major = 0;
    int format_minor = 0;
    std::string tool_version;   // of the pvsbake that wrote it
    std::string world_path;     // the world file as given to pvsbake
    std::string world_hash;     // content hash of the world file (hex)
    std::string mode;           // "sampled" or "conservative"
    bool conservative = false;  // false: aggressive (may miss visible objects)
};

// The bake's PVS sizes (docs/FORMAT.md, /pvs attributes) and what the loader holds in memory.
struct PvsStats {
    uint64_t cell_count = 0;
    uint64_t object_count = 0;
    uint64_t unique_rows = 0;    // distinct rows (identical rows are stored once)
    uint64_t bytes_per_row = 0;  // ceil(object_count / 8)
    uint64_t bytes_raw = 0;      // cell_count * bytes_per_row: the plain bit sets
    uint64_t bytes_stored = 0;   // what the file spends on the deflated rows and cell_row
    uint64_t bytes_code = 0;     // the PVS in memory: row code, row offsets, cell_row
    uint64_t memory_bytes = 0;   // everything this Bake holds (PVS, cells, lookup, objects, strings)
};

namespace detail {

constexpr uint32_t kEnd = UINT32_MAX;

// 57 or more bits from bit `at` of p (bit 0 = the lowest bit of p[0]): reads the 8 bytes from p[at / 8].
inline uint64_t peek_bits(const uint8_t* p, uint64_t at) {
    uint64_t w;
    std::memcpy(&w, p + (at >> 3), 8);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    w = __builtin_bswap64(w);
#endif
    return w >> (at & 7);
}

// Reads the Rice-coded gaps of one row (docs/FORMAT.md, "The PVS code"): object indices in increasing
// order, then kEnd. Bounded: it never returns an index >= limit (the object count) and ends there, and it
// reads at most 27 bits an object plus 16 bytes past the row's start, whatever the bits (the loader pads
// the code that much: row_code.h, code_padding), so even code that passed only the heads' check
// (check_row_heads) cannot take it out of range.
class GapReader {
public:
    GapReader() = default;
    GapReader(const uint8_t* bits, uint32_t count, uint32_t k, uint32_t limit)
        : bits_(bits), left_(count), k_(k), limit_(limit) {}

    uint32_t next() {
        if (left_ == 0) return kEnd;
        --left_;
        uint64_t w = peek();
        if (w != 0) {  // the usual case: the unary part and the low bits within one 57-bit window
            const uint32_t z = uint32_t(__builtin_ctzll(w));
            if (z + 1 + k_ <= 57) {
                const uint32_t low = uint32_t(w >> (z + 1)) & ((uint32_t(1) << k_) - 1);
                pos_ += z + 1 + k_;
                last_ += 1 + ((z << k_) | low);  // < 2^31: last_ < limit_ <= 2^27, z < 57, k_ <= 24
                return last_ < limit_ ? last_ : stop();
            }
        }
        uint64_t q = 0;
        for (;;) {
            w = peek();
            if (w != 0) {
                const uint32_t z = uint32_t(__builtin_ctzll(w));
                q += z;
                pos_ += z + 1;
                break;
            }
            const uint32_t valid = 64 - uint32_t(pos_ & 7);  // all real bits seen were zero
            q += valid;
            pos_ += valid;
            if (q > limit_) return stop();
        }
        if (q > limit_) return stop();
        const uint64_t low = peek() & ((uint64_t(1) << k_) - 1);
        pos_ += k_;
        const uint64_t next = uint64_t(last_) + 1 + ((q << k_) | low);  // last_ + 1 wraps to 0 at the start
        if ((next & 0xffffffffu) >= limit_ || (q << k_) >= limit_) return stop();
        last_ = uint32_t(next);
        return last_;
    }

private:
    uint64_t peek() const { return peek_bits(bits_, pos_); }
    uint32_t stop() {
        left_ = 0;
        return kEnd;
    }

    const uint8_t* bits_ = nullptr;
    uint64_t pos_ = 0;  // bit position, bit 0 = lowest bit of byte 0
    uint32_t left_ = 0;
    uint32_t k_ = 0;
    uint32_t limit_ = 0;
    uint32_t last_ = UINT32_MAX;  // + 1 wraps to 0
};

// A varint (7 bits a byte, low first) of validated code.
inline uint32_t read_varint(const uint8_t*& p) {
    uint32_t v = 0;
    for (int shift = 0;; shift += 7) {
        const uint8_t b = *p++;
        v |= uint32_t(b & 0x7f) << shift;
        if ((b & 0x80) == 0) return v;
    }
}

// Indices kept in 16 bits when every value fits, else 32: the row of each cell and where each row's code
// starts weigh as much as the code itself on small bakes (a few bytes a row).
class IndexArray {
public:
    void assign(std::vector<uint32_t>&& values) {
        uint32_t top = 0;
        for (uint32_t v : values) top = v > top ? v : top;
        if (top <= UINT16_MAX) {
            narrow_.assign(values.begin(), values.end());
            std::vector<uint32_t>().swap(wide_);
        } else {
            wide_ = std::move(values);
            std::vector<uint16_t>().swap(narrow_);
        }
        size_ = narrow_.size() + wide_.size();
    }
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    uint32_t operator[](size_t i) const { return wide_.empty() ? narrow_[i] : wide_[i]; }
    uint64_t bytes() const {
        return uint64_t(narrow_.capacity()) * sizeof(uint16_t) +
               uint64_t(wide_.capacity()) * sizeof(uint32_t);
    }

private:
    std::vector<uint16_t> narrow_;
    std::vector<uint32_t> wide_;
    size_t size_ = 0;
};

}  // namespace detail

class Bake;

// A cell's ranked occluders, best first: a view into a Bake (valid while it lives and is not reloaded).
// Entries are made on access from the Bake's compact arrays, so they come by value.
class OccluderList {
public:
    class Iterator {
    public:
        using iterator_category = std::input_iterator_tag;
        using value_type = RankedOccluder;
        using difference_type = std::ptrdiff_t;
        using pointer = void;
        using reference = RankedOccluder;
        RankedOccluder operator*() const noexcept;
        Iterator& operator++() noexcept {
            ++at_;
            return *this;
        }
        bool operator==(const Iterator& o) const noexcept { return at_ == o.at_; }
        bool operator!=(const Iterator& o) const noexcept { return at_ != o.at_; }

    private:
        friend class OccluderList;
        Iterator(const Bake* bake, uint32_t at) : bake_(bake), at_(at) {}
        const Bake* bake_;
        uint32_t at_;
    };

    OccluderList() = default;
    uint32_t size() const noexcept { return count_; }
    bool empty() const noexcept { return count_ == 0; }
    RankedOccluder operator[](uint32_t rank) const noexcept;  // rank < size(); 0 = best
    Iterator begin() const noexcept { return Iterator(bake_, first_); }
    Iterator end() const noexcept { return Iterator(bake_, first_ + count_); }

private:
    friend class Bake;
    OccluderList(const Bake* bake, uint32_t first, uint32_t count)
        : bake_(bake), first_(first), count_(count) {}
    const Bake* bake_ = nullptr;
    uint32_t first_ = 0, count_ = 0;
};

// A loaded bake. Default-constructed (or after a failed load) it is empty: no cells, no objects.
class Bake {
public:
    Bake() = default;
    Bake(Bake&&) noexcept = default;
    Bake& operator=(Bake&&) noexcept = default;
    Bake(const Bake&) = delete;
    Bake& operator=(const Bake&) = delete;

    // Loads and validates the bake file at path, replacing what this holds. On failure this is empty and
    // the result says why; it never throws or crashes, whatever the file holds.
    LoadResult load(const std::string& path) noexcept;

    bool empty() const { return cell_row_.empty() && object_count_ == 0; }
    uint32_t cell_count() const { return uint32_t(cell_row_.size()); }
    uint32_t object_count() const { return object_count_; }

    // ---- Cells
    // The cell holding p (metres), or -1 outside the view volume or every cell. Same rule as the baker's
    // CellSet::find (core/cell_set.h): grid cells are half-open except on the grid's max face; with a
    // view volume, a point outside its voxels (closed boxes) has no cell.
    int32_t find_cell(float x, float y, float z) const noexcept;
    int32_t find_cell(const float p[3]) const noexcept { return find_cell(p[0], p[1], p[2]); }
    // Is p in the EYE SPACE, the free voxels (closed boxes) where the bake's eyes are? The bake's promises
    // hold for eyes there: the PVS lists everything an eye there can see, and occluders cull only what is
    // hidden from there. find_cell() also answers in a rim one voxel wide around it (up to and into thin
    // walls), where they do not: a game that culls with occluders should do so only when this is true.
    // Bakes without an eye mask: true wherever find_cell() finds a cell.
    bool in_eye_space(float x, float y, float z) const noexcept;
    bool in_eye_space(const float p[3]) const noexcept { return in_eye_space(p[0], p[1], p[2]); }
    CellKind cell_kind() const { return kind_; }
    // The box of cell c (an empty box for c out of range).
    Box cell_bounds(uint32_t c) const noexcept;

    // ---- The potentially visible set of a cell
    // Calls visit(object) for each object visible from cell c, in increasing index order. Allocates
    // nothing. Out-of-range c visits nothing.
    template <class F>
    void for_each_visible(uint32_t c, F&& visit) const {
        if (c >= cell_row_.size()) return;
        detail::GapReader key, diff;
        if (!row_readers(cell_row_[c], key, diff)) {
            for (uint32_t i = key.next(); i != detail::kEnd; i = key.next()) visit(i);
            return;
        }
        if (object_count_ <= 64 * kStackWords) {
            // The key row XOR the difference in a bit set on the stack: branch-light, measured 2-3 times
            // faster than merging the two index streams (whose comparisons the CPU cannot predict).
            uint64_t bits[kStackWords];
            const size_t words = words_per_row();
            std::memset(bits, 0, words * sizeof(uint64_t));
            for (uint32_t i = key.next(); i != detail::kEnd; i = key.next())
                bits[i >> 6] |= uint64_t(1) << (i & 63);
            for (uint32_t i = diff.next(); i != detail::kEnd; i = diff.next())
                bits[i >> 6] ^= uint64_t(1) << (i & 63);
            for (size_t w = 0; w < words; ++w) {
                for (uint64_t b = bits[w]; b != 0; b &= b - 1)
                    visit(uint32_t(w * 64) + uint32_t(__builtin_ctzll(b)));
            }
            return;
        }
        uint32_t a = key.next(), b = diff.next();
        for (;;) {  // the key row XOR the difference: an index in both cancels
            if (a < b) {
                visit(a);
                a = key.next();
            } else if (b < a) {
                visit(b);
                b = diff.next();
            } else {
                if (a == detail::kEnd) return;
                a = key.next();
                b = diff.next();
            }
        }
    }
    // Number of objects visible from cell c.
    uint32_t visible_count(uint32_t c) const noexcept;
    // Is object o visible from cell c? False for out-of-range indices.
    bool is_visible(uint32_t c, uint32_t o) const noexcept;
    // Fills words[0 .. word_count) with the PVS of cell c as a bit set (object i = bit i % 64 of word
    // i / 64; words past the objects are zeroed). Needs word_count >= words_per_row(); returns the number
    // of visible objects, or UINT32_MAX (words untouched) when word_count is too small or c out of range.
    uint32_t fill_bitset(uint32_t c, uint64_t* words, size_t word_count) const noexcept;
    size_t words_per_row() const { return (size_t(object_count_) + 63) / 64; }

    // ---- Objects (o < object_count(); out of range gives "", an empty box, 0)
    std::string_view object_name(uint32_t o) const noexcept;
    const char* object_name_c(uint32_t o) const noexcept;  // NUL-terminated, lives as long as the Bake
    Box object_bounds(uint32_t o) const noexcept;
    uint32_t object_triangles(uint32_t o) const noexcept;
    uint32_t object_flags(
        uint32_t o) const noexcept;  // bit 0 opaque, 1 see-through, 2 always visible, 3 never occludes
    uint64_t total_triangles() const { return total_triangles_; }
    // Format 1.9: object o's part boxes (its triangles split into a few groups, each inside one part, every
    // part inside its bounds; docs/ALGORITHMS.md#object-parts): none (0) or a few; out of range: an empty
    // box.
    uint32_t object_part_count(uint32_t o) const noexcept;
    Box object_part(uint32_t o, uint32_t k) const noexcept;

    // ---- Ranked occluders of a cell (format 1.2): the few occluder boxes worth testing at run time from
    // anywhere in cell c, best first (score = sqrt(mean solid angle / 4 pi * mean hidden share), see
    // docs/FORMAT.md). Files of format 1.0 and 1.1, bakes made without occluders or with
    // --occluders-per-cell 0 have none. Every entry was validated at load (a proven, finite box; finite
    // measures; scores never increasing), so a culler may use them as they are.
    uint32_t occluder_count(uint32_t c) const noexcept;  // 0 for old files / out of range
    OccluderList occluders(uint32_t c) const noexcept;   // best first; empty if none
    // The boxes of the best min(occluder_count(c), capacity) occluders of cell c into out, best first (as
    // OcclusionCuller::begin_frame takes them); returns how many were written.
    uint32_t occluder_boxes(uint32_t c, Box* out, uint32_t capacity) const noexcept;
    // Format 1.7: the cell's ranked polygon occluders, best first. They rank among the boxes: the cell's
    // whole list holds its occluder_count(c) boxes and its occluder_polygon_count(c) polygons, each polygon
    // at its `place`, the boxes in order at the other places. Older files: none.
    uint32_t occluder_polygon_count(uint32_t c) const noexcept;
    // The polygon of rank k among the cell's polygons; false (out untouched) out of range.
    bool occluder_polygon(uint32_t c, uint32_t k, RankedPolygon& out) const noexcept;
    // The cell's list of the run-time horizon's occluders (format 1.8; pvsbake::Horizon builds a frame from
    // it): how many; 0 without lists or out of range.
    uint32_t horizon_list_count(uint32_t c) const noexcept {
        if (c >= horizon_cell_list_.size()) return 0;
        const size_t l = horizon_cell_list_[c];  // validated: below the lists
        return l + 1 < horizon_list_offset_.size() ? horizon_list_offset_[l + 1] - horizon_list_offset_[l]
                                                   : 0;
    }
    // Format 1.10: the objects of cell c's PVS that its frames test with the horizon, ascending, in
    // [first, last) (for_each_drawn gives the horizon only those; docs/ALGORITHMS.md#horizon-tests). False,
    // and nothing set, when the bake kept none (the horizon tests every object) or c is out of range.
    bool horizon_tests(uint32_t c, const uint32_t*& first, const uint32_t*& last) const noexcept {
        if (size_t(c) + 1 >= horizon_test_offset_.size()) return false;
        first = horizon_test_.data() + horizon_test_offset_[c];  // validated: within the tests
        last = horizon_test_.data() + horizon_test_offset_[size_t(c) + 1];
        return true;
    }

    // ---- What the bake is
    const BakeInfo& info() const { return info_; }
    int format_major() const { return info_.format_major; }
    int format_minor() const { return info_.format_minor; }
    const std::string& mode() const { return info_.mode; }  // "sampled" or "conservative"
    bool is_conservative() const { return info_.conservative; }
    const char* mode_label() const { return info_.conservative ? "conservative" : "aggressive"; }
    const std::string& tool_version() const { return info_.tool_version; }
    const std::string& world_path() const { return info_.world_path; }
    const std::string& world_hash() const { return info_.world_hash; }
    // Every resolved option of the bake (name, value as text), in the file's order.
    const std::vector<std::pair<std::string, std::string>>& parameters() const { return parameters_; }
    // The bake's figures (name, value), in the file's order, and the verification's (empty if none ran).
    const std::vector<std::pair<std::string, double>>& figures() const { return figures_; }
    const std::vector<std::pair<std::string, double>>& verification_figures() const {
        return verification_figures_;
    }
    bool verification_ran() const { return verification_ran_; }
    // The first figure or parameter of that name; nullptr when there is none.
    const double* figure(std::string_view name) const noexcept;
    const std::string* parameter(std::string_view name) const noexcept;
    const PvsStats& pvs_stats() const { return stats_; }

private:
    friend class Loading;
    static constexpr size_t kStackWords =
        256;  // rows of up to 16,384 objects are merged on the stack (2 KiB)
    struct Node {
        float center[3];
        int32_t first_child;  // -1: a leaf
        int32_t cell;         // a leaf's cell or -1
    };

    // Sets key (and diff, for a row coded against a key row) to the row's readers; true when there is a diff.
    bool row_readers(uint32_t row, detail::GapReader& key, detail::GapReader& diff) const {
        const uint8_t* p = code_.data() + row_offset_[row];
        const uint32_t ref = detail::read_varint(p);
        const uint32_t head = detail::read_varint(p);
        if (ref == 0) {
            key = detail::GapReader(p, head >> 5, head & 31, object_count_);
            return false;
        }
        diff = detail::GapReader(p, head >> 5, head & 31, object_count_);
        const uint8_t* q = code_.data() + row_offset_[row - ref];
        detail::read_varint(q);  // 0: a key row (validated)
        const uint32_t key_head = detail::read_varint(q);
        key = detail::GapReader(q, key_head >> 5, key_head & 31, object_count_);
        return true;
    }
    Box grid_box(uint32_t grid_index) const;
    bool mask_voxel(bool eyes, int64_t x, int64_t y, int64_t z) const;
    bool mask_contains(bool eyes, float x, float y, float z) const;

    // What the bake is.
    BakeInfo info_;
    bool verification_ran_ = false;
    std::vector<std::pair<std::string, std::string>> parameters_;
    std::vector<std::pair<std::string, double>> figures_, verification_figures_;
    // Objects: names NUL-terminated one after the other.
    uint32_t object_count_ = 0;
    uint64_t total_triangles_ = 0;
    std::vector<char> names_;
    std::vector<uint32_t> name_offset_;  // object_count + 1
    std::vector<Box> object_bounds_;
    std::vector<uint32_t> object_triangles_, object_flags_;
    std::vector<uint32_t> part_offsets_;  // object_count + 1, or empty: no parts
    std::vector<Box> part_boxes_;
    // Cells and lookup.
    CellKind kind_ = CellKind::kGrid;
    float origin_[3] = {0, 0, 0};
    float cell_size_m_ = 0;
    int32_t dims_[3] = {0, 0, 0};
    std::vector<int32_t> grid_to_cell_;
    std::vector<Node> nodes_;          // octree only
    std::vector<Box> cell_bounds_;     // explicit boxes; empty when every grid cell's box is its grid box
    std::vector<uint32_t> cell_grid_;  // grid position of each cell when cell_bounds_ is empty
    // The view volume as 8 x 8 x 8 voxel bricks: brick_[b] is kBrickEmpty, kBrickFull, or the index of
    // its 64 bytes in brick_bytes_ (byte (z % 8) * 8 + (y % 8), bit x % 8).
    bool has_view_ = false;
    float view_origin_[3] = {0, 0, 0};
    float view_voxel_m_ = 0;
    int32_t view_dims_[3] = {0, 0, 0};
    int32_t brick_dims_[3] = {0, 0, 0};
    std::vector<uint32_t> brick_;
    std::vector<uint8_t> brick_bytes_;
    // The eye space (within the view volume, same voxels and bricks).
    bool has_eyes_ = false;
    std::vector<uint32_t> eye_brick_;
    std::vector<uint8_t> eye_brick_bytes_;
    // Ranked occluders, as the file stores them: cell c has entries ranked_offset_[c] ..
    // ranked_offset_[c + 1] (empty offsets: none); entry k is the box ranked_boxes_[ranked_box_[k]] and
    // four measures.
    // The run-time horizon's occluders and lists, as the file stores them (validated by read_horizon).
    friend class Horizon;
    std::vector<float> horizon_boxes_, horizon_tile_planes_, horizon_tile_corners_;
    std::vector<uint32_t> horizon_tile_offset_, horizon_cell_list_, horizon_list_offset_, horizon_list_entry_;
    std::vector<uint32_t> horizon_test_offset_, horizon_test_;  // 1.10: cells + 1 and the tests, or empty
    friend class OccluderList;
    RankedOccluder ranked_entry(uint32_t k) const noexcept {
        return RankedOccluder{ranked_boxes_[ranked_box_[k]], ranked_score_[k], ranked_solid_angle_sr_[k],
                              ranked_hidden_objects_[k], ranked_hidden_triangle_share_[k]};
    }
    detail::IndexArray ranked_offset_;
    std::vector<Box> ranked_boxes_;
    std::vector<uint32_t> ranked_box_;
    std::vector<float> ranked_score_, ranked_solid_angle_sr_, ranked_hidden_objects_,
        ranked_hidden_triangle_share_;
    // Ranked polygons (1.7): cell c has entries ranked_polygon_offset_[c] .. [c + 1]; entry k is polygon
    // ranked_polygon_[k] (corners polygon_offset_[p] .. [p + 1] of polygon_corners_, plane 5 floats at
    // polygon_planes_[5 p]) at place ranked_polygon_place_[k].
    std::vector<uint32_t> polygon_offset_, ranked_polygon_offset_, ranked_polygon_, ranked_polygon_place_;
    std::vector<float> polygon_corners_, polygon_planes_, ranked_polygon_score_;
    // The PVS: row code (plus 8 bytes of padding), where each distinct row starts, and each cell's row.
    std::vector<uint8_t> code_;
    detail::IndexArray row_offset_;
    detail::IndexArray cell_row_;
    PvsStats stats_;
};

inline RankedOccluder OccluderList::Iterator::operator*() const noexcept {
    return bake_->ranked_entry(at_);
}

inline RankedOccluder OccluderList::operator[](uint32_t rank) const noexcept {
    return bake_->ranked_entry(first_ + rank);
}

}  // namespace pvsbake
