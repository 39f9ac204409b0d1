#!/usr/bin/env bash
# texture-defrag (Maggiordomo, Cignoni, Tarini 2021; github.com/maggio-a/texture-defrag) and tightex on
# the same inputs, one after the other in one run: wall, user and sys time and peak memory of each whole
# process (median of N runs, /usr/bin/time), then `tightex measure INPUT OUTPUT` on both outputs
# (docs/metrics.md: output texels, surface PSNR, lost and flipped triangles), as a markdown table with the
# ratios texture-defrag / tightex.
#
# Usage:
#   bench/peers.sh [--runs N] [MODEL.obj ...]   time both tools (default N = 3; default models:
#                                               ../shared/data meshroom_esp32cam and fuze, and
#                                               meshroom_esp32cam subdivided PEERS_SUBDIVIDE times (default
#                                               2, 854k faces) when tools/subdivide_obj.py exists)
#   bench/peers.sh --build [SOURCE_DIR]         build texture-defrag from a copy of its source
#
# texture-defrag is a benchmark-only dependency: scripts/setup.sh does not install it and tightex never
# uses it. To build it (Debian 12; it bundles vcglib and Eigen, and needs Qt5, GLU and, to run, an X
# display for its OpenGL render of the new texture: Xvfb with Mesa's software OpenGL does):
#   apt-get install qtbase5-dev qt5-qmake libqt5svg5-dev libqt5opengl5-dev libglu1-mesa-dev \
#                   libgl1-mesa-dri xvfb xauth time
#   git clone https://github.com/maggio-a/texture-defrag /tmp/texture-defrag-src   # measured: 5c5543a
#   TEXTURE_DEFRAG_SRC=/tmp/texture-defrag-src bench/peers.sh --build
# The build is qmake's release configuration (g++ -O2), in TEXTURE_DEFRAG_BUILD.
#
# Environment:
#   TEXTURE_DEFRAG_SRC    its source (for --build when no SOURCE_DIR is given)
#   TEXTURE_DEFRAG_BUILD  its build folder (default /tmp/texture-defrag-build)
#   TEXTURE_DEFRAG        its executable (default $TEXTURE_DEFRAG_BUILD/texture-defrag)
#   TIGHTEX               tightex's executable (default build/tightex)
#   PEERS_SUBDIVIDE       subdivision levels of the generated model (0: none)
#
# Exit status: 0, 1 on a usage error, 77 (skipped) when texture-defrag, tightex, /usr/bin/time or
# xvfb-run is missing. Either tool failing on a model gives a row that says so, not an exit.
set -euo pipefail
cd "$(dirname "$0")/.."

td_build=${TEXTURE_DEFRAG_BUILD:-/tmp/texture-defrag-build}
td_bin=${TEXTURE_DEFRAG:-$td_build/texture-defrag}
tightex=${TIGHTEX:-build/tightex}
data=../shared/data

# The packages and steps above, for the messages of a missing dependency.
install_help() {
  sed -n '/^# texture-defrag is a benchmark-only/,/^# The build is/p' "$0" | sed 's/^# \{0,1\}//' >&2
}

# Builds texture-defrag out of source with qmake and make.
build_texture_defrag() {
  local src=${1:-${TEXTURE_DEFRAG_SRC:-}}
  if [ -z "$src" ] || [ ! -f "$src/texture-defrag/texture-defrag.pro" ]; then
    echo "peers.sh --build: no texture-defrag source (give SOURCE_DIR or TEXTURE_DEFRAG_SRC)" >&2
    install_help
    exit 1
  fi
  command -v qmake > /dev/null || { echo "peers.sh --build: qmake is missing" >&2; install_help; exit 77; }
  src=$(cd "$src" && pwd)
  mkdir -p "$td_build"
  (cd "$td_build" && qmake "$src/texture-defrag/texture-defrag.pro" -spec linux-g++ CONFIG+=release \
    && make -j"$(nproc)")
  echo "built $td_build/texture-defrag"
}

# Exits 77 with the way to install whatever is missing.
require_tools() {
  local missing=""
  [ -x "$td_bin" ] || missing="$missing texture-defrag ($td_bin)"
  [ -x /usr/bin/time ] || missing="$missing /usr/bin/time"
  [ -n "${DISPLAY:-}" ] || command -v xvfb-run > /dev/null || missing="$missing xvfb-run"
  if [ -n "$missing" ]; then
    echo "peers.sh: skipped, missing:$missing" >&2
    install_help
    exit 77
  fi
  [ -x "$tightex" ] || { echo "peers.sh: skipped, no $tightex (build tightex first)" >&2; exit 77; }
}

