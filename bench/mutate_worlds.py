#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Bad input against a bake's limits: random mutants of a small valid world (samples/tiny_world.py), each
baked under a wall-clock limit and an address-space limit, and whether every one either baked or was
refused within them. Prints one JSON object on stdout (or --json), a Markdown table on stderr.

Each mutant is the tiny world with one random change of one of these kinds (each mutant's kind drawn with
even shares by a random.Random seeded by --seed and the mutant's index, so a seed gives the same mutants
whatever --count and --jobs are):
  json_value: one member or element of the glTF document: a number replaced by another (0, -1, 1, 1e30,
              4294967295, 2**31, a small perturbation, a negative, a fraction where an integer is
              expected), a value by one of another type, a key removed, an array element duplicated, or
              an unknown key added;
  json_text:  a number of the JSON text replaced by a token json.dumps cannot write (1e400, -1e400, NaN,
              Infinity, -Infinity, a huge integer);
  bin_bytes:  1 to 8 bytes of the BIN chunk XORed with a random nonzero byte;
  bin_float:  one coordinate of a POSITION accessor's data overwritten with +-1e6, +-1e9, +-3e38 or the
              bit pattern of NaN or +-Inf, while the accessor's min and max still say what they said;
  glb_bytes:  1 to 8 bytes anywhere in the .glb (headers and JSON text too) XORed likewise;
  truncate:   the .glb cut at a random length in one of its parts (its header, the JSON chunk's header,
              the JSON text, the BIN chunk's header, the BIN chunk), the part drawn with even shares.
Descriptions name the change, e.g. `accessors[0].count: 8 -> 4294967295` or `accessors[0][5].y: 3 -> 1e+09`
(element 5 of accessor 0, its y).

Each mutant is written to WORK/NNNN/world.glb and baked there (the folder is the bake's working folder):
    PVSBAKE bake world.glb -o OUT.h5 --no-verify --threads 1 [EXTRA BAKE ARGS...]
with RLIMIT_AS set to --memory-limit-mib (and RLIMIT_CORE to 0, so crashes leave no core files) and
killed, with its process group, after --time-limit seconds; os.wait4 gives its peak resident memory
(ru_maxrss). Before the mutants the unmutated world is baked the same way: if that does not exit 0 with
OUT.h5 written within the limits, the bench says so and stops. The bakes run a copy of PVSBAKE taken at
the start (waiting while the file is missing or was changed in the last few seconds), so a relink during
the run neither fails mutants nor mixes two binaries.

Classes: baked (exit 0, OUT.h5 written) and refused (exit 2, no OUT.h5) are the answers a bad file may
get; the others are failures, taken in this order:
  over_time:           killed at the time limit;
  over_memory:         peak resident memory above the limit; or killed by SIGKILL that the bench did not
                       send (the kernel's OOM killer); or any other exit than 0 and 2 (a signal included)
                       with stderr saying "out of memory", "bad_alloc" or "cannot allocate" (an
                       allocation refused under RLIMIT_AS that the baker did not turn into a refusal);
  crashed:             any other signal, or an exit code other than 0 and 2;
  refused_left_output: exit 2 with OUT.h5 left;
  baked_no_output:     exit 0 without OUT.h5.
A refusal because an allocation failed (exit 2, "out of memory while loading") is a refusal. Anything else
the bake leaves in its folder (OUT.h5.tmp-*, OUT.h5.checkpoint/, ...) is listed as the mutant's "stray"
files whatever its class, and counted in the table.

JSON: the parameters, the unmutated bake, per kind the count of each class, per class the median and
max wall seconds and peak RSS (MiB), and every mutant (index, kind, description, class, exit code (a
negative one is the signal that ended it), wall s, peak RSS MiB, the first stderr line containing "error",
stray files, and for failures the last 20 lines of stderr). With --keep-failures, each failing mutant's
.glb and stderr are copied there. Exit status 1 if any mutant is a failure, else 0.

usage: bench/mutate_worlds.py [--pvsbake PATH] [--count N] [--seed S] [--jobs J] [--time-limit SEC]
                              [--memory-limit-mib M] [--work DIR] [--json OUT.json] [--keep-failures DIR]
                              [-- EXTRA BAKE ARGS...]
e.g.  nice python3 bench/mutate_worlds.py --count 300 --jobs 2 --keep-failures failures > mutants.json
"""
import argparse
import concurrent.futures
import copy
import json
import os
import random
import resource
import shutil
import signal
import statistics
import struct
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "samples"))
import tiny_world  # noqa: E402

FAILURES = ("over_time", "over_memory", "crashed", "refused_left_output", "baked_no_output")
CLASSES = ("baked", "refused") + FAILURES
WORLD = "world.glb"
OUT = "OUT.h5"
STDERR = "stderr.txt"
MIB = 1024 * 1024
OUT_OF_MEMORY = ("out of memory", "bad_alloc", "cannot allocate")

# Values a json_value mutant puts in place of a value of another type, by type.
OTHER_TYPE = {"string": "mutant", "list": [], "dict": {}, "null": None, "bool": True, "number": 1}
# Tokens a json_text mutant writes in place of a number.
RAW_TOKENS = ("1e400", "-1e400", "NaN", "Infinity", "-Infinity", "18446744073709551616", "1" + "0" * 40)
# Coordinates a bin_float mutant writes, as little-endian float bits.
FLOAT_BITS = [(f"{v:g}", struct.pack("<f", v)) for v in (1e6, -1e6, 1e9, -1e9, 3e38, -3e38)] + [
    ("NaN", struct.pack("<I", 0x7FC00000)), ("Inf", struct.pack("<I", 0x7F800000)),
    ("-Inf", struct.pack("<I", 0xFF800000))]
COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
SENTINEL = "\u0000pvsbake-mutant\u0000"


# --- the document ---------------------------------------------------------------------------------

def members(value, path=()):
    """Every (path, value) below `value`, depth first: a path is the keys and indices that reach it."""
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, v in items:
        yield path + (key,), v
        yield from members(v, path + (key,))


def name(path):
    text = "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path).lstrip(".")
    return text or "the document"


def parent(doc, path):
    for key in path[:-1]:
        doc = doc[key]
    return doc


def show(value):
    text = json.dumps(value, separators=(",", ":"))
    return text if len(text) <= 40 else text[:37] + "..."


def value_type(value):
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return {str: "string", list: "list", dict: "dict"}[type(value)]


def other_numbers(rng, old):
    """Numbers to put in place of `old`: the usual suspects, a small change, a negative, a fraction."""
    small = old + rng.choice((-2, -1, 1, 2)) if isinstance(old, int) else round(old + rng.uniform(-0.1, 0.1), 6)
    negative = -abs(old) if old else -rng.randint(1, 100)
    choices = (0, -1, 1, 1e30, 4294967295, 2**31, small, negative, int(old) + 0.5)
    return [n for n in choices if n != old or type(n) is not type(old)]


# --- the BIN chunk ---------------------------------------------------------------------------------

def bin_element(doc, offset):
    """What byte `offset` of the BIN chunk holds, e.g. accessors[0][5].y, or where it lies."""
    for a, acc in enumerate(doc["accessors"]):
        view = doc["bufferViews"][acc["bufferView"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        components = COMPONENTS[acc["type"]]
        size = COMPONENT_BYTES[acc["componentType"]]
        stride = view.get("byteStride", components * size)
        element, within = divmod(offset - start, stride)
        if 0 <= element < acc["count"] and within < components * size:
            if components == 1:
                return f"accessors[{a}][{element}]"
            part = "xyzw"[within // size] if components <= 4 else str(within // size)
            return f"accessors[{a}][{element}].{part}"
    return "padding"


def positions(doc):
    """The indices of the accessors that meshes use as POSITION."""
    return sorted({p["attributes"]["POSITION"] for m in doc["meshes"] for p in m["primitives"]})


def glb_regions(data):
    """The (name, start, end) byte ranges of a .glb file: its header, its chunks' headers and contents."""
    json_end = 20 + struct.unpack_from("<I", data, 12)[0]
    return [("GLB header", 0, 12), ("JSON chunk header", 12, 20), ("JSON text", 20, json_end),
            ("BIN chunk header", json_end, json_end + 8), ("BIN chunk", json_end + 8, len(data))]


def glb_region(data, offset):
    return next(name for name, start, end in glb_regions(data) if start <= offset < end)


def glb_of_text(text, binary):
    """tiny_world.glb for JSON text that json.dumps would not write."""
    js = text.encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


def flip(rng, data):
    """`data` with 1 to 8 distinct bytes XORed with random nonzero bytes, and the (offset, old, new) list."""
    data = bytearray(data)
    changes = []
    for offset in sorted(rng.sample(range(len(data)), rng.randint(1, 8))):
        old = data[offset]
        data[offset] ^= rng.randint(1, 255)
        changes.append((offset, old, data[offset]))
    return bytes(data), changes


def byte_text(b):
    return f"0x{b:02x}" + (f" {chr(b)!r}" if 32 <= b < 127 else "")


# --- the mutations: each takes (rng, doc, binary) and gives (.glb bytes, description) ---------------

def json_value(rng, doc, binary):
    doc = copy.deepcopy(doc)
    paths = list(members(doc))
    op = rng.choice(("number", "type", "remove", "duplicate", "add"))
    if op == "number":
        path, old = rng.choice([(p, v) for p, v in paths if value_type(v) == "number"])
        new = rng.choice(other_numbers(rng, old))
        parent(doc, path)[path[-1]] = new
        text = f"{name(path)}: {show(old)} -> {show(new)}"
    elif op == "type":
        path, old = rng.choice(paths)
        new = OTHER_TYPE[rng.choice(sorted(set(OTHER_TYPE) - {value_type(old)}))]
        parent(doc, path)[path[-1]] = new
        text = f"{name(path)}: {show(old)} -> {show(new)}"
    elif op == "remove":
        path, old = rng.choice([(p, v) for p, v in paths if isinstance(p[-1], str)])
        del parent(doc, path)[path[-1]]
        text = f"removed {name(path)} (was {show(old)})"
    elif op == "duplicate":
        path, old = rng.choice([(p, v) for p, v in paths if isinstance(p[-1], int)])
        parent(doc, path).insert(path[-1] + 1, copy.deepcopy(old))
        text = f"duplicated {name(path)} (as {name(path[:-1] + (path[-1] + 1,))}, the rest shift by one)"
    else:
        path = rng.choice([()] + [p for p, v in paths if isinstance(v, dict)])
        new = rng.choice(list(OTHER_TYPE.values()))
        (parent(doc, path)[path[-1]] if path else doc)["pvsbake_mutant"] = new
        text = f"added {name(path + ('pvsbake_mutant',))} = {show(new)}"
    return tiny_world.glb(doc, binary), text


def json_text(rng, doc, binary):
    doc = copy.deepcopy(doc)
    path, old = rng.choice([(p, v) for p, v in members(doc) if value_type(v) == "number"])
    token = rng.choice(RAW_TOKENS)
    parent(doc, path)[path[-1]] = SENTINEL
    text = json.dumps(doc, separators=(",", ":")).replace(json.dumps(SENTINEL), token)
    return glb_of_text(text, binary), f"{name(path)}: {show(old)} -> {token} (raw text)"


def bin_bytes(rng, doc, binary):
    data, changes = flip(rng, binary)
    text = ", ".join(f"BIN byte {o} ({bin_element(doc, o)}): 0x{a:02x} -> 0x{b:02x}" for o, a, b in changes)
    return tiny_world.glb(doc, data), text


def bin_float(rng, doc, binary):
    a = rng.choice(positions(doc))
    acc = doc["accessors"][a]
    view = doc["bufferViews"][acc["bufferView"]]
    vertex, axis = rng.randrange(acc["count"]), rng.randrange(3)
    offset = view.get("byteOffset", 0) + acc.get("byteOffset", 0) + view.get("byteStride", 12) * vertex + 4 * axis
    label, bits = rng.choice(FLOAT_BITS)
    old = struct.unpack_from("<f", binary, offset)[0]
    data = binary[:offset] + bits + binary[offset + 4:]
    return tiny_world.glb(doc, data), f"accessors[{a}][{vertex}].{'xyz'[axis]}: {old:g} -> {label}"


def glb_bytes(rng, doc, binary):
    original = tiny_world.glb(doc, binary)
    data, changes = flip(rng, original)
    parts = []
    for o, a, b in changes:
        where = glb_region(original, o)
        if where == "BIN chunk":
            where += ", " + bin_element(doc, o - glb_regions(original)[-1][1])
        parts.append(f"byte {o} ({where}): {byte_text(a)} -> {byte_text(b)}")
    return data, ", ".join(parts)


def truncate(rng, doc, binary):
    data = tiny_world.glb(doc, binary)
    where, start, end = rng.choice(glb_regions(data))
    cut = rng.randrange(start, end)
    return data[:cut], f"cut to {cut} of {len(data)} bytes, in the {where}"


MUTATIONS = {f.__name__: f for f in (json_value, json_text, bin_bytes, bin_float, glb_bytes, truncate)}
KINDS = tuple(MUTATIONS)


def mutant(seed, index, doc, binary):
    """Mutant `index` of --seed `seed`: (kind, .glb bytes, description)."""
    rng = random.Random(f"{seed}:{index}")
    kind = rng.choice(KINDS)
    data, text = MUTATIONS[kind](rng, doc, binary)
    return kind, data, text


# --- baking ----------------------------------------------------------------------------------------

def copy_pvsbake(path, work):
    """A copy of `path` in `work`, taken once the file exists and has not changed for 3 s (not mid-link)."""
    copy_path = os.path.join(work, "pvsbake")
    deadline = time.monotonic() + 120
    while True:
        try:
            if time.time() - os.stat(path).st_mtime >= 3:
                shutil.copy2(path, copy_path)
                return copy_path
        except FileNotFoundError:
            pass
        if time.monotonic() > deadline:
            sys.exit(f"{path} is missing or still changing after 2 minutes")
        print(f"{path} is missing or being written (relinked?); waiting", file=sys.stderr)
        time.sleep(3)


def bake(pvsbake, folder, extra, time_limit, memory_mib):
    """Bakes folder/world.glb under the limits: (exit code (-signal), killed at the limit, wall s, peak MiB)."""
    limit = memory_mib * MIB

    def limits():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    cmd = [pvsbake, "bake", os.path.join(folder, WORLD), "-o", os.path.join(folder, OUT), "--no-verify",
           "--threads", "1"] + extra
    with open(os.path.join(folder, STDERR), "wb") as err:
        start = time.monotonic()
        proc = subprocess.Popen(cmd, cwd=folder, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=err, preexec_fn=limits, start_new_session=True)
        killed = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if not killed and time.monotonic() - start > time_limit:
                os.killpg(proc.pid, signal.SIGKILL)
                killed = True
            time.sleep(0.05)
        wall = time.monotonic() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, killed, wall, usage.ru_maxrss / 1024.0


def classify(code, killed, rss_mib, output, stderr, memory_mib):
    if killed:
        return "over_time"
    out_of_memory = any(s in stderr.lower() for s in OUT_OF_MEMORY)
    if rss_mib > memory_mib or code == -signal.SIGKILL or (code not in (0, 2) and out_of_memory):
        return "over_memory"
    if code not in (0, 2):
        return "crashed"
    if code == 2:
        return "refused_left_output" if output else "refused"
    return "baked" if output else "baked_no_output"


def run_one(a, pvsbake, folder, data):
    """Writes `data` as folder/world.glb, bakes it and describes the outcome (a dict)."""
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    with open(os.path.join(folder, WORLD), "wb") as f:
        f.write(data)
    code, killed, wall, rss = bake(pvsbake, folder, a.extra, a.time_limit, a.memory_limit_mib)
    with open(os.path.join(folder, STDERR), errors="replace") as f:
        lines = f.read().splitlines()
    output = os.path.exists(os.path.join(folder, OUT))
    cls = classify(code, killed, rss, output, "\n".join(lines), a.memory_limit_mib)
    result = {"class": cls, "exit_code": code, "wall_s": round(wall, 3), "peak_rss_mib": round(rss, 1),
              "error_line": next((line for line in lines if "error" in line.lower()), None),
              "stray": sorted(set(os.listdir(folder)) - {WORLD, OUT, STDERR})}
    if cls in FAILURES:
        result["stderr_tail"] = lines[-20:]
    return result


def run_mutant(a, pvsbake, doc, binary, index):
    kind, data, text = mutant(a.seed, index, doc, binary)
    folder = os.path.join(a.work, f"{index:04d}")
    result = {"index": index, "kind": kind, "description": text}
    result.update(run_one(a, pvsbake, folder, data))
    if result["class"] in FAILURES and a.keep_failures:
        stem = os.path.join(a.keep_failures, f"{index:04d}_{kind}")
        shutil.copyfile(os.path.join(folder, WORLD), stem + ".glb")
        shutil.copyfile(os.path.join(folder, STDERR), stem + ".stderr.txt")
    return result


# --- the report ------------------------------------------------------------------------------------

def summary(mutants):
    by_kind = {k: {c: sum(1 for m in mutants if m["kind"] == k and m["class"] == c) for c in CLASSES}
               for k in KINDS}
    by_class = {}
    for c in CLASSES:
        ms = [m for m in mutants if m["class"] == c]
        if ms:
            walls, rss = [m["wall_s"] for m in ms], [m["peak_rss_mib"] for m in ms]
            by_class[c] = {"count": len(ms), "wall_s_median": round(statistics.median(walls), 3),
                           "wall_s_max": max(walls), "peak_rss_mib_median": round(statistics.median(rss), 1),
                           "peak_rss_mib_max": max(rss)}
    return by_kind, by_class


def table(mutants):
    """The Markdown table: kinds as rows, classes as columns, then mutants with stray files, max wall, max RSS."""
    lines = ["| kind | " + " | ".join(CLASSES) + " | stray files | max wall s | max RSS MiB |",
             "|---" * (len(CLASSES) + 4) + "|"]
    for label, ms in [(k, [m for m in mutants if m["kind"] == k]) for k in KINDS] + [("**total**", mutants)]:
        counts = [str(sum(1 for m in ms if m["class"] == c)) for c in CLASSES]
        stray = str(sum(1 for m in ms if m["stray"]))
        wall = f"{max(m['wall_s'] for m in ms):.1f}" if ms else "-"
        rss = f"{max(m['peak_rss_mib'] for m in ms):.0f}" if ms else "-"
        lines.append(f"| {label} | " + " | ".join(counts + [stray, wall, rss]) + " |")
    return "\n".join(lines)


def progress(done, count, m):
    line = (f"[{done}/{count}] #{m['index']} {m['kind']}: {m['class']} (exit {m['exit_code']}, {m['wall_s']:.1f} s, "
            f"{m['peak_rss_mib']:.0f} MiB) {m['description']}")
    if m["error_line"]:
        line += f"\n    {m['error_line']}"
    if m["stray"]:
        line += f"\n    stray: {', '.join(m['stray'])}"
    print(line, file=sys.stderr)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pvsbake", default=os.path.join(REPO, "build", "bin", "pvsbake"))
    p.add_argument("--count", type=int, default=300, help="mutants")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--jobs", type=int, default=2, help="bakes at a time")
    p.add_argument("--time-limit", type=float, default=60.0, help="wall seconds per bake")
    p.add_argument("--memory-limit-mib", type=int, default=4096, help="address space per bake (RLIMIT_AS)")
    p.add_argument("--work", help="folder for the mutants and their bakes (default: a temporary one)")
    p.add_argument("--json", help="write the JSON here instead of stdout")
    p.add_argument("--keep-failures", help="copy failing mutants' .glb and stderr here")
    p.add_argument("extra", nargs="*", metavar="-- BAKE OPTION", help="more options for every bake, after --")
    a = p.parse_args()
    a.work = os.path.abspath(a.work or tempfile.mkdtemp(prefix="pvsbake-mutate-"))
    os.makedirs(a.work, exist_ok=True)
    if a.keep_failures:
        os.makedirs(a.keep_failures, exist_ok=True)
    pvsbake = copy_pvsbake(a.pvsbake, a.work)
    doc, binary = tiny_world.parts()

    base = run_one(a, pvsbake, os.path.join(a.work, "unmutated"), tiny_world.glb(doc, binary))
    print(f"unmutated: {base['class']} (exit {base['exit_code']}, {base['wall_s']:.1f} s, "
          f"{base['peak_rss_mib']:.0f} MiB)", file=sys.stderr)
    if base["class"] != "baked":
        sys.exit(f"the unmutated world does not bake within the limits ({base['class']}); stderr ends:\n"
                 + "\n".join(base.get("stderr_tail", [])))

    mutants = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = [pool.submit(run_mutant, a, pvsbake, doc, binary, i) for i in range(a.count)]
        for future in concurrent.futures.as_completed(futures):
            mutants.append(future.result())
            progress(len(mutants), a.count, mutants[-1])
    mutants.sort(key=lambda m: m["index"])

    by_kind, by_class = summary(mutants)
    failures = sum(1 for m in mutants if m["class"] in FAILURES)
    print("\n" + table(mutants) + "\n", file=sys.stderr)
    print(f"{failures} of {len(mutants)} mutants failed", file=sys.stderr)
    result = {"bench": "mutate_worlds",
              "parameters": {"pvsbake": os.path.abspath(a.pvsbake), "count": a.count, "seed": a.seed,
                             "jobs": a.jobs, "time_limit_s": a.time_limit, "memory_limit_mib": a.memory_limit_mib,
                             "work": a.work, "bake_options": ["--no-verify", "--threads", "1"] + a.extra},
              "unmutated": base, "by_kind": by_kind, "by_class": by_class, "failures": failures,
              "mutants": mutants}
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=1)
            f.write("\n")
    else:
        json.dump(result, sys.stdout, indent=1)
        print()
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
