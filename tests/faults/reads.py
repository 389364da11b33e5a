# SPDX-License-Identifier: MIT
"""Reads that fail: every command that reads a bake file or a checkpoint, given one that is truncated, empty,
unreadable, a folder, or missing, must end with status 1 or 2 and one line naming the file, write nothing,
and never crash or hang.

Bake files are read by info, query, export, verify and bake --reuse; checkpoints by a bake that resumes.
"Unreadable" is made with the preloaded tests/faults/fail_io.c (PVSBAKE_DENY_READ): the tests run as root,
whom file permissions do not stop.

    reads.py --pvsbake build/bin/pvsbake --shim build/tests/libpvsbake_fail_io.so

Prints one line per case and a JSON summary on the last line.
"""

import argparse
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples"))
import tiny_world  # noqa: E402
from fault_runs import FAST, run  # noqa: E402



def check_refused(label, rc, err, name, failures):
    """A refused read: status 1 or 2 (no crash, no hang) and exactly one error line naming `name`. Appends what
    is wrong to failures; returns the lines printed."""
    lines = [l for l in err.splitlines() if l.strip()]
    if rc is None:
        failures.append(f"{label}: hung")
    elif rc not in (1, 2):
        failures.append(f"{label}: exit status {rc}{' (a crash)' if rc < 0 else ''}\n{err}")
    elif len(lines) != 1 or not lines[0].startswith("error: ") or name not in lines[0]:
        failures.append(f"{label}: not one error line naming {name}:\n{err}")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pvsbake", required=True)
    ap.add_argument("--shim", required=True)
    a = ap.parse_args()
    pvsbake, shim = os.path.abspath(a.pvsbake), os.path.abspath(a.shim)
    base = tempfile.mkdtemp(prefix="pvsbake-reads-")
    world = os.path.join(base, "tiny.glb")
    with open(world, "wb") as f:
        f.write(tiny_world.glb(*tiny_world.parts()))
    good = os.path.join(base, "good.h5")
    rc, _, err = run([pvsbake, "bake", world, "-o", good] + FAST, base)
    if rc != 0:
        sys.exit(f"the bake to damage failed ({rc}): {err}")
    with open(good, "rb") as f:
        data = f.read()

    # The damaged bake files, each made in a fresh folder as "in.h5".
    def truncated(keep):
        def make(path):
            with open(path, "wb") as f:
                f.write(data[:keep])
        return make

    def folder(path):
        os.mkdir(path)
        open(os.path.join(path, "inside"), "w").close()

    def whole(path):
        with open(path, "wb") as f:
            f.write(data)

    damages = [
        ("truncated to half", truncated(len(data) // 2), {}),
        ("truncated to its header", truncated(96), {}),
        ("empty", truncated(0), {}),
        ("a folder in its place", folder, {}),
        ("missing", None, {}),
        ("unreadable", whole, {"PVSBAKE_DENY_READ": "in.h5", "LD_PRELOAD": shim}),
    ]
    readers = [
        ("info", ["info", "in.h5"], []),
        ("query", ["query", "in.h5", "0", "1", "0"], []),
        ("export", ["export", "in.h5", "-o", "out.pvsr"], ["out.pvsr"]),
        ("verify", ["verify", world, "in.h5", "-q", "--report", "v.json"], ["v.json"]),
        ("--reuse", ["bake", world, "-o", "out.h5", "--reuse", "in.h5"] + FAST, ["out.h5", "out.h5.checkpoint"]),
    ]
    failures, cases = [], 0
    for dname, make, env in damages:
        for rname, args, outputs in readers:
            d = tempfile.mkdtemp(dir=base)
            if make:
                make(os.path.join(d, "in.h5"))
            rc, out, err = run([pvsbake] + args, d, env)
            cases += 1
            label = f"{rname} of a bake file {dname}"
            lines = check_refused(label, rc, err, "in.h5", failures)
            for o in outputs:
                if os.path.exists(os.path.join(d, o)):
                    failures.append(f"{label}: {o} was written")
            print(f"{label}: {rc} {lines[0] if lines else ''}", flush=True)
            shutil.rmtree(d, ignore_errors=True)

    # Checkpoints: a bake whose checkpoint folder holds a damaged or unreadable chunk, or is a file.
    def chunk(damage):
        def make(d):
            folder_ = os.path.join(d, "out.h5.checkpoint")
            os.mkdir(folder_)
            path = os.path.join(folder_, "rows-000001.h5")
            if damage == "folder":
                os.mkdir(path)
            else:
                whole_chunk = chunk_bytes
                with open(path, "wb") as f:
                    f.write(whole_chunk if damage == "unreadable" else whole_chunk[: {"half": len(whole_chunk) // 2,
                                                                                       "empty": 0}[damage]])
        return make

    # A real chunk of this bake: the one a bake leaves when its bake file cannot be written.
    d = tempfile.mkdtemp(dir=base)
    run([pvsbake, "bake", world, "-o", "out.h5"] + FAST, d,
        {"LD_PRELOAD": shim, "PVSBAKE_FAIL_PATH": "out.h5.tmp-", "PVSBAKE_FAIL_AT": "3",
         "PVSBAKE_FAIL_STICKY": "1"})  # 1 and 2: the check before the first stage (open, close)
    chunks = sorted(os.listdir(os.path.join(d, "out.h5.checkpoint"))) if os.path.isdir(
        os.path.join(d, "out.h5.checkpoint")) else []
    if not chunks:
        sys.exit("no checkpoint chunk to damage")
    with open(os.path.join(d, "out.h5.checkpoint", chunks[0]), "rb") as f:
        chunk_bytes = f.read()
    shutil.rmtree(d)

    def checkpoint_is_file(d):
        open(os.path.join(d, "out.h5.checkpoint"), "w").close()

    chunk_cases = [
        ("a chunk truncated to half", chunk("half"), {}),
        ("an empty chunk", chunk("empty"), {}),
        ("a folder in a chunk's place", chunk("folder"), {}),
        ("an unreadable chunk", chunk("unreadable"), {"PVSBAKE_DENY_READ": "rows-", "LD_PRELOAD": shim}),
        ("a file in the checkpoint folder's place", checkpoint_is_file, {}),
    ]
    for cname, make, env in chunk_cases:
        for resume in ([], ["--resume"]):
            d = tempfile.mkdtemp(dir=base)
            make(d)
            rc, _, err = run([pvsbake, "bake", world, "-o", "out.h5"] + resume + FAST, d, env)
            cases += 1
            label = f"a bake{' --resume' if resume else ''} with {cname}"
            lines = check_refused(label, rc, err, "out.h5.checkpoint", failures)
            if os.path.exists(os.path.join(d, "out.h5")):
                failures.append(f"{label}: out.h5 was written")
            print(f"{label}: {rc} {lines[0] if lines else ''}", flush=True)
            shutil.rmtree(d, ignore_errors=True)

    shutil.rmtree(base, ignore_errors=True)
    print(json.dumps({"cases": cases, "failures": len(failures)}))
    if failures:
        print(f"\n{len(failures)} failures:", file=sys.stderr)
        for f in failures[:20]:
            print(f, file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
