#!/usr/bin/env bash
# The performance regression gate: is HEAD_REV slower than BASE_REV?
#
# Usage: scripts/gate.sh BASE_REV [HEAD_REV] [--threshold 5] [--reps 9] [--rounds 3]
#                        [--filter REGEX] [--max-n 256] [--min-time 0.2] [--same-harness]
#                        [--out DIR] [--keep]
#   BASE_REV, HEAD_REV  any git revisions (HEAD_REV defaults to HEAD); each is checked out with
#                       `git worktree` into a temporary folder and built (Release, -O3
#                       -march=native) in its own build folder
#   --threshold P       fail when a median is more than P per cent slower (default 5) ...
#                       ... and the Mann-Whitney U test gives p < 0.05 (--alpha A to change)
#   --reps R            repetitions per side in all (default 9; compare.py wants >= 9)
#   --rounds K          split them over K alternated whole runs per side (default 3: runs go
#                       base, head, head, base, base, head, each with ceil(R/K) repetitions)
#   --filter REGEX      Google Benchmark filter (POSIX ERE). Default: every BM_Frame benchmark
#                       of the crumple backends (not the Bullet peer) with N <= --max-n (256;
#                       each run prepares every benchmark's crumple anew, ~10 s at 256, ~75 s
#                       at 512 on 2 cores, so larger sheets make the gate much longer)
#   --min-time S        seconds of timed frames per repetition (default 0.2)
#   --same-harness      build both revisions with this checkout's bench/ (compares core code
#                       only); a revision without bench/ always gets this checkout's bench/
#   --out DIR           keep base.json, head.json (merged runs) and compare.json there
#   --keep              keep the temporary folder (worktrees, builds, every run's JSON)
# Exit status: 0 pass, 1 regression (or a benchmark that errors only in the head), 2 usage or
# build problems.
#
# Why alternated whole runs: on a shared or virtual machine the speed drifts (other tenants,
# frequency, caches); alternating base/head runs spreads that drift over both sides instead of
# giving it all to whichever side ran second, and each run is a fresh process (fresh heap
# layout, fresh preparation), so the repetitions include the run-to-run variance that one long
# run would hide, which keeps the U test honest. Within a run, random interleaving spreads the
# drift over the benchmarks.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3
compare=/usr/share/benchmark/compare.py

usage() { sed -n '2,25p' "$0"; exit 2; }
revs=()
threshold=5 alpha=0.05 reps=9 rounds=3 filter="" max_n=256 min_time=0.2 same=0 out="" keep=0
while (($#)); do
  case "$1" in
    --threshold) threshold=$2; shift ;;
    --alpha) alpha=$2; shift ;;
    --reps) reps=$2; shift ;;
    --rounds) rounds=$2; shift ;;
    --filter) filter=$2; shift ;;
    --max-n) max_n=$2; shift ;;
    --min-time) min_time=$2; shift ;;
    --same-harness) same=1 ;;
    --out) out=$2; shift ;;
    --keep) keep=1 ;;
    -h|--help) usage ;;
    -*) echo "gate.sh: unknown option '$1'" >&2; usage ;;
    *) revs+=("$1") ;;
  esac
  shift
