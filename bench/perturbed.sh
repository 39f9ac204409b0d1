#!/usr/bin/env bash
# Robustness sweep: every model in ../shared/data made messy as unseen scans come (tools/perturb_obj.py:
# pepper, patches, noise, flip), each through every --map; one line per run with the docs/metrics.md figures
# that must hold (flipped 0, charts = components, utilization) and the ones that measure quality.
# Usage: [MAPS="detail area"] [MODES="pepper noise"] [TIGHTEX=binary] bench/perturbed.sh [SEED=7] [extra tightex options...]
# (MAPS: all four by default; MODES: all four perturbations by default)
set -euo pipefail
cd "$(dirname "$0")/.."
seed=${1:-7}; shift || true
bin=${TIGHTEX:-./build/tightex}  # TIGHTEX=path: another build (a before/after pair)
data=../shared/data
[ -d "$data" ] || { echo "no $data"; exit 0; }
out=$(mktemp -d)
echo "| model | perturbation | map | PSNR dB | flipped | density P5 / P95 | utilization | charts | reoriented | holes capped / opened |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for dir in "$data"/*/; do
  obj=$(ls "$dir"*.obj 2>/dev/null | head -1 || true); name=$(basename "$dir")
  [ -n "$obj" ] || continue  # a glTF-only model
  for mode in ${MODES:-pepper patches noise flip}; do
    python3 tools/perturb_obj.py "$obj" "$out/in_$name.$mode" "$mode" "$seed"
    for map in ${MAPS:-detail texel area harmonic}; do
      o="$out/$name.$mode.$map"
      if ! "$bin" "$out/in_$name.$mode/$(basename "$obj")" -o "$o" --quiet --map "$map" "$@" > "$o.log" 2>&1; then
        echo "| $name | $mode | $map | FAILED: $(head -c 200 "$o.log" | tr '\n' ' ') |"; continue
      fi
      python3 - "$o/report.json" "$name" "$mode" "$map" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); m = r["metrics"]; d = m["density_spread"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {m['surface_psnr_db']:.2f} | {m['flipped']} | {d['p5']:.2f} / {d['p95']:.2f} | "
      f"{m['output']['utilization']*100:.2f}% | {m['charts']} | {r['preparation']['reoriented_triangles']} | "
      f"{r['preparation']['holes_filled']} / {r['preparation']['holes_cut']} |")
PY
    done
  done
done
rm -rf "$out"
