#!/bin/sh
# The runtime for aarch64 (a Raspberry Pi 4/5 or any arm64 board; docs/runtime.md "aarch64"):
# Debian's cross compiler (g++-aarch64-linux-gnu) builds the runtime package alone and its C-only
# consumer (check.sh), which runs under qemu-user; then the consumer's fixed pattern of 2000 cycles
# (duties, statuses and distances moved as exact hexadecimal floats) must be the x86-64 build's
# byte for byte.
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
