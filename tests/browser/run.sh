#!/bin/sh
# The browser test of report.html (ctest Browser.ReportPage): runs tightex on the demo and, where
# ../shared/data has them, on meshroom_esp32cam and WaterBottle.glb (a PBR material's maps), then
# opens each report.html in Debian's headless chromium (check_report.mjs, through the npm package
# playwright-core pinned in package-lock.json). Exit 77 (skipped) when chromium or node is absent.
# Screenshots: BUILD/browser_test/*.png.
#   run.sh BUILD_DIR TIGHTEX MAKE_DEMO SHARED_DATA
set -eu
skip() { echo "SKIPPED: $*"; exit 77; }
command -v node >/dev/null 2>&1 || skip "node not found (the browser test needs Node.js >= 18 and npm)"
command -v npm >/dev/null 2>&1 || skip "npm not found (the browser test installs playwright-core with it)"
CHROMIUM=${CHROMIUM:-$(command -v chromium || true)}
[ -n "$CHROMIUM" ] || skip "chromium not found (apt-get install chromium; scripts/setup.sh does)"
export CHROMIUM
here=$(cd "$(dirname "$0")" && pwd)
build=$1 tightex=$2 make_demo=$3 shared=$4

work=$build/browser_test
mkdir -p "$work"
# playwright-core as the lock file pins it, installed once per lock file.
if ! cmp -s "$here/package-lock.json" "$work/package-lock.json" || [ ! -d "$work/node_modules/playwright-core" ]; then
  cp "$here/package.json" "$here/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
fi
cp "$here/check_report.mjs" "$work/"

rm -rf "$work/demo" "$work/meshroom" "$work/bottle" "$work/network_probe"
"$make_demo" "$work/demo/input" >/dev/null
"$tightex" "$work/demo/input/vase.obj" -o "$work/demo/out" -q
pages="$work/demo/out/report.html $work/demo/out/report.json $work/demo.png"
scan=$shared/meshroom_esp32cam/texturedMesh.obj
if [ -f "$scan" ]; then
  # --aspect 1 skips the shape probes (most of this scan's run): the page is under test, not the map.
  "$tightex" "$scan" -o "$work/meshroom/out" -q --aspect 1
  pages="$pages $work/meshroom/out/report.html $work/meshroom/out/report.json $work/meshroom.png"
else
  echo "note: $scan absent: only the demo is checked"
fi

bottle=$shared/khronos_waterbottle/WaterBottle.glb
if [ -f "$bottle" ]; then
  # Every map of a PBR material beside the base colour, with its figures; --size 512 keeps it short.
  "$tightex" "$bottle" -o "$work/bottle/out" -q --size 512
  pages="$pages $work/bottle/out/report.html $work/bottle/out/report.json $work/bottle.png"
else
  echo "note: $bottle absent: no page with maps is checked"
fi

# The checker must notice a page that reaches for the network (an image and a fetch).
mkdir -p "$work/network_probe"
cat > "$work/network_probe/report.html" <<'PAGE'
<!DOCTYPE html><html><body><img src="http://127.0.0.1:9/probe.png" alt="">
<script>window.tightexPage = { ready: true, errors: [] }; fetch("http://127.0.0.1:9/probe").catch(() => {});</script></body></html>
PAGE
(cd "$work" && node check_report.mjs network_probe/report.html demo/out/report.json network_probe/shot.png) \
  > "$work/network_probe/log.txt" 2>&1 || true
if ! grep -q "requested from the network: http://127.0.0.1:9/probe.png" "$work/network_probe/log.txt" ||
   ! grep -q "requested from the network: http://127.0.0.1:9/probe$" "$work/network_probe/log.txt"; then
  echo "FAIL: the checker did not notice a page that fetches from the network:"
  cat "$work/network_probe/log.txt"
  exit 1
fi
echo "ok: a page that fetches from the network is caught"

# shellcheck disable=SC2086
(cd "$work" && node check_report.mjs $pages)
