// SPDX-License-Identifier: MIT
// pvsbake runtime loader: load() (reads and validates everything through bake_reader.h, then builds the
// lookup structures) and the queries of pvsbake/loader.h. Nothing here throws out of load(); queries are
// noexcept and read only validated data.
#include "pvsbake/loader.h"

#include "bake_reader.h"
#include "mask_bricks.h"
#include "row_code.h"

#include <algorithm>
#include <cmath>
#include <new>

namespace pvsbake {
namespace {

using detail::kBrickFull;
using detail::kFirstBrick;

Box empty_box() {
    const float inf = INFINITY;
    return Box{{inf, inf, inf}, {-inf, -inf, -inf}};
}

Box box_at(const std::vector<float>& flat, size_t i) {
    const float* b = &flat[i * 6];
    return Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
}

bool same_box(const Box& a, const Box& b) {
    return std::memcmp(&a, &b, sizeof(Box)) == 0;
}

}  // namespace

const char* status_name(Status status) noexcept {
    switch (status) {
        case Status::kOk:
            return "ok";
        case Status::kFileMissing:
            return "file missing";
        case Status::kNotBakeFile:
            return "not a bake file";
        case Status::kVersionTooNew:
            return "version too new";
        case Status::kCorrupt:
            return "corrupt";
        case Status::kOutOfMemory:
            return "out of memory";
        case Status::kIoError:
            return "read error";
        case Status::kInvalidArgument:
            return "invalid argument";
    }
    return "unknown status";
}

// Builds a Bake from the validated sections of a file (friend of Bake).
class Loading {
public:
    static void run(const std::string& path, Bake& b) {
        detail::QuietHdf5 quiet;
        uint64_t file_bytes = 0;
        detail::Handle file = detail::open_bake_file(path, file_bytes);
        const detail::Reader r(path, file_bytes);
        detail::Handle root = r.handle(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose, "cannot open /");
        b.info_ = detail::read_header(r, root.get());
        b.parameters_ = detail::read_parameters(r, root.get());
        objects(detail::read_objects(r, root.get()), b);
        detail::FileCells file_cells = detail::read_cells(r, root.get(), /*read_eyes=*/true, /*bricks=*/true);
        const uint32_t cell_count = file_cells.count;
        cells(std::move(file_cells), b);
        pvs(detail::read_pvs(r, root.get(), b.object_count_, cell_count, /*want_rows=*/false), b);
        ranked(detail::read_occluders(r, root.get(), b.object_count_, cell_count, /*want_boxes=*/false), b);
        horizon(detail::read_horizon(r, root.get(), cell_count, b.object_count_), b);
        b.figures_ = r.named_values(root.get(), "/figures");
        detail::Handle v = r.open_group(root.get(), "/verification");
        const int64_t ran = r.int_attr(v.get(), "/verification", "ran");
        if (ran != 0 && ran != 1) r.fail("/verification attribute ran is not 0 or 1");
        b.verification_ran_ = ran == 1;
        b.verification_figures_ = r.named_values(v.get(), "/verification/figures");
        b.stats_.memory_bytes = memory(b);
    }

private:
    static void objects(detail::FileObjects o, Bake& b) {
        b.object_count_ = uint32_t(o.names.size());
        size_t chars = 0;
        for (const std::string& n : o.names) chars += n.size() + 1;
        b.names_.reserve(chars);
        b.name_offset_.reserve(o.names.size() + 1);
        for (const std::string& n : o.names) {
            b.name_offset_.push_back(uint32_t(b.names_.size()));
            b.names_.insert(b.names_.end(), n.begin(), n.end());
            b.names_.push_back('\0');
        }
        b.name_offset_.push_back(uint32_t(b.names_.size()));
        b.object_bounds_.resize(o.names.size());
        for (size_t i = 0; i < o.names.size(); ++i) b.object_bounds_[i] = box_at(o.bounds, i);
        b.object_triangles_ = std::move(o.triangle_count);
        b.object_flags_ = std::move(o.flags);
        b.part_offsets_ = std::move(o.part_offsets);
        b.part_boxes_.resize(o.part_boxes.size() / 6);
        for (size_t i = 0; i < b.part_boxes_.size(); ++i) b.part_boxes_[i] = box_at(o.part_boxes, i);
        for (uint32_t t : b.object_triangles_) b.total_triangles_ += t;
    }

