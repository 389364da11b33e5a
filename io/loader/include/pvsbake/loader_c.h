// SPDX-License-Identifier: MIT
/* pvsbake runtime loader, plain C API (for engines in C or other languages). Mirrors pvsbake/loader.h:
 * an opaque handle from pvsbake_load(), status codes, and no allocation by the caller beyond the buffers
 * it passes. A loaded bake is immutable: any number of threads may query it at once. Nothing here
 * crashes on a bad file; a null handle or out-of-range index gives 0, -1 or "" as each function says.
 *
 * Conventions: glTF axes (right-handed, +Y up), metres. Boxes are float[6]: min x, y, z, max x, y, z.
 * PVS bit sets: object i is bit (i % 64) of word (i / 64), pvsbake_words_per_row() words.
 *
 *   pvsbake_bake* bake = NULL;
 *   char message[512];
 *   if (pvsbake_load("level.h5", &bake, message, sizeof message) != PVSBAKE_OK) { puts(message); ... }
 *   int32_t cell = pvsbake_find_cell(bake, x, y, z);        // -1: outside the view volume, draw all
 *   if (cell >= 0) pvsbake_visit_visible(bake, (uint32_t)cell, draw_object, &scene);
 *   pvsbake_free(bake);
 */
#ifndef PVSBAKE_LOADER_C_H
#define PVSBAKE_LOADER_C_H

#include <stddef.h>
#include <stdint.h>

#include "pvsbake/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pvsbake_bake pvsbake_bake;

/* The same values as pvsbake::Status. */
typedef enum pvsbake_status {
    PVSBAKE_OK = 0,
    PVSBAKE_FILE_MISSING = 1,
    PVSBAKE_NOT_A_BAKE_FILE = 2,
    PVSBAKE_VERSION_TOO_NEW = 3,
    PVSBAKE_CORRUPT = 4,
    PVSBAKE_OUT_OF_MEMORY = 5,
    PVSBAKE_IO_ERROR = 6,
    PVSBAKE_INVALID_ARGUMENT = 7
} pvsbake_status;

/* Loads and validates the bake at path. On success *out is a new handle (free it with pvsbake_free);
 * on failure *out is NULL. message (may be NULL) receives a NUL-terminated, possibly shortened, one-line
 * message naming the file and what is wrong ("" on success). */
PVSBAKE_API pvsbake_status pvsbake_load(const char* path, pvsbake_bake** out, char* message,
                                        size_t message_size);
