#!/usr/bin/python3
"""A third opinion for bench/accuracy.sh: on a smooth convex sphere under the default rig,
B has a closed form (no occlusion, no interreflection): B = rho (I_sky(n) + I_key(x, n)), the
uniform sky's clipped irradiance (pi/2) L (1 + n.up) and the key light's irradiance integrated
numerically over its square (120 x 120 cells, cos clipped at the receiver). Compares both the
reference and the bake at the reference's points against it.

  bash: T=build/spheretest; mkdir -p $T
        build/tools/mkscan -n 20000 --noise 0 -o $T/s.ply
        mebake ingest $T/s.ply -o $T/s.mebake; mebake solve $T/s.mebake --order 2
        mebake reference $T/s.mebake --points 500 -o $T/ref.json
        mebake compare $T/s.mebake $T/ref.json --points -o $T/cmp.json
        /usr/bin/python3 bench/accuracy_sphere.py $T/s.mebake $T/ref.json $T/cmp.json
The default rig's key light is rebuilt here as src/solve/scene.cpp AddDefaultRig places it.
"""
import json, sys
import numpy as np

bake_dir, ref_path, cmp_path = sys.argv[1:4]
m = json.load(open(bake_dir + "/manifest.json"))
lo, hi = np.array(m["bbox"][0]), np.array(m["bbox"][1])
center, diag, up = (lo + hi) / 2, np.linalg.norm(hi - lo), np.array([0, 1.0, 0])
side = np.array([1.0, 0, 0])
front = np.cross(side, up); front /= np.linalg.norm(front)
side = np.cross(up, front); side /= np.linalg.norm(side)
d = up + front * 0.6 + side * 0.5; d /= np.linalg.norm(d)
c = center + d * 1.5 * diag
a = np.cross(d, up); a /= np.linalg.norm(a)
b = np.cross(a, d)
h = diag * 0.25
L = 3.0 / (4 * h * h / (1.5 * diag) ** 2) * np.array([1, 0.97, 0.92])
sky = np.array([0.25, 0.27, 0.30])
N = 120
s = (np.arange(N) + 0.5) / N * 2 - 1
P = (c[None, None] + a[None, None] * h * s[:, None, None] + b[None, None] * h * s[None, :, None]).reshape(-1, 3)
dA = (2 * h / N) ** 2
ref = json.load(open(ref_path))["points"]
bake = json.load(open(cmp_path))["points"]
ex, R, B = [], [], []
for p, q in zip(ref, bake):
    x, n, rho = np.array(p["position"]), np.array(p["normal"]), np.array(p["albedo"])
    w = P - x
    r2 = (w * w).sum(1)
    w /= np.sqrt(r2)[:, None]
    il = (np.clip(w @ n, 0, None) * np.clip(w @ d, 0, None) / r2).sum() * dA
    ex.append(rho * (L * il + sky * (np.pi / 2) * (1 + n @ up)))
    R.append(p["B"]); B.append(q["bake_B"])
ex, R, B = map(np.array, (ex, R, B))
lvl = np.sqrt((ex ** 2).sum(1).mean())
rms = lambda v: np.sqrt(((v - ex) ** 2).sum(1).mean()) / lvl
print("points %d  mean |B|: exact %.4f reference %.4f bake %.4f" % (
    len(ex), np.linalg.norm(ex, axis=1).mean(), np.linalg.norm(R, axis=1).mean(), np.linalg.norm(B, axis=1).mean()))
print("relative RMS vs the closed form: reference %.2f %%, bake %.2f %%" % (100 * rms(R), 100 * rms(B)))
