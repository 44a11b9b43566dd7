#!/usr/bin/env bash
# A/B of two crumple_bench binaries on a shared, noisy machine: runs them alternately for a
# number of rounds (A B, B A, A B ...: neither side always runs first), each round one run of
# the filter with repetitions, and prints per benchmark the round medians of A and B, the median
# of each, and the median of the paired ratios B/A (the two runs of one round share its load).
#
# Usage: scripts/ab.sh A_BINARY B_BINARY FILTER [ROUNDS=4] [REPETITIONS=3] [COUNTER]
# COUNTER: the user counter to compare (default: the benchmark's real time), e.g. us_per_event;
# several separated by commas give a table each from the same runs (real_time: the time itself),
# e.g. real_time,longest_ms.
# CRUMPLE_AB_PLACEMENT=1: before each round, A's binary measures how far apart the first two
# CPUs are (BM_CoreToCore's round trip), printed a round under the table: a VM's host may move
# its vCPUs between chips from one minute to the next, which changes two-thread timings
# (docs/PERFORMANCE.md), so rounds that disagree can be told apart.
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
placement=${CRUMPLE_AB_PLACEMENT:-0}
for r in $(seq "$rounds"); do
  if [[ $placement == 1 ]]; then
    "$a" --benchmark_filter='^BM_CoreToCore/' --benchmark_min_time=0.05 --benchmark_format=json \
      --benchmark_out="$out/trip$r.json" --benchmark_out_format=json > /dev/null \
      || { echo "ab.sh: BM_CoreToCore failed before round $r" >&2; exit 1; }
  fi
  order="A B"; ((r % 2)) || order="B A"
  for side in $order; do
    bin=$a; [[ $side == B ]] && bin=$b
    echo "ab.sh: round $r/$rounds, $side" >&2
    "$bin" --benchmark_filter="$filter" --benchmark_repetitions="$reps" --benchmark_report_aggregates_only=true \
      --benchmark_format=json --benchmark_out="$out/$side$r.json" --benchmark_out_format=json > /dev/null \
      || { echo "ab.sh: $bin failed in round $r" >&2; exit 1; }
  done
done
/usr/bin/python3 - "$out" "$rounds" "$counter" "$placement" <<'EOF'
import json, statistics, sys
out, rounds, counters, placement = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(","), sys.argv[4] == "1"
def medians(side, r, counter):
    path, rows = f"{out}/{side}{r}.json", {}
    try:
        benchmarks = json.load(open(path))["benchmarks"]
    except (OSError, ValueError, KeyError):  # no output: the filter matched nothing
        return rows
    for b in benchmarks:  # the median of the repetitions (one repetition: its only run)
        if b.get("error_occurred") or b.get("skipped"):
            sys.exit(f"ab.sh: {b['run_name']} did not run on {side} in round {r}: "
                     f"{b.get('error_message') or b.get('skip_message') or 'skipped'}")
        if b.get("aggregate_name") == "median" or (b.get("run_type") == "iteration" and b["run_name"] not in rows):
            if counter and counter not in b:
                sys.exit(f"ab.sh: {b['run_name']} has no counter {counter}")
            rows[b["run_name"]] = b[counter] if counter else b["real_time"]
    return rows
def table(counter):
    runs = {side: [medians(side, r, counter) for r in range(1, rounds + 1)] for side in "AB"}
    names = sorted(set().union(*runs["A"]) & set().union(*runs["B"]))
    if not names:
        sys.exit("ab.sh: the filter matched no benchmark in both binaries")
    print(f"| benchmark | A ({counter or 'real time'}) | B | median A | median B | median of B/A |")
    print("|---|---|---|---:|---:|---:|")
    for n in names:
        pairs = [(a[n], b[n]) for a, b in zip(runs["A"], runs["B"]) if n in a and n in b]  # by round
        A, B = [a for a, _ in pairs], [b for _, b in pairs]
        ratios = [b / a for a, b in pairs]
        fmt = lambda xs: " ".join(f"{x:.3g}" for x in xs)
        print(f"| {n} | {fmt(A)} | {fmt(B)} | {statistics.median(A):.3g} | {statistics.median(B):.3g} "
              f"| {statistics.median(ratios):.3f} |")
for k, counter in enumerate(counters):
    if k:
        print()
    table("" if counter == "real_time" else counter)
if placement:
    trips = []
    for r in range(1, rounds + 1):
        rows = [b for b in json.load(open(f"{out}/trip{r}.json")).get("benchmarks", []) if "ns_per_round_trip" in b]
        if not rows:
            sys.exit(f"ab.sh: BM_CoreToCore gave no round trip before round {r} (not in A's binary, or it could not pin two CPUs)")
        trips.append(rows[0]["ns_per_round_trip"])
    print("\nThe first two CPUs' round trip before each round (BM_CoreToCore, ns): " + " ".join(f"{t:.0f}" for t in trips))
EOF
