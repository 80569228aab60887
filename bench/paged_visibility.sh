#!/usr/bin/env bash
# Paged visibility against the whole proxy (issue 16): for each mesh, ingest once, solve with
# the whole proxy in one Embree scene, then with the proxy forced into 8 pieces and a cache
# of half its Embree scene (the proxy twice over its share, as --memory would make it), and
# compare the solutions' bytes. Prints CPU-s, peak RSS, the piece cache's hit rate, builds,
# rays per build. Last, the 16M sphere at --memory 128M, where the proxy truly exceeds its
# share (32 MiB) and the solve pages on its own.
#
#   MEBAKE_DATA=/work/shared/data bash bench/paged_visibility.sh [--work DIR] [--meshes "..."]
# meshes: scan file names under $MEBAKE_DATA/scans, or gen:N for `mkscan -n N`.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
MKSCAN="${MKSCAN:-$ROOT/build/tools/mkscan}"
DATA="${MEBAKE_DATA:-$ROOT/../shared/data}"
WORK=/tmp/mebake-paged
MESHES="bun_zipper.ply lucy.ply gen:4000000 gen:16000000"
SMALL_MEMORY=128M
while [ $# -gt 0 ]; do
    case "$1" in
    --work) WORK="$2"; shift 2 ;;
    --meshes) MESHES="$2"; shift 2 ;;
    --small-memory) SMALL_MEMORY="$2"; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
    esac
done
mkdir -p "$WORK"

# run NAME CMD...: CPU-s (user+sys) and peak RSS of CMD into $WORK/NAME.time
run() {
    local name="$1"; shift
    /usr/bin/time -f "%U %S %M" -o "$WORK/$name.time" "$@" > "$WORK/$name.log" 2>&1
}
cpu_rss() { awk '{printf "%.1f CPU-s, %.0f MiB", $1 + $2, $3 / 1024}' "$WORK/$1.time"; }
paging() {
    python3 - "$1" <<'EOF'
import json, sys
v = json.load(open(sys.argv[1]))["visibility"]
if not v["paged"]:
    print("whole proxy, %d triangles" % v["triangles"]); sys.exit()
print("%d pieces (largest %d), hit rate %.2f%% (%d of %d), %d loads + %d rentals, %d "
      "triangles built, %.0f rays per build, %.2f pieces per segment" %
      (v["pieces"], v["largest_piece"], 100 * v["hit_rate"], v["hits"], v["requests"],
       v["loads"], v["rentals"], v["built_triangles"], v["rays_per_build"],
       v["rays_per_segment"]))
EOF
}

echo "load: $(cut -d' ' -f1-3 /proc/loadavg)"
for mesh in $MESHES; do
    name="${mesh%.*}"; name="${name/:/}"
    dir="$WORK/$name.mebake"
    if [ ! -f "$dir/manifest.json" ]; then
        if [[ "$mesh" == gen:* ]]; then
            "$MKSCAN" -n "${mesh#gen:}" 2>/dev/null | "$MEBAKE" -q ingest - -o "$dir" --memory 2G
        else
            "$MEBAKE" -q ingest "$DATA/scans/$mesh" -o "$dir"
        fi
    fi
    tris=$(python3 -c "import json; print(json.load(open('$dir/manifest.json'))['proxy']['triangles'])")
    piece=$(( (tris + 7) / 8 ))
    cache=$(( tris * 100 / 2 ))
    rm -rf "$dir/solve"
    run "$name.whole" "$MEBAKE" solve "$dir" --force
    cp "$dir/solve/solution.bin" "$WORK/$name.whole.bin"
    cp "$dir/solve/stats.json" "$WORK/$name.whole.json"
    rm -rf "$dir/solve"
    run "$name.paged" "$MEBAKE" solve "$dir" --force --paged-visibility "$piece" --paged-cache "$cache"
    cp "$dir/solve/stats.json" "$WORK/$name.paged.json"
    same=$(cmp -s "$dir/solve/solution.bin" "$WORK/$name.whole.bin" && echo "same bytes" || echo "DIFFERENT")
    echo "$name ($tris proxy triangles): whole $(cpu_rss "$name.whole"); paged" \
         "(pieces of $piece, cache $cache B) $(cpu_rss "$name.paged"), $same;" \
         "$(paging "$WORK/$name.paged.json"); load $(cut -d' ' -f1 /proc/loadavg)"
done

# The proxy over its share: --memory $SMALL_MEMORY makes the Embree cap 64 MiB, the share 32.
dir="$WORK/gen16000000.mebake"
if [ -d "$dir" ] && [ -f "$WORK/gen16000000.whole.bin" ]; then
    rm -rf "$dir/solve"
    run small "$MEBAKE" solve "$dir" --force --memory "$SMALL_MEMORY"
    cp "$dir/solve/stats.json" "$WORK/small.json"
    same=$(cmp -s "$dir/solve/solution.bin" "$WORK/gen16000000.whole.bin" && echo "same bytes as at 1G" || echo "DIFFERENT from 1G")
    echo "gen16000000 at --memory $SMALL_MEMORY: $(cpu_rss small), $same; $(paging "$WORK/small.json");" \
         "load $(cut -d' ' -f1 /proc/loadavg)"
fi
