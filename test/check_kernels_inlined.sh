#!/bin/sh
# Fails if a batch kernel's per-block body was compiled out of line. FIVEBAR_SIMD_CLONES compiles
# each batch kernel once per ISA (baseline, AVX2, AVX-512), but a lambda it calls and GCC does not
# inline is compiled once, for baseline x86-64, and then runs with two doubles per vector in every
# clone: the FK batch ran 3x slower that way. The bodies carry always_inline; this check proves
# that no `..._batch(...)::{lambda ...}` function is left in the objects.
# Usage: check_kernels_inlined.sh NM OBJECT...
set -eu
nm=$1
shift
found=0
for o in "$@"; do
  n=$("$nm" -C "$o" | grep -cE '_batch\(.*\)::\{lambda' || true)
  if [ "$n" -gt 0 ]; then
    echo "$o: $n batch-kernel lambdas compiled out of line:"
    "$nm" -C "$o" | grep -E '_batch\(.*\)::\{lambda' | sed 's/^/  /'
    found=1
  fi
done
[ "$found" -eq 0 ] && echo "every batch-kernel body inlined in $# objects"
exit "$found"
