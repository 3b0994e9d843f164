#!/bin/sh
# Fails if an object file holds a fused multiply-add instruction. The batch kernels are compiled in
# baseline, AVX2 and AVX-512 clones (FIVEBAR_SIMD_CLONES); the last two may use FMA, whose single
# rounding of a*b+c would make the clones disagree with each other and with the scalar path. The
# library is compiled with -ffp-contract=off to prevent that; this check proves it on the objects.
# Usage: check_no_fma.sh OBJDUMP OBJECT...
set -eu
objdump=$1
shift
found=0
for o in "$@"; do
  n=$("$objdump" -d --no-show-raw-insn "$o" | grep -cE '[[:space:]]vfn?m(add|sub)(add|sub)?[0-9]' || true)
  if [ "$n" -gt 0 ]; then
    echo "$o: $n fused multiply-add instructions"
    found=1
  fi
done
[ "$found" -eq 0 ] && echo "no fused multiply-add in $# objects"
exit "$found"
