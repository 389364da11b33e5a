#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Worlds that lie, set before the Khronos glTF-Validator and before pvsbake: pvsbake must refuse each one,
naming what lies, and the validator must raise its error code for it where it has a rule.

Each case is a small variant of samples/tiny_world.py's world (mesh/node 0 the room with accessors
0 = POSITION and 1 = indices in bufferViews 0 and 1; mesh/node 1 the crate with accessors 2 and 3 in
bufferViews 2 and 3; one buffer, the GLB's BIN chunk) whose data contradicts what it declares: a POSITION
value outside its accessor's min/max, a NaN or infinite POSITION value, an index past the vertices, an
accessor past its bufferView, a bufferView past its buffer, a buffer longer than the BIN chunk, a vertex
bufferView overlapping an index bufferView, sparse indices out of range or not increasing. Beside them: a
POSITION accessor without min/max (only what the validator says is recorded) and the world itself, which
both must accept.

Per case, the expectation is:
  validator  each expected error code, raised at or under the JSON pointer given (tests/gltf/validate.js
             runs the validator; no code is expected where the validator has no rule for the lie) and,
             for the world itself, no error at all;
  pvsbake    `pvsbake occluders WORLD -o OUT` exits 2, writes nothing, and its last stderr line names the
             world file, the accessor / bufferView / buffer (`accessor 2`, `accessors[2]` and
             `/accessors/2` all do) and the offending numbers, however formatted (1e+06 and 1000000
             alike; nan, inf). The world itself loads: exit 0 and an output file.

usage: tests/gltf/lies.py [--report] [--pvsbake PATH] [--validator DIR] [--out DIR]
  default   test mode: exit 0 when every expectation holds, 1 with one line per failing case
  --report  print the cases as a Markdown table, then as JSON; exit 0 whatever they show
Exit 77 when the validator (npm install --prefix /opt/pvsbake-npm gltf-validator) or node is missing.
"""
import argparse
import errno
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from collections import namedtuple

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "samples"))
import tiny_world  # noqa: E402

SKIPPED = 77
PVSBAKE_TIMEOUT_S = 60
BAD_INPUT = 2
# The binary may be missing for a moment while it is relinked.
RELINK_RETRIES = 10
RELINK_WAIT_S = 3

CRATE_POSITION, CRATE_INDICES = 2, 3
CRATE_VERTEX_VIEW, CRATE_INDEX_VIEW = 2, 3

# What pvsbake must say: names, the glTF objects it names as (kind, index); values, the numbers it names.
Expect = namedtuple("Expect", "names values")
# validator: {error code: JSON pointer the issue is raised at or under}; pvsbake: an Expect, or None where
# pvsbake's answer is only recorded, or "loads" for a world it must accept.
Case = namedtuple("Case", "name lie data validator pvsbake")

NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|[-+]?\b(?:nan|inf(?:inity)?)\b", re.IGNORECASE)


def ref(name):
    """A pattern for glTF object (kind, index) as a message may name it: kind 3, kind #3, kinds[3], /kinds/3."""
    kind, index = name
    return rf"(?<![A-Za-z]){kind}s?(?:\s+#?|\[|/){index}\b"


def accessor(index):
    return ("accessor", index)


def buffer_view(index):
    return ("bufferView", index)


def buffer(index):
    return ("buffer", index)


# Building the lies.

def element_offset(doc, acc, element, component, size):
    a = doc["accessors"][acc]
    view = doc["bufferViews"][a["bufferView"]]
    stride = view.get("byteStride", size * (3 if a["type"] == "VEC3" else 1))
    return view.get("byteOffset", 0) + a.get("byteOffset", 0) + element * stride + component * size


def set_position(doc, binary, acc, vertex, component, value):
    struct.pack_into("<f", binary, element_offset(doc, acc, vertex, component, 4), value)


def set_index(doc, binary, acc, element, value):
    struct.pack_into("<H", binary, element_offset(doc, acc, element, 0, 2), value)


def vertex_bytes(doc, binary, acc, vertex):
    start = element_offset(doc, acc, vertex, 0, 4)
    return bytes(binary[start:start + 12])


def append_view(doc, binary, data):
    """Appends data to the BIN chunk (4-byte aligned) as a new bufferView without target; its index."""
    binary += b"\0" * (-len(binary) % 4)
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data)})
    binary += data
    doc["buffers"][0]["byteLength"] = len(binary)
    return len(doc["bufferViews"]) - 1


def make_sparse(doc, binary, acc, targets):
    """Makes accessor acc sparse, overriding the vertices at targets with copies of vertices 0, 1, ...:
    values inside the declared min/max, so that the sparse indices are the only lie."""
    copies = b"".join(vertex_bytes(doc, binary, acc, k) for k in range(len(targets)))
    indices = append_view(doc, binary, struct.pack(f"<{len(targets)}H", *targets))
    values = append_view(doc, binary, copies)
    doc["accessors"][acc]["sparse"] = {
        "count": len(targets),
        "indices": {"bufferView": indices, "componentType": tiny_world.UNSIGNED_SHORT},
        "values": {"bufferView": values},
    }


