#!/usr/bin/env bash
# Builds crumple's benchmark harness (Release: -O3 -march=native) into build-bench/, runs it on
# every core and writes, under results/<machine-tag>/ (e.g. results/amd-epyc-zen5_avx512/):
#   frame.json      Google Benchmark JSON (every repetition, plus aggregates)
#   run.json        the machine and how the run was made
#   REPORT.md       machine, command, table, largest sheet at 60/30 fps, charts
#   frame_time.png  frame time against vertex count; speedup.png; passes.png (if BM_Pass/ ran);
#                   roofline.png (the passes' GB/s against BM_Stream's measured bandwidth)
# and copies frame_time.png to results/frame_time.png (the README's chart).
#
# Usage: scripts/bench.sh [--quick] [--out DIR] [-- extra crumple_bench flags]
#   --quick   N <= 256 and fewer, shorter repetitions (6-22 minutes by machine: README); writes to
#             results/<machine-tag>/quick/ and leaves results/frame_time.png alone
#   --out DIR write the results there instead (results/frame_time.png is then not touched);
#             refused if DIR/run.json records another machine's run
# Environment: CRUMPLE_BENCH_BUILD (build folder, default build-bench), CRUMPLE_BENCH_REPS,
#   CRUMPLE_BENCH_MIN_TIME (seconds, a plain number) override the mode's defaults.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3  # the python3 first on PATH may lack matplotlib/scipy

quick=0
out=""
extra=()
while (($#)); do
  case "$1" in
    --quick) quick=1 ;;
    --out) out=$2; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

# shellcheck source=scripts/bench_build.sh
source "$root/scripts/bench_build.sh"
# The load average before this script's own build: Google Benchmark's "load average at start"
# is read after the two builds, whose compilers still weigh in the 1-minute average.
read -r load1 load5 load15 _ < /proc/loadavg
bench_setup
tag=$("$py" "$root/scripts/machine_info.py" --tag)
if ((quick)); then
  reps=${CRUMPLE_BENCH_REPS:-3}
  min_time=${CRUMPLE_BENCH_MIN_TIME:-0.2}
  # Every benchmark at N <= 256 (per-pass ones too), and the stream benchmarks, whose last
  # number is their arrays' MiB (128 or more: it may match no size above).
  filter='/(32|64|128|256)/|^BM_Stream/'
  dest=${out:-$root/results/$tag/quick}
else
  reps=${CRUMPLE_BENCH_REPS:-10}
  min_time=${CRUMPLE_BENCH_MIN_TIME:-0.5}
  filter='.'
  dest=${out:-$root/results/$tag}
fi
refuse_other_machine "$dest"  # before the builds
# What competes for the CPUs now (the load average still carries work that ended a minute ago):
# the busy and stolen shares of all CPUs' time over a few seconds, after the set-up's installs.
cpu_use=$("$py" "$root/scripts/machine_info.py" --cpu-use 3) || cpu_use='{}'  # a reading, not worth stopping for
echo "bench.sh: configuring and building crumple_bench (Release) in $build"
build_bench "$build" crumple_bench
bin=$build/bench/crumple_bench
# The same kernels without vectorization (CRUMPLE_DISABLE_SIMD): its fast backend is labelled
# fast-nosimd, so the report shows scalar -> SIMD -> two threads from one run.
nosimd_build=${build}-nosimd
echo "bench.sh: building the no-SIMD variant in $nosimd_build"
build_bench "$nosimd_build" crumple_bench -DCRUMPLE_DISABLE_SIMD=ON
nosimd_bin=$nosimd_build/bench/crumple_bench

mkdir -p "$dest"
json=$dest/frame.json

# Every core: the benchmarks set their own TBB thread limit (1 or 2); taskset only makes sure
# the process may use all of them. bench_cmd BINARY FILTER OUT_JSON fills the array `cmd`.
bench_cmd() {
  cmd=(taskset -c "0-$(($(nproc) - 1))" "$1"
       --benchmark_filter="$2"
       --benchmark_repetitions="$reps"
       --benchmark_enable_random_interleaving=true
       --benchmark_min_time="$min_time"
       --benchmark_out="$3" --benchmark_out_format=json
       "${extra[@]}")
}
bench_cmd "$bin" "$filter" "$json"
main_cmd=("${cmd[@]}")
echo "bench.sh: ${cmd[*]}"
start=$(date +%s)
"${cmd[@]}"
# The no-SIMD fast backend on one thread (its gain is a per-core question), N <= 512.
nosimd_json=$dest/nosimd.json
nosimd_sizes='32|64|128|256|512'
if ((quick)); then nosimd_sizes='32|64|128|256'; fi
bench_cmd "$nosimd_bin" "fast-nosimd/1/($nosimd_sizes)/" "$nosimd_json"
echo "bench.sh: ${cmd[*]}"
"${cmd[@]}"
"$py" - "$json" "$nosimd_json" <<'PY'
import json, sys
main, extra = sys.argv[1:]
a = json.load(open(main))
a["benchmarks"] += json.load(open(extra))["benchmarks"]
json.dump(a, open(main, "w"), indent=1)
PY
rm -f "$nosimd_json"
elapsed=$(($(date +%s) - start))

"$py" "$root/scripts/machine_info.py" --json > "$dest/machine.json"
"$py" - "$dest/run.json" "$dest/machine.json" "$elapsed" "$quick" "$reps" "$min_time" "$filter" \
      "$rev" "${main_cmd[*]}" "$load1 $load5 $load15" "$cpu_use" <<'PY'
import json, sys, datetime
out, machine, elapsed, quick, reps, min_time, flt, rev, cmd, load, cpu_use = sys.argv[1:]
with open(machine) as f:
    m = json.load(f)
json.dump({"machine": m, "mode": "quick" if quick == "1" else "full",
           "command": "scripts/bench.sh" + (" --quick" if quick == "1" else ""),
           "benchmark_command": cmd, "repetitions": int(reps), "min_time": float(min_time),
           "filter": flt, "random_interleaving": True, "git": rev, "seconds": int(elapsed),
           "load_before_build": [float(x) for x in load.split()],
           "cpu_use_before_build": json.loads(cpu_use or "{}"),
           "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds")},
          open(out, "w"), indent=2)
PY
rm -f "$dest/machine.json"

headline=()
if ((!quick)) && [ -z "$out" ]; then headline=(--headline "$root/results/frame_time.png"); fi
"$py" "$root/scripts/bench_report.py" "$json" --run "$dest/run.json" --out "$dest" "${headline[@]}"
echo "bench.sh: done in ${elapsed}s of benchmarking; results in ${dest#"$root"/}/"
