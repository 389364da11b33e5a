// SPDX-License-Identifier: MIT
/* runtime_check CASES.txt: the C99 runtime (runtime/pvsr.h) against expectations the HDF5 loader wrote
 * (make_runtime_cases), on whatever machine this is built for: natively, 32-bit x86, Windows (MinGW-w64,
 * run under Wine) and WebAssembly (Emscripten, run under Node). For each case: the runtime file opens; every
 * cell's visible objects, bounds and ranked occluders, every object's name, bounds, triangles and flags, and
 * the cell and eye space of each listed point are as expected; the file truncated, with a byte flipped, or
 * with another magic is refused with its status. Floats are compared bit for bit. C99 and the C library only.
 * Exit status 0 when everything holds; else the first difference is printed. */
#include "pvsr.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;
static unsigned long culled = 0;
static unsigned long drawn_culled = 0; /* objects of cells' PVS that drawn walks leave out */
static pvsr_culler culler;

#define CHECK(cond, ...)                              \
    do {                                              \
        if (!(cond)) {                                \
            if (failures++ < 20) {                    \
                fprintf(stderr, "runtime_check: ");   \
                fprintf(stderr, __VA_ARGS__);         \
                fprintf(stderr, "\n");                \
            }                                         \
        }                                             \
    } while (0)

static uint32_t bits_of(float f) {
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}
static float float_of(unsigned long u) {
    uint32_t v = (uint32_t)u;
    float f;
    memcpy(&f, &v, 4);
    return f;
}

/* The whole file, in an 8-byte aligned block of `*size` bytes (NULL when it cannot be read). */
static void* read_all(const char* path, size_t* size) {
    FILE* f = fopen(path, "rb");
    void* data;
    long n;
    if (f == NULL) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return NULL;
    }
    data = malloc((size_t)n + 8);
    if (data != NULL && fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        data = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return data;
}

typedef struct counter {
    const unsigned long* want;
    unsigned long n, at;
    int bad;
} counter;

static void expect_next(void* user, uint32_t object) {
    counter* c = (counter*)user;
    if (c->at >= c->n || c->want[c->at] != object) c->bad = 1;
    ++c->at;
}

static void check_damage(const uint8_t* good, size_t size) {
    char why[256];
    pvsr_level l;
    uint8_t* copy = (uint8_t*)malloc(size + 8);
    if (copy == NULL) return;
    memcpy(copy, good, size);
    CHECK(pvsr_open(&l, copy, size - 64, why, sizeof why) == PVSR_CORRUPT && strstr(why, "truncated") != NULL,
          "a truncated file is not refused as truncated: %s", why);
    copy[size / 2] ^= 0x20;
    CHECK(pvsr_open(&l, copy, size, why, sizeof why) == PVSR_CORRUPT && strstr(why, "checksum") != NULL,
          "a flipped byte is not refused by the checksum: %s", why);
    copy[size / 2] ^= 0x20;
    copy[0] = 'X';
    CHECK(pvsr_open(&l, copy, size, why, sizeof why) == PVSR_NOT_A_RUNTIME_FILE, "another magic is not refused: %s", why);
    copy[0] = 'P';
    copy[8] = (uint8_t)(PVSR_VERSION_MAJOR + 1);
    CHECK(pvsr_open(&l, copy, size, why, sizeof why) == PVSR_VERSION_TOO_NEW, "a newer version is not refused: %s", why);
    CHECK(pvsr_cell_count(&l) == 0 && pvsr_find_cell(&l, 0, 0, 0) == -1, "a refused level is not empty");
    free(copy);
}