def variant(change):
    """The tiny world's .glb bytes after change(doc, binary) edits its document and BIN chunk."""
    doc, binary = tiny_world.parts()
    binary = bytearray(binary)
    change(doc, binary)
    return tiny_world.glb(doc, binary)


def crate_vertex_thrown(doc, binary):
    set_position(doc, binary, CRATE_POSITION, 0, 0, 1.0e6)


def crate_max_below_data(doc, binary):
    doc["accessors"][CRATE_POSITION]["max"][0] = 1.25


def crate_min_above_data(doc, binary):
    doc["accessors"][CRATE_POSITION]["min"][2] = 1.75


def crate_vertex_nan(doc, binary):
    set_position(doc, binary, CRATE_POSITION, 5, 1, math.nan)


def crate_vertex_inf(doc, binary):
    set_position(doc, binary, CRATE_POSITION, 6, 2, math.inf)


def crate_index_past_vertices(doc, binary):
    set_index(doc, binary, CRATE_INDICES, 7, 8)


def crate_accessor_past_view(doc, binary):
    doc["accessors"][CRATE_POSITION]["count"] = 9


def crate_view_past_buffer(doc, binary):
    doc["bufferViews"][CRATE_INDEX_VIEW]["byteLength"] += 8


def buffer_past_bin_chunk(doc, binary):
    doc["buffers"][0]["byteLength"] = 400


def vertex_view_over_indices(doc, binary):
    doc["bufferViews"][CRATE_VERTEX_VIEW]["byteLength"] += doc["bufferViews"][CRATE_INDEX_VIEW]["byteLength"]


def sparse_index_past_count(doc, binary):
    make_sparse(doc, binary, CRATE_POSITION, [8])


def sparse_indices_decreasing(doc, binary):
    make_sparse(doc, binary, CRATE_POSITION, [5, 3])


def crate_indices_huge(doc, binary):
    doc["meshes"][1]["primitives"][0]["indices"] = 1e20


def crate_node_mesh_missing(doc, binary):
    doc["nodes"][1]["mesh"] = 7


def crate_offset_negative(doc, binary):
    doc["accessors"][CRATE_POSITION]["byteOffset"] = -12


def crate_indices_not_triangles(doc, binary):
    doc["accessors"][CRATE_INDICES]["count"] -= 1


def crate_indices_in_vertex_view(doc, binary):
    doc["accessors"][CRATE_INDICES]["bufferView"] = CRATE_VERTEX_VIEW


def crate_without_bounds(doc, binary):
    del doc["accessors"][CRATE_POSITION]["min"]
    del doc["accessors"][CRATE_POSITION]["max"]


