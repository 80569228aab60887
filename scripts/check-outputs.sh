#!/usr/bin/env bash
# Bakes the quick-start sample, the Cornell boxes and every shared scan, and checks each
# output with the tools people open them with:
#   lightmap.exr, irradiance.exr  -> OpenEXR's exrheader
#   baked.glb                     -> the Khronos glTF validator (npm gltf-validator)
#   vertex_colors.ply             -> MeshLab's loader (meshlabserver under xvfb-run)
# A checker that is not installed is reported as "-" (skipped), never as a pass.
# Prints a Markdown table (one row per mesh) on stdout; logs go to $OUT/<name>/log.txt.
#   bash scripts/check-outputs.sh [OUT=/tmp/mebake-outputs]
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
MB=$ROOT/build/src/app/mebake
OUT=${1:-/tmp/mebake-outputs}
DATA=$ROOT/../shared/data
GLTFV=$ROOT/build/gltfv/node_modules
[ -x "$MB" ] || { echo "build first: $MB is missing" >&2; exit 2; }
mkdir -p "$OUT"

have() { command -v "$1" >/dev/null 2>&1; }

check_exr() { have exrheader || { echo "-"; return; }
  exrheader "$1" >/dev/null 2>&1 && echo ok || echo FAIL; }
check_glb() { [ -d "$GLTFV/gltf-validator" ] && have node || { echo "-"; return; }
  NODE_PATH=$GLTFV node tests/e2e/validate_gltf.js "$1" >/dev/null 2>&1 && echo ok || echo FAIL; }
check_ply() { have meshlabserver && have xvfb-run || { echo "-"; return; }
  (cd "$(dirname "$1")" && xvfb-run -a meshlabserver -i "$1" -o meshlab_copy.ply -m vc \
     >meshlab.log 2>&1) && grep -q "saved as" "$(dirname "$1")/meshlab.log" && echo ok || echo FAIL; }

echo "| mesh | triangles | charts | bake s | peak MiB | seams mean | lightmap.exr | irradiance.exr | baked.glb | vertex_colors.ply |"
echo "|---|---:|---:|---:|---:|---:|---|---|---|---|"

bake() {  # name scene-file inputs...
  local name=$1 scene=$2; shift 2
  local d=$OUT/$name
  rm -rf "$d"; mkdir -p "$d"
  local extra=()
  [ -n "$scene" ] && extra=(--scene "$scene")
  local t0=$(date +%s.%N)
  if ! /usr/bin/time -f '%M' -o "$d/rss.txt" "$MB" bake "$@" "${extra[@]}" -o "$d/out" >"$d/log.txt" 2>&1; then
    echo "| $name | | | | | | bake FAILED (see $d/log.txt) | | | |"; return; fi
  local secs=$(python3 -c "print($(date +%s.%N) - $t0)")
  "$MB" -q export "$d/out/scene.mebake" --irradiance "$d/out/irradiance.exr" --stats "$d/stats.json" --force >>"$d/log.txt" 2>&1
  local tris=$(python3 -c "import json;m=json.load(open('$d/out/scene.mebake/manifest.json'));print(m['face_count'] if 'face_count' in m else sum(c['triangles'] for c in m['charts']))")
  local charts=$(python3 -c "import json;print(len(json.load(open('$d/out/scene.mebake/manifest.json'))['charts']))")
  local seams=$(python3 -c "import json;s=json.load(open('$d/stats.json')).get('seams',{});print('%.3f'%s.get('mean_relative_jump',0))")
  local rss=$(( $(cat "$d/rss.txt" | tail -1) / 1024 ))
  echo "| $name | $tris | $charts | $(printf %.1f "$secs") | $rss | $seams | $(check_exr "$d/out/lightmap.exr") | $(check_exr "$d/out/irradiance.exr") | $(check_glb "$d/out/baked.glb") | $(check_ply "$d/out/vertex_colors.ply") |"
}

bake sample-rock "" data/samples/rock.ply
for f in Original Sphere Glossy Empty-RG; do
  [ -f "$DATA/scenes/cornell-mcguire/CornellBox-$f.obj" ] &&
    bake "cornell-mcguire-$f" "" "$DATA/scenes/cornell-mcguire/CornellBox-$f.obj"
done
[ -f "$DATA/scenes/cornell-tinyobjloader/cornell_box.obj" ] &&
  bake cornell-tinyobjloader "" "$DATA/scenes/cornell-tinyobjloader/cornell_box.obj"
m=$DATA/scenes/cornell-mitsuba/meshes/cbox
[ -d "$m" ] && bake cornell-mitsuba data/scenes/cornell-mitsuba.json \
  "$m/floor.obj" "$m/ceiling.obj" "$m/back.obj" "$m/greenwall.obj" "$m/redwall.obj" \
  "$m/smallbox.obj" "$m/largebox.obj"
for s in "$DATA"/scans/*.ply "$DATA"/scans/*.obj; do
  [ -f "$s" ] && bake "$(basename "${s%.*}")" "" "$s"
done
