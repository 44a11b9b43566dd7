#!/usr/bin/env bash
# The installed package as a user meets it (README.md, "Using crumple as a library"): installs
# the build into a fresh prefix, checks what was installed, builds examples/embed against it
# with CMake (find_package) and with pkg-config, runs both and the installed command.
# Usage: test_install.sh <build-dir> <source-dir> <work-dir> [extra compile and link flags]
set -euo pipefail
build=$1 src=$2 work=$3 flags=${4:-}
prefix=$work/prefix
rm -rf "$work" && mkdir -p "$work"

cmake --install "$build" --prefix "$prefix" > "$work/install.log"  # README: build, /tmp/crumple-prefix
for f in include/crumple/crumple.h include/crumple/model/params.h include/crumple/sim/manipulators.h \
         lib/cmake/crumple/crumpleConfig.cmake lib/cmake/crumple/crumpleConfigVersion.cmake \
         lib/cmake/crumple/crumpleTargets.cmake lib/pkgconfig/crumple.pc bin/crumple; do
  [[ -e $prefix/$f ]] || { echo "test_install: $f was not installed"; exit 1; }
done
ls "$prefix"/lib/libcrumple.* > /dev/null || { echo "test_install: no libcrumple in $prefix/lib"; exit 1; }
# The public headers stand alone: no Eigen, no oneTBB, no internal header.
if grep -nE '#include [<"](Eigen|oneapi|tbb|mesh/|fast/|reference/)' -r "$prefix/include/crumple"; then
  echo "test_install: an installed header includes a dependency or an internal header"; exit 1
fi
"$prefix/bin/crumple" --version

# CMake: the README's commands (sanitized builds add their flags).
extra=()
[[ -n $flags ]] && extra=(-DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags")
cd "$src"
cmake -S examples/embed -B "$work/build-embed" -DCMAKE_PREFIX_PATH="$prefix" "${extra[@]}" > "$work/configure.log"
cmake --build "$work/build-embed" > "$work/build.log"
# 30 frames (the example's own 300 take 64 steps each with the default configuration, minutes
# under the sanitizers): the test is that it builds and runs against the installed package.
"$work/build-embed/embed" 30

# pkg-config: the same program from crumple.pc's flags.
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
# shellcheck disable=SC2046,SC2086
g++ $flags "$src/examples/embed/main.cpp" -o "$work/embed-pc" $(pkg-config --cflags --libs --static crumple) \
    -Wl,-rpath,"$prefix/lib"
"$work/embed-pc" 30 > "$work/embed-pc.txt"
tail -n 1 "$work/embed-pc.txt"
