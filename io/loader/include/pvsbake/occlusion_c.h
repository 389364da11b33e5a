// SPDX-License-Identifier: MIT
/* pvsbake runtime loader, plain C API of the run-time occlusion culler of moving objects. Mirrors
 * pvsbake/occlusion.h (read its conventions: glTF axes, metres, solid occluder boxes, "hidden" only when
 * certainly hidden). Boxes are float[6]: min x, y, z, max x, y, z, as in pvsbake/loader_c.h. Nothing here
 * throws or crashes; a null culler or box gives "visible" (0).
 *
 *   pvsbake_culler* culler = pvsbake_culler_create(0);       // 0: the default cube resolution
 *   each frame:
 *     pvsbake_culler_begin_cell(culler, bake, cell, eye, 64);  // the cell's ranked occluders
 *     pvsbake_visit_drawn(bake, cell, culler, draw_object, &scene);
 *     for each moving object: if (!pvsbake_culler_is_hidden(culler, box)) draw(object);
 *   (pvsbake_culler_begin_frame takes any occluder boxes instead.)
 *   pvsbake_culler_free(culler);
 */
#ifndef PVSBAKE_OCCLUSION_C_H
#define PVSBAKE_OCCLUSION_C_H

#include <stddef.h>
#include <stdint.h>

#include "pvsbake/export.h"
#include "pvsbake/loader_c.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pvsbake_culler pvsbake_culler;

/* The same values as pvsbake::OcclusionCuller::Path. */
typedef enum pvsbake_cull_path {
    PVSBAKE_CULL_VISIBLE = 0,        /* not proven hidden: draw it */
    PVSBAKE_CULL_SHADOW_FRUSTUM = 1, /* inside one occluder's shadow frustum */
    PVSBAKE_CULL_DEPTH_BUFFER = 2,   /* hidden by the fused depth cube, not by one frustum */
    PVSBAKE_CULL_FACES = 3           /* hidden by the exact union of the occluders' faces only */
} pvsbake_cull_path;

/* A new culler (free it with pvsbake_culler_free). resolution: pixels per cube face edge, 0 = default
 * (32), negative = shadow frusta only. NULL when out of memory. */
PVSBAKE_API pvsbake_culler* pvsbake_culler_create(int resolution);
PVSBAKE_API void pvsbake_culler_free(pvsbake_culler* culler);
/* Prepares a frame: eye float[3] and `count` occluder boxes (float[6] each, count * 6 floats). */
PVSBAKE_API void pvsbake_culler_begin_frame(pvsbake_culler* culler, const float eye[3], const float* boxes,
                                            size_t count);
/* Adds a convex polygon occluder to this frame, after begin_frame: plane = normal x, y, z, offset, thickness;
 * `count` corners of 3 floats (OcclusionCuller::add_polygon says what it promises). 1 when added, 0 when
 * refused. */
PVSBAKE_API int pvsbake_culler_add_polygon(pvsbake_culler* culler, const float plane[5], const float* corners,
                                           uint32_t count);
/* Prepares a frame with the best min(max_occluders, 64) of the cell's ranked occluders of the bake, boxes and
 * polygons at their places; returns how many were given (a NULL bake: none, nothing is culled). */
PVSBAKE_API uint32_t pvsbake_culler_begin_cell(pvsbake_culler* culler, const pvsbake_bake* bake,
                                               uint32_t cell, const float eye[3], size_t max_occluders);
/* What a game draws of the cell from this frame's eye: the cell's PVS less the objects whose bounds the
 * culler proves hidden (objects flagged always visible are never culled). Calls visit(user, object) in
 * increasing order; returns how many. A NULL culler draws the whole PVS (pvsbake_visit_visible). */
PVSBAKE_API uint32_t pvsbake_visit_drawn(const pvsbake_bake* bake, uint32_t cell,
                                         const pvsbake_culler* culler, pvsbake_visit_fn visit, void* user);
/* The same objects into a list: up to capacity of them; returns how many there are (may be more). */
PVSBAKE_API uint32_t pvsbake_drawn_objects(const pvsbake_bake* bake, uint32_t cell,
                                           const pvsbake_culler* culler, uint32_t* objects, size_t capacity);
/* 1 only if box (float[6]) is certainly hidden from this frame's eye. */
PVSBAKE_API int pvsbake_culler_is_hidden(const pvsbake_culler* culler, const float box[6]);
/* Which test proved it (pvsbake_cull_path). */
PVSBAKE_API int pvsbake_culler_classify(const pvsbake_culler* culler, const float box[6]);

/* ---- The occlusion horizon of a cell's list (format 1.8; pvsbake::Horizon in pvsbake/occlusion.h, the C99
 * runtime's pvsr_horizon):
 *   pvsbake_horizon* horizon = pvsbake_horizon_create(256, 65536);
 *   each frame: pvsbake_horizon_begin_cell(horizon, bake, cell, eye);
 *               pvsbake_visit_drawn_horizon(bake, cell, culler, horizon, draw_object, &scene);
 */
typedef struct pvsbake_horizon pvsbake_horizon;
/* A new horizon of that many columns a side (a power of two, 4 to 8192) holding up to max_pieces pieces a
 * frame (free it with pvsbake_horizon_free). NULL when out of memory. */
PVSBAKE_API pvsbake_horizon* pvsbake_horizon_create(int columns, size_t max_pieces);
PVSBAKE_API void pvsbake_horizon_free(pvsbake_horizon* horizon);
/* The cell's list of horizon occluders: how many (0 without lists, or a NULL bake). */
PVSBAKE_API uint32_t pvsbake_horizon_list_count(const pvsbake_bake* bake, uint32_t cell);
/* A frame at the eye (float[3]) with the cell's list; returns how many occluders were given. */
PVSBAKE_API uint32_t pvsbake_horizon_begin_cell(pvsbake_horizon* horizon, const pvsbake_bake* bake,
                                                uint32_t cell, const float eye[3]);
/* 1 only if box (float[6]) is certainly hidden from this frame's eye by the horizon. */
PVSBAKE_API int pvsbake_horizon_is_hidden(const pvsbake_horizon* horizon, const float box[6]);
/* What a game draws of the cell culled by the culler (may be NULL) and the horizon (may be NULL): the PVS
 * less the objects whose bounds either proves hidden, in increasing order; returns how many. */
PVSBAKE_API uint32_t pvsbake_visit_drawn_horizon(const pvsbake_bake* bake, uint32_t cell,
                                                 const pvsbake_culler* culler, const pvsbake_horizon* horizon,
                                                 pvsbake_visit_fn visit, void* user);
/* The same objects into a list: up to capacity of them; returns how many there are (may be more). */
PVSBAKE_API uint32_t pvsbake_drawn_objects_horizon(const pvsbake_bake* bake, uint32_t cell,
                                                   const pvsbake_culler* culler,
                                                   const pvsbake_horizon* horizon, uint32_t* objects,
                                                   size_t capacity);

#ifdef __cplusplus
}
#endif

#endif /* PVSBAKE_OCCLUSION_C_H */
