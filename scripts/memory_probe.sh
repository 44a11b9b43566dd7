#!/usr/bin/env bash
# The machine's memory rates by working-set size: builds crumple_memory_probe
# (bench/memory_probe.cpp; Release, -march=native) in build-bench/ and runs it on each thread
# count: a streaming read and random 64-byte lines over arrays from 16 MiB up (within a quarter
# of the memory). Writes its output, with the machine and revision, to
# results/<machine-tag>/memory.txt (or --out FILE).
# An --out FILE in a folder whose run.json records another machine is refused before the build
# (exit 2), as scripts/bench.sh refuses such a folder.
#
# Usage: scripts/memory_probe.sh [--out FILE] [--threads "1 2"] [--reps 5]
# About 2 minutes with the defaults on the 2-vCPU Emerald Rapids VM.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"

out="" threads="1 2" reps=5
probe_options "out threads reps" "$@"
probe_begin crumple_memory_probe memory
echo "# reps $reps; $(lscpu | sed -n 's/^L3 cache: *//p') L3" >> "$tmp"
for t in $threads; do
  probe_run "$t thread(s)" "$t" "$reps"
done
probe_end
