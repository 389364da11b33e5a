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
// pvsr: the pvsbake runtime for C++17 (runtime/pvsr.h holds the contracts). A header over the C99 runtime:
// no exceptions, no allocation; a Level views the bytes it was opened on, which must stay unchanged and alive.
//
//   pvsr::Level level;
//   std::string why;
//   if (level.open(bytes, size, &why) != PVSR_OK) { ... why ... }
//   const int32_t cell = level.find_cell(x, y, z);           // -1: outside the view volume, draw all
//   if (cell >= 0) level.for_each_visible(uint32_t(cell), [&](uint32_t object) { draw(object); });
#pragma once

#include "pvsr.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace pvsr {

class Culler;
class Horizon;

class Level {
public:
    // Opens `size` bytes at `data` (pvsr_open); on failure the level is empty and *why (if given) says why.
    pvsr_status open(const void* data, size_t size, std::string* why = nullptr) noexcept {
        char message[256];
        const pvsr_status s = pvsr_open(&level_, data, size, message, sizeof message);
        if (why != nullptr) {
            try {
                *why = message;
            } catch (...) {
            }
        }
        return s;
    }

    uint32_t cell_count() const noexcept { return pvsr_cell_count(&level_); }
    uint32_t object_count() const noexcept { return pvsr_object_count(&level_); }
    uint32_t cell_kind() const noexcept { return pvsr_cell_kind(&level_); }  // 0 grid, 1 octree
    size_t words_per_row() const noexcept { return pvsr_words_per_row(&level_); }

    int32_t find_cell(float x, float y, float z) const noexcept { return pvsr_find_cell(&level_, x, y, z); }
    bool in_eye_space(float x, float y, float z) const noexcept { return pvsr_in_eye_space(&level_, x, y, z) != 0; }
    bool cell_bounds(uint32_t cell, float box[6]) const noexcept { return pvsr_cell_bounds(&level_, cell, box) != 0; }

    // Calls visit(object) for every object visible from the cell, in increasing order; returns how many.
    // Levels of up to PVSR_STACK_OBJECTS objects are walked from a bit set on the stack (2 KiB at most), with
    // visit inlined; larger ones through the C callback.
    template <class F>
    uint32_t for_each_visible(uint32_t cell, F&& visit) const {
        if (object_count() <= PVSR_STACK_OBJECTS) {
            uint64_t bits[PVSR_STACK_OBJECTS / 64];
            const size_t words = words_per_row();
            const uint32_t n = pvsr_fill_bitset(&level_, cell, bits, words);
            if (n == UINT32_MAX) return 0;
            for (size_t w = 0; w < words; ++w)
                for (uint64_t v = bits[w]; v != 0; v &= v - 1) visit(uint32_t(w * 64) + uint32_t(ctz(v)));
            return n;
        }
        using Fn = std::remove_reference_t<F>;
        return pvsr_visit_visible(
            &level_, cell, [](void* user, uint32_t object) { (*static_cast<Fn*>(user))(object); },
            const_cast<void*>(static_cast<const void*>(&visit)));
    }
    // What a game draws of the cell from one eye: the PVS less what the culler, set up for this frame
    // (Culler::begin_cell), proves hidden (pvsr_visit_drawn). Calls visit(object) in increasing order;
    // returns how many.
    template <class F>
    uint32_t for_each_drawn(uint32_t cell, const Culler& culler, F&& visit) const;
    uint32_t drawn_objects(uint32_t cell, const Culler& culler, uint32_t* objects,
                           size_t capacity) const noexcept;
    // The same, culled by the cell's horizon as well (Horizon::begin_cell; pvsr_visit_drawn_horizon); a null
    // culler leaves it to the horizon.
    template <class F>
    uint32_t for_each_drawn(uint32_t cell, const Culler* culler, const Horizon& horizon, F&& visit) const;
    // The cell's list of horizon occluders (file 2.1): how many (0 without lists).
    uint32_t horizon_list_count(uint32_t cell) const noexcept {
        return pvsr_horizon_list_count(&level_, cell);
    }
    uint32_t visible_count(uint32_t cell) const noexcept { return pvsr_visible_count(&level_, cell); }
    uint32_t visible_objects(uint32_t cell, uint32_t* objects, size_t capacity) const noexcept {
        return pvsr_visible_objects(&level_, cell, objects, capacity);
    }
    uint32_t fill_bitset(uint32_t cell, uint64_t* words, size_t word_count) const noexcept {
        return pvsr_fill_bitset(&level_, cell, words, word_count);
    }
    bool is_visible(uint32_t cell, uint32_t object) const noexcept { return pvsr_is_visible(&level_, cell, object) != 0; }

