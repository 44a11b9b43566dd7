#!/usr/bin/env bash
# The crumple statistics of two crumple binaries, as scripts/ab.sh compares their speed: runs
# `crumple run ARGS --seed S` with both for seeds 1..SEEDS (each seed's two runs side by side)
# and prints, per statistic, each binary's seed mean and spread, their difference and that
# difference in standard errors (Welch). For a change that alters the bits but must not alter
# the crumple: differences within about two standard errors are seed noise.
# Statistics: total splits and restores over the run (stats.csv's per-frame counts summed) and
# the final vertex count.
#
# Usage: scripts/ab_stats.sh A_BINARY B_BINARY SEEDS -- RUN_ARGS...
# e.g.   scripts/ab_stats.sh /tmp/crumple_old build/app/crumple 8 -- --grid 64 --paper
set -euo pipefail
if (($# < 4)) || [[ $4 != -- ]]; then
  echo "usage: scripts/ab_stats.sh A_BINARY B_BINARY SEEDS -- RUN_ARGS..." >&2
  exit 2
fi
a=$1 b=$2 seeds=$3
shift 4
for bin in "$a" "$b"; do
  [[ -x $bin ]] || { echo "ab_stats.sh: $bin is not an executable" >&2; exit 2; }
done
[[ $seeds =~ ^[0-9]+$ ]] && ((seeds >= 2)) || { echo "ab_stats.sh: SEEDS must be an integer >= 2" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for s in $(seq "$seeds"); do
  [[ -t 2 ]] && echo "ab_stats.sh: seed $s/$seeds" >&2
  "$a" run "$@" --seed "$s" --out "$out/a$s" --quiet &
  pid=$!
  "$b" run "$@" --seed "$s" --out "$out/b$s" --quiet || { echo "ab_stats.sh: $b failed on seed $s" >&2; exit 1; }
  wait "$pid" || { echo "ab_stats.sh: $a failed on seed $s" >&2; exit 1; }
done
/usr/bin/python3 - "$out" "$seeds" <<'PY'
import csv, statistics, sys
out, seeds = sys.argv[1], int(sys.argv[2])
def stat(side, seed, col):
    rows = list(csv.DictReader(open(f'{out}/{side}{seed}/stats.csv')))
    return float(rows[-1][col]) if col == 'vertices' else sum(float(r[col]) for r in rows)
print('| statistic | A mean +- sd | B mean +- sd | B - A | in standard errors |')
print('|---|---:|---:|---:|---:|')
for col in ['splits', 'restores', 'vertices']:
    a = [stat('a', s, col) for s in range(1, seeds + 1)]
    b = [stat('b', s, col) for s in range(1, seeds + 1)]
    ma, mb, sa, sb = statistics.mean(a), statistics.mean(b), statistics.stdev(a), statistics.stdev(b)
    se = ((sa * sa + sb * sb) / seeds) ** 0.5
    z = (mb - ma) / se if se > 0 else 0.0
    print(f'| {col} | {ma:.1f} +- {sa:.1f} | {mb:.1f} +- {sb:.1f} | {100 * (mb - ma) / ma:+.2f} % | {z:+.2f} |')
PY
