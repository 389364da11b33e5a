#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Sets up everything pvsbake needs on Debian 12 (run as root) and builds it (Release) into build/.
# Idempotent: packages already installed are not fetched again, and the build is incremental.
#   scripts/setup.sh            install what is missing, configure, build
#   BUILD_DIR=... BUILD_TYPE=... scripts/setup.sh   another folder or build type
#   PVSBAKE_MPI=OFF scripts/setup.sh                 without MPI (one process per bake)
#   PVSBAKE_TEST_TOOLS=1 scripts/setup.sh            also the tools only the tests use (scripts/test.sh)
set -euo pipefail
cd "$(dirname "$0")/.."

# Why each package is here: README.md, "Dependencies".
PACKAGES=(
  g++ cmake ninja-build pkg-config
  libembree-dev       # Embree 3: ray tracing for verification and the sampled PVS
  libglm-dev          # vectors and matrices
  libtinygltf-dev     # glTF 2.0 parsing
  libhdf5-dev hdf5-tools  # the bake file (and h5dump to read it)
  libgtest-dev        # tests
  libopenmpi-dev openmpi-bin  # bakes over several processes or machines (mpirun; PVSBAKE_MPI)
  libcli11-dev        # command line parsing and --help
  nlohmann-json3-dev  # JSON reports
  libfmt-dev          # message formatting
  libxxhash-dev       # content hash of the world in the bake file
  libvtk9-dev         # pvsview, the viewer (optional: the rest builds without it)
  xvfb xauth          # xvfb-run: pvsview's headless screenshots and their tests without a display
  python3             # the loader's install tests: a ctypes game, the exported-symbol check
)

# Only the tests use these (why each: CONTRIBUTING.md, "Test dependencies"): the runtime (runtime/pvsr.h) built
# and run on other machines, and fuzzed.
TEST_PACKAGES=(
  clang libclang-rt-14-dev  # Clang: the runtime built as C99 and C++17 by a second compiler; libFuzzer
  gcc-multilib g++-multilib # the runtime for 32-bit x86 (gcc -m32), as C and as C++
  qemu-user                 # qemu-i386: runs that 32-bit test where the kernel's 32-bit emulation is off
  gcc-mingw-w64-x86-64 wine wine64  # the runtime for Windows, its test run under Wine
  emscripten nodejs         # the runtime for WebAssembly, its test run under Node
)
if [ "${PVSBAKE_TEST_TOOLS:-0}" = 1 ]; then
  PACKAGES+=("${TEST_PACKAGES[@]}")
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: installing packages needs root (run as root, or install: ${missing[*]})" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The Khronos glTF-Validator (npm's gltf-validator), which tests/gltf/lies.py sets beside the loader's own
# checks: npm from Debian where the machine has none.
GLTF_VALIDATOR_DIR=/opt/pvsbake-npm
if [ "${PVSBAKE_TEST_TOOLS:-0}" = 1 ] && [ ! -f "$GLTF_VALIDATOR_DIR/node_modules/gltf-validator/package.json" ]; then
  if ! command -v npm >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends npm >/dev/null
  fi
  echo "setup: installing gltf-validator into $GLTF_VALIDATOR_DIR"
  npm install --prefix "$GLTF_VALIDATOR_DIR" --no-audit --no-fund --loglevel=error gltf-validator@2.0.0-dev.3.10 >/dev/null
fi

BUILD_DIR=${BUILD_DIR:-build}
BUILD_TYPE=${BUILD_TYPE:-Release}
PVSBAKE_MPI=${PVSBAKE_MPI:-ON}
if [ ! -f "$BUILD_DIR/build.ninja" ] ||
  ! grep -q "^PVSBAKE_MPI:BOOL=$PVSBAKE_MPI\$" "$BUILD_DIR/CMakeCache.txt"; then
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE="$BUILD_TYPE" -DPVSBAKE_MPI="$PVSBAKE_MPI" >/dev/null
fi
cmake --build "$BUILD_DIR" -j "$(nproc)"
echo "setup: built $BUILD_DIR/bin/pvsbake"
