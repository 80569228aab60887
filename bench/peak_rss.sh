#!/usr/bin/env bash
# Peak resident memory of `mebake info -` reading a generated mesh from a pipe.
#
#   bench/peak_rss.sh [-n TRIANGLES] [--limit MIB] [mkscan options...]
#
# Runs `mkscan --triangles N [options] | /usr/bin/time -v mebake info -` and prints
# the peak RSS that GNU time reports ("Maximum resident set size"; it counts touched
# file-backed mmap pages too). N defaults to 20000000. With --limit, exits 1 when the
# peak exceeds MIB (the design target is 64). /usr/bin/time is the Debian package
# `time` (apt-get install time).
#
# Environment: MEBAKE (default build/src/app/mebake), MKSCAN (default build/tools/mkscan).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mebake=${MEBAKE:-$root/build/src/app/mebake}
mkscan=${MKSCAN:-$root/build/tools/mkscan}
triangles=20000000
limit=
extra=()

usage() { sed -n '2,12s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; exit "${1:-2}"; }
die() { echo "peak_rss: $*" >&2; exit 1; }

while [[ $# -gt 0 ]]; do
    case $1 in
        -n|--triangles) triangles=$2; shift 2 ;;
        --limit) limit=$2; shift 2 ;;
        -h|--help) usage 0 ;;
        *) extra+=("$1"); shift ;;
    esac
done
[[ $triangles =~ ^[0-9]+$ ]] || die "--triangles needs a number, got '$triangles'"
[[ -z $limit || $limit =~ ^[0-9]+$ ]] || die "--limit needs a whole number of MiB, got '$limit'"
[[ -x /usr/bin/time ]] || die "/usr/bin/time is missing: install the Debian package 'time' (apt-get install time)"
[[ -x $mkscan ]] || die "mkscan not found at $mkscan (cmake --build build --target mkscan, or set MKSCAN)"
[[ -x $mebake ]] || die "mebake not found at $mebake (cmake --build build --target mebake, or set MEBAKE)"

log=$(mktemp "${TMPDIR:-/tmp}/peak_rss.XXXXXX")
trap 'rm -f "$log"' EXIT

cmd="$mkscan --triangles $triangles ${extra[*]} | /usr/bin/time -v $mebake info -"
echo "\$ $cmd"
start=$EPOCHREALTIME
set +e
"$mkscan" --triangles "$triangles" "${extra[@]}" | /usr/bin/time -v -o "$log" "$mebake" info -
status=("${PIPESTATUS[@]}")
set -e
end=$EPOCHREALTIME
# mebake first: when it stops early, mkscan dies of SIGPIPE as a consequence.
if [[ ${status[1]} -ne 0 ]]; then
    cat "$log" >&2
    die "mebake info failed (exit ${status[1]})"
fi
[[ ${status[0]} -eq 0 ]] || die "mkscan failed (exit ${status[0]})"

kb=$(sed -n 's/^[[:space:]]*Maximum resident set size (kbytes): *\([0-9]*\)/\1/p' "$log")
[[ -n $kb ]] || { cat "$log" >&2; die "no 'Maximum resident set size' in the output of /usr/bin/time -v"; }
awk -v kb="$kb" -v s0="$start" -v s1="$end" 'BEGIN {
    printf "peak RSS of mebake info: %.1f MiB (%d kB); pipeline wall time %.2f s\n", kb / 1024, kb, s1 - s0 }'
if [[ -n $limit ]] && (( kb > limit * 1024 )); then
    die "peak RSS $((kb / 1024)) MiB exceeds the limit of $limit MiB"
fi
