#!/usr/bin/env bash
# A/B of two crumple_bench binaries on a shared, noisy machine: runs them alternately for a
# number of rounds (A, B, A, B ...), each round one run of the filter with repetitions, and
# prints per benchmark the round medians of A and B, the median of each, and the median of the
# paired ratios B/A (the ratio of the two runs of one round, which share that round's load).
#
# Usage: scripts/ab.sh A_BINARY B_BINARY FILTER [ROUNDS=4] [REPETITIONS=3] [COUNTER]
# COUNTER: the user counter to compare (default: the benchmark's real time), e.g. us_per_event.
# Copy the binaries out of the build folder first, so a rebuild cannot change one mid-run.
set -euo pipefail
if (($# < 3)); then
  echo "usage: scripts/ab.sh A_BINARY B_BINARY FILTER [ROUNDS] [REPETITIONS] [COUNTER]" >&2
  exit 2
fi
a=$1 b=$2 filter=$3 rounds=${4:-4} reps=${5:-3} counter=${6:-}
for bin in "$a" "$b"; do
  [[ -x $bin ]] || { echo "ab.sh: $bin is not an executable" >&2; exit 2; }
done
[[ $rounds =~ ^[1-9][0-9]*$ && $reps =~ ^[1-9][0-9]*$ ]] || { echo "ab.sh: ROUNDS and REPETITIONS must be positive integers" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for r in $(seq "$rounds"); do
  for side in A B; do
    bin=$a; [[ $side == B ]] && bin=$b
    echo "ab.sh: round $r/$rounds, $side" >&2
    "$bin" --benchmark_filter="$filter" --benchmark_repetitions="$reps" --benchmark_report_aggregates_only=true \
      --benchmark_format=json --benchmark_out="$out/$side$r.json" --benchmark_out_format=json > /dev/null \
      || { echo "ab.sh: $bin failed in round $r" >&2; exit 1; }
  done
done
/usr/bin/python3 - "$out" "$rounds" "$counter" <<'EOF'
import json, statistics, sys
out, rounds, counter = sys.argv[1], int(sys.argv[2]), sys.argv[3]
def medians(path):
    rows = {}
    try:
        benchmarks = json.load(open(path))["benchmarks"]
    except (OSError, ValueError, KeyError):  # no output: the filter matched nothing
        return rows
    for b in benchmarks:  # the median of the repetitions (one repetition: its only run)
        if b.get("aggregate_name") == "median" or b.get("run_type") == "iteration" and b["run_name"] not in rows:
            if counter not in b and counter:
                sys.exit(f"ab.sh: {b['run_name']} has no counter {counter}")
            rows[b["run_name"]] = b[counter] if counter else b["real_time"]
    return rows
runs = {side: [medians(f"{out}/{side}{r}.json") for r in range(1, rounds + 1)] for side in "AB"}
names = sorted(set().union(*runs["A"]) & set().union(*runs["B"]))
if not names:
    sys.exit("ab.sh: the filter matched no benchmark in both binaries")
unit = counter or "real time"
print(f"| benchmark | A ({unit}) | B | median A | median B | median of B/A |")
print("|---|---|---|---:|---:|---:|")
for n in names:
    A = [r[n] for r in runs["A"] if n in r]
    B = [r[n] for r in runs["B"] if n in r]
    ratios = [y / x for x, y in zip(A, B)]
    fmt = lambda xs: " ".join(f"{x:.3g}" for x in xs)
    print(f"| {n} | {fmt(A)} | {fmt(B)} | {statistics.median(A):.3g} | {statistics.median(B):.3g} "
          f"| {statistics.median(ratios):.3f} |")
EOF