PVSBAKE_API void pvsbake_free(pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_status_name(pvsbake_status status); /* "ok", "file missing", ... */

PVSBAKE_API uint32_t pvsbake_cell_count(const pvsbake_bake* bake);
PVSBAKE_API uint32_t pvsbake_object_count(const pvsbake_bake* bake);
PVSBAKE_API size_t pvsbake_words_per_row(const pvsbake_bake* bake);

/* The cell holding (x, y, z), or -1 outside the view volume (then draw everything). */
PVSBAKE_API int32_t pvsbake_find_cell(const pvsbake_bake* bake, float x, float y, float z);
/* 1 when the point is in the eye space, where the bake's promises hold (Bake::in_eye_space), else 0. */
PVSBAKE_API int pvsbake_in_eye_space(const pvsbake_bake* bake, float x, float y, float z);
/* The box of a cell; 0 when cell is out of range. 0 = grid, 1 = octree. */
PVSBAKE_API int pvsbake_cell_bounds(const pvsbake_bake* bake, uint32_t cell, float box[6]);
PVSBAKE_API int pvsbake_cell_kind(const pvsbake_bake* bake);

/* Calls visit(user, object) for every object visible from cell, in increasing order; returns how many. */
typedef void (*pvsbake_visit_fn)(void* user, uint32_t object);
PVSBAKE_API uint32_t pvsbake_visit_visible(const pvsbake_bake* bake, uint32_t cell, pvsbake_visit_fn visit,
                                           void* user);
/* Writes up to capacity visible object indices to objects; returns how many there are (may be more). */
PVSBAKE_API uint32_t pvsbake_visible_objects(const pvsbake_bake* bake, uint32_t cell, uint32_t* objects,
                                             size_t capacity);
/* Fills a bit set of word_count >= pvsbake_words_per_row() words; returns the number of visible objects,
 * or UINT32_MAX (words untouched) when the buffer is too small or cell is out of range. */
PVSBAKE_API uint32_t pvsbake_fill_bitset(const pvsbake_bake* bake, uint32_t cell, uint64_t* words,
                                         size_t word_count);
PVSBAKE_API int pvsbake_is_visible(const pvsbake_bake* bake, uint32_t cell, uint32_t object);

/* Objects: name (UTF-8, lives as long as the bake; "" out of range), bounds, triangles, flags
 * (bit 0 opaque, 1 see-through, 2 always visible, 3 never occludes). */
PVSBAKE_API const char* pvsbake_object_name(const pvsbake_bake* bake, uint32_t object);
PVSBAKE_API int pvsbake_object_bounds(const pvsbake_bake* bake, uint32_t object, float box[6]);
PVSBAKE_API uint32_t pvsbake_object_triangles(const pvsbake_bake* bake, uint32_t object);
PVSBAKE_API uint32_t pvsbake_object_flags(const pvsbake_bake* bake, uint32_t object);
PVSBAKE_API uint64_t pvsbake_total_triangles(const pvsbake_bake* bake);
/* Format 1.9: an object's part boxes (docs/ALGORITHMS.md#object-parts); 0 parts when it has none.
 * pvsbake_object_part writes part `part` (float[6]); 0 when out of range. */
PVSBAKE_API uint32_t pvsbake_object_part_count(const pvsbake_bake* bake, uint32_t object);
PVSBAKE_API int pvsbake_object_part(const pvsbake_bake* bake, uint32_t object, uint32_t part, float box[6]);

/* Ranked occluders of a cell (format 1.2), best first: as pvsbake::RankedOccluder. box is float[6]
 * (min x, y, z, max x, y, z), world metres; score higher is better; solid_angle_sr the largest solid angle
 * from the cell's sampled eyes; hidden_objects the mean number of objects, hidden_triangle_share the mean
 * share of the world's triangles, wholly in its shadow. Old files and out-of-range cells have none. */
typedef struct pvsbake_ranked_occluder {
    float box[6];
    float score;
    float solid_angle_sr;
    float hidden_objects;
    float hidden_triangle_share;
} pvsbake_ranked_occluder;
PVSBAKE_API uint32_t pvsbake_occluder_count(const pvsbake_bake* bake, uint32_t cell);
/* Writes the occluder of that rank (0 = best) to *out; returns 1, or 0 (out untouched) when the cell or
 * rank is out of range or a pointer is NULL. */
PVSBAKE_API int pvsbake_occluder(const pvsbake_bake* bake, uint32_t cell, uint32_t rank,
                                 pvsbake_ranked_occluder* out);

/* What the bake is. Strings live as long as the bake. */
PVSBAKE_API const char* pvsbake_mode(const pvsbake_bake* bake);       /* "sampled" or "conservative" */
PVSBAKE_API const char* pvsbake_mode_label(const pvsbake_bake* bake); /* "conservative" or "aggressive" */
PVSBAKE_API int pvsbake_is_conservative(const pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_tool_version(const pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_world_path(const pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_world_hash(const pvsbake_bake* bake);
PVSBAKE_API void pvsbake_format_version(const pvsbake_bake* bake, int* major, int* minor);
/* Figures and parameters by index (name and value; NULL out of range) or by name (0 when absent). */
PVSBAKE_API uint32_t pvsbake_figure_count(const pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_figure_name(const pvsbake_bake* bake, uint32_t i);
PVSBAKE_API double pvsbake_figure_value(const pvsbake_bake* bake, uint32_t i);
PVSBAKE_API int pvsbake_find_figure(const pvsbake_bake* bake, const char* name, double* value);
PVSBAKE_API uint32_t pvsbake_parameter_count(const pvsbake_bake* bake);
PVSBAKE_API const char* pvsbake_parameter_key(const pvsbake_bake* bake, uint32_t i);
PVSBAKE_API const char* pvsbake_parameter_value(const pvsbake_bake* bake, uint32_t i);
PVSBAKE_API const char* pvsbake_find_parameter(const pvsbake_bake* bake, const char* key);

/* PVS sizes, as pvsbake::PvsStats. */
typedef struct pvsbake_pvs_stats {
    uint64_t cell_count, object_count, unique_rows, bytes_per_row;
    uint64_t bytes_raw, bytes_stored, bytes_code, memory_bytes;
} pvsbake_pvs_stats;
PVSBAKE_API int pvsbake_get_pvs_stats(const pvsbake_bake* bake, pvsbake_pvs_stats* stats);

#ifdef __cplusplus
}
#endif

#endif /* PVSBAKE_LOADER_C_H */
