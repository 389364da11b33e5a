// SPDX-License-Identifier: MIT
// pvsbake runtime loader: the C API (pvsbake/loader_c.h) over pvsbake::Bake. Every entry point is
// noexcept in effect: Bake's queries do not throw, and load() reports instead of throwing.
#include "pvsbake/loader_c.h"

#include "c_handles.h"
#include "pvsbake/loader.h"

#include <cstring>
#include <new>

namespace {

void copy_message(const std::string& text, char* message, size_t size) {
    if (message == nullptr || size == 0) return;
    const size_t n = std::min(text.size(), size - 1);
    std::memcpy(message, text.data(), n);
    message[n] = '\0';
}

int copy_box(const pvsbake::Box& b, float box[6]) {
    if (box == nullptr) return 0;
    std::memcpy(box, b.min, sizeof(b.min));
    std::memcpy(box + 3, b.max, sizeof(b.max));
    return 1;
}

const char* text(const pvsbake_bake* b, const std::string& (pvsbake::Bake::*get)() const) {
    return b != nullptr ? (b->bake.*get)().c_str() : "";
}

}  // namespace

extern "C" {

pvsbake_status pvsbake_load(const char* path, pvsbake_bake** out, char* message, size_t message_size) {
    copy_message("", message, message_size);
    if (out == nullptr || path == nullptr) {
        copy_message("pvsbake_load: path and out must not be NULL", message, message_size);
        return PVSBAKE_INVALID_ARGUMENT;
    }
    *out = nullptr;
    pvsbake_bake* b = new (std::nothrow) pvsbake_bake;
    if (b == nullptr) {
        copy_message("pvsbake_load: out of memory", message, message_size);
        return PVSBAKE_OUT_OF_MEMORY;
    }
    pvsbake::LoadResult r;
    try {
        r = b->bake.load(path);
    } catch (...) {  // only building the path string can throw
        r.status = pvsbake::Status::kOutOfMemory;
    }
    if (!r) {
        copy_message(r.message, message, message_size);
        delete b;
        return pvsbake_status(r.status);
    }
    *out = b;
    return PVSBAKE_OK;
}

void pvsbake_free(pvsbake_bake* bake) {
    delete bake;
}

const char* pvsbake_status_name(pvsbake_status status) {
    return pvsbake::status_name(pvsbake::Status(status));
}

uint32_t pvsbake_cell_count(const pvsbake_bake* b) {
    return b != nullptr ? b->bake.cell_count() : 0;
}
uint32_t pvsbake_object_count(const pvsbake_bake* b) {
    return b != nullptr ? b->bake.object_count() : 0;
}
size_t pvsbake_words_per_row(const pvsbake_bake* b) {
    return b != nullptr ? b->bake.words_per_row() : 0;
}

int32_t pvsbake_find_cell(const pvsbake_bake* b, float x, float y, float z) {
    return b != nullptr ? b->bake.find_cell(x, y, z) : -1;
}

int pvsbake_in_eye_space(const pvsbake_bake* b, float x, float y, float z) {
    return b != nullptr && b->bake.in_eye_space(x, y, z) ? 1 : 0;
}
int pvsbake_cell_bounds(const pvsbake_bake* b, uint32_t cell, float box[6]) {
    return b != nullptr && cell < b->bake.cell_count() ? copy_box(b->bake.cell_bounds(cell), box) : 0;
}
int pvsbake_cell_kind(const pvsbake_bake* b) {
    return b != nullptr ? int(b->bake.cell_kind()) : 0;
}

uint32_t pvsbake_visit_visible(const pvsbake_bake* b, uint32_t cell, pvsbake_visit_fn visit, void* user) {
    if (b == nullptr) return 0;
    uint32_t n = 0;
    b->bake.for_each_visible(cell, [&](uint32_t o) {
        if (visit != nullptr) visit(user, o);
        ++n;
    });
    return n;
}
uint32_t pvsbake_visible_objects(const pvsbake_bake* b, uint32_t cell, uint32_t* objects, size_t capacity) {
    if (b == nullptr) return 0;
    uint32_t n = 0;
    b->bake.for_each_visible(cell, [&](uint32_t o) {
        if (objects != nullptr && n < capacity) objects[n] = o;
        ++n;
    });
    return n;
}
uint32_t pvsbake_fill_bitset(const pvsbake_bake* b, uint32_t cell, uint64_t* words, size_t word_count) {
    return b != nullptr ? b->bake.fill_bitset(cell, words, word_count) : UINT32_MAX;
}
int pvsbake_is_visible(const pvsbake_bake* b, uint32_t cell, uint32_t object) {
    return b != nullptr && b->bake.is_visible(cell, object) ? 1 : 0;
}

const char* pvsbake_object_name(const pvsbake_bake* b, uint32_t object) {
    return b != nullptr ? b->bake.object_name_c(object) : "";
}
int pvsbake_object_bounds(const pvsbake_bake* b, uint32_t object, float box[6]) {
    return b != nullptr && object < b->bake.object_count() ? copy_box(b->bake.object_bounds(object), box) : 0;
}
uint32_t pvsbake_object_part_count(const pvsbake_bake* b, uint32_t object) {
    return b != nullptr ? b->bake.object_part_count(object) : 0;
}
int pvsbake_object_part(const pvsbake_bake* b, uint32_t object, uint32_t part, float box[6]) {
    return b != nullptr && part < b->bake.object_part_count(object)
               ? copy_box(b->bake.object_part(object, part), box)
               : 0;
}
uint32_t pvsbake_object_triangles(const pvsbake_bake* b, uint32_t object) {
    return b != nullptr ? b->bake.object_triangles(object) : 0;
}
uint32_t pvsbake_object_flags(const pvsbake_bake* b, uint32_t object) {
    return b != nullptr ? b->bake.object_flags(object) : 0;
}
uint64_t pvsbake_total_triangles(const pvsbake_bake* b) {
    return b != nullptr ? b->bake.total_triangles() : 0;
}

uint32_t pvsbake_occluder_count(const pvsbake_bake* b, uint32_t cell) {
    return b != nullptr ? b->bake.occluder_count(cell) : 0;
}
int pvsbake_occluder(const pvsbake_bake* b, uint32_t cell, uint32_t rank, pvsbake_ranked_occluder* out) {
    if (b == nullptr || out == nullptr || rank >= b->bake.occluder_count(cell)) return 0;
    const pvsbake::RankedOccluder r = b->bake.occluders(cell)[rank];
    copy_box(r.box, out->box);
    out->score = r.score;
    out->solid_angle_sr = r.solid_angle_sr;
    out->hidden_objects = r.hidden_objects;
    out->hidden_triangle_share = r.hidden_triangle_share;
    return 1;
}

const char* pvsbake_mode(const pvsbake_bake* b) {
    return text(b, &pvsbake::Bake::mode);
}
const char* pvsbake_mode_label(const pvsbake_bake* b) {
    return b != nullptr ? b->bake.mode_label() : "";
}
int pvsbake_is_conservative(const pvsbake_bake* b) {
    return b != nullptr && b->bake.is_conservative() ? 1 : 0;
}
const char* pvsbake_tool_version(const pvsbake_bake* b) {
    return text(b, &pvsbake::Bake::tool_version);
}
const char* pvsbake_world_path(const pvsbake_bake* b) {
    return text(b, &pvsbake::Bake::world_path);
}
const char* pvsbake_world_hash(const pvsbake_bake* b) {
    return text(b, &pvsbake::Bake::world_hash);
}
void pvsbake_format_version(const pvsbake_bake* b, int* major, int* minor) {
    if (major != nullptr) *major = b != nullptr ? b->bake.format_major() : 0;
    if (minor != nullptr) *minor = b != nullptr ? b->bake.format_minor() : 0;
}

uint32_t pvsbake_figure_count(const pvsbake_bake* b) {
    return b != nullptr ? uint32_t(b->bake.figures().size()) : 0;
}
const char* pvsbake_figure_name(const pvsbake_bake* b, uint32_t i) {
    return b != nullptr && i < b->bake.figures().size() ? b->bake.figures()[i].first.c_str() : nullptr;
}
double pvsbake_figure_value(const pvsbake_bake* b, uint32_t i) {
    return b != nullptr && i < b->bake.figures().size() ? b->bake.figures()[i].second : 0.0;
}
int pvsbake_find_figure(const pvsbake_bake* b, const char* name, double* value) {
    if (b == nullptr || name == nullptr) return 0;
    const double* v = b->bake.figure(name);
    if (v != nullptr && value != nullptr) *value = *v;
    return v != nullptr ? 1 : 0;
}
uint32_t pvsbake_parameter_count(const pvsbake_bake* b) {
    return b != nullptr ? uint32_t(b->bake.parameters().size()) : 0;
}
const char* pvsbake_parameter_key(const pvsbake_bake* b, uint32_t i) {
    return b != nullptr && i < b->bake.parameters().size() ? b->bake.parameters()[i].first.c_str() : nullptr;
}
const char* pvsbake_parameter_value(const pvsbake_bake* b, uint32_t i) {
    return b != nullptr && i < b->bake.parameters().size() ? b->bake.parameters()[i].second.c_str() : nullptr;
}
const char* pvsbake_find_parameter(const pvsbake_bake* b, const char* key) {
    if (b == nullptr || key == nullptr) return nullptr;
    const std::string* v = b->bake.parameter(key);
    return v != nullptr ? v->c_str() : nullptr;
}

int pvsbake_get_pvs_stats(const pvsbake_bake* b, pvsbake_pvs_stats* stats) {
    if (b == nullptr || stats == nullptr) return 0;
    const pvsbake::PvsStats& s = b->bake.pvs_stats();
    *stats = pvsbake_pvs_stats{s.cell_count, s.object_count, s.unique_rows, s.bytes_per_row,
                               s.bytes_raw,  s.bytes_stored, s.bytes_code,  s.memory_bytes};
    return 1;
}

}  // extern "C"