static int run_case(FILE* in, const char* folder) {
    char word[64], name[512], path[1024];
    unsigned long cells, objects, kind, conservative, n, i;
    unsigned long long triangles;
    void* data;
    size_t size = 0;
    pvsr_level level;
    char why[256];
    unsigned long* want = NULL;
    if (fscanf(in, "%511s", name) != 1) return 0;
    snprintf(path, sizeof path, "%s/%s", folder, name);
    data = read_all(path, &size);
    if (data == NULL) {
        fprintf(stderr, "runtime_check: cannot read %s\n", path);
        return 0;
    }
    if (pvsr_open(&level, data, size, why, sizeof why) != PVSR_OK) {
        fprintf(stderr, "runtime_check: %s: %s\n", path, why);
        free(data);
        return 0;
    }
    check_damage((const uint8_t*)data, size);
    if (fscanf(in, " level %lu %lu %lu %lu %llu", &cells, &objects, &kind, &conservative, &triangles) != 5) return 0;
    CHECK(pvsr_cell_count(&level) == cells && pvsr_object_count(&level) == objects, "%s: counts differ", name);
    CHECK(pvsr_cell_kind(&level) == kind, "%s: cell kind differs", name);
    CHECK(pvsr_is_conservative(&level) == (int)conservative, "%s: mode differs", name);
    CHECK(pvsr_total_triangles(&level) == triangles, "%s: triangles differ", name);
    want = (unsigned long*)malloc(sizeof(unsigned long) * (objects + 1));
    while (want != NULL && fscanf(in, "%63s", word) == 1 && strcmp(word, "end") != 0) {
        if (strcmp(word, "cell") == 0) {
            unsigned long c;
            counter k;
            float box[6];
            unsigned long b[6];
            if (fscanf(in, "%lu %lu", &c, &n) != 2) return 0;
            for (i = 0; i < n; ++i)
                if (fscanf(in, "%lu", &want[i]) != 1) return 0;
            k.want = want;
            k.n = n;
            k.at = 0;
            k.bad = 0;
            CHECK(pvsr_visit_visible(&level, (uint32_t)c, expect_next, &k) == n && !k.bad && k.at == n,
                  "%s: cell %lu lists other objects", name, c);
            CHECK(pvsr_visible_count(&level, (uint32_t)c) == n, "%s: cell %lu counts other objects", name, c);
            if (n > 0) CHECK(pvsr_is_visible(&level, (uint32_t)c, (uint32_t)want[n / 2]), "%s: cell %lu: is_visible", name, c);
            if (fscanf(in, " bounds %lx %lx %lx %lx %lx %lx", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) != 6) return 0;
            CHECK(pvsr_cell_bounds(&level, (uint32_t)c, box), "%s: cell %lu has no bounds", name, c);
            for (i = 0; i < 6; ++i) CHECK(bits_of(box[i]) == (uint32_t)b[i], "%s: cell %lu bounds differ", name, c);
            if (fscanf(in, " occluders %lu", &n) != 1) return 0;
            CHECK(pvsr_occluder_count(&level, (uint32_t)c) == n, "%s: cell %lu occluder count differs", name, c);
            for (i = 0; i < n; ++i) {
                unsigned long v[10];
                int a;
                pvsr_ranked_occluder o;
                if (fscanf(in, "%lx %lx %lx %lx %lx %lx %lx %lx %lx %lx", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                           &v[7], &v[8], &v[9]) != 10)
                    return 0;
                CHECK(pvsr_occluder(&level, (uint32_t)c, (uint32_t)i, &o), "%s: cell %lu occluder %lu missing", name, c, i);
                for (a = 0; a < 6; ++a) CHECK(bits_of(o.box[a]) == (uint32_t)v[a], "%s: occluder box differs", name);
                if (pvsr_has_occluder_measures(&level))
                    CHECK(bits_of(o.score) == (uint32_t)v[6] && bits_of(o.solid_angle_sr) == (uint32_t)v[7] &&
                              bits_of(o.hidden_objects) == (uint32_t)v[8] && bits_of(o.hidden_triangle_share) == (uint32_t)v[9],
                          "%s: cell %lu occluder %lu measures differ", name, c, i);
                else
                    CHECK(o.score != o.score && o.hidden_triangle_share != o.hidden_triangle_share,
                          "%s: measures that the file does not hold are not NaN", name);
            }
        } else if (strcmp(word, "object") == 0) {
            unsigned long o, tris, flags, b[6];
            char hex[1024];
            const char* got;
            char got_hex[1024];
            float box[6];
            size_t at = 0;
            if (fscanf(in, "%lu %lu %lu %lx %lx %lx %lx %lx %lx %1023s", &o, &tris, &flags, &b[0], &b[1], &b[2], &b[3], &b[4],
                       &b[5], hex) != 10)
                return 0;
            CHECK(pvsr_object_triangles(&level, (uint32_t)o) == tris && pvsr_object_flags(&level, (uint32_t)o) == flags,
                  "%s: object %lu differs", name, o);
            pvsr_object_bounds(&level, (uint32_t)o, box);
            for (i = 0; i < 6; ++i) CHECK(bits_of(box[i]) == (uint32_t)b[i], "%s: object %lu bounds differ", name, o);
            got = pvsr_object_name(&level, (uint32_t)o);
            got_hex[0] = '-';
            got_hex[1] = '\0';
            for (; got[at] != '\0' && 2 * at + 2 < sizeof got_hex; ++at) snprintf(got_hex + 2 * at, 3, "%02x", (unsigned)(uint8_t)got[at]);
            CHECK(strcmp(got_hex, hex) == 0, "%s: object %lu name differs", name, o);
        } else if (strcmp(word, "part") == 0) {
            unsigned long o, k, b[6];
            float box[6];
            if (fscanf(in, "%lu %lu %lx %lx %lx %lx %lx %lx", &o, &k, &b[0], &b[1], &b[2], &b[3], &b[4],
                       &b[5]) != 8)
                return 0;
            CHECK(pvsr_object_part(&level, (uint32_t)o, (uint32_t)k, box), "%s: object %lu has no part %lu",
                  name, o, k);
            for (i = 0; i < 6; ++i)
                CHECK(bits_of(box[i]) == (uint32_t)b[i], "%s: object %lu part %lu differs", name, o, k);
        } else if (strcmp(word, "cull") == 0) {
            unsigned long e[3], v;
            float eye[3], *boxes;
            size_t count, k;
            if (fscanf(in, "%lx %lx %lx %lu", &e[0], &e[1], &e[2], &n) != 4) return 0;
            count = (size_t)n;
            boxes = (float*)malloc(sizeof(float) * 6 * (count + 1));
            if (boxes == NULL) return 0;
            for (k = 0; k < 6 * count; ++k) {
                if (fscanf(in, "%lx", &v) != 1) {
                    free(boxes);
                    return 0;
                }
                boxes[k] = float_of(v);
            }
            for (k = 0; k < 3; ++k) eye[k] = float_of(e[k]);
            pvsr_culler_begin_frame(&culler, eye, boxes, count);
            free(boxes);
        } else if (strcmp(word, "box") == 0) {
            unsigned long b[6];
            float box[6];
            int path;
            if (fscanf(in, "%lx %lx %lx %lx %lx %lx %d", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5], &path) != 7) return 0;
            for (i = 0; i < 6; ++i) box[i] = float_of(b[i]);
            ++culled;
            CHECK(pvsr_culler_classify(&culler, box) == path, "%s: the culler's answer for a box differs", name);
        } else if (strcmp(word, "drawn") == 0) {
            unsigned long c, e[3], most, count, k, o;
            float eye[3];
            uint32_t* list;
            if (fscanf(in, "%lu %lx %lx %lx %lu %lu", &c, &e[0], &e[1], &e[2], &most, &count) != 6) return 0;
            for (k = 0; k < 3; ++k) eye[k] = float_of(e[k]);
            list = (uint32_t*)malloc(sizeof(uint32_t) * (count + 1));
            if (list == NULL) return 0;
            pvsr_culler_begin_cell(&culler, &level, (uint32_t)c, eye, (uint32_t)most);
            CHECK(pvsr_drawn_objects(&level, (uint32_t)c, &culler, list, count + 1) == count,
                  "%s: cell %lu draws another count", name, c);
            CHECK(pvsr_visit_drawn(&level, (uint32_t)c, &culler, NULL, NULL) == count,
                  "%s: cell %lu walks another count", name, c);
            for (k = 0; k < count; ++k) {
                if (fscanf(in, "%lu", &o) != 1) {
                    free(list);
                    return 0;
                }
                CHECK(list[k] == (uint32_t)o, "%s: cell %lu draws another object", name, c);
            }
            drawn_culled += pvsr_visible_count(&level, (uint32_t)c) - (uint32_t)count;
            free(list);
        } else if (strcmp(word, "point") == 0) {
            unsigned long p[3];
            long cell;
            int eye;
            float x, y, z;
            if (fscanf(in, "%lx %lx %lx %ld %d", &p[0], &p[1], &p[2], &cell, &eye) != 5) return 0;
            x = float_of(p[0]);
            y = float_of(p[1]);
            z = float_of(p[2]);
            CHECK(pvsr_find_cell(&level, x, y, z) == cell, "%s: the cell at (%g, %g, %g) differs", name, (double)x, (double)y, (double)z);
            CHECK(pvsr_in_eye_space(&level, x, y, z) == eye, "%s: eye space at (%g, %g, %g) differs", name, (double)x, (double)y, (double)z);
        } else {
            fprintf(stderr, "runtime_check: unknown line '%s'\n", word);
            return 0;
        }
    }
    free(want);
    free(data);
    return 1;
}

