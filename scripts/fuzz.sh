#!/usr/bin/env bash
# Fuzzes the OBJ reader and mesh validation (tests/fuzz/fuzz_obj.cpp) with libFuzzer for SECONDS.
# Usage: scripts/fuzz.sh SECONDS [build-dir]   (default build-dir: build-fuzz)
# Builds with clang 14 (-fsanitize=fuzzer,address,undefined; tinyobjloader compiled in, so its
# code is instrumented too), seeds from tests/fuzz/corpus and tests/data, keeps the growing
# corpus in <build-dir>/corpus, and writes findings to <build-dir>/findings (copy each one into
# tests/fuzz/crashes, named after what it found, once fixed). Limits: 10 s per input (a hang),
# 2048 MB resident (an allocation the input does not justify), inputs up to 64 KiB. Runs in
# libFuzzer's fork mode with timeouts recorded but not fatal: on a loaded machine a wall-clock
# timeout is often the machine, so re-time each timeout-* finding alone before calling it a hang.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:?usage: scripts/fuzz.sh SECONDS [build-dir]}
build=${2:-$root/build-fuzz}
"$root/scripts/install_deps.sh"
mkdir -p "$build/corpus" "$build/findings"
src=("$root/tests/fuzz/fuzz_obj.cpp" "$root/tests/fuzz/tinyobj_impl.cpp"
     "$root"/core/mesh/{grid,obj_io,validate}.cpp)
if [ ! -x "$build/fuzz_obj" ] || [ -n "$(find "${src[@]}" "$root"/core/mesh/*.h -newer "$build/fuzz_obj")" ]; then
  clang++-14 -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I"$root/core" "${src[@]}" -o "$build/fuzz_obj"
fi
cd "$build"
exec ./fuzz_obj -fork=1 -ignore_timeouts=1 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
  -artifact_prefix="$build/findings/" -print_final_stats=1 \
  corpus "$root/tests/fuzz/corpus" "$root/tests/data"