    std::string_view object_name(uint32_t object) const noexcept { return pvsr_object_name(&level_, object); }
    bool object_bounds(uint32_t object, float box[6]) const noexcept {
        return pvsr_object_bounds(&level_, object, box) != 0;
    }
    uint32_t object_triangles(uint32_t object) const noexcept { return pvsr_object_triangles(&level_, object); }
    uint32_t object_flags(uint32_t object) const noexcept { return pvsr_object_flags(&level_, object); }
    // File 2.2: the object's part boxes (pvsr_object_part_count, pvsr_object_part).
    uint32_t object_part_count(uint32_t object) const noexcept {
        return pvsr_object_part_count(&level_, object);
    }
    bool object_part(uint32_t object, uint32_t part, float box[6]) const noexcept {
        return pvsr_object_part(&level_, object, part, box) != 0;
    }
    uint64_t total_triangles() const noexcept { return pvsr_total_triangles(&level_); }

    uint32_t occluder_count(uint32_t cell) const noexcept { return pvsr_occluder_count(&level_, cell); }
    bool occluder(uint32_t cell, uint32_t rank, pvsr_ranked_occluder& out) const noexcept {
        return pvsr_occluder(&level_, cell, rank, &out) != 0;
    }
    // The cell's ranked polygon occluders (file version 1.1), each at its place among the boxes.
    uint32_t occluder_polygon_count(uint32_t cell) const noexcept {
        return pvsr_occluder_polygon_count(&level_, cell);
    }
    uint32_t occluder_polygon(uint32_t cell, uint32_t rank, float plane[5], float* corners, uint32_t capacity,
                              uint32_t* place = nullptr) const noexcept {
        return pvsr_occluder_polygon(&level_, cell, rank, plane, corners, capacity, place);
    }
    uint32_t occluder_boxes(uint32_t cell, float* boxes, uint32_t capacity) const noexcept {
        return pvsr_occluder_boxes(&level_, cell, boxes, capacity);
    }

    bool is_conservative() const noexcept { return pvsr_is_conservative(&level_) != 0; }
    const char* mode_label() const noexcept { return pvsr_mode_label(&level_); }
    std::string_view string(const char* key) const noexcept { return pvsr_string(&level_, key); }

    const pvsr_level& c_level() const noexcept { return level_; }

private:
    static int ctz(uint64_t v) noexcept {
#if defined(__GNUC__) || defined(__clang__)
        return __builtin_ctzll(v);
#else
        int n = 0;
        for (; (v & 1) == 0; v >>= 1) ++n;
        return n;
#endif
    }
    pvsr_level level_{};
};

// The culler of moving objects (pvsr_culler in pvsr.h) with its memory: allocated once here, never per frame.
class Culler {
public:
    // resolution: pixels per cube face edge (0: shadow frusta only). ok() is false when the memory could not
    // be allocated: then it culls nothing.
    explicit Culler(int resolution = 32) noexcept {
        try {
            memory_.resize(pvsr_culler_memory_bytes(resolution) / sizeof(float) + 1);
            ok_ = pvsr_culler_init(&culler_, resolution, memory_.data(), memory_.size() * sizeof(float)) != 0;
        } catch (...) {
            pvsr_culler_init(&culler_, resolution, nullptr, 0);
        }
    }
    Culler(const Culler&) = delete;  // it points into its own memory
    Culler& operator=(const Culler&) = delete;

