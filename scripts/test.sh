#!/usr/bin/env bash
# Set up, build and run the whole test suite. CI=true runs the long checks at a smaller size.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j "$(nproc)" --timeout 900
