#!/usr/bin/env bash
# Tile sets on Dask (python3 -m tightex.tiles): wall time and tiles per minute of a generated folder of
# tiles with 1 and with 2 LocalCluster workers (one thread each), and the scaling efficiency
# (speed-up / workers). Tiles: tools/make_boxes.py, COUNT boxes each (COUNT components, one 512^2 texture).
# The wall time includes starting the cluster (a few seconds).
# Usage: bench/tiles.sh [TILES=16] [COUNT=300]   (needs the module built: build/python)
set -euo pipefail
cd "$(dirname "$0")/.."
tiles=${1:-24}; count=${2:-1500}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for i in $(seq 1 "$tiles"); do /usr/bin/python3 tools/make_boxes.py "$count" "$work/in/t$i" --seed "$i" >/dev/null; done
PYTHONPATH=build/python /usr/bin/python3 - "$work" <<'PY'
import json, subprocess, sys, time
work = sys.argv[1]
wall, span = {}, {}
for workers in (1, 2):
    start = time.monotonic()
    subprocess.run([sys.executable, "-m", "tightex.tiles", f"{work}/in", f"{work}/out{workers}", "--workers", str(workers),
                    "--threads-per-worker", "1"], stderr=subprocess.DEVNULL)
    wall[workers] = time.monotonic() - start
    s = json.load(open(f"{work}/out{workers}/summary.json"))
    per_tile = sum(r["seconds"] for r in s["per_tile"]) / max(1, s["done"])
    span[workers] = max(r["finished"] for r in s["per_tile"]) - min(r["started"] for r in s["per_tile"])
    print(f"{workers} worker(s): {s['done']} tiles done, {s['failed']} failed, wall {wall[workers]:.1f} s "
          f"({60 * s['done'] / wall[workers]:.1f} tiles/min), tiles {span[workers]:.1f} s "
          f"({60 * s['done'] / span[workers]:.1f} tiles/min), {per_tile:.2f} s per tile in the worker")
print(f"scaling efficiency 1 -> 2 workers: {wall[1] / wall[2] / 2:.2f} (wall), {span[1] / span[2] / 2:.2f} (tiles)")
PY
