#!/usr/bin/env bash
# Pictures of the bake against path-traced pictures of the same view (docs/accuracy.md,
# "Pictures"): for each case, bake with the defaults, then at two views render the bake
# (`mebake render`, linear EXR and PNG) and path-trace the reference picture (`mebake
# reference --image`), and score them (`mebake compare IMAGE REF --diff`).
#
#   bash bench/refimg.sh [--cases "rock cornell bunny ..."] [--size 400x300]
#                        [--se-target 0.01] [--ref-time 300] [--work DIR] [--reuse-ref]
#
# The reference depends on the ingest and the scene only, not on the solve: --reuse-ref
# keeps the reference pictures already in WORK (to score another solve or another
# renderer of the same bake). MEBAKE_RENDER (default: MEBAKE) is the binary that renders.
#
# The error splits in two with the reference's display-rule picture (`reference
# --rule-image`: (pi Le + rho (n.E)+)/pi with the path-traced vector irradiance E at the
# same hits): "rule" is that picture against the reference (what the light map's display
# rule loses even with the exact E), "field" is the render against it (what the bake's
# field gets wrong: the solve and its reconstruction between nodes and across charts).
# The rule picture's E is gathered over the geometric normal's hemisphere; the solver's
# receivers cut their light at a smooth horizon close to the display's normal, so a bake
# carries only part of that loss and "field" then counts the rest of it the other way.
# "carried (slope) / rest" splits the render's own error by the rule picture (`compare
# --rule`, docs/accuracy.md): the part along the rule's loss, and the rest.
#
# Views: "default" is render's default camera (front-right-above, the side the default
# rig's key light comes from); "away" looks from the opposite horizontal direction, at the
# side facing away from the key light (lit by the sky and bounced light). The Cornell box
# has no key light: its second view is the classic one through the open front. Writes
# WORK/refimg.md (a markdown table) and WORK/<case>-<view>-{bake,ref,diff}.png (the
# difference with the reference's chart borders drawn in black).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
DATA="$ROOT/../shared/data"
CASES="rock cornell bunny horse igea lucy nefertiti pepper turbineblade"
SIZE=400x300
SE=0.01
REF_TIME=300
WORK="$ROOT/build/bench-refimg"
REUSE_REF=0
while [ $# -gt 0 ]; do
  case "$1" in
    --cases) CASES="$2"; shift 2 ;;
    --size) SIZE="$2"; shift 2 ;;
    --se-target) SE="$2"; shift 2 ;;
    --ref-time) REF_TIME="$2"; shift 2 ;;
    --work) WORK="$2"; shift 2 ;;
    --reuse-ref) REUSE_REF=1; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
[ -x "$MEBAKE" ] || { echo "build mebake first: $MEBAKE" >&2; exit 1; }
RENDER="${MEBAKE_RENDER:-$MEBAKE}"
mkdir -p "$WORK"

input_of() {
  case "$1" in
    rock) echo "$ROOT/data/samples/rock.ply" ;;
    cornell) echo "$DATA/scenes/cornell-mcguire/CornellBox-Original.obj" ;;
    bunny) echo "$DATA/scans/bun_zipper.ply" ;;
    nefertiti) echo "$DATA/scans/nefertiti.obj" ;;
    *) echo "$DATA/scans/$1.ply" ;;
  esac
}

# The "away" camera of a bake directory: render's default distance and field of view,
# from the side opposite the default rig's key light, in the rig's frame for the scan's up
# axis (the manifest's "up"; solve/scene.cpp AddDefaultRig, output/render.cpp DefaultCamera).
away_view() {
  python3 - "$1/manifest.json" <<'PY'
import json, math, sys
m = json.load(open(sys.argv[1]))
lo, hi = m["bbox"]
c = [(a + b) / 2 for a, b in zip(lo, hi)]
radius = max(0.5 * math.dist(lo, hi), 1e-9)
def norm(v):
    n = math.sqrt(sum(x * x for x in v)); return [x / n for x in v]
def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
up = norm(m.get("up", [0, 1, 0]))
side = [1, 0, 0] if abs(up[0]) < 0.9 else [0, 0, 1]
front = norm(cross(side, up))
side = norm(cross(up, front))
d = [-0.6 * f - 0.5 * s + 0.25 * u for f, s, u in zip(front, side, up)]
n = math.sqrt(sum(x * x for x in d))
dist = 1.1 * radius / math.sin(math.radians(25))
eye = [ci + di / n * dist for ci, di in zip(c, d)]
print("--eye %.6g,%.6g,%.6g --target %.6g,%.6g,%.6g --up %.6g,%.6g,%.6g" % (*eye, *c, *up))
PY
}

