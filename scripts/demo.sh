#!/usr/bin/env bash
# The main job on a built-in default: generate a scan-like model (a vase with a fragmented atlas of
# ~400 charts, holes and a floating fragment), optimize its texture space, and show the report.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=${1:-demo_out}
mkdir -p "$out/input"
./build/tightex_make_demo "$out/input"
./build/tightex "$out/input/vase.obj" -o "$out/result" --size 2048 --verbose --preview "$out/before_after.png"
echo "input:  $out/input/vase.obj (+ vase_texture.png)"
echo "output: $out/result/vase.obj (+ vase_tightex.png); report: $out/result/report.json; picture: $out/before_after.png"
