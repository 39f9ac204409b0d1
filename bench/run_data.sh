#!/usr/bin/env bash
# End-to-end figures of the tightex CLI on every model in ../shared/data: wall time (median of N runs)
# and peak memory from /usr/bin/time, quality figures from the tool's report (docs/metrics.md).
# Usage: bench/run_data.sh [RUNS=3] [extra tightex options...]   (TIGHTEX_BIN: the binary, default build/tightex)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}; shift || true
bin=${TIGHTEX_BIN:-./build/tightex}
data=../shared/data
[ -d "$data" ] || { echo "no $data"; exit 0; }
out=$(mktemp -d)
printf "| model | triangles | size | in util | out util | charts | PSNR dB | density P5/P50/P95 | angle mean/P95 | detail loss | seam in->out | flipped | wall s (median of %s) | peak MiB |\n" "$runs"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for dir in "$data"/*/; do
  obj=$(ls "$dir"*.obj 2>/dev/null | head -1 || true); name=$(basename "$dir")
  [ -n "$obj" ] || continue  # a glTF-only model
  times=()
  for i in $(seq "$runs"); do
    /usr/bin/time -f "%e %M" -o "$out/time" "$bin" "$obj" -o "$out/$name" --quiet "$@"
    times+=("$(cat "$out/time")")
  done
  python3 - "$out/$name/report.json" "${times[@]}" <<'PY'
import json, sys, statistics
r = json.load(open(sys.argv[1])); m = r["metrics"]
t = [tuple(map(float, x.split())) for x in sys.argv[2:]]
wall = statistics.median(x[0] for x in t); mem = max(x[1] for x in t) / 1024
d = m["density_spread"]; a = m["angle_distortion"]
print(f"| {r['input']['file'].split('/')[-2]} | {r['input']['triangles']} | {r['options']['size']} | {m['input']['utilization']*100:.1f}% | {m['output']['utilization']*100:.2f}% | {m['charts']} | {m['surface_psnr_db']:.2f} | {d['p5']:.2f} / {d['p50']:.2f} / {d['p95']:.2f} | {a['mean']:.2f} / {a['p95']:.2f} | {m['detail_loss_area']*100:.1f}% | {m['seam_length']['input']:.1f} -> {m['seam_length']['output']:.1f} | {m['flipped']} | {wall:.2f} | {mem:.0f} |")
PY
done
rm -rf "$out"
