// SPDX-License-Identifier: MIT
// pvsbake::OcclusionCuller and pvsbake::Horizon (pvsbake/occlusion.h): the C99 runtime's culler and occlusion
// horizon (runtime/pvsr.c) compiled into the loader in a namespace of its own (PVSR_CXX_LINKAGE: C++ linkage,
// so a game's own copy of the runtime cannot clash with it), so that the HDF5 loader and the runtime file
// answer alike by construction. The culler is fed the cell's ranked occluders from the bake file; the
// horizon the cell's list in the order the runtime file keeps it (ascending: boxes, then tiles). The safety
// arguments: docs/ALGORITHMS.md#runtime-culler and #horizon-lists.
#include <pvsbake/occlusion.h>

#include "bake_reader.h"

// The runtime's headers first, outside the namespace (their include guards keep them out of it below).
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <algorithm>
#include <new>
#include <vector>

#define PVSR_CXX_LINKAGE
namespace pvsbake::detail::runtime {
#include "../../runtime/pvsr.c"
}  // namespace pvsbake::detail::runtime

namespace pvsbake {

namespace rt = detail::runtime;

bool detail::part_on_runtime_grid(const float bounds[6], float part[6]) {
    uint16_t steps[6];
    float box[6];
    if (!rt::pvsr_part_encode(bounds, part, steps, box)) return false;
    std::copy(box, box + 6, part);
    return true;
}

static_assert(OcclusionCuller::kMaxOccluders == PVSR_CULLER_MAX_OCCLUDERS);
static_assert(OcclusionCuller::kMaxPolygons == PVSR_CULLER_MAX_POLYGONS);
static_assert(OcclusionCuller::kMaxPolygonCorners == PVSR_POLYGON_MAX_CORNERS);
static_assert(int(OcclusionCuller::Path::kShadowFrustum) == rt::PVSR_CULL_SHADOW_FRUSTUM &&
              int(OcclusionCuller::Path::kDepthBuffer) == rt::PVSR_CULL_DEPTH_CUBE &&
              int(OcclusionCuller::Path::kFaces) == rt::PVSR_CULL_FACES);

namespace {

void to_floats(const Box& box, float b[6]) {
    for (int a = 0; a < 3; ++a) {
        b[a] = box.min[a];
        b[3 + a] = box.max[a];
    }
}

}  // namespace

// ---- OcclusionCuller

struct OcclusionCuller::State {
    std::vector<float> memory;
    rt::pvsr_culler culler{};
    bool ok = false;
};

OcclusionCuller::OcclusionCuller(int resolution) noexcept {
    try {
        state_ = std::make_unique<State>();
        const size_t bytes = rt::pvsr_culler_memory_bytes(resolution);
        state_->memory.resize(bytes / sizeof(float) + 1);
        state_->ok = rt::pvsr_culler_init(&state_->culler, resolution,
                                          bytes > 0 ? state_->memory.data() : nullptr, bytes) != 0;
    } catch (...) {  // std::bad_alloc: a culler that culls nothing
        state_.reset();
    }
}

OcclusionCuller::~OcclusionCuller() = default;
OcclusionCuller::OcclusionCuller(OcclusionCuller&&) noexcept = default;
OcclusionCuller& OcclusionCuller::operator=(OcclusionCuller&&) noexcept = default;

bool OcclusionCuller::ok() const noexcept {
    return state_ != nullptr && state_->ok;
}

int OcclusionCuller::resolution() const noexcept {
    return ok() ? state_->culler.resolution : 0;
}

uint32_t OcclusionCuller::begin_cell(const Bake& bake, uint32_t c, const float eye[3],
                                     size_t max_occluders) noexcept {
    Box boxes[kMaxOccluders];
    const uint32_t limit = uint32_t(std::min(max_occluders, kMaxOccluders));
    const uint32_t polygons = bake.occluder_polygon_count(c);
    uint32_t first = 0;  // the cell's polygons at places below the limit (as pvsr_culler_begin_cell)
    RankedPolygon p;
    while (first < polygons && bake.occluder_polygon(c, first, p) && p.place < limit) ++first;
    uint32_t n = bake.occluder_boxes(c, boxes, limit - first);
    begin_frame(eye, boxes, n);
    for (uint32_t k = 0; k < first; ++k)
        if (bake.occluder_polygon(c, k, p)) n += add_polygon(p.plane, p.corners, p.count) ? 1 : 0;
    return n;
}

void OcclusionCuller::begin_frame(const float eye[3], const Box* occluders, size_t count,
                                  size_t stride_bytes) noexcept {
    if (!ok()) return;
    float boxes[6 * kMaxOccluders];
    const size_t n = occluders == nullptr ? 0 : std::min(count, kMaxOccluders);
    for (size_t k = 0; k < n; ++k)
        to_floats(*reinterpret_cast<const Box*>(reinterpret_cast<const char*>(occluders) + k * stride_bytes),
                  boxes + 6 * k);
    rt::pvsr_culler_begin_frame(&state_->culler, eye, boxes, n);
}

bool OcclusionCuller::add_polygon(const float plane[5], const float* corners, uint32_t count) noexcept {
    return ok() && rt::pvsr_culler_add_polygon(&state_->culler, plane, corners, count) != 0;
}

size_t OcclusionCuller::polygons_used() const noexcept {
    return ok() ? state_->culler.polygon_count : 0;
}

OcclusionCuller::Path OcclusionCuller::classify(const Box& box) const noexcept {
    float b[6];
    to_floats(box, b);
    return ok() ? Path(rt::pvsr_culler_classify(&state_->culler, b)) : Path::kVisible;
}

// The tests alone take the runtime's own (each refuses what classify() refuses before it).
bool OcclusionCuller::hidden_by_shadow_frusta(const Box& box) const noexcept {
    float b[6];
    to_floats(box, b);
    return ok() && rt::hidden_by_shadow_frusta(&state_->culler, b) != 0;
}

bool OcclusionCuller::hidden_by_depth_cube(const Box& box) const noexcept {
    float b[6];
    to_floats(box, b);
    return ok() && rt::hidden_by_depth_cube(&state_->culler, b) != 0;
}

bool OcclusionCuller::hidden_by_faces(const Box& box) const noexcept {
    float b[6];
    to_floats(box, b);
    return ok() && rt::hidden_by_faces(&state_->culler, b) != 0;
}

size_t OcclusionCuller::occluders_used() const noexcept {
    return ok() ? state_->culler.used : 0;
}

size_t OcclusionCuller::occluders_redundant() const noexcept {
    return ok() ? state_->culler.redundant : 0;
}

size_t OcclusionCuller::covered_pixels() const noexcept {
    if (!ok() || state_->culler.depth == nullptr) return 0;
    const rt::pvsr_culler& c = state_->culler;
    const size_t r = size_t(c.resolution);
    size_t n = 0;
    for (int face = 0; face < 6; ++face) {
        const int* w = c.written[face];  // i0, i1, j0, j1
        for (int j = w[2]; j <= w[3]; ++j) {
            const float* row = c.depth + (size_t(face) * r + size_t(j)) * r;
            for (int i = w[0]; i <= w[1]; ++i) n += row[i] < INFINITY;
        }
    }
    return n;
}

// ---- Horizon

struct Horizon::State {
    std::vector<uint64_t> memory;
    rt::pvsr_horizon horizon{};
    bool ok = false;
};

Horizon::Horizon(int columns, size_t max_pieces) noexcept {
    try {
        state_ = std::make_unique<State>();
        state_->memory.resize(rt::pvsr_horizon_memory_bytes(columns, max_pieces) / sizeof(uint64_t) + 1);
        state_->ok = rt::pvsr_horizon_init(&state_->horizon, columns, max_pieces, state_->memory.data(),
                                           state_->memory.size() * sizeof(uint64_t)) != 0;
    } catch (...) {
        state_.reset();
    }
}

Horizon::~Horizon() = default;
Horizon::Horizon(Horizon&&) noexcept = default;
Horizon& Horizon::operator=(Horizon&&) noexcept = default;

bool Horizon::ok() const noexcept {
    return state_ != nullptr && state_->ok;
}

uint32_t Horizon::begin_cell(const Bake& bake, uint32_t c, const float eye[3]) noexcept {
    if (!ok()) return 0;
    rt::pvsr_horizon* h = &state_->horizon;
    rt::pvsr_horizon_begin(h, eye);
    const uint32_t n = bake.horizon_list_count(c);
    const uint32_t boxes = uint32_t(bake.horizon_boxes_.size() / 6);
    if (n > 0) {
        const uint32_t* entry =
            &bake.horizon_list_entry_[bake.horizon_list_offset_[bake.horizon_cell_list_[c]]];
        for (uint32_t k = 0; k < n; ++k) {
            const uint32_t o = entry[k];  // validated: below boxes + tiles
            rt::pvsr_horizon_set_tag(h, o);
            if (o < boxes) {
                rt::pvsr_horizon_add_box(h, &bake.horizon_boxes_[6 * size_t(o)]);
            } else {
                const uint32_t t = o - boxes;
                const uint32_t first = bake.horizon_tile_offset_[t];
                rt::pvsr_horizon_add_tile(h, &bake.horizon_tile_planes_[5 * size_t(t)],
                                          &bake.horizon_tile_corners_[3 * size_t(first)],
                                          bake.horizon_tile_offset_[t + 1] - first);
            }
        }
    }
    rt::pvsr_horizon_end(h);
    return n;
}

bool Horizon::is_hidden(const Box& box) const noexcept {
    if (!ok()) return false;
    const float b[6] = {box.min[0], box.min[1], box.min[2], box.max[0], box.max[1], box.max[2]};
    return rt::pvsr_horizon_is_hidden(&state_->horizon, b) != 0;
}

}  // namespace pvsbake
