#!/usr/bin/env bash
# Quick start on a fresh Debian 12 machine: install the dependencies, build mebake
# (Release) and bake the bundled sample scan with the default lighting rig.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target mebake mkscan

out=out/rock
./build/src/app/mebake bake data/samples/rock.ply -o "$out" --force
./build/src/app/mebake info "$out/scene.mebake"
echo
echo "Baked. Open these in the tools you already use:"
echo "  light map (HDR):     $out/lightmap.exr   (also $out/lightmap.png)"
echo "  lit mesh (glTF):     $out/baked.glb      (three.js, Blender, any glTF viewer)"
echo "  vertex colours:      $out/vertex_colors.ply (MeshLab, CloudCompare)"
echo "  a rendered view:     $out/render.png"
