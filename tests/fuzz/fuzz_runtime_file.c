// SPDX-License-Identifier: MIT
/* libFuzzer target of the C99 runtime (runtime/pvsr.h): any bytes, with the checksum made right (so that the
 * mutations reach the structural checks), are refused by pvsr_open() or every query of the level stays inside
 * the bytes and in range (the cells' occluders, boxes and polygons, given to a culler too); and the culler of
 * moving objects, given the bytes as floats (an eye, occluder boxes, polygons, boxes to test: any values, NaN
 * and infinities too), stays in its memory. Built with Clang, -fsanitize=fuzzer,address,undefined
 * (tests/CMakeLists.txt); run fuzz_runtime_file -runs=1000000 CORPUS_DIR SEEDS_DIR with the seeds
 * make_runtime_seeds writes. docs/RESULTS.md has the runs. */
#include "pvsr.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static void visit(void* user, uint32_t object) {
    if (object >= *(const uint32_t*)user) abort(); /* an index out of range */
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    /* The bytes, 8-byte aligned in a buffer of exactly their size (ASan sees any read past them). */
    uint8_t* bytes = (uint8_t*)malloc(size ? size : 1);
    pvsr_level level;
    uint32_t c, k, objects;
    size_t i;
    if (bytes == NULL) return 0;
    if (size) memcpy(bytes, data, size);
    if (size >= 64) {
        const uint64_t sum = pvsr_xxh64(bytes + 32, size - 32, 0);
        memcpy(bytes + 24, &sum, 8);
        memcpy(bytes + 16, &(uint64_t){(uint64_t)size}, 8);
    }
    if (pvsr_open(&level, bytes, size, NULL, 0) == PVSR_OK) {
        objects = pvsr_object_count(&level);
        for (c = 0; c < pvsr_cell_count(&level) && c < 4096; ++c) {
            float box[6];
            pvsr_ranked_occluder o;
            pvsr_visit_visible(&level, c, visit, &objects);
            (void)pvsr_is_visible(&level, c, objects / 2);
            (void)pvsr_cell_bounds(&level, c, box);
            for (k = 0; k < pvsr_occluder_count(&level, c) && k < 64; ++k) (void)pvsr_occluder(&level, c, k, &o);
            for (k = 0; k < pvsr_occluder_polygon_count(&level, c) && k < 64; ++k) {
                float plane[5], corners[3 * PVSR_POLYGON_MAX_CORNERS];
                uint32_t place;
                if (pvsr_occluder_polygon(&level, c, k, plane, corners, PVSR_POLYGON_MAX_CORNERS, &place) >
                    PVSR_POLYGON_MAX_CORNERS)
                    abort(); /* a polygon with more corners than checked */
            }
            if (c < 64) { /* the cell's occluders, boxes and polygons, in the culler */
                static pvsr_culler cell_culler;
                const float eye[3] = {box[0], box[1], box[2]};
                pvsr_culler_init(&cell_culler, 0, NULL, 0);
                (void)pvsr_culler_begin_cell(&cell_culler, &level, c, eye, PVSR_CULLER_MAX_OCCLUDERS);
                (void)pvsr_culler_classify(&cell_culler, box);
            }
            if (c < 64 && pvsr_horizon_occluder_count(&level) > 0) { /* the cell's horizon list (2.1) */
                static pvsr_horizon horizon;
                static uint64_t horizon_memory[8192];
                static int horizon_ready;
                const float eye[3] = {box[3], box[4], box[5]};
                if (!horizon_ready)
                    horizon_ready =
                        pvsr_horizon_init(&horizon, 16, 256, horizon_memory, sizeof horizon_memory);
                (void)pvsr_horizon_list_count(&level, c);
                (void)pvsr_horizon_begin_cell(&horizon, &level, c, eye);
                (void)pvsr_horizon_is_hidden(&horizon, box);
                /* the walk culled by the horizon, with the objects' parts (2.2) */
                (void)pvsr_visit_drawn_horizon(&level, c, NULL, &horizon, visit, &objects);
            }
        }
        for (k = 0; k < objects && k < 4096; ++k) {
            float part[6];
            uint32_t p;
            (void)strlen(pvsr_object_name(&level, k));
            for (p = 0; p < pvsr_object_part_count(&level, k) && p < 64; ++p)
                if (!pvsr_object_part(&level, k, p, part) || !(part[0] <= part[3]))
                    abort(); /* checked at open */
        }
        (void)strlen(pvsr_string(&level, "mode"));
        for (i = 0; i + 12 <= size && i < 12 * 64; i += 12) {
            float p[3];
            memcpy(p, data + i, 12);
            if (pvsr_find_cell(&level, p[0], p[1], p[2]) >= (int32_t)pvsr_cell_count(&level)) abort();
            (void)pvsr_in_eye_space(&level, p[0], p[1], p[2]);
        }
    }
    {
        /* The culler: eye, up to 12 occluders and up to 16 boxes from the bytes as floats. */
        static pvsr_culler culler;
        static float memory[6 * 8 * 8 + 7 * 9];
        static int ready = 0;
        const size_t floats = size / 4;
        float* f = (float*)malloc(sizeof(float) * (floats + 1));
        if (f != NULL) {
            size_t boxes, q;
            if (!ready) ready = pvsr_culler_init(&culler, 8, memory, sizeof memory);
            memcpy(f, data, 4 * floats);
            if (floats >= 3) {
                boxes = (floats - 3) / 6;
                pvsr_culler_begin_frame(&culler, f, f + 3, boxes < 12 ? boxes : 12);
                for (q = 0; q < 4 && 3 + 29 * (q + 1) <= floats; ++q) /* polygons: plane, corners */
                    (void)pvsr_culler_add_polygon(&culler, f + 3 + 29 * q, f + 8 + 29 * q, 3 + (uint32_t)q);
                for (q = 0; q < 16 && 3 + 6 * (q + 1) <= floats; ++q) (void)pvsr_culler_classify(&culler, f + 3 + 6 * q);
            }
            free(f);
        }
    }
    free(bytes);
    return 0;
}
