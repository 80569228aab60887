#!/bin/bash
# Ingest benchmark (issue 3): one markdown table row per mesh with end-to-end and
# per-pass triangles/s, CPU time, peak RSS (/usr/bin/time -v), charts, area distortion
# and virtual-area fraction (from manifest.json).
#
#   bench/ingest_bench.sh [--memory 1G] [--scans] [--generated "1000000 4000000 16000000"]
#
# Shared scans are read from ../shared/data/scans; generated meshes are piped from
# build/tools/mkscan through stdin. Run from the repository root after building
# build/src/app/mebake and build/tools/mkscan (or set MEBAKE, MKSCAN). Work files go to
# ${TMPDIR:-/tmp}.
set -euo pipefail
memory=1G
scans=0
generated=""
while [ $# -gt 0 ]; do
    case "$1" in
    --memory) memory=$2; shift 2 ;;
    --scans) scans=1; shift ;;
    --generated) generated=$2; shift 2 ;;
    *) echo "usage: $0 [--memory 1G] [--scans] [--generated \"N ...\"]" >&2; exit 2 ;;
    esac
done
bin=${MEBAKE:-build/src/app/mebake}
mkscan=${MKSCAN:-build/tools/mkscan}
tmp=${TMPDIR:-/tmp}/mebake_ingest_bench
mkdir -p "$tmp"

row() {  # name, bake dir, time -v log
    python3 - "$1" "$2" "$3" <<'PY'
import json, re, sys
name, d, log = sys.argv[1:]
m = json.load(open(d + "/manifest.json"))
t = dict(m["timings"])
text = open(log).read()
def field(label):
    return re.search(re.escape(label) + r":\s*(\S+)", text).group(1)
wall_s = field("Elapsed (wall clock) time (h:mm:ss or m:ss)")
parts = [float(x) for x in wall_s.split(":")]
wall = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
cpu = float(field("User time (seconds)")) + float(field("System time (seconds)"))
rss = int(field("Maximum resident set size (kbytes)")) / 1024
tris = m["face_count"]
c = m["charts"]
area = sum(x["area"] for x in c)
mean = sum(x["area_distortion"] * x["area"] for x in c) / area
worst = max(x["area_distortion"] for x in c)
virt = sum(x["virtual_fraction"] for x in c) / len(c)
rate = lambda s: "%.0fK" % (tris / s / 1e3) if s > 0 else "-"
print("| %s | %s | %.1f s | %s | %.1f s | %s | %s / %s / %s / %s | %.0f MiB | %d | %d | %.2f%% | %.2f%% | %.0f%% |" % (
    name, format(tris, ","), wall, rate(wall), cpu, rate(cpu / 2),
    rate(t["spill"]), rate(t["bricks"]), rate(t["charts"]), rate(t["proxy"]),
    rss, m["brick_count"], len(c), 100 * mean, 100 * worst, 100 * virt))
PY
}

echo "| mesh | triangles | wall | tri/s (wall) | CPU (user+sys) | tri/s per CPU-s x2 | tri/s spill / bricks / charts / proxy | peak RSS | bricks | charts | area dist. mean | worst chart | virtual |"
echo "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"
if [ "$scans" = 1 ]; then
    for f in ../shared/data/scans/*.ply ../shared/data/scans/*.obj; do
        [ -f "$f" ] || continue
        n=$(basename "$f")
        /usr/bin/time -v "$bin" ingest "$f" -o "$tmp/scan.mebake" --force --memory "$memory" \
            2> "$tmp/time.log" > /dev/null
        row "$n" "$tmp/scan.mebake" "$tmp/time.log"
    done
fi
for n in $generated; do
    "$mkscan" -n "$n" -q | /usr/bin/time -v "$bin" ingest - -o "$tmp/gen.mebake" --force \
        --memory "$memory" 2> "$tmp/time.log" > /dev/null
    row "mkscan sphere $n, stdin" "$tmp/gen.mebake" "$tmp/time.log"
done
rm -rf "$tmp"
