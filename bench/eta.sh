#!/usr/bin/env bash
# How good the solve's ETA is (issue 17): for each scan, ingest, then solve with
# `--progress json` and compare, at 25 %, 50 % and 75 % of the batches' wall time, the ETA
# shown then with the time that was actually left (bench/eta_error.py).
#   bash bench/eta.sh [--work DIR] [--order N] scan.ply ...
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MEBAKE="${MEBAKE:-$ROOT/build/src/app/mebake}"
WORK=/tmp/mebake-eta
ORDER=2
while [ $# -gt 0 ]; do
  case "$1" in
    --work) WORK="$2"; shift 2 ;;
    --order) ORDER="$2"; shift 2 ;;
    *) break ;;
  esac
done
mkdir -p "$WORK"
echo "| scan | batches | solve s | ETA error at 25 % | at 50 % | at 75 % |"
echo "|---|---:|---:|---:|---:|---:|"
for scan in "$@"; do
  name="$(basename "${scan%.*}")"
  "$MEBAKE" -q ingest "$scan" -o "$WORK/$name.mebake" --force
  "$MEBAKE" solve "$WORK/$name.mebake" --force --order "$ORDER" --progress json \
    2> "$WORK/$name.progress.jsonl"
  python3 "$ROOT/bench/eta_error.py" "$name" "$WORK/$name.progress.jsonl"
done
