// SPDX-License-Identifier: MIT
/* A game in plain C over the installed runtime loader (tests/test_loader_install.cpp builds it with CMake,
 * static and shared, and with pkg-config). Usage: game BAKE.h5
 * Loads the bake, walks the PVS of every cell three ways (visit, list, bit set), checks that they agree,
 * and prints one line: "cells C objects O visible V sum S found F", where V is the number of (cell,
 * object) pairs listed, S a checksum of them, and F how many cell centres find_cell maps to their cell.
 * Exit status 1 on any disagreement or a failed load (the message is printed). */
#include <pvsbake/loader_c.h>
#include <pvsbake/occlusion_c.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct Walk {
    uint32_t* objects;
    uint32_t count;
} Walk;

static void collect(void* user, uint32_t object) {
    Walk* walk = (Walk*)user;
    walk->objects[walk->count++] = object;
}

int main(int argc, char** argv) {
    pvsbake_bake* bake = NULL;
    char message[512];
    pvsbake_status status;
    uint32_t cells, objects, c, i, found = 0;
    uint64_t visible = 0, sum = 0;
    size_t words;
    uint32_t *list, *walked;
    uint64_t* bits;
    pvsbake_culler* culler;

    if (argc != 2) {
        fprintf(stderr, "usage: game BAKE.h5\n");
        return 2;
    }
    /* A missing file is a status and a message naming it, not a crash. */
    status = pvsbake_load("no-such-bake.h5", &bake, message, sizeof message);
    if (status != PVSBAKE_FILE_MISSING || bake != NULL || strstr(message, "no-such-bake.h5") == NULL) {
        fprintf(stderr, "game: a missing file gave status %d (%s), message '%s'\n", (int)status,
                pvsbake_status_name(status), message);
        return 1;
    }
    status = pvsbake_load(argv[1], &bake, message, sizeof message);
    if (status != PVSBAKE_OK) {
        fprintf(stderr, "game: %s (%s)\n", message, pvsbake_status_name(status));
        return 1;
    }
    cells = pvsbake_cell_count(bake);
    objects = pvsbake_object_count(bake);
    words = pvsbake_words_per_row(bake);
    list = (uint32_t*)malloc(sizeof(uint32_t) * (objects + 1));
    walked = (uint32_t*)malloc(sizeof(uint32_t) * (objects + 1));
    bits = (uint64_t*)malloc(sizeof(uint64_t) * (words + 1));
    if (list == NULL || walked == NULL || bits == NULL) return 1;
    for (c = 0; c < cells; ++c) {
        Walk walk;
        uint32_t n, listed, set = 0;
        float box[6];
        walk.objects = walked;
        walk.count = 0;
        n = pvsbake_visit_visible(bake, c, collect, &walk);
        listed = pvsbake_visible_objects(bake, c, list, objects);
        if (n != walk.count || listed != n || pvsbake_fill_bitset(bake, c, bits, words) != n) {
            fprintf(stderr, "game: cell %u: the visit, the list and the bit set disagree on the count\n", c);
            return 1;
        }
        for (i = 0; i < n; ++i) {
            const uint32_t o = walked[i];
            if (list[i] != o || (bits[o / 64] >> (o % 64) & 1) == 0 || !pvsbake_is_visible(bake, c, o) ||
                (i > 0 && walked[i - 1] >= o)) {
                fprintf(stderr, "game: cell %u: object %u differs between the three walks\n", c, o);
                return 1;
            }
            sum += (uint64_t)(c + 1) * (o + 1);
        }
        for (i = 0; i < words; ++i) {
            uint64_t w = bits[i];
            for (; w != 0; w &= w - 1) ++set;
        }
        if (set != n) {
            fprintf(stderr, "game: cell %u: the bit set holds %u objects, not %u\n", c, set, n);
            return 1;
        }
        visible += n;
        if (pvsbake_cell_bounds(bake, c, box) &&
            pvsbake_find_cell(bake, (box[0] + box[3]) / 2, (box[1] + box[4]) / 2, (box[2] + box[5]) / 2) ==
                (int32_t)c)
            ++found;
    }
    if (pvsbake_visible_objects(bake, cells, list, objects) != 0 ||
        pvsbake_object_name(bake, objects)[0] != 0) {
        fprintf(stderr, "game: out-of-range indices did not give 0 and \"\"\n");
        return 1;
    }
    /* The culler of moving objects links too. */
    culler = pvsbake_culler_create(0);
    if (culler == NULL) return 1;
    pvsbake_culler_free(culler);
    printf("cells %u objects %u visible %llu sum %llu found %u\n", cells, objects,
           (unsigned long long)visible, (unsigned long long)sum, found);
    free(list);
    free(walked);
    free(bits);
    pvsbake_free(bake);
    return 0;
}
