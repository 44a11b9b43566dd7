#!/usr/bin/env bash
# A/B of two crumple_layout_probe binaries (bench/layout_probe.cpp) in continuous runs: cycles
# of A B B A (neither side always first), each run a process of its own after a pause, then per
# column of the probe's summary (mean frame, longest frame, each pass, warm) the medians and
# ranges of A and B and each cycle's ratio B / A (its two B runs over its two A runs).
# The pause matters on a VM whose kernel reports free memory to its host: a run that starts
# right after another finds the memory the last one freed still backed, one that starts after
# a few seconds meets memory the host has taken back, whose first touches cost 10-30x more
# (docs/PERFORMANCE.md, "The frame's serial time, and faulting ahead by huge pages").
#
# Usage: scripts/probe_ab.sh A_PROBE B_PROBE N THREADS [FRAMES=24] [CYCLES=4] [PAUSE=4]
# e.g. scripts/probe_ab.sh /tmp/probe_old /tmp/probe_new 256 2 24 4 4 (about 2 minutes).
# Copy the binaries out of the build folder first, so a rebuild cannot change one mid-run.
set -euo pipefail
if (($# < 4)); then
  echo "usage: scripts/probe_ab.sh A_PROBE B_PROBE N THREADS [FRAMES] [CYCLES] [PAUSE]" >&2
  exit 2
fi
a=$1 b=$2 n=$3 threads=$4 frames=${5:-24} cycles=${6:-4} pause=${7:-4}
for bin in "$a" "$b"; do
  [[ -x $bin ]] || { echo "probe_ab.sh: $bin is not an executable" >&2; exit 2; }
done
for v in "$n" "$threads" "$frames" "$cycles"; do
  [[ $v =~ ^[1-9][0-9]*$ ]] || { echo "probe_ab.sh: N, THREADS, FRAMES and CYCLES must be positive whole numbers" >&2; exit 2; }
done
[[ $pause =~ ^[0-9]+$ ]] || { echo "probe_ab.sh: PAUSE must be a whole number of seconds" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for c in $(seq "$cycles"); do
  for side in A B B A; do
    sleep "$pause"
    bin=$a
    [[ $side == B ]] && bin=$b
    echo "probe_ab.sh: cycle $c/$cycles, $side" >&2
    # The summary's header and its one row (one fraction, one round).
    "$bin" "$n" "$threads" "$frames" 1 0.25 | grep -A1 '^fraction' >> "$out/$side.$c" \
      || { echo "probe_ab.sh: $bin failed or printed no summary" >&2; exit 1; }
  done
done
/usr/bin/python3 - "$out" "$cycles" <<'EOF'
import statistics, sys
out, cycles = sys.argv[1], int(sys.argv[2])
def rows(side, c):  # the two runs of one side in cycle c, as {column: value}
    lines = open(f"{out}/{side}.{c}").read().split("\n")
    pairs = [(lines[k].split(), lines[k + 1].split()) for k in range(0, len(lines) - 1, 2) if lines[k].startswith("fraction")]
    return [dict(zip(h, map(float, v))) for h, v in pairs]
runs = {s: [rows(s, c) for c in range(1, cycles + 1)] for s in "AB"}
columns = [k for k in runs["A"][0][0] if k != "fraction"]
print("| column | A median (range) | B median (range) | cycle ratios B/A |")
print("|---|---:|---:|---|")
for k in columns:
    v = {s: [r[k] for cyc in runs[s] for r in cyc] for s in "AB"}
    ratios = []
    for ca, cb in zip(runs["A"], runs["B"]):
        sa, sb = sum(r[k] for r in ca), sum(r[k] for r in cb)
        ratios.append(f"{sb / sa:.2f}" if sa > 0 else "-")
    cell = lambda x: f"{statistics.median(x):.2f} ({min(x):.2f}-{max(x):.2f})"
    print(f"| {k} | {cell(v['A'])} | {cell(v['B'])} | {' '.join(ratios)} |")
EOF
