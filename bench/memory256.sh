#!/usr/bin/env bash
# Peak RSS per stage under a small budget (issue 16): every shared scan (and optional
# generated sizes) ingested and solved with --memory M, then exported (light map, glTF,
# vertex colours) and rendered, each stage under /usr/bin/time -v; the whole bake (ingest
# included) runs again with --memory BIG and the outputs are compared byte for byte.
#
#   bash bench/memory256.sh [--memory 256M] [--big 4G] [--scans "bun_zipper.ply ..."]
#                           [--generated "1000000 ..."] [--work DIR] [--no-compare]
#
# Writes WORK/memory.tsv (name, stage, budget, wall s, CPU s, peak KiB, load, status) and
# prints a markdown table. Data: ../shared/data/scans (or $MEBAKE_DATA/scans).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
MKSCAN="${MKSCAN:-$ROOT/build/tools/mkscan}"
DATA="${MEBAKE_DATA:-$ROOT/../shared/data}"
SMALL=256M
BIG=4G
SCANS="bun_zipper.ply horse.ply igea.ply lucy.ply nefertiti.obj pepper.ply turbineblade.ply"
GENERATED=""
WORK="$ROOT/build/bench-memory"
COMPARE=1
while [ $# -gt 0 ]; do
  case "$1" in
    --memory) SMALL="$2"; shift 2 ;;
    --big) BIG="$2"; shift 2 ;;
    --scans) SCANS="$2"; shift 2 ;;
    --generated) GENERATED="$2"; shift 2 ;;
    --work) WORK="$2"; shift 2 ;;
    --no-compare) COMPARE=0; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$WORK"
TSV="$WORK/memory.tsv"
[ -f "$TSV" ] || printf "name\tstage\tbudget\tseconds\tcpu_seconds\tpeak_kib\tload1\tstatus\n" > "$TSV"

measure() {  # measure NAME STAGE BUDGET CMD...
  local name="$1" stage="$2" budget="$3"; shift 3
  local log="$WORK/$name.$stage.$budget.time" st=ok rc=0 load
  load=$(cut -d' ' -f1 /proc/loadavg)
  /usr/bin/time -v -o "$log" nice -n 5 "$@" > "$WORK/$name.$stage.$budget.log" 2>&1 || rc=$?
  [ "$rc" = 0 ] || st=failed
  local wall cpu rss
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/{n=split($2,a,":"); s=0; for(i=1;i<=n;i++) s=s*60+a[i]; print s}' "$log")
  cpu=$(awk -F': ' '/User time|System time/{s += $2} END {print s}' "$log")
  rss=$(awk -F': ' '/Maximum resident set size/{print $2}' "$log")
  printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$name" "$stage" "$budget" "$wall" "$cpu" "$rss" "$load" "$st" >> "$TSV"
  echo "$name $stage $budget: ${wall}s (cpu ${cpu}s, load $load), $((rss / 1024)) MiB, $st" >&2
  [ "$st" = ok ]
}

# solve, export, render of bake directory D with budget B into outputs under O
downstream() {
  local name="$1" d="$2" b="$3" o="$4"
  mkdir -p "$o"
  measure "$name" solve "$b" "$MEBAKE" solve "$d" --memory "$b" --force || return 1
  measure "$name" export "$b" "$MEBAKE" export "$d" --lightmap "$o/lightmap.exr" \
    --mesh "$o/baked.glb" --vertex-colors "$o/vertex_colors.ply" --memory "$b" --force || return 1
  measure "$name" render "$b" "$MEBAKE" render "$d" -o "$o/render.png" --force || return 1
  cp "$d/solve/solution.bin" "$o/solution.bin"
}

one() {  # one NAME INGEST-CMD...
  local name="$1"; shift
  local d="$WORK/$name.mebake"
  rm -rf "$d" "$WORK/$name.small" "$WORK/$name.big"
  measure "$name" ingest "$SMALL" "$@" -o "$d" --memory "$SMALL" --force || return 0
  downstream "$name" "$d" "$SMALL" "$WORK/$name.small" || return 0
  if [ "$COMPARE" = 1 ]; then
    rm -rf "$d"
    measure "$name" ingest "$BIG" "$@" -o "$d" --memory "$BIG" --force || return 0
    downstream "$name" "$d" "$BIG" "$WORK/$name.big" || return 0
    local same=identical
    for f in solution.bin lightmap.exr baked.glb vertex_colors.ply render.png; do
      cmp -s "$WORK/$name.small/$f" "$WORK/$name.big/$f" || same="differ ($f)"
    done
    printf "%s\tcompare\t%s/%s\t0\t0\t0\t0\t%s\n" "$name" "$SMALL" "$BIG" "$same" >> "$TSV"
    echo "$name: outputs at $SMALL and $BIG: $same" >&2
  fi
  rm -rf "$d"
}

for s in $SCANS; do
  one "${s%.*}" "$MEBAKE" ingest "$DATA/scans/$s"
done
for n in $GENERATED; do
  one "s$n" bash -c "'$MKSCAN' -n $n | '$MEBAKE' ingest - \"\$@\"" _
done

python3 - "$TSV" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])][1:]
names = []
for r in rows:
    if r[0] not in names: names.append(r[0])
print("| mesh | ingest | solve | export | render | outputs small vs big |")
print("|---|---:|---:|---:|---:|---|")
for n in names:
    cells = []
    small = next((r[2] for r in rows if r[0] == n and r[1] == "ingest"), "?")
    for st in ["ingest", "solve", "export", "render"]:
        r = [r for r in rows if r[0] == n and r[1] == st and r[2] == small]
        if not r: cells.append("-"); continue
        r = r[-1]
        cells.append("%.0f MiB / %.1f s%s" % (int(r[5]) / 1024, float(r[4]), "" if r[7] == "ok" else " (" + r[7] + ")"))
    cmpr = [r for r in rows if r[0] == n and r[1] == "compare"]
    cells.append(cmpr[-1][7] if cmpr else "-")
    print("| %s | %s |" % (n, " | ".join(cells)))
print("\nEach cell: peak RSS / CPU s (user+sys) at the small budget.")
PY