    static void cells(detail::FileCells f, Bake& b) {
        b.kind_ = CellKind(f.kind);
        std::copy(f.origin, f.origin + 3, b.origin_);
        b.cell_size_m_ = f.cell_size_m;
        std::copy(f.dims, f.dims + 3, b.dims_);
        b.grid_to_cell_ = std::move(f.grid_to_cell);
        b.nodes_.resize(f.node_first_child.size());
        for (size_t i = 0; i < b.nodes_.size(); ++i) {
            const Box box = box_at(f.node_bounds, i);
            Bake::Node& n = b.nodes_[i];
            for (int a = 0; a < 3; ++a) n.center[a] = 0.5f * (box.min[a] + box.max[a]);  // as Aabb::center()
            n.first_child = f.node_first_child[i];
            n.cell = f.node_cell[i];
        }
        cell_boxes(f, b);
        view_bricks(f.view, f.eyes, b);
    }

    // A grid cell's box is its grid box (cells/grid.cpp: origin + index * size): then only its grid
    // position is kept (4 bytes, not 24). Any other box (an octree, or a file that says otherwise) is kept.
    static void cell_boxes(const detail::FileCells& f, Bake& b) {
        const uint32_t count = f.count;
        b.cell_grid_.clear();
        b.cell_bounds_.clear();
        bool derived = f.kind == 0;
        if (derived) {
            b.cell_grid_.assign(count, UINT32_MAX);
            for (size_t g = 0; g < b.grid_to_cell_.size() && derived; ++g) {
                const int32_t c = b.grid_to_cell_[g];
                if (c < 0) continue;
                if (b.cell_grid_[size_t(c)] != UINT32_MAX || g > UINT32_MAX) derived = false;
                b.cell_grid_[size_t(c)] = uint32_t(g);
            }
            for (uint32_t c = 0; c < count && derived; ++c) {
                derived = b.cell_grid_[c] != UINT32_MAX &&
                          same_box(b.grid_box(b.cell_grid_[c]), box_at(f.bounds, c));
            }
        }
        if (derived) return;
        std::vector<uint32_t>().swap(b.cell_grid_);
        b.cell_bounds_.resize(count);
        for (uint32_t c = 0; c < count; ++c) b.cell_bounds_[c] = box_at(f.bounds, c);
    }

    // The view mask as 8 x 8 x 8 bricks (io/loader/mask_bricks.h): empty and full bricks cost 4 bytes, mixed
    // ones 68. The eye mask (on the same voxels) the same way, when the file has one. Files before format
    // 1.4 store only the bits: their bricks are made here.
    static void view_bricks(detail::FileMask& m, detail::FileMask& eyes, Bake& b) {
        b.has_view_ = m.present;
        if (!b.has_view_) return;
        std::copy(m.origin, m.origin + 3, b.view_origin_);
        b.view_voxel_m_ = m.voxel_size_m;
        std::copy(m.dims, m.dims + 3, b.view_dims_);
        for (int a = 0; a < 3; ++a) b.brick_dims_[a] = int32_t(detail::bricks_along(m.dims[a]));
        bricks(m, b.brick_, b.brick_bytes_);
        b.has_eyes_ = eyes.present && eyes.voxel_size_m == m.voxel_size_m &&
                      std::equal(eyes.origin, eyes.origin + 3, m.origin) &&
                      std::equal(eyes.dims, eyes.dims + 3, m.dims);
        if (b.has_eyes_) bricks(eyes, b.eye_brick_, b.eye_brick_bytes_);
    }

    static void bricks(detail::FileMask& m, std::vector<uint32_t>& index, std::vector<uint8_t>& bytes) {
        if (!m.brick_index.empty()) {
            index = std::move(m.brick_index);
            bytes = std::move(m.brick_bytes);
            return;
        }
        detail::make_bricks(m.bytes, m.dims, index, bytes);
    }

    static void pvs(detail::FilePvs f, Bake& b) {
        if (f.code_offsets.empty()) {  // a format 1.0 file: code its rows now
            detail::RowCode code =
                detail::encode_rows(f.rows.data(), f.unique_rows, f.row_bytes, b.object_count_);
            code.code.resize(code.code.size() + detail::code_padding(b.object_count_), 0);  // row_code.h
            f.code = std::move(code.code);
            f.code_offsets = std::move(code.offsets);
            std::vector<uint8_t>().swap(f.rows);
        }
        b.code_ = std::move(f.code);
        b.row_offset_.assign(std::move(f.code_offsets));
        b.cell_row_.assign(std::move(f.cell_row));
        PvsStats& s = b.stats_;
        s.cell_count = b.cell_row_.size();
        s.object_count = b.object_count_;
        s.unique_rows = f.unique_rows;
        s.bytes_per_row = f.row_bytes;
        s.bytes_raw = f.bytes_raw;
        s.bytes_stored = f.bytes_stored;
        s.bytes_code = b.code_.size() + b.row_offset_.bytes() + b.cell_row_.bytes();
    }