def cases():
    a2 = "/accessors/2"
    crate = "/meshes/1/primitives/0"
    above_max = {"ACCESSOR_MAX_MISMATCH": a2 + "/max/0", "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND": a2 + "/max/0"}
    below_min = {"ACCESSOR_MIN_MISMATCH": a2 + "/min/2", "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND": a2 + "/min/2"}
    return [
        Case("vertex_thrown", "crate vertex 0 x = 1e6 (flipped bytes), min/max still the crate's box",
             variant(crate_vertex_thrown), above_max, Expect([accessor(2)], [1.0e6])),
        Case("max_below_data", "crate POSITION max x declared 1.25, data reach 2",
             variant(crate_max_below_data), above_max, Expect([accessor(2)], [1.25])),
        Case("min_above_data", "crate POSITION min z declared 1.75, data reach 1",
             variant(crate_min_above_data), below_min, Expect([accessor(2)], [1.75])),
        Case("position_nan", "crate vertex 5 y = NaN", variant(crate_vertex_nan),
             {"ACCESSOR_INVALID_FLOAT": a2}, Expect([accessor(2)], [math.nan])),
        Case("position_inf", "crate vertex 6 z = +Inf", variant(crate_vertex_inf),
             {"ACCESSOR_INVALID_FLOAT": a2}, Expect([accessor(2)], [math.inf])),
        Case("index_past_vertices", "crate index 7 = 8, the crate has 8 vertices",
             variant(crate_index_past_vertices), {"ACCESSOR_INDEX_OOB": crate + "/indices"},
             Expect([accessor(3)], [8])),
        Case("accessor_past_view", "crate POSITION count 9: 108 bytes in bufferView 2's 96",
             variant(crate_accessor_past_view), {"ACCESSOR_TOO_LONG": a2}, Expect([accessor(2)], [])),
        Case("view_past_buffer", "bufferView 3 ends 8 bytes past buffer 0 (336 bytes)",
             variant(crate_view_past_buffer), {"BUFFER_VIEW_TOO_LONG": "/bufferViews/3/byteLength"},
             Expect([buffer_view(3)], [])),
        Case("buffer_past_bin", "buffer 0 declares 400 bytes, the BIN chunk holds 336",
             variant(buffer_past_bin_chunk), {"BUFFER_BYTE_LENGTH_MISMATCH": "/buffers/0"},
             Expect([buffer(0)], [400, 336])),
        # The validator has no rule for bufferViews whose bytes overlap (only for one bufferView used as
        # both vertex and index data: BUFFER_VIEW_TARGET_OVERRIDE).
        Case("vertex_view_over_indices", "bufferView 2 (vertices) stretched over bufferView 3 (indices)",
             variant(vertex_view_over_indices), {}, Expect([buffer_view(2), buffer_view(3)], [])),
        Case("sparse_index_past_count", "crate POSITION sparse index 8, the accessor has 8 elements",
             variant(sparse_index_past_count), {"ACCESSOR_SPARSE_INDEX_OOB": a2 + "/sparse"},
             Expect([accessor(2)], [8])),
        Case("sparse_indices_decreasing", "crate POSITION sparse indices 5, 3",
             variant(sparse_indices_decreasing), {"ACCESSOR_SPARSE_INDICES_NON_INCREASING": a2 + "/sparse"},
             Expect([accessor(2)], [5, 3])),
        Case("indices_huge", "crate indices = 1e20, an id no int holds",
             variant(crate_indices_huge), {"UNRESOLVED_REFERENCE": crate + "/indices"},
             Expect([], [1e20])),
        Case("node_mesh_missing", "crate node names mesh 7 of 2",
             variant(crate_node_mesh_missing), {"UNRESOLVED_REFERENCE": "/nodes/1/mesh"}, Expect([], [7])),
        Case("offset_negative", "crate POSITION byteOffset -12",
             variant(crate_offset_negative), {"VALUE_NOT_IN_RANGE": a2 + "/byteOffset"}, Expect([], [-12])),
        # A warning for the validator (MESH_PRIMITIVE_INCOMPATIBLE_MODE): pvsbake warns and bakes.
        Case("indices_not_triangles", "crate indices count 35: not a multiple of 3 (recorded, not judged)",
             variant(crate_indices_not_triangles), {}, None),
        Case("indices_in_vertex_view", "crate indices read from the crate's vertex bufferView",
             variant(crate_indices_in_vertex_view), {"BUFFER_VIEW_TARGET_OVERRIDE": crate + "/indices"},
             Expect([buffer_view(2)], [])),
        Case("position_without_bounds", "crate POSITION without min/max (recorded, not judged)",
             variant(crate_without_bounds),
             {"MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS": crate + "/attributes/POSITION"}, None),
        Case("control", "the tiny world itself", tiny_world.glb(*tiny_world.parts()), {}, "loads"),
    ]


# Running the validator and pvsbake.

def validate(files, validator_dir):
    """validate.js's report per file, by path; exits 77 when node or the validator is missing."""
    cmd = ["node", os.path.join(HERE, "validate.js")] + (["--validator", validator_dir] if validator_dir else [])
    try:
        done = subprocess.run(cmd + files, capture_output=True, text=True)
    except FileNotFoundError:
        print("lies.py: skipped: node is not installed", file=sys.stderr)
        sys.exit(SKIPPED)
    if done.returncode == SKIPPED:
        print(f"lies.py: skipped: {done.stderr.strip()}", file=sys.stderr)
        sys.exit(SKIPPED)
    reports = {}
    for line in done.stdout.splitlines():
        report = json.loads(line)
        reports[report["file"]] = report
    if done.returncode != 0 or len(reports) != len(files):
        sys.exit(f"lies.py: validate.js failed (exit {done.returncode}): {done.stderr.strip() or done.stdout}")
    return reports


def run_pvsbake(pvsbake, world, out):
    """pvsbake occluders on world: (exit code or 'timeout', its last stderr line)."""
    cmd = [pvsbake, "occluders", world, "-o", out, "-q", "--threads", "1"]
    for attempt in range(RELINK_RETRIES):
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=PVSBAKE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            return "timeout", f"(killed after {PVSBAKE_TIMEOUT_S} s)"
        except OSError as e:
            if e.errno not in (errno.ENOENT, errno.ETXTBSY, errno.ENOEXEC) or attempt + 1 == RELINK_RETRIES:
                sys.exit(f"lies.py: cannot run {pvsbake}: {e}")
            time.sleep(RELINK_WAIT_S)
            continue
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        return done.returncode, lines[-1] if lines else ""


