#!/usr/bin/env bash
# Time and peak memory per stage against mesh size (issue 7): generated scans piped through
# stdin, `mkscan -n N | mebake ingest -`, then `mebake solve` (default rig) and
# `mebake export` (light map + stats), each under /usr/bin/time -v.
#
#   bash bench/scale.sh [--sizes "100000 1000000 ..."] [--memory 2G] [--timeout S] [--work DIR]
#                       [--no-results] [--stages "ingest solve export"] [--keep] [--plot FILE]
#
# --stages runs only those stages (a size whose ingest is not among them reuses WORK/sN.mebake
# from an earlier --keep run, so a long ingest and solve need not be repeated to re-measure
# the export with another binary); --keep leaves the bake directory in WORK.
# --memory is passed to every stage (default: the stages' own default). Each row records
# wall and CPU seconds (user + sys), peak RSS and the 1-min load average when the stage
# started; disk.tsv the bake directory's size after export.
#
# Each stage runs under `nice -n 5` and `timeout S` (default 7200 s); a stage that times out
# is recorded as such (and the later stages of that size are skipped).
#
# Writes WORK/scale.tsv, WORK/scale.md, the plot (log-log; --plot, default bench/scale.png;
# skipped without gnuplot)
# and the table into bench/RESULTS.md between the "scale:begin/end" markers.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
MKSCAN="${MKSCAN:-$ROOT/build/tools/mkscan}"
SIZES="100000 1000000 4000000 16000000"
WORK="$ROOT/build/bench-scale"
RESULTS=1
TIMEOUT=7200
MEMORY=()
STAGES="ingest solve export"
KEEP=0
PLOT="$ROOT/bench/scale.png"
CMD="bash bench/scale.sh$(printf " %q" "$@")"
while [ $# -gt 0 ]; do
  case "$1" in
    --sizes) SIZES="$2"; shift 2 ;;
    --work) WORK="$2"; shift 2 ;;
    --timeout) TIMEOUT="$2"; shift 2 ;;
    --memory) MEMORY=(--memory "$2"); shift 2 ;;
    --no-results) RESULTS=0; shift ;;
    --stages) STAGES="$2"; shift 2 ;;
    --keep) KEEP=1; shift ;;
    --plot) PLOT="$(realpath -m "$2")"; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
[ -x "$MEBAKE" ] && [ -x "$MKSCAN" ] || { echo "build mebake and mkscan first" >&2; exit 1; }
mkdir -p "$WORK"
TSV="$WORK/scale.tsv"
[ -f "$TSV" ] || printf "triangles\tstage\tseconds\tpeak_kib\tstatus\tcpu_seconds\tload1\n" > "$TSV"

measure() {  # measure N STAGE CMD... : appends a row (wall and CPU seconds, peak RSS, load)
  local n="$1" stage="$2"; shift 2
  local log="$WORK/$n.$stage.time" st=ok rc=0 load
  load=$(cut -d' ' -f1 /proc/loadavg)
  /usr/bin/time -v -o "$log" timeout "$TIMEOUT" nice -n 5 "$@" > "$WORK/$n.$stage.log" 2>&1 || rc=$?
  [ "$rc" = 0 ] || st=failed
  [ "$rc" = 124 ] && st=timeout
  local wall rss
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/{n=split($2,a,":"); s=0; for(i=1;i<=n;i++) s=s*60+a[i]; print s}' "$log")
  rss=$(awk -F': ' '/Maximum resident set size/{print $2}' "$log")
  cpu=$(awk -F': ' '/User time|System time/{s += $2} END {print s}' "$log")
  # replace an earlier row of the same size and stage
  grep -v -P "^$n\t$stage\t" "$TSV" > "$TSV.tmp" || true
  printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$n" "$stage" "$wall" "$rss" "$st" "$cpu" "$load" >> "$TSV.tmp"
  mv "$TSV.tmp" "$TSV"
  echo "$n $stage: ${wall}s (cpu ${cpu}s, load $load), $((rss / 1024)) MiB, $st" >&2
}

wants() { case " $STAGES " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }
last_ok() { [ "$(tail -1 "$TSV" | cut -f5)" = ok ]; }

for n in $SIZES; do
  d="$WORK/s$n.mebake"
  ok=1
  if wants ingest; then
    rm -rf "$d"
    measure "$n" ingest bash -c "'$MKSCAN' -n $n | '$MEBAKE' ingest - -o '$d' --force ${MEMORY[*]}"
    last_ok || ok=0
  elif [ ! -d "$d" ]; then
    echo "$n: no $d to reuse (run its ingest with --keep first)" >&2; continue
  fi
  if [ "$ok" = 1 ] && wants solve; then
    measure "$n" solve "$MEBAKE" solve "$d" --force "${MEMORY[@]}"
    last_ok || ok=0
  fi
  if [ "$ok" = 1 ] && wants export; then
    measure "$n" export "$MEBAKE" export "$d" --lightmap "$WORK/s$n.exr" --stats "$WORK/s$n.stats.json" --force "${MEMORY[@]}"
  fi
  grep -v -P "^$n\t" "$WORK/disk.tsv" > "$WORK/disk.tmp" 2>/dev/null || true
  du -sk "$d" | awk -v n="$n" '{print n "\t" $1}' >> "$WORK/disk.tmp"
  mv "$WORK/disk.tmp" "$WORK/disk.tsv"
  [ "$KEEP" = 1 ] || rm -rf "$d"
  rm -f "$WORK"/s$n.*.exr "$WORK/s$n.exr"
