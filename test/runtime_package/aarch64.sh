#!/bin/sh
# The runtime for aarch64 (a Raspberry Pi 4/5 or any arm64 board; docs/runtime.md "aarch64"):
# Debian's cross compiler (g++-aarch64-linux-gnu) builds the runtime package alone and its C-only
# consumer (check.sh), which runs under qemu-user; then the consumer's fixed pattern of 2000 cycles
# (duties, statuses and distances moved as exact hexadecimal floats) must be the x86-64 build's
# byte for byte. Then the arm64 .deb packages (docs/runtime.md ".deb"): the runtime package built
# shared with the same cross compiler, `cpack -G DEB`, and each package's architecture and file list
# checked with dpkg-deb -f / -c (the shared library's ELF machine with `file`).
#   aarch64.sh SOURCE_DIR SCRATCH_DIR EXPORTED.json NATIVE_TEST_RUNTIME_C
# Exit 77 (skipped) without the cross compiler or qemu.
set -eu
src=$1 scratch=$2 json=$3 native=$4
for tool in aarch64-linux-gnu-g++ aarch64-linux-gnu-gcc qemu-aarch64; do
  command -v $tool >/dev/null 2>&1 || { echo "no $tool: skipped"; exit 77; }
done
FIVEBAR_RUNTIME_EMULATOR="qemu-aarch64 -L /usr/aarch64-linux-gnu" \
  sh "$src/test/runtime_package/check.sh" "$src" "$scratch" "$json" \
  -DCMAKE_SYSTEM_NAME=Linux -DCMAKE_SYSTEM_PROCESSOR=aarch64 \
  -DCMAKE_C_COMPILER=aarch64-linux-gnu-gcc -DCMAKE_CXX_COMPILER=aarch64-linux-gnu-g++
file "$scratch/consumer/consumer" 2>/dev/null | grep -q aarch64 || file "$scratch/consumer/consumer" | grep -qi "arm"
"$native" "$json" "$scratch/x86_64.txt" >/dev/null
qemu-aarch64 -L /usr/aarch64-linux-gnu "$scratch/consumer/consumer" "$json" "$scratch/aarch64.txt" >/dev/null
if ! cmp "$scratch/x86_64.txt" "$scratch/aarch64.txt"; then
  echo "aarch64 duties differ from x86-64's" >&2
  exit 1
fi
echo "aarch64: $(wc -l <"$scratch/aarch64.txt") cycles, duties bit-identical to x86-64"

# The .deb: a shared build beside the static one (same sources and flags; ccache serves the rest).
launcher=""
if command -v ccache >/dev/null 2>&1; then launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"; fi
cmake -S "$src/lib/runtime" -B "$scratch/deb" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=ON $launcher \
  -DCMAKE_SYSTEM_NAME=Linux -DCMAKE_SYSTEM_PROCESSOR=aarch64 \
  -DCMAKE_C_COMPILER=aarch64-linux-gnu-gcc -DCMAKE_CXX_COMPILER=aarch64-linux-gnu-g++ >"$scratch/deb-configure.log"
cmake --build "$scratch/deb" >"$scratch/deb-build.log"
(cd "$scratch/deb" && cpack -G DEB >"$scratch/deb-cpack.log")
run="$scratch/deb/libfivebar-runtime0_0.1.0_arm64.deb" dev="$scratch/deb/libfivebar-runtime-dev_0.1.0_arm64.deb"
for deb in "$run" "$dev"; do
  test -f "$deb" || { echo "no $deb" >&2; ls "$scratch/deb" >&2; exit 1; }
  arch=$(dpkg-deb -f "$deb" Architecture)
  [ "$arch" = arm64 ] || { echo "$deb: Architecture $arch, expected arm64" >&2; exit 1; }
done
[ "$(dpkg-deb -f "$run" Package)" = libfivebar-runtime0 ] && [ "$(dpkg-deb -f "$dev" Package)" = libfivebar-runtime-dev ]
dpkg-deb -f "$dev" Depends | grep -qx 'libfivebar-runtime0 (= 0.1.0)'
expect() {  # expect DEB PATH...: each path is in the package's file list
  deb=$1
  shift
  for path in "$@"; do
    dpkg-deb -c "$deb" | awk '{print $6}' | grep -qx "./$path" || { echo "$deb: no $path" >&2; exit 1; }
  done
}
expect "$run" usr/lib/libfivebar_runtime.so.0.1.0 usr/lib/libfivebar_runtime_linux.so.0.1.0
expect "$dev" usr/include/fivebar/runtime.hpp usr/include/fivebar/runtime/c_api.h usr/include/fivebar/runtime/linux_io.hpp \
  usr/lib/libfivebar_runtime.so usr/lib/cmake/fivebar_runtime/fivebar_runtimeConfig.cmake \
  usr/lib/cmake/fivebar_runtime/fivebar_runtimeConfigVersion.cmake
if dpkg-deb -c "$run" | awk '{print $6}' | grep -q '^./usr/include/'; then echo "$run: holds headers" >&2; exit 1; fi
rm -rf "$scratch/deb-x" && dpkg-deb -x "$run" "$scratch/deb-x"
file -L "$scratch/deb-x/usr/lib/libfivebar_runtime.so.0.1.0" | grep -q "ARM aarch64" || {
  file -L "$scratch/deb-x/usr/lib/libfivebar_runtime.so.0.1.0" >&2
  exit 1
}
echo "arm64 .deb: $(basename "$run"), $(basename "$dev") (architecture and file lists checked)"
