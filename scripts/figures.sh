#!/usr/bin/env bash
# Builds the crumple binary (Release, in build-fig) and regenerates results/figures/.
# Usage: scripts/figures.sh [--quick] [any scripts/figures.py option, e.g. --sim-args "--substeps 2"]
# Writes results/figures/ (with --quick: build-fig/figwork/quick-figures/, a 2-seed 120-frame pass).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${CRUMPLE_FIG_BUILD:-$root/build-fig}
"$root/scripts/install_deps.sh"
mkdir -p "$build"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCRUMPLE_BUILD_BENCH=OFF \
      > "$build/figures-configure.log" 2>&1 || { cat "$build/figures-configure.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target crumple > "$build/figures-build.log" 2>&1 \
  || { tail -40 "$build/figures-build.log"; exit 1; }
# matplotlib is a Debian package: use the system interpreter, not a python3 first on PATH
exec /usr/bin/python3 "$root/scripts/figures.py" --bin "$build/app/crumple" \
     --work "$build/figwork" "$@"
