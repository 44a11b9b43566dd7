#!/usr/bin/env bash
# What the fast backend's layout fraction costs and saves: builds crumple_layout_probe
# (bench/layout_probe.cpp; Release, -march=native) in build-bench/ and runs it for each N and
# thread count, every fraction interleaved within each round. Writes the probe's output, with
# the machine and revision, to results/<machine-tag>/layout_fraction.txt (or --out FILE).
# An --out FILE in a folder whose run.json records another machine is refused before the build
# (exit 2), as scripts/bench.sh refuses such a folder.
#
# Usage: scripts/layout_probe.sh [--out FILE] [--sizes "128 256 512"] [--threads "1 2"]
#                                [--frames 52] [--rounds 3] [--fractions "0.25 0.15 0.1 0.06"]
# Took 10 minutes with the defaults on the 2-vCPU Intel VM.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"

out="" sizes="128 256 512" threads="1 2" frames=52 rounds=3 fractions="0.25 0.15 0.1 0.06"
probe_options "out sizes threads frames rounds fractions" "$@"
probe_begin crumple_layout_probe layout_fraction
echo "# frames $frames, rounds $rounds, fractions $fractions" >> "$tmp"
for n in $sizes; do
  for t in $threads; do
    # shellcheck disable=SC2086  # the fractions are separate arguments
    probe_run "N = $n, $t thread(s)" "$n" "$t" "$frames" "$rounds" $fractions
  done
done
probe_end