int main(int argc, char** argv) {
    char folder[1024], word[64];
    FILE* in;
    int cases = 0;
    const char* slash;
    if (argc != 2) {
        fprintf(stderr, "usage: runtime_check CASES.txt\n");
        return 2;
    }
    {
        static float memory[6 * 32 * 32 + 7 * 33];
        if (sizeof memory < pvsr_culler_memory_bytes(32) || !pvsr_culler_init(&culler, 32, memory, sizeof memory)) {
            fprintf(stderr, "runtime_check: the culler's memory is too small\n");
            return 1;
        }
    }
    in = fopen(argv[1], "r");
    if (in == NULL) {
        fprintf(stderr, "runtime_check: cannot open %s\n", argv[1]);
        return 2;
    }
    slash = strrchr(argv[1], '/');
    if (slash == NULL) {
        strcpy(folder, ".");
    } else {
        size_t n = (size_t)(slash - argv[1]);
        if (n >= sizeof folder) n = sizeof folder - 1;
        memcpy(folder, argv[1], n);
        folder[n] = '\0';
    }
    while (fscanf(in, "%63s", word) == 1) {
        if (strcmp(word, "case") != 0 || !run_case(in, folder)) {
            fprintf(stderr, "runtime_check: %s: a malformed or unreadable case\n", argv[1]);
            fclose(in);
            return 1;
        }
        ++cases;
    }
    fclose(in);
    if (failures == 0)
        printf(
            "runtime_check: %d cases, %lu culled boxes and %lu objects culled from drawn walks, every query "
            "as expected "
            "(%u-bit pointers)\n",
            cases, culled, drawn_culled, (unsigned)(8 * sizeof(void*)));
    return failures == 0 && cases > 0 ? 0 : 1;
}
