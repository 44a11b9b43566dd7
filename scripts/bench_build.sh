# shellcheck shell=bash disable=SC2154  # sourced: the caller sets $root
# Sourced by the scripts that build benchmark binaries (bench.sh and the probes' scripts), after they
# set $root.

# bench_setup: installs what a fresh machine lacks, then sets `rev`, the revision measured (taken
# before a run writes its results, which are tracked files: a label taken afterwards would always
# read -dirty), and `build`, the build folder (CRUMPLE_BENCH_BUILD, default build-bench).
bench_setup() {
  "$root/scripts/install_deps.sh"
  rev=$(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)
  build=${CRUMPLE_BENCH_BUILD:-$root/build-bench}
}

# refuse_other_machine DIR: exits 2 with machine_info.py's one-line reason, in the calling
# script's name, when DIR/run.json records another machine's run: a results folder holds one
# machine's runs, and a VM's kind can change between sessions.
refuse_other_machine() {
  local problem
  problem=$(/usr/bin/python3 "$root/scripts/machine_info.py" --check-folder "$1" 2>&1) ||
    { echo "$(basename "$0"): ${problem#machine_info.py: }" >&2; exit 2; }
}

# build_bench DIR TARGET [CMAKE_ARGS...]: configures DIR as a Release build of $root with the
# benchmarks and without the tests (the configure log in DIR.cmake.log, shown if it fails) and
# builds TARGET on every core.
build_bench() {
  local dir=$1 target=$2
  shift 2
  cmake -S "$root" -B "$dir" -DCMAKE_BUILD_TYPE=Release -DCRUMPLE_BUILD_BENCH=ON \
        -DCRUMPLE_BUILD_TESTS=OFF "$@" > "$dir.cmake.log" 2>&1 || { cat "$dir.cmake.log"; exit 1; }
  cmake --build "$dir" -j "$(nproc)" --target "$target"
}

# The probes' scripts (layout_probe.sh, resident_probe.sh, memory_probe.sh) share their options'
# parsing and their output file.

# probe_options "NAME ..." ARGS...: sets the global variable NAME for each `--NAME VALUE` in
# ARGS whose NAME is listed; -h/--help prints the calling script's header comment (lines 2-9);
# anything else exits 2 naming it.
probe_options() {
  local names=" $1 " me
  me=$(basename "$0")
  shift
  while (($#)); do
    case "$1" in
      -h | --help) sed -n '2,9p' "$0"; exit 0 ;;
      *)
        [[ $1 == --* && $names == *" ${1#--} "* ]] || { echo "$me: unknown argument '$1' (see --help)" >&2; exit 2; }
        if (($# < 2)) || [[ $2 == --* ]]; then echo "$me: $1 needs a value" >&2; exit 2; fi
        declare -g "${1#--}=$2"
        shift ;;
    esac
    shift
  done
}

# probe_begin TARGET NAME: installs what a fresh machine lacks, refuses an `out` in another
# machine's results folder (machine_info.py --check-folder), builds TARGET in the bench build
# and sets `probe` (its path), `out` (results/<machine-tag>/NAME.txt unless already set) and
# `tmp`, the file the run collects into (removed on exit unless probe_end moves it), headed by
# the script, the revision, the time, the CPU, the load average (which still carries the build)
# and the CPUs' busy and stolen shares over the 3 s after the build (what competes now).
probe_begin() {
  bench_setup
  local tag use seconds=3
  tag=$(/usr/bin/python3 "$root/scripts/machine_info.py" --tag)  # the python3 first on PATH may lack its imports
  out=${out:-$root/results/$tag/$2.txt}
  refuse_other_machine "$(dirname "$out")"
  build_bench "$build" "$1"
  # shellcheck disable=SC2034  # read by the caller
  probe=$build/bench/$1
  use=$(/usr/bin/python3 "$root/scripts/machine_info.py" --cpu-use "$seconds") || use='{}'
  mkdir -p "$(dirname "$out")"
  tmp=$(mktemp)
  trap 'rm -f "$tmp"' EXIT
  {
    echo "# scripts/$(basename "$0") at $rev, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
    echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
    echo "# CPU time over the $seconds s before the run (/proc/stat; busy and stolen shares of all CPUs' time, {} if unread): $use"
  } > "$tmp"
}

# probe_run LABEL ARGS...: runs the probe with ARGS, its output shown and collected, LABEL on
# stderr first.
probe_run() {
  echo "$(basename "$0"): $1" >&2
  shift
  "$probe" "$@" | tee -a "$tmp"
  echo >> "$tmp"
}

# probe_end: moves the collected run to `out`.
probe_end() {
  mv "$tmp" "$out"
  trap - EXIT
  echo "$(basename "$0"): wrote $out" >&2
}
