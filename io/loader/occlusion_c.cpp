// SPDX-License-Identifier: MIT
// The C API of the run-time occlusion culler (pvsbake/occlusion_c.h) over pvsbake::OcclusionCuller.
#include <pvsbake/occlusion.h>
#include <pvsbake/occlusion_c.h>

#include "c_handles.h"

#include <cstring>
#include <new>

namespace {

static_assert(sizeof(pvsbake::Box) == 6 * sizeof(float), "Box is float[6]: min x, y, z, max x, y, z");

pvsbake::Box to_box(const float box[6]) {
    pvsbake::Box b;
    std::memcpy(&b, box, sizeof b);
    return b;
}

}  // namespace

extern "C" {

pvsbake_culler* pvsbake_culler_create(int resolution) {
    const int r = resolution == 0  ? pvsbake::OcclusionCuller::kDefaultResolution
                  : resolution < 0 ? 0
                                   : resolution;
    pvsbake_culler* c = new (std::nothrow) pvsbake_culler(r);
    if (c != nullptr && !c->culler.ok()) {
        delete c;
        return nullptr;
    }
    return c;
}

void pvsbake_culler_free(pvsbake_culler* culler) {
    delete culler;
}

void pvsbake_culler_begin_frame(pvsbake_culler* culler, const float eye[3], const float* boxes,
                                size_t count) {
    if (culler == nullptr) return;
    // begin_frame() reads each box with memcpy, so float[6] records are read as Box records.
    culler->culler.begin_frame(eye, reinterpret_cast<const pvsbake::Box*>(boxes), boxes ? count : 0,
                               6 * sizeof(float));
}

int pvsbake_culler_add_polygon(pvsbake_culler* culler, const float plane[5], const float* corners,
                               uint32_t count) {
    return culler != nullptr && culler->culler.add_polygon(plane, corners, count) ? 1 : 0;
}

int pvsbake_culler_is_hidden(const pvsbake_culler* culler, const float box[6]) {
    return pvsbake_culler_classify(culler, box) != PVSBAKE_CULL_VISIBLE ? 1 : 0;
}

int pvsbake_culler_classify(const pvsbake_culler* culler, const float box[6]) {
    if (culler == nullptr || box == nullptr) return PVSBAKE_CULL_VISIBLE;
    return int(culler->culler.classify(to_box(box)));
}

uint32_t pvsbake_culler_begin_cell(pvsbake_culler* culler, const pvsbake_bake* bake, uint32_t cell,
                                   const float eye[3], size_t max_occluders) {
    if (culler == nullptr) return 0;
    if (bake == nullptr) {
        culler->culler.begin_frame(eye, nullptr, 0);
        return 0;
    }
    return culler->culler.begin_cell(bake->bake, cell, eye, max_occluders);
}

uint32_t pvsbake_visit_drawn(const pvsbake_bake* bake, uint32_t cell, const pvsbake_culler* culler,
                             pvsbake_visit_fn visit, void* user) {
    if (culler == nullptr) return pvsbake_visit_visible(bake, cell, visit, user);
    if (bake == nullptr) return 0;
    return pvsbake::for_each_drawn(bake->bake, cell, culler->culler, [&](uint32_t o) {
        if (visit != nullptr) visit(user, o);
    });
}

uint32_t pvsbake_drawn_objects(const pvsbake_bake* bake, uint32_t cell, const pvsbake_culler* culler,
                               uint32_t* objects, size_t capacity) {
    if (culler == nullptr) return pvsbake_visible_objects(bake, cell, objects, capacity);
    if (bake == nullptr) return 0;
    uint32_t n = 0;
    pvsbake::for_each_drawn(bake->bake, cell, culler->culler, [&](uint32_t o) {
        if (objects != nullptr && n < capacity) objects[n] = o;
        ++n;
    });
    return n;
}

pvsbake_horizon* pvsbake_horizon_create(int columns, size_t max_pieces) {
    pvsbake_horizon* h = new (std::nothrow) pvsbake_horizon(columns, max_pieces);
    if (h != nullptr && !h->horizon.ok()) {
        delete h;
        return nullptr;
    }
    return h;
}

void pvsbake_horizon_free(pvsbake_horizon* horizon) {
    delete horizon;
}

uint32_t pvsbake_horizon_list_count(const pvsbake_bake* bake, uint32_t cell) {
    return bake != nullptr ? bake->bake.horizon_list_count(cell) : 0;
}

uint32_t pvsbake_horizon_begin_cell(pvsbake_horizon* horizon, const pvsbake_bake* bake, uint32_t cell,
                                    const float eye[3]) {
    if (horizon == nullptr) return 0;
    static const pvsbake::Bake kNone;
    return horizon->horizon.begin_cell(bake != nullptr ? bake->bake : kNone, cell, eye);
}

int pvsbake_horizon_is_hidden(const pvsbake_horizon* horizon, const float box[6]) {
    return horizon != nullptr && box != nullptr && horizon->horizon.is_hidden(to_box(box)) ? 1 : 0;
}

uint32_t pvsbake_visit_drawn_horizon(const pvsbake_bake* bake, uint32_t cell, const pvsbake_culler* culler,
                                     const pvsbake_horizon* horizon, pvsbake_visit_fn visit, void* user) {
    if (horizon == nullptr) return pvsbake_visit_drawn(bake, cell, culler, visit, user);
    if (bake == nullptr) return 0;
    return pvsbake::for_each_drawn(bake->bake, cell, culler != nullptr ? &culler->culler : nullptr,
                                   horizon->horizon, [&](uint32_t o) {
                                       if (visit != nullptr) visit(user, o);
                                   });
}

uint32_t pvsbake_drawn_objects_horizon(const pvsbake_bake* bake, uint32_t cell, const pvsbake_culler* culler,
                                       const pvsbake_horizon* horizon, uint32_t* objects, size_t capacity) {
    if (horizon == nullptr) return pvsbake_drawn_objects(bake, cell, culler, objects, capacity);
    if (bake == nullptr) return 0;
    uint32_t n = 0;
    pvsbake::for_each_drawn(bake->bake, cell, culler != nullptr ? &culler->culler : nullptr, horizon->horizon,
                            [&](uint32_t o) {
                                if (objects != nullptr && n < capacity) objects[n] = o;
                                ++n;
                            });
    return n;
}

}  // extern "C"