    bool ok() const noexcept { return ok_; }
    // The eye (float[3]) and `count` occluder boxes of 6 floats each, such as Level::occluder_boxes gives.
    void begin_frame(const float eye[3], const float* boxes, size_t count) noexcept {
        pvsr_culler_begin_frame(&culler_, eye, boxes, count);
    }
    // A convex polygon occluder for this frame, after begin_frame (pvsr_culler_add_polygon); false when
    // refused.
    bool add_polygon(const float plane[5], const float* corners, uint32_t count) noexcept {
        return pvsr_culler_add_polygon(&culler_, plane, corners, count) != 0;
    }
    // The eye (float[3]) and the best min(max_occluders, PVSR_CULLER_MAX_OCCLUDERS) of the cell's ranked
    // occluders, boxes and polygons; returns how many were given (pvsr_culler_begin_cell).
    uint32_t begin_cell(const Level& level, uint32_t cell, const float eye[3],
                        uint32_t max_occluders = PVSR_CULLER_MAX_OCCLUDERS) noexcept {
        return pvsr_culler_begin_cell(&culler_, &level.c_level(), cell, eye, max_occluders);
    }
    bool is_hidden(const float box[6]) const noexcept { return pvsr_culler_is_hidden(&culler_, box) != 0; }
    pvsr_cull_path classify(const float box[6]) const noexcept {
        return pvsr_cull_path(pvsr_culler_classify(&culler_, box));
    }
    // Occluders this frame uses (those touching the eye and those nearer ones already hide are skipped).
    size_t occluders_used() const noexcept { return culler_.used; }

    const pvsr_culler& c_culler() const noexcept { return culler_; }

private:
    std::vector<float> memory_;
    pvsr_culler culler_{};
    bool ok_ = false;
};

// The occlusion horizon (pvsr_horizon in pvsr.h) with its memory: allocated once here, never per frame.
class Horizon {
public:
    // columns a side (a power of two, PVSR_HORIZON_MIN_COLUMNS to PVSR_HORIZON_MAX_COLUMNS) and the pieces
    // a frame may hold (past them occluders are dropped: fewer culls). ok() is false when the memory could
    // not be allocated: then it hides nothing.
    explicit Horizon(int columns = 256, size_t max_pieces = 65536) noexcept {
        try {
            memory_.resize(pvsr_horizon_memory_bytes(columns, max_pieces) / sizeof(uint64_t) + 1);
            ok_ = pvsr_horizon_init(&horizon_, columns, max_pieces, memory_.data(),
                                    memory_.size() * sizeof(uint64_t)) != 0;
        } catch (...) {
            pvsr_horizon_init(&horizon_, columns, max_pieces, nullptr, 0);
        }
    }
    Horizon(const Horizon&) = delete;  // it points into its own memory
    Horizon& operator=(const Horizon&) = delete;

    bool ok() const noexcept { return ok_; }
    // A frame at the eye (float[3]) with the cell's list of horizon occluders; returns how many were given
    // (pvsr_horizon_begin_cell).
    uint32_t begin_cell(const Level& level, uint32_t cell, const float eye[3]) noexcept {
        return pvsr_horizon_begin_cell(&horizon_, &level.c_level(), cell, eye);
    }
    bool is_hidden(const float box[6]) const noexcept { return pvsr_horizon_is_hidden(&horizon_, box) != 0; }
    // Pieces this frame holds, and those dropped for want of room.
    size_t pieces() const noexcept { return horizon_.count; }
    size_t dropped() const noexcept { return horizon_.dropped; }

    const pvsr_horizon& c_horizon() const noexcept { return horizon_; }

private:
    std::vector<uint64_t> memory_;
    pvsr_horizon horizon_{};
    bool ok_ = false;
};

template <class F>
uint32_t Level::for_each_drawn(uint32_t cell, const Culler* culler, const Horizon& horizon, F&& visit) const {
    using Fn = std::remove_reference_t<F>;
    return pvsr_visit_drawn_horizon(
        &level_, cell, culler != nullptr ? &culler->c_culler() : nullptr, &horizon.c_horizon(),
        [](void* user, uint32_t object) { (*static_cast<Fn*>(user))(object); },
        const_cast<void*>(static_cast<const void*>(&visit)));
}

template <class F>
uint32_t Level::for_each_drawn(uint32_t cell, const Culler& culler, F&& visit) const {
    using Fn = std::remove_reference_t<F>;
    return pvsr_visit_drawn(
        &level_, cell, &culler.c_culler(),
        [](void* user, uint32_t object) { (*static_cast<Fn*>(user))(object); },
        const_cast<void*>(static_cast<const void*>(&visit)));
}

inline uint32_t Level::drawn_objects(uint32_t cell, const Culler& culler, uint32_t* objects,
                                     size_t capacity) const noexcept {
    return pvsr_drawn_objects(&level_, cell, &culler.c_culler(), objects, capacity);
}

}  // namespace pvsr
