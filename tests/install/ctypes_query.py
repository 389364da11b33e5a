#!/usr/bin/env python3
"""A Python game over the installed shared loader through ctypes (tests/test_loader_install.cpp).

    ctypes_query.py LIB BAKE PVSBAKE POINTS SEED

Loads BAKE with the shared library LIB, then for POINTS random points (fixed SEED) in and around the
bake's cells (most in a random cell's box) finds the cell and walks its PVS (visit callback, list and
bit set), and checks every answer against `PVSBAKE query BAKE --json -- X Y Z` on the same point: the
cell, its box and the names of the visible objects. Prints one summary line; exit status 1 with the
first difference.
"""
import ctypes
import json
import random
import struct
import subprocess
import sys


def f32(x):
    """x rounded to a float32, as a Python float (exact, so the command reads the same float)."""
    return struct.unpack("f", struct.pack("f", x))[0]


def fail(message):
    print("ctypes_query: " + message, file=sys.stderr)
    sys.exit(1)


def bind(lib):
    bake_p = ctypes.c_void_p
    sigs = {
        "pvsbake_load": (ctypes.c_int, [ctypes.c_char_p, ctypes.POINTER(bake_p), ctypes.c_char_p, ctypes.c_size_t]),
        "pvsbake_free": (None, [bake_p]),
        "pvsbake_status_name": (ctypes.c_char_p, [ctypes.c_int]),
        "pvsbake_cell_count": (ctypes.c_uint32, [bake_p]),
        "pvsbake_object_count": (ctypes.c_uint32, [bake_p]),
        "pvsbake_words_per_row": (ctypes.c_size_t, [bake_p]),
        "pvsbake_cell_kind": (ctypes.c_int, [bake_p]),
        "pvsbake_find_cell": (ctypes.c_int32, [bake_p, ctypes.c_float, ctypes.c_float, ctypes.c_float]),
        "pvsbake_cell_bounds": (ctypes.c_int, [bake_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_float)]),
        "pvsbake_visit_visible": (ctypes.c_uint32, [bake_p, ctypes.c_uint32, ctypes.c_void_p, ctypes.c_void_p]),
        "pvsbake_visible_objects": (ctypes.c_uint32, [bake_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint32),
                                                      ctypes.c_size_t]),
        "pvsbake_fill_bitset": (ctypes.c_uint32, [bake_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint64),
                                                  ctypes.c_size_t]),
        "pvsbake_object_name": (ctypes.c_char_p, [bake_p, ctypes.c_uint32]),
    }
    for name, (restype, argtypes) in sigs.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


VISIT = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_uint32)


def main():
    if len(sys.argv) != 6:
        fail("usage: ctypes_query.py LIB BAKE PVSBAKE POINTS SEED")
    lib_path, bake_path, pvsbake, points, seed = sys.argv[1:6]
    lib = ctypes.CDLL(lib_path)
    bind(lib)

    message = ctypes.create_string_buffer(512)
    bake = ctypes.c_void_p()
    status = lib.pvsbake_load(b"no-such-bake.h5", ctypes.byref(bake), message, len(message))
    if status != 1 or bake.value is not None or b"no-such-bake.h5" not in message.value:
        fail("a missing file gave status %d, message %r" % (status, message.value))
    status = lib.pvsbake_load(bake_path.encode(), ctypes.byref(bake), message, len(message))
    if status != 0:
        fail("%s (%s)" % (message.value.decode(), lib.pvsbake_status_name(status).decode()))

    cells = lib.pvsbake_cell_count(bake)
    objects = lib.pvsbake_object_count(bake)
    words = lib.pvsbake_words_per_row(bake)
    names = [lib.pvsbake_object_name(bake, o).decode() for o in range(objects)]
    box = (ctypes.c_float * 6)()
    lo, hi = [float("inf")] * 3, [float("-inf")] * 3
    for c in range(cells):
        if not lib.pvsbake_cell_bounds(bake, c, box):
            fail("cell %d has no bounds" % c)
        lo = [min(lo[i], box[i]) for i in range(3)]
        hi = [max(hi[i], box[3 + i]) for i in range(3)]

    rng = random.Random(int(seed))
    listed = (ctypes.c_uint32 * max(objects, 1))()
    bits = (ctypes.c_uint64 * max(words, 1))()
    inside = 0
    walked = []
    visit = VISIT(lambda user, o: walked.append(o))
    for k in range(int(points)):
        # Mostly points in a random cell's box; a quarter over the cells' bounds and a margin around them,
        # so some have no cell.
        if rng.random() < 0.75:
            lib.pvsbake_cell_bounds(bake, rng.randrange(cells), box)
            p = [f32(rng.uniform(box[i], box[3 + i])) for i in range(3)]
        else:
            p = [f32(rng.uniform(lo[i] - 0.1 * (hi[i] - lo[i]), hi[i] + 0.1 * (hi[i] - lo[i]))) for i in range(3)]
        cell = lib.pvsbake_find_cell(bake, *p)
        query = subprocess.run([pvsbake, "query", bake_path, "--json", "--"] + [repr(x) for x in p],
                               capture_output=True, text=True)
        if query.returncode != 0:
            fail("pvsbake query %r failed: %s" % (p, query.stderr.strip()))
        expect = json.loads(query.stdout)
        where = "point %r" % (p,)
        if expect["cell"] is None:
            if cell != -1:
                fail("%s: the library finds cell %d, pvsbake query none" % (where, cell))
            continue
        if cell != expect["cell"]:
            fail("%s: the library finds cell %d, pvsbake query %d" % (where, cell, expect["cell"]))
        inside += 1
        lib.pvsbake_cell_bounds(bake, cell, box)
        if list(box) != expect["cell_bounds"]:
            fail("%s: cell %d box %r, pvsbake query %r" % (where, cell, list(box), expect["cell_bounds"]))
        del walked[:]
        n = lib.pvsbake_visit_visible(bake, cell, ctypes.cast(visit, ctypes.c_void_p), None)
        m = lib.pvsbake_visible_objects(bake, cell, listed, objects)
        b = lib.pvsbake_fill_bitset(bake, cell, bits, words)
        from_bits = [o for o in range(objects) if bits[o // 64] >> (o % 64) & 1]
        if not (n == m == b == len(walked) == len(from_bits)) or list(listed[:m]) != walked or from_bits != walked:
            fail("%s: cell %d: the visit, the list and the bit set disagree" % (where, cell))
        if [names[o] for o in walked] != expect["visible"] or n != expect["visible_count"]:
            fail("%s: cell %d: the library lists %d objects, pvsbake query %d (or other names)"
                 % (where, cell, n, expect["visible_count"]))
    kind = "octree" if lib.pvsbake_cell_kind(bake) == 1 else "grid"
    lib.pvsbake_free(bake)
    if inside == 0:
        fail("no random point fell in a cell")
    print("ctypes_query: %s: %d %s cells, %d points, %d in a cell, all as pvsbake query"
          % (bake_path, cells, kind, int(points), inside))


if __name__ == "__main__":
    main()
