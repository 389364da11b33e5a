#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""bench/bake_jobs.py --project against hand-made reports: Amdahl's law per outermost stage from wall and
CPU seconds, inner stages not counted twice, verification after the PVS, and every stage taken as parallel
without CPU seconds."""
import json
import subprocess
import sys
import tempfile

script = sys.argv[1]


def project(report, cores="2,16", one_thread=None):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(report, f)
    extra = []
    if one_thread is not None:
        with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as g:
            json.dump(one_thread, g)
        extra = ["--one-thread", g.name]
    out = subprocess.run([sys.executable, script, "--project", f.name, "--ranks", "1", "--threads", "2",
                          "--cores", cores] + extra, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def close(a, b):
    assert abs(a - b) < 1e-9, (a, b)


timings = {"voxelize": 1.0, "view_volume": 2.0, "boxes": 3.0, "occluders": 10.0, "conservative_pvs": 4.0,
           "occluder_ranking": 1.0, "verify": 5.0, "total": 30.0}
# occluders: W 10, C 15 at 2 threads: parallel 10, serial 5. view_volume: W 2, C 2: all serial.
# ranking: W 1, C 2, and verify: W 5, C 10: all parallel, counted after the PVS.
figures = {"threads": 2, "cpu_seconds_occluders": 15.0, "cpu_seconds_view_volume": 2.0,
           "cpu_seconds_occluder_ranking": 2.0, "cpu_seconds_boxes": 3.0, "cpu_seconds_verify": 10.0}
o = project({"figures": {"cells": 10}, "run": {"timings_s": timings, "figures": figures}})
assert o["amdahl"]
close(o["stages_before_pvs_s"], 12.0)  # view_volume + occluders; voxelize and boxes are inside them
close(o["stages"]["occluders"]["serial_s"], 5.0)
close(o["stages"]["occluders"]["parallel_s"], 10.0)
close(o["stages"]["view_volume"]["serial_s"], 2.0)
close(o["projection"]["2"]["seconds"], 12.0 + 4.0 + 1.0 + 5.0)
close(o["projection"]["16"]["stages_before_pvs_s"], 2.0 + 5.0 + 10.0 / 16)
close(o["projection"]["16"]["pvs_s"], 8.0 / 16)
close(o["projection"]["16"]["after_pvs_s"], (2.0 + 10.0) / 16)
# Without CPU seconds every stage is parallel: 2 threads' wall is 2 thread-seconds per second.
o = project({"figures": {"cells": 10}, "run": {"timings_s": timings, "figures": {}}})
assert not o["amdahl"]
close(o["projection"]["16"]["stages_before_pvs_s"], 12.0 * 2 / 16)
# From two wall times (1 and 2 threads), whatever the CPU seconds say (threads spinning at joins count as
# busy): occluders 16 s alone and 10 s on two threads: parallel 12, serial 4. view_volume the same at both:
# serial. A stage the one-thread report lacks falls back to the CPU seconds.
timings_1 = dict(timings, occluders=16.0, view_volume=2.0)
del timings_1["occluder_ranking"]
o = project({"figures": {"cells": 10}, "run": {"timings_s": timings, "figures": figures}},
            one_thread={"run": {"timings_s": timings_1}})
assert o["fit"] == "two wall times"
close(o["stages"]["occluders"]["serial_s"], 4.0)
close(o["stages"]["occluders"]["parallel_s"], 12.0)
close(o["stages"]["view_volume"]["serial_s"], 2.0)
close(o["stages"]["occluder_ranking"]["parallel_s"], 2.0)
close(o["projection"]["16"]["stages_before_pvs_s"], 2.0 + 4.0 + 12.0 / 16)
print("ok")
