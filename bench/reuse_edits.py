#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""What an incremental re-bake saves (docs/ALGORITHMS.md#reuse): for each edit of a world, a full bake of the
edited world against a bake with --reuse of the bake before the edit, one after the other; the two files must
be the same outside /run. Prints JSON: per edit, the pairs kept, the seconds of each bake and its PVS stage, and
whether the files are the same.

  python3 bench/reuse_edits.py PVSBAKE EDIT_WORLD WORLD.glb --edit NAME 'EDIT OPTIONS' [--edit ...]
                               [--out DIR] [-- BAKE OPTIONS]

EDIT OPTIONS are samples/edit_world's (--move, --remove, --remove-in, --cut, --add-box, --tile). --base 'OPTIONS'
edits the world before the edit too (a crate that the edit then moves, say); the world is always written
again by edit_world, so both bakes read the same writer's output.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import time


def bake(pvsbake, world, out, report, extra):
    start = time.monotonic()
    subprocess.run([pvsbake, "bake", world, "-o", out, "--report", report, "-q"] + extra, check=True)
    seconds = time.monotonic() - start
    with open(report) as f:
        r = json.load(f)
    return seconds, r


def main():
    argv = sys.argv[1:]
    bake_extra = []
    if "--" in argv:
        i = argv.index("--")
        argv, bake_extra = argv[:i], argv[i + 1:]
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("pvsbake")
    p.add_argument("edit_world")
    p.add_argument("world")
    p.add_argument("--base", default="", help="edit_world options applied before every edit and to the old world")
    p.add_argument("--edit", nargs=2, action="append", metavar=("NAME", "OPTIONS"), required=True)
    p.add_argument("--out", default="reuse_edits")
    a = p.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    base = shlex.split(a.base)
    old_world = os.path.join(a.out, "old.glb")
    subprocess.run([a.edit_world, a.world, old_world] + base, check=True)
    old = os.path.join(a.out, "old.h5")
    old_seconds, old_report = bake(a.pvsbake, old_world, old, old + ".json", bake_extra)
    rows = []
    for name, options in a.edit:
        world = os.path.join(a.out, name + ".glb")
        subprocess.run([a.edit_world, a.world, world] + base + shlex.split(options), check=True)
        full, reuse = os.path.join(a.out, name + ".full.h5"), os.path.join(a.out, name + ".reuse.h5")
        full_seconds, full_report = bake(a.pvsbake, world, full, full + ".json", bake_extra)
        reuse_seconds, reuse_report = bake(a.pvsbake, world, reuse, reuse + ".json", bake_extra + ["--reuse", old])
        same = subprocess.run(["h5diff", "--exclude-path", "/run", full, reuse], stdout=subprocess.DEVNULL).returncode == 0
        rf = reuse_report["run"]["figures"]
        ft = full_report["run"]["timings_s"]
        rt = reuse_report["run"]["timings_s"]
        rows.append({
            "edit": name,
            "options": options,
            "same_file": same,
            "pairs": rf["reuse_pairs"],
            "pairs_kept": rf["reuse_pairs_kept"],
            "kept_share": rf["reuse_pairs_kept"] / max(rf["reuse_pairs"], 1),
            "cells_whole": rf["reuse_cells_whole"],
            "changed_tiles": rf["reuse_changed_tiles"],
            "objects_matched": rf["reuse_objects_matched"],
            "full_seconds": full_seconds,
            "reuse_seconds": reuse_seconds,
            "full_pvs_seconds": ft.get("conservative_pvs", 0.0),
            "reuse_pvs_seconds": rt.get("conservative_pvs", 0.0),
            "reuse_plan_seconds": rt.get("reuse_plan", 0.0),
            "pvs_speedup": ft.get("conservative_pvs", 0.0) / max(rt.get("conservative_pvs", 0.0), 1e-9),
            "mean_pvs": reuse_report["figures"]["pvs_objects_mean"],
        })
    json.dump({"bench": "reuse_edits", "world": a.world, "bake_options": bake_extra, "base": a.base,
               "old_seconds": old_seconds, "old_pvs_seconds": old_report["run"]["timings_s"].get("conservative_pvs", 0.0),
               "edits": rows}, sys.stdout, indent=2)
    print()
    return 0 if all(r["same_file"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
