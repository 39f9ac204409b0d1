#!/usr/bin/env bash
# The figures of every map (BENCHMARKS.md, "Every map"): the two Khronos GLBs of ../shared/data and the
# generated scan-like PBR models (the demo's vase; the several-page meshroom scan with a packed
# occlusion-roughness-metallic image per page) through tightex at the default budget, each map's
# surface PSNR against the ideal re-sampler (tools/map_eval.cpp), the normal maps' angular error, and the Khronos
# glTF-Validator on every GLB written.
#
#   bash bench/material_maps.sh [OUT]      (needs a build with TIGHTEX_BUILD_TOOLS, the default)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/maps-bench}
rm -rf "$out" && mkdir -p "$out"
./build/tightex_make_demo "$out/demo" >/dev/null
./build/tightex_map_eval make-scan "$out/demo/vase.obj" "$out/scan"
pages=../shared/data/meshroom_esp32cam_pages/texturedMesh.obj
[ -f "$pages" ] && ./build/tightex_map_eval make-orm-scan "$pages" "$out/scan"
bash scripts/gltf-checks.sh >/dev/null
status=0
for model in ../shared/data/khronos_waterbottle/WaterBottle.glb ../shared/data/khronos_avocado/Avocado.glb "$out/scan/scan_pbr.glb" "$out/scan/scan_orm.glb"; do
  [ -f "$model" ] || { echo "maps: $model absent, skipped"; continue; }
  name=$(basename "$model" .glb)
  ./build/tightex "$model" -o "$out/$name" -q
  ./build/tightex_map_eval compare "$model" "$out/$name/$name.glb" | tail -n +2 || status=1
  python3 - "$out/$name/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
bake = sum(t["seconds"] for t in r["timings"] if t["stage"] == "bake")
print("  base colour bake %.2f s;" % bake, "; ".join("%s %s %.2f s" % (m["name"], "x".join(map(str, m["sizes"][0])), m["seconds"]) for m in r.get("maps", [])))
PY
  command -v node >/dev/null && node tests/gltf/check_gltf.mjs "$out/$name/$name.glb" | python3 -c "import json,sys; j=json.load(sys.stdin); print('  validator: %d errors, %d warnings' % (j['errors'], j['warnings']))"
done
exit $status
