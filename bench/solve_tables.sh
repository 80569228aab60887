#!/usr/bin/env bash
# The seed's Table 1 / Table 2 for this machine: `mebake solve` per scan and per setting
# (orders M0..M3 of vector irradiance, and the radiosity unknown at M2), default rig
# (sky + key light), --max-bounces 3. Prints one markdown row per run: wall and CPU
# seconds, peak RSS (GNU time), nodes, leaves, rays (and per pass), rays per CPU-second.
#
#   bench/solve_tables.sh [--configs "M0 M1 M2 M3 R2"] [--bounces N] [--work DIR] SCAN...
#
# SCAN is a mesh path, or gen1m / gen4m for `mkscan -n 1000000 / 4000000` (sphere).
# Bake directories are cached in DIR (default /tmp/mebake-solve-tables) and re-used.
# Environment: MEBAKE, MKSCAN (defaults: build/src/app/mebake, build/tools/mkscan).
# The machine is usually shared: CPU seconds are the steadier figure.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mebake=${MEBAKE:-$root/build/src/app/mebake}
mkscan=${MKSCAN:-$root/build/tools/mkscan}
configs="M0 M1 M2 M3 R2"
bounces=3
work=/tmp/mebake-solve-tables
scans=()

usage() { sed -n '2,12s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; exit "${1:-2}"; }
while [[ $# -gt 0 ]]; do
    case $1 in
        --configs) configs=$2; shift 2 ;;
        --bounces) bounces=$2; shift 2 ;;
        --work) work=$2; shift 2 ;;
        -h|--help) usage 0 ;;
        -*) usage ;;
        *) scans+=("$1"); shift ;;
    esac
done
[[ ${#scans[@]} -gt 0 ]] || usage
command -v /usr/bin/time >/dev/null || { echo "solve_tables: needs GNU time (/usr/bin/time)" >&2; exit 1; }
mkdir -p "$work"

echo "| scan | triangles | setting | wall s | CPU s | peak RSS MiB | nodes | leaves | rays | classify / penumbra / sky / link | rays per CPU-s |"
echo "|---|---:|---|---:|---:|---:|---:|---:|---:|---|---:|"
for scan in "${scans[@]}"; do
    name=$(basename "${scan%.*}")
    bake=$work/$name.mebake
    if [[ ! -f $bake/manifest.json ]]; then
        case $scan in
            gen1m) "$mkscan" -q -n 1000000 | "$mebake" -q ingest - -o "$bake" ;;
            gen4m) "$mkscan" -q -n 4000000 | "$mebake" -q ingest - -o "$bake" ;;
            *) "$mebake" -q ingest "$scan" -o "$bake" ;;
        esac
    fi
    tris=$("$mebake" info "$bake" 2>/dev/null | sed -n 's/.*[^0-9]\([0-9][0-9,]*\) triangles.*/\1/p' | head -1)
    for cfg in $configs; do
        order=${cfg:1:1}
        args=(--order "$order" --max-bounces "$bounces")
        [[ ${cfg:0:1} == R ]] && args+=(--unknown radiosity)
        stats=$work/$name.$cfg.json
        timing=$work/$name.$cfg.time
        /usr/bin/time -v -o "$timing" "$mebake" -q solve "$bake" "${args[@]}" --stats "$stats"
        python3 - "$scan" "${tris:-?}" "$cfg" "$stats" "$timing" <<'PY'
import json, re, sys
scan, tris, cfg, stats, timing = sys.argv[1:]
j = json.load(open(stats))
t = open(timing).read()
def field(pat):
    m = re.search(pat, t)
    return m.group(1) if m else "0"
wall = field(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)")
parts = [float(x) for x in wall.split(":")]
secs = sum(p * 60 ** (len(parts) - 1 - i) for i, p in enumerate(parts))
cpu = float(field(r"User time \(seconds\): (\S+)")) + float(field(r"System time \(seconds\): (\S+)"))
rss = int(field(r"Maximum resident set size \(kbytes\): (\d+)")) / 1024
k = j.get("rays_by_kind", {})
passes = " / ".join(f"{k.get(n, 0) / 1e6:.1f}M" for n in ("classify", "penumbra", "sky", "link"))
setting = ("radiosity M" + cfg[1]) if cfg[0] == "R" else cfg
print(f"| {scan.split('/')[-1]} | {tris} | {setting} | {secs:.1f} | {cpu:.1f} | {rss:.0f} | "
      f"{sum(j['nodes_per_level'])} | {j['leaves']} | {j['rays'] / 1e6:.1f}M | {passes} | "
      f"{j['rays'] / max(cpu, 1e-9) / 1e6:.2f}M |")
PY
    done
done
