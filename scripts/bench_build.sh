# Sourced by the scripts that build benchmark binaries (bench.sh, layout_probe.sh), after they
# set $root.

# bench_setup: installs what a fresh machine lacks, then sets `rev`, the revision measured (taken
# before a run writes its results, which are tracked files: a label taken afterwards would always
# read -dirty), and `build`, the build folder (CRUMPLE_BENCH_BUILD, default build-bench).
bench_setup() {
  "$root/scripts/install_deps.sh"
  rev=$(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)
  build=${CRUMPLE_BENCH_BUILD:-$root/build-bench}
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
