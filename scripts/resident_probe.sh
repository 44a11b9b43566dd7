#!/usr/bin/env bash
# What `--resident` costs and saves in a continuous run: builds crumple_resident_probe
# (bench/resident_probe.cpp; Release, -march=native) in build-bench/ and runs it for each N and
# thread count, plain and resident runs alternated within each round. Writes the probe's output,
# with the machine and revision, to results/<machine-tag>/resident.txt (or --out FILE).
# An --out FILE in a folder whose run.json records another machine is refused before the build
# (exit 2), as scripts/bench.sh refuses such a folder.
#
# Usage: scripts/resident_probe.sh [--out FILE] [--sizes "256 512"] [--threads "2"]
#                                  [--from 60] [--to 120] [--rounds 5]
# About 5 minutes with the defaults on the 2-vCPU Emerald Rapids VM.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"

out="" sizes="256 512" threads="2" from=60 to=120 rounds=5
probe_options "out sizes threads from to rounds" "$@"
probe_begin crumple_resident_probe resident
echo "# frames $from to $to timed, rounds $rounds" >> "$tmp"
for n in $sizes; do
  for t in $threads; do
    probe_run "N = $n, $t thread(s)" "$n" "$t" "$from" "$to" "$rounds"
  done
done
probe_end
