#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A Python game over the installed shared loader through ctypes (tests/test_loader_install.cpp).

    ctypes_query.py LIB BAKE PVSBAKE POINTS SEED [RUNTIME_LIB LEVEL.pvsr]

Loads BAKE with the shared library LIB, then for POINTS random points (fixed SEED) in and around the
bake's cells (most in a random cell's box) finds the cell and walks its PVS (visit callback, list and
bit set), and checks every answer against `PVSBAKE query BAKE --json -- X Y Z` on the same point: the
cell, its box and the names of the visible objects. With RUNTIME_LIB and LEVEL.pvsr (`pvsbake export BAKE`),
the same through the C99 runtime's shared library reading the runtime file from memory (what a game that
ships no HDF5 does). Prints one summary line; exit status 1 with the first difference.
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
        "pvsbake_culler_create": (ctypes.c_void_p, [ctypes.c_int]),
        "pvsbake_culler_free": (None, [ctypes.c_void_p]),
        "pvsbake_culler_begin_cell": (ctypes.c_uint32, [ctypes.c_void_p, bake_p, ctypes.c_uint32,
                                                        ctypes.POINTER(ctypes.c_float), ctypes.c_size_t]),
        "pvsbake_drawn_objects": (ctypes.c_uint32, [bake_p, ctypes.c_uint32, ctypes.c_void_p,
                                                    ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t]),
        "pvsbake_horizon_create": (ctypes.c_void_p, [ctypes.c_int, ctypes.c_size_t]),
        "pvsbake_horizon_free": (None, [ctypes.c_void_p]),
        "pvsbake_horizon_begin_cell": (ctypes.c_uint32, [ctypes.c_void_p, bake_p, ctypes.c_uint32,
                                                         ctypes.POINTER(ctypes.c_float)]),
        "pvsbake_drawn_objects_horizon": (ctypes.c_uint32, [bake_p, ctypes.c_uint32, ctypes.c_void_p,
                                                            ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32),
                                                            ctypes.c_size_t]),
    }
    for name, (restype, argtypes) in sigs.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


VISIT = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_uint32)


