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
/* pvsr: the pvsbake runtime, for games. Reads a runtime file (.pvsr, docs/FORMAT.md, "The runtime file"),
 * written by `pvsbake export BAKE.h5 -o LEVEL.pvsr`, from memory the game provides (a mapped file, a pak
 * entry), without copying it and without allocating: pvsr_open() checks the bytes once, then every query
 * reads them in place. C99, the C standard library only (string.h, math.h); copy pvsr.h and pvsr.c into a
 * game's tree, or link pvsbake's install. pvsr.hpp wraps it for C++17.
 *
 * Conventions: glTF axes (right-handed, +Y up), metres. Boxes are float[6]: min x, y, z, max x, y, z.
 * Object and cell indices are the bake's. A point outside the view volume has no cell (pvsr_find_cell()
 * gives -1): draw everything there. A bake whose pvsr_is_conservative() is 1 lists every object any eye of
 * the cell may see; otherwise it is "aggressive" (sampled: it may miss small or grazing objects).
 *
 * Safety: pvsr_open() refuses (with a status and a one-line reason) any bytes that are not a whole,
 * consistent runtime file of a version it reads: the checksum, every size, offset and index, and the head
 * of every PVS row are checked, and the row decoder is bounded, so no query of an opened level reads
 * outside its bytes or returns an index out of range, whatever the bytes were. The memory must stay
 * unchanged and alive while the level is used. An opened level is read-only: any number of threads may
 * query it at once. Queries with an index out of range return 0, -1 or "" as each says.
 *
 *   pvsr_level level;
 *   char why[256];
 *   if (pvsr_open(&level, bytes, size, why, sizeof why) != PVSR_OK) { puts(why); ... }
 *   int32_t cell = pvsr_find_cell(&level, x, y, z);         -1: outside the view volume, draw all
 *   if (cell >= 0) pvsr_visit_visible(&level, (uint32_t)cell, draw_object, &scene);
 */
#ifndef PVSR_H
#define PVSR_H

#include <stddef.h>
#include <stdint.h>

/* PVSR_CXX_LINKAGE: compiled as C++ into a namespace of its own (the HDF5 loader's horizon does), so that a
 * game's own copy of the runtime cannot clash with it. */