def numbers_in(message, world, names):
    """The numbers in message once the world's path and the object names (whose indices are no values) are
    taken out."""
    message = message.replace(world, " ").replace(os.path.basename(world), " ")
    for name in names:
        message = re.sub(ref(name), " ", message, flags=re.IGNORECASE)
    return [float(t) for t in NUMBER.findall(message)]


def names_value(numbers, value):
    if math.isnan(value):
        return any(math.isnan(n) for n in numbers)
    return any(n == value or abs(n - value) <= 1e-6 * abs(value) for n in numbers)


# Judging.

def validator_failures(case, report):
    if case.pvsbake == "loads":
        return [f"the validator reports errors {report['errors']} on a valid world"] if report["errors"] else []
    failures = []
    for code, pointer in case.validator.items():
        at = [m.get("pointer") or "" for m in report["messages"] if m["code"] == code and m["severity"] == 0]
        if not at:
            failures.append(f"the validator does not report {code} (it reports {report['errors'] or 'no error'})")
        elif not any(p == pointer or p.startswith(pointer + "/") for p in at):
            failures.append(f"the validator reports {code} at {', '.join(at)}, not at {pointer}")
    return failures


def pvsbake_failures(case, world, result):
    code, line, left = result["exit"], result["message"], result["left"]
    if case.pvsbake is None:
        return []
    if case.pvsbake == "loads":
        if code != 0:
            return [f"pvsbake's exit is {code} on a valid world: {line}"]
        return [] if left else ["pvsbake exits 0 but writes no output"]
    failures = []
    if code != BAD_INPUT:
        failures.append(f"pvsbake's exit is {code}, not {BAD_INPUT}" + (f": {line}" if line else ""))
    else:
        wanted = [os.path.basename(world)] if os.path.basename(world) not in line else []
        wanted += [f"{k} {i}" for k, i in case.pvsbake.names if not re.search(ref((k, i)), line, re.IGNORECASE)]
        numbers = numbers_in(line, world, case.pvsbake.names)
        wanted += [f"{v:g}" for v in case.pvsbake.values if not names_value(numbers, v)]
        if wanted:
            failures.append(f"pvsbake's message does not name {', '.join(wanted)}: {line}")
    if left:
        failures.append(f"pvsbake leaves {', '.join(left)} behind")
    return failures


def run_case(case, folder, pvsbake, report):
    world = os.path.join(folder, case.name + ".glb")
    work = tempfile.mkdtemp(prefix=case.name + "_", dir=folder)
    code, line = run_pvsbake(pvsbake, world, os.path.join(work, "occluders.glb"))
    result = {"name": case.name, "lie": case.lie, "expected_codes": sorted(case.validator),
              "validator_errors": report["errors"], "validator_warnings": report["warnings"],
              "exit": code, "message": line, "left": sorted(os.listdir(work))}
    shutil.rmtree(work)
    result["failures"] = validator_failures(case, report) + pvsbake_failures(case, world, result)
    return result


def markdown(results):
    rows = ["| case | lie | validator errors (expected) | pvsbake exit | pvsbake's message |",
            "|---|---|---|---|---|"]
    for r in results:
        errors = ", ".join(r["validator_errors"]) or "none"
        expected = ", ".join(r["expected_codes"]) or "none"
        message = r["message"].replace("|", "\\|")
        rows.append(f"| {r['name']} | {r['lie']} | {errors} ({expected}) | {r['exit']} | {message} |")
    return "\n".join(rows)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--report", action="store_true", help="print the table (Markdown, then JSON) and exit 0")
    p.add_argument("--pvsbake", default=os.path.join(REPO, "build", "bin", "pvsbake"))
    p.add_argument("--validator", help="the gltf-validator package folder (default: validate.js's)")
    p.add_argument("--out", help="keep the lying worlds here (default: a temporary folder, removed)")
    a = p.parse_args()
    folder = a.out or tempfile.mkdtemp(prefix="gltf_lies_")
    os.makedirs(folder, exist_ok=True)
    try:
        all_cases = cases()
        worlds = []
        for case in all_cases:
            worlds.append(os.path.join(folder, case.name + ".glb"))
            with open(worlds[-1], "wb") as f:
                f.write(case.data)
        reports = validate(worlds, a.validator)
        results = [run_case(c, folder, a.pvsbake, reports[w]) for c, w in zip(all_cases, worlds)]
    finally:
        if not a.out:
            shutil.rmtree(folder, ignore_errors=True)
    if a.report:
        print(markdown(results))
        print()
        print(json.dumps({"validator": next(iter(reports.values())).get("validator"), "cases": results},
                         indent=1))
        return 0
    failing = [r for r in results if r["failures"]]
    for r in failing:
        for failure in r["failures"]:
            print(f"FAIL {r['name']}: {failure}")
    print(f"{len(results) - len(failing)} of {len(results)} cases hold")
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main())
