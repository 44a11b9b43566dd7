#!/usr/bin/env bash
# What the fast backend's layout fraction costs and saves: builds crumple_layout_probe
# (bench/layout_probe.cpp; Release, -march=native) in build-bench/ and runs it for each N and
# thread count, every fraction interleaved within each round. Writes the probe's output, with
# the machine and revision, to results/<machine-tag>/layout_fraction.txt (or --out FILE).
#
# Usage: scripts/layout_probe.sh [--out FILE] [--sizes "128 256 512"] [--threads "1 2"]
#                                [--frames 52] [--rounds 3] [--fractions "0.25 0.15 0.1 0.06"]
# Took 10 minutes with the defaults on the 2-vCPU Intel VM.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3  # the python3 first on PATH may lack what machine_info.py imports

out="" sizes="128 256 512" threads="1 2" frames=52 rounds=3 fractions="0.25 0.15 0.1 0.06"
while (($#)); do
  case "$1" in
    --out | --sizes | --threads | --frames | --rounds | --fractions)
      (($# >= 2)) || { echo "layout_probe.sh: $1 needs a value" >&2; exit 2; }
      declare "${1#--}=$2"
      shift ;;
    -h | --help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "layout_probe.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"
bench_setup
build_bench "$build" crumple_layout_probe
probe=$build/bench/crumple_layout_probe

tag=$("$py" "$root/scripts/machine_info.py" --tag)
out=${out:-$root/results/$tag/layout_fraction.txt}
mkdir -p "$(dirname "$out")"
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
{
  echo "# scripts/layout_probe.sh at $rev, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# frames $frames, rounds $rounds, fractions $fractions"
} > "$tmp"
for n in $sizes; do
  for t in $threads; do
    echo "layout_probe.sh: N = $n, $t thread(s)" >&2
    # shellcheck disable=SC2086  # the fractions are separate arguments
    "$probe" "$n" "$t" "$frames" "$rounds" $fractions | tee -a "$tmp"
    echo >> "$tmp"
  done
done
mv "$tmp" "$out"
trap - EXIT
echo "layout_probe.sh: wrote $out" >&2
