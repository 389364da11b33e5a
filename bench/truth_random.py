#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Waste on random worlds: how much a plain-defaults bake lists over what its cells really see, on the
property tests' random closed box worlds (samples/random_world.h), grid and octree. Prints one JSON object.

For each seed, samples/make_random_world writes the world, `pvsbake bake` bakes it with plain defaults (and
BAKE OPTIONS) once on the grid and once with --cells octree, and bench_truth measures each bake against
rays aimed at every listed object from eyes drawn uniformly in the cells' eye space (--cells, --rays as
bench_truth's). Per world and kind: listed / really visible by triangles and by objects; in all: the same
ratios of the sums over every world (the figure the waste goal reads), and their median over worlds.

usage: bench/truth_random.py BUILD_DIR [--worlds N] [--first-seed S] [--cells C] [--rays R] [--out DIR]
                             [-- BAKE OPTIONS...]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile


def truth(build, world, bake, cells, rays):
    out = subprocess.run([os.path.join(build, "bench", "bench_truth"), world, bake, "--cells", str(cells),
                          "--rays", str(rays)], check=True, capture_output=True, text=True).stdout
    return json.loads(out[out.index("{"):])


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("build", help="the build folder (bin/pvsbake, samples/make_random_world, bench/bench_truth)")
    p.add_argument("--worlds", type=int, default=10)
    p.add_argument("--first-seed", type=int, default=1)
    p.add_argument("--cells", type=int, default=30, help="cells per bake that bench_truth measures")
    p.add_argument("--rays", type=int, default=16384, help="aimed rays per listed object")
    p.add_argument("--out", help="folder for the worlds and bakes (default: a temporary one)")
    a = p.parse_args(argv)
    out = a.out or tempfile.mkdtemp(prefix="truth_random_")
    os.makedirs(out, exist_ok=True)
    pvsbake = os.path.join(a.build, "bin", "pvsbake")
    rows = []
    sums = {k: {"listed_triangles": 0, "visible_triangles": 0, "listed_objects": 0, "visible_objects": 0}
            for k in ("grid", "octree")}
    for seed in range(a.first_seed, a.first_seed + a.worlds):
        world = os.path.join(out, f"random_{seed}.glb")
        subprocess.run([os.path.join(a.build, "samples", "make_random_world"), world, "--seed", str(seed)],
                       check=True, capture_output=True)
        for kind in ("grid", "octree"):
            bake = os.path.join(out, f"random_{seed}_{kind}.h5")
            cmd = [pvsbake, "bake", world, "-o", bake, "-q"] + (["--cells", "octree"] if kind == "octree" else [])
            done = subprocess.run(cmd + extra, capture_output=True, text=True)
            if done.returncode != 0:
                # A world whose seeds give no view volume is skipped, as the property tests draw another.
                rows.append({"seed": seed, "cells_kind": kind, "baked": False,
                             "error": done.stderr.strip().splitlines()[-1:] or ""})
                continue
            t = truth(a.build, world, bake, a.cells, a.rays)
            for k in sums[kind]:
                sums[kind][k] += t[k]
            rows.append({"seed": seed, "cells_kind": kind, "baked": True, "bake_cells": t["bake_cells"],
                         "cells": t["cells"], "objects": t["world_objects"],
                         "listed_over_visible_triangles": t["listed_over_visible_triangles"],
                         "listed_over_visible_objects": t["listed_over_visible_objects"],
                         "listed_triangle_share_mean": t["listed_triangle_share_mean"],
                         "visible_triangle_share_mean": t["visible_triangle_share_mean"]})
            print(f"seed {seed} {kind}: {t['listed_over_visible_triangles']:.3f}", file=sys.stderr)
    summary = {}
    for kind, s in sums.items():
        ratios = [r["listed_over_visible_triangles"] for r in rows if r["cells_kind"] == kind and r["baked"]]
        summary[kind] = {
            "worlds": len(ratios),
            "listed_over_visible_triangles": s["listed_triangles"] / max(1, s["visible_triangles"]),
            "listed_over_visible_objects": s["listed_objects"] / max(1, s["visible_objects"]),
            "listed_over_visible_triangles_world_median": statistics.median(ratios) if ratios else None,
            "listed_over_visible_triangles_world_max": max(ratios) if ratios else None,
        }
    json.dump({"bench": "truth_random", "rays_per_object": a.rays, "cells_per_bake": a.cells,
               "bake_options": extra, "summary": summary, "worlds": rows}, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
