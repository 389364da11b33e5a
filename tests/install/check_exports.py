#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The shared loader exports the C API and nothing else (docs/LOADER.md, "Stability").

    check_exports.py LIB SONAME HEADER...

Reads the functions the headers declare with PVSBAKE_API, the dynamic symbols LIB defines
(`nm -D --defined-only`) and its SONAME (`readelf -d`), and fails (exit status 1, listing what differs) when
LIB exports anything else (a C++ symbol, an internal function), misses a declared function, or has
another soname.
"""
import re
import subprocess
import sys


def main():
    if len(sys.argv) < 4:
        print("usage: check_exports.py LIB SONAME HEADER...", file=sys.stderr)
        sys.exit(2)
    lib, soname = sys.argv[1], sys.argv[2]
    declared = set()
    for header in sys.argv[3:]:
        text = re.sub(r"/\*.*?\*/", " ", open(header).read(), flags=re.S)
        declared |= set(re.findall(r"PVSBAKE_API\b[^;{(]*?\b(pvsbake_\w+)\s*\(", text))
    if not declared:
        print("check_exports: the headers declare no PVSBAKE_API function", file=sys.stderr)
        sys.exit(1)

    nm = subprocess.run(["nm", "-D", "--defined-only", lib], capture_output=True, text=True, check=True)
    exported = set()
    for line in nm.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[1] not in ("A",):  # "A": a version node's name, not code
            exported.add(parts[2].split("@")[0])
    readelf = subprocess.run(["readelf", "-d", lib], capture_output=True, text=True, check=True)
    found = re.findall(r"\(SONAME\)\s+Library soname: \[([^\]]+)\]", readelf.stdout)

    errors = []
    for name in sorted(exported - declared):
        errors.append("exports %s, which no header declares with PVSBAKE_API%s"
                      % (name, " (a C++ symbol)" if name.startswith("_Z") else ""))
    for name in sorted(declared - exported):
        errors.append("does not export %s, declared with PVSBAKE_API" % name)
    if found != [soname]:
        errors.append("soname %s, expected %s" % (found, soname))
    for e in errors:
        print("check_exports: %s: %s" % (lib, e), file=sys.stderr)
    if errors:
        sys.exit(1)
    print("check_exports: %s (soname %s) exports exactly the %d C API functions" % (lib, soname, len(declared)))


if __name__ == "__main__":
    main()
