# SPDX-License-Identifier: MIT
"""What the fault scripts (inject.py, reads.py) share: the cheap bake options and running pvsbake undisturbed
or under the preloaded tests/faults/fail_io.c."""

import os
import subprocess

# Cheap occluders, few verification rays: a bake of the tiny world (samples/tiny_world.py) in under a second.
FAST = ["-q", "--occluder-probe-eyes", "64", "--occluder-gap-lines", "0", "--occluder-seal-rays", "0",
        "--eyes", "2", "--rays", "64", "--threads", "2"]
TIMEOUT_S = 120


def run(cmd, cwd, env_extra=None):
    """(status, stdout, stderr) of cmd run in cwd, with env_extra (LD_PRELOAD only when it says so); status None
    when it ran past TIMEOUT_S (a hang)."""
    env = dict(os.environ)
    env.pop("LD_PRELOAD", None)
    env.update(env_extra or {})
    try:
        p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return None, "", "timed out (a hang)"
    return p.returncode, p.stdout, p.stderr
