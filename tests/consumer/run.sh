#!/bin/sh
# Installs the build into a fresh prefix, builds tests/consumer against it with find_package(tightex),
# and runs it on a generated scan.
# Arguments: BUILD_DIR SOURCE_DIR MAKE_DEMO GENERATOR BUILD_TYPE CXX_FLAGS (the last may be empty).
set -eu
build=$1 src=$2 make_demo=$3 generator=$4 build_type=$5 flags=$6
work=$(pwd)/install_consumer
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/tests/consumer" -B "$work/build" -G "$generator" -DCMAKE_BUILD_TYPE="$build_type" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DTIGHTEX_EXAMPLE="$src/examples/optimize_obj.cpp" >/dev/null
cmake --build "$work/build" >/dev/null
"$make_demo" --segments 24 "$work/in" >/dev/null
"$work/build/consumer" "$work/in/vase.obj" "$work/out" | grep ' 0 flipped, 0 lost'
test -s "$work/out/vase_tightex.png"
