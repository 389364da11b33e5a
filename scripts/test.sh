#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Set up, build and run the whole test suite. CI=true runs the long checks at a smaller size.
# Then the runtime loader's round-trip and fuzz tests, the runtime file's tests and the run-time culler's
# tests again, built with
# AddressSanitizer and UBSan (PVSBAKE_SANITIZE) in their own folder (ASAN_BUILD_DIR, default build-asan;
# only the loader, the libraries and those tests are built there, not the pvsbake command or the benches).
# SKIP_ASAN=1 skips that part.
set -euo pipefail
cd "$(dirname "$0")/.."
PVSBAKE_TEST_TOOLS=1 scripts/setup.sh
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j "$(nproc)" --timeout 900)

if [ "${SKIP_ASAN:-0}" != 1 ]; then
  ASAN_DIR=${ASAN_BUILD_DIR:-build-asan}
  if [ ! -f "$ASAN_DIR/build.ninja" ]; then
    cmake -S . -B "$ASAN_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPVSBAKE_SANITIZE=ON \
      -DPVSBAKE_BUILD_BENCH=OFF >/dev/null
  fi
  cmake --build "$ASAN_DIR" -j "$(nproc)" --target test_runtime_loader test_runtime_loader_fuzz test_runtime_file test_runtime_occlusion \
    pvsbake_walkthrough
  # No leak checking: HDF5 1.10.8 itself leaks a few allocations on some damaged files (every leak
  # LeakSanitizer reports in the fuzz test is inside libhdf5; the other tests leak nothing).
  export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  "$ASAN_DIR/tests/test_runtime_loader"
  "$ASAN_DIR/tests/test_runtime_loader_fuzz"
  "$ASAN_DIR/tests/test_runtime_file"
  "$ASAN_DIR/tests/test_runtime_occlusion"
  echo "test: the loaders' and the culler's tests pass under AddressSanitizer and UBSan ($ASAN_DIR)"
fi
