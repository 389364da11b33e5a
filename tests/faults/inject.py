# SPDX-License-Identifier: MIT
"""Fails every write of pvsbake's commands in turn, in the manner of SQLite's I/O error tests.

Each scenario (a bake with its report and runtime file, a bake of a leaking world with its leak path, export,
occluders -o, verify writing back) is run once undisturbed (the reference) and once under the preloaded
tests/faults/fail_io.c counting its writes (open for writing, write, fsync, close, rename, mkdir). Then for every
N it runs again with the Nth write failing: once alone (ENOSPC), once with every write from the Nth on failing
(a disk that stays full), and once alone with EIO. Each run must:

- end with status 0 or 1, never a signal (a crash) and never a hang;
- with status 1, print exactly one line starting "error: " that names an output and says why in plain words
  ("no space left on device"), and no warning the undisturbed run does not print but at most one that the
  checkpoint could not be written;
- leave every output either absent or whole (the reference's content), and no temporary file;
- leave every checkpoint chunk it wrote readable;
- with status 1, be followed by the same command, undisturbed, that ends with status 0 and the reference's
  outputs (resuming from the checkpoint the failed run left).

    inject.py --pvsbake build/bin/pvsbake --shim build/tests/libpvsbake_fail_io.so [--quick]

--quick (CI=true sets it too) leaves the EIO pass out. Prints one line per scenario with
its figures, and a JSON summary on the last line.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples"))
import tiny_world  # noqa: E402
from fault_runs import FAST, run  # noqa: E402

REASONS = {"ENOSPC": "no space left on device", "EIO": "the device reported an I/O error"}



def h5_same(a, b, h5diff, scratch):
    """The two bake files hold the same (outside /run, which holds timings and the machine)."""
    p = subprocess.run([h5diff, "--exclude-path", "/run", a, b], capture_output=True, text=True)
    return p.returncode == 0


def same_output(path, ref, h5diff, scratch):
    if path.endswith(".h5"):
        return h5_same(path, ref, h5diff, scratch)
    if path.endswith(".json"):
        try:
            with open(path) as f, open(ref) as g:
                return json.load(f).keys() == json.load(g).keys()
        except (OSError, ValueError):
            return False
    with open(path, "rb") as f, open(ref, "rb") as g:
        return f.read() == g.read()


class Scenario:
    """A command run in a folder prepared by `setup`, writing `outputs` (names in that folder)."""

    def __init__(self, name, args, outputs, setup=None, checkpoint=None, originals=None):
        self.name, self.args, self.outputs, self.setup, self.checkpoint = name, args, outputs, setup, checkpoint
        self.originals = originals or {}  # output -> the file it was before the command (verify writes back)

    def fresh(self, base, pvsbake):
        d = tempfile.mkdtemp(dir=base)
        if self.setup:
            self.setup(d, pvsbake)
        return d


def check_run(sc, d, rc, err, refs, h5diff, failures, label, reason, ref_warnings):
    """Checks one failed-write run in folder d; appends what is wrong to failures. Returns True when it must be
    rerun (status 1)."""
    def bad(what):
        failures.append(f"{sc.name} {label}: {what}\n--- stderr:\n{err}")

    if rc is None:
        bad("hung")
        return False
    if rc < 0 or rc > 1:
        bad(f"exit status {rc}" + (" (killed by a signal: a crash)" if rc < 0 else ""))
        return False
    lines = [l for l in err.splitlines() if l.strip()]
    errors = [l for l in lines if l.startswith("error: ")]
    warnings = [l for l in lines if l.startswith("warning: ")]
    others = [l for l in lines if l not in errors and l not in warnings]
    if others:
        bad(f"lines that are neither an error nor a warning: {others}")
    if rc == 1:
        if len(errors) != 1:
            bad(f"{len(errors)} error lines, not one")
        elif reason not in errors[0] or not any(o in errors[0] for o in sc.outputs + [sc.checkpoint or "-"]):
            bad(f"the error line does not name the output and say '{reason}': {errors[0]}")
    elif errors:
        bad("status 0 with an error line")
    new_warnings = [w for w in warnings if w not in ref_warnings]
    if len(new_warnings) > 1 or any("checkpoint" not in w or reason not in w for w in new_warnings):
        bad(f"warnings other than one about the checkpoint: {new_warnings}")
    for root, _, files in os.walk(d):
        for f in files:
            if ".tmp-" in f:
                bad(f"a temporary file is left: {os.path.join(root, f)}")
    for out in sc.outputs:
        path = os.path.join(d, out)
        if os.path.exists(path) and not same_output(path, refs[out], h5diff, d) and not (
                rc != 0 and out in sc.originals and same_output(path, sc.originals[out], h5diff, d)):
            bad(f"{out} is there but neither whole nor as it was (differs from the reference)")
        if rc == 0 and not os.path.exists(path):
            bad(f"status 0 but {out} is missing")
    return rc == 1


def chunk_files(d, sc):
    if not sc.checkpoint:
        return []
    folder = os.path.join(d, sc.checkpoint)
    if not os.path.isdir(folder):
        return []
    return sorted(f for f in os.listdir(folder) if f.startswith("rows-") and f.endswith(".h5"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pvsbake", required=True)
    ap.add_argument("--shim", required=True, help="the preloaded failing-write library (fail_io.c)")
    ap.add_argument("--h5diff", default=shutil.which("h5diff") or "h5diff")
    ap.add_argument("--h5dump", default=shutil.which("h5dump") or "h5dump")
    ap.add_argument("--quick", action="store_true", default=os.environ.get("CI") == "true")
    a = ap.parse_args()
    pvsbake, shim = os.path.abspath(a.pvsbake), os.path.abspath(a.shim)
    base = tempfile.mkdtemp(prefix="pvsbake-faults-")
    tiny = os.path.join(base, "tiny.glb")
    leak = os.path.join(base, "leak.glb")
    with open(tiny, "wb") as f:
        f.write(tiny_world.glb(*tiny_world.parts()))
    with open(leak, "wb") as f:  # a small room, the spawn above it: the flood leaks out
        f.write(tiny_world.glb(*tiny_world.parts(room=((-1.5, 0, -1.5), (1.5, 2, 1.5)),
                                                 crate=((0.2, 0, 0.2), (0.8, 0.6, 0.8)),
                                                 spawn=(-0.75, 2.3, -0.75))))

    # A bake file to export and verify, made once.
    bake_file = os.path.join(base, "made.h5")
    rc, _, err = run([pvsbake, "bake", tiny, "-o", bake_file] + FAST, base)
    if rc != 0:
        sys.exit(f"the bake to export and verify failed ({rc}): {err}")

    def with_bake(d, _):
        shutil.copy(bake_file, os.path.join(d, "in.h5"))

    scenarios = [
        Scenario("bake", ["bake", tiny, "-o", "t.h5", "--report", "t.json", "--runtime-output", "t.pvsr"] + FAST,
                 ["t.h5", "t.json", "t.pvsr"], checkpoint="t.h5.checkpoint"),
        Scenario("bake-leak", ["bake", leak, "-o", "l.h5", "--report", "l.json", "--no-verify",
                               "--checkpoint-interval", "0"] + FAST,
                 ["l.h5", "l.h5.leak.obj", "l.json"], checkpoint="l.h5.checkpoint"),
        Scenario("export", ["export", "in.h5", "-o", "x.pvsr", "-q"], ["x.pvsr"], setup=with_bake),
        Scenario("occluders", ["occluders", tiny, "-o", "occ.glb", "--report", "occ.json"] + FAST[:7],
                 ["occ.glb", "occ.json"]),
        Scenario("verify", ["verify", tiny, "in.h5", "--report", "v.json", "-q", "--verify-eyes", "2",
                            "--verify-rays-per-eye", "64", "--threads", "2"],
                 ["in.h5", "v.json"], setup=with_bake, originals={"in.h5": bake_file}),
    ]
    passes = [("once", {"PVSBAKE_FAIL_ERRNO": "ENOSPC"}),
              ("full", {"PVSBAKE_FAIL_ERRNO": "ENOSPC", "PVSBAKE_FAIL_STICKY": "1"}),
              ("eio", {"PVSBAKE_FAIL_ERRNO": "EIO"})]
    failures, summary = [], []
    start = time.monotonic()
    for si, sc in enumerate(scenarios):
        ref_dir = sc.fresh(base, pvsbake)
        rc, _, err = run([pvsbake] + sc.args, ref_dir)
        ref_warnings = {l for l in err.splitlines() if l.startswith("warning: ")}
        if rc != 0:
            failures.append(f"{sc.name}: the undisturbed run failed ({rc}): {err}")
            continue
        refs = {o: os.path.join(ref_dir, o) for o in sc.outputs}
        for o, p in refs.items():
            if not os.path.exists(p):
                failures.append(f"{sc.name}: the undisturbed run wrote no {o}")
        count_dir = sc.fresh(base, pvsbake)
        trace = os.path.join(base, f"trace-{sc.name}.txt")
        rc, _, err = run([pvsbake] + sc.args, count_dir, {"LD_PRELOAD": shim, "PVSBAKE_FAIL_TRACE": trace})
        with open(trace) as f:
            calls = [l.split()[1] for l in f if l.strip()]
        if rc != 0 or not calls:
            failures.append(f"{sc.name}: the counting run failed ({rc}) or counted nothing: {err}")
            continue
        figures = {"scenario": sc.name, "writes": len(calls), "runs": 0, "exit_0": 0, "exit_1": 0,
                   "crashes": 0, "hangs": 0, "resumed": 0, "calls": sorted(set(calls))}
        for label, env in passes:
            if label == "eio" and a.quick:
                continue
            for n in range(1, len(calls) + 1):
                d = sc.fresh(base, pvsbake)
                env_n = dict(env, LD_PRELOAD=shim, PVSBAKE_FAIL_AT=str(n))
                rc, _, err = run([pvsbake] + sc.args, d, env_n)
                figures["runs"] += 1
                kind = "hangs" if rc is None else "crashes" if rc < 0 else f"exit_{rc}"
                figures[kind] = figures.get(kind, 0) + 1
                tag = f"{label} write {n} ({calls[n - 1]})"
                reason = REASONS[env["PVSBAKE_FAIL_ERRNO"]]
                if not check_run(sc, d, rc, err, refs, a.h5diff, failures, tag, reason, ref_warnings):
                    shutil.rmtree(d, ignore_errors=True)
                    continue
                chunks = chunk_files(d, sc)
                for c in chunks:
                    p = subprocess.run([a.h5dump, "-H", os.path.join(d, sc.checkpoint, c)], capture_output=True)
                    if p.returncode != 0:
                        failures.append(f"{sc.name} {tag}: the checkpoint chunk {c} is not readable")
                args = [x for x in sc.args if x != "-q"]
                rc2, out2, err2 = run([pvsbake] + args, d)
                if rc2 != 0:
                    failures.append(f"{sc.name} {tag}: the undisturbed rerun failed ({rc2}): {err2}")
                else:
                    if chunks and "resuming from the checkpoint" not in out2 + err2:
                        failures.append(f"{sc.name} {tag}: the rerun did not resume from {chunks}")
                    figures["resumed"] += bool(chunks)
                    for o in sc.outputs:
                        p = os.path.join(d, o)
                        if not os.path.exists(p) or not same_output(p, refs[o], a.h5diff, d):
                            failures.append(f"{sc.name} {tag}: after the rerun {o} differs from the reference")
                shutil.rmtree(d, ignore_errors=True)
        print(f"{sc.name}: {figures['writes']} writes ({', '.join(figures['calls'])}), {figures['runs']} runs: "
              f"{figures['exit_0']} exit 0, {figures['exit_1']} exit 1, {figures['crashes']} crashed, "
              f"{figures['hangs']} hung; {figures['resumed']} reruns resumed from a checkpoint", flush=True)
        summary.append(figures)
    shutil.rmtree(base, ignore_errors=True)
    print(json.dumps({"seconds": round(time.monotonic() - start, 1), "scenarios": summary,
                      "failures": len(failures)}))
    if failures:
        print(f"\n{len(failures)} failures; the first ones:", file=sys.stderr)
        for f in failures[:15]:
            print(f, file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
