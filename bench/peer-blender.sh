#!/usr/bin/env bash
# mebake next to Blender Cycles' light-map bake (issue 7): the same mesh, light and albedo,
# errors against the same path-traced reference, wall time and peak RSS of each.
#
#   bash bench/peer-blender.sh [--tris N] [--samples "16 64 256"] [--tolerances "0.05 0.02"]
#                              [--points N] [--work DIR] [--no-results]
#
# Mesh: ../shared/peers/blender_gen_rock.py (a displaced rock on a ground with a back wall,
# the scene the peer scripts are made for), N triangles (default 1M). Light: the peer
# script's 1 x 0.5 m rectangle at (0.8, -0.6, 3.2) facing down, 300 W, i.e. radiance
# P / (4 A) = 150 W/(m^2 sr) (measured in ../shared/peers/README.md); black world; albedo 0.7.
# Blender: blender_bake.py, DIFFUSE direct+indirect, 1024^2 smart-UV light map, 16 bounces,
# 2 threads, numpy PLY importer. mebake: ingest + solve (M2, several tolerances) + export of
# the light map. Skips (exit 0) when blender is not installed. Not part of the tests.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
PEERS="$ROOT/../shared/peers"
PY=/usr/bin/python3   # Debian's python3 (numpy from python3-numpy)
TRIS=1000000
SAMPLES="16 64 256"
TOLS="0.05 0.02"
POINTS=2000
WORK="$ROOT/build/bench-peer"
RESULTS=1
CMD="bash bench/peer-blender.sh$(printf " %q" "$@")"
while [ $# -gt 0 ]; do
  case "$1" in
    --tris) TRIS="$2"; shift 2 ;;
    --samples) SAMPLES="$2"; shift 2 ;;
    --tolerances) TOLS="$2"; shift 2 ;;
    --points) POINTS="$2"; shift 2 ;;
    --work) WORK="$2"; shift 2 ;;
    --no-results) RESULTS=0; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
if ! command -v blender > /dev/null; then
  echo "peer-blender: blender is not installed (apt-get install blender); skipped" >&2
  exit 0
fi
$PY -c "import numpy" 2> /dev/null || { echo "peer-blender: needs python3-numpy; skipped" >&2; exit 0; }
[ -x "$MEBAKE" ] || { echo "build mebake first" >&2; exit 1; }
mkdir -p "$WORK"
MESH="$WORK/rock.ply"
[ -f "$MESH" ] || $PY "$PEERS/blender_gen_rock.py" --tris "$TRIS" --out "$MESH"
cat > "$WORK/scene.json" <<'JS'
{"up": [0, 0, 1],
 "materials": [{"albedo": [0.7, 0.7, 0.7], "use_vertex_colors": false}],
 "lights": [{"vertices": [[0.3, -0.85, 3.2], [0.3, -0.35, 3.2], [1.3, -0.35, 3.2], [1.3, -0.85, 3.2]],
             "radiance": [150, 150, 150]}],
 "sky": {"type": "none"}}
JS
TSV="$WORK/peer.tsv"
# Steps already measured in WORK (a row in peer.tsv) are kept and not run again.
[ -f "$TSV" ] || printf "tool\tsetting\tstage\tseconds\tpeak_kib\tcpu_s\n" > "$TSV"
done_before() { grep -q -P "^$1\t$2\t$3\t" "$TSV"; }
timed() {  # timed TOOL SETTING STAGE CMD...
  local tool="$1" setting="$2" stage="$3"; shift 3
  if done_before "$tool" "$setting" "$stage"; then echo "kept: $tool $setting $stage" >&2; return 0; fi
  local log="$WORK/$tool.$setting.$stage.time"
  /usr/bin/time -v -o "$log" "$@" > "$WORK/$tool.$setting.$stage.log" 2>&1
  awk -F': ' -v t="$tool" -v s="$setting" -v g="$stage" '
    /Elapsed \(wall clock\)/ {n = split($2, a, ":"); w = 0; for (i = 1; i <= n; i++) w = w * 60 + a[i]}
    /Maximum resident set size/ {m = $2}
    /User time/ {u = $2} /System time/ {y = $2}
    END {printf "%s\t%s\t%s\t%s\t%s\t%s\n", t, s, g, w, m, u + y}' "$log" >> "$TSV"
  tail -1 "$TSV" >&2
}

D="$WORK/rock.mebake"
timed mebake all ingest "$MEBAKE" ingest "$MESH" -o "$D" --force
# The reference, on the ingested mesh (the same surface Blender bakes).
[ -f "$WORK/ref.json" ] || "$MEBAKE" reference "$D" --scene "$WORK/scene.json" --points "$POINTS" \
    --target 0.01 --samples 65536 --time-limit 300 -o "$WORK/ref.json"
for t in $TOLS; do
  timed mebake "tol$t" solve "$MEBAKE" solve "$D" --scene "$WORK/scene.json" --order 2 --tolerance "$t"
  timed mebake "tol$t" export "$MEBAKE" export "$D" --lightmap "$WORK/mebake.exr" --force
  [ -f "$WORK/mebake.tol$t.err.json" ] || "$MEBAKE" -q compare "$D" "$WORK/ref.json" -o "$WORK/mebake.tol$t.err.json"
