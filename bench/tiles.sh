#!/usr/bin/env bash
# Tile sets on Dask (python3 -m tightex.tiles): wall time and tiles per minute of a generated folder of
# tiles with 1 and with 2 LocalCluster workers of one core each (--tile-threads 1), the scaling
# efficiency (speed-up / workers), and 1 worker using both cores (--tile-threads 2) for comparison. Tiles: tools/make_boxes.py, COUNT boxes each (COUNT components, one 512^2 texture).
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
# (workers, tightex threads a worker): one core a worker, then one worker with every core.
for workers, threads in ((1, 1), (2, 1), (1, 2)):
    key = (workers, threads)
    out = f"{work}/out{workers}x{threads}"
    start = time.monotonic()
    subprocess.run([sys.executable, "-m", "tightex.tiles", f"{work}/in", out, "--workers", str(workers), "--threads-per-worker", "1",
                    "--tile-threads", str(threads)], stderr=subprocess.DEVNULL)
    wall[key] = time.monotonic() - start
    s = json.load(open(f"{out}/summary.json"))
    per_tile = sum(r["seconds"] for r in s["per_tile"]) / max(1, s["done"])
    span[key] = max(r["finished"] for r in s["per_tile"]) - min(r["started"] for r in s["per_tile"])
    print(f"{workers} worker(s), {threads} thread(s) each: {s['done']} tiles done, {s['failed']} failed, wall {wall[key]:.1f} s "
          f"({60 * s['done'] / wall[key]:.1f} tiles/min), tiles {span[key]:.1f} s "
          f"({60 * s['done'] / span[key]:.1f} tiles/min), {per_tile:.2f} s per tile in the worker")
print(f"scaling efficiency 1 -> 2 workers, one core each: {wall[1, 1] / wall[2, 1] / 2:.2f} (wall), {span[1, 1] / span[2, 1] / 2:.2f} (tiles)")
print(f"2 single-core workers against 1 worker on both cores: {wall[1, 2] / wall[2, 1]:.2f}x (wall), {span[1, 2] / span[2, 1]:.2f}x (tiles)")
PY
