#!/usr/bin/env python3
"""Scene files of bench/RESULTS.md, "Issue 15": the bunny (bun_zipper.ply) lit by N square
lights on a ring, and McGuire's Cornell box with its lamp off and N ceiling lights.
Usage: multi_emitter_scenes.py OUTDIR  (writes bunnyN.json, cornellN.json, cornell4b.json)."""
import json
import math
import os
import sys


def cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def unit(u):
    n = math.sqrt(sum(x * x for x in u))
    return [x / n for x in u]


def square(centre, front, half, radiance):
    """A square light of half-side `half`, counter-clockwise seen from `front`."""
    up = [0, 1, 0] if abs(front[1]) < 0.9 else [1, 0, 0]
    t = unit(cross(up, front))
    b = cross(front, t)  # t x b = front
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    verts = [[round(centre[i] + half * (s * t[i] + r * b[i]), 6) for i in range(3)]
             for s, r in corners]
    return {"type": "polygon", "vertices": verts, "radiance": [radiance] * 3}


def main(out):
    os.makedirs(out, exist_ok=True)
    centre, radius = [-0.017, 0.11, -0.002], 0.35
    for n in (1, 2, 4, 8):
        lights = []
        for k in range(n):
            az = 2 * math.pi * k / n + 0.3
            el = math.radians(50 if k % 2 == 0 else 30)
            d = [math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)]
            pos = [centre[i] + radius * d[i] for i in range(3)]
            lights.append(square(pos, [-x for x in d], 0.04, 30.0 / n))
        scene = {"materials": [{"albedo": 0.7}], "lights": lights, "sky": {"type": "none"},
                 "default_rig": False, "solver": {"max_bounces": 0}}
        json.dump(scene, open(os.path.join(out, f"bunny{n}.json"), "w"), indent=1)
    spots = {1: [(0, 0)], 2: [(-0.4, 0), (0.4, 0)],
             4: [(-0.45, -0.45), (0.45, -0.45), (-0.45, 0.45), (0.45, 0.45)],
             8: [(x, z) for x in (-0.6, -0.2, 0.2, 0.6) for z in (-0.35, 0.35)]}
    for n, where in spots.items():
        lights = [square([x, 1.97, z], [0, -1, 0], 0.12, 17.0 / n) for x, z in where]
        scene = {"materials": [{"name": "light", "emission": [0, 0, 0], "albedo": 0.78}],
                 "lights": lights, "sky": {"type": "none"}, "default_rig": False,
                 "solver": {"max_bounces": 0}}
        json.dump(scene, open(os.path.join(out, f"cornell{n}.json"), "w"), indent=1)
        if n == 4:
            scene["solver"] = {}
            json.dump(scene, open(os.path.join(out, "cornell4b.json"), "w"), indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
