#!/usr/bin/env bash
# Speed against accuracy, stability, adaptivity (issue 5): builds crumple and the tests in
# build-acc/ and regenerates everything under results/accuracy/ (JSON, CSV-like tables, PNG).
#
#   scripts/accuracy.sh           full study (~15 min on a shared 2-core machine)
#   scripts/accuracy.sh --quick   a ~3 min subset, written to results/accuracy/quick/ instead
#
# Stages (each a script of its own, runnable alone with /usr/bin/python3):
#   stability_tests.py     the ctest stability tests; what they measured -> stability_tests.json
#   accuracy_reference.py  reference solutions (symplectic Euler, h halved until converged)
#   accuracy_sweep.py      every method x step x case: error and cost; Pareto charts, pareto.md
#   stability_map.py       bounded or not over kappa x h per method, two scenes
#   accuracy_adaptive.py   adaptive vs uniform; floor / epsilon as cost controls
# Needs numpy, scipy, matplotlib for /usr/bin/python3 (scripts/install_deps.sh installs them).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
quick=""
out=$root/results/accuracy
if [[ "${1:-}" == "--quick" ]]; then
  quick=--quick
  out=$root/results/accuracy/quick
elif [[ $# -gt 0 ]]; then
  echo "usage: scripts/accuracy.sh [--quick]" >&2
  exit 2
fi
build=${CRUMPLE_ACC_BUILD:-$root/build-acc}
py=/usr/bin/python3

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCRUMPLE_BUILD_BENCH=OFF > "$build.cmake.log" 2>&1 \
  || { cat "$build.cmake.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target crumple test_model

export CRUMPLE_EXE=$build/app/crumple
export CRUMPLE_ACC_OUT=$out
mkdir -p "$out"
work=$build/acc_runs
rm -rf "$work"

# The machine and the source the numbers come from.
{
  echo "{"
  echo "  \"cpu\": \"$(LC_ALL=C lscpu | sed -n 's/^Model name:[[:space:]]*//p' | head -1)\","
  echo "  \"cpus\": $(nproc),"
  echo "  \"commit\": \"$(git -C "$root" rev-parse HEAD 2>/dev/null || echo unknown)\","
  echo "  \"core_app_modified_files\": $(git -C "$root" status --porcelain core app 2>/dev/null | wc -l),"
  echo "  \"date\": \"$(date -u +%Y-%m-%dT%H:%M:%SZ)\","
  echo "  \"quick\": $([[ -n $quick ]] && echo true || echo false)"
  echo "}"
} > "$out/machine.json"

: > "$out/runtimes.txt"
stage() {
  local name=$1
  shift
  local t0=$SECONDS
  echo "== $name"
  "$@"
  echo "$name: $((SECONDS - t0)) s" | tee -a "$out/runtimes.txt"
}
total0=$SECONDS
stage stability_tests $py "$root/scripts/stability_tests.py" --build "$build"
stage reference $py "$root/scripts/accuracy_reference.py" $quick --work "$work"
stage sweep $py "$root/scripts/accuracy_sweep.py" $quick --work "$work"
stage stability_map $py "$root/scripts/stability_map.py" $quick --work "$work"
stage adaptive $py "$root/scripts/accuracy_adaptive.py" $quick --work "$work"
echo "total: $((SECONDS - total0)) s" | tee -a "$out/runtimes.txt"
$py "$root/scripts/recommend.py" --table "$out/sweep.json" --scene hang --kappa 1e5 --error 1e-2 || true
rm -rf "$work"
