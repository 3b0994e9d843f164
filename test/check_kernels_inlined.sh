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
kernels=0
for o in "$@"; do
  kernels=$((kernels + $("$nm" -C --defined-only "$o" | grep -cE ' fivebar::(fk|ik|lci)_batch\(' || true)))
  n=$("$nm" -C "$o" | grep -cE '_batch\(.*\)::\{lambda' || true)
  if [ "$n" -gt 0 ]; then
    echo "$o: $n batch-kernel lambdas compiled out of line:"
    "$nm" -C "$o" | grep -E '_batch\(.*\)::\{lambda' | sed 's/^/  /'
    found=1
  fi
done
# The check proves nothing unless the kernels are among the objects (a library split once hid them).
if [ "$kernels" -eq 0 ]; then
  echo "no batch kernel (fivebar::fk_batch, ik_batch, lci_batch) defined in the $# objects given"
  found=1
fi
[ "$found" -eq 0 ] && echo "every batch-kernel body inlined in $# objects ($kernels kernel symbols)"
exit "$found"