done

python3 - "$TSV" "$CMD" "$WORK/disk.tsv" > "$WORK/scale.md" <<'PY'
import sys, os, platform, datetime
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])][1:]
cmd = sys.argv[2]
disk = {}
if os.path.exists(sys.argv[3]):
    for l in open(sys.argv[3]):
        f = l.split()
        if len(f) == 2: disk[int(f[0])] = int(f[1])
cpu = "?"
for l in open("/proc/cpuinfo"):
    if l.startswith("model name"): cpu = l.split(":", 1)[1].strip(); break
mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
sizes = sorted({int(r[0]) for r in rows})
stages = ["ingest", "solve", "export"]
t = {(int(r[0]), r[1]): r for r in rows}
print("## Scale: time and peak RSS against triangles (issue 7)\n")
print("Machine: %s, %d cores (whether it was shared: see the notes), %.0f GiB, %s." %
      (cpu, os.cpu_count(), mem, platform.platform()))
print("Date: %s UTC. Command: `%s`. Input: `mkscan -n N` (noisy sphere) piped into\n"
      "`mebake ingest -`, then `mebake solve` (default rig, M2) and `mebake export --lightmap --stats`.\n"
      "Peak RSS is `/usr/bin/time -v`'s maximum resident set size of that stage's process.\n" %
      (datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), cmd))
print("Each cell: wall s / CPU s (user+sys) / peak MiB / 1-min load when the stage started.\n")
print("| triangles | " + " | ".join(stages) + " | disk (bake dir) |")
print("|---:|" + "---:|" * len(stages) + "---:|")
for n in sizes:
    cells = []
    for s in stages:
        r = t.get((n, s))
        if not r: cells.append("-"); continue
        bad = "" if r[4] == "ok" else " (%s)" % r[4]
        cpu = float(r[5]) if len(r) > 5 and r[5] else float("nan")
        load = r[6] if len(r) > 6 else "?"
        cells.append("%.1f / %.1f / %.0f / %s%s" % (float(r[2]), cpu, int(r[3]) / 1024, load, bad))
    d = disk.get(n)
    cells.append("%.0f MiB, %.0f B/tri" % (d / 1024, d * 1024 / n) if d else "-")
    print("| %s | %s |" % (format(n, ","), " | ".join(cells)))
base = [n for n in sizes if n == 1000000]
if base:
    print()
    for big in [n for n in sizes if n > 1000000]:
        for s in stages:
            a, b = t.get((base[0], s)), t.get((big, s))
            if a and b and a[4] == b[4] == "ok":
                q = int(b[3]) / int(a[3])
                print("- %s: peak RSS %dM / 1M = %.2fx (target <= 1.25x: %s)" %
                      (s, big // 1000000, q, "met" if q <= 1.25 else "**missed**"))
PY
cat "$WORK/scale.md"

if command -v gnuplot > /dev/null; then
  for s in ingest solve export; do
    # triangles, wall s, peak MiB, CPU s (rows of older runs have no CPU column: wall)
    awk -F'\t' -v s="$s" 'NR > 1 && $2 == s && $5 == "ok" {print $1, $3, $4 / 1024, ($6 == "" ? $3 : $6)}' "$TSV" | sort -n > "$WORK/$s.dat"
  done
  gnuplot <<GP
set terminal pngcairo size 1100,480 noenhanced
set output "$PLOT"
set multiplot layout 1,2 title "mebake scale (mkscan sphere, default rig; 2-core machine)"
set logscale xy
set grid
set xlabel "triangles"
set key top left
set title "peak RSS (MiB)"
plot "$WORK/ingest.dat" u 1:3 w lp t "ingest", "$WORK/solve.dat" u 1:3 w lp t "solve", "$WORK/export.dat" u 1:3 w lp t "export"
set title "CPU time, user + sys (s)"
plot "$WORK/ingest.dat" u 1:4 w lp t "ingest", "$WORK/solve.dat" u 1:4 w lp t "solve", "$WORK/export.dat" u 1:4 w lp t "export", x/1e5 w l dt 2 t "linear"
unset multiplot
GP
  echo "wrote $PLOT" >&2
else
  echo "gnuplot not installed: no plot (apt-get install gnuplot-nox)" >&2
fi

if [ "$RESULTS" = 1 ]; then
  python3 - "$ROOT/bench/RESULTS.md" "$WORK/scale.md" scale "$(basename "$PLOT")" <<'PY'
import sys
path, table, key, plot = sys.argv[1], open(sys.argv[2]).read(), sys.argv[3], sys.argv[4]
b, e = "<!-- %s:begin -->" % key, "<!-- %s:end -->" % key
s = open(path).read()
block = "%s\n%s%s" % (b, table + "\n![scale](%s)\n" % plot, e)
if b in s and e in s:
    s = s[:s.index(b)] + block + s[s.index(e) + len(e):]
else:
    s = s.rstrip("\n") + "\n\n" + block + "\n"
open(path, "w").write(s)
PY
fi
