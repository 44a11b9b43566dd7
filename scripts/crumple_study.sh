#!/usr/bin/env bash
# The converged crumple and the error of every method against it (issue 12): builds crumple in
# build-acc/ (Release) and runs the stages of scripts/crumple_study.py into
# results/accuracy/crumple/ (crumple.json, runs.json with every run's statistics, tables.md,
# crumple_convergence.png).
#
#   scripts/crumple_study.sh            every stage (many hours on a 2-core machine: the N = 128
#                                       references alone are ~2 h of one core per level)
#   scripts/crumple_study.sh --quick    N = 32 only, 3 seeds (minutes), into results/accuracy/crumple/quick/
#   scripts/crumple_study.sh --report   only redraw the tables and charts from crumple.json
# Runs are cached by command line in runs.json: an interrupted study resumes where it stopped.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3
out=$root/results/accuracy/crumple
mode=${1:-}
case "$mode" in
  ""|--report) ;;
  --quick) out=$out/quick ;;
  *) echo "usage: scripts/crumple_study.sh [--quick|--report]" >&2; exit 2 ;;
esac
export CRUMPLE_CRUMPLE_OUT=$out
study() { $py "$root/scripts/crumple_study.py" "$@"; }
if [[ $mode == --report ]]; then study report; exit 0; fi
"$root/scripts/install_deps.sh"
build=${CRUMPLE_ACC_BUILD:-$root/build-acc}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCRUMPLE_BUILD_BENCH=OFF -DCRUMPLE_BUILD_TESTS=OFF \
  > "$build.cmake.log" 2>&1 || { cat "$build.cmake.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target crumple
export CRUMPLE_EXE=$build/app/crumple
mkdir -p "$out"
if [[ $mode == --quick ]]; then
  study calibrate --quick --substeps 64
  study converge --quick
  study pareto --quick --cases N32_k1e4
  study backends --quick
else
  study calibrate --sizes 32 --substeps 64
  study calibrate --sizes 64 128 --substeps 16
  study converge
  study pareto
  study backends
fi
study report
