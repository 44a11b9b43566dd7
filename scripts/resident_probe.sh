#!/usr/bin/env bash
# What `--resident` costs and saves in a continuous run: builds crumple_resident_probe
# (bench/resident_probe.cpp; Release, -march=native) in build-bench/ and runs it for each N and
# thread count, plain and resident runs alternated within each round. Writes the probe's output,
# with the machine and revision, to results/<machine-tag>/resident.txt (or --out FILE).
#
# Usage: scripts/resident_probe.sh [--out FILE] [--sizes "256 512"] [--threads "2"]
#                                  [--from 60] [--to 120] [--rounds 5]
# About 5 minutes with the defaults on the 2-vCPU Emerald Rapids VM.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3  # the python3 first on PATH may lack what machine_info.py imports

out="" sizes="256 512" threads="2" from=60 to=120 rounds=5
while (($#)); do
  case "$1" in
    --out | --sizes | --threads | --from | --to | --rounds)
      (($# >= 2)) || { echo "resident_probe.sh: $1 needs a value" >&2; exit 2; }
      declare "${1#--}=$2"
      shift ;;
    -h | --help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "resident_probe.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"
bench_setup
build_bench "$build" crumple_resident_probe
probe=$build/bench/crumple_resident_probe

tag=$("$py" "$root/scripts/machine_info.py" --tag)
out=${out:-$root/results/$tag/resident.txt}
mkdir -p "$(dirname "$out")"
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
{
  echo "# scripts/resident_probe.sh at $rev, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# frames $from to $to timed, rounds $rounds"
} > "$tmp"
for n in $sizes; do
  for t in $threads; do
    echo "resident_probe.sh: N = $n, $t thread(s)" >&2
    "$probe" "$n" "$t" "$from" "$to" "$rounds" | tee -a "$tmp"
    echo >> "$tmp"
  done
done
mv "$tmp" "$out"
trap - EXIT
echo "resident_probe.sh: wrote $out" >&2