    // The ranked occluders as the file stores them (validated by read_occluders): the boxes they name, and
    // per entry a box index and four measures.
    static void ranked(detail::FileOccluders f, Bake& b) {
        if (f.ranked_offsets.empty()) return;
        b.ranked_boxes_.resize(size_t(f.count));
        for (size_t i = 0; i < b.ranked_boxes_.size(); ++i) b.ranked_boxes_[i] = box_at(f.bounds, i);
        b.ranked_box_ = std::move(f.ranked_box);
        b.ranked_score_ = std::move(f.ranked_score);
        b.ranked_solid_angle_sr_ = std::move(f.ranked_solid_angle_sr);
        b.ranked_hidden_objects_ = std::move(f.ranked_hidden_objects);
        b.ranked_hidden_triangle_share_ = std::move(f.ranked_hidden_triangle_share);
        b.ranked_offset_.assign(std::move(f.ranked_offsets));
        b.polygon_offset_ = std::move(f.polygon_offsets);
        b.polygon_corners_ = std::move(f.polygon_corners);
        b.polygon_planes_ = std::move(f.polygon_planes);
        b.ranked_polygon_offset_ = std::move(f.ranked_polygon_offsets);
        b.ranked_polygon_ = std::move(f.ranked_polygon);
        b.ranked_polygon_place_ = std::move(f.ranked_polygon_rank);
        b.ranked_polygon_score_ = std::move(f.ranked_polygon_score);
    }

    static void horizon(detail::FileHorizon f, Bake& b) {
        if (!f.present) return;
        b.horizon_boxes_ = std::move(f.boxes);
        b.horizon_tile_planes_ = std::move(f.tile_planes);
        b.horizon_tile_corners_ = std::move(f.tile_corners);
        b.horizon_tile_offset_ = std::move(f.tile_offsets);
        b.horizon_cell_list_ = std::move(f.cell_list);
        b.horizon_list_offset_ = std::move(f.list_offsets);
        b.horizon_list_entry_ = std::move(f.list_entries);
        b.horizon_test_offset_ = std::move(f.test_offsets);
        b.horizon_test_ = std::move(f.tests);
    }

