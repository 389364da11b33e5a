// SPDX-License-Identifier: MIT
// The C API of the run-time occlusion culler (pvsbake/occlusion_c.h) over pvsbake::OcclusionCuller.
#include <pvsbake/occlusion.h>
#include <pvsbake/occlusion_c.h>

#include <cstring>
#include <new>

struct pvsbake_culler {
    pvsbake::OcclusionCuller culler;
    explicit pvsbake_culler(int resolution) : culler(resolution) {}
};

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

int pvsbake_culler_is_hidden(const pvsbake_culler* culler, const float box[6]) {
    return pvsbake_culler_classify(culler, box) != PVSBAKE_CULL_VISIBLE ? 1 : 0;
}

int pvsbake_culler_classify(const pvsbake_culler* culler, const float box[6]) {
    if (culler == nullptr || box == nullptr) return PVSBAKE_CULL_VISIBLE;
    return int(culler->culler.classify(to_box(box)));
}

}  // extern "C"
