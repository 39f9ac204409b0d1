#!/usr/bin/env bash
# How tightex's default run grows with the input: a real scan (meshroom_esp32cam, 53k faces) subdivided
# 1:4 LEVEL times (tools/subdivide_obj.py: same surface, same texture), each run once with
# /usr/bin/time. Prints per size the process's wall, user and sys time and peak memory, each stage's
# wall time, the process's CPU time while it ran (user + sys, and sys) and peak memory from
# report.json, the surface PSNR and flipped count, and the log-log slope of wall and CPU time against
# faces between consecutive sizes and over all.
# Usage: bench/scale.sh [LEVELS="0 1 2"] [extra tightex options...]
#   LEVELS 3 (3.4M faces) and 4 (13.7M) take minutes to generate and to run.
# Subdivided copies are kept in ${TIGHTEX_SCALE_CACHE:-/tmp/tightex_scale}.
# TIGHTEX_SCALE_SOURCE=OBJ subdivides another model instead, e.g. the 10M-face row of BENCHMARKS.md:
#   ./build/tightex_make_demo --segments 600 /tmp/vase600    # 622k faces
#   TIGHTEX_SCALE_SOURCE=/tmp/vase600/vase.obj bench/scale.sh 2 --size 8192
set -euo pipefail
cd "$(dirname "$0")/.."
levels=${1:-0 1 2}; shift || true
bin=./build/tightex
src=${TIGHTEX_SCALE_SOURCE:-../shared/data/meshroom_esp32cam/texturedMesh.obj}
[ -f "$src" ] || { echo "no $src"; exit 0; }
cache=${TIGHTEX_SCALE_CACHE:-/tmp/tightex_scale}
name=$(basename "$src" .obj)
[ -z "${TIGHTEX_SCALE_SOURCE:-}" ] && name=esp32cam
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mkdir -p "$cache"
rows=()
for level in $levels; do
  obj=$src
  if [ "$level" != 0 ]; then
    obj=$cache/${name}_s$level/$(basename "$src")
    [ -f "$obj" ] || python3 tools/subdivide_obj.py "$src" "$cache/${name}_s$level" "$level"
  fi
  /usr/bin/time -f "%e %U %S %M" -o "$out/time" "$bin" "$obj" -o "$out/run" --quiet "$@"
  rows+=("$(python3 - "$out/run/report.json" "$(cat "$out/time")" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); m = r["metrics"]
wall, user, sys_, rss = map(float, sys.argv[2].split())
def stage(t):
    s = f"{t['stage'].split(' (')[0]} {t['seconds']:.2f}"
    if 'user_seconds' in t:
        s += f" [CPU {t['user_seconds'] + t['sys_seconds']:.2f}, sys {t['sys_seconds']:.2f}]"
    return s + (f" ({t['peak_rss_mib']:.0f} MiB)" if 'peak_rss_mib' in t else "")
stages = "; ".join(stage(t) for t in r["timings"])
print(f"{r['input']['triangles']}|{wall}|{user}|{sys_}|{rss / 1024:.0f}|{m['surface_psnr_db']:.2f}|{m['flipped']}|{stages}")
PY
)")
done
echo "| faces | wall s | user s | sys s | sys share | peak MiB | surface PSNR dB | flipped | stages: wall s [process CPU s while it ran, of it sys] (peak MiB) |"
echo "|---|---|---|---|---|---|---|---|---|"
for row in "${rows[@]}"; do
  IFS='|' read -r faces wall user sys rss psnr flipped stages <<<"$row"
  share=$(python3 -c "print(f'{100 * $sys / max($user + $sys, 1e-9):.0f}%')")
  echo "| $faces | $wall | $user | $sys | $share | $rss | $psnr | $flipped | $stages |"
done
python3 - "${rows[@]}" <<'PY'
import math, sys
pts = [tuple(map(float, r.split('|')[:4])) for r in sys.argv[1:]]
def slope(a, b, k):
    return math.log(b[k] / a[k]) / math.log(b[0] / a[0])
for a, b in zip(pts, pts[1:]):
    print(f"slope {a[0]:.0f} -> {b[0]:.0f} faces: wall {slope(a, b, 1):.2f}, CPU {math.log((b[2] + b[3]) / (a[2] + a[3])) / math.log(b[0] / a[0]):.2f}")
if len(pts) > 2:
    a, b = pts[0], pts[-1]
    print(f"slope {a[0]:.0f} -> {b[0]:.0f} faces: wall {slope(a, b, 1):.2f}, CPU {math.log((b[2] + b[3]) / (a[2] + a[3])) / math.log(b[0] / a[0]):.2f}")
PY
