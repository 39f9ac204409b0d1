#!/usr/bin/env bash
# The corner rules (docs/corners.md) on every model in ../shared/data: for each --map and --corners, the
# docs/metrics.md figures of the tool's report (the same measure() as `tightex measure IN OUT`).
# Usage: bench/corners.sh [maps="area harmonic"] [rules="arcs turning"]
set -euo pipefail
cd "$(dirname "$0")/.."
maps=${1:-"area harmonic"}; rules=${2:-"arcs turning"}
bin=./build/tightex
data=../shared/data
[ -d "$data" ] || { echo "no $data"; exit 0; }
out=$(mktemp -d)
echo "| model | map | corners | comps | charts | flipped | lost | angle mean / P95 | density P5 / P95 | PSNR dB | seam in -> out |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for dir in "$data"/*/; do
  obj=$(ls "$dir"*.obj 2>/dev/null | head -1 || true); name=$(basename "$dir")
  [ -n "$obj" ] || continue  # a glTF-only model
  for map in $maps; do
    for rule in $rules; do
      nice "$bin" "$obj" -o "$out/$name" --quiet --map "$map" --corners "$rule"
      python3 - "$out/$name/report.json" "$name" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); m = r["metrics"]; o = r["options"]
a = m["angle_distortion"]; d = m["density_spread"]; s = m["seam_length"]
print(f"| {sys.argv[2]} | {o['map']} | {o['corners']} | {r['preparation']['components']} | {m['charts']} | {m['flipped']} | {m['lost_triangles']} "
      f"| {a['mean']:.2f} / {a['p95']:.1f} | {d['p5']:.2f} / {d['p95']:.2f} | {m['surface_psnr_db']:.2f} | {s['input']:.1f} -> {s['output']:.2f} |", flush=True)
PY
    done
  done
done
rm -rf "$out"
