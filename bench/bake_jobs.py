#!/usr/bin/env python3
"""What checkpoints cost a bake, and what a kill costs with them (docs/ALGORITHMS.md#resume).

Bakes WORLD three ways with the same options and prints one JSON object:
  plain:    --checkpoint-interval 0 (no checkpoint), the reference file;
  journal:  --checkpoint-interval S: its checkpoint_seconds against its PVS seconds is what writing the
            chunks cost (a bound: the chunk is written under the journal's lock), and its wall time against
            the plain bake's (a noisy ratio on a shared machine);
  killed:   --checkpoint-interval S, SIGKILLed after F x the plain bake's wall time, then run again: the
            two runs' wall times, the rows the second took from the checkpoint, and whether the file equals
            the plain bake outside /run (h5diff --exclude-path /run).

usage: bench/bake_jobs.py PVSBAKE WORLD [--interval S] [--kill-at F] [--out DIR] [-- BAKE OPTIONS...]
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


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pvsbake")
    ap.add_argument("world")
    ap.add_argument("--interval", type=float, default=300.0, help="seconds between checkpoint chunks")
    ap.add_argument("--kill-at", type=float, default=0.7, help="kill after this share of the plain bake's time")
    ap.add_argument("--out", default=None, help="folder for the bakes (default: a temporary one)")
    argv = sys.argv[1:]
    options = argv[argv.index("--") + 1 :] if "--" in argv else []
    a = ap.parse_args(argv[: argv.index("--")] if "--" in argv else argv)
    a.options = options
    out_dir = a.out or tempfile.mkdtemp(prefix="pvsbake-bake-jobs-")
    os.makedirs(out_dir, exist_ok=True)
    log = os.path.join(out_dir, "log.txt")
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