#if defined(__cplusplus) && !defined(PVSR_CXX_LINKAGE)
extern "C" {
#endif

#define PVSR_VERSION_MAJOR \
    5 /* the newest file version this runtime reads: 1.x to 3.x and 5.x (4.x: refused) */
#define PVSR_VERSION_MINOR 3

typedef enum pvsr_status {
    PVSR_OK = 0,
    PVSR_NOT_A_RUNTIME_FILE = 1, /* too short, or the magic bytes are not there */
    PVSR_VERSION_TOO_NEW = 2,    /* a major version this runtime does not read: a newer one, or 4.x */
    PVSR_CORRUPT = 3,            /* damaged or inconsistent: the checksum, a size, an offset or an index */
    PVSR_UNSUPPORTED = 4,        /* a big-endian machine (the file is little-endian) */
    PVSR_INVALID_ARGUMENT = 5    /* a null pointer where one is required */
} pvsr_status;

/* "ok", "not a runtime file", ... (static strings). */
const char* pvsr_status_name(pvsr_status status);

/* One array of the file: `count` items of `item_bytes` each, at `at` (a pointer into the file's bytes). */
typedef struct pvsr_array {
    const uint8_t* at;
    uint64_t count, bytes; /* bytes: the whole section, padding included */
    uint32_t item_bytes;
} pvsr_array;

/* An opened level: pointers into the caller's bytes and a few counts, filled by pvsr_open(). Read its
 * fields through the functions below; their layout may change between versions of this runtime. */
typedef struct pvsr_level {
    const uint8_t* bytes;
    uint64_t size;
    uint32_t version_major, version_minor;
    uint32_t flags, mask_flags;
    uint32_t object_count, cell_count, cell_kind, node_count, row_count, occluder_box_count;
    uint32_t grid_identity; /* 2.0: a grid whose cells are its (occupied) positions in order: no GRID, CGRD */
    float origin[3], cell_size_m;
    int32_t dims[3];
    float mask_origin[3], mask_voxel_m;
    int32_t mask_dims[3], tile_dims[3];
    pvsr_array grid_to_cell, nodes, cell_grid, cell_boxes, view_tiles, eye_tiles, mask_refs, mask_bits,
        cell_row, row_offsets, code, object_boxes, object_triangles, object_flags, name_offsets, names,
        occluder_boxes, ranked_offsets, ranked_boxes, ranked_measures, strings, occluder_polygons,
        polygon_corners, ranked_polygon_offsets, ranked_polygons, palette_blocks, palette, occupancy,
        occupancy_ranks, horizon_boxes, horizon_tiles, horizon_corners, horizon_list_offsets, horizon_lists,
        object_part_offsets, object_parts, row_offset_bases, ranked_counts, ranked_count_bases,
        horizon_cell_offsets, horizon_cell_lists, horizon_test_offsets, horizon_tests;
    uint64_t code_bytes; /* the code without its padding */
    uint64_t total_triangles;
} pvsr_level;

/* Checks `size` bytes at `data` (8-byte aligned: a mapped file or malloc'ed block is) and fills *level.
 * message (may be NULL) receives a NUL-terminated, possibly shortened, one-line reason ("" when ok). On
 * failure *level is zeroed: every query of it answers as for an empty level. Costs one pass over the bytes
 * (the checksum, with the rows and the big index arrays checked as it passes them) and one over the cells
 * and objects; allocates nothing (about 4 KiB of stack). */
pvsr_status pvsr_open(pvsr_level* level, const void* data, size_t size, char* message, size_t message_size);

/* sizeof(pvsr_level), sizeof(pvsr_culler) and sizeof(pvsr_horizon), for languages that reach the runtime
 * through a C FFI (Python's ctypes, C#, Rust) and allocate its structs themselves. */
size_t pvsr_level_bytes(void);
size_t pvsr_culler_bytes(void);
size_t pvsr_horizon_bytes(void);

uint32_t pvsr_cell_count(const pvsr_level* level);
uint32_t pvsr_object_count(const pvsr_level* level);
uint32_t pvsr_cell_kind(const pvsr_level* level); /* 0 grid, 1 octree */
/* 64-bit words a PVS bit set of this level needs: ceil(objects / 64). */
size_t pvsr_words_per_row(const pvsr_level* level);

/* ---- Cells */
/* The cell holding (x, y, z), or -1 outside the view volume or every cell. O(1) on a grid, O(depth) on an
 * octree. Grid cells are half-open except on the grid's max faces; view voxels are closed boxes. */
int32_t pvsr_find_cell(const pvsr_level* level, float x, float y, float z);
/* 1 when (x, y, z) is in the EYE SPACE (the free voxels where the bake's eyes are, closed boxes), where the
 * bake's promises hold; pvsr_find_cell() also answers in a rim a voxel wide around it. A game that culls
 * moving objects with the ranked occluders should do so only where this is 1. Levels without an eye mask:
 * 1 wherever pvsr_find_cell() finds a cell. */
int pvsr_in_eye_space(const pvsr_level* level, float x, float y, float z);
/* The box of cell c into box[6]; 0 (box untouched) when c is out of range. */
int pvsr_cell_bounds(const pvsr_level* level, uint32_t cell, float box[6]);

/* ---- The potentially visible set of a cell */
typedef void (*pvsr_visit_fn)(void* user, uint32_t object);
/* Calls visit(user, object) for every object visible from the cell, in increasing order; returns how many
 * (0 for a cell out of range). Allocates nothing (a bit set of up to 2 KiB on the stack for levels of
 * up to 16,384 objects). */
uint32_t pvsr_visit_visible(const pvsr_level* level, uint32_t cell, pvsr_visit_fn visit, void* user);
/* The number of objects visible from the cell. */
uint32_t pvsr_visible_count(const pvsr_level* level, uint32_t cell);
/* Writes up to capacity visible object indices in increasing order; returns how many there are (may be
 * more than capacity). */
uint32_t pvsr_visible_objects(const pvsr_level* level, uint32_t cell, uint32_t* objects, size_t capacity);
struct pvsr_culler; /* below, with the culler's calls */
/* What a game draws of the cell from one eye: the cell's PVS less what the culler, set up for this frame
 * (pvsr_culler_begin_cell() with the cell's ranked occluders, or pvsr_culler_begin_frame()), proves hidden
 * by the object's bounds. Objects flagged always visible, and objects without bounds, are never culled. Calls
 * visit(user, object) for every drawn object, in increasing order; returns how many. A NULL culler draws the
 * whole PVS (pvsr_visit_visible()). Allocates nothing; the culler is only read, so threads may walk cells
 * with one culler between its begin calls (docs/ALGORITHMS.md#runtime-culler). */
uint32_t pvsr_visit_drawn(const pvsr_level* level, uint32_t cell, const struct pvsr_culler* culler,
                          pvsr_visit_fn visit, void* user);
/* The same objects into a list: writes up to capacity of them in increasing order; returns how many there
 * are (may be more than capacity). */
uint32_t pvsr_drawn_objects(const pvsr_level* level, uint32_t cell, const struct pvsr_culler* culler,
                            uint32_t* objects, size_t capacity);
/* Fills words[0 .. word_count) with the cell's PVS as a bit set (object i = bit i % 64 of word i / 64; the
 * words past the objects zero); returns the number of visible objects, or UINT32_MAX (words untouched)
 * when word_count < pvsr_words_per_row(), words is NULL or the cell is out of range. */
uint32_t pvsr_fill_bitset(const pvsr_level* level, uint32_t cell, uint64_t* words, size_t word_count);
/* 1 when object o is visible from the cell; 0 otherwise or out of range. */
int pvsr_is_visible(const pvsr_level* level, uint32_t cell, uint32_t object);

/* ---- Objects: name (UTF-8, NUL-terminated, in the file's bytes; "" out of range), bounds, triangles,
 * flags (bit 0 opaque, 1 see-through, 2 always visible, 3 never occludes). */
#define PVSR_OBJECT_OPAQUE 1u
#define PVSR_OBJECT_SEE_THROUGH 2u
#define PVSR_OBJECT_ALWAYS_VISIBLE 4u
#define PVSR_OBJECT_NEVER_OCCLUDES 8u
const char* pvsr_object_name(const pvsr_level* level, uint32_t object);
int pvsr_object_bounds(const pvsr_level* level, uint32_t object, float box[6]);
uint32_t pvsr_object_triangles(const pvsr_level* level, uint32_t object);
uint32_t pvsr_object_flags(const pvsr_level* level, uint32_t object);
uint64_t pvsr_total_triangles(const pvsr_level* level);
/* File 2.2: an object's part boxes (docs/ALGORITHMS.md#object-parts): its surface cut into a few pieces,
 * each inside one part box, every part inside the object's bounds. The walks with a culler or horizon cull an
 * object whose bounds they do not hide when they hide every part. Count 0 when it has none (or an older
 * file); pvsr_object_part writes part `part` (float[6]), 0 when out of range. */
uint32_t pvsr_object_part_count(const pvsr_level* level, uint32_t object);
int pvsr_object_part(const pvsr_level* level, uint32_t object, uint32_t part, float box[6]);
/* For tools that write runtime files. File 5.1 stores a part as six 16-bit steps on a grid of its object's
 * bounds (docs/FORMAT.md, 'OPBQ'): this writes the steps of the part rounded outward, and the box every
 * reader decodes from them (bit for bit on every platform: it holds `part` and lies inside `bounds`). 0 when
 * bounds or part is not finite, or part is not a box inside bounds. */
int pvsr_part_encode(const float bounds[6], const float part[6], uint16_t steps[6], float box[6]);

/* ---- Ranked occluders of a cell, best first (docs/FORMAT.md, "Ranked occluders"): boxes inside the
 * opaque solid worth testing at run time to cull moving objects. box is float[6]; score higher is better;
 * solid_angle_sr the largest from the cell's sampled eyes; hidden_objects the mean number of objects, and
 * hidden_triangle_share the mean share of the world's triangles, wholly in its shadow. */
typedef struct pvsr_ranked_occluder {
    float box[6];
    float score;
    float solid_angle_sr;
    float hidden_objects;
    float hidden_triangle_share;
} pvsr_ranked_occluder;
uint32_t pvsr_occluder_count(const pvsr_level* level, uint32_t cell);
/* The occluder of that rank (0 = best) into *out: 1, or 0 (out untouched) out of range (or, in a file made
 * to pass the checksum, an entry past its block's palette: pvsr_occluder_boxes gives an empty box). Its
 * measures are NaN when the file does not hold them (pvsr_has_occluder_measures: `pvsbake export
 * --occluder-measures`). */
int pvsr_occluder(const pvsr_level* level, uint32_t cell, uint32_t rank, pvsr_ranked_occluder* out);
/* The boxes of the best min(count, capacity) occluders of the cell into boxes (6 floats each), best first;
 * returns how many were written. */
uint32_t pvsr_occluder_boxes(const pvsr_level* level, uint32_t cell, float* boxes, uint32_t capacity);
int pvsr_has_occluder_measures(const pvsr_level* level);
/* File version 1.1: the cell's ranked POLYGON occluders (slanted panels of the opaque surface, for the faces
 * test: pvsr_culler_add_polygon()), best first. They rank among the boxes: a cell's whole list of ranked
 * occluders holds its pvsr_occluder_count() boxes and its pvsr_occluder_polygon_count() polygons, each
 * polygon at the place *place says (0 = the best of all), the boxes in order at the other places. Older
 * files: none. */
uint32_t pvsr_occluder_polygon_count(const pvsr_level* level, uint32_t cell);
/* The cell's polygon of that rank among its polygons (0 = best): writes plane[5] (normal x, y, z, offset,
 * thickness), up to `capacity` corners (3 floats each, PVSR_POLYGON_MAX_CORNERS at most) and, when place is
 * not NULL, its place in the cell's whole list; returns its corner count, or 0 (nothing written) out of
 * range. */
uint32_t pvsr_occluder_polygon(const pvsr_level* level, uint32_t cell, uint32_t rank, float plane[5],
                               float* corners, uint32_t capacity, uint32_t* place);

/* ---- What the bake is */
int pvsr_is_conservative(const pvsr_level* level);
const char* pvsr_mode_label(const pvsr_level* level); /* "conservative" or "aggressive" */
/* The bake's strings by key: "tool_version", "world_path", "world_hash", "mode"; "" when absent. They live
 * in the file's bytes. */
const char* pvsr_string(const pvsr_level* level, const char* key);

/* ---- The culler of moving objects (characters, vehicles, props: what no PVS lists) against a few occluder
 * boxes, such as a cell's ranked occluders: the same tests and answers as pvsbake/occlusion.h, whose
 * conventions it follows (read them there): shadow frusta of single boxes, then a float depth cube around the
 * eye that fuses them, then the exact union of their faces toward the eye (closing the junctions where they
 * meet, up to 1e-9 of the coordinates' scale); "hidden" only when certainly hidden
 * (docs/ALGORITHMS.md#runtime-culler). Boxes are float[6] (min x, y, z, max x, y, z), SOLID; an occluder flat
 * along exactly one axis is a PANEL, a rectangle of the opaque surface (docs/ALGORITHMS.md#runtime-panels).
 * No allocation: the depth cube lives in memory the caller gives (pvsr_culler_memory_bytes). Between
 * pvsr_culler_begin_frame() calls any number of threads may test boxes.
 *
 *   static pvsr_culler culler;                     (about 74 KiB; keep one per thread that begins frames)
 *   pvsr_culler_init(&culler, 0, NULL, 0);         (no depth cube: for the culled walk the faces fuse
 *                                                   exactly; with many moving objects a cube of 32 may pay:
 *                                                   pvsr_culler_init(&culler, 32, memory, bytes), bytes =
 *                                                   pvsr_culler_memory_bytes(32))
 *   each frame: pvsr_culler_begin_cell(&culler, &level, cell, eye, PVSR_CULLER_MAX_OCCLUDERS);
 *               pvsr_visit_drawn(&level, cell, &culler, draw_object, &scene);     (the level's objects)
 *               for each moving object: if (!pvsr_culler_is_hidden(&culler, box)) draw(object);
 * (pvsr_culler_begin_frame() takes any boxes instead of the cell's ranked occluders; then
 * pvsr_culler_add_polygon() any convex polygons: docs/ALGORITHMS.md#runtime-polygons.)
 */
#define PVSR_CULLER_MAX_OCCLUDERS 64 /* more are ignored: pass the best first */
#define PVSR_CULLER_MAX_POLYGONS 32  /* polygon occluders of a frame; more are refused */
#define PVSR_POLYGON_MAX_CORNERS 8   /* corners of a polygon occluder */
#define PVSR_CULLER_MIN_RESOLUTION 2
#define PVSR_CULLER_MAX_RESOLUTION 256

typedef enum pvsr_cull_path {
    PVSR_CULL_VISIBLE = 0,        /* not proven hidden: draw it */
    PVSR_CULL_SHADOW_FRUSTUM = 1, /* inside the shadow frustum of one occluder */
    PVSR_CULL_DEPTH_CUBE = 2,     /* hidden by the fused depth cube, not by one frustum */
    PVSR_CULL_FACES = 3           /* hidden by the exact union of the occluders' faces only */
} pvsr_cull_path;

typedef struct pvsr_culler_frustum {
    double lo[3], hi[3], n[6][3], w[6];
    int planes, usable;
} pvsr_culler_frustum;

typedef struct pvsr_culler_candidate {
    float box[6], raster[6]; /* raster: what the depth cube draws (a panel's rectangle shrunk by delta) */
    int flat;                /* a panel's flat axis, -1 for a solid box */
    double delta, dist2;
} pvsr_culler_candidate;

/* A face that hides what lies beyond its plane from the eye: a panel, or a solid box's face toward the eye,
 * its rectangle shrunk by delta (docs/ALGORITHMS.md#runtime-faces). */
typedef struct pvsr_culler_face {
    double plane, lo[2], hi[2]; /* x[axis] = plane; the rectangle on axes (axis + 1) % 3, (axis + 2) % 3 */
    double delta;
    double rel_plane, rel_lo[2], rel_hi[2]; /* the same less the eye */
    int axis, above; /* above: the eye is below the plane, and what lies above it is hidden */
    int axis1, axis2; /* (axis + 1) % 3, (axis + 2) % 3 */
} pvsr_culler_face;

/* A convex polygon occluder as the culler keeps it (pvsr_culler_add_polygon): the slab, its normal turned
 * away from the eye, and the prism over its corners (docs/ALGORITHMS.md#runtime-polygons). */
typedef struct pvsr_culler_polygon {
    /* Relative to the eye (x is a point less the eye): */
    double n[3];                 /* unit, pointing away from the eye */
    double near_w, far_w, delta; /* the slab: near_w <= n.x <= far_w, 0 < near_w (the eye before it) */
    double c[PVSR_POLYGON_MAX_CORNERS][3]; /* the corners */
    double m[PVSR_POLYGON_MAX_CORNERS][3]; /* the prism: m[i].x >= k[i] for every edge i */
    double k[PVSR_POLYGON_MAX_CORNERS];
    int count, axis; /* axis: the largest |n[axis]| */
} pvsr_culler_polygon;

/* A culler: its fields are the runtime's (their layout may change between versions). */
typedef struct pvsr_culler {
    int ok, eye_ok, resolution;
    float eye[3];
    double eye_d[3];
    size_t used, redundant, frustum_count, candidate_count;
    pvsr_culler_candidate candidates[PVSR_CULLER_MAX_OCCLUDERS];
    pvsr_culler_frustum frusta[PVSR_CULLER_MAX_OCCLUDERS];
    size_t face_count;
    pvsr_culler_face faces[3 * PVSR_CULLER_MAX_OCCLUDERS];
    /* Per face and per frame of the faces test (axis p, sign: 2 p + (sign < 0)), the bounds of its projection
     * (u lo, v lo, u hi, v hi), rounded outward; lo > hi when it has none. */
    float face_directions[6][3 * PVSR_CULLER_MAX_OCCLUDERS][4];
    size_t polygon_count;
    pvsr_culler_polygon polygons[PVSR_CULLER_MAX_POLYGONS];
    int written[6][4]; /* per face: i0, i1, j0, j1 of the written pixels (empty when i0 > i1) */
    float *grid, *depth, *col_enter, *col_exit, *row_enter, *row_exit, *corner_prev, *corner_cur;
} pvsr_culler;

/* Bytes of memory a culler of that resolution needs (pixels per cube face edge, rounded up to even and
 * clamped to [2, 256]; 0 or less: shadow frusta only, no memory). */
size_t pvsr_culler_memory_bytes(int resolution);
/* Sets the culler up on `memory` (4-byte aligned, at least pvsr_culler_memory_bytes(resolution) bytes, kept
 * while the culler is used). 1, or 0 when the memory is missing or too small: then it culls nothing. */
int pvsr_culler_init(pvsr_culler* culler, int resolution, void* memory, size_t memory_bytes);
/* Prepares a frame: the eye (float[3]) and `count` occluder boxes (6 floats each, count * 6 floats). */
void pvsr_culler_begin_frame(pvsr_culler* culler, const float eye[3], const float* boxes, size_t count);
/* Prepares a frame with the best min(max_occluders, PVSR_CULLER_MAX_OCCLUDERS) of the cell's ranked
 * occluders, boxes (pvsr_occluder_boxes()) and polygons (pvsr_culler_add_polygon()) at their places; returns
 * how many were given. Allocates nothing (a buffer of PVSR_CULLER_MAX_OCCLUDERS boxes on the stack). Then
 * pvsr_visit_drawn() gives what to draw. */
uint32_t pvsr_culler_begin_cell(pvsr_culler* culler, const pvsr_level* level, uint32_t cell,
                                const float eye[3], uint32_t max_occluders);
/* Adds a convex POLYGON occluder to this frame, after pvsr_culler_begin_frame(): a slanted panel of the
 * opaque surface (pvsr_occluder_polygon()). plane = normal x, y, z, offset, thickness: the opaque surface
 * lies in the slab |normal . x - offset| <= thickness; corners = `count` points of 3 floats, convex and
 * counter-clockwise seen from the side the normal points to, 3 <= count <= PVSR_POLYGON_MAX_CORNERS. Its
 * promise: every segment that crosses the slab from one side to the other, entering and leaving it inside the
 * prism over the corners (along the normal), meets the opaque surface. Only the faces test uses polygons.
 * 1 when added; 0 when refused (the eye within the slab's margin, a polygon that is not convex and
 * counter-clockwise, a value that is not finite, or PVSR_CULLER_MAX_POLYGONS already added). */
int pvsr_culler_add_polygon(pvsr_culler* culler, const float plane[5], const float* corners, uint32_t count);
/* 1 only if the box (float[6]) is certainly hidden from this frame's eye. */
int pvsr_culler_is_hidden(const pvsr_culler* culler, const float box[6]);
/* Which test proved it (pvsr_cull_path). */
int pvsr_culler_classify(const pvsr_culler* culler, const float box[6]);

/* ---- The occlusion horizon: MANY occluders fused exactly where they meet, whatever their planes
 * (docs/ALGORITHMS.md#runtime-horizon). Around the eye, four side frames (+x, -x, +z, -z; y is up) are cut
 * into `columns` columns of directions each (a power of two: the leaves of a binary tree); every occluder
 * face adds, over the columns it spans whole, trapezoids of directions between its chords (within its
 * directions there), each over a node of the tree, with its depth. A box is hidden when in every column its
 * directions fall in, the pieces over it lying wholly before it cover its whole height range: an exact union
 * in v, along chords at any slope, so a wall on a floor, terrain polygons sharing an edge and a roof over
 * walls hide together what none hides alone. The occluders are those of the culler: solid boxes (faces
 * towards the eye), panels (a box flat along one axis) and polygon occluders, in any order and any number up
 * to the pieces the memory holds (past them, the rest are dropped: fewer pieces only cull less). "Hidden"
 * means, as for the culler's faces test, that every segment from the eye to the box meets an occluder or
 * passes within about 1e-9 of the coordinates' scale of one. No allocation: the pieces live in memory the
 * caller gives.
 *
 *   static pvsr_horizon h;
 *   pvsr_horizon_init(&h, 256, 65536, memory, pvsr_horizon_memory_bytes(256, 65536));
 *   each frame: pvsr_horizon_begin(&h, eye);
 *               pvsr_horizon_add_box(&h, box) / pvsr_horizon_add_polygon(&h, plane, corners, n) /
 *               pvsr_horizon_add_tile(&h, plane, corners, n) for each;
 *               pvsr_horizon_end(&h);
 *               if (!pvsr_horizon_is_hidden(&h, bounds)) draw(object);   (any number of threads)
 */
#define PVSR_HORIZON_MIN_COLUMNS 4
#define PVSR_HORIZON_MAX_COLUMNS 8192
#define PVSR_HORIZON_MAX_CORNERS 32 /* of a polygon occluder given to the horizon */
/* Bytes after the horizon lists ('HLST', 5.0) that their reader may read, for n occluders (FORMAT.md). */
#define PVSR_HORIZON_LIST_PADDING(n) ((n) / 4 + 32)

typedef struct pvsr_horizon_piece {
    /* Every direction (u, v) with u in [u[0], u[1]] and v between the line through (u[0], lo[0]) and
     * (u[1], lo[1]) and the line through (u[0], hi[0]) and (u[1], hi[1]) meets an occluder (a trapezoid;
     * docs/ALGORITHMS.md#runtime-horizon). u[0], u[1]: the sides of its node's columns, or, for a face's
     * end within a column, of the face's part of that column. */
    double lo[2], hi[2];
    double depth;    /* at least the depth of the occluder anywhere over the trapezoid */
    double plane[3]; /* 1 / the occluder's depth at direction (u, v): plane[0] + plane[1] u + plane[2] v */
    uint32_t column; /* frame * 2 * columns + the node of the frame's tree (docs/ALGORITHMS.md) */
    uint32_t tag;    /* the caller's tag of its occluder (pvsr_horizon_set_tag) */
    float reach; /* after pvsr_horizon_end(): at least the highest top of this piece and those before it */
    float u[2];
} pvsr_horizon_piece;

/* A horizon: its fields are the runtime's (their layout may change between versions). */
typedef struct pvsr_horizon {
    int ok, eye_ok, ready, columns;
    double eye[3], scale;
    size_t capacity, count, dropped; /* pieces the memory holds, added this frame, dropped for want of room */
    uint32_t tag;                    /* the tag of the pieces the adds make */
    pvsr_horizon_piece *pieces, *sorted;
    uint32_t*
        first; /* after pvsr_horizon_end(): node j's pieces are sorted[first[j]] .. sorted[first[j+1]) */
} pvsr_horizon;

/* Bytes of memory a horizon of that many columns a frame and pieces needs (columns clamped to
 * [PVSR_HORIZON_MIN_COLUMNS, PVSR_HORIZON_MAX_COLUMNS] and rounded down to a power of two). */
size_t pvsr_horizon_memory_bytes(int columns, size_t max_pieces);
/* Sets the horizon up on `memory` (8-byte aligned, at least pvsr_horizon_memory_bytes() bytes, kept while
 * the horizon is used). 1, or 0 when the memory is missing or too small: then it hides nothing. */
int pvsr_horizon_init(pvsr_horizon* h, int columns, size_t max_pieces, void* memory, size_t memory_bytes);
/* Starts a frame at the eye (float[3]); nothing is hidden until pvsr_horizon_end(). */
void pvsr_horizon_begin(pvsr_horizon* h, const float eye[3]);
/* Adds an occluder box (float[6]): solid, or a panel when flat along exactly one axis. 1 when it added a
 * face; 0 when it adds nothing (not finite, empty, flat along two axes, holding the eye, a panel seen
 * edge-on, or no face of it towards the eye). */
int pvsr_horizon_add_box(pvsr_horizon* h, const float box[6]);
/* Adds a polygon occluder, with the promise and the arguments of pvsr_culler_add_polygon() but up to
 * PVSR_HORIZON_MAX_CORNERS corners; 1 when added. */
int pvsr_horizon_add_polygon(pvsr_horizon* h, const float plane[5], const float* corners, uint32_t count);
/* Adds a TILE: a polygon occluder (the arguments of pvsr_horizon_add_polygon()) with a stronger promise: its
 * corners, in order, are the boundary of a disk of opaque surface lying within the slab, such as a mesh's
 * triangles whose vertices are all among the corners (the bake's slanted panels, kept whole). Then every
 * direction from an eye outside the slab inside the corners' projection meets the surface, so tiles sharing
 * an edge (the same corners) fuse exactly there, with no seam for the slab's thickness. A tile also keeps
 * pvsr_horizon_add_polygon()'s promise, and any polygon of a subset of its corners keeps that one. 1 when
 * added. */
int pvsr_horizon_add_tile(pvsr_horizon* h, const float plane[5], const float* corners, uint32_t count);
/* Ends the frame's occluders (sorts the pieces by node); then boxes may be tested, and nothing more is
 * added until the next pvsr_horizon_begin() (the adds return 0). */
void pvsr_horizon_end(pvsr_horizon* h);
/* 1 only if the box (float[6]) is certainly hidden from this frame's eye by the horizon. */
int pvsr_horizon_is_hidden(const pvsr_horizon* h, const float box[6]);
/* Which occluders hide what: the tag the next adds give their pieces (0 after pvsr_horizon_begin()), and
 * pvsr_horizon_is_hidden() that, when the box is hidden, calls use(user, tag) for the pieces of the chains
 * that proved it (a tag may come more than once; up to 1024 calls). For a bake or a tool choosing which
 * occluders a cell's list should hold. */
typedef void (*pvsr_horizon_use_fn)(void* user, uint32_t tag);
void pvsr_horizon_set_tag(pvsr_horizon* h, uint32_t tag);
int pvsr_horizon_hidden_by(const pvsr_horizon* h, const float box[6], pvsr_horizon_use_fn use, void* user);

/* ---- The cell's horizon occluders (file 2.1; docs/ALGORITHMS.md#horizon-lists): the proven boxes, panels
 * and tiles (the slanted panels kept whole) that the bake chose for the block of cells holding the cell, by
 * the use this horizon made of them from eyes of the block. A frame:
 *
 *   pvsr_horizon_begin_cell(&h, &level, cell, eye);
 *   pvsr_visit_drawn_horizon(&level, cell, &culler, &h, draw_object, scene);   (culler may be NULL)
 *
 * Every listed occluder is proven, so any frame's answers are safe; the lists only decide which occluders
 * are worth the frame's time. */
/* Occluders of the cell's list (0 when the file has no lists or the cell is out of range): its block's list,
 * or from file 5.2, where the bake chose lists per cell, the cell's own part of it. */
uint32_t pvsr_horizon_list_count(const pvsr_level* level, uint32_t cell);
/* Occluders in the file's horizon set (boxes, then tiles); a list's entries index them. */
uint32_t pvsr_horizon_occluder_count(const pvsr_level* level);
/* A frame of the horizon at the eye with the cell's list: pvsr_horizon_begin(), each occluder added (tagged
 * with its index in the file's set, for pvsr_horizon_hidden_by()), pvsr_horizon_end(). Returns the occluders
 * given (those that add no face from this eye count too); with no list the horizon hides nothing. */
uint32_t pvsr_horizon_begin_cell(pvsr_horizon* h, const pvsr_level* level, uint32_t cell, const float eye[3]);
/* pvsr_visit_drawn() culled by the horizon as well: an object is drawn unless the culler (when given) or the
 * horizon (when given, after its pvsr_horizon_end()) proves its bounds hidden. Both are only read: threads
 * may walk cells with them. */
uint32_t pvsr_visit_drawn_horizon(const pvsr_level* level, uint32_t cell, const struct pvsr_culler* culler,
                                  const pvsr_horizon* horizon, pvsr_visit_fn visit, void* user);
/* The same objects into a list, as pvsr_drawn_objects(). */
uint32_t pvsr_drawn_objects_horizon(const pvsr_level* level, uint32_t cell, const struct pvsr_culler* culler,
                                    const pvsr_horizon* horizon, uint32_t* objects, size_t capacity);

/* ---- The file's layout (docs/FORMAT.md, "The runtime file"), for writers and tools. Little-endian.
 * A 64-byte header, then the section table (PVSR_ENTRY_BYTES an entry), then the sections, each at an offset
 * that is a multiple of 64, in any order. */
#define PVSR_HEADER_BYTES 64
#define PVSR_ENTRY_BYTES 32
#define PVSR_ALIGN 64
#define PVSR_CHECKSUMMED_FROM 32 /* the checksum covers bytes [32, file size) */
#define PVSR_FLAG_CONSERVATIVE 1u
#define PVSR_MASK_VIEW 1u
#define PVSR_MASK_EYES 2u
#define PVSR_TAG(a, b, c, d) ((uint32_t)(a) | (uint32_t)(b) << 8 | (uint32_t)(c) << 16 | (uint32_t)(d) << 24)
#define PVSR_LEVEL_BYTES 64        /* 'LEVL': the cells' grid and the masks' voxels */
#define PVSR_NODE_BYTES 20         /* 'NODE': float center[3], int32 first_child, int32 cell */
#define PVSR_MEASURE_BYTES 16      /* 'RMEA': float score, solid angle, hidden objects, hidden triangle share */
#define PVSR_POLYGON_BYTES \
    32 /* 'OPLN': float normal[3], offset, thickness; uint32 first corner, corners, 0 */
#define PVSR_MAX_OBJECTS (1u << 27) /* the PVS code's limit */
#define PVSR_MAX_CHAIN 16 /* rows XORed to decode one row: a key row and up to 15 coded against it */
#define PVSR_STACK_OBJECTS 16384    /* objects of the bit set a walk keeps on the stack; past it, chains of 2 */
#define PVSR_TILE_BRICKS 4          /* a mask tile is 4 x 4 x 4 bricks of 8 x 8 x 8 voxels */
#define PVSR_BRICK_EMPTY 0u         /* a tile or brick reference: no voxel set */
#define PVSR_BRICK_FULL 1u          /* every voxel set */
#define PVSR_FIRST_BRICK 2u         /* 2 + j: block (tile) or bits (brick) j */

/* ---- The checksum of the file (docs/FORMAT.md): XXH64 with seed 0, exposed for tools and tests. */
uint64_t pvsr_xxh64(const void* data, size_t size, uint64_t seed);

#if defined(__cplusplus) && !defined(PVSR_CXX_LINKAGE)
}
#endif

#endif /* PVSR_H */
