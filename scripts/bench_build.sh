# Sourced by the scripts that build benchmark binaries (bench.sh, layout_probe.sh).
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
