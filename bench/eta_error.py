#!/usr/bin/env python3
# One markdown row: the "solve" stage's ETA error at 25/50/75 % of its wall time, from a
# `mebake solve --progress json` log. Error = (ETA shown - time actually left), as a share
# of the stage's total time (+ = too pessimistic); the ETA is the last one shown before
# each point.
import json
import sys

name, path = sys.argv[1], sys.argv[2]
rows, detail = [], ""
for line in open(path):
    if line.startswith("{"):
        j = json.loads(line)
        if j["stage"] == "solve":
            rows.append(j)
if not rows or not rows[-1]["final"]:
    sys.exit(f"{path}: no finished solve stage")
total = rows[-1]["elapsed"]
batches = rows[-1]["detail"].split(",")[0]
cells = []
for share in (0.25, 0.5, 0.75):
    t = share * total
    shown = [r for r in rows if r["elapsed"] <= t and r["eta"] is not None and not r["final"]]
    if not shown:
        cells.append("n/a")
        continue
    r = shown[-1]
    left = total - r["elapsed"]
    cells.append(f"{100 * (r['eta'] - left) / total:+.0f} % (ETA {r['eta']:.0f} s, left {left:.0f} s)")
print(f"| {name} | {batches} | {total:.1f} | " + " | ".join(cells) + " |")