class Runtime:
    """The C99 runtime (runtime/pvsr.h) over a runtime file's bytes, with the loader's call shapes."""

    def __init__(self, lib_path, level_path):
        self.lib = lib = ctypes.CDLL(lib_path)
        level_p = ctypes.c_void_p
        sigs = {
            "pvsr_level_bytes": (ctypes.c_size_t, []),
            "pvsr_open": (ctypes.c_int, [level_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_size_t]),
            "pvsr_status_name": (ctypes.c_char_p, [ctypes.c_int]),
            "pvsr_cell_count": (ctypes.c_uint32, [level_p]),
            "pvsr_object_count": (ctypes.c_uint32, [level_p]),
            "pvsr_words_per_row": (ctypes.c_size_t, [level_p]),
            "pvsr_find_cell": (ctypes.c_int32, [level_p, ctypes.c_float, ctypes.c_float, ctypes.c_float]),
            "pvsr_cell_bounds": (ctypes.c_int, [level_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_float)]),
            "pvsr_visit_visible": (ctypes.c_uint32, [level_p, ctypes.c_uint32, ctypes.c_void_p, ctypes.c_void_p]),
            "pvsr_visible_objects": (ctypes.c_uint32, [level_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint32),
                                                       ctypes.c_size_t]),
            "pvsr_fill_bitset": (ctypes.c_uint32, [level_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint64),
                                                   ctypes.c_size_t]),
            "pvsr_object_name": (ctypes.c_char_p, [level_p, ctypes.c_uint32]),
            "pvsr_culler_bytes": (ctypes.c_size_t, []),
            "pvsr_culler_memory_bytes": (ctypes.c_size_t, [ctypes.c_int]),
            "pvsr_culler_init": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p, ctypes.c_size_t]),
            "pvsr_culler_begin_cell": (ctypes.c_uint32, [ctypes.c_void_p, level_p, ctypes.c_uint32,
                                                         ctypes.POINTER(ctypes.c_float), ctypes.c_uint32]),
            "pvsr_drawn_objects": (ctypes.c_uint32, [level_p, ctypes.c_uint32, ctypes.c_void_p,
                                                     ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t]),
            "pvsr_horizon_bytes": (ctypes.c_size_t, []),
            "pvsr_horizon_memory_bytes": (ctypes.c_size_t, [ctypes.c_int, ctypes.c_size_t]),
            "pvsr_horizon_init": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t, ctypes.c_void_p,
                                                 ctypes.c_size_t]),
            "pvsr_horizon_begin_cell": (ctypes.c_uint32, [ctypes.c_void_p, level_p, ctypes.c_uint32,
                                                          ctypes.POINTER(ctypes.c_float)]),
            "pvsr_drawn_objects_horizon": (ctypes.c_uint32, [level_p, ctypes.c_uint32, ctypes.c_void_p,
                                                             ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32),
                                                             ctypes.c_size_t]),
        }
        for name, (restype, argtypes) in sigs.items():
            fn = getattr(lib, name)
            fn.restype = restype
            fn.argtypes = argtypes
        data = open(level_path, "rb").read()
        # The bytes in 8-byte aligned memory that lives as long as the level (a game would map the file).
        self.bytes = (ctypes.c_uint64 * ((len(data) + 7) // 8))()
        ctypes.memmove(self.bytes, data, len(data))
        self.level = ctypes.create_string_buffer(lib.pvsr_level_bytes())
        message = ctypes.create_string_buffer(256)
        status = lib.pvsr_open(self.level, self.bytes, len(data), message, len(message))
        if status != 0:
            fail("%s: %s (%s)" % (level_path, message.value.decode(), lib.pvsr_status_name(status).decode()))
        broken = (ctypes.c_uint64 * len(self.bytes))()
        ctypes.memmove(broken, data, len(data) - 1)
        if lib.pvsr_open(ctypes.create_string_buffer(lib.pvsr_level_bytes()), broken, len(data) - 1, message,
                         len(message)) == 0 or b"truncated" not in message.value:
            fail("%s less its last byte opened: %r" % (level_path, message.value))
        # The culler: its struct and its depth cube's memory (32 pixels a face), both allocated here once.
        self.culler = ctypes.create_string_buffer(lib.pvsr_culler_bytes())
        self.culler_memory = (ctypes.c_float * (lib.pvsr_culler_memory_bytes(32) // 4 + 1))()
        if not lib.pvsr_culler_init(self.culler, 32, self.culler_memory, ctypes.sizeof(self.culler_memory)):
            fail("the runtime's culler did not take its memory")
        # The horizon (64 columns a side, 16,384 pieces), its struct and memory allocated here once.
        self.horizon = ctypes.create_string_buffer(lib.pvsr_horizon_bytes())
        self.horizon_memory = (ctypes.c_uint64 * (lib.pvsr_horizon_memory_bytes(64, 16384) // 8 + 1))()
        if not lib.pvsr_horizon_init(self.horizon, 64, 16384, self.horizon_memory,
                                     ctypes.sizeof(self.horizon_memory)):
            fail("the runtime's horizon did not take its memory")

    def drawn(self, cell, eye, objects):
        """What a game draws of the cell from the eye: its PVS less what its ranked occluders and its horizon
        hide."""
        lib = self.lib
        lib.pvsr_culler_begin_cell(self.culler, self.level, cell, eye, 64)
        lib.pvsr_horizon_begin_cell(self.horizon, self.level, cell, eye)
        listed = (ctypes.c_uint32 * max(objects, 1))()
        n = lib.pvsr_drawn_objects_horizon(self.level, cell, self.culler, self.horizon, listed, objects)
        return list(listed[:n])

    def check(self, cell, objects, words, names, expect, where):
        lib, level = self.lib, self.level
        box = (ctypes.c_float * 6)()
        if not lib.pvsr_cell_bounds(level, cell, box) or list(box) != expect["cell_bounds"]:
            fail("%s: the runtime's cell %d box %r, pvsbake query %r" % (where, cell, list(box), expect["cell_bounds"]))
        walked = []
        visit = VISIT(lambda user, o: walked.append(o))
        listed = (ctypes.c_uint32 * max(objects, 1))()
        bits = (ctypes.c_uint64 * max(words, 1))()
        n = lib.pvsr_visit_visible(level, cell, ctypes.cast(visit, ctypes.c_void_p), None)
        m = lib.pvsr_visible_objects(level, cell, listed, objects)
        b = lib.pvsr_fill_bitset(level, cell, bits, words)
        from_bits = [o for o in range(objects) if bits[o // 64] >> (o % 64) & 1]
        if not (n == m == b == len(walked) == len(from_bits)) or list(listed[:m]) != walked or from_bits != walked:
            fail("%s: the runtime's cell %d: the visit, the list and the bit set disagree" % (where, cell))
        if [lib.pvsr_object_name(level, o).decode() for o in walked] != expect["visible"]:
            fail("%s: the runtime's cell %d lists other objects than pvsbake query" % (where, cell))


def main():
    if len(sys.argv) not in (6, 8):
        fail("usage: ctypes_query.py LIB BAKE PVSBAKE POINTS SEED [RUNTIME_LIB LEVEL.pvsr]")
    lib_path, bake_path, pvsbake, points, seed = sys.argv[1:6]
    runtime = Runtime(sys.argv[6], sys.argv[7]) if len(sys.argv) == 8 else None
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
    culler = lib.pvsbake_culler_create(0)
    if not culler:
        fail("pvsbake_culler_create gave NULL")
    horizon = lib.pvsbake_horizon_create(64, 16384)
    if not horizon:
        fail("pvsbake_horizon_create gave NULL")
    drawn = (ctypes.c_uint32 * max(objects, 1))()
    culled = 0
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
        if runtime is not None and runtime.lib.pvsr_find_cell(runtime.level, *p) != cell:
            fail("point %r: the runtime finds cell %d, the loader %d"
                 % (p, runtime.lib.pvsr_find_cell(runtime.level, *p), cell))
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
        if runtime is not None:
            runtime.check(cell, objects, words, names, expect, where)
        # What a game draws from this point as its eye: the PVS less what the cell's ranked occluders and its
        # horizon hide.
        eye = (ctypes.c_float * 3)(*p)
        lib.pvsbake_culler_begin_cell(culler, bake, cell, eye, 64)
        lib.pvsbake_horizon_begin_cell(horizon, bake, cell, eye)
        d = lib.pvsbake_drawn_objects_horizon(bake, cell, culler, horizon, drawn, objects)
        if not set(drawn[:d]) <= set(walked) or list(drawn[:d]) != sorted(drawn[:d]):
            fail("%s: cell %d draws objects out of order or outside its PVS" % (where, cell))
        culled += n - d
        if runtime is not None and runtime.drawn(cell, eye, objects) != list(drawn[:d]):
            fail("%s: cell %d: the runtime draws other objects than the library" % (where, cell))
    kind = "octree" if lib.pvsbake_cell_kind(bake) == 1 else "grid"
    lib.pvsbake_culler_free(culler)
    lib.pvsbake_horizon_free(horizon)
    lib.pvsbake_free(bake)
    if inside == 0:
        fail("no random point fell in a cell")
    print("ctypes_query: %s: %d %s cells, %d points, %d in a cell (their ranked occluders and horizons culled %d objects of "
          "the PVS from them), all as pvsbake query%s"
          % (bake_path, cells, kind, int(points), inside, culled,
             ", and the same through the runtime file" if runtime is not None else ""))


if __name__ == "__main__":
    main()
