#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The licence reaches every file a studio may copy: LICENSE at the root is the MIT licence; every source,
script and build file under the root names it in an SPDX line near its head; the runtime's three files
(runtime/pvsr.h, pvsr.c, pvsr.hpp, meant to be copied into a game's tree) carry the licence text itself, so
that a copy keeps it. Usage: check_licence.py ROOT"""
import os
import sys

TAG = "SPDX-License-Identifier: MIT"
SOURCES = (".cpp", ".h", ".hpp", ".c", ".py", ".sh", ".cmake", ".in", ".js", ".map")
SKIP_DIRS = {".git", "node_modules"}


def main():
    root = sys.argv[1]
    problems = []
    licence = open(os.path.join(root, "LICENSE")).read()
    if not licence.startswith("MIT License"):
        problems.append("LICENSE: not the MIT licence")
    body = [line.strip() for line in licence.splitlines() if line.strip()]
    checked = 0
    for top, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("build"))
        for name in sorted(files):
            path = os.path.join(top, name)
            rel = os.path.relpath(path, root)
            if not (name.endswith(SOURCES) or name == "CMakeLists.txt" or rel == os.path.join(".ci", "run")):
                continue
            with open(path, errors="replace") as f:
                head = "".join(f.readline() for _ in range(4))
            checked += 1
            if TAG not in head:
                problems.append(f"{rel}: no '{TAG}' line in its first four lines")
    for name in ("pvsr.h", "pvsr.c", "pvsr.hpp"):
        text = open(os.path.join(root, "runtime", name)).read()
        lines = {line.strip(" */") for line in text.splitlines()}
        missing = [line for line in body if line not in lines]
        if missing:
            problems.append(f"runtime/{name}: the licence text is not in its head (first missing: {missing[0]!r})")
    for p in problems:
        print(p)
    print(f"{checked} files checked, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
