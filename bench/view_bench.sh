#!/usr/bin/env bash
# The browser viewer on real bakes (bench/RESULTS.md, "Browser viewer"): for each solved
# bake given, the size of its mesh chunks with and without EXT_meshopt_compression, the
# time to the first frame and to the whole mesh, and the frame time, in headless Chromium
# with software WebGL (SwiftShader) at 800x600.
#   bash bench/view_bench.sh build out/rock/scene.mebake out/igea/scene.mebake ...
set -euo pipefail
build=$1
shift
root=$(cd "$(dirname "$0")/.." && pwd)
echo "load: $(uptime)"
for bake in "$@"; do
  for variant in meshopt plain; do
    extra="--rewrite"
    [ "$variant" = plain ] && extra="--rewrite --no-meshopt"
    # Viewer data written first (not timed here), then the page loaded twice: the first
    # run warms the file cache and Chromium's shader cache like a user's second visit.
    json=$(node "$root/tests/e2e/view_driver.mjs" --node-modules "$build/web/node_modules" \
      --mebake "$build/src/app/mebake" --dir "$bake" --size 800x600 --extra "$extra" \
      --shot /tmp/view-bench-1.png=mode=glossy --shot /tmp/view-bench-2.png=mode=glossy --frames 20 2>/dev/null)
    mesh=$(du -cb "$bake"/web/mesh.*.glb | tail -1 | cut -f1)
    maps=$(du -cb "$bake"/web/*.half | tail -1 | cut -f1)
    tris=$(grep -o '"triangles": [0-9]*' "$bake/web/view.json" | grep -o '[0-9]*$')
    chunks=$(ls "$bake"/web/mesh.*.glb | wc -l)
    echo "$bake $variant triangles=$tris chunks=$chunks mesh_bytes=$mesh map_bytes=$maps $json"
  done
done
echo "load: $(uptime)"
