#!/usr/bin/env bash
# Bytes against surface PSNR (BENCHMARKS.md, "Bytes"): for each model, the input's texture bytes, the
# default run (the input's codec, no larger on disk for a lossy input), tightex --format webp at several
# --target-psnr, and the input's own textures re-encoded to WebP at several qualities without repacking
# (tools/reencode_curve.cpp, what gltf-transform or gltfpack would do: libwebp's plain RGB-to-YUV
# conversion, as Pillow and cwebp by default); tightex's bytes beside the re-encode's at the same
# written PSNR (its curve interpolated), and beside a re-encode by tightex's own encoder (the sharp
# conversion: what the repacking alone saves), and each --target-psnr run's wall time over that of
# `--format webp` at its default quality (the time the search adds) and over the default run's.
#
#   bash bench/bytes.sh [OUT] [MODEL...]    (default: every model of ../shared/data; a build with the tools)
#   TARGETS="40" QUALITIES="50 70 80 90 95" bash bench/bytes.sh ...   (other targets and re-encode qualities)
#   REPEATS=3 bash bench/bytes.sh ...   (the time ratio from the medians of 3 alternating runs of each)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/bytes-bench}
shift || true
models=("$@")
if [ ${#models[@]} -eq 0 ]; then
  for d in ../shared/data/*/; do
    m=$(ls "$d"*.obj "$d"*.glb 2>/dev/null | head -1 || true)
    [ -n "$m" ] && models+=("$m")
  done
fi
rm -rf "$out" && mkdir -p "$out"
read -r -a targets <<< "${TARGETS:-36 40 44}"
read -r -a qualities <<< "${QUALITIES:-1 5 10 20 35 50 70 80 90 95}"
echo "| model | input KiB | default: codec, KiB, written dB | webp --target-psnr: written dB, KiB, re-encode KiB at that dB, ratio (tightex's encoder's re-encode: ratio), time over --format webp's (over the default run's) | input re-encoded to WebP: quality dB KiB |"
echo "|---|---|---|---|---|"
for model in "${models[@]}"; do
  name=$(basename "$(dirname "$model")")
  ./build/tightex "$model" -o "$out/$name/default" -q --no-html
  ./build/tightex "$model" -o "$out/$name/webp" -q --no-html --format webp
  for t in "${targets[@]}"; do ./build/tightex "$model" -o "$out/$name/webp$t" -q --no-html --format webp --target-psnr "$t"; done
  # The times again, alternating, for medians (the runs of a few seconds vary by +-0.3x alone).
  for ((r = 2; r <= ${REPEATS:-1}; ++r)); do
    ./build/tightex "$model" -o "$out/$name/time$r/default" -q --no-html
    ./build/tightex "$model" -o "$out/$name/time$r/webp" -q --no-html --format webp
    for t in "${targets[@]}"; do ./build/tightex "$model" -o "$out/$name/time$r/webp$t" -q --no-html --format webp --target-psnr "$t"; done
  done
  ./build/tightex_reencode_curve "$model" webp-plain "${qualities[@]}" > "$out/$name/reencode.txt"
  ./build/tightex_reencode_curve "$model" webp "${qualities[@]}" > "$out/$name/reencode_own.txt"
  python3 - "$out/$name" "$name" "${targets[@]}" <<'PY'
import json, sys
folder, name, targets = sys.argv[1], sys.argv[2], sys.argv[3:]
def read_curve(file):  # (quality, bytes, dB) per line
    return sorted(tuple(float(x) for x in line.split()) for line in open(file))
curve, own_curve = read_curve(folder + "/reencode.txt"), read_curve(folder + "/reencode_own.txt")
def reencode_bytes_at(db, curve=curve):
    pts = sorted((p, b) for _, b, p in curve)
    for (p0, b0), (p1, b1) in zip(pts, pts[1:]):
        if p0 <= db <= p1:
            return b0 + (b1 - b0) * (db - p0) / (p1 - p0) if p1 > p0 else b1
    return None
import glob, statistics
d = json.load(open(folder + "/default/report.json"))["bytes"]
def median_wall(run):  # the first run's and every repeat's
    return statistics.median(json.load(open(f))["wall_seconds"] for f in [f"{folder}/{run}/report.json"] + glob.glob(f"{folder}/time*/{run}/report.json"))
base_s, default_s = median_wall("webp"), median_wall("default")
cells = []
for t in targets:
    r = json.load(open(f"{folder}/webp{t}/report.json"))
    b = r["bytes"]
    db, out = b["surface_psnr_written_db"], b["output"]["total"]
    ref, own = reencode_bytes_at(db), reencode_bytes_at(db, own_curve)
    cells.append(f"{t}: {db:.2f}, {out/1024:.0f}, " + (f"{ref/1024:.0f}, {out/ref:.2f}" if ref else "beyond the curve") +
                 (f" ({out/own:.2f})" if own else " (beyond)") +
                 f", {median_wall('webp' + t) / base_s:.2f}x ({median_wall('webp' + t) / default_s:.2f}x)")
kib = lambda x: f"{x/1024:.0f}"
print(f"| {name} | {kib(d['input']['total'])} | {d['encoding']['format']} q{d['encoding'].get('quality', '-')}, {kib(d['output']['total'])}, "
      f"{d['surface_psnr_written_db']:.1f} | {'; '.join(cells)} | " + "; ".join(f"{q:.0f}: {p:.1f} {b/1024:.0f}" for q, b, p in curve) + " |")
PY
done
