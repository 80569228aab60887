#!/usr/bin/env python3
"""Where the light map's display rule loses, at the reference's points (docs/accuracy.md).

    mebake compare DIR ref.json --points -o pts.json
    python3 bench/rule_points.py pts.json [more.json ...]

For each `compare --points` output: the relative RMS and bias of the bake (bake_B) and of
the display rule applied to the reference's own E (rule_B) against the reference's B, and
of the bake against the rule, over all points and per band of tilt (degrees between the
shading normal and the face's), with each band's share of the squared errors; and the
share of the rule's loss the bake carries (the least-squares slope k of the bake's error
on the rule's, as `compare IMAGE REF --rule` does for pictures), the bake's error split
into the part along the rule's loss and the rest (RMS^2 = carried^2 + rest^2). RMS is
relative to the RMS of |B|, bias to the mean of B, as `compare` reports them.
"""
import json
import math
import sys

BANDS = [(0, 2), (2, 5), (5, 10), (10, 20), (20, 40), (40, 180)]


def table(path):
    pts = json.load(open(path))["points"]
    if not pts or "rule_B" not in pts[0]:
        sys.exit(f"{path}: no rule_B (a reference without E, or a radiosity solve)")
    n = len(pts)
    level = math.sqrt(sum(sum(b * b for b in p["B"]) for p in pts) / n)
    mean = sum(sum(p["B"]) for p in pts) / (3 * n)

    def sq(p, x, y):
        return sum((a - b) ** 2 for a, b in zip(p[x], p[y]))

    def stats(ps, x, y):
        rms = math.sqrt(sum(sq(p, x, y) for p in ps) / len(ps)) / level
        bias = sum(a - b for p in ps for a, b in zip(p[x], p[y])) / (3 * len(ps)) / mean
        return "%.2f %% (%+.2f)" % (100 * rms, 100 * bias)

    tot = {k: sum(sq(p, *k) for p in pts) for k in [("rule_B", "B"), ("bake_B", "B")]}
    print(f"{path}: {n} points")
    print("| tilt (deg) | points | rule vs reference RMS (bias) | bake vs reference | bake vs rule "
          "| share of the rule's sq. error | of the bake's |")
    print("|---|---|---|---|---|---|---|")
    for lo, hi in BANDS + [(0, 180)]:
        ps = [p for p in pts if lo <= p["tilt"] < hi or (hi == 180 and p["tilt"] == 180)]
        if not ps:
            continue
        share = ["%.0f %%" % (100 * sum(sq(p, *k) for p in ps) / max(tot[k], 1e-300))
                 for k in [("rule_B", "B"), ("bake_B", "B")]]
        name = "all" if (lo, hi) == (0, 180) else f"{lo}-{hi}"
        print(f"| {name} | {len(ps)} | {stats(ps, 'rule_B', 'B')} | {stats(ps, 'bake_B', 'B')} "
              f"| {stats(ps, 'bake_B', 'rule_B')} | {share[0]} | {share[1]} |")
    dl = sum((a - r) * (b - r) for p in pts for a, b, r in zip(p["bake_B"], p["rule_B"], p["B"]))
    ll, dd = tot[("rule_B", "B")], tot[("bake_B", "B")]
    k = dl / ll if ll > 0 else 0
    print("the bake carries x%.2f of the rule's loss: carried %.2f %%, rest %.2f %%" % (
        k, 100 * abs(k) * math.sqrt(ll / n) / level, 100 * math.sqrt(max(0, dd - k * dl) / n) / level))


for f in sys.argv[1:]:
    table(f)