done
for s in $SAMPLES; do
  timed blender "spp$s" bake blender -b --factory-startup -t 2 --python-exit-code 1 \
    --python "$PEERS/blender_bake.py" -- "$MESH" --out "$WORK/blender$s.exr" --json "$WORK/blender$s.json" \
    --res 1024 --samples "$s" --bounces 16 --threads 2 --importer numpy --dump-uv "$WORK/uv$s.npy"
  [ -f "$WORK/blender.spp$s.err.json" ] || blender -b --factory-startup --python-exit-code 1 --python "$ROOT/bench/peer-blender-eval.py" -- \
    "$WORK/ref.json" "$MESH" "$WORK/uv$s.npy" "$WORK/blender$s.exr" 0.7 "$WORK/blender.spp$s.err.json" \
    > "$WORK/eval$s.log" 2>&1 || { echo "evaluation failed, see $WORK/eval$s.log" >&2; exit 1; }
done

$PY - "$WORK" "$CMD" "$TRIS" "$SAMPLES" "$TOLS" > "$WORK/peer.md" <<'PY'
import json, os, sys, platform, datetime, glob
work, cmd, tris = sys.argv[1], sys.argv[2], sys.argv[3]
rows = [l.rstrip("\n").split("\t") for l in open(work + "/peer.tsv")][1:]
samples_run = set("spp" + x for x in sys.argv[4].split())
tols_run = set("tol" + x for x in sys.argv[5].split())
rows = [r for r in rows if r[0] != "blender" or r[1] in samples_run]
rows = [r for r in rows if r[0] != "mebake" or r[1] == "all" or r[1] in tols_run]
cpu = "?"
for l in open("/proc/cpuinfo"):
    if l.startswith("model name"): cpu = l.split(":", 1)[1].strip(); break
ref = json.load(open(work + "/ref.json"))
ing = [r for r in rows if r[0] == "mebake" and r[2] == "ingest"][0]
out = []
def add(tool, setting, secs, cpu_s, rss, err):
    out.append((tool, setting, secs, cpu_s, rss, err))
for r in rows:
    if r[0] == "mebake" and r[2] == "solve":
        ex = [x for x in rows if x[0] == "mebake" and x[1] == r[1] and x[2] == "export"][0]
        e = json.load(open("%s/mebake.%s.err.json" % (work, r[1])))["error"]
        add("mebake", r[1].replace("tol", "M2, tolerance "), float(ing[3]) + float(r[3]) + float(ex[3]),
            float(ing[5]) + float(r[5]) + float(ex[5]), max(int(ing[4]), int(r[4]), int(ex[4])), e)
    if r[0] == "blender":
        e = json.load(open("%s/blender.%s.err.json" % (work, r[1])))
        add("Blender Cycles", r[1].replace("spp", "") + " samples", float(r[3]), float(r[5]), int(r[4]), e)
print("## Peer: Blender Cycles bake vs mebake (issue 7)\n")
print("Machine: %s, %d cores (shared with other jobs), Debian Blender %s. Date: %s UTC.\n"
      "Command: `%s`. Mesh: `blender_gen_rock.py --tris %s` (%s triangles after ingest); one\n"
      "area light, black world, albedo 0.7. Both errors are against the same `mebake reference`\n"
      "(%d points, reference noise %.2f %%), B = albedo x pi x (Cycles' DIFFUSE texel) for Blender,\n"
      "bilinear at the point's smart-UV coordinate (points on repaired triangles skipped).\n"
      "mebake time = ingest + solve + export of the light map; Blender time = the whole blender\n"
      "process (import, smart UV, bake, save). Peak RSS: /usr/bin/time -v, largest of the stages.\n" %
      (cpu, os.cpu_count(), json.load(open(glob.glob(work + "/blender[0-9]*.json")[0])).get("blender", "?"),
       datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), cmd, tris, ref["triangles"],
       len(ref["points"]), 100 * json.load(open(glob.glob(work + "/mebake.*.err.json")[0]))["error"]["reference_noise_rms"]))
print("| tool | setting | wall s | CPU s | peak RSS MiB | rel RMS of B | corrected | max | points |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
for tool, setting, secs, cpu_s, rss, e in out:
    print("| %s | %s | %.1f | %.1f | %.0f | %.2f %% | %.2f %% | %.1f %% | %d |" % (
        tool, setting, secs, cpu_s, rss / 1024, 100 * e["relative_rms"], 100 * e["corrected_rms"],
        100 * e["relative_max"], e["points"]))
PY
cat "$WORK/peer.md"
if [ "$RESULTS" = 1 ]; then
  $PY - "$ROOT/bench/RESULTS.md" "$WORK/peer.md" peer-blender <<'PY'
import sys
path, table, key = sys.argv[1], open(sys.argv[2]).read(), sys.argv[3]
b, e = "<!-- %s:begin -->" % key, "<!-- %s:end -->" % key
s = open(path).read()
block = "%s\n%s%s" % (b, table, e)
if b in s and e in s:
    s = s[:s.index(b)] + block + s[s.index(e) + len(e):]
else:
    s = s.rstrip("\n") + "\n\n" + block + "\n"
open(path, "w").write(s)
PY
fi
