#!/usr/bin/env bash
# Shows that the fast kernels vectorize (and that the no-SIMD build really is scalar), from the
# machine code the build made: each kernel named below must contain packed single-precision
# arithmetic (vaddps, vfmadd231ps, ...) in the SIMD build and none in the no-SIMD build.
# Usage: check_simd.sh <libcrumple.a or .so> simd|scalar
# A kernel that silently stops vectorizing (a clamp the compiler turns into a branch, a
# constant read through a pointer in the loop) fails here with its name.
set -euo pipefail
lib=$1 mode=$2
# Vectorized loops (omp simd), wide-row sums (wide.h) and the AVX lanes (lanes8.h) of the edge
# pass and the adapt test. The triangle pass is scalar on purpose (kernels.cpp says why) and not
# listed. advance holds one loop per scene kind (with and without the sphere), each branch-free:
# a branch inside would keep an AVX2 target's vectorizer off it (no masked operations).
kernels=(adapt_test advance edge_forces gather_forces jacobi_sweep vertex_normals)
command -v objdump > /dev/null || { echo "check_simd: objdump not found (package binutils)"; exit 1; }
dump=$(objdump -d -C --no-show-raw-insn "$lib")
status=0
for k in "${kernels[@]}"; do
  # The body of crumple::fast::<k>(...) and of any <k>_body(...) or <k>_body<...>(...) helper
  # it calls, if the compiler did not inline it.
  body=$(awk -v a="crumple::fast::$k(" -v b="::${k}_body(" -v c="::${k}_body<" \
    '/>:$/ {p = index($0, a) || index($0, b) || index($0, c); next} /^$/ {p = 0} p' <<<"$dump")
  if [[ -z $body ]]; then echo "check_simd: no function $k in $lib"; status=1; continue; fi
  packed=$(grep -cE $'\t(\\{evex\\} )?v?(add|sub|mul|div|sqrt|max|min|f(n)?m(add|sub)[0-9]+)ps ' <<<"$body" || true)
  echo "$k: $packed packed float instructions"
  if [[ $mode == simd && $packed -eq 0 ]]; then echo "check_simd: $k is not vectorized"; status=1; fi
  if [[ $mode == scalar && $packed -ne 0 ]]; then echo "check_simd: $k is vectorized in the no-SIMD build"; status=1; fi
done
exit $status
