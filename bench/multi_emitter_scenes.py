#!/usr/bin/env python3
"""Scene files of bench/RESULTS.md, "Issue 15": the bunny (bun_zipper.ply) lit by N square
lights on a ring, and McGuire's Cornell box with its lamp off and N ceiling lights.
Usage: multi_emitter_scenes.py OUTDIR [NAME=BAKE_DIR ...] [--veach VEACH_MIS_XML]
writes bunnyN.json, cornellN.json (direct light only) and bunnyNb.json, cornellNb.json
(with the default bounces) for N = 1, 2, 4, 8, and rigN(b).json: the bunny's N lights added
to the default rig; for each NAME=BAKE_DIR (an ingested scan) also
NAMEN.json and NAMENb.json: the bunny's ring scaled to the scan's bounding box (manifest.json);
with --veach also veach5.json / veach5b.json: the five sphere lights of Veach's plates scene
(Mitsuba XML) as octagons of the same area facing the plates (all surfaces albedo 0.4)."""
import re
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


def ring(centre, diag, n):
    """N square lights on a ring 1.4 diagonals from the centre, at 50/30 degrees elevation
    about +y, side 0.32 diagonals, radiance 30/N (the bunny's rig of session 5 for diag 0.25)."""
    lights = []
    for k in range(n):
        az = 2 * math.pi * k / n + 0.3
        el = math.radians(50 if k % 2 == 0 else 30)
        d = [math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)]
        pos = [centre[i] + 1.4 * diag * d[i] for i in range(3)]
        lights.append(square(pos, [-x for x in d], 0.16 * diag, 30.0 / n))
    return lights


def write(out, name, scene):
    """name.json with direct light only, nameb.json with the default bounces."""
    scene["solver"] = {"max_bounces": 0}
    json.dump(scene, open(os.path.join(out, f"{name}.json"), "w"), indent=1)
    scene["solver"] = {}
    json.dump(scene, open(os.path.join(out, f"{name}b.json"), "w"), indent=1)


def octagon(centre, towards, radius, radiance):
    """An octagon of the area of a disc of `radius`, centred at `centre`, facing `towards`."""
    front = unit([towards[i] - centre[i] for i in range(3)])
    up = [0, 1, 0] if abs(front[1]) < 0.9 else [1, 0, 0]
    t = unit(cross(up, front))
    b = cross(front, t)
    r = radius * math.sqrt(math.pi / (2 * math.sqrt(2)))
    verts = [[round(centre[i] + r * (math.cos(a) * t[i] + math.sin(a) * b[i]), 6) for i in range(3)]
             for a in (2 * math.pi * k / 8 for k in range(8))]
    return {"type": "polygon", "vertices": verts, "radiance": radiance}


def veach(out, xml):
    """Veach's plates: each emitting sphere becomes an octagon facing the camera's target."""
    text = open(xml).read()
    lights = []
    for shape in re.findall(r'<shape type="sphere">(.*?)</shape>', text, re.S):
        c = re.search(r'name="center" x="([-\d.]+)" y="([-\d.]+)" z="([-\d.]+)"', shape)
        r = re.search(r'name="radius" value="([-\d.]+)"', shape)
        e = re.search(r'<emitter.*?name="radiance" value="([^"]+)"', shape, re.S)
        if not (c and r and e):
            continue
        rad = [float(x) for x in re.split(r"[,\s]+", e.group(1).strip())]
        lights.append(octagon([float(x) for x in c.groups()], [0, -2, 2.5], float(r.group(1)), rad))
    write(out, f"veach{len(lights)}", {"materials": [{"albedo": 0.4}], "lights": lights,
                                       "sky": {"type": "none"}, "default_rig": False})


def main(out, scans):
    os.makedirs(out, exist_ok=True)
    # The bunny's numbers of session 5: centre and a ring of radius 0.35.
    for n in (1, 2, 4, 8):
        lights = ring([-0.017, 0.11, -0.002], 0.25, n)
        write(out, f"bunny{n}", {"materials": [{"albedo": 0.7}], "lights": lights,
                                 "sky": {"type": "none"}, "default_rig": False})
        # The same lights added to the default rig (its sky and key light).
        write(out, f"rig{n}", {"materials": [{"albedo": 0.7}], "lights": lights,
                               "default_rig": True})
    for arg in scans:
        name, bake = arg.split("=", 1)
        lo, hi = json.load(open(os.path.join(bake, "manifest.json")))["bbox"]
        centre = [(a + b) / 2 for a, b in zip(lo, hi)]
        diag = math.sqrt(sum((b - a) ** 2 for a, b in zip(lo, hi)))
        for n in (1, 2, 4, 8):
            write(out, f"{name}{n}", {"materials": [{"albedo": 0.7}],
                                      "lights": ring(centre, diag, n),
                                      "sky": {"type": "none"}, "default_rig": False})
    spots = {1: [(0, 0)], 2: [(-0.4, 0), (0.4, 0)],
             4: [(-0.45, -0.45), (0.45, -0.45), (-0.45, 0.45), (0.45, 0.45)],
             8: [(x, z) for x in (-0.6, -0.2, 0.2, 0.6) for z in (-0.35, 0.35)]}
    for n, where in spots.items():
        lights = [square([x, 1.97, z], [0, -1, 0], 0.12, 17.0 / n) for x, z in where]
        write(out, f"cornell{n}",
              {"materials": [{"name": "light", "emission": [0, 0, 0], "albedo": 0.78}],
               "lights": lights, "sky": {"type": "none"}, "default_rig": False})


if __name__ == "__main__":
    args = sys.argv[2:]
    if "--veach" in args:
        i = args.index("--veach")
        veach(sys.argv[1], args[i + 1])
        del args[i:i + 2]
    main(sys.argv[1] if len(sys.argv) > 1 else ".", args)