echo "| case | view | pixels | RMS | reference noise | RMS without noise | bias | p95 | max | display RMS | RMS next to chart borders / elsewhere | RMS at silhouettes (share of pixels) | rule / field | carried (slope) / rest | reference time (s) |" > "$WORK/refimg.md"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|" >> "$WORK/refimg.md"
for c in $CASES; do
  input=$(input_of "$c")
  [ -f "$input" ] || { echo "$c: $input absent, skipped" >&2; continue; }
  out="$WORK/$c"
  # A bake resumes where an earlier run stopped.
  [ -f "$out/scene.mebake/solve/solution.bin" ] || "$MEBAKE" -q bake "$input" -o "$out"
  dir="$out/scene.mebake"
  for view in default away; do
    cam=""
    if [ "$view" = away ]; then
      if [ "$c" = cornell ]; then cam="--eye 0,1,3.4 --target 0,1,0 --up 0,1,0 --fov 40";
      else cam=$(away_view "$dir"); fi
    fi
    base="$WORK/$c-$view"
    # shellcheck disable=SC2086
    "$RENDER" -q render "$dir" $cam --size "$SIZE" --float -o "$base-bake.exr" -f
    # shellcheck disable=SC2086
    "$RENDER" -q render "$dir" $cam --size "$SIZE" -o "$base-bake.png" -f
    if [ "$REUSE_REF" = 0 ] || [ ! -f "$base-ref.json" ]; then
      # shellcheck disable=SC2086
      "$MEBAKE" -q reference "$dir" $cam --size "$SIZE" --se-target "$SE" --time-limit "$REF_TIME" \
        --image "$base-ref.exr" --image "$base-ref.png" --rule-image "$base-rule.exr" -o "$base-ref.json"
    fi
    "$MEBAKE" -q compare "$base-rule.exr" "$base-ref.exr" -o "$base-rule-cmp.json"
    "$MEBAKE" -q compare "$base-bake.exr" "$base-rule.exr" --mask "$base-ref.exr" -o "$base-field-cmp.json"
    if ! "$MEBAKE" -q compare "$base-bake.exr" "$base-ref.exr" --diff "$base-diff.png" --borders \
        --rule "$base-rule.exr" -o "$base-cmp.json" 2> "$base-cmp.err"; then
      echo "| $c | $view | not compared: $(sed 's/.*error: //' "$base-cmp.err" | head -1) |" >> "$WORK/refimg.md"
      tail -1 "$WORK/refimg.md"
      continue
    fi
    python3 - "$base-cmp.json" "$base-ref.json" "$c" "$view" "$base-rule-cmp.json" \
      "$base-field-cmp.json" >> "$WORK/refimg.md" <<'PY'
import json, sys
d, r = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
rule, field = json.load(open(sys.argv[5])), json.load(open(sys.argv[6]))
pct = lambda x: "%.2f %%" % (100 * x)
border = ("%s / %s" % (pct(d["border_rms"]), pct(d["interior_rms"]))) if "border_rms" in d else "-"
outline = ("%s (%.0f %%)" % (pct(d["silhouette_rms"]), 100 * d["silhouette_pixels"] / d["pixels"])
           if "silhouette_rms" in d else "-")
carried = "%s (x%.2f) / %s" % (pct(d["rule_carried_rms"]), d["rule_slope"], pct(d["rule_rest_rms"]))
print("| %s | %s | %d | %s | %s | %s | %+.2f %% | %s | %s | %s | %s | %s | %s / %s | %s | %.0f (%s) |" % (
    sys.argv[3], sys.argv[4], d["pixels"], pct(d["relative_rms"]), pct(d["reference_noise_rms"]),
    pct(d["corrected_rms"]), 100 * d["relative_bias"], pct(d["relative_p95"]),
    pct(d["relative_max"]), pct(d["display_rms"]), border, outline, pct(rule["relative_rms"]),
    pct(field["relative_rms"]), carried, r["stats"]["seconds"], r["stats"]["stop"]))
PY
    tail -1 "$WORK/refimg.md"
  done
done