    template <class T>
    static uint64_t bytes(const std::vector<T>& v) {
        return uint64_t(v.capacity()) * sizeof(T);
    }
    static uint64_t memory(const Bake& b) {
        uint64_t n = sizeof(Bake) + b.info_.tool_version.capacity() + b.info_.world_path.capacity() +
                     b.info_.world_hash.capacity() + b.info_.mode.capacity();
        for (const auto& [k, v] : b.parameters_) n += sizeof(k) + sizeof(v) + k.capacity() + v.capacity();
        for (const auto& [k, v] : b.figures_) n += sizeof(k) + sizeof(v) + k.capacity();
        for (const auto& [k, v] : b.verification_figures_) n += sizeof(k) + sizeof(v) + k.capacity();
        return n + bytes(b.names_) + bytes(b.name_offset_) + bytes(b.object_bounds_) +
               bytes(b.part_offsets_) + bytes(b.part_boxes_) + bytes(b.object_triangles_) +
               bytes(b.object_flags_) + bytes(b.grid_to_cell_) + bytes(b.nodes_) + bytes(b.cell_bounds_) +
               bytes(b.cell_grid_) + bytes(b.brick_) + bytes(b.brick_bytes_) + bytes(b.eye_brick_) +
               bytes(b.eye_brick_bytes_) + bytes(b.code_) + b.row_offset_.bytes() + b.cell_row_.bytes() +
               b.ranked_offset_.bytes() + bytes(b.ranked_boxes_) + bytes(b.ranked_box_) +
               bytes(b.ranked_score_) + bytes(b.ranked_solid_angle_sr_) + bytes(b.ranked_hidden_objects_) +
               bytes(b.ranked_hidden_triangle_share_) + bytes(b.polygon_offset_) +
               bytes(b.ranked_polygon_offset_) + bytes(b.ranked_polygon_) + bytes(b.ranked_polygon_place_) +
               bytes(b.polygon_corners_) + bytes(b.polygon_planes_) + bytes(b.ranked_polygon_score_) +
               bytes(b.horizon_boxes_) + bytes(b.horizon_tile_planes_) + bytes(b.horizon_tile_corners_) +
               bytes(b.horizon_tile_offset_) + bytes(b.horizon_cell_list_) + bytes(b.horizon_list_offset_) +
               bytes(b.horizon_list_entry_) + bytes(b.horizon_test_offset_) + bytes(b.horizon_test_);
    }
};

LoadResult Bake::load(const std::string& path) noexcept {
    LoadResult result;
    try {
        *this = Bake();
        Loading::run(path, *this);
        return result;
    } catch (const detail::ReadError& e) {
        result.status = e.status();
        try {
            result.message = e.what();
        } catch (...) {
        }
    } catch (const std::bad_alloc&) {
        result.status = Status::kOutOfMemory;
    } catch (const std::length_error&) {
        result.status = Status::kOutOfMemory;
    } catch (...) {
        result.status = Status::kCorrupt;
    }
    *this = Bake();
    if (result.message.empty()) {
        try {
            result.message =
                path + (result.status == Status::kOutOfMemory ? ": the bake does not fit in memory"
                                                              : ": cannot load the bake");
        } catch (...) {
        }
    }
    return result;
}

Box Bake::grid_box(uint32_t g) const {
    const uint32_t gx = g % uint32_t(dims_[0]);
    const uint32_t gy = g / uint32_t(dims_[0]) % uint32_t(dims_[1]);
    const uint32_t gz = g / (uint32_t(dims_[0]) * uint32_t(dims_[1]));
    const uint32_t idx[3] = {gx, gy, gz};
    Box box;
    for (int a = 0; a < 3; ++a) {
        box.min[a] = origin_[a] + float(idx[a]) * cell_size_m_;
        box.max[a] = origin_[a] + float(idx[a] + 1) * cell_size_m_;
    }
    return box;
}

Box Bake::cell_bounds(uint32_t c) const noexcept {
    if (c >= cell_row_.size()) return empty_box();
    return cell_bounds_.empty() ? grid_box(cell_grid_[c]) : cell_bounds_[c];
}

bool Bake::mask_voxel(bool eyes, int64_t x, int64_t y, int64_t z) const {
    const size_t b =
        size_t(x >> 3) + size_t(brick_dims_[0]) * (size_t(y >> 3) + size_t(brick_dims_[1]) * size_t(z >> 3));
    const uint32_t t = (eyes ? eye_brick_ : brick_)[b];
    if (t < kFirstBrick) return t == kBrickFull;
    return ((eyes ? eye_brick_bytes_
                  : brick_bytes_)[size_t(t - kFirstBrick) * 64 + size_t(z & 7) * 8 + size_t(y & 7)] >>
            (x & 7)) &
           1u;
}

// VoxelMask::contains (core/cell_set.h), step by step: voxels are closed boxes, so a point on a face of a
// set voxel is in.
bool Bake::mask_contains(bool eyes, float x, float y, float z) const {
    const float p[3] = {x, y, z};
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        const float rel = (p[a] - view_origin_[a]) / view_voxel_m_;
        if (!(rel >= 0.0f) || rel > float(view_dims_[a])) return false;
        const float f = std::floor(rel);
        hi[a] = std::min(int(f), view_dims_[a] - 1);
        lo[a] = rel == f ? std::min(std::max(int(f) - 1, 0), hi[a]) : hi[a];
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i)
                if (mask_voxel(eyes, i, j, k)) return true;
    return false;
}

bool Bake::in_eye_space(float x, float y, float z) const noexcept {
    if (find_cell(x, y, z) < 0) return false;
    return !has_eyes_ || mask_contains(true, x, y, z);
}

