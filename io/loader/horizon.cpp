// SPDX-License-Identifier: MIT
// pvsbake::Horizon (pvsbake/occlusion.h): the C99 runtime's occlusion horizon (runtime/pvsr.c) compiled into
// the loader in a namespace of its own (PVSR_CXX_LINKAGE: C++ linkage, so a game's own copy of the runtime
// cannot clash with it), fed the cell's list from the bake file in the order the runtime file keeps it
// (ascending: boxes, then tiles). docs/ALGORITHMS.md#horizon-lists.
#include <pvsbake/occlusion.h>

// The runtime's headers first, outside the namespace (their include guards keep them out of it below).
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <new>
#include <vector>

#define PVSR_CXX_LINKAGE
namespace pvsbake::detail::runtime {
#include "../../runtime/pvsr.c"
}  // namespace pvsbake::detail::runtime

namespace pvsbake {

namespace rt = detail::runtime;

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
