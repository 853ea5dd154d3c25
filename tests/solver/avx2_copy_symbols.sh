#!/bin/sh
# CpuKernels.Avx2CopyExportsOnlyItsFactories (solver/cpu_kernels.h): the AVX2 copy's object defines no global
# symbol but its two factories, so no AVX2-compiled inline function or template instance of it can replace the
# portable copy's at link time. OpenMP's named critical sections (common symbols, one lock for both copies) aside.
#   avx2_copy_symbols.sh NM OBJECT
nm=$1
obj=$2
symbols=$("$nm" -g --defined-only "$obj") || exit 1
factories=$(printf '%s\n' "$symbols" | grep -cE ' T _ZN5flume24make_(cpu|sph)_simulation_avx2')
others=$(printf '%s\n' "$symbols" | awk 'NF == 3 && $2 != "C" && $3 !~ /^_ZN5flume24make_(cpu|sph)_simulation_avx2/')
if [ "$factories" -ne 2 ]; then
  echo "$obj: expected the two factories as global text symbols, found $factories"
  exit 1
fi
if [ -n "$others" ]; then
  echo "$obj: global symbols beside the two factories:"
  printf '%s\n' "$others" | head -20
  exit 1
fi
echo "$obj: only make_cpu_simulation_avx2 and make_sph_simulation_avx2 are global"
