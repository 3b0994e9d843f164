#!/bin/sh
# The runtime package alone (docs/runtime.md "Building and installing alone"), as a lab does it:
# configure lib/runtime by itself (a C++17 compiler and nothing else), build, install only the
# `development` component into a scratch prefix, then build a C-only consumer (LANGUAGES C) with
# find_package(fivebar_runtime 0.1) against that prefix alone and run it (the C API's test on the
# showcase's exported JSON). find_package(fivebar_runtime 0.2) must fail (the version file).
#   check.sh SOURCE_DIR SCRATCH_DIR EXPORTED.json [extra cmake arguments, e.g. a toolchain file]
# With FIVEBAR_RUNTIME_EMULATOR set (e.g. "qemu-aarch64 -L /usr/aarch64-linux-gnu") the consumer
# runs under it.
set -eu
src=$1 scratch=$2 json=$3
shift 3
rm -rf "$scratch"
mkdir -p "$scratch"
launcher=""
if command -v ccache >/dev/null 2>&1; then launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"; fi
cmake -S "$src/lib/runtime" -B "$scratch/build" -G Ninja -DCMAKE_BUILD_TYPE=Release $launcher "$@" >"$scratch/configure.log"
cmake --build "$scratch/build" >"$scratch/build.log"
cmake --install "$scratch/build" --prefix "$scratch/prefix" --component development >"$scratch/install.log"
test -f "$scratch/prefix/lib/cmake/fivebar_runtime/fivebar_runtimeConfigVersion.cmake" ||
  test -n "$(find "$scratch/prefix" -name fivebar_runtimeConfigVersion.cmake)"
cmake -S "$src/test/runtime_package/consumer" -B "$scratch/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" "$@" >"$scratch/consumer-configure.log"
cmake --build "$scratch/consumer" >"$scratch/consumer-build.log"
${FIVEBAR_RUNTIME_EMULATOR:-} "$scratch/consumer/consumer" "$json"
if cmake -S "$src/test/runtime_package/consumer" -B "$scratch/consumer-0.2" -G Ninja \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" -DFIVEBAR_RUNTIME_REQUIRED_VERSION=0.2 "$@" >"$scratch/consumer-0.2.log" 2>&1; then
  echo "find_package(fivebar_runtime 0.2) found the 0.1 package" >&2
  exit 1
fi
echo "runtime package: built alone, installed (development component), consumed from C"
