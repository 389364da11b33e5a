#!/usr/bin/env python3
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

usage: bench/bake_jobs.py PVSBAKE WORLD [--interval S] [--kill-at F] [--ranks R [--threads T]] [--out DIR]
                          [-- BAKE OPTIONS...]
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


def main():
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
