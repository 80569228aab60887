#!/usr/bin/env bash
# Builds and runs the whole test suite on a fresh Debian 12 machine:
#   1. Release build (warnings are errors) and every ctest test: units, end-to-end runs
#      of the real binary on real data (skipped when ../shared/data is absent).
#   2. Debug + AddressSanitizer + UndefinedBehaviorSanitizer build with clang, running
#      the unit tests of core, io, stream and solve (not the minutes-long ones) and each
#      reader's libFuzzer target briefly.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

bash scripts/install-deps.sh

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DMEBAKE_WERROR=ON
cmake --build build -j"$jobs"
# The Khronos glTF validator (npm) checks the .glb exports; tests skip without it. A fresh
# machine may lack node and npm: they come from Debian (best effort, like MeshLab below).
if ! command -v npm >/dev/null 2>&1; then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm \
    >/dev/null 2>&1 || echo "note: npm could not be installed; the glTF validator tests will skip"
fi
if command -v npm >/dev/null 2>&1 && [ ! -d build/gltfv/node_modules/gltf-validator ]; then
  mkdir -p build/gltfv
  (cd build/gltfv && npm install --silent --no-audit --no-fund gltf-validator >/dev/null 2>&1) ||
    echo "note: gltf-validator could not be installed; its tests will skip"
fi
# MeshLab's loader checks the vertex-coloured PLY (under a virtual X server, as it needs
# OpenGL); the test skips where the packages cannot be installed.
if ! command -v meshlabserver >/dev/null 2>&1 || ! command -v xvfb-run >/dev/null 2>&1; then
  (export DEBIAN_FRONTEND=noninteractive
   apt-get install -y -qq --no-install-recommends meshlab xvfb xauth libgl1-mesa-dri >/dev/null 2>&1 ||
     { apt-get update -qq >/dev/null 2>&1 &&
       apt-get install -y -qq --no-install-recommends meshlab xvfb xauth libgl1-mesa-dri >/dev/null 2>&1; }) ||
    echo "note: meshlab/xvfb could not be installed; the MeshLab test will skip"
fi
ctest --test-dir build -j"$jobs" --output-on-failure --timeout 900

CC=clang-14 CXX=clang++-14 cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug \
  -DMEBAKE_SANITIZE=ON -DMEBAKE_FUZZ=ON -DMEBAKE_BENCH=OFF -DMEBAKE_TEST_MODULES="core;io;stream;solve;output;reference"
cmake --build build-asan -j"$jobs" --target sanitize_set
# Real-data tests and the long convergence and thread-count tests take minutes each in a
# Debug sanitizer build (40 min together); they ran above in the Release build, as did the
# seven that take 40-80 s each here (half this run's test time; shorter tests of the same
# code run here).
ctest --test-dir build-asan -j"$jobs" --output-on-failure --timeout 900 \
  -E 'Data\.|Scans\.|AllSceneMeshes|RealMeshes|Furnace|ClosedCube|BitIdentical|ResumedSolve|ConcaveChartAndAnyResolution|CorruptedTile|DeferredLinkRaysGiveTheBytes|Table1BoundaryAgainstComplete|SmallBudgetSimplifiesCrackFree|LitBoxWithinTolerance|NarrowGrooveConverges|DeviationBoundsTheDistanceBothWays|InwardsSphereAcrossBricks'
