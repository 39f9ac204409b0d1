#!/usr/bin/env bash
# Proves that a change leaves tightex's output unchanged: builds the reference commit REF (default
# HEAD) in /tmp, runs its CLI and this tree's on the generated demo and every OBJ and GLB model in
# ../shared/data with the default map, --map harmonic and --map area, and compares every written file
# but report.json and report.html (which hold times) byte for byte.
#
#   bash scripts/same_output.sh [REF] [MODEL_FILTER]
#
# The reference's outputs are kept in /tmp/tightex-ref-REF and reused. Prints one line per run (same /
# DIFFERENT) and exits non-zero if any output differs or is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
ref=$(git rev-parse --short "${1:-HEAD}")
filter=${2:-}
ref_dir=/tmp/tightex-ref-$ref
work=build/same-output

generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
build_cli() {  # source dir, build dir
  if [ ! -f "$2/CMakeCache.txt" ]; then
    cmake -S "$1" -B "$2" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTIGHTEX_BUILD_TESTS=OFF \
      -DTIGHTEX_BUILD_BENCH=OFF -DTIGHTEX_BUILD_TOOLS=ON >/dev/null
  fi
  cmake --build "$2" --parallel "$(nproc)" --target tightex tightex_make_demo >/dev/null
}

bash scripts/setup.sh
if [ ! -d "$ref_dir/src" ]; then
  mkdir -p "$ref_dir/src"
  git archive "$ref" | tar -x -C "$ref_dir/src"
fi
build_cli "$ref_dir/src" "$ref_dir/build"
build_cli . build

mkdir -p "$ref_dir/demo" "$work"
[ -f "$ref_dir/demo/vase.obj" ] || "$ref_dir/build/tightex_make_demo" "$ref_dir/demo" >/dev/null
models=("$ref_dir/demo/vase.obj")
if [ -d ../shared/data ]; then
  while IFS= read -r m; do models+=("$m"); done < <(find ../shared/data -name '*.obj' -o -name '*.glb' | sort)
fi

hashes() { (cd "$1" 2>/dev/null && find . -type f ! -name report.json ! -name report.html | sort | xargs -r sha256sum); }
failed=0
for model in "${models[@]}"; do
  [ -n "$filter" ] && [[ "$model" != *"$filter"* ]] && continue
  name=$(basename "$(dirname "$model")")_$(basename "${model%.*}")
  for map in default harmonic area; do
    args=()
    [ "$map" != default ] && args=(--map "$map")
    ref_out="$ref_dir/out/$name/$map"
    if [ ! -f "$ref_out/.done" ]; then
      rm -rf "$ref_out"
      "$ref_dir/build/tightex" "$model" -o "$ref_out" "${args[@]}" --quiet >/dev/null 2>&1 || true
      touch "$ref_out/.done"
    fi
    out="$work/$name/$map"
    rm -rf "$out"
    ./build/tightex "$model" -o "$out" "${args[@]}" --quiet >/dev/null 2>&1 || true
    a=$(hashes "$ref_out" | grep -v '\.done$' || true)
    b=$(hashes "$out")
    if [ -n "$a" ] && [ "$a" = "$b" ]; then
      echo "same       $name --map $map ($(echo "$a" | wc -l) files)"
    else
      echo "DIFFERENT  $name --map $map"
      failed=1
    fi
  done
done
exit $failed
