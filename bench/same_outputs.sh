#!/usr/bin/env bash
# Bakes the sample, a Cornell box and igea with two mebake binaries and says whether every
# output file is byte-identical (timings and paths in the manifest/stats JSON excluded).
# For refactors that must not change results.
#   bash bench/same_outputs.sh OLD_MEBAKE NEW_MEBAKE [WORKDIR]
set -euo pipefail
old=$1 new=$2 work=${3:-$(mktemp -d)}
mkdir -p "$work"
root=$(cd "$(dirname "$0")/.." && pwd)
data=$root/../shared/data
cases=("rock:$root/data/samples/rock.ply")
[ -f "$data/scenes/cornell-mcguire/CornellBox-Original.obj" ] &&
  cases+=("cornell:$data/scenes/cornell-mcguire/CornellBox-Original.obj")
[ -f "$data/scans/igea.ply" ] && cases+=("igea:$data/scans/igea.ply")
status=0
for c in "${cases[@]}"; do
  name=${c%%:*} input=${c#*:}
  for side in old new; do
    bin=$old; [ $side = new ] && bin=$new
    if [ ! -d "$work/$side-$name" ]; then
      "$bin" bake "$input" -o "$work/$side-$name" --force >"$work/$side-$name.log" 2>&1
    fi
  done
  differ=0 files=0
  while IFS= read -r f; do
    files=$((files + 1))
    case "$f" in
      *.json|*/manifest*|*.log) continue ;;  # timings and paths differ between runs
    esac
    if ! cmp -s "$work/old-$name/$f" "$work/new-$name/$f"; then
      echo "$name: $f differs"; differ=1
    fi
  done < <(cd "$work/old-$name" && find . -type f | sort)
  if [ $differ = 0 ]; then echo "$name: $files files, every non-JSON output byte-identical"; else status=1; fi
done
exit $status
