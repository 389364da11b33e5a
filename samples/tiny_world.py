# SPDX-License-Identifier: MIT
"""A tiny valid glTF 2.0 world, written without any dependency: a closed room, a crate and a spawn point.

It is the world the mutation bench (bench/mutate_worlds.py) and the glTF-Validator comparison
(tests/gltf/lies.py) start from: small enough that a bake takes seconds, complete enough that a bake
runs every stage (a view seed, an occluding shell, an object to see).

    import tiny_world
    doc, binary = tiny_world.parts()          # the JSON document (a dict) and the BIN chunk (bytes)
    data = tiny_world.glb(doc, binary)        # a .glb file's bytes

Axes are glTF's (+Y up), units metres. Every POSITION accessor declares its min and max, as glTF
requires; indices are unsigned shorts.
"""

import json
import struct

ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
FLOAT = 5126
UNSIGNED_SHORT = 5123

# Corner k of a box: bit 0 = max x, bit 1 = max y, bit 2 = max z. Faces as two triangles each, wound
# outwards (the room's shell is two-sided for visibility, so winding does not matter to a bake).
_BOX_TRIANGLES = [
    (0, 2, 3), (0, 3, 1),  # -z
    (4, 5, 7), (4, 7, 6),  # +z
    (0, 4, 6), (0, 6, 2),  # -x
    (1, 3, 7), (1, 7, 5),  # +x
    (0, 1, 5), (0, 5, 4),  # -y
    (2, 6, 7), (2, 7, 3),  # +y
]


def box_vertices(lo, hi):
    return [(hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2])
            for k in range(8)]


def parts(room=((-4.0, 0.0, -4.0), (4.0, 3.0, 4.0)), crate=((1.0, 0.0, 1.0), (2.0, 1.0, 2.0)),
          spawn=(-2.0, 1.5, -2.0)):
    """The world as (document, BIN chunk): two meshes (room, crate), one node each, and a spawn node."""
    binary = bytearray()
    doc = {
        "asset": {"version": "2.0", "generator": "pvsbake samples/tiny_world.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [],
        "meshes": [],
        "accessors": [],
        "bufferViews": [],
        "buffers": [],
    }
    for name, (lo, hi) in (("room", room), ("crate", crate)):
        verts = box_vertices(lo, hi)
        vpos = len(binary)
        for v in verts:
            binary += struct.pack("<3f", *v)
        ipos = len(binary)
        for t in _BOX_TRIANGLES:
            binary += struct.pack("<3H", *t)
        while len(binary) % 4:
            binary += b"\0"
        views = doc["bufferViews"]
        views.append({"buffer": 0, "byteOffset": vpos, "byteLength": 12 * len(verts), "target": ARRAY_BUFFER})
        views.append({"buffer": 0, "byteOffset": ipos, "byteLength": 6 * len(_BOX_TRIANGLES),
                      "target": ELEMENT_ARRAY_BUFFER})
        acc = doc["accessors"]
        acc.append({"bufferView": len(views) - 2, "componentType": FLOAT, "count": len(verts), "type": "VEC3",
                    "min": [min(v[i] for v in verts) for i in range(3)],
                    "max": [max(v[i] for v in verts) for i in range(3)]})
        acc.append({"bufferView": len(views) - 1, "componentType": UNSIGNED_SHORT,
                    "count": 3 * len(_BOX_TRIANGLES), "type": "SCALAR"})
        doc["meshes"].append({"name": name, "primitives": [
            {"attributes": {"POSITION": len(acc) - 2}, "indices": len(acc) - 1, "mode": 4}]})
        doc["nodes"].append({"name": name, "mesh": len(doc["meshes"]) - 1})
    doc["nodes"].append({"name": "spawn", "translation": list(spawn), "extras": {"pvs_view_seed": True}})
    doc["buffers"].append({"byteLength": len(binary)})
    return doc, bytes(binary)


def glb(doc, binary):
    """A .glb file of a document and its BIN chunk (both chunks padded to 4 bytes, as GLB requires)."""
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    binary = bytes(binary) + b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary:
        chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


if __name__ == "__main__":
    import sys
    if len(sys.argv) != 2:
        sys.exit("usage: tiny_world.py OUT.glb")
    with open(sys.argv[1], "wb") as f:
        f.write(glb(*parts()))
