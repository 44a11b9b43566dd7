#!/usr/bin/env bash
# Builds crumple and runs every test (ctest). Usage: scripts/test.sh [build-dir]
# CRUMPLE_SANITIZE=address|thread builds with sanitizers (in build-asan / build-tsan by default).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install_deps.sh"
san=${CRUMPLE_SANITIZE:-}
build=${1:-$root/build${san:+-$san}}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=${CRUMPLE_BUILD_TYPE:-Release} \
      -DCRUMPLE_SANITIZE="$san" -DCRUMPLE_BUILD_BENCH=${CRUMPLE_BUILD_BENCH:-ON} > "$build.cmake.log" 2>&1 \
  || { cat "$build.cmake.log"; exit 1; }
cmake --build "$build" -j "$(nproc)"
cd "$build" && ctest --output-on-failure -j "$(nproc)" ${CTEST_ARGS:-}
