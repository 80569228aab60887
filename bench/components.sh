#!/usr/bin/env bash
# Where a scan's error against the path tracer comes from: the default rig split into its
# key light and its sky, each solved and traced at albedo 0.7 (with bounces) and at albedo
# 0.001 (direct light only: the bounces are 1e-3 of it), so that
#   direct = 700 B(albedo 0.001),   indirect = B(albedo 0.7) - direct
# for the bake and for the reference at the same points (B is linear in the lights; E
# does not depend on the albedo where nothing bounces). Prints a markdown table: each
# component's RMS error and mean bias, on its own level and on the whole rig's.
#
#   bash bench/components.sh SCAN_DIR [WORK]
#
# SCAN_DIR: an accuracy.sh case directory (its scene.mebake ingest is copied, not changed),
# e.g. build/bench-accuracy/lucy. Needs a scan without vertex colours (all albedo 0.7 under
# the default rig). WORK: default SCAN_DIR/components. Points, samples and time limit as
# accuracy.sh's (2000 points, 1 % target, 60 s).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
SRC="$(cd "$1" && pwd)"
WORK="${2:-$SRC/components}"
[ -x "$MEBAKE" ] || { echo "build mebake first: $MEBAKE" >&2; exit 1; }
[ -d "$SRC/scene.mebake" ] || { echo "$SRC/scene.mebake: no ingest there" >&2; exit 1; }
mkdir -p "$WORK"

# The default rig of solve/scene.cpp (AddDefaultRig) written out, key and sky apart.
python3 - "$SRC/scene.mebake/manifest.json" "$WORK" <<'PY'
import json, math, sys
m = json.load(open(sys.argv[1])); lo, hi = m["bbox"]; up = m["up"]
def add(a, b): return [a[i] + b[i] for i in range(3)]
def mul(a, s): return [x * s for x in a]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]]
def norm(a): return mul(a, 1 / math.sqrt(dot(a, a)))
c = mul(add(lo, hi), 0.5); span = [hi[i] - lo[i] for i in range(3)]
diag = max(math.sqrt(dot(span, span)), 1e-9)
side = [1, 0, 0] if abs(up[0]) < 0.9 else [0, 0, 1]
front = norm(cross(side, up)); side = norm(cross(up, front))
d = norm(add(add(mul(up, 0.84), mul(side, 0.94)), mul(front, -0.2)))
ctr = add(c, mul(d, 1.5 * diag)); a = norm(cross(d, up)); b = cross(a, d); h = diag * 0.1
verts = [add(add(ctr, mul(a, sa * h)), mul(b, sb * h)) for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
l = 3.0 / (4 * h * h / (1.5 * diag) ** 2)
key = {"vertices": verts, "radiance": [l, l * 0.97, l * 0.92]}
sky = {"type": "uniform", "radiance": [0.25, 0.27, 0.30]}
for name, lights, s in (("key", [key], {"type": "none"}), ("sky", [], sky)):
    for albedo, suffix in ((0.7, ""), (0.001, "-direct")):
        json.dump({"up": up, "materials": [{"albedo": albedo, "use_vertex_colors": False}],
                   "lights": lights, "sky": s}, open("%s/%s%s.json" % (sys.argv[2], name, suffix), "w"))
PY

for c in key-direct sky-direct key sky; do
  d="$WORK/$c"
  rm -rf "$d"; mkdir -p "$d"
  cp -r "$SRC/scene.mebake" "$d/scene.mebake"; rm -rf "$d/scene.mebake/solve"
  echo "== $c" >&2
  "$MEBAKE" -q reference "$d/scene.mebake" --scene "$WORK/$c.json" --points 2000 --target 0.01 \
    --samples 65536 --time-limit 60 -o "$d/ref.json"
  /usr/bin/time -f "%e %U %S %M" -o "$d/solve.time" \
    "$MEBAKE" -q solve "$d/scene.mebake" --scene "$WORK/$c.json" --order 2
  "$MEBAKE" -q compare "$d/scene.mebake" "$d/ref.json" --points -o "$d/cmp.json"
  rm -rf "$d/scene.mebake"
done

python3 - "$WORK" <<'PY'
import json, math, sys
w = sys.argv[1]
def load(c):
    p = json.load(open("%s/%s/cmp.json" % (w, c)))["points"]
    return [q["B"] for q in p], [q["bake_B"] for q in p]
def comb(a, x, b=0, y=None):  # a x + b y, point by point and colour by colour
    return [[a * u[i] + (b * v[i] if y else 0) for i in range(3)] for u, v in zip(x, y or x)]
def rms(v): return math.sqrt(sum(sum(c * c for c in u) for u in v) / len(v))
s = 0.7 / 0.001
K, KD, S, SD = load("key"), load("key-direct"), load("sky"), load("sky-direct")
parts = {"key direct": [comb(s, x) for x in KD], "sky direct": [comb(s, x) for x in SD]}
parts["key indirect"] = [comb(1, K[i], -s, KD[i]) for i in range(2)]
parts["sky indirect"] = [comb(1, S[i], -s, SD[i]) for i in range(2)]
parts["direct"] = [comb(1, parts["key direct"][i], 1, parts["sky direct"][i]) for i in range(2)]
parts["indirect"] = [comb(1, parts["key indirect"][i], 1, parts["sky indirect"][i]) for i in range(2)]
parts["key scene"], parts["sky scene"] = K, S
parts["whole rig (key + sky)"] = [comb(1, K[i], 1, S[i]) for i in range(2)]
full = parts["whole rig (key + sky)"][0]
print("| component | level (RMS of B) | RMS error / own level | / rig level | mean bias / own | / rig |")
print("|---|---:|---:|---:|---:|---:|")
for name, (r, b) in parts.items():
    d = comb(1, b, -1, r); e = rms(d); bias = sum(map(sum, d))
    print("| %s | %.4f | %.2f %% | %.2f %% | %+.2f %% | %+.2f %% |" % (
        name, rms(r), 100 * e / rms(r), 100 * e / rms(full), 100 * bias / sum(map(sum, r)),
        100 * bias / sum(map(sum, full))))
PY