done
((${#revs[@]} >= 1 && ${#revs[@]} <= 2)) || usage
((rounds >= 1 && reps >= 1)) || usage
per_run=$(((reps + rounds - 1) / rounds))

"$root/scripts/install_deps.sh"

base_sha=$(git -C "$root" rev-parse --verify "${revs[0]}^{commit}")
head_sha=$(git -C "$root" rev-parse --verify "${revs[1]:-HEAD}^{commit}")
echo "gate: base ${revs[0]} = ${base_sha:0:12}, head ${revs[1]:-HEAD} = ${head_sha:0:12}"

work=$(mktemp -d "${TMPDIR:-/tmp}/crumple-gate.XXXXXX")
cleanup() {
  for wt in "$work"/src-*; do
    [ -d "$wt" ] && git -C "$root" worktree remove --force "$wt" >/dev/null 2>&1 || true
  done
  git -C "$root" worktree prune >/dev/null 2>&1 || true
  if ((keep)); then echo "gate: kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT

build_rev() {  # build_rev SHA SIDE -> $work/build-SIDE/bench/crumple_bench
  local sha=$1 side=$2 src=$work/src-$2 build=$work/build-$2
  git -C "$root" worktree add --detach --quiet "$src" "$sha"
  if ((same)) || [ ! -f "$src/bench/CMakeLists.txt" ]; then
    [ -f "$src/bench/CMakeLists.txt" ] || echo "gate: $side (${sha:0:12}) has no bench/; using this checkout's bench/"
    rm -rf "$src/bench"
    cp -r "$root/bench" "$src/bench"
  fi
  echo "gate: building $side (${sha:0:12}) in $build"
  if ! { cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCRUMPLE_BUILD_TESTS=OFF -DCRUMPLE_BUILD_BENCH=ON &&
         cmake --build "$build" -j "$(nproc)" --target crumple_bench; } > "$work/build-$side.log" 2>&1; then
    tail -30 "$work/build-$side.log"
    echo "gate: the $side revision does not build (log: $work/build-$side.log)" >&2
    keep=1
    exit 2
  fi
}

build_rev "$base_sha" base
bin_base=$work/build-base/bench/crumple_bench
if [ "$head_sha" = "$base_sha" ] && ((!same)); then
  echo "gate: head is the base revision: one build serves both sides (an A/A comparison)"
  bin_head=$bin_base
else
  build_rev "$head_sha" head
  bin_head=$work/build-head/bench/crumple_bench
fi

if [ -z "$filter" ]; then
  # Every crumple frame benchmark the head has with N <= max_n, as an explicit list (the
  # benchmark library's POSIX regex has no negative look-ahead to leave the Bullet peer out).
  names=$("$bin_head" --benchmark_list_tests | grep '^BM_Frame/' | grep -v '^BM_Frame/bullet/' |
          awk -F/ -v m="$max_n" '$4 + 0 <= m + 0') || true
  [ -n "$names" ] || { echo "gate: no frame benchmark to run" >&2; exit 2; }
  filter="^($(echo "$names" | paste -sd'|'))\$"
  echo "gate: benchmarks: $(echo "$names" | sed 's|/manual_time||' | paste -sd' ')"
fi

run_side() {  # run_side SIDE ROUND
  local side=$1 r=$2 bin
  [ "$side" = base ] && bin=$bin_base || bin=$bin_head
  echo "gate: round $r/$rounds: $side, $per_run repetitions"
  taskset -c "0-$(($(nproc) - 1))" "$bin" --benchmark_filter="$filter" \
    --benchmark_repetitions="$per_run" --benchmark_enable_random_interleaving=true \
    --benchmark_min_time="$min_time" --benchmark_display_aggregates_only=true \
    --benchmark_out="$work/$side-$r.json" --benchmark_out_format=json 2>&1 |
    grep -E '_median|ERROR' || true
  if [ ! -s "$work/$side-$r.json" ]; then
    echo "gate: the $side benchmark run $r wrote no JSON (crashed?)" >&2
    keep=1
    exit 2
  fi
}

start=$(date +%s)
for ((r = 1; r <= rounds; r++)); do
  if ((r % 2)); then run_side base "$r"; run_side head "$r"; else run_side head "$r"; run_side base "$r"; fi
done
echo "gate: measured in $(($(date +%s) - start)) s"

"$py" "$root/scripts/gate.py" merge "$work/base.json" "$work"/base-*.json
"$py" "$root/scripts/gate.py" merge "$work/head.json" "$work"/head-*.json
echo "gate: compare.py (U test over $((per_run * rounds)) repetitions per side):"
"$py" "$compare" -a --no-color --dump_to_json "$work/compare.json" benchmarks "$work/base.json" "$work/head.json"
if [ -n "$out" ]; then
  mkdir -p "$out"
  cp "$work/base.json" "$work/head.json" "$work/compare.json" "$out/"
fi
echo
set +e
"$py" "$root/scripts/gate.py" check "$work/compare.json" --base "$work/base.json" --head "$work/head.json" \
  --threshold "$threshold" --alpha "$alpha"
status=$?
set -e
exit $status
