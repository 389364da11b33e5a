#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Bake jobs: what checkpoints cost, what a kill costs with them (docs/ALGORITHMS.md#resume), and what
several processes gain (docs/ALGORITHMS.md#processes). Prints one JSON object.

checkpoint mode (the default) bakes WORLD three ways with the same options:
  plain:    --checkpoint-interval 0 (no checkpoint), the reference file;
  journal:  --checkpoint-interval S: its checkpoint_seconds against its PVS seconds is what writing the
            chunks cost (a bound: the chunk is written under the journal's lock), and its wall time against
            the plain bake's (a noisy ratio on a shared machine);
  killed:   --checkpoint-interval S, SIGKILLed after F x the plain bake's wall time, then run again: the
            two runs' wall times, the rows the second took from the checkpoint, and whether the file equals
            the plain bake outside /run (h5diff --exclude-path /run).

--ranks R: bakes WORLD as 1 process of T threads and as R MPI ranks of T / R threads each (T = --threads,
  default 2), one after the other: wall times, their ratio, each rank's peak memory (GNU time) and whether
  the files are the same outside /run.

--project REPORT: no bake; from the report of a finished conservative grid bake (and the ranks and threads
  per rank it ran with, --ranks R --threads T), the time the same bake would take on each of --cores
  (default 2,16,64), nodes of --node-cores (default 16) each running one rank with a thread per core:
      sum over the stages before the PVS (each rank computes them) of  serial + parallel / t
      +  PVS CPU-seconds / P  +  the same sum over ranking, verification and writing
  with t = min(P, node cores). Only the outermost stages count (the inner ones, NESTED below, are parts
  of them). A stage's serial and parallel seconds come from its wall seconds W and CPU seconds C at T
  threads (run figures cpu_seconds_<stage> and threads, in reports since they were recorded): with
  W = serial + parallel / T and C = serial + parallel, parallel = (C - W) T / (T - 1) (Amdahl's law from one
  run); a report without them, or of one thread, takes every stage as wholly parallel, which favours many
  cores. The PVS CPU-seconds are its wall time times the ranks times their threads (dealing keeps them
  busy; the phase ends wait, so this bounds it from above). --one-thread REPORT1, the report of the same
  bake at one thread, fits each stage from the two wall times instead (W1 = serial + parallel, W = serial +
  parallel / T): CPU seconds count threads that spin-wait at OpenMP's joins as busy, which favours many
  cores, and two wall times do not. --scale CELLS,COST projects a bake of
  CELLS times as many cells, each COST times as costly (e.g. another play height, from two bakes of a
  smaller world); the stages before the PVS are kept as measured.

usage: bench/bake_jobs.py PVSBAKE WORLD [--interval S] [--kill-at F] [--ranks R [--threads T]] [--out DIR]
                          [-- BAKE OPTIONS...]
       bench/bake_jobs.py --project REPORT --ranks R --threads T [--cores 2,16,64] [--node-cores N]
                          [--one-thread REPORT1] [--scale CELLS,COST]
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time


def bake(pvsbake, world, out, options, interval):
    report = out + ".json"
    cmd = [pvsbake, "bake", world, "-o", out, "--report", report, "--checkpoint-interval", str(interval)]
    return cmd + options, report


def run(cmd, log):
    start = time.monotonic()
    with open(log, "ab") as f:
        status = subprocess.call(cmd, stdout=f, stderr=f)
    return status, time.monotonic() - start


def figure(report, name):
    with open(report) as f:
        j = json.load(f)
    return j["run"]["figures"].get(name), j["run"]["timings_s"]


def peak_mb(time_log):
    """Peak resident memory (MB) of each process GNU time measured, from lines "peak_kb N"."""
    with open(time_log) as f:
        return [int(line.split()[1]) / 1024.0 for line in f if line.startswith("peak_kb ")]


def compare_ranks(a, out_dir, log):
    per_rank = max(1, a.threads // a.ranks)
    result = {"world": a.world, "options": a.options, "threads": a.threads, "ranks": a.ranks,
              "threads_per_rank": per_rank}
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    files = {}
    for name, prefix, threads in (("one", [], a.threads),
                                  ("mpi", ["mpirun", "--oversubscribe", "-np", str(a.ranks)], per_rank)):
        out = os.path.join(out_dir, name + ".h5")
        time_log = os.path.join(out_dir, name + ".time")
        if os.path.exists(time_log):
            os.remove(time_log)
        cmd, report = bake(a.pvsbake, a.world, out, a.options + ["--threads", str(threads)], 0)
        cmd = prefix + ["/usr/bin/time", "-a", "-o", time_log, "-f", "peak_kb %M"] + cmd
        start = time.monotonic()
        with open(log, "ab") as f:
            status = subprocess.call(cmd, stdout=f, stderr=f, env=env)
        wall = time.monotonic() - start
        if status != 0:
            sys.exit(f"the {name} bake failed ({status}); see {log}")
        _, timings = figure(report, "total")
        result[name] = {"wall_s": wall, "pvs_s": timings.get("conservative_pvs"),
                        "peak_mb_per_process": peak_mb(time_log)}
        files[name] = out
    result["wall_ratio_one_to_mpi"] = result["one"]["wall_s"] / result["mpi"]["wall_s"]
    pvs_one, pvs_mpi = result["one"]["pvs_s"], result["mpi"]["pvs_s"]
    result["pvs_ratio_one_to_mpi"] = pvs_one / pvs_mpi if pvs_one and pvs_mpi else None
    result["same_file_outside_run"] = subprocess.call(
        ["h5diff", "--exclude-path", "/run", files["one"], files["mpi"]], stdout=subprocess.DEVNULL) == 0
    return result


# Stages timed inside another stage (view_volume holds voxelize and flood; occluders holds the solid, the
# probes, the boxes and the shrinking): left out of the sums, which take their outer stage.
NESTED = {"voxelize", "flood", "solid", "sight_probe", "gap_probe", "seal_probe", "boxes", "shrink",
          "block_occluders", "verify_miss_widths"}


def amdahl(wall, cpu, threads):
    """A stage's (serial, parallel) seconds of one thread from its wall and CPU seconds at `threads`."""
    if cpu is None or threads <= 1:
        return 0.0, wall * max(1, threads)
    parallel = max(0.0, (cpu - wall) * threads / (threads - 1))
    return max(0.0, wall - parallel / threads), parallel


def amdahl_two(wall_1, wall, threads):
    """A stage's (serial, parallel) seconds of one thread from its wall seconds at 1 and at `threads`."""
    parallel = max(0.0, (wall_1 - wall) * threads / (threads - 1)) if threads > 1 else wall_1
    return max(0.0, wall_1 - parallel), min(parallel, wall_1)


def project(a):
    with open(a.project) as f:
        j = json.load(f)
    timings = j["run"]["timings_s"]
    timings_1 = None
    if a.one_thread:
        with open(a.one_thread) as f:
            timings_1 = json.load(f)["run"]["timings_s"]
    figures = j["run"].get("figures", {})
    stages = list(timings)
    if "conservative_pvs" not in stages:
        sys.exit(f"{a.project}: no conservative_pvs stage (a conservative bake's report is needed)")
    at = stages.index("conservative_pvs")
    skip = NESTED | {"total", "conservative_pvs"}
    threads = max(1, a.threads // max(1, a.ranks)) if a.ranks else a.threads
    parts = {}
    for s in stages:
        if s in skip:
            continue
        if timings_1 is not None and s in timings_1:
            serial, parallel = amdahl_two(timings_1[s], timings[s], threads)
        else:
            serial, parallel = amdahl(timings[s], figures.get("cpu_seconds_" + s), threads)
        parts[s] = {"wall_s": timings[s], "serial_s": serial, "parallel_s": parallel,
                    "after_pvs": stages.index(s) > at}
    before = sum(timings[s] for s in parts if not parts[s]["after_pvs"])
    after = sum(timings[s] for s in parts if parts[s]["after_pvs"])
    cpu = timings["conservative_pvs"] * max(1, a.ranks) * threads
    cells = j["figures"]["cells"]
    cells_scale, cost_scale = (float(x) for x in a.scale.split(",")) if a.scale else (1.0, 1.0)
    pvs_1 = cpu * cells_scale * cost_scale
    out = {"report": a.project, "cells": cells, "measured_ranks": max(1, a.ranks),
           "measured_threads_per_rank": threads, "stages_before_pvs_s": before,
           "pvs_s": timings["conservative_pvs"], "pvs_cpu_s": cpu, "pvs_cpu_s_per_cell": cpu / cells,
           "after_pvs_s": after, "stages": parts, "amdahl": timings_1 is not None or any("cpu_seconds_" + s in figures for s in parts),
           "fit": "two wall times" if timings_1 is not None else "CPU seconds",
           "scale": {"cells": cells_scale, "cost_per_cell": cost_scale},
           "projected_cells": cells * cells_scale, "node_cores": a.node_cores, "projection": {}}
    for p in (int(x) for x in a.cores.split(",")):
        t = min(p, a.node_cores)
        before_p = sum(v["serial_s"] + v["parallel_s"] / t for v in parts.values() if not v["after_pvs"])
        # After the PVS (ranking, writing) the work grows with the cells.
        after_p = cells_scale * sum(v["serial_s"] + v["parallel_s"] / t for v in parts.values() if v["after_pvs"])
        total = before_p + pvs_1 / p + after_p
        out["projection"][str(p)] = {"nodes": -(-p // a.node_cores), "threads_per_rank": t,
                                     "stages_before_pvs_s": before_p, "pvs_s": pvs_1 / p,
                                     "after_pvs_s": after_p, "seconds": total, "hours": total / 3600.0}
    return out


def main():
    if "--project" in sys.argv:
        ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
        ap.add_argument("--project", required=True, help="the report of a finished conservative bake")
        ap.add_argument("--ranks", type=int, default=1, help="the ranks it ran with")
        ap.add_argument("--threads", type=int, default=1, help="its threads in all (ranks x threads per rank)")
        ap.add_argument("--cores", default="2,16,64")
        ap.add_argument("--node-cores", type=int, default=16)
        ap.add_argument("--scale", default=None, help="CELLS,COST: more cells, each costlier")
        ap.add_argument("--one-thread", default=None, help="the same bake's report at one thread")
        print(json.dumps(project(ap.parse_args()), indent=2))
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pvsbake")
    ap.add_argument("world")
    ap.add_argument("--interval", type=float, default=300.0, help="seconds between checkpoint chunks")
    ap.add_argument("--kill-at", type=float, default=0.7, help="kill after this share of the plain bake's time")
    ap.add_argument("--out", default=None, help="folder for the bakes (default: a temporary one)")
    ap.add_argument("--ranks", type=int, default=0, help="compare 1 process with this many MPI ranks")
    ap.add_argument("--threads", type=int, default=2, help="threads of the one process (--ranks)")
    argv = sys.argv[1:]
    options = argv[argv.index("--") + 1 :] if "--" in argv else []
    a = ap.parse_args(argv[: argv.index("--")] if "--" in argv else argv)
    a.options = options
    out_dir = a.out or tempfile.mkdtemp(prefix="pvsbake-bake-jobs-")
    os.makedirs(out_dir, exist_ok=True)
    log = os.path.join(out_dir, "log.txt")
    if a.ranks > 0:
        print(json.dumps(compare_ranks(a, out_dir, log), indent=2))
        return
    result = {"world": a.world, "options": a.options, "interval_s": a.interval, "kill_at": a.kill_at}

    plain = os.path.join(out_dir, "plain.h5")
    cmd, plain_report = bake(a.pvsbake, a.world, plain, a.options, 0)
    status, wall = run(cmd, log)
    if status != 0:
        sys.exit(f"the plain bake failed ({status}); see {log}")
    _, timings = figure(plain_report, "total")
    result["plain"] = {"wall_s": wall, "pvs_s": timings.get("conservative_pvs")}

    journal = os.path.join(out_dir, "journal.h5")
    cmd, journal_report = bake(a.pvsbake, a.world, journal, a.options, a.interval)
    status, wall = run(cmd, log)
    if status != 0:
        sys.exit(f"the bake with checkpoints failed ({status}); see {log}")
    seconds, timings = figure(journal_report, "checkpoint_seconds")
    chunks, _ = figure(journal_report, "checkpoint_chunks")
    pvs_s = timings.get("conservative_pvs")
    result["journal"] = {
        "wall_s": wall,
        "pvs_s": pvs_s,
        "checkpoint_seconds": seconds,
        "checkpoint_chunks": chunks,
        "checkpoint_share_of_pvs": seconds / pvs_s if pvs_s else None,
        "wall_ratio_to_plain": wall / result["plain"]["wall_s"],
    }

    killed = os.path.join(out_dir, "killed.h5")
    cmd, killed_report = bake(a.pvsbake, a.world, killed, a.options, a.interval)
    with open(log, "ab") as f:
        start = time.monotonic()
        p = subprocess.Popen(cmd, stdout=f, stderr=f)
        try:
            p.wait(timeout=a.kill_at * result["plain"]["wall_s"])
        except subprocess.TimeoutExpired:
            p.send_signal(signal.SIGKILL)
            p.wait()
        first = time.monotonic() - start
    status, second = run(cmd, log)
    if status != 0:
        sys.exit(f"the resumed bake failed ({status}); see {log}")
    resumed, _ = figure(killed_report, "resumed_rows")
    same = subprocess.call(["h5diff", "--exclude-path", "/run", plain, killed], stdout=subprocess.DEVNULL) == 0
    result["killed"] = {
        "killed_after_s": first,
        "resumed_wall_s": second,
        "resumed_rows": resumed,
        "same_file_outside_run": same,
        "lost_s": first + second - result["plain"]["wall_s"],
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