# The default models: two scans, and a subdivided scan when the subdivision tool is there.
default_models() {
  local levels=${PEERS_SUBDIVIDE:-2} scan=$data/meshroom_esp32cam/texturedMesh.obj
  [ -f "$scan" ] && echo "$scan"
  [ -f "$data/fuze/fuze.obj" ] && echo "$data/fuze/fuze.obj"
  if [ -f "$scan" ] && [ -f tools/subdivide_obj.py ] && [ "$levels" -gt 0 ]; then
    python3 tools/subdivide_obj.py "$scan" "$work/meshroom_esp32cam_subdivided_x$levels" "$levels" > /dev/null
    echo "$work/meshroom_esp32cam_subdivided_x$levels/texturedMesh.obj"
  fi
}

# Runs one command `runs` times under /usr/bin/time; prints "wall user sys peak_kib" per run.
time_runs() {
  local log=$1
  shift
  for _ in $(seq "$runs"); do
    /usr/bin/time -f "%e %U %S %M" -o "$work/time" "$@" > "$log" 2>&1 || {
      echo "exit status $?" >> "$log"
      return 1
    }
    cat "$work/time"
  done
}

# One table row per tool for a model, and the ratio line.
compare_model() {
  local obj=$1 index=$2 name
  name=$(basename "$(dirname "$obj")")
  local out=$work/out/$index
  mkdir -p "$out/td" "$out/tx"
  local td_times="" tx_times=""
  td_times=$(time_runs "$out/td.log" "$td_bin" "$obj" -o "$out/td/out.obj") || td_times="failed"
  tx_times=$(time_runs "$out/tx.log" "$tightex" "$obj" -o "$out/tx" -q) || tx_times="failed"
  local td_obj=$out/td/out.obj tx_obj
  tx_obj=$out/tx/$(basename "$obj")
  [ "$td_times" = failed ] || "$tightex" measure "$obj" "$td_obj" > "$out/td.json" 2> "$out/td.measure.log" || true
  [ "$tx_times" = failed ] || "$tightex" measure "$obj" "$tx_obj" > "$out/tx.json" 2> "$out/tx.measure.log" || true
  python3 - "$name" "$out" "$td_times" "$tx_times" <<'PY'
import json, os, statistics, sys
name, out, td, tx = sys.argv[1:5]

def figures(times, tag):
    if times == "failed":
        return None
    runs = [list(map(float, line.split())) for line in times.splitlines()]
    med = [statistics.median(r[i] for r in runs) for i in range(4)]
    path = os.path.join(out, tag + ".json")
    m = json.load(open(path)) if os.path.getsize(path) > 0 else None
    return med, m

def row(tool, f, log):
    if f is None:
        tail = open(os.path.join(out, log)).read().strip().splitlines()[-1:]
        return f"| {name} | {tool} | failed: {' '.join(tail)[:80]} | | | | | | | |"
    (wall, user, sys_s, kib), m = f
    q = "| | | |" if m is None else (
        f"| {m['output']['texels'] / 1e6:.2f} M ({m['output']['utilization'] * 100:.0f}% used) "
        f"| {m['surface_psnr_db']:.2f} | {m['lost_triangles']} | {m['flipped']} |")
    return f"| {name} | {tool} | {wall:.2f} | {user + sys_s:.2f} | {sys_s:.2f} | {kib / 1024:.0f} " + q

ftd, ftx = figures(td, "td"), figures(tx, "tx")
print(row("texture-defrag", ftd, "td.log"))
print(row("tightex", ftx, "tx.log"))
if ftd and ftx:
    (w1, u1, s1, k1), _ = ftd
    (w2, u2, s2, k2), _ = ftx
    print(f"| {name} | **texture-defrag / tightex** | **{w1 / w2:.2f}x** | {(u1 + s1) / (u2 + s2):.2f}x | "
          f"| {k1 / k2:.2f}x | | | | |")
PY
}

if [ "${1:-}" = --build ]; then
  shift
  build_texture_defrag "$@"
  exit 0
fi
runs=3
if [ "${1:-}" = --runs ]; then
  runs=${2:?--runs needs a number}
  shift 2
fi
require_tools
# texture-defrag renders its texture with OpenGL through Qt: without a display, the whole run moves
# into one Xvfb server, so the server's start is not in any timing.
if [ -z "${DISPLAY:-}" ]; then
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" --runs "$runs" "$@"
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ $# -gt 0 ]; then models=("$@"); else mapfile -t models < <(default_models); fi
[ ${#models[@]} -gt 0 ] || { echo "peers.sh: no models (no $data, none given)" >&2; exit 77; }

echo "tightex $(git rev-parse --short HEAD), texture-defrag $td_bin; median of $runs runs each, one after the other;"
echo "$(nproc) cores, load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| model | tool | wall s | CPU s | sys s | peak MiB | texels | surface PSNR dB | lost | flipped |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for index in "${!models[@]}"; do
  obj=${models[$index]}
  [ -f "$obj" ] || { echo "peers.sh: no such model $obj" >&2; exit 1; }
  compare_model "$obj" "$index"
done
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