int32_t Bake::find_cell(float x, float y, float z) const noexcept {
    if (!(cell_size_m_ > 0.0f) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return -1;
    if (grid_to_cell_.empty()) return -1;
    if (has_view_ && !mask_contains(false, x, y, z)) return -1;
    const float p[3] = {x, y, z};
    int idx[3];
    for (int a = 0; a < 3; ++a) {
        const float rel = (p[a] - origin_[a]) / cell_size_m_;
        if (!(rel >= 0.0f) || rel > float(dims_[a])) return -1;
        idx[a] = std::min(int(std::floor(rel)), dims_[a] - 1);
    }
    const size_t g = size_t(idx[0]) + size_t(dims_[0]) * (size_t(idx[1]) + size_t(dims_[1]) * size_t(idx[2]));
    int32_t n = grid_to_cell_[g];
    if (kind_ == CellKind::kGrid) return n;
    while (n >= 0 && nodes_[size_t(n)].first_child >= 0) {  // children come after parents: this ends
        const Node& node = nodes_[size_t(n)];
        n = node.first_child + (x >= node.center[0] ? 1 : 0) + (y >= node.center[1] ? 2 : 0) +
            (z >= node.center[2] ? 4 : 0);
    }
    return n >= 0 ? nodes_[size_t(n)].cell : -1;
}

uint32_t Bake::visible_count(uint32_t c) const noexcept {
    uint32_t n = 0;
    for_each_visible(c, [&](uint32_t) { ++n; });
    return n;
}

bool Bake::is_visible(uint32_t c, uint32_t o) const noexcept {
    if (c >= cell_row_.size() || o >= object_count_) return false;
    detail::GapReader key, diff;
    const bool has_diff = row_readers(cell_row_[c], key, diff);
    bool in = false;
    uint32_t i = key.next();
    while (i < o) i = key.next();
    in = i == o;
    if (has_diff) {
        i = diff.next();
        while (i < o) i = diff.next();
        in = in != (i == o);
    }
    return in;
}

uint32_t Bake::fill_bitset(uint32_t c, uint64_t* words, size_t word_count) const noexcept {
    if (c >= cell_row_.size() || words == nullptr || word_count < words_per_row()) return UINT32_MAX;
    std::memset(words, 0, word_count * sizeof(uint64_t));
    uint32_t n = 0;
    for_each_visible(c, [&](uint32_t i) {
        words[i >> 6] |= uint64_t(1) << (i & 63);
        ++n;
    });
    return n;
}

std::string_view Bake::object_name(uint32_t o) const noexcept {
    if (o >= object_count_) return {};
    return std::string_view(names_.data() + name_offset_[o], name_offset_[o + 1] - name_offset_[o] - 1);
}

const char* Bake::object_name_c(uint32_t o) const noexcept {
    return o < object_count_ ? names_.data() + name_offset_[o] : "";
}

uint32_t Bake::object_part_count(uint32_t o) const noexcept {
    return o < object_count_ && !part_offsets_.empty() ? part_offsets_[o + 1] - part_offsets_[o] : 0;
}

Box Bake::object_part(uint32_t o, uint32_t k) const noexcept {
    return k < object_part_count(o) ? part_boxes_[part_offsets_[o] + k] : empty_box();
}

Box Bake::object_bounds(uint32_t o) const noexcept {
    return o < object_count_ ? object_bounds_[o] : empty_box();
}

uint32_t Bake::object_triangles(uint32_t o) const noexcept {
    return o < object_count_ ? object_triangles_[o] : 0;
}

uint32_t Bake::object_flags(uint32_t o) const noexcept {
    return o < object_count_ ? object_flags_[o] : 0;
}

uint32_t Bake::occluder_count(uint32_t c) const noexcept {
    if (size_t(c) + 1 >= ranked_offset_.size()) return 0;
    return ranked_offset_[size_t(c) + 1] - ranked_offset_[c];
}

OccluderList Bake::occluders(uint32_t c) const noexcept {
    const uint32_t n = occluder_count(c);
    return n == 0 ? OccluderList() : OccluderList(this, ranked_offset_[c], n);
}

uint32_t Bake::occluder_boxes(uint32_t c, Box* out, uint32_t capacity) const noexcept {
    if (out == nullptr) return 0;
    const uint32_t n = std::min(occluder_count(c), capacity);
    for (uint32_t k = 0; k < n; ++k) out[k] = ranked_boxes_[ranked_box_[ranked_offset_[c] + k]];
    return n;
}

uint32_t Bake::occluder_polygon_count(uint32_t c) const noexcept {
    if (size_t(c) + 1 >= ranked_polygon_offset_.size()) return 0;
    return ranked_polygon_offset_[size_t(c) + 1] - ranked_polygon_offset_[c];
}

bool Bake::occluder_polygon(uint32_t c, uint32_t k, RankedPolygon& out) const noexcept {
    if (k >= occluder_polygon_count(c)) return false;
    const size_t e = size_t(ranked_polygon_offset_[c]) + k, p = ranked_polygon_[e];
    out.plane = polygon_planes_.data() + 5 * p;
    out.corners = polygon_corners_.data() + 3 * size_t(polygon_offset_[p]);
    out.count = polygon_offset_[p + 1] - polygon_offset_[p];
    out.place = ranked_polygon_place_[e];
    out.score = ranked_polygon_score_[e];
    return true;
}

const double* Bake::figure(std::string_view name) const noexcept {
    for (const auto& [k, v] : figures_)
        if (k == name) return &v;
    return nullptr;
}

const std::string* Bake::parameter(std::string_view name) const noexcept {
    for (const auto& [k, v] : parameters_)
        if (k == name) return &v;
    return nullptr;
}

}  // namespace pvsbake
