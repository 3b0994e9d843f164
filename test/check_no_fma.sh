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
clones=0
for o in "$@"; do
  clones=$((clones + $("$objdump" -d --no-show-raw-insn "$o" | grep -cE '^[0-9a-f]+ <.*_batch.*\.avx2>:' || true)))
  n=$("$objdump" -d --no-show-raw-insn "$o" | grep -cE '[[:space:]]vfn?m(add|sub)(add|sub)?[0-9]' || true)
  if [ "$n" -gt 0 ]; then
    echo "$o: $n fused multiply-add instructions"
    found=1
  fi
done
# The check proves nothing unless the AVX2 clones of the kernels are among the objects.
if [ "$clones" -eq 0 ]; then
  echo "no AVX2 clone of a batch kernel in the $# objects given"
  found=1
fi
[ "$found" -eq 0 ] && echo "no fused multiply-add in $# objects ($clones AVX2 kernel clones)"
exit "$found"
